//! Rock bolts and material points (docs/scene-format.md, "Bolts and measured points").
//!
//! A material point is followed through the run by the affine map of its block: DDA
//! moves a block by an affine map in every step (translation, rotation taken exactly,
//! constant strain), and the composition of affine maps is affine, so a point keeps its
//! coordinates in the frame of three of its block's vertices. Its position now is read
//! from the block's polygon now; nothing is saved for it.
//!
//! A bolt is an axial spring between two material points, each in its own block: its
//! tension is `T = T0 + k (L - L0)` (`T0` the pretension, `L0` the length at the start,
//! compression negative). In a step it adds, like a fixed point, the stiffness
//! `k r r^T` of its elongation `e = r_to . D_to - r_from . D_from` to its blocks' terms
//! (`r` the projection of a block's point displacement on the bolt's direction at step
//! start) and its tension to their right-hand sides, with the coupling of two free
//! blocks in the matrix pattern. After a step whose end tension exceeds its strength, it
//! is broken for good (time and tension recorded).

use crate::kinematics::{Vec6, along, half_turned, point_displacement};
use crate::simulation::Simulation;
use dda_geom::DVec2;
use serde::{Deserialize, Serialize};

/// The coordinates (a, b) of point `p` in the frame of a convex polygon's first three
/// `vertices`: p = v0 + a (v1 - v0) + b (v2 - v0). A block's points keep them as it
/// moves (its motion is affine), so a material point is found again from them
/// ([`from_affine`]). A convex polygon's first three vertices are never collinear.
pub fn affine_coordinates(vertices: &[DVec2], p: DVec2) -> [f64; 2] {
    let (e1, e2, q) = (
        vertices[1] - vertices[0],
        vertices[2] - vertices[0],
        p - vertices[0],
    );
    let det = e1.perp_dot(e2);
    [q.perp_dot(e2) / det, e1.perp_dot(q) / det]
}

/// The point of coordinates `ab` ([`affine_coordinates`]) in the frame of `vertices`.
pub fn from_affine(vertices: &[DVec2], ab: [f64; 2]) -> DVec2 {
    let (v0, v1, v2) = (vertices[0], vertices[1], vertices[2]);
    v0 + ab[0] * (v1 - v0) + ab[1] * (v2 - v0)
}

/// What a bolt has come to: broken or not.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BoltState {
    /// When it broke, s, and its tension then, N.
    pub broken: Option<(f64, f64)>,
}

/// A bolt in the current state: its tension and each end's projection on its direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoltNow {
    tension: f64,
    r_from: Vec6,
    r_to: Vec6,
}

impl Simulation {
    /// Where the material point that was at `start` in block `block` at t = 0 is now.
    pub fn material_point(&self, block: usize, start: DVec2) -> DVec2 {
        let [a, b] = affine_coordinates(self.model.blocks[block].polygon.vertices(), start);
        from_affine(self.state.blocks[block].polygon.vertices(), [a, b])
    }

    /// The velocity of the material point that was at `start` in block `block`, m/s.
    pub fn material_velocity(&self, block: usize, start: DVec2) -> DVec2 {
        let p = self.material_point(block, start);
        let centroid = self.scratch.shapes[block].centroid;
        point_displacement(p, centroid, &self.state.blocks[block].velocity)
    }

    /// Bolt `k`'s tension now, N (negative: compression); `None` once broken or once an
    /// excavation has removed a block it holds.
    pub fn bolt_tension(&self, k: usize) -> Option<f64> {
        self.bolt_now(k).map(|b| b.tension)
    }

    /// What has come of each bolt.
    pub fn bolt_states(&self) -> &[BoltState] {
        &self.state.bolts
    }

    /// Whether bolt `k` holds: not broken, and neither of its blocks excavated.
    fn bolt_holds(&self, k: usize) -> bool {
        let b = &self.model.bolts[k];
        self.state.bolts[k].broken.is_none()
            && !self.removed[b.from_block]
            && !self.removed[b.to_block]
    }

    pub(crate) fn bolt_now(&self, k: usize) -> Option<BoltNow> {
        if !self.bolt_holds(k) {
            return None;
        }
        let b = &self.model.bolts[k];
        let from = self.material_point(b.from_block, b.from);
        let to = self.material_point(b.to_block, b.to);
        let length = from.distance(to);
        let n = (to - from) / length;
        let tension = b.pretension + b.stiffness * (length - b.from.distance(b.to));
        // The bolt's direction and each end's lever arm half way through the step, as the
        // blocks' velocities predict it (`half_turned`): the bolt's line turns at the
        // ends' relative speed across it over its length.
        let dt = self.scratch.attempt_dt;
        let centroid = |block: usize| self.scratch.shapes[block].centroid;
        let velocity = |block: usize, at: DVec2| {
            point_displacement(at, centroid(block), &self.state.blocks[block].velocity)
        };
        let across = DVec2::new(-n.y, n.x);
        let line_turn =
            (velocity(b.to_block, to) - velocity(b.from_block, from)).dot(across) / length * dt;
        let n = half_turned(n, DVec2::ZERO, line_turn);
        let row = |block: usize, at: DVec2| {
            let c = centroid(block);
            let turn = self.state.blocks[block].velocity[2] * dt;
            along(n, half_turned(at, c, turn), c)
        };
        Some(BoltNow {
            tension,
            r_from: row(b.from_block, from),
            r_to: row(b.to_block, to),
        })
    }

    /// Adds every holding bolt's stiffness and tension to its free blocks' base terms.
    pub(crate) fn bolt_terms(&mut self) {
        for k in 0..self.model.bolts.len() {
            let Some(now) = self.bolt_now(k) else {
                continue;
            };
            let b = &self.model.bolts[k];
            // The tension pulls `from` towards `to` (+r_from) and `to` back (-r_to).
            for (block, r, sign) in [
                (b.from_block, now.r_from, 1.0),
                (b.to_block, now.r_to, -1.0),
            ] {
                let Some(f) = self.free[block] else {
                    continue;
                };
                let (kk, ff) = (
                    &mut self.scratch.base_k[f as usize],
                    &mut self.scratch.base_f[f as usize],
                );
                for a in 0..6 {
                    ff[a] += sign * now.tension * r[a];
                    for c in 0..6 {
                        kk[a][c] += b.stiffness * r[a] * r[c];
                    }
                }
            }
        }
    }

    /// Adds the coupling of the bolts between two free blocks to the matrix.
    pub(crate) fn bolt_couplings(&mut self) {
        for k in 0..self.model.bolts.len() {
            let Some(now) = self.bolt_now(k) else {
                continue;
            };
            let b = &self.model.bolts[k];
            if let (Some(fa), Some(fb)) = (self.free[b.from_block], self.free[b.to_block])
                && let Some(e) = self.scratch.system.entry(fa, fb)
            {
                self.scratch
                    .system
                    .add_outer(e, fa, fb, -b.stiffness, &now.r_from, &now.r_to);
            }
        }
    }

    /// The free-block pairs the holding bolts couple (for the matrix pattern).
    pub(crate) fn bolt_pairs(&self, out: &mut Vec<(u32, u32)>) {
        for (k, b) in self.model.bolts.iter().enumerate() {
            if !self.bolt_holds(k) {
                continue;
            }
            if let (Some(a), Some(c)) = (self.free[b.from_block], self.free[b.to_block]) {
                out.push((a.min(c), a.max(c)));
            }
        }
    }

    /// The work the bolts do on the blocks in the trial step (`scratch.d`): minus the
    /// rise of their elastic energy, -(T + k e / 2) e, for the physics guard.
    pub(crate) fn bolt_work(&self) -> f64 {
        let mut work = 0.0;
        for k in 0..self.model.bolts.len() {
            let Some(now) = self.bolt_now(k) else {
                continue;
            };
            let b = &self.model.bolts[k];
            let moved = |block: usize, r: &Vec6| -> f64 {
                if self.free[block].is_some() {
                    (0..6).map(|a| r[a] * self.scratch.d[block][a]).sum()
                } else {
                    0.0
                }
            };
            let e = moved(b.to_block, &now.r_to) - moved(b.from_block, &now.r_from);
            work -= (now.tension + 0.5 * b.stiffness * e) * e;
        }
        work
    }

    /// Breaks the bolts whose tension, after the step just taken, exceeds their strength.
    pub(crate) fn break_bolts(&mut self) {
        for k in 0..self.model.bolts.len() {
            let (Some(strength), Some(now)) = (self.model.bolts[k].strength, self.bolt_now(k))
            else {
                continue;
            };
            if now.tension > strength {
                self.state.bolts[k].broken = Some((self.state.t, now.tension));
            }
        }
    }
}
