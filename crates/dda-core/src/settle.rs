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
//! the penalty ([`SETTLE_INERTIA`]). Stiff modes (the contact springs) converge in a
//! few such steps, to the forces that balance the weight, the loads and the inertia of
//! the motion the blocks start (d'Alembert): those of a joint that holds, and of one
//! that slides (friction at its limit, the normal force of the accelerated blocks).
//! The steps go on until every vertex moves in a step as it moved in the step before
//! (settled, or sliding steadily) to [`SETTLE_TOLERANCE`] of the first step's motion,
//! until that stops improving ([`SETTLE_STALL`]), or for [`SETTLE_MAX_STEPS`]. Blocks
//! that rest on nothing (in flight) are held where they are; the ground is still; and
//! nothing is excavated (the settling's steps take time of their own, before t = 0,
//! and would pass the excavations of the run). The run then starts from
//! the settled places, stresses and contacts (their springs loaded, shear springs
//! anchored where they were, glued seams bonded) with the blocks' own velocities. The
//! work gravity and the loads did while settling is added to the energy the physics
//! guard counts as supplied. A block free to slide moves by its slide while settling, a
//! dt^2 / 2 a step (a its acceleration).
//!
//! Holding every joint while settling (a static solution of glued blocks, our first
//! design) is wrong where the scene's joints cannot hold: it loads them with shear they
//! do not carry in the run, a column that would topple glued starts the run on its toe,
//! and an equilibrium reached with no joint at its limit creeps once the limits apply
//! (docs/method.md, section 13).

use crate::diagnosis::SimError;
use crate::model::supported_blocks;
use crate::scene::{Integration, Mode};
use crate::simulation::{RunOptions, Simulation};
use dda_contact::BlockShape;
use dda_geom::DVec2;

/// Most static steps of the settling.
const SETTLE_MAX_STEPS: u32 = 2000;

/// The settling has converged when no vertex's motion in a step differs from its motion
/// in the step before by more than this share of the first step's largest motion. Our
/// choice, measured on running-bond walls of 1 x 0.5 m bricks with half bricks at the
/// course ends, 8 courses of 5 on 30/25 (p 3e10 to 1e12, dt 1 ms): their steady slide
/// takes hundreds of steps to converge (the pieces of the wall slide at rates that
/// approach one another by a fraction of a percent a step), and started from a
/// settling stopped at 1e-3, 1e-4 or 3e-5 the walls parted by 10% to 30% (the slide as
/// one body is unstable there, docs/method.md section 13); from 1e-5 (400 to 500
/// steps) they hold to 0.29% (`tests/physics/stacks.rs`). The toppling columns of
/// `tests/physics/regions.rs` stood to 0.24 mm at 1e-3 already.
const SETTLE_TOLERANCE: f64 = 1e-5;

/// Steps without progress after which the settling stops: the change of the motion has
/// not fallen below half its smallest value so far. Contacts at their friction limit
/// that lock and slide in turn can hold the change at a floor; the slow convergence of
/// a wall's slide halves it every 20 to 140 steps. At 20 (until 2026-11-24) the walls
/// above stopped after 22 steps and parted by 20% to 57%.
const SETTLE_STALL: u32 = 200;

/// The inertia of a settling step, 2 m / dt^2 for the heaviest block, is at most this
/// share of the normal penalty: the step is the run's own, or longer where that would
/// take many steps for the springs to carry their load (each step carries the
/// imbalance down to inertia / (inertia + penalty) of what it was).
const SETTLE_INERTIA: f64 = 1.0;

/// What the settling did before t = 0 ([`Simulation::settling`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Settling {
    /// Static steps taken.
    pub steps: u32,
    /// Whether the motion converged (every vertex moving as in the step before, to 1e-5
    /// of the first step's motion); if not, the settling stopped after 200 steps
    /// without progress, or at its most steps, 2,000 (docs/method.md section 13).
    pub converged: bool,
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

    /// Settles the blocks at t = 0 (see the module docs), once, before the first step
    /// of a dynamic run whose scene asks for it and has something to settle.
    pub(crate) fn settle(&mut self) -> Result<(), SimError> {
        let settles = self.settles();
        self.state.settled = true;
        if !settles {
            return Ok(());
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
            }
        }
        if heaviest == 0.0 {
            return Ok(());
        }
        let mp = &mut model.params;
        mp.mode = Mode::Static;
        let shortest = (2.0 * heaviest / (SETTLE_INERTIA * mp.normal_penalty)).sqrt();
        mp.dt0 = mp.dt0.max(shortest);
        mp.duration = f64::from(SETTLE_MAX_STEPS) * mp.dt0;
        mp.impact_steps = None;
        mp.integration = Integration::ConstantAcceleration;
        mp.settle = false;
        model.ground = None;
        for b in &mut model.bolts {
            // A bolt breaks in the run, not while the blocks settle onto it.
            b.strength = None;
        }
        let options = RunOptions {
            stop_on_violation: false,
            ..self.options
        };
        let mut settling = Simulation::new(model, options);
        // Blocks written resting on each other touch along flush faces, where a contact
        // starts open: closed from the start, they carry their weight in the first step,
        // where each open-close iteration would otherwise close one more layer of a
        // stack (the layers above falling with it) and a tall stack runs out of them.
        settling.close_touching = true;
        let supplied = settling.state.energy.supplied;
        // Each step's motion of every free vertex over dt^2 / 2 (its acceleration from
        // rest, the same over steps of any size while a block slides steadily, so that
        // steps cut and grown back compare); the first step's largest; the smallest
        // change from step to step so far, and its step.
        let mut last: Vec<DVec2> = Vec::new();
        let mut first = None;
        let (mut best, mut best_at) = (f64::INFINITY, 0);
        let mut report = Settling {
            steps: 0,
            converged: false,
        };
        for n in 1..=SETTLE_MAX_STEPS {
            if settling.finished() {
                break;
            }
            report.steps = n;
            let before = settling.free_vertices();
            let record = settling.step().map_err(|e| SimError::Settle {
                reason: e.to_string(),
            })?;
            let per = 2.0 / (record.dt * record.dt);
            let motion: Vec<DVec2> = settling
                .free_vertices()
                .iter()
                .zip(&before)
                .map(|(a, b)| (*a - *b) * per)
                .collect();
            let size = motion.iter().map(|m| m.length()).fold(0.0, f64::max);
            let scale = *first.get_or_insert(size);
            let change = if last.is_empty() {
                f64::INFINITY
            } else {
                motion
                    .iter()
                    .zip(&last)
                    .map(|(a, b)| (*a - *b).length())
                    .fold(0.0, f64::max)
            };
            if change <= SETTLE_TOLERANCE * scale {
                report.converged = true;
                break;
            }
            if change <= 0.5 * best {
                (best, best_at) = (change, n);
            } else if n - best_at >= SETTLE_STALL {
                break;
            }
            last = motion;
        }
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
        // ones sliding: each joint goes on carrying the force it settled with.
        self.state.contacts = settling.state.contacts;
        for k in 0..self.state.contacts.contacts.len() {
            // Bonding joints bond at the run's first step, as without settling. The seams
            // of glued parts stay bonded where they settled: loaded, a seam may lie
            // further off its edge's line than the run's first step would bond (and a
            // seam not bonded is no contact at all: the parts passed into each other).
            if !self.joint(k).glued {
                self.state.contacts.contacts[k].bonded = false;
            }
        }
        self.settling = Some(report);
        let work = settling.state.energy.supplied - supplied;
        self.state.energy.supplied += work;
        self.state.energy.supplied_max = self
            .state
            .energy
            .supplied_max
            .max(self.state.energy.supplied);
        Ok(())
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
