//! Settling before a dynamic run (`analysis.settle`, docs/method.md section 13).
//!
//! Blocks written resting on each other start with their contact springs unloaded: in
//! the first steps they sink into them under their weight and ring at sqrt(p / m), and
//! friction, which follows the normal force, rings with them. A block sliding down an
//! incline keeps the error of wherever the ring stopped, and a stack of blocks slides
//! apart where it should slide as one (docs/accuracy.md; `tests/physics/stacks.rs`).
//!
//! Settling takes the blocks to the equilibrium of their weight and loads on their
//! contacts with every joint held (glued: no opening, no sliding) before t = 0, by a
//! few static steps of a copy of the model, long enough that inertia does not resist
//! them; blocks that rest on nothing (in flight) are held where they are. The run then
//! starts from the settled places and stresses, with the settled contacts (their
//! springs loaded, shear springs anchored where they were) under the scene's own
//! joints, so that a joint that cannot hold its load slides from the first step. The
//! work gravity and the loads did while settling is added to the energy the physics
//! guard counts as supplied.

use crate::diagnosis::SimError;
use crate::model::supported_blocks;
use crate::scene::{Integration, JointProps, Mode};
use crate::simulation::{RunOptions, Simulation};
use dda_contact::BlockShape;

/// tan(phi) of every joint while settling.
const SETTLE_FRICTION: f64 = 1e3;

/// Static steps of the settling.
const SETTLE_STEPS: u32 = 3;

/// The inertia of a static step, 2 m / dt^2, is at most this share of the normal penalty
/// for the heaviest block while settling: the step then comes within that share of the
/// equilibrium.
const SETTLE_INERTIA: f64 = 1e-6;

impl Simulation {
    /// Settles the blocks at t = 0 (see the module docs), once, before the first step
    /// of a dynamic run whose scene asks for it and has something to settle.
    pub(crate) fn settle(&mut self) -> Result<(), SimError> {
        self.state.settled = true;
        let p = &self.model.params;
        let pulled = p.gravity.is_some_and(|g| g != glam::DVec2::ZERO)
            || self.model.blocks.iter().any(|b| !b.loads.is_empty())
            || self.model.bolts.iter().any(|b| b.pretension != 0.0);
        if !p.settle || !self.effects.contact || !pulled {
            return Ok(());
        }
        let mut model = self.model.clone();
        let tied: Vec<(usize, usize)> = model
            .bolts
            .iter()
            .map(|b| (b.from_block, b.to_block))
            .collect();
        let supported = supported_blocks(&model.blocks, p.d_tol, &tied);
        let mut heaviest = 0.0f64;
        for (i, (b, s)) in model.blocks.iter_mut().zip(&supported).enumerate() {
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
        mp.dt0 = (2.0 * heaviest / (SETTLE_INERTIA * mp.normal_penalty)).sqrt();
        mp.duration = f64::from(SETTLE_STEPS) * mp.dt0;
        mp.impact_steps = None;
        mp.integration = Integration::ConstantAcceleration;
        mp.settle = false;
        for j in &mut model.joints {
            // Held by friction no load in equilibrium reaches (tan phi = 1e3, 89.94
            // degrees); the glue between the parts of a body stays.
            *j = JointProps {
                tan_phi: SETTLE_FRICTION,
                cohesion: 0.0,
                tensile_strength: 0.0,
                glued: false,
            };
        }
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
        let supplied = settling.state.energy.supplied;
        for _ in 0..SETTLE_STEPS {
            if settling.finished() {
                break;
            }
            settling.step().map_err(|e| SimError::Settle {
                reason: e.to_string(),
            })?;
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
        // The settled contacts, their shear springs anchored where they were: a joint
        // that holds its load goes on holding it (no creep while the shear springs load
        // again); one that cannot slides from the first step.
        self.state.contacts = settling.state.contacts;
        for c in &mut self.state.contacts.contacts {
            // The settling's joints are not the scene's: bonding joints bond at the
            // first step, and the scene's joints decide every state from there.
            c.bonded = false;
        }
        let work = settling.state.energy.supplied - supplied;
        self.state.energy.supplied += work;
        self.state.energy.supplied_max = self
            .state
            .energy
            .supplied_max
            .max(self.state.energy.supplied);
        Ok(())
    }
}
