//! Detection at step start: the neighbour pairs (a sort-and-sweep broad phase reused
//! within a skin), each pair's candidate contacts from the detector with states
//! inherited from the previous step, then the engine's normalisation of states.

use crate::assembly::joint_of;
use crate::simulation::Simulation;
use dda_contact::ContactState;

/// The neighbour search's skin, in d_max: its pairs are found for d_tol plus twice the
/// skin and reused while no block's box has moved by more than the skin
/// ([`NeighbourSearch::with_skin`]). The pairs are the same whatever the skin; only
/// the number of sweeps changes. Measured on paper 5.2b (826 blocks, 844 steps): skins
/// of 1, 2, 3 and 5 d_max swept at 416, 289, 222 and 162 steps, and the search took
/// 0.81%, 0.60%, 0.61% and 0.48% of the run's samples against 1.20% sweeping every
/// step; at r_tol = 10, 1 and 2 d_max swept 68 and 38 times in 635 steps, 0.38% and
/// 0.44% against 0.87%.
pub(crate) const NEIGHBOUR_SKIN: f64 = 2.0;

/// How far from the line of an edge, in d_tol, a vertex of another part of the same
/// body may be for their contact to be a seam of the glue: parts cut from one outline
/// share their seams to rounding (1e-14 m and less), and no other pair of their
/// features comes this close without touching.
pub(crate) const GLUE_SEAM: f64 = 1e-3;

/// How far from the line of a seam edge of another part of its body a vertex may be for
/// their contact to be glue, and from the line of an edge of another block for blocks
/// written touching to start bonded by a joint with cohesion or tensile strength, m:
/// [`GLUE_SEAM`] d_tol, or as far as faces written by hand to 6 decimals may differ
/// (`limits::START_OVERLAP`) where that is more, so that a body written by hand holds
/// where it finds its seams (`Model::seams`), and a bond written by hand holds.
pub(crate) fn glue_reach(d_tol: f64) -> f64 {
    (GLUE_SEAM * d_tol).max(crate::limits::START_OVERLAP)
}

impl Simulation {
    /// Step-start detection with states inherited from the previous step, then the
    /// engine's normalisation: closed contacts of frictionless joints slide (no shear
    /// spring), contacts of bonding joints whose blocks touch as the scene wrote them
    /// start bonded, and active contacts between parts of one body are locked and
    /// bonded.
    pub(crate) fn detect_step_start(&mut self) {
        self.scratch.aabbs.clear();
        self.scratch
            .aabbs
            .extend(self.scratch.shapes.iter().map(|s| s.aabb));
        self.scratch.neighbours.find(
            &self.scratch.aabbs,
            self.detection.d_tol,
            &mut self.scratch.pairs,
        );
        let (free, removed) = (&self.free, &self.removed);
        self.scratch.pairs.retain(|p| {
            let (a, b) = (p.a as usize, p.b as usize);
            (free[a].is_some() || free[b].is_some()) && !removed[a] && !removed[b]
        });
        std::mem::swap(&mut self.scratch.prev, &mut self.state.contacts);
        dda_contact::detect(
            self.detector.as_ref(),
            &self.scratch.shapes,
            &self.scratch.pairs,
            &self.detection,
            &self.scratch.prev,
            self.threads(),
            &mut self.state.contacts,
        );
        // Each candidate's joint, looked up once for the step: the open-close iteration
        // reads it for every closed contact in every iteration.
        let (model, bodies, material) = (&self.model, &self.bodies, &self.material);
        self.scratch.joints.clear();
        self.scratch.joints.extend(
            self.state
                .contacts
                .contacts
                .iter()
                .map(|c| joint_of(model, bodies, material, c)),
        );
        let first = self.state.totals.steps == 0;
        let glue = self.model.joints_by_edge;
        let close_touching = first && self.close_touching;
        // The first detection of the blocks as the scene wrote them: the settling's first
        // static step, or the run's first step where nothing settled them. Contacts of
        // bonding joints that touch then start bonded.
        let bond_touching = first && self.settling.is_none();
        let touch = glue_reach(self.detection.d_tol);
        let open_band = self.open_band();
        for k in 0..self.state.contacts.contacts.len() {
            let mut c = self.state.contacts.contacts[k];
            // A bond holds only while its contact is closed: the contact law unbonds one
            // it opens, and one that was not closed (the twin of a bonded corner, where
            // the other block's corner carried the bond, or one the detector dropped)
            // has none either. Glue keeps its own bonds (below).
            let stale = c.bonded && !c.state.is_closed() && !bond_touching;
            if stale && !(glue && self.joint(k).glued) {
                self.state.contacts.contacts[k].bonded = false;
                continue;
            }
            // A bonded contact the detector left inactive because its vertex passed its
            // edge's end, at the corner of a bonded face as its blocks turn or strain,
            // holds there until the contact law breaks it (as a seam's end does).
            if c.bonded && c.state.is_closed() && !c.active && self.at_seam_end(&c) {
                self.state.contacts.contacts[k].active = true;
                c.active = true;
            }
            // Only closed contacts, and with glue, closing the touching ones or bonding
            // them active ones, need their joint.
            if !(c.state.is_closed() || (glue || close_touching || bond_touching) && c.active) {
                continue;
            }
            let j = self.joint(k);
            if glue && j.glued && (c.active || c.bonded && self.at_seam_end(&c)) {
                // Parts of one body: a contact on the seam (its vertex on the edge's line,
                // within `glue_reach`) is locked and bonded where it is, unloaded,
                // for good; any other contact between them (a vertex across a sliver
                // part) is no contact at all. A seam's end, where the parts' corners
                // meet, stays bonded when its vertex passes the edge's end by rounding
                // or strain, where the detector no longer lists it active.
                let seam = glue_reach(self.detection.d_tol);
                let c = &mut self.state.contacts.contacts[k];
                c.active = true;
                if c.bonded || c.d_n.abs() <= seam {
                    if !c.bonded {
                        c.locked_r = c.r;
                    }
                    c.state = ContactState::Locked;
                    c.bonded = true;
                } else {
                    c.state = ContactState::Open;
                    c.active = false;
                }
                continue;
            }
            // A contact of a bonding joint whose blocks touch at the start (its vertex on
            // the edge's line within `glue_reach`, or past it) is bonded and locked
            // where it is, unloaded: the rock holds across it until its tensile strength
            // or its cohesion and friction give way. A corner against a corner of the
            // type-based detectors has no contact length, and so no bond.
            if bond_touching && c.active && !c.vertex_vertex && j.bonds() && c.d_n <= touch {
                let c = &mut self.state.contacts.contacts[k];
                close_where_it_is(c, &j);
                c.bonded = true;
                continue;
            }
            // Open contacts are left as they are, but for the settling's touching ones.
            if !c.state.is_closed() {
                if close_touching && c.active && c.d_n <= open_band {
                    close_where_it_is(&mut self.state.contacts.contacts[k], &j);
                }
                continue;
            }
            let c = &mut self.state.contacts.contacts[k];
            if !j.has_shear() {
                c.state = ContactState::Sliding;
            }
        }
        self.scratch.track_list.rebuild(
            self.detector.as_ref(),
            &self.scratch.shapes,
            &self.state.contacts,
        );
    }

    /// Whether bonded contact `c`, active at the end of the last step, still holds its
    /// seam (or bonded face) though the detector left it inactive because its vertex
    /// passed its edge's end: the vertex lies within d_tol of the edge's line and past
    /// the end by at most d_tol. Parts of one body meet at the ends of a seam corner to
    /// corner (r = 0 or 1), where rounding and the parts' strain take the vertex past
    /// the edge's end; the seam's spring there must go on, or the parts press into each
    /// other unheld (found on a jointed pit wall under a quake: a sliver part's seam end
    /// went 2.8 mm deep in five steps, and the spring that took it up again created 6%
    /// of the reference energy). A seam contact the detector left inactive for another
    /// reason (the other block's face carries the seam) stays so.
    fn at_seam_end(&self, c: &dda_contact::Contact) -> bool {
        if (0.0..=1.0).contains(&c.r)
            || !self
                .scratch
                .prev
                .find(&c.key)
                .is_some_and(|p| p.active && p.bonded)
        {
            return false;
        }
        let shape = &self.scratch.shapes[c.key.edge_block as usize];
        let e = c.key.edge as usize;
        let length = shape.vertices[e].distance(shape.vertices[shape.next(e)]);
        let d_tol = self.detection.d_tol;
        let slack = d_tol / length;
        c.d_n.abs() <= d_tol && (-slack..=1.0 + slack).contains(&c.r)
    }
}

/// Closes contact `c` of joint `j` where it is: locked, its shear spring anchored at its
/// vertex's place along the edge (unloaded), or sliding where the joint has no shear
/// spring.
fn close_where_it_is(c: &mut dda_contact::Contact, j: &crate::model::JointProps) {
    c.state = if j.has_shear() {
        ContactState::Locked
    } else {
        ContactState::Sliding
    };
    c.locked_r = c.r.clamp(0.0, 1.0);
}
