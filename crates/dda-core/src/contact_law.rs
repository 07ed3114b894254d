//! The contact law: each active contact re-checked against the trial solution of an
//! open-close iteration: open or closed by the normal distance (or a bond's tensile
//! strength), locked or sliding by Mohr-Coulomb.

use crate::simulation::Simulation;
use crate::springs::{contact_length, contact_points, shear_row};
use dda_contact::ContactState;
use dda_geom::VertexEdge;

impl Simulation {
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
        self.flipped.clear();
        for k in 0..self.contacts.contacts.len() {
            let c = self.contacts.contacts[k];
            if !c.active {
                continue;
            }
            let j = self.joint(k);
            let d = self.rows[k].eval(&self.d);
            let mut n = c;
            match c.state {
                ContactState::Open => {
                    if d < 0.0 {
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
                    let length = || contact_length(&c, &self.shapes);
                    let holds_tension = c.bonded
                        && j.tensile_strength > 0.0
                        && pn * d <= j.tensile_strength * length();
                    if d > open_band && !holds_tension {
                        n.state = ContactState::Open;
                        n.bonded = false;
                        n.normal_force = 0.0;
                    } else {
                        n.normal_force = -pn * d;
                        if j.has_shear() {
                            if c.state == ContactState::Locked {
                                let s = shear_row(&c, &self.shapes, &self.half, c.locked_r)
                                    .eval(&self.d);
                                let mut limit = n.normal_force.max(0.0) * j.tan_phi;
                                if c.bonded {
                                    limit += j.cohesion * length();
                                }
                                if ps * s.abs() > limit {
                                    n.state = ContactState::Sliding;
                                    n.slide_dir = s.signum();
                                    n.bonded = false;
                                }
                            } else {
                                let s =
                                    shear_row(&c, &self.shapes, &self.half, c.r.clamp(0.0, 1.0))
                                        .eval(&self.d);
                                if c.slide_dir == 0.0 {
                                    n.slide_dir = s.signum();
                                } else if s * c.slide_dir < 0.0 {
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
                self.flipped.push(k as u32);
            }
            self.contacts.contacts[k] = n;
        }
        changed
    }

    /// Projection ratio of a contact's vertex on its edge at the trial positions.
    pub(crate) fn trial_ratio(&self, c: &dda_contact::Contact) -> f64 {
        let (p1, p2, p3) = contact_points(c, &self.shapes);
        let k = c.key;
        let (mv, me) = (
            &self.motions[k.vertex_block as usize],
            &self.motions[k.edge_block as usize],
        );
        VertexEdge::new(mv.apply(p1), me.apply(p2), me.apply(p3)).r
    }
}
