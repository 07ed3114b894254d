//! The effects a scene calls for ("simulate only the effects a scene calls
//! for", docs/method.md section 2): decided once from the validated model, listed at run
//! start and in summary.json. Each term of the global system belongs to exactly one effect,
//! and the engine assembles a term only when its effect is on.

use crate::scene::{Mode, Model};
use serde::{Deserialize, Serialize};

/// Which physical effects a run assembles.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Effects {
    /// Block elasticity and stresses (deformable blocks, 6 DOF); off: rigid, 3 DOF.
    pub elasticity: bool,
    /// Inertia carried between steps (dynamic); off: static (velocities zeroed per step).
    pub inertia: bool,
    /// Body force from a non-zero gravity.
    pub gravity: bool,
    /// Blocks with eliminated DOFs.
    pub fixed_blocks: bool,
    /// Stiff springs holding block points in place.
    pub fixed_points: bool,
    /// Point loads.
    pub point_loads: bool,
    /// Non-zero initial velocities.
    pub initial_velocity: bool,
    /// Non-zero initial stresses.
    pub initial_stress: bool,
    /// Normal contact springs (more than one block).
    pub contact: bool,
    /// Shear springs and friction (a joint in use has friction or cohesion).
    pub friction: bool,
    /// Cohesion along bonded contacts.
    pub cohesion: bool,
    /// Tensile strength of bonded contacts.
    pub tension: bool,
    /// Non-convex blocks carried as convex parts glued together.
    pub glued_parts: bool,
    /// Rock bolts.
    pub bolts: bool,
    /// Blocks driven by a ground-motion record.
    pub seismic: bool,
}

impl Effects {
    /// The effects `model` calls for.
    pub fn of(model: &Model) -> Self {
        let p = &model.params;
        let blocks = &model.blocks;
        let nm = model.materials.len();
        let mut used = vec![false; nm];
        for b in blocks {
            used[b.material] = true;
        }
        let (mut friction, mut cohesion, mut tension) = (false, false, false);
        let mut note = |j: &crate::scene::JointProps| {
            friction |= j.tan_phi > 0.0 || j.cohesion > 0.0;
            cohesion |= j.cohesion > 0.0;
            tension |= j.tensile_strength > 0.0;
        };
        if blocks.len() > 1 {
            for a in 0..nm {
                for b in 0..nm {
                    if used[a] && used[b] {
                        note(&model.joints[model.joint_of[a * nm + b] as usize]);
                    }
                }
            }
            for k in blocks.iter().flat_map(|b| b.edge_joints.iter().flatten()) {
                note(&model.joints[*k as usize]);
            }
        }
        Effects {
            elasticity: p.deformable,
            inertia: p.mode == Mode::Dynamic,
            gravity: p.gravity.is_some_and(|g| g != glam::DVec2::ZERO),
            fixed_blocks: blocks.iter().any(|b| b.fixed),
            fixed_points: blocks.iter().any(|b| !b.fixed_points.is_empty()),
            point_loads: blocks.iter().any(|b| !b.loads.is_empty()),
            initial_velocity: blocks
                .iter()
                .any(|b| !b.fixed && b.velocity.iter().any(|&v| v != 0.0)),
            initial_stress: p.deformable
                && blocks.iter().any(|b| b.stress.iter().any(|&s| s != 0.0)),
            contact: blocks.len() > 1,
            friction,
            cohesion,
            tension,
            glued_parts: blocks.iter().any(|b| b.body.is_some()),
            bolts: !model.bolts.is_empty(),
            seismic: model.ground.is_some(),
        }
    }

    /// DOFs per free block: 6 with elasticity, else 3.
    pub fn dofs_per_block(&self) -> usize {
        if self.elasticity { 6 } else { 3 }
    }

    /// The names of the effects that are on, in a fixed order (summary.json `effects`).
    pub fn names(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        let mut on = |b: bool, name: &'static str| {
            if b {
                v.push(name);
            }
        };
        on(self.elasticity, "elasticity");
        on(self.inertia, "inertia");
        on(!self.inertia, "static");
        on(self.gravity, "gravity");
        on(self.fixed_blocks, "fixed-blocks");
        on(self.fixed_points, "fixed-points");
        on(self.point_loads, "point-loads");
        on(self.initial_velocity, "initial-velocity");
        on(self.initial_stress, "initial-stress");
        on(self.contact, "contact");
        on(self.friction, "friction");
        on(self.cohesion, "cohesion");
        on(self.tension, "tension");
        on(self.glued_parts, "glued-parts");
        on(self.bolts, "bolts");
        on(self.seismic, "seismic");
        v
    }
}
