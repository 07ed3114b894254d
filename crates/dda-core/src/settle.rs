//! Settling before a dynamic run (`analysis.settle`, docs/method.md section 13).
//!
//! Blocks written resting on each other start with their contact springs unloaded: in
//! the first steps they sink into them under their weight and ring at sqrt(p / m), and
//! friction, which follows the normal force, rings with them. A block sliding down an
//! incline keeps the error of wherever the ring stopped, and a stack of blocks slides
//! apart where it should slide as one (docs/accuracy.md; `tests/physics/stacks.rs`).
//!
//! Settling loads the contacts before t = 0 with the forces the run starts with. It takes
//! static steps of a copy of the model under the scene's own joints: each is a step of
//! the run from rest (static: the velocities reset, so nothing rings), of the run's own
//! size dt, or longer where the inertia 2 m / dt^2 of the heaviest block would exceed
//! a hundredth of the penalty ([`SETTLE_INERTIA`]), solved directly under `solver =
//! "auto"` below [`crate::iterative::SETTLE_ITERATIVE_FROM_BLOCKS`] free blocks (such a
//! step is stiff, which costs conjugate gradients many iterations and a factor nothing).
//! Stiff modes (the contact springs)
//! converge in a few such steps, to the forces that balance the weight, the loads and
//! the inertia of the motion the blocks start (d'Alembert): those of a joint that
//! holds, and of one that slides (friction at its limit, the normal force of the
//! accelerated blocks). The steps go on until every vertex moves in a step as it moved
//! in the step before (settled, or sliding steadily) to [`SETTLE_TOLERANCE`] of the
//! first step's motion (at most [`SETTLE_FREE_FLIGHT`] times what the blocks' own
//! forces alone would move them), or as in the step two before (a flicker of period two, a
//! contact at a junction switched on and off in turn: the steady motion is the mean of
//! the two), until that stops improving ([`SETTLE_STALL`]), or for
//! [`SETTLE_MAX_STEPS`] in all. Blocks that rest on nothing (in flight) are held where
//! they are; the ground is still; and nothing is excavated (the settling's steps take
//! time of their own, before t = 0, and would pass the excavations of the run).
//!
//! A block free to slide moves by its slide while settling, a dt^2 / 2 a step (a its
//! acceleration): over a hundred steps of a wall, millimetres, a percent of what it
//! slides in the run's first half second. A converged settling takes that back
//! ([`Simulation::rewind`]): every group of blocks in contact moves back as one along
//! its steady translation, which changes no contact between them, and slides a group
//! sliding on fixed blocks back along them. Where the blocks moved alike only to the
//! tolerance, going back by a hundred steps of it disturbs the loads a little, so the
//! settling goes on after it, and takes the blocks back again: [`SETTLE_ROUNDS`]
//! rounds, each way back towards where the scene put the blocks (their translation
//! since the settling began), the last one checked by one more step, which must move
//! as the round's last did ([`SETTLE_CHECK`]), and whose slide, one step of the same
//! steady motion, is then taken back as well. A round
//! that does not converge within the steps the rounds before it took is undone, and so
//! is a last way back that the check step does not confirm; blocks whose slide is not
//! their steady motion (they came to rest after loading their contacts) are not taken
//! back at all, and nothing is after a round whose last step turned a moving block (a
//! mechanism, [`Simulation::was_a_slide`]).
//!
//! The run then starts from the settled places, stresses and contacts (their springs
//! loaded, shear springs anchored where they were, glued seams bonded, and the bonds of
//! joints with cohesion or tension that the settling did not break) with the blocks'
//! own velocities. The work gravity and the loads did while settling, net of the way
//! back, is added to the energy the physics guard counts as supplied.
//!
//! Holding every joint while settling (a static solution of glued blocks, our first
//! design) is wrong where the scene's joints cannot hold: it loads them with shear they
//! do not carry in the run, a column that would topple glued starts the run on its toe,
//! and an equilibrium reached with no joint at its limit creeps once the limits apply
//! (docs/method.md, section 13).

use crate::contact_law::DECISION_BAND;
use crate::diagnosis::SimError;
use crate::iterative::settling_solver;
use crate::kinematics::{Vec6, along};
use crate::model::supported_blocks;
use crate::scene::{Integration, Mode, Model, SolverChoice};
use crate::simulation::{RunOptions, Simulation};
use crate::solver::{SolveError, chol, chol_solve};
use crate::state::RunState;
use dda_contact::BlockShape;
use dda_geom::{DVec2, Groups, displace_point};

/// Most static steps of the settling.
const SETTLE_MAX_STEPS: u32 = 2000;

/// The settling has converged when no vertex's motion in a step differs from its motion
/// in the step before by more than this share of the settling's scale (the first step's
/// largest motion, at most [`SETTLE_FREE_FLIGHT`] times the blocks' free flight). Our
/// choice, measured on running-bond walls of 1 x 0.5 m bricks with half bricks at the
/// course ends, 8 courses of 5 on 30/25 (p 3e10 to 1e12, dt 1 ms): their steady slide
/// takes hundreds of steps to converge (the pieces of the wall slide at rates that
/// approach one another by a fraction of a percent a step), and started from a settling
/// stopped at 1e-3, 1e-4 or 3e-5 the walls parted by 10% to 30% (the slide as one body
/// is unstable there,
/// docs/notes/2026-11-25-10-settling-stacks-and-walls-as-measured.md); from 1e-5 (400
/// to 500 steps) they hold to 0.29% (`tests/physics/stacks.rs`). The toppling columns
/// of `tests/physics/regions.rs` stood to 0.24 mm at 1e-3 already.
const SETTLE_TOLERANCE: f64 = 1e-5;

/// The settling's scale, the largest motion of its first step, is at most this multiple
/// of the largest its blocks' own forces give them alone ([`Simulation::free_flight`]).
/// From rest, contacts hold blocks back; a block tipping about a corner moves its far
/// vertices faster than it would fall. Measured on the examples, the test scenes and
/// some hundred masses, slopes, pits and tunnels written by hand: the first step moved
/// 0.17 to 1.53 times the free flight. The conventional detectors' mistakes at short
/// edges, a block taken deep into its neighbour, made it 1.6e4 to 2.4e7 times on five
/// jointed masses and a pit (`a_settling_is_judged_against_the_forces_not_a_detectors_first_push`,
/// `tests/physics/regions.rs`); measured against such a step, a change of 0.1 g a step
/// passed for converged, and the run started ringing. Ten leaves the first range alone
/// (those scenes settle to the same bits) and takes the second to within ten times of
/// what the forces do. Where the blocks' forces move nothing (no gravity, load or
/// stress), the first step's motion stands.
const SETTLE_FREE_FLIGHT: f64 = 10.0;

/// Steps without progress after which the settling stops: the change of the motion has
/// not fallen below half its smallest value so far. Contacts at their friction limit
/// that lock and slide in turn can hold the change at a floor; the slow convergence of
/// a wall's slide halves it every 20 to 140 steps. At 20 (until 2026-11-24) the walls
/// above stopped after 22 steps and parted by 20% to 57%. The count starts once the
/// steps have grown to the settling's own size, or after half of [`SETTLE_MAX_STEPS`]
/// if they have not: a jointed mass of 345 blocks (two persistent sets, 60 m x 30 m)
/// took 150 to 250 steps to grow its first step, cut to 4.6e-5 s where its junctions'
/// contacts would not converge, to 0.0125 s; counted from the first step, the stall
/// stopped it at 256 steps, its contacts a third loaded, and the run started with the
/// mass falling at 0.64 g (`a_jointed_mass_settles_onto_its_contacts`,
/// `tests/physics/regions.rs`).
/// Two random jointed masses took 861 and 1,073 steps to converge, their steps at full
/// size only after the 200th (started from the 200th, the count stopped them at 431
/// and 470 steps, unsettled). A random jointed mass under TB-CD-1, whose steps never
/// got there, runs to 1,200 steps and ends at the steadiest step it ended at when the
/// count started at the first (the 50th); counted only at full size, it ran to the
/// 2,000-step cap.
const SETTLE_STALL: u32 = 200;

/// The inertia of a settling step, 2 m / dt^2 for the heaviest block, is at most this
/// share of the normal penalty: the step is the run's own, or longer. Each step carries
/// a contact's imbalance down to inertia / (inertia + penalty) of what it was, and the
/// blocks' own elastic modes (E = 1e9 Pa bricks are softer than a penalty of 1e10 N/m)
/// likewise against their stiffness. Our choice, measured on masons' walls (courses of
/// five 1 m bricks, E = 1e9 Pa, p = 1e10 N/m, dt 1 ms, 30/25, so that the run's step
/// gives an inertia of a quarter of the penalty): at 1 (until 2026-11-25) the settling
/// took 700 to 860 steps, often without converging, and 6 and 8 courses parted by 1.6%
/// to 24% in the run; at 0.01 (with the rounds below), 130 to 450 steps, within 0.18%
/// to 0.82% (docs/notes/2026-11-25-10-settling-stacks-and-walls-as-measured.md). Stiff
/// walls and stacks settled with steps as long already.
const SETTLE_INERTIA: f64 = 0.01;

/// Rounds of settling, each after the first begun by taking back the slide of the ones
/// before ([`Simulation::rewind`]); the last one's slide is taken back after them,
/// checked ([`SETTLE_CHECK`]). Our choice, measured with the last round's slide kept
/// (until 2026-11-25; worst block after 0.5 s against the closed form, displacement):
/// the softest wall above, 1.3% with two rounds, 0.88% with three, 0.81% with five,
/// 0.54% with eight;
/// six courses of `dda_bench::Masonry`'s bricks on 40/30 (its rounds 378, 160 and 109
/// steps), 1.25%, 0.81% and 0.75% with three, five and eight. A stack's rounds take two
/// steps each; of the examples and test scenes only the rock mass takes more steps
/// with five rounds than with three (206 against 173). Measured again with the slide
/// taken back by groups: the soft 8-course wall (density 2600) 0.52%, 0.60% and 0.53%,
/// the Masonry wall 0.35%, 0.37% and 0.33% with three, five and eight rounds.
const SETTLE_ROUNDS: u32 = 5;

/// The step after the last round's slide is taken back must move as the round's last
/// step did, to this share of the settling's scale (a change 1,000 times the
/// settling's tolerance, [`SETTLE_TOLERANCE`]); else the way back is undone. Our
/// choice, measured on 130 stacks and walls
/// (`docs/notes/2026-11-25-10-settling-stacks-and-walls-as-measured.md`): the walls
/// that slide steadily change by at most 7.5e-4; walls whose end groups topple while
/// they settle, by 86 to 99, and without the check the run's first step found energy
/// created.
const SETTLE_CHECK: f64 = 1e-2;

/// Blocks in contact whose steady translations differ by this share of the larger, or
/// more (and by a force beyond the decision band), are taken back as separate groups
/// ([`Simulation::move_together`]): one slides and the other rests, or slides another
/// way. Our choice, between the whole of a slide against a block at rest and the few
/// percent by which the courses of a wall sliding as one body differ (the walls of
/// `tests/physics/stacks.rs` slide within their bounds as before).
const SETTLE_APART: f64 = 0.5;

/// What one round of settling did ([`Simulation::relax`]).
struct Relaxed {
    /// Static steps taken.
    steps: u32,
    /// Whether the motion converged.
    converged: bool,
    /// The settling's scale: the largest motion of its first step, over dt^2 / 2, at
    /// most [`SETTLE_FREE_FLIGHT`] times that of the blocks' free flight.
    scale: f64,
    /// Each block's translation summed over the round's steps.
    slide: Vec<DVec2>,
    /// Each block's translation in the round's last step.
    steady: Vec<DVec2>,
    /// Each block's rotation in the round's last step.
    spin: Vec<f64>,
    /// Each free vertex's motion in the round's last step, over dt^2 / 2.
    last: Vec<DVec2>,
    /// The largest change of a vertex's motion from the step before in the round's last
    /// step, over `scale` (infinite after a first step of its own).
    change: f64,
    /// Whether the watcher stopped the round.
    interrupted: bool,
    /// For a round that did not converge, the step (of the settling, counted from its
    /// first) whose state it ended in: the steadiest one, where the motion changed least.
    kept: Option<u32>,
}

/// How far the settling has come ([`Simulation::settle_watched`]), after a static step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SettleProgress {
    /// Static steps taken so far.
    pub steps: u32,
    /// The largest change of a vertex's motion from the step before, over the largest
    /// motion of the settling's first step, or ten times what the blocks' own forces
    /// alone would move them where that is less (infinite for a round's first step):
    /// the settling has converged at 1e-5.
    pub change: f64,
    /// The size of the static step just taken, s: it starts short and grows to
    /// `full_dt` over easy steps; the blocks load their contacts once it is there.
    pub dt: f64,
    /// The settling's own step, s (docs/method.md section 13).
    pub full_dt: f64,
}

/// What the settling did before t = 0 ([`Simulation::settling`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settling {
    /// Static steps taken.
    pub steps: u32,
    /// Whether the motion converged (every vertex moving as in the step before, to 1e-5
    /// of the first step's motion, or of ten times the blocks' free flight where that is
    /// less) in the last round; if not, the settling stopped
    /// after 200 steps without progress, or at its most steps, 2,000 in all
    /// (docs/method.md section 13).
    pub converged: bool,
    /// How its static steps were solved, `Direct` or `Iterative`
    /// ([`crate::iterative::settling_solver`]).
    pub solver: SolverChoice,
    /// For a settling that did not converge, the static step whose state the run starts
    /// from: the steadiest one, where the motion changed least from the step before
    /// (docs/method.md section 13).
    pub kept_step: Option<u32>,
}

impl Simulation {
    /// Whether the next step begins by settling the blocks (see the module docs): the
    /// scene asks for it (`analysis.settle`), contacts are on, something pulls the blocks
    /// (gravity, loads, bolt pretension), and it has not been done.
    pub fn settles(&self) -> bool {
        let p = &self.model.params;
        let pulled = p.gravity.is_some_and(|g| g != glam::DVec2::ZERO)
            || self.model.blocks.iter().any(|b| !b.loads.is_empty())
            || self.model.bolts.iter().any(|b| b.pretension != 0.0);
        !self.state.settled && p.settle && self.effects.contact && pulled
    }

    /// What the settling of this process did, once it has settled the blocks (None
    /// before, without settling, and after a resume).
    pub fn settling(&self) -> Option<Settling> {
        self.settling
    }

    /// Settles the blocks now, if the scene asks for it and it has not been done (the
    /// first step does it otherwise), calling `watch` after every static step with how
    /// far the settling has come. `watch` returning false stops it, the blocks left as
    /// they were, to settle again at the next call or step (a run interrupted while it
    /// settles): `Ok(false)`. `Ok(true)` once settled, or with nothing to settle. On an
    /// error [`Simulation::diagnosis`] says what happened.
    pub fn settle_watched(
        &mut self,
        mut watch: impl FnMut(&SettleProgress) -> bool,
    ) -> Result<bool, SimError> {
        if self.state.settled {
            return Ok(true);
        }
        let settled = self.settle(&mut watch);
        // Settled, with nothing to settle, or failed: done either way. Stopped: to do.
        self.state.settled = !matches!(settled, Ok(false));
        if let Err(e) = &settled {
            self.diagnose(e, self.state.dt, None);
        }
        settled
    }

    /// Settles the blocks at t = 0 (see the module docs), once, before the first step
    /// of a dynamic run whose scene asks for it and has something to settle; false if
    /// `watch` stopped it (the blocks left as they were).
    fn settle(&mut self, watch: &mut dyn FnMut(&SettleProgress) -> bool) -> Result<bool, SimError> {
        if !self.settles() {
            return Ok(true);
        }
        let p = &self.model.params;
        let mut model = self.model.clone();
        let tied: Vec<(usize, usize)> = model
            .bolts
            .iter()
            .map(|b| (b.from_block, b.to_block))
            .collect();
        let supported = supported_blocks(&model.blocks, p.d_tol, &tied);
        let mut heaviest = 0.0f64;
        let mut n_free = 0;
        for (i, (b, s)) in model.blocks.iter_mut().zip(&supported).enumerate() {
            // Excavated in the run, not while settling (the blocks removed at t = 0 are
            // gone from both).
            if b.removed_at.is_some_and(|at| at > 0.0) {
                b.removed_at = None;
            }
            // Blocks in flight are held: they have no equilibrium.
            if !s {
                b.fixed = true;
            }
            if !b.fixed {
                heaviest = heaviest.max(self.block_mass(i));
                n_free += 1;
            }
        }
        if heaviest == 0.0 {
            return Ok(true);
        }
        let mp = &mut model.params;
        mp.mode = Mode::Static;
        let shortest = (2.0 * heaviest / (SETTLE_INERTIA * mp.normal_penalty)).sqrt();
        mp.dt0 = mp.dt0.max(shortest);
        let first = (2.0 * heaviest / mp.normal_penalty).sqrt().min(mp.dt0);
        mp.duration = f64::from(SETTLE_MAX_STEPS) * mp.dt0;
        mp.impact_steps = None;
        mp.integration = Integration::ConstantAcceleration;
        mp.settle = false;
        mp.solver = settling_solver(mp.solver, n_free);
        model.ground = None;
        for b in &mut model.bolts {
            // A bolt breaks in the run, not while the blocks settle onto it.
            b.strength = None;
        }
        let options = RunOptions {
            stop_on_violation: false,
            ..self.options
        };
        // Under `auto` the direct solve settles a scene the run may solve iteratively, for
        // want of memory among other reasons: where its factor would not fit, the
        // settling is begun again iteratively.
        let fallback = self.model.params.solver == SolverChoice::Auto
            && model.params.solver == SolverChoice::Direct;
        let settled = if fallback {
            match self.settle_copy(model.clone(), options, first, watch) {
                Err(SimError::Solve {
                    source: SolveError::OutOfMemory { .. },
                    ..
                }) => {
                    model.params.solver = SolverChoice::Iterative;
                    self.settle_copy(model, options, first, watch)
                }
                other => other,
            }
        } else {
            self.settle_copy(model, options, first, watch)
        }
        .map_err(|e| SimError::Settle {
            reason: e.to_string(),
        })?;
        let Some((settling, report, work)) = settled else {
            return Ok(false);
        };
        // The settled places, stresses and contacts; the run's own velocities.
        for (i, (b, settled)) in self
            .state
            .blocks
            .iter_mut()
            .zip(settling.state.blocks)
            .enumerate()
        {
            if self.free[i].is_none() {
                continue;
            }
            b.polygon = settled.polygon;
            b.stress = settled.stress;
            b.rotation = settled.rotation;
            b.loads = settled.loads;
            b.fixed_points = settled.fixed_points;
            self.scratch.shapes[i] = BlockShape::new(&b.polygon);
        }
        // The settled contacts, their shear springs anchored where they were and sliding
        // ones sliding: each joint goes on carrying the force it settled with. Bonds
        // too: the contacts that touched as the scene wrote them bonded at the
        // settling's first static step (as they would at the run's first step without
        // it), and those the settling's loads broke stay broken. The seams of glued
        // parts stay bonded where they settled: loaded, a seam may lie further off its
        // edge's line than a first step would bond (and a seam not bonded is no contact
        // at all: the parts passed into each other).
        self.state.contacts = settling.state.contacts;
        self.settling = Some(report);
        self.state.energy.supplied += work;
        self.state.energy.supplied_max = self
            .state
            .energy
            .supplied_max
            .max(self.state.energy.supplied);
        Ok(true)
    }

    /// The static steps of [`Simulation::settle`] on `model`, its copy of the scene for
    /// settling (see the module docs), from a first step of `first` seconds: the settled
    /// copy, what it did, and the work gravity and the loads did on it (net of the ways
    /// back); None if `watch` stopped it. A step's error is returned as it came.
    fn settle_copy(
        &self,
        model: Model,
        options: RunOptions,
        first: f64,
        watch: &mut dyn FnMut(&SettleProgress) -> bool,
    ) -> Result<Option<(Simulation, Settling, f64)>, SimError> {
        let mut settling = Simulation::new(model, options);
        // The first static step's inertia is the penalty: from rest, no block moves further
        // in it than its contact springs give under its weight, so no joint slides far
        // before its normal force is loaded. The steps then grow by the run's rule for easy
        // steps (docs/method.md section 7) to the settling's own.
        settling.state.dt = first;
        // Blocks written resting on each other touch along flush faces, where a contact
        // starts open: closed from the start, they carry their weight in the first step,
        // where each open-close iteration would otherwise close one more layer of a
        // stack (the layers above falling with it) and a tall stack runs out of them.
        settling.close_touching = true;
        let supplied = settling.state.energy.supplied;
        let mut round = settling.relax(SETTLE_MAX_STEPS, first, None, None, 0, watch)?;
        if round.interrupted {
            return Ok(None);
        }
        let mut report = Settling {
            steps: round.steps,
            converged: round.converged,
            kept_step: round.kept,
            solver: if settling.solves_iteratively() {
                SolverChoice::Iterative
            } else {
                SolverChoice::Direct
            },
        };
        // Each block's translation since the settling began.
        let mut moved = round.slide.clone();
        for _ in 1..SETTLE_ROUNDS {
            if !round.converged {
                break;
            }
            // A round after a rewind has at most the steps the rounds before it took; one
            // that does not converge in them leaves the blocks where they had settled.
            let settled = (settling.state.clone(), moved.clone());
            if !settling.rewind(&round, &mut moved, report.steps) {
                break;
            }
            let budget = report.steps.min(SETTLE_MAX_STEPS - report.steps);
            let next =
                settling.relax(budget, first, Some(round.scale), None, report.steps, watch)?;
            if next.interrupted {
                return Ok(None);
            }
            report.steps += next.steps;
            if !next.converged {
                (settling.state, moved) = settled;
                break;
            }
            for (m, s) in moved.iter_mut().zip(&next.slide) {
                *m += *s;
            }
            round = next;
        }
        // The last round's slide is taken back too, and one more step loads the contacts
        // where the run starts. That step must move as the round's last did: otherwise
        // the way back was not the blocks' steady slide, and it is undone.
        if round.converged {
            let settled = settling.state.clone();
            if settling.rewind(&round, &mut moved, report.steps) {
                let check = settling.relax(
                    1,
                    first,
                    Some(round.scale),
                    Some(&round.last),
                    report.steps,
                    watch,
                )?;
                if check.interrupted {
                    return Ok(None);
                }
                report.steps += check.steps;
                // False for a step not taken (infinite) or of no motion (NaN).
                let confirmed = check.change <= SETTLE_CHECK;
                if confirmed {
                    // The check step slid as the round's last did: one step of the steady
                    // motion, taken back as the rounds' were where each group moved as one
                    // in it, so that its contacts keep their loads.
                    let steady = settling.group_translations(&check.steady);
                    if settling.moved_as_groups(&check.steady, &steady) {
                        settling.move_back(&steady, 1.0, &mut moved);
                    }
                } else {
                    settling.state = settled;
                }
            }
        }
        let work = settling.state.energy.supplied - supplied;
        Ok(Some((settling, report, work)))
    }

    /// One round of settling: static steps until the motion converges (see the module
    /// docs), for at most `budget` steps; `scale`, the settling's scale (the largest
    /// motion of its first step, over dt^2 / 2, bounded by [`SETTLE_FREE_FLIGHT`]), once
    /// known; `first_dt`, the settling's first step (below). `watch` is told of every step (`done`
    /// steps came before the round), and stops the round by returning false.
    fn relax(
        &mut self,
        budget: u32,
        first_dt: f64,
        scale: Option<f64>,
        before: Option<&[DVec2]>,
        done: u32,
        watch: &mut dyn FnMut(&SettleProgress) -> bool,
    ) -> Result<Relaxed, SimError> {
        // Each step's motion of every free vertex over dt^2 / 2 (its acceleration from
        // rest, the same over steps of any size while a block slides steadily, so that
        // steps cut and grown back compare), from `before` if given; the settling's
        // scale; the smallest change from step to step so far, and its step.
        let mut last: Vec<DVec2> = before.map(<[DVec2]>::to_vec).unwrap_or_default();
        // The motion two steps back, and each block's translation and turn in the step
        // before (a flicker of period two, below).
        let mut last2: Vec<DVec2> = Vec::new();
        let (mut steady_before, mut spin_before) = (Vec::new(), Vec::new());
        let mut first = scale;
        let (mut best, mut best_at) = (f64::INFINITY, 0);
        let mut full = false;
        let mut report = Relaxed {
            steps: 0,
            converged: false,
            scale: 0.0,
            slide: vec![DVec2::ZERO; self.state.blocks.len()],
            steady: vec![DVec2::ZERO; self.state.blocks.len()],
            spin: vec![0.0; self.state.blocks.len()],
            last: Vec::new(),
            change: f64::INFINITY,
            interrupted: false,
            kept: None,
        };
        // The steadiest step so far (the least change), its change and its state, where
        // a round that does not converge ends (below).
        let mut steadiest: Option<(u32, f64, RunState)> = None;
        // The settling's first step: its inertia the penalty for the heaviest block
        // (`Simulation::settle`). A step cut below it loads no contact: its inertia
        // exceeds every spring, each block moves by nearly its free fall, the same over
        // dt^2 / 2 from step to step, and a barely loaded state passes for a steady one
        // (a 10,000-block grid settled iteratively, unconverged, kept its 46th static
        // step of 1,379, and its run loaded the mass itself in steps of 2e-5 s where
        // 2e-3 s was asked for). Such a step is no candidate for the steadiest.
        // Less a rounding: a step grown back from a cut lands on the first only to it.
        let loads = first_dt * (1.0 - 1e-9);
        for n in 1..=budget {
            if self.finished() {
                break;
            }
            report.steps = n;
            let before = self.free_vertices();
            let record = self.step()?;
            let per = 2.0 / (record.dt * record.dt);
            let motion: Vec<DVec2> = self
                .free_vertices()
                .iter()
                .zip(&before)
                .map(|(a, b)| (*a - *b) * per)
                .collect();
            let size = motion.iter().map(|m| m.length()).fold(0.0, f64::max);
            let scale = *first.get_or_insert_with(|| match self.free_flight(record.dt) {
                reach if reach > 0.0 => size.min(SETTLE_FREE_FLIGHT * reach),
                _ => size,
            });
            report.scale = scale;
            let (change, change2) = (
                largest_change(&motion, &last),
                largest_change(&motion, &last2),
            );
            steady_before.clone_from(&report.steady);
            spin_before.clone_from(&report.spin);
            // The translation of the step, block by block (see `rewind`).
            for (i, slid) in report.slide.iter_mut().enumerate() {
                if self.free[i].is_some() {
                    let d = &self.scratch.d[i];
                    report.steady[i] = DVec2::new(d[0], d[1]);
                    report.spin[i] = d[2];
                    *slid += report.steady[i];
                }
            }
            report.change = change / scale;
            let progress = SettleProgress {
                steps: done + n,
                change: report.change,
                dt: record.dt,
                full_dt: self.model.params.dt0,
            };
            if !watch(&progress) {
                report.interrupted = true;
                break;
            }
            if change <= SETTLE_TOLERANCE * scale {
                report.last = motion;
                report.converged = true;
                break;
            }
            if change2 <= SETTLE_TOLERANCE * scale {
                // A flicker of period two: the motion repeats every other step, a contact
                // switched on in one and off in the next (a vertex at the end of an edge,
                // where blocks meet at a junction, taken past it by its spring and back
                // by its load). The loads are as settled as they will be; the blocks'
                // steady motion is the mean of the two steps', and the next step repeats
                // the one before this.
                for (i, (t, w)) in report.steady.iter_mut().zip(&mut report.spin).enumerate() {
                    *t = 0.5 * (*t + steady_before[i]);
                    *w = 0.5 * (*w + spin_before[i]);
                }
                report.last = last;
                report.converged = true;
                break;
            }
            if record.dt >= loads
                && steadiest
                    .as_ref()
                    .is_none_or(|(_, least, _)| change < *least)
            {
                steadiest = Some((n, change, self.state.clone()));
            }
            // The stall's clock starts once the steps have grown to the settling's own
            // size: before, a step moves the blocks by a small part of what loads their
            // contacts, and its change is no measure of progress. Steps held below it
            // for half the settling's steps (contacts whose open-close iteration keeps
            // failing) start it all the same.
            full |= record.dt >= self.model.params.dt0 || n >= SETTLE_MAX_STEPS / 2;
            if change <= 0.5 * best || !full {
                (best, best_at) = (change, n);
            } else if n - best_at >= SETTLE_STALL {
                break;
            }
            last2 = std::mem::replace(&mut last, motion);
        }
        // A round that does not converge ends at its steadiest step: the steps after it
        // moved a mechanism on (a column toppling, a wheel rolling, a pendulum swinging
        // moves by a static step's motion a step, and changes its geometry as it goes:
        // its motion never repeats to the tolerance), or flickered, and loaded the
        // contacts no better (docs/method.md section 13).
        if !report.converged
            && !report.interrupted
            && let Some((at, _, state)) = steadiest
            && at < report.steps
        {
            self.state = state;
            report.kept = Some(done + at);
        }
        Ok(report)
    }

    /// Takes the blocks back towards the places the scene gave them, after a converged
    /// round of settling (see the module docs): every group of free blocks in contact
    /// moves back along its steady translation (the mean of its blocks' translations in
    /// the round's last step, weighted by their masses,
    /// [`Simulation::group_translations`]), by the one multiple of it that best undoes
    /// the translations the blocks made since the settling began, `moved` (least squares,
    /// weighted by their masses; `moved` is updated), after `steps` static steps. A
    /// group moved as one keeps every contact between its blocks as it was, and a group
    /// sliding steadily on fixed blocks slides back along them; so the contacts keep
    /// their loads. The work gravity and the loads do on the way back is taken from the
    /// energy supplied. Returns whether it moved the blocks.
    fn rewind(&mut self, round: &Relaxed, moved: &mut [DVec2], steps: u32) -> bool {
        let steady = self.group_translations(&round.steady);
        if !self.was_a_slide(round, &steady) {
            return false;
        }
        let (mut along, mut norm) = (0.0, 0.0);
        for &i in &self.free_blocks {
            let i = i as usize;
            let m = self.block_mass(i);
            along += m * moved[i].dot(steady[i]);
            norm += m * steady[i].length_squared();
        }
        // A block sliding steadily from the settling's first step has moved by its steps
        // of its steady motion, and by the little it sank into its springs. A move of
        // more than twice that is not that motion (blocks that moved while loading their
        // contacts and came to rest, whose last motion is a creep of rounding: the
        // examples' slopes and tunnel, 1e3 to 1e4 times their steps), and stays.
        let back = along / norm;
        if !(back > 0.0 && back <= 2.0 * f64::from(steps)) {
            return false;
        }
        self.move_back(&steady, back, moved);
        true
    }

    /// Whether the round's last step was a slide (`group`, the groups' translations,
    /// [`Simulation::group_translations`]): no block that moves turns, its rotation
    /// moving a vertex by [`SETTLE_APART`] of its translation, or of its group's, or
    /// more. A mechanism is no slide: an arch turning about its hinges and a pier
    /// tipping about its toe move steadily from static step to static step too, but
    /// taken back by its groups' mean translations, a settled arch on free piers under a
    /// point load was lifted off its piers and pressed into the ground round after
    /// round, the energy supplied fell to -8.8 J/m against 4.6 J/m of strain energy,
    /// and the run's first step was called energy created (docs/method.md section 13).
    /// The rule is the round's, not each group's: a group whose blocks do not turn can
    /// still be part of the mechanism (the arch's voussoirs translate apart by up to
    /// two thirds of their group's translation, as the courses of a sliding wall do by
    /// a few percent). A block moving less than [`SETTLE_TOLERANCE`] of the fastest
    /// block's translation is at rest here (its way back is nothing).
    fn was_a_slide(&self, round: &Relaxed, group: &[DVec2]) -> bool {
        let fastest = self
            .free_blocks
            .iter()
            .map(|&i| round.steady[i as usize].length())
            .fold(0.0, f64::max);
        self.free_blocks.iter().all(|&i| {
            let i = i as usize;
            let shape = &self.scratch.shapes[i];
            let reach = shape
                .vertices
                .iter()
                .map(|v| (*v - shape.centroid).length())
                .fold(0.0, f64::max);
            let own = round.steady[i];
            let turn = reach * round.spin[i].abs();
            if own.length() + turn <= SETTLE_TOLERANCE * fastest {
                return true;
            }
            turn <= SETTLE_APART * group[i].length().max(own.length())
        })
    }

    /// Whether every free block's translation in a step, `own`, is its group's, `group`
    /// ([`Simulation::group_translations`]), to a force within the decision band: moved
    /// back by its group's translation instead of its own, a block's contacts with
    /// blocks outside the group (fixed ones) are displaced by the difference, which the
    /// normal penalty turns into a force; that force must be negligible as the contact
    /// law counts it, at most [`DECISION_BAND`] of the block's force scale. A wall whose
    /// courses slide at rates a few percent apart fails it (a 10-course wall of soft
    /// bricks: its run's first step created 1% of the reference energy when moved back
    /// regardless); a stack or a block sliding steadily passes it to rounding.
    fn moved_as_groups(&self, own: &[DVec2], group: &[DVec2]) -> bool {
        let p = self.model.params.normal_penalty;
        self.free_blocks.iter().all(|&i| {
            let i = i as usize;
            p * (own[i] - group[i]).length() <= DECISION_BAND * self.scratch.force_scale[i]
        })
    }

    /// Moves every free block back by `back` times its group's translation `steady`
    /// (`moved` updated), taking the work gravity and the loads do on the way from the
    /// energy supplied.
    fn move_back(&mut self, steady: &[DVec2], back: f64, moved: &mut [DVec2]) {
        let gravity = self.gravity();
        let mut work = 0.0;
        for i in 0..self.state.blocks.len() {
            if self.free[i].is_none() {
                continue;
            }
            let d = [-back * steady[i].x, -back * steady[i].y, 0.0, 0.0, 0.0, 0.0];
            moved[i] -= back * steady[i];
            let mass = self.block_mass(i);
            let b = &mut self.state.blocks[i];
            let c = b.polygon.centroid();
            // A translation keeps the polygon's orientation: this cannot fail (and a
            // failure would leave the block where it is).
            if b.polygon.displace(c, &d).is_err() {
                continue;
            }
            self.scratch.shapes[i].set(&b.polygon);
            work += mass * gravity.dot(DVec2::new(d[0], d[1]));
            for (at, force) in b.loads.iter_mut() {
                let to = displace_point(*at, c, &d);
                work += force.dot(to - *at);
                *at = to;
            }
            for (now, _) in b.fixed_points.iter_mut() {
                *now = displace_point(*now, c, &d);
            }
        }
        self.state.energy.supplied += work;
    }

    /// Each free block's share of `steady` (the blocks' translations in a step) taken as
    /// a group: the mean translation, weighted by mass, of the blocks it is
    /// joined to through closed contacts between free blocks. Rewound by its blocks' own
    /// motions, a wall of soft bricks whose rows slid at rates equal only to the
    /// settling's tolerance, or turned a little, was pressed into its joints by up to 14
    /// times a brick's weight, and took as many steps to settle again as it had taken
    /// first (docs/method.md section 13).
    fn group_translations(&self, steady: &[DVec2]) -> Vec<DVec2> {
        let n = self.state.blocks.len();
        let mut group = Groups::new(n);
        let p = self.model.params.normal_penalty;
        for c in &self.state.contacts.contacts {
            let (a, b) = (c.key.vertex_block as usize, c.key.edge_block as usize);
            if c.active
                && c.state.is_closed()
                && self.free[a].is_some()
                && self.free[b].is_some()
                && self.move_together(steady, p, a, b)
            {
                group.join(a, b);
            }
        }
        let mut sum = vec![(DVec2::ZERO, 0.0); n];
        for &i in &self.free_blocks {
            let (i, m) = (i as usize, self.block_mass(i as usize));
            let r = group.of(i);
            sum[r].0 += m * steady[i];
            sum[r].1 += m;
        }
        (0..n)
            .map(|i| {
                if self.free[i].is_none() {
                    return DVec2::ZERO;
                }
                let (t, m) = sum[group.of(i)];
                t / m
            })
            .collect()
    }

    /// Whether blocks `a` and `b` (in contact) move as one in a step of the steady
    /// translations `steady`: their translations differ by a force within the decision
    /// band at the normal penalty `p` (as [`Simulation::moved_as_groups`] counts it), or
    /// by less than [`SETTLE_APART`] of the larger. A wedge sliding on a mass at rest
    /// does neither: moved back with the mass as one group, by the group's mean, it
    /// would push the mass into its base and leave most of its own slide (docs/method.md
    /// section 13).
    fn move_together(&self, steady: &[DVec2], p: f64, a: usize, b: usize) -> bool {
        let apart = (steady[a] - steady[b]).length();
        let band = DECISION_BAND * self.scratch.force_scale[a].min(self.scratch.force_scale[b]);
        p * apart <= band || apart < SETTLE_APART * steady[a].length().max(steady[b].length())
    }

    /// The largest motion of a free vertex, over `dt^2 / 2`, that the forces of the step
    /// just taken would give its block on its own, contacts aside: each free block's
    /// step terms (its inertia at `dt`, elasticity, weight, loads, initial stress, fixed
    /// points and bolts, [`Simulation::base_terms`]) solved for its motion from rest.
    /// Zero where those forces move nothing.
    fn free_flight(&self, dt: f64) -> f64 {
        let per = 2.0 / (dt * dt);
        let mut reach: f64 = 0.0;
        for (f, &i) in self.free_blocks.iter().enumerate() {
            let (Some(k), Some(rhs)) = (self.scratch.base_k.get(f), self.scratch.base_f.get(f))
            else {
                continue;
            };
            let Some(l) = chol(k, 6) else {
                continue;
            };
            let mut d = *rhs;
            chol_solve(&l, 6, &mut d);
            // Each vertex's motion to first order (its rows of T times d), free of the
            // rounding of its place.
            let polygon = &self.state.blocks[i as usize].polygon;
            let c = polygon.centroid();
            let dot = |r: Vec6| r.iter().zip(&d).map(|(a, b)| a * b).sum::<f64>();
            for &v in polygon.vertices() {
                let moved = DVec2::new(dot(along(DVec2::X, v, c)), dot(along(DVec2::Y, v, c)));
                reach = reach.max(moved.length() * per);
            }
        }
        reach
    }

    /// The vertices of every free block, block by block.
    fn free_vertices(&self) -> Vec<DVec2> {
        self.free_blocks
            .iter()
            .flat_map(|&i| {
                self.state.blocks[i as usize]
                    .polygon
                    .vertices()
                    .iter()
                    .copied()
            })
            .collect()
    }
}

/// The largest change of any vertex's motion from `before` to `motion` (infinite when
/// there is no `before` yet).
fn largest_change(motion: &[DVec2], before: &[DVec2]) -> f64 {
    if before.is_empty() {
        return f64::INFINITY;
    }
    motion
        .iter()
        .zip(before)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use crate::scene::{Format, Scene};
    use crate::simulation::{RunOptions, Simulation};

    /// The free flight of a block (`Simulation::free_flight`): a 2 m x 1 m block of
    /// density 2600 (m = 5,200 kg/m) under gravity and a point load at its centroid moves
    /// from rest by a dt^2 / 2 with a = g + F / m at every vertex (its elastic modes take
    /// no force: it has no stress), whatever dt.
    #[test]
    fn a_blocks_free_flight_is_its_forces_over_its_mass() {
        let scene = r#"
name = "free-flight"
[analysis]
duration = 0.01
time_step = 0.001
max_displacement = 0.005
normal_penalty = 1e10
gravity = [0.0, -9.81]
[materials.rock]
density = 2600.0
young = 10e9
poisson = 0.25
[[blocks]]
id = "floor"
material = "rock"
fixed = true
vertices = [[-2.0, -1.0], [4.0, -1.0], [4.0, 0.0], [-2.0, 0.0]]
[[blocks]]
id = "block"
material = "rock"
vertices = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]
loads = [{ at = [1.0, 0.5], force = [52000.0, 0.0] }]
"#;
        let (_, model) = Scene::parse(scene, Format::Toml, "free-flight.toml").unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        // a = (52000 / 5200, -9.81) = (10, -9.81).
        let expected = (10.0f64).hypot(9.81);
        for dt in [1e-5, 1e-3] {
            sim.base_terms(dt);
            let reach = sim.free_flight(dt);
            assert!(
                (reach / expected - 1.0).abs() < 1e-9,
                "dt {dt}: {reach} against {expected}"
            );
        }
    }
}
