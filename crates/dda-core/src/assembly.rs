//! Assembly of the global system: each free block's own terms (inertia, elasticity,
//! gravity, loads, fixed points: [`block_terms`], computed apart from the global
//! matrix), the contact rows linearised for the attempt, the springs and friction
//! forces of the current contact states, and their scatter into the block-sparse
//! matrix and right-hand side.

use crate::diagnosis::SimError;
use crate::effects::Effects;
use crate::kinematics::{Mat6, Vec6, along, elasticity, half_turned, mass_matrix, own_damping};
use crate::scene::{Integration, JointProps, Mode, Model};
use crate::simulation::Simulation;
use crate::solver::{BlockSystem, Entry};
use crate::springs::{HalfStep, Row, contact_length, normal_row, shear_row};
use crate::state::{BlockState, StepRecord};
use crate::timing::{Phase, Stopwatch};
use dda_contact::{BlockShape, Contact, ContactSet, ContactState};
use dda_geom::DVec2;

/// Fewest free blocks for which per-block terms are computed on the thread pool (when
/// [`RunOptions::parallel`] is on): below it, waking the pool costs more than it saves.
#[cfg(feature = "rayon")]
pub(crate) const PARALLEL_MIN_BLOCKS: usize = 256;

/// A spring in effect in an OCI iteration: its contact, whether it is the shear spring
/// (else the normal one), its penalty, where it couples in the system, and what its row
/// depends on besides the attempt's geometry: nothing for a normal spring (its row is
/// the contact's in `rows`), the locked point for a shear spring. Two springs of one
/// attempt that compare equal have the same row ([`Simulation::spring_row`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Spring {
    pub(crate) contact: u32,
    pub(crate) shear: bool,
    pub(crate) penalty: f64,
    /// The dashpot beside the spring over the step's length, beta / dt (0 without one;
    /// [`Dashpots`]): the spring's force is p (q + beta / dt (q - q_ref)), q_ref where
    /// the dashpot measures from ([`dashpot_base`]).
    pub(crate) viscous: f64,
    /// The system entry coupling its two blocks, if both are free.
    pub(crate) entry: Option<Entry>,
    /// The shear spring's locked point (ratio along the edge); 0 for a normal spring.
    pub(crate) anchor: f64,
}

impl Spring {
    /// The stiffness it adds to the matrix: its penalty and its dashpot's,
    /// p (1 + beta / dt).
    #[inline]
    pub(crate) fn stiffness(&self) -> f64 {
        self.penalty * (1.0 + self.viscous)
    }

    /// The coefficient of its row's coefficients in the right-hand side, for its `row`:
    /// -p (g0 + beta / dt (g0 - q_ref)), the dashpot acting on q - q_ref ([`dashpot_base`]).
    #[inline]
    pub(crate) fn rhs(&self, row: &Row) -> f64 {
        -self.penalty * (row.g0 + self.viscous * (row.g0 - dashpot_base(row)))
    }

    /// Its row in the attempt whose contact rows are `rows` and whose shear rows made so
    /// far are `sheared` (see [`Simulation::spring_row`]).
    #[inline]
    pub(crate) fn row(
        &self,
        rows: &[Row],
        sheared: &ShearRows,
        set: &ContactSet,
        shapes: &[BlockShape],
        half: &[HalfStep],
    ) -> Row {
        let k = self.contact as usize;
        if self.shear {
            sheared.row(k, self.anchor, &set.contacts[k], shapes, half)
        } else {
            rows[k]
        }
    }
}

/// The dashpots beside the normal springs of the contacts at rest in an attempt (not in
/// impact at its start, [`Simulation::in_impact`]; docs/method.md section 12): each
/// damps its spring's vibration at its own frequency w = sqrt(p / m),
/// m the reduced mass of the contact's two blocks (a fixed, driven or removed block
/// counts as infinitely heavy), at the ratio `analysis.contact_damping` z, as a dashpot
/// of coefficient beta p, beta = 2 z / w. It acts on the change of the spring's measure
/// over the step, at its mean rate (the blocks' strain damping does so too), from where
/// the blocks touched ([`dashpot_base`]): the spring's force is
/// p (q + beta / dt (q - q_ref)). Only in the dynamic steps Shi's rule
/// takes: static steps (and the settling) have no velocity to damp, and the
/// average-acceleration rule of an impact resolved in time keeps its energy. Why: a
/// block held at its friction limit on penalty springs has rocking and bouncing modes
/// that friction feeds (a flutter), which Shi's rule damps only where its step is long
/// against their period, so that finer steps gave worse answers.
#[derive(Debug, Default)]
pub(crate) struct Dashpots {
    /// 2 z / (dt sqrt(p)): a contact's beta / dt is this times sqrt(m) (0: none).
    scale: f64,
    /// Each block's inverse mass, 1 / kg (0 for a fixed, driven or removed block).
    inverse_mass: Vec<f64>,
    /// Per contact: whether it is in impact at the step's start
    /// ([`Simulation::in_impact`]), and so has no dashpot.
    in_impact: Vec<bool>,
}

impl Dashpots {
    /// beta / dt of the dashpot beside contact `k`'s normal spring, `key` its blocks
    /// (0: none).
    #[inline]
    pub(crate) fn normal(&self, k: usize, key: dda_contact::ContactKey) -> f64 {
        if self.scale == 0.0 || self.in_impact.get(k).copied().unwrap_or(true) {
            return 0.0;
        }
        let m_inv = self.inverse_mass[key.vertex_block as usize]
            + self.inverse_mass[key.edge_block as usize];
        if m_inv > 0.0 {
            self.scale / m_inv.sqrt()
        } else {
            0.0
        }
    }
}

impl Simulation {
    /// Sets the attempt's dashpots ([`Dashpots`]): after the base terms (the blocks'
    /// masses) and with the step's rule known.
    pub(crate) fn set_dashpots(&mut self) {
        let p = &self.model.params;
        // Under the average-acceleration rule throughout, a step taken by Shi's rule (the
        // first, whose start accelerations are unknown) carries its end's acceleration
        // into the next: a dashpot's force in it would push on where no dashpot acts.
        let active = p.contact_damping > 0.0
            && p.mode == Mode::Dynamic
            && p.integration != Integration::AverageAcceleration
            && self.step_rule().viscous();
        let dt = self.scratch.attempt_dt;
        let dash = &mut self.scratch.dashpots;
        dash.scale = if active {
            2.0 * p.contact_damping / (dt * p.normal_penalty.sqrt())
        } else {
            0.0
        };
        dash.inverse_mass.clear();
        dash.inverse_mass.resize(self.free.len(), 0.0);
        dash.in_impact.clear();
        if !active {
            return;
        }
        for (mass, &i) in self.scratch.mass.iter().zip(&self.free_blocks) {
            dash.inverse_mass[i as usize] = 1.0 / mass[0][0];
        }
        let mut in_impact = std::mem::take(&mut self.scratch.dashpots.in_impact);
        in_impact.resize(self.state.contacts.len(), false);
        for pc in &self.state.contacts.pairs {
            if let Some((_, speed)) = self.impact_speed(pc.pair) {
                for k in pc.start as usize..pc.end as usize {
                    in_impact[k] = self.in_impact(&self.state.contacts.contacts[k], speed);
                }
            }
        }
        self.scratch.dashpots.in_impact = in_impact;
    }
}

/// Where a spring's dashpot measures the change of its measure q from: its value at the
/// step's start, q0 = g0 less a driven block's known motion over the step
/// (`Row::driven`, folded into g0), or 0 where the contact was open then (q0 > 0): the
/// blocks' approach through the gap before they touch is no motion of the spring.
#[inline]
pub(crate) fn dashpot_base(row: &Row) -> f64 {
    (row.g0 - row.driven).min(0.0)
}

/// The shear rows of an attempt's contact states, by contact: each locked contact's at
/// its locked point and each sliding one's at its ratio, made by
/// [`Simulation::collect_springs`] when a contact's anchor is new to the attempt, and
/// read by the assembly, the low-rank changes and the contact law (a shear row was a
/// tenth of a wall's step when made at each use). The geometry is the attempt's
/// ([`Simulation::linearise`] forgets them): the same bits as made anew.
#[derive(Debug, Default)]
pub(crate) struct ShearRows {
    /// Per contact: its entry in `rows`, or `u32::MAX`.
    at: Vec<u32>,
    /// The anchor each row was made at, and the row.
    rows: Vec<(f64, Row)>,
}

impl ShearRows {
    /// Forgets every row (a new attempt's geometry).
    fn clear(&mut self) {
        self.at.clear();
        self.rows.clear();
    }

    /// Contact `k`'s row kept at `anchor`, if one is.
    #[inline]
    fn kept(&self, k: usize, anchor: f64) -> Option<&Row> {
        let (a, row) = self.rows.get(*self.at.get(k)? as usize)?;
        (a.to_bits() == anchor.to_bits()).then_some(row)
    }

    /// Contact `k`'s shear row at `anchor`: the one kept if it was made at that anchor,
    /// else made and kept (in place of one at another anchor).
    fn make(
        &mut self,
        k: usize,
        anchor: f64,
        c: &Contact,
        shapes: &[BlockShape],
        half: &[HalfStep],
    ) -> Row {
        if let Some(row) = self.kept(k, anchor) {
            return *row;
        }
        let row = shear_row(c, shapes, half, anchor);
        if self.at.len() <= k {
            self.at.resize(k + 1, u32::MAX);
        }
        match self.rows.get_mut(self.at[k] as usize) {
            Some(kept) => *kept = (anchor, row),
            None => {
                self.at[k] = self.rows.len() as u32;
                self.rows.push((anchor, row));
            }
        }
        row
    }

    /// Contact `k`'s shear row at `anchor`: the one kept if it was made at that anchor,
    /// else made anew (not kept).
    #[inline]
    pub(crate) fn row(
        &self,
        k: usize,
        anchor: f64,
        c: &Contact,
        shapes: &[BlockShape],
        half: &[HalfStep],
    ) -> Row {
        self.kept(k, anchor)
            .copied()
            .unwrap_or_else(|| shear_row(c, shapes, half, anchor))
    }
}

/// The share of a step after which a gap changing at a steady rate from `g` at the
/// step's start to `d` at its end crosses zero (`g` and `d` of opposite signs).
fn crossing(g: f64, d: f64) -> f64 {
    (-g / (d - g)).clamp(0.0, 1.0)
}

/// The row of an inactive contact until it becomes active: NaN, so that a read of it
/// could not pass unseen.
pub(crate) const NO_ROW: Row = Row {
    g0: f64::NAN,
    blocks: [0, 0],
    c: [[0.0; 6]; 2],
    driven: 0.0,
};

impl Simulation {
    /// Per-block terms that do not depend on contacts (see [`block_terms`]), one per free
    /// block in free-block order. With `parallel` they are computed on the thread pool:
    /// each block's terms depend on that block alone, so the result is the same.
    pub(crate) fn base_terms(&mut self, dt: f64) {
        self.scratch.attempt_dt = dt;
        self.scratch.iteration_ready = false;
        self.block_base_terms(dt);
        self.bolt_terms();
    }

    /// The per-block part of [`Simulation::base_terms`].
    fn block_base_terms(&mut self, dt: f64) {
        let n = self.free_blocks.len();
        self.scratch.base_k.resize(n, [[0.0; 6]; 6]);
        self.scratch.base_f.resize(n, [0.0; 6]);
        self.scratch.mass.resize(n, [[0.0; 6]; 6]);
        let (model, blocks, eff) = (&self.model, &self.state.blocks, self.effects);
        let rule = self.step_rule();
        let terms = |(((k, f), mass), &i): (((&mut Mat6, &mut Vec6), &mut Mat6), &u32)| {
            (*k, *f, *mass) = block_terms(model, eff, rule, &blocks[i as usize], i as usize, dt);
        };
        #[cfg(feature = "rayon")]
        if self.threads() && n >= PARALLEL_MIN_BLOCKS {
            use rayon::prelude::*;
            self.scratch
                .base_k
                .par_iter_mut()
                .zip(self.scratch.base_f.par_iter_mut())
                .zip(self.scratch.mass.par_iter_mut())
                .zip(self.free_blocks.par_iter())
                .for_each(terms);
            return;
        }
        self.scratch
            .base_k
            .iter_mut()
            .zip(self.scratch.base_f.iter_mut())
            .zip(self.scratch.mass.iter_mut())
            .zip(self.free_blocks.iter())
            .for_each(terms);
    }

    /// The joint of contact `k` (see [`joint_of`]), as detection found it for the step.
    pub(crate) fn joint(&self, k: usize) -> JointProps {
        self.scratch.joints[k]
    }

    /// Sets the half step of every block for an attempt of size `dt` and the contacts'
    /// normal rows, linearised there (see `springs`).
    pub(crate) fn linearise(&mut self, dt: f64) {
        self.scratch.half.clear();
        self.scratch.sheared.clear();
        let ground = self.ground_step(dt);
        for (i, s) in self.scratch.shapes.iter().enumerate() {
            self.scratch.half.push(match (self.free[i], ground) {
                (Some(_), _) => HalfStep::new(s.centroid, &self.state.blocks[i].velocity, dt),
                (None, Some((half, step))) if self.model.blocks[i].driven => {
                    HalfStep::driven(s.centroid, half, step)
                }
                (None, _) => HalfStep::at_rest(s.centroid),
            });
        }
        self.scratch.rows.clear();
        for c in &self.state.contacts.contacts {
            self.scratch.rows.push(if c.active {
                normal_row(c, &self.scratch.shapes, &self.scratch.half)
            } else {
                NO_ROW
            });
        }
    }

    /// Collects the springs and friction forces of the current contact states: the active
    /// closed contacts' normal springs, and, where the joint has shear, locked contacts'
    /// shear springs and sliding contacts' friction forces.
    pub(crate) fn collect_springs(&mut self) {
        self.scratch.springs.clear();
        self.scratch.forces.clear();
        self.scratch.released.clear();
        self.scratch.engaged.clear();
        let p = &self.model.params;
        let (pn, ps) = (p.normal_penalty, p.shear_penalty);
        let carried = self.step_rule() == StepRule::Average;
        for (pk, pc) in self.state.contacts.pairs.iter().enumerate() {
            let entry = self.scratch.pair_entry[pk];
            for k in pc.start as usize..pc.end as usize {
                let c = self.state.contacts.contacts[k];
                if !(c.active && c.state.is_closed()) {
                    if carried
                        && c.active
                        && let Some(release) = self.release(k)
                    {
                        self.scratch.forces.push(release);
                        self.scratch.released.push(release);
                    }
                    continue;
                }
                let contact = k as u32;
                // The share of the step the contact is closed in: 1 but where it closed
                // within the step under the average-acceleration rule (`engaged`).
                let share = if carried { self.engaged(k) } else { 1.0 };
                if share < 1.0 {
                    self.scratch.engaged.push((contact, 1.0 - share));
                }
                self.scratch.springs.push(Spring {
                    contact,
                    shear: false,
                    penalty: share * pn,
                    viscous: self.scratch.dashpots.normal(k, c.key),
                    entry,
                    anchor: 0.0,
                });
                let j = self.joint(k);
                if !j.has_shear() {
                    continue;
                }
                match c.state {
                    ContactState::Locked => {
                        let (shapes, half) = (&self.scratch.shapes, &self.scratch.half);
                        self.scratch.sheared.make(k, c.locked_r, &c, shapes, half);
                        self.scratch.springs.push(Spring {
                            contact,
                            shear: true,
                            penalty: share * ps,
                            viscous: 0.0,
                            entry,
                            anchor: c.locked_r,
                        });
                    }
                    ContactState::Sliding if c.slide_dir != 0.0 => {
                        // The force the open-close iteration set where friction swung
                        // (`Simulation::relax_friction`), else the limit.
                        let force = self
                            .scratch
                            .friction_trials
                            .get(k)
                            .and_then(|t| t.next(c.slide_dir))
                            .unwrap_or_else(|| -c.slide_dir * share * self.friction_limit(&c, &j));
                        let (shapes, half) = (&self.scratch.shapes, &self.scratch.half);
                        let row =
                            self.scratch
                                .sheared
                                .make(k, c.r.clamp(0.0, 1.0), &c, shapes, half);
                        self.scratch.forces.push((contact, force, row));
                    }
                    _ => {}
                }
            }
        }
    }

    /// The share of the step contact `k`, closed in the current trial of a step under the
    /// average-acceleration rule, is closed for: 1 if it was closed at the step's start,
    /// else the part of the step after its vertex crossed the edge's line.
    ///
    /// The rule's first force of the step is the step start's, without the contact's
    /// spring, and its last holds the spring pressed to the trial's overlap d < 0: their
    /// mean, p |d| / 2, would act over the whole step's approach g - d (g > 0 the gap at
    /// the step's start), doing the work p |d| (g - d) / 2 where the spring stores
    /// p d^2 / 2. Closing at a steady rate, the contact is closed for the share
    /// -d / (g - d) of the step; its springs and friction taken at that share of their
    /// stiffness and force in the step's system (the accelerations carried on are the
    /// step end's, whole: `update.rs`), their mean force does the work of the energy
    /// stored. With d from the open-close iteration's latest trial, as the release
    /// ([`Simulation::release`]) takes it; 1 where the trial does not cross.
    pub(crate) fn engaged(&self, k: usize) -> f64 {
        if self
            .scratch
            .saved
            .get(k)
            .is_some_and(|start| start.state.is_closed())
        {
            return 1.0;
        }
        let (g, d) = self.step_gaps(k);
        if g > 0.0 && d < 0.0 {
            // The share after the crossing: the step taken backwards, from d to g.
            crossing(d, g)
        } else {
            1.0
        }
    }

    /// Contact `k`'s normal gap at the step's start and at the end of the current trial.
    fn step_gaps(&self, k: usize) -> (f64, f64) {
        let normal = self.scratch.rows[k];
        (normal.g0 - normal.driven, normal.eval(&self.scratch.d))
    }

    /// The share phi of the step contact `k` stays closed for, open in the current trial
    /// but closed at the step's start and carrying a force then (see
    /// [`Simulation::release`]); None otherwise.
    pub(crate) fn released_share(&self, k: usize) -> Option<f64> {
        let start = self.scratch.saved.get(k)?;
        if !start.state.is_closed() || start.normal_force <= 0.0 {
            return None;
        }
        let (g0, d) = self.step_gaps(k);
        Some(if g0 < 0.0 && d > g0 {
            crossing(g0, d)
        } else {
            0.0
        })
    }

    /// The release of contact `k`, open in the current trial of a step under the
    /// average-acceleration rule but closed at the step's start: a force term that takes
    /// back the part of its step-start forces the rule would carry past its separation.
    ///
    /// The rule moves the blocks by the mean of the step's first and last accelerations,
    /// and the first holds every force of the step's start (`StepRule::Average`): the
    /// contact's normal spring, and its shear spring or friction force, would push for
    /// half the step on the whole step's motion, while the spring held only the energy
    /// of its step-start overlap. Measured on a head-on collision of two deformable 1 m
    /// blocks (p = 1e9 N/m, E = 2e10 to 1e11 Pa, 10 steps an impact): the blocks parted
    /// faster than they met (restitution 1.004 to 1.008) and the run stopped on energy
    /// created, 1.3% to 1.8%. A spring unloading at a steady rate from the step-start gap
    /// g0 < 0 to the trial's d > 0 is released after the fraction phi = -g0 / (d - g0) of
    /// the step; carried for that fraction its mean force does the work of the energy it
    /// held, p g0^2 / 2. So (1 - phi) of the step-start forces are taken back, with d from
    /// the open-close iteration's latest trial (as friction takes its normal force).
    /// None where the contact was not closed at the step's start, or carried no force.
    pub(crate) fn release(&self, k: usize) -> Option<(u32, f64, Row)> {
        let phi = self.released_share(k)?;
        let start = &self.scratch.saved[k];
        let row = Row {
            g0: 0.0,
            blocks: self.scratch.rows[k].blocks,
            c: self.contact_forces(k, start, false),
            driven: 0.0,
        };
        Some((k as u32, -(1.0 - phi), row))
    }

    /// The forces contact `k` in state `c` exerts on its two blocks (as in its normal
    /// row's `blocks`), over their unknowns: its normal spring's (normal force times the
    /// normal row), and its shear spring's or friction force's, at the step's start, or
    /// at the current trial's end (`end`).
    pub(crate) fn contact_forces(&self, k: usize, c: &Contact, end: bool) -> [Vec6; 2] {
        let (shapes, half) = (&self.scratch.shapes, &self.scratch.half);
        let normal = self.scratch.rows[k];
        let n = c.normal_force.max(0.0);
        let mut force = normal.c.map(|row| row.map(|x| n * x));
        let value = |row: &Row| {
            if end {
                row.eval(&self.scratch.d)
            } else {
                row.g0 - row.driven
            }
        };
        let j = self.joint(k);
        let shear = match c.state {
            _ if !j.has_shear() => None,
            ContactState::Locked => {
                let row = self.scratch.sheared.row(k, c.locked_r, c, shapes, half);
                Some((-self.model.params.shear_penalty * value(&row), row))
            }
            ContactState::Sliding if c.slide_dir != 0.0 => {
                let limit = self.friction_limit(c, &j);
                let row = self
                    .scratch
                    .sheared
                    .row(k, c.r.clamp(0.0, 1.0), c, shapes, half);
                Some((-c.slide_dir * limit, row))
            }
            _ => None,
        };
        if let Some((f, row)) = shear
            && row.blocks == normal.blocks
        {
            for (fb, cb) in force.iter_mut().zip(&row.c) {
                for (x, c) in fb.iter_mut().zip(cb) {
                    *x += f * c;
                }
            }
        }
        force
    }

    /// The friction force of sliding contact `c` under joint `j`: its normal force times
    /// tan phi, and its cohesion over its length while it is bonded.
    pub(crate) fn friction_limit(&self, c: &Contact, j: &JointProps) -> f64 {
        let mut limit = c.normal_force.max(0.0) * j.tan_phi;
        if c.bonded {
            limit +=
                j.cohesion * contact_length(c, &self.scratch.shapes, self.detection.sin_theta_e());
        }
        limit
    }

    /// The row of spring `s` in this attempt: the contact's normal row, or its shear row
    /// at the spring's locked point (computed again, by the same function on the same
    /// geometry, so the same bits).
    #[inline]
    pub(crate) fn spring_row(&self, s: &Spring) -> Row {
        s.row(
            &self.scratch.rows,
            &self.scratch.sheared,
            &self.state.contacts,
            &self.scratch.shapes,
            &self.scratch.half,
        )
    }

    /// Adds the right-hand side of the base terms, the springs and the forces.
    pub(crate) fn assemble_rhs(&mut self) {
        for (f, rhs) in self.scratch.base_f.iter().enumerate() {
            self.scratch.system.add_rhs(f as u32, 1.0, rhs);
        }
        for s in &self.scratch.springs {
            let row = self.spring_row(s);
            for (b, c) in row.blocks.iter().zip(&row.c) {
                if let Some(f) = self.free[*b as usize] {
                    self.scratch.system.add_rhs(f, s.rhs(&row), c);
                }
            }
        }
        for (_, f, row) in &self.scratch.forces {
            for (b, c) in row.blocks.iter().zip(&row.c) {
                if let Some(fi) = self.free[*b as usize] {
                    self.scratch.system.add_rhs(fi, *f, c);
                }
            }
        }
    }

    /// Assembles K (base terms and springs) and F, and factorises and solves.
    /// Returns false when the system is solved iteratively and the solve did not meet
    /// its bound (`crate::iterative`).
    pub(crate) fn assemble_and_factorise(
        &mut self,
        rec: &mut StepRecord,
    ) -> Result<bool, SimError> {
        let mut watch = Stopwatch::start();
        self.scratch.system.clear();
        for (f, k) in self.scratch.base_k.iter().enumerate() {
            self.scratch.system.add_diagonal(f as u32, k);
        }
        for s in &self.scratch.springs {
            let row = self.spring_row(s);
            add_spring(
                &mut self.scratch.system,
                &self.free,
                s.entry,
                s.stiffness(),
                &row,
            );
        }
        self.bolt_couplings();
        self.assemble_rhs();
        watch.lap(rec, Phase::Assembly);
        let solved = if self.scratch.system.is_iterative() {
            self.solve_iteratively().converged
        } else {
            self.scratch
                .system
                .solve()
                .map_err(|source| SimError::Solve {
                    t: self.state.t,
                    source,
                })?;
            true
        };
        watch.lap(rec, Phase::Solve);
        self.keep_assembled();
        Ok(solved)
    }

    /// Records the springs and friction forces in effect as those of the matrix just
    /// factorised or assembled, of this attempt: the next OCI iteration's changes are
    /// counted from them.
    pub(crate) fn keep_assembled(&mut self) {
        self.scratch
            .factored_springs
            .clone_from(&self.scratch.springs);
        self.scratch
            .factored_forces
            .clone_from(&self.scratch.forces);
        self.scratch.factor_current = true;
    }
}

/// The joint of contact `c` in `model` (`bodies`: each block's body as the parts that
/// remain hold together, `Model::bodies`; `material`: each block's material index): none
/// (no friction, cohesion or tension) for a vertex-vertex contact, which carries a normal
/// spring only (`Contact::vertex_vertex`); else the glue between parts of one body, the
/// joint its edge names, or that of its blocks' materials (`Model::joint_of_contact`).
pub(crate) fn joint_of(
    model: &Model,
    bodies: &[Option<u32>],
    material: &[u32],
    c: &Contact,
) -> JointProps {
    if c.vertex_vertex {
        return JointProps::default();
    }
    if model.joints_by_edge {
        return *model.joint_of_contact(
            bodies,
            c.key.vertex_block as usize,
            c.key.edge_block as usize,
            c.key.edge as usize,
        );
    }
    let m = |b: u32| material[b as usize] as usize;
    *model.joint_of_materials(m(c.key.vertex_block), m(c.key.edge_block))
}

/// A free block's terms that do not depend on contacts, at step size `dt` under `rule`:
/// its stiffness (inertia, elasticity, fixed-point springs), right-hand side (inertia,
/// initial stress, gravity, point loads, fixed points) and mass matrix M (each only if
/// its effect is on). Inertia is 2/dt^2 M and 2/dt M V under the constant-acceleration
/// rule, 16/(9 dt^2) M and M (16/(9 dt) V - A / 9) under the damped one, 4/dt^2 M and
/// M (4/dt V + A) under the average-acceleration one (see [`StepRule`]).
pub(crate) fn block_terms(
    model: &Model,
    eff: Effects,
    rule: StepRule,
    b: &BlockState,
    i: usize,
    dt: f64,
) -> (Mat6, Vec6, Mat6) {
    let p = &model.params;
    let m = b.polygon.moments();
    let mat = model.materials[model.blocks[i].material];
    let mass = mass_matrix(&m, mat.density);
    let mut k = [[0.0; 6]; 6];
    let mut f = [0.0; 6];
    let average = rule == StepRule::Average;
    let c2 = rule.inertia_factor(dt);
    for a in 0..6 {
        for bb in 0..6 {
            k[a][bb] += c2 * mass[a][bb];
        }
    }
    if eff.inertia {
        if average {
            let c1 = 4.0 / dt;
            for a in 0..6 {
                f[a] += (0..6)
                    .map(|bb| mass[a][bb] * (c1 * b.velocity[bb] + b.acceleration[bb]))
                    .sum::<f64>();
            }
        } else if rule == StepRule::Damped {
            // M a with a = (D - V dt - (1/2 - beta) A dt^2) / (beta dt^2): its part
            // without D goes to the right-hand side.
            let c1 = 1.0 / (DAMPED_BETA * dt);
            let ca = (0.5 - DAMPED_BETA) / DAMPED_BETA;
            for a in 0..6 {
                f[a] += (0..6)
                    .map(|bb| mass[a][bb] * (c1 * b.velocity[bb] + ca * b.acceleration[bb]))
                    .sum::<f64>();
            }
        } else {
            let c1 = 2.0 / dt;
            for a in 0..6 {
                f[a] += c1 * (0..6).map(|bb| mass[a][bb] * b.velocity[bb]).sum::<f64>();
            }
        }
    }
    if eff.elasticity {
        let e = elasticity(mat.young, mat.poisson);
        // The material's damping (`materials.*.damping`, beta, or the block's own): a
        // viscous stress beta C e' at the step's mean strain rate e' = strain / dt, in a
        // dynamic step under Shi's rule or its damped form (the average-acceleration
        // rule, which an impact resolved in time takes, keeps every energy:
        // docs/method.md section 12).
        let viscous = if p.mode == Mode::Dynamic && rule.viscous() {
            mat.damping
                .unwrap_or_else(|| own_damping(&mass, m.area, &e))
                / dt
        } else {
            0.0
        };
        for a in 0..3 {
            for bb in 0..3 {
                k[3 + a][3 + bb] += m.area * e[a][bb] * (1.0 + viscous);
            }
            f[3 + a] -= m.area * b.stress[a];
        }
    }
    if eff.gravity
        && let Some(g) = p.gravity
    {
        f[0] += mat.density * g.x * m.area;
        f[1] += mat.density * g.y * m.area;
    }
    for &(at, force) in &b.loads {
        // The load's point half way through the step's turn (`half_turned`): the load
        // then works along the chord of the point's arc, as the exact turn moves it.
        let r = along(
            force,
            half_turned(at, m.centroid, b.velocity[2] * dt),
            m.centroid,
        );
        for a in 0..6 {
            f[a] += r[a];
        }
    }
    for &(now, place) in &b.fixed_points {
        // Two rows (x and y) of a spring pulling the point to its place, the point's
        // lever arm half way through the step's turn as its spin predicts it.
        let at = half_turned(now, m.centroid, b.velocity[2] * dt);
        for dir in [DVec2::X, DVec2::Y] {
            let r = along(dir, at, m.centroid);
            let g0 = (now - place).dot(dir);
            for a in 0..6 {
                f[a] -= p.fixed_penalty * g0 * r[a];
                for bb in 0..6 {
                    k[a][bb] += p.fixed_penalty * r[a] * r[bb];
                }
            }
        }
    }
    (k, f, mass)
}

/// The rule a step integrates by: Shi's constant acceleration (D = V dt + a dt^2 / 2,
/// V' = V + a dt, a from the end of the step's forces), the same with its stiff modes
/// damped (D = V dt + (9 a - A) dt^2 / 16, V' = V + a dt, A the last step's
/// acceleration), or Newmark's average acceleration (D = V dt + (A + a) dt^2 / 4,
/// V' = V + (A + a) dt / 2). Shi's and the average give V' = 2 D / dt - V.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum StepRule {
    /// Shi's constant acceleration (and every static step).
    Constant,
    /// Shi's with its stiff modes damped: Newmark's gamma = 1, beta = 9/16.
    Damped,
    /// Newmark's average acceleration.
    Average,
}

/// Newmark's beta of the damped rule: with gamma = 1, beta = (gamma + 1/2)^2 / 4 keeps
/// a third of an infinitely stiff mode a step (docs/method.md section 12).
const DAMPED_BETA: f64 = 9.0 / 16.0;

impl StepRule {
    /// The factor c of the inertia term c M of a step of size `dt` under this rule:
    /// 2 / dt^2 (constant acceleration), 1 / (beta dt^2) (damped) or 4 / dt^2 (average
    /// acceleration).
    pub(crate) fn inertia_factor(self, dt: f64) -> f64 {
        let c = match self {
            StepRule::Constant => 2.0,
            StepRule::Damped => 1.0 / DAMPED_BETA,
            StepRule::Average => 4.0,
        };
        c / (dt * dt)
    }

    /// Whether the dashpots of the contacts and the damping of the blocks' strain act in
    /// a dynamic step under this rule: Shi's and its damped form (the average-acceleration
    /// rule keeps every energy).
    pub(crate) fn viscous(self) -> bool {
        self != StepRule::Average
    }

    /// The acceleration of a step under the damped rule that moved an unknown by `d`,
    /// from velocity `v` and the last step's acceleration `a`, in a step of `dt`:
    /// D = V dt + ((1/2 - beta) A + beta a) dt^2 solved for a.
    pub(crate) fn damped_acceleration(d: f64, v: f64, a: f64, dt: f64) -> f64 {
        (d - v * dt - (0.5 - DAMPED_BETA) * a * dt * dt) / (DAMPED_BETA * dt * dt)
    }

    /// The velocity at the end of a dynamic step under this rule that moved an unknown
    /// by `d`, from velocity `v` and the last step's acceleration `a` (read by the
    /// damped rule only).
    pub(crate) fn end_velocity(self, d: f64, v: f64, a: f64, dt: f64) -> f64 {
        match self {
            StepRule::Damped => v + Self::damped_acceleration(d, v, a, dt) * dt,
            StepRule::Constant | StepRule::Average => 2.0 * d / dt - v,
        }
    }
}

impl Simulation {
    /// The rule of the next step: the average-acceleration rule or the damped one when
    /// the scene asks for it (throughout, or in the steps an impact holds down, as the
    /// step set out), the analysis is dynamic and the blocks' accelerations are known
    /// (from a step taken); else the constant-acceleration rule.
    pub(crate) fn step_rule(&self) -> StepRule {
        let p = &self.model.params;
        let asked = match p.integration {
            Integration::ConstantAcceleration => StepRule::Constant,
            Integration::DampedConstantAcceleration => StepRule::Damped,
            Integration::AverageAcceleration => StepRule::Average,
            Integration::AverageInImpacts if self.scratch.in_impact => StepRule::Average,
            Integration::AverageInImpacts => StepRule::Constant,
        };
        if p.mode == Mode::Dynamic && self.state.accelerations_known {
            asked
        } else {
            StepRule::Constant
        }
    }
}

/// Adds the stiffness of the spring p q^2 / 2 of `row` to the matrix (fixed blocks
/// contribute nothing); its right-hand side comes with [`Simulation::assemble_rhs`].
pub(crate) fn add_spring(
    sys: &mut BlockSystem,
    free: &[Option<u32>],
    pair_entry: Option<Entry>,
    p: f64,
    row: &Row,
) {
    let fa = free[row.blocks[0] as usize];
    let fb = free[row.blocks[1] as usize];
    for (f, c) in [(fa, &row.c[0]), (fb, &row.c[1])] {
        if let Some(f) = f {
            sys.add_outer(sys.diagonal(f), f, f, p, c, c);
        }
    }
    if let (Some(a), Some(b), Some(e)) = (fa, fb, pair_entry) {
        sys.add_outer(e, a, b, p, &row.c[0], &row.c[1]);
    }
}
