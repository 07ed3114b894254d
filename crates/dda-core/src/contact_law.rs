//! The contact law: each active contact re-checked against the trial solution of an
//! open-close iteration: open or closed by the normal distance (or a bond's tensile
//! strength), locked or sliding by Mohr-Coulomb.
//!
//! **Decisions of negligible force keep the state** (our choice; the paper decides by
//! signs alone). Every change of state is about a force: the spring force of a contact
//! that would close (p |d|) or the tension a closed one would have to hold (p d), the
//! shear force beyond the friction limit of a locked contact that would slide, the
//! shear spring force a sliding contact would take if it locked. A change is made only
//! when that force exceeds [`DECISION_BAND`] of the contact's force scale: the external
//! force (weight and point loads) on the lighter of its two free blocks. Below it the contact keeps its state: a hysteresis band stated in the
//! step's own forces. Where blocks meet along flush joints (T- and X-junctions, the
//! two covers of one corner) contacts sit at d_n = 0 with forces that hover around
//! zero; decided by sign they flip between open and closed, locked and sliding, on
//! forces of 1e-4 of a block's weight and below, and the iteration never ends.
//! `docs/method.md`, section 6, gives the measurements.

use crate::simulation::Simulation;

/// Fraction of a contact's force scale (see the module docs) below which a change of its
/// state is negligible and not made: a closed contact holds that much tension at most,
/// an open one lets its blocks overlap by that much force over the penalty, a locked one
/// holds that much beyond its friction limit. Our choice, measured in
/// `docs/method.md` (section 6): 1e-4, 1e-3 and 1e-2 all let a running-bond wall and a
/// grid of equal blocks stand; 1e-3 keeps the force error of a decision to a thousandth
/// of the lighter block's weight.
pub(crate) const DECISION_BAND: f64 = 1e-3;
use crate::springs::{contact_length, contact_points, shear_row};
use dda_contact::ContactState;
use dda_geom::{DVec2, VertexEdge};

impl Simulation {
    /// Sets each block's force scale (see the module docs): the magnitude of the external
    /// force on a free block, its weight and its point loads; infinite for a fixed block.
    /// The inertia terms of the time scheme are not forces on the block: a block moving
    /// at constant speed has none.
    pub(crate) fn set_force_scale(&mut self) {
        let g = match self.model.params.gravity {
            Some(g) if self.effects.gravity => g,
            _ => DVec2::ZERO,
        };
        self.scratch.force_scale.clear();
        self.scratch
            .force_scale
            .resize(self.state.blocks.len(), f64::INFINITY);
        for (mass, &i) in self.scratch.mass.iter().zip(&self.free_blocks) {
            let loads: DVec2 = self.state.blocks[i as usize]
                .loads
                .iter()
                .map(|l| l.1)
                .sum();
            // mass[0][0] is the block's mass (rho times its area).
            self.scratch.force_scale[i as usize] = (mass[0][0] * g + loads).length();
        }
    }

    /// Re-checks every active contact against the trial solution; returns how many
    /// changed state.
    pub(crate) fn update_states(&mut self) -> usize {
        let p = &self.model.params;
        let (pn, ps) = (p.normal_penalty, p.shear_penalty);
        // A closed contact opens only beyond a band of 1e-9 d_tol: blocks that touch to
        // rounding (joint faces cut from one rock) otherwise chatter between open and
        // closed on d of order 1e-17 m and never converge. The tension held inside the
        // band, p * 1e-9 d_tol, is negligible (our choice; the paper is silent).
        let open_band = 1e-9 * p.d_tol;
        let mut changed = 0;
        self.scratch.flipped.clear();
        for k in 0..self.state.contacts.contacts.len() {
            let c = self.state.contacts.contacts[k];
            if !c.active {
                continue;
            }
            let j = self.joint(k);
            let d = self.scratch.rows[k].eval(&self.scratch.d);
            let key = c.key;
            // The force below which a change is negligible (see the module docs).
            let band = DECISION_BAND
                * self.scratch.force_scale[key.vertex_block as usize]
                    .min(self.scratch.force_scale[key.edge_block as usize]);
            let mut n = c;
            match c.state {
                ContactState::Open => {
                    if d < 0.0 && pn * -d > band {
                        // Closes where its trajectory crossed the edge's line.
                        let r1 = self.trial_ratio(&c);
                        let t = if c.d_n > 0.0 {
                            c.d_n / (c.d_n - d)
                        } else {
                            0.0
                        };
                        n.locked_r = (c.r + t * (r1 - c.r)).clamp(0.0, 1.0);
                        n.state = if j.has_shear() {
                            ContactState::Locked
                        } else {
                            ContactState::Sliding
                        };
                        n.slide_dir = 0.0;
                        n.normal_force = -pn * d;
                    }
                }
                ContactState::Locked | ContactState::Sliding => {
                    // Only bonds need the length: looked up (a load from the edge block's
                    // shape, often a cache miss) only for them.
                    let length = || contact_length(&c, &self.scratch.shapes);
                    let holds_tension = c.bonded
                        && j.tensile_strength > 0.0
                        && pn * d <= j.tensile_strength * length();
                    if d > open_band && pn * d > band && !holds_tension {
                        n.state = ContactState::Open;
                        n.bonded = false;
                        n.normal_force = 0.0;
                    } else {
                        n.normal_force = -pn * d;
                        if j.has_shear() {
                            if c.state == ContactState::Locked {
                                let s = shear_row(
                                    &c,
                                    &self.scratch.shapes,
                                    &self.scratch.half,
                                    c.locked_r,
                                )
                                .eval(&self.scratch.d);
                                let mut limit = n.normal_force.max(0.0) * j.tan_phi;
                                if c.bonded {
                                    limit += j.cohesion * length();
                                }
                                if ps * s.abs() > limit + band {
                                    n.state = ContactState::Sliding;
                                    n.slide_dir = s.signum();
                                    n.bonded = false;
                                }
                            } else {
                                let s = shear_row(
                                    &c,
                                    &self.scratch.shapes,
                                    &self.scratch.half,
                                    c.r.clamp(0.0, 1.0),
                                )
                                .eval(&self.scratch.d);
                                if c.slide_dir == 0.0 {
                                    n.slide_dir = s.signum();
                                } else if s * c.slide_dir < 0.0 && ps * s.abs() > band {
                                    // The motion reversed against friction: it sticks.
                                    n.state = ContactState::Locked;
                                    n.locked_r = c.r.clamp(0.0, 1.0);
                                }
                            }
                        }
                    }
                }
            }
            if n.state != c.state || n.slide_dir != c.slide_dir {
                changed += 1;
                self.scratch.flipped.push(k as u32);
            }
            self.state.contacts.contacts[k] = n;
        }
        changed
    }

    /// Projection ratio of a contact's vertex on its edge at the trial positions.
    pub(crate) fn trial_ratio(&self, c: &dda_contact::Contact) -> f64 {
        let (p1, p2, p3) = contact_points(c, &self.scratch.shapes);
        let k = c.key;
        let (mv, me) = (
            &self.scratch.motions[k.vertex_block as usize],
            &self.scratch.motions[k.edge_block as usize],
        );
        VertexEdge::new(mv.apply(p1), me.apply(p2), me.apply(p3)).r
    }
}
