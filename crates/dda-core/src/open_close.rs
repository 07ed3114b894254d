//! The open-close iteration (OCI): solve for the current contact states, re-check
//! every contact (`contact_law`), let trajectory tracking activate covers, and repeat
//! until nothing changes. Before it, the state predictor solves the step with the
//! previous step's factor. Iterations after the first solve through a low-rank update
//! of the factor while few springs changed.

use crate::assembly::Spring;
use crate::contact_law::{DECISION_BAND, decision_band};
use crate::diagnosis::SimError;
use crate::kinematics::Vec6;
use crate::simulation::Simulation;
use crate::solver::RankOne;
use crate::springs::{HalfStep, Row, normal_row};
use crate::state::StepRecord;
use crate::timing::{Phase, Stopwatch};
use dda_contact::ContactState;
use dda_geom::Motion;

/// Most springs that may differ from the factorised matrix before an OCI iteration
/// assembles and factorises anew rather than solving through a low-rank update. Measured
/// on paper 5.2b (4,956 unknowns, one run each) with the half-sweep low-rank solve
/// (`BlockSystem::solve_low_rank`): solve seconds per OCI iteration 1.43 ms at 24, 1.34
/// at 48, 1.12 at 64, 1.11 at 80, 1.03 at 96, 1.11 at 128 and 1.14 at 200 (a
/// factorisation costs about 2.7 ms; beyond about 100 terms the capacitance matrix and
/// the Gram products of the new columns cost as much). With full solves per column it
/// had been 1.85 ms at 24 and 2.02 at 64. Measured again after the dt growth rule: a
/// low-rank solve of rank 100-149 costs 1.25 ms and one of 150-199 2.41 ms; at a bound
/// of 200 the run saved 302 factorisations and lost more in low-rank solves
/// (`docs/performance.md`).
pub(crate) const MAX_RANK: usize = 96;

/// How far a share of the step a contact acts for (`Simulation::engaged`,
/// `Simulation::release`) may move between the trial it was taken from and the next,
/// relative to it, before the open-close iteration takes one more iteration. The energy
/// the contact's spring gives or takes in the step is wrong by that share of itself. Our
/// choice: the contact law's band, [`DECISION_BAND`], a thousandth.
pub(crate) const SHARE_TOLERANCE: f64 = DECISION_BAND;

/// How many times `max_oci` an open-close iteration may run while only contacts with
/// friction still change state, or a trial still moves a sliding contact's friction
/// force, before its attempt is cut (dt / 3), or, where its states have converged, ends
/// with its friction forces as they stand. At `max_oci` an attempt whose states have
/// converged ends with its shares as they stand, and one whose last iteration
/// changed a frictionless contact or activated a cover is cut as before; one whose last
/// iteration changed only contacts with friction (stick and slip, a turn, opening or
/// closing) goes on while they change, up to this bound. Such an attempt is kept only
/// where its result keeps the physics guard (`Simulation::try_step`); its iterations
/// count towards the easy-step rule as any others (`time_step::step_growth`: those
/// that changed only stick and slip do not). Our choice (docs/method.md
/// section 7): on jointed masses with friction the changes of an attempt die out over a
/// few more iterations (traced on a 2,130-block pit wall: 97, 44, 10, 2, then 1 or 2 of
/// some 14,000 contacts), and cut at `max_oci` such steps fell to a hundredth of the step
/// asked for and never grew back: dt held down by a few contacts of thousands.
/// Frictionless scenes (the paper's columns) are left as they were: there a bound of 7
/// or 12 instead of 6 turned TB-CD-2's 826-block column, a contact it loses for 60 ms
/// and finds 19 mm deep, into energy created (5, 6, 8, 9 and 10 did not). Until
/// 2026-11-28 friction forces that a trial still moved ended at `max_oci` as they stood:
/// a block written on a fixed block at d_n = 0 and sliding at 1 m/s (friction 30
/// degrees, unsettled) ended its first step, at its seventh iteration, with a friction
/// force of 196 kN taken from a trial where it had pitched onto its front corner, where
/// its own normal force carried 25 kN, and stopped after 0.0385 m of the 0.0883 m
/// friction allows.
pub(crate) const OCI_GRACE: u32 = 3;

impl Simulation {
    /// Predicts the contact states of a step before its first OCI iteration: the step's
    /// right-hand side, with the states inherited from the previous step, solved with the
    /// previous step's factor (same pattern; geometry and dt one step apart), and every
    /// active contact re-checked against that approximate motion. About a tenth of a
    /// collapsing column's contacts change state at each step; found here for the price
    /// of one solve, they no longer cost a factorisation in the OCI, which still decides
    /// every state and convergence with exact solves. Skipped when the pattern changed.
    /// (Our choice: the paper starts the OCI from the previous step's states.)
    ///
    /// A scene with friction predicts from the step's own matrix instead
    /// ([`Simulation::predict_states_exactly`], as a system solved iteratively always
    /// does), from its second step on. The last step's factor is that of its first
    /// iteration, with the states predicted then; the changes its later iterations made
    /// reached their solutions through low-rank terms this prediction does not apply, and
    /// where many contacts go between stick and slip within a step it starts from states
    /// the last step had left behind. The step's factor then serves the open-close
    /// iteration's low-rank updates from its first iteration on. Measured
    /// (docs/method.md section 3): the seismic example 750 steps and 1,138 OCI iterations
    /// against 783 and 3,113; without friction the paper's 826-block column took 1,613
    /// factorisations against 1,067 and 19% longer for 6% fewer OCI iterations, so
    /// frictionless scenes keep the last step's factor.
    pub(crate) fn predict_states(&mut self, rec: &mut StepRecord) -> Result<(), SimError> {
        // The friction forces the last attempt's iteration set are not this step's.
        self.scratch.friction_trials.clear();
        if self.scratch.system.is_iterative()
            || (self.effects.friction && self.state.totals.steps > 0)
        {
            return self.predict_states_exactly(rec);
        }
        if !self.scratch.system.is_factored() {
            if self.state.totals.steps == 0 {
                self.predict_states_kinematically(rec);
            }
            return Ok(());
        }
        let mut watch = Stopwatch::start();
        // The prediction is no iteration of the attempt: its changes are not counted.
        self.scratch.flips.clear();
        self.collect_springs();
        self.scratch.system.clear_rhs();
        self.assemble_rhs();
        watch.lap(rec, Phase::Assembly);
        let solved = self.scratch.system.resolve();
        watch.lap(rec, Phase::Solve);
        if solved {
            self.gather_solution();
            self.update_states();
            watch.lap(rec, Phase::Assembly);
        }
        Ok(())
    }

    /// The state predictor of a run's first step, which has no earlier factor: every
    /// active contact re-checked against the motion the blocks' current velocities give
    /// over the step, V dt. A block that starts moving along its
    /// support (a scene's initial velocity, its contacts locked by the settling) is
    /// predicted sliding; decided from its step-start states, its first trials held it
    /// on locked springs and pivoted it about them, and the iteration took a step with
    /// friction forces of another trial's normal forces (a block sliding on level
    /// ground at 1 m/s stopped after 0.137 m instead of 0.140 m).
    fn predict_states_kinematically(&mut self, rec: &mut StepRecord) {
        let mut watch = Stopwatch::start();
        self.scratch.flips.clear();
        let dt = self.scratch.attempt_dt;
        let blocks = &self.state.blocks;
        let free = |i: usize, _: u32| blocks[i].velocity.map(|v| v * dt);
        set_motions(
            &self.free,
            &mut self.scratch.d,
            &mut self.scratch.motions,
            &self.scratch.shapes,
            &self.scratch.half,
            free,
        );
        self.update_states();
        watch.lap(rec, Phase::Assembly);
    }

    /// The state predictor from the step's own matrix and right-hand side with the
    /// inherited states, solved (factorised, or iteratively), and every active contact
    /// re-checked against that motion.
    fn predict_states_exactly(&mut self, rec: &mut StepRecord) -> Result<(), SimError> {
        self.scratch.flips.clear();
        self.collect_springs();
        if self.assemble_and_factorise(rec)? {
            let mut watch = Stopwatch::start();
            self.gather_solution();
            self.update_states();
            watch.lap(rec, Phase::Assembly);
        }
        Ok(())
    }

    /// Open-close iteration at step size `dt` (base terms already built). Returns whether
    /// it converged, how many iterations it took, and how many of them are no sign of a
    /// hard step: those that changed no state (taken for the forces alone: friction and
    /// the shares of a step) and those that changed only stick and slip (docs/method.md
    /// section 7).
    pub(crate) fn open_close_iteration(
        &mut self,
        rec: &mut StepRecord,
    ) -> Result<(bool, u32, u32), SimError> {
        let max_oci = self.model.params.max_oci;
        let bound = max_oci.saturating_mul(OCI_GRACE);
        // Each attempt counts its contacts' changes afresh (see `contact_law`).
        self.scratch.flips.clear();
        self.scratch.flips.resize(self.state.contacts.len(), 0);
        self.scratch.friction_trials.clear();
        self.scratch
            .friction_trials
            .resize(self.state.contacts.len(), FrictionTrial::NONE);
        let mut not_hard = 0;
        // Whether the trial about to be solved has the contact states of the one before.
        let mut same_states = false;
        for it in 1..=bound {
            if !self.solve_states(rec)? {
                return Ok((false, it, not_hard));
            }
            let mut watch = Stopwatch::start();
            self.gather_solution();
            if let Some(i) = (0..self.scratch.d.len())
                .find(|&i| self.scratch.d[i].iter().any(|x| !x.is_finite()))
            {
                return Err(SimError::NonFinite {
                    t: self.state.t,
                    block: self.model.blocks[i].id.clone(),
                });
            }
            let mut changed = self.update_states();
            changed -= self.relax_friction(same_states);
            watch.lap(rec, Phase::Assembly);
            let activated = self.scratch.track_list.track(
                self.detector.as_ref(),
                &self.scratch.shapes,
                &self.scratch.motions,
                &mut self.state.contacts,
            );
            if activated > 0 {
                self.set_up_new_active();
            }
            changed += activated;
            same_states = changed == 0;
            watch.lap(rec, Phase::Detection);
            // From `max_oci` on, only changes at contacts with friction go on
            // (`OCI_GRACE`).
            if it >= max_oci && (activated > 0 || self.scratch.frictionless_changes > 0) {
                return Ok((false, it, not_hard));
            }
            // An iteration that changed only stick and slip is no sign of a hard step
            // (docs/method.md section 7).
            let slip_only = activated == 0
                && self.scratch.frictionless_changes == 0
                && self.scratch.opened_or_closed == 0;
            if changed > 0 && slip_only {
                not_hard += 1;
            }
            // The shares of the step that contacts closing or opening within it act for
            // are taken from the trial before (`Simulation::engaged`, `release`): one more
            // iteration where this trial moves one of them, before `max_oci`. A sliding
            // contact's friction force is taken from the trial before too, and must be
            // that of the step's own normal force: one more iteration where this trial
            // moves one, up to the grace bound (`OCI_GRACE`), where the attempt ends as it
            // stands.
            if changed == 0 {
                let friction = self.friction_moved();
                if it == bound || (!friction && (it >= max_oci || !self.shares_moved())) {
                    return Ok((true, it, not_hard));
                }
                not_hard += 1;
            }
        }
        Ok((false, bound, not_hard))
    }

    /// Solves for the current contact states: through the factor already computed when
    /// few springs changed since, otherwise by assembling and factorising anew (or
    /// solving iteratively). False when an iterative solve did not meet its bound.
    pub(crate) fn solve_states(&mut self, rec: &mut StepRecord) -> Result<bool, SimError> {
        let mut watch = Stopwatch::start();
        self.collect_springs();
        let shear = self.scratch.springs.iter().filter(|s| s.shear).count() as u64;
        self.state.totals.shear_springs += shear;
        self.state.totals.normal_springs += self.scratch.springs.len() as u64 - shear;
        self.state.totals.friction_forces += self.scratch.forces.len() as u64;
        if self.scratch.system.is_iterative() {
            // Changed springs (and friction forces) are added to the matrix and the
            // right-hand side while they are fewer than the springs a new assembly
            // would add.
            let limit = self.scratch.springs.len().max(MAX_RANK);
            if self.scratch.factor_current && self.spring_changes(limit).is_some() {
                self.force_changes();
                let system = &mut self.scratch.system;
                for t in &self.scratch.changes {
                    system.add_rank_one(t);
                }
                for t in &self.scratch.rhs_changes {
                    system.add_rhs_term(t);
                }
                watch.lap(rec, Phase::Assembly);
                let solved = self.solve_iteratively();
                watch.lap(rec, Phase::Solve);
                self.keep_assembled();
                return Ok(solved.converged);
            }
        } else if self.scratch.factor_current
            && self.scratch.system.is_factored()
            && self.spring_changes(MAX_RANK).is_some()
        {
            self.force_changes();
            watch.lap(rec, Phase::Assembly);
            let solved = self
                .scratch
                .system
                .solve_low_rank(&self.scratch.changes, &self.scratch.rhs_changes);
            watch.lap(rec, Phase::Solve);
            if solved {
                return Ok(true);
            }
        } else {
            watch.lap(rec, Phase::Assembly);
        }
        self.assemble_and_factorise(rec)
    }

    /// Whether the current trial moves a share of the step that a contact closing or
    /// opening within it acts for (`Simulation::engaged`, `Simulation::release`) from the
    /// share the trial was solved with, by more than [`SHARE_TOLERANCE`] of the share and
    /// by a force beyond the contact law's band (the contact's normal force times the
    /// change; a change of negligible force keeps the state, as the decisions do,
    /// `contact_law`).
    fn shares_moved(&self) -> bool {
        let contacts = &self.state.contacts.contacts;
        let scale = &self.scratch.force_scale;
        let moved = |k: usize, now: f64, then: f64, force: f64| {
            let change = (now - then).abs();
            change > SHARE_TOLERANCE * now.max(then)
                && change * force > decision_band(scale, contacts[k].key)
        };
        self.scratch.engaged.iter().any(|&(k, before)| {
            let k = k as usize;
            moved(k, self.engaged(k), 1.0 - before, contacts[k].normal_force)
        }) || self.scratch.released.iter().any(|&(k, f, _)| {
            let k = k as usize;
            let force = self.scratch.saved.get(k).map_or(0.0, |c| c.normal_force);
            // Both shares as the release's force term holds them, -(1 - phi).
            self.released_share(k)
                .is_some_and(|phi| moved(k, 1.0 - (1.0 - phi), 1.0 + f, force))
        })
    }

    /// Sets the friction force the next trial applies at each sliding contact whose
    /// friction swings (docs/method.md section 6), and returns how many contacts it kept
    /// sliding against the contact law's decision. A sliding contact's friction force
    /// enters a trial as a force, the one its normal force in the trial before asks for.
    /// Where a trial's own normal force asks for more than it was solved with and the
    /// trial before, solved with the same contact states, asked for less (or the other
    /// way), the two trials bracket the friction force that agrees with its own normal
    /// force, and the next trial takes it where the line through them crosses (regula
    /// falsi), between the two. A contact the trial turned back and the contact law
    /// locked at its reversal is kept sliding where the two trials bracket its friction
    /// so: it turned back under a friction force its own normal force does not carry, a
    /// force the next trial takes down. `same_states`: whether the trial just solved had
    /// the contact states of the one before, so that only friction forces differed
    /// between them. (Between trials of other states, a swing is the other changes', and
    /// the next trial takes the force its normal force asks for, as before.)
    fn relax_friction(&mut self, same_states: bool) -> usize {
        let carried = self.step_rule() == crate::assembly::StepRule::Average;
        let mut trials = std::mem::take(&mut self.scratch.friction_trials);
        let forces = std::mem::take(&mut self.scratch.forces);
        let mut kept = 0;
        for &(k, used, _) in &forces {
            let k = k as usize;
            let mut c = self.state.contacts.contacts[k];
            let j = self.joint(k);
            let Some(t) = trials.get_mut(k) else {
                continue;
            };
            if !(c.active && j.has_shear()) {
                *t = FrictionTrial::NONE;
                continue;
            }
            let share = if carried { self.engaged(k) } else { 1.0 };
            let limit = share * self.friction_limit(&c, &j);
            // The friction force the trial's normal force asks for against slip in `dir`.
            let asked = |dir: f64| -dir * limit;
            // Solved sliding in the trial of the same states as the one before (so with
            // a trial record), locked at its reversal.
            if same_states && c.state == ContactState::Locked && used != 0.0 {
                let dir = -used.signum();
                if t.residual() * (asked(dir) - used) < 0.0 {
                    c.state = ContactState::Sliding;
                    c.slide_dir = dir;
                    self.state.contacts.contacts[k] = c;
                    if let Some(f) = self.scratch.flips.get_mut(k) {
                        *f = f.saturating_sub(1);
                    }
                    self.scratch.flipped.retain(|&x| x as usize != k);
                    kept += 1;
                }
            }
            if !(c.state == ContactState::Sliding && c.slide_dir != 0.0) {
                *t = FrictionTrial::NONE;
                continue;
            }
            let now = asked(c.slide_dir);
            let (r, before) = (now - used, t.residual());
            t.next = if same_states && before * r < 0.0 {
                used - r * (used - t.used) / (r - before)
            } else {
                f64::NAN
            };
            t.used = used;
            t.asked = now;
        }
        self.scratch.friction_trials = trials;
        self.scratch.forces = forces;
        kept
    }

    /// Whether the current trial moves a sliding contact's friction force from the one
    /// the trial was solved with (taken from the normal force of the trial before), by
    /// more than [`SHARE_TOLERANCE`] of it and by a force beyond the contact law's band.
    /// The open-close iteration ends on states; without this, a step could end with its
    /// friction forces those of another step's normal forces: a rigid block sliding on
    /// level ground at 1 m/s (friction 20 degrees, settled) stopped after 0.094 m
    /// instead of v^2 / (2 g tan phi) = 0.140 m, rocking onto its front corner, and a
    /// deformable one after 0.136 m; now 0.140 m both.
    fn friction_moved(&self) -> bool {
        let contacts = &self.state.contacts.contacts;
        let scale = &self.scratch.force_scale;
        let trials = &self.scratch.friction_trials;
        // The force each sliding contact's trial asked for is in its friction trial
        // (`Simulation::relax_friction`, after the trial's decisions).
        self.scratch.forces.iter().any(|&(k, used, _)| {
            let Some(t) = trials.get(k as usize).filter(|t| !t.asked.is_nan()) else {
                return false;
            };
            let change = (t.asked - used).abs();
            change > SHARE_TOLERANCE * t.asked.abs().max(used.abs())
                && change > decision_band(scale, contacts[k as usize].key)
        })
    }

    /// The difference between the springs in effect and those in the factorised (or,
    /// solved iteratively, assembled) matrix, as rank-one terms (both lists are in
    /// contact order); None if it has more than `limit` terms.
    pub(crate) fn spring_changes(&mut self, limit: usize) -> Option<()> {
        self.scratch.changes.clear();
        self.scratch.rhs_changes.clear();
        let (now, then) = (&self.scratch.springs, &self.scratch.factored_springs);
        let (mut i, mut j) = (0, 0);
        let free = &self.free;
        let (rows, sheared, set, shapes, half) = (
            &self.scratch.rows,
            &self.scratch.sheared,
            &self.state.contacts,
            &self.scratch.shapes,
            &self.scratch.half,
        );
        let (changes, rhs_changes) = (&mut self.scratch.changes, &mut self.scratch.rhs_changes);
        // A spring added (sign 1) or removed (-1): its stiffness p c c^T and its
        // right-hand side -p g0 c.
        let mut change = |s: &Spring, sign: f64| {
            let row = s.row(rows, sheared, set, shapes, half);
            let blocks = [free[row.blocks[0] as usize], free[row.blocks[1] as usize]];
            changes.push(RankOne {
                blocks,
                c: row.c,
                s: sign * s.stiffness(),
            });
            rhs_changes.push(RankOne {
                blocks,
                c: row.c,
                s: sign * s.rhs(&row),
            });
            changes.len() <= limit
        };
        while i < now.len() || j < then.len() {
            let key = |s: &Spring| (s.contact, s.shear);
            let within = match (now.get(i), then.get(j)) {
                (Some(a), Some(b)) if key(a) == key(b) => {
                    i += 1;
                    j += 1;
                    // Equal springs of one attempt have equal rows.
                    a == b || {
                        change(a, 1.0);
                        change(b, -1.0)
                    }
                }
                (Some(a), Some(b)) if key(a) < key(b) => {
                    i += 1;
                    change(a, 1.0)
                }
                (Some(a), None) => {
                    i += 1;
                    change(a, 1.0)
                }
                (_, Some(b)) => {
                    j += 1;
                    change(b, -1.0)
                }
                (None, None) => break,
            };
            if !within {
                return None;
            }
        }
        Some(())
    }

    /// Adds the changes of the friction forces since the factorisation to the
    /// right-hand side changes (both lists are in contact order).
    pub(crate) fn force_changes(&mut self) {
        let (now, then) = (&self.scratch.forces, &self.scratch.factored_forces);
        let free = &self.free;
        let mut change = |f: f64, row: &Row| {
            self.scratch.rhs_changes.push(RankOne {
                blocks: [free[row.blocks[0] as usize], free[row.blocks[1] as usize]],
                c: row.c,
                s: f,
            });
        };
        let (mut i, mut j) = (0, 0);
        while i < now.len() || j < then.len() {
            match (now.get(i), then.get(j)) {
                (Some(a), Some(b)) if a.0 == b.0 => {
                    if a.2 == b.2 {
                        if a.1 != b.1 {
                            change(a.1 - b.1, &a.2);
                        }
                    } else {
                        change(a.1, &a.2);
                        change(-b.1, &b.2);
                    }
                    i += 1;
                    j += 1;
                }
                (Some(a), Some(b)) if a.0 < b.0 => {
                    change(a.1, &a.2);
                    i += 1;
                }
                (Some(a), None) => {
                    change(a.1, &a.2);
                    i += 1;
                }
                (_, Some(b)) => {
                    change(-b.1, &b.2);
                    j += 1;
                }
                (None, None) => break,
            }
        }
    }

    /// Copies the solution into per-block motions (zero for fixed blocks, the ground's
    /// for driven ones).
    pub(crate) fn gather_solution(&mut self) {
        let nd = self.nd;
        let system = &self.scratch.system;
        let free = |_, f| {
            let mut d = [0.0; 6];
            d[..nd].copy_from_slice(system.solution(f));
            d
        };
        set_motions(
            &self.free,
            &mut self.scratch.d,
            &mut self.scratch.motions,
            &self.scratch.shapes,
            &self.scratch.half,
            free,
        );
    }

    /// Sets up the contacts made active since [`Simulation::linearise`] (by trajectory
    /// tracking, or a spring moved to the deepest face; the ones whose row is still
    /// [`NO_ROW`]): their rows are linearised as `linearise` would have, and those
    /// tracking brought back locked slide instead where the joint has no shear (every
    /// other closed contact of such a joint slides already: the step-start normalisation
    /// and `update_states` see to it).
    pub(crate) fn set_up_new_active(&mut self) {
        for &k in self.scratch.track_list.activated() {
            let k = k as usize;
            let c = self.state.contacts.contacts[k];
            if !(c.active && self.scratch.rows[k].g0.is_nan()) {
                continue;
            }
            self.scratch.rows[k] = normal_row(&c, &self.scratch.shapes, &self.scratch.half);
            if c.state == ContactState::Locked && !self.joint(k).has_shear() {
                self.state.contacts.contacts[k].state = ContactState::Sliding;
            }
        }
    }
}

/// A sliding contact's last friction trial in the open-close iteration
/// ([`Simulation::relax_friction`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct FrictionTrial {
    /// The friction force the trial was solved with, N (signed along the shear row).
    used: f64,
    /// The force its normal force in the trial asked for, N; NaN: no trial (the contact
    /// did not slide in it).
    asked: f64,
    /// The force the next trial takes, N; NaN: the one its normal force asks for.
    next: f64,
}

impl FrictionTrial {
    /// No trial.
    pub(crate) const NONE: FrictionTrial = FrictionTrial {
        used: f64::NAN,
        asked: f64::NAN,
        next: f64::NAN,
    };

    /// How far the force the trial asked for is from the one it was solved with, N.
    fn residual(&self) -> f64 {
        self.asked - self.used
    }

    /// The force the next trial takes at a contact sliding in direction `dir`, where
    /// the iteration set one that resists that direction.
    pub(crate) fn next(&self, dir: f64) -> Option<f64> {
        (self.next.is_finite() && -dir * self.next >= 0.0).then_some(self.next)
    }
}

/// Each block's motion `d` for the attempt and its map of points `motions`: a free
/// block's from `free(block, free index)`, a driven block's the ground's over the step,
/// any other block's none.
fn set_motions(
    free_of: &[Option<u32>],
    d: &mut [Vec6],
    motions: &mut Vec<Motion>,
    shapes: &[dda_contact::BlockShape],
    half: &[HalfStep],
    free: impl Fn(usize, u32) -> Vec6,
) {
    motions.clear();
    for (i, f) in free_of.iter().enumerate() {
        d[i] = match (f, half[i].driven) {
            (Some(f), _) => free(i, *f),
            (None, Some(u)) => [u.x, u.y, 0.0, 0.0, 0.0, 0.0],
            (None, None) => [0.0; 6],
        };
        motions.push(Motion::new(shapes[i].centroid, &d[i]));
    }
}
