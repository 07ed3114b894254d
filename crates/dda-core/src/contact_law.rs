//! The contact law: each active contact re-checked against the trial solution of an
//! open-close iteration: open or closed by the normal distance (or a bond's tensile
//! strength), locked or sliding by Mohr-Coulomb.
//!
//! **Decisions of negligible force keep the state** (our choice; the paper decides by
//! signs alone). Every change of state is about a force: the spring force of a contact
//! that would close (p |d|) or the tension a closed one would have to hold (p d), the
//! shear force beyond the friction limit of a locked contact that would slide, the
//! shear spring force a sliding contact would take if it locked. A change is made only
//! when that force exceeds [`DECISION_BAND`] of the contact's force scale: the smaller
//! of its two free blocks' scales, each the larger of the external force on the block
//! (weight and point loads) and the largest normal force its contacts carried at the
//! step's start. Below it the contact keeps its state: a hysteresis band stated in the
//! step's own forces. Where blocks meet along flush joints (T- and X-junctions, the
//! two covers of one corner) contacts sit at d_n = 0 with forces that hover around
//! zero; decided by sign they flip between open and closed, locked and sliding, on
//! forces of 1e-4 of a block's weight and below, and the iteration never ends.
//! `docs/method.md`, section 6, gives the measurements.
//!
//! **A contact that sticks again keeps its friction** (our choice; Shi's code and the
//! paper lock it with an unloaded shear spring). A sliding contact whose motion reverses
//! locks with its shear spring anchored so that it carries the friction force the
//! contact slid against, and unloads from there with the reversal: the force is
//! continuous through the change, as in elastic-plastic Coulomb friction. Locked
//! unloaded, a joint held at its friction limit dropped its force to zero each time it
//! stuck and slid again: the rows of a wall sliding on an incline, whose every bed
//! joint carries exactly its limit, parted by 1% to 3% (docs/method.md, section 13).
//!
//! **Cycles end closed and sliding** (our choice). A contact that changes state more
//! than [`CYCLE_LIMIT`] times in one attempt of a step alternates with others: its
//! decision depends on theirs, and both of its states are consistent with some of them
//! (the two covers of one corner sharing a load, a shear force hovering at the friction
//! limit). From then on, for the rest of the attempt, it may close, or go from locked to
//! sliding, but neither open nor lock again; kept from locking where its motion
//! reversed, it slides the way the locked spring would have pushed at the trial (back,
//! against its new motion, where the reversal's spring force passes the friction
//! force), so that friction never pushes blocks along their slip by more than a spring
//! would; kept from opening, it is decided as a closed contact carrying no normal force
//! (so it slides if sheared beyond the band, or locks if its motion reversed:
//! [`end_cycle`]). Closed never lets blocks pass into each other, and sliding bounds its
//! shear force by friction instead of holding a block that is still moving. The next
//! step decides it afresh. A contact whose sliding direction keeps turning (its turns
//! count as changes past the cycle limit) locks at its reversal once it has changed
//! [`FREEZE_LIMIT`] times, and changes no more in the attempt.

use crate::simulation::Simulation;

/// Fraction of a contact's force scale (see the module docs) below which a change of its
/// state is negligible and not made: a closed contact holds that much tension at most,
/// an open one lets its blocks overlap by that much force over the penalty, a locked one
/// holds that much beyond its friction limit. Our choice, measured in
/// `docs/method.md` (section 6): 1e-4, 1e-3 and 1e-2 all let a running-bond wall and a
/// grid of equal blocks stand; 1e-3 keeps the force error of a decision to a thousandth
/// of the forces on the less loaded of its blocks.
pub(crate) const DECISION_BAND: f64 = 1e-3;
use crate::scene::JointProps;
use crate::springs::{contact_length, contact_points};
use dda_contact::{BlockShape, Contact, ContactState};
use dda_geom::{DVec2, Motion, VertexEdge};

/// Changes of state a contact may make in one attempt of a step before it is taken to
/// cycle: past it, a closed contact stays closed for the rest of the attempt.
pub(crate) const CYCLE_LIMIT: u8 = 2;

/// Changes a contact may make in one attempt of a step (past [`CYCLE_LIMIT`] a sliding
/// contact's turn counts as one) before it keeps its state for the rest of the attempt
/// ([`end_cycle`]). Past [`CYCLE_LIMIT`] a sliding contact kept from locking where its
/// motion reversed slides the way its spring would push, and that turn can recur:
/// traced on a soft jointed layer, the two covers of one corner turned their friction at
/// every iteration of an attempt, 4 N one way and then the other, until the attempt's
/// bound cut dt, step after step. At this many changes its reversal locks it after all,
/// the stick its motion asks for (its spring carrying the friction force it slid
/// against, as [`decide`] anchors it), and from then on it changes no more in the
/// attempt; the next step decides it afresh. Our choice: twice [`CYCLE_LIMIT`], which
/// leaves it the spring's turn past the cycle limit (that keeps friction from pushing a
/// hinge along its slip, docs/method.md section 6). Frozen in its direction instead of
/// locked, the thin arch of `tests/physics/arches.rs` created 1.7% of its reference
/// energy in a step.
pub(crate) const FREEZE_LIMIT: u8 = 2 * CYCLE_LIMIT;

/// Whether `n` counts as a change from `c` for a contact that has changed `flips` times
/// in this attempt: a change of state (open, locked, sliding), and past [`CYCLE_LIMIT`]
/// also a sliding contact's turn (its friction force changes sign).
pub(crate) fn counts_as_change(c: &Contact, n: &Contact, flips: u8) -> bool {
    n.state != c.state
        || (flips >= CYCLE_LIMIT
            && c.state == ContactState::Sliding
            && c.slide_dir != 0.0
            && n.slide_dir != c.slide_dir)
}

/// The constants of the contact law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Law {
    /// Normal penalty p, N/m.
    pub normal_penalty: f64,
    /// Shear penalty, N/m.
    pub shear_penalty: f64,
    /// How far a closed contact's normal distance must be positive for it to open, m.
    pub open_band: f64,
}

/// What the trial solution says of one contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trial {
    /// Normal distance after the trial step, m (negative: penetrating).
    pub d: f64,
    /// The force below which a change of state is negligible, N (see the module docs).
    pub band: f64,
}

/// The contact law for one contact: its state after an open-close iteration whose
/// trial solution gives `trial`, for joint `joint` and law `law`. `shear(anchor)` is the
/// trial's tangential displacement of the vertex from the point at ratio `anchor` along
/// the edge; `trial_ratio()` the vertex's ratio along the edge at the trial positions;
/// `length()` the length a bond's cohesion and tension act over. A pure function: the
/// closures are asked only where the decision needs them.
pub fn decide(
    c: &Contact,
    joint: &JointProps,
    law: &Law,
    trial: Trial,
    shear: impl Fn(f64) -> f64,
    trial_ratio: impl FnOnce() -> f64,
    length: impl Fn() -> f64,
) -> Contact {
    let (pn, ps) = (law.normal_penalty, law.shear_penalty);
    let Trial { d, band } = trial;
    let mut n = *c;
    if joint.glued {
        // Parts of one body: a seam contact (bonded at detection) stays locked whatever
        // the trial says; any other contact between them stays open.
        if c.bonded {
            n.state = ContactState::Locked;
            n.normal_force = -pn * d;
        }
        return n;
    }
    match c.state {
        ContactState::Open => {
            if d < 0.0 && pn * -d > band {
                // Closes where its trajectory crossed the edge's line.
                let r1 = trial_ratio();
                let t = if c.d_n > 0.0 {
                    c.d_n / (c.d_n - d)
                } else {
                    0.0
                };
                n.locked_r = (c.r + t * (r1 - c.r)).clamp(0.0, 1.0);
                n.state = if joint.has_shear() {
                    ContactState::Locked
                } else {
                    ContactState::Sliding
                };
                n.slide_dir = 0.0;
                n.normal_force = -pn * d;
            }
        }
        ContactState::Locked | ContactState::Sliding => {
            let holds_tension = c.bonded
                && joint.tensile_strength > 0.0
                && pn * d <= joint.tensile_strength * length();
            if d > law.open_band && pn * d > band && !holds_tension {
                n.state = ContactState::Open;
                n.bonded = false;
                n.normal_force = 0.0;
            } else {
                n.normal_force = -pn * d;
                if joint.has_shear() {
                    if c.state == ContactState::Locked {
                        let s = shear(c.locked_r);
                        let mut limit = n.normal_force.max(0.0) * joint.tan_phi;
                        if c.bonded {
                            limit += joint.cohesion * length();
                        }
                        if ps * s.abs() > limit + band {
                            n.state = ContactState::Sliding;
                            n.slide_dir = s.signum();
                            n.bonded = false;
                        }
                    } else {
                        let r = c.r.clamp(0.0, 1.0);
                        let s = shear(r);
                        if c.slide_dir == 0.0 {
                            n.slide_dir = s.signum();
                        } else if s * c.slide_dir < 0.0 && ps * s.abs() > band {
                            // The motion reversed against friction: it sticks, its shear
                            // spring anchored behind the point it slid to by the friction
                            // force over the shear penalty, so that the spring takes up
                            // the force the contact slid against and unloads with the
                            // reversal (elastic-plastic Coulomb friction; see the module
                            // docs). shear(a) is linear in a, falling by the edge's
                            // length per unit of a.
                            let length = s - shear(r + 1.0);
                            let limit = c.normal_force.max(0.0) * joint.tan_phi;
                            n.state = ContactState::Locked;
                            // The way it slides if it may not lock (`end_cycle`): the way
                            // its spring would push at the trial, back where the
                            // reversal's own spring force passes the friction force, on
                            // where the spring still pulls along with the reversal.
                            if ps * s.abs() > limit {
                                n.slide_dir = -c.slide_dir;
                            }
                            n.locked_r = if length > 0.0 {
                                r - c.slide_dir * limit / (ps * length)
                            } else {
                                r
                            };
                        }
                    }
                }
            }
        }
    }
    n
}

/// The state of contact `c` decided as `n`, once it has changed state `flips` times in
/// this attempt of a step: past [`CYCLE_LIMIT`] it cycles (see the module docs), and may
/// close or begin to slide, but neither open nor lock again. Kept from locking where its
/// motion reversed, it slides the way its spring would have pushed (see [`decide`]).
/// Kept from opening, it is decided as closed with no normal force (`at_rest`, the
/// decision at d = 0), so that it holds no shear beyond the band; that decision stands,
/// a lock included (our choice;
/// kept sliding there instead, walls of 2 m x 0.5 m bricks on 45/40 parted by 23% to
/// 43% where they held to 0.03%, docs/method.md section 6). At [`FREEZE_LIMIT`] changes
/// a sliding contact's reversal locks it, and past them it keeps its state.
pub fn end_cycle(c: &Contact, n: Contact, flips: u8, at_rest: impl FnOnce() -> Contact) -> Contact {
    if flips > FREEZE_LIMIT {
        // It keeps its state for the rest of the attempt, with its decision's force.
        return Contact {
            normal_force: n.normal_force,
            ..*c
        };
    }
    if flips == FREEZE_LIMIT && c.state == ContactState::Sliding && n.state == ContactState::Locked
    {
        // Its motion reversed once more: it sticks, its spring carrying the friction
        // force it slid against (`decide`), and keeps that state (above).
        return n;
    }
    cycle_ended(c, n, flips, at_rest)
}

/// [`end_cycle`] below [`FREEZE_LIMIT`] changes.
fn cycle_ended(c: &Contact, n: Contact, flips: u8, at_rest: impl FnOnce() -> Contact) -> Contact {
    if n.state == c.state || flips < CYCLE_LIMIT {
        return n;
    }
    if c.state.is_closed() && !n.state.is_closed() {
        return at_rest();
    }
    if c.state == ContactState::Sliding && n.state == ContactState::Locked {
        // It would lock because its motion reversed: it slides on, back where the
        // reversal's spring force passes the friction force (`decide`), so that the
        // friction never pushes the blocks along their slip.
        return Contact {
            normal_force: n.normal_force,
            slide_dir: n.slide_dir,
            ..*c
        };
    }
    n
}

/// The force below which a change of contact `key`'s state is negligible:
/// [`DECISION_BAND`] of the smaller of its two blocks' force scales (`scale`, by block;
/// see the module docs).
pub(crate) fn decision_band(scale: &[f64], key: dda_contact::ContactKey) -> f64 {
    DECISION_BAND * scale[key.vertex_block as usize].min(scale[key.edge_block as usize])
}

impl Simulation {
    /// Sets each block's force scale (see the module docs): for a free block the larger
    /// of the magnitude of its external force (its weight and point loads) and the
    /// largest normal force a closed contact of it carried at the step's start; infinite
    /// for a fixed block. The inertia terms of the time scheme are not forces on the
    /// block: a block moving at constant speed has none.
    pub(crate) fn set_force_scale(&mut self) {
        let g = self.gravity();
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
        // The forces its contacts carry: deep in a mass they are many times a block's
        // weight, and a decision is negligible against them, not against the weight.
        let scale = &mut self.scratch.force_scale;
        for c in &self.state.contacts.contacts {
            if !(c.active && c.state.is_closed()) {
                continue;
            }
            for b in [c.key.vertex_block, c.key.edge_block] {
                let s = &mut scale[b as usize];
                *s = s.max(c.normal_force);
            }
        }
    }

    /// How far a closed contact's vertex must be outside its edge's line for it to open,
    /// m: 1e-9 d_tol. Blocks that touch to rounding (joint faces cut from one rock)
    /// otherwise chatter between open and closed on d of order 1e-17 m and never
    /// converge. The tension held inside the band, p * 1e-9 d_tol, is negligible (our
    /// choice; the paper is silent).
    pub(crate) fn open_band(&self) -> f64 {
        1e-9 * self.model.params.d_tol
    }

    /// Re-checks every active contact against the trial solution; returns how many
    /// changed state. Each contact's decision reads the trial alone, so with many
    /// contacts, on the pool ([`Simulation::threads`]), the two halves of the list are
    /// decided on two threads: the same decisions, listed in the same order.
    pub(crate) fn update_states(&mut self) -> usize {
        let p = &self.model.params;
        let law = Law {
            normal_penalty: p.normal_penalty,
            shear_penalty: p.shear_penalty,
            open_band: self.open_band(),
        };
        #[cfg(feature = "rayon")]
        let threads = self.threads();
        let sc = &mut self.scratch;
        let (rows, shapes, half, d) = (&sc.rows, &sc.shapes, &sc.half, &sc.d);
        let joints = &sc.joints;
        let (sheared, scale, motions) = (&sc.sheared, &sc.force_scale, &sc.motions);
        let sin_e = self.detection.sin_theta_e();
        // Decides the contacts of `contacts` (the list's from `first` on), counting
        // each one's changes of state in `flips` where it has them, and lists in
        // `flipped` the contacts that changed state or sliding direction; returns how
        // many of them are frictionless, and how many opened or closed.
        let run =
            |first: usize, contacts: &mut [Contact], flips: &mut [u8], flipped: &mut Vec<u32>| {
                let mut frictionless = 0;
                let mut opened_or_closed = 0;
                for (i, slot) in contacts.iter_mut().enumerate() {
                    let (k, c) = (first + i, *slot);
                    if !c.active {
                        continue;
                    }
                    let key = c.key;
                    let trial = Trial {
                        d: rows[k].eval(d),
                        // The force below which a change is negligible (see the module
                        // docs).
                        band: decision_band(scale, key),
                    };
                    let joint = joints[k];
                    let decide_at = |trial: Trial| {
                        decide(
                            &c,
                            &joint,
                            &law,
                            trial,
                            |anchor| sheared.row(k, anchor, &c, shapes, half).eval(d),
                            || trial_ratio(&c, shapes, motions),
                            // Only bonds need the length: looked up (a load from the edge
                            // block's shape, often a cache miss) only for them.
                            || contact_length(&c, shapes, sin_e),
                        )
                    };
                    let count = flips.get(i).copied().unwrap_or(0);
                    let n = end_cycle(&c, decide_at(trial), count, || {
                        decide_at(Trial { d: 0.0, ..trial })
                    });
                    if counts_as_change(&c, &n, count)
                        && let Some(f) = flips.get_mut(i)
                    {
                        *f = f.saturating_add(1);
                    }
                    if n.state != c.state || n.slide_dir != c.slide_dir {
                        if !joint.has_shear() {
                            frictionless += 1;
                        }
                        if n.state.is_closed() != c.state.is_closed() {
                            opened_or_closed += 1;
                        }
                        flipped.push(k as u32);
                    }
                    *slot = n;
                }
                [frictionless, opened_or_closed]
            };
        let contacts = &mut self.state.contacts.contacts;
        // The flip counts are kept in the open-close iteration only (not the predictor).
        let flips: &mut [u8] = if sc.flips.len() == contacts.len() {
            &mut sc.flips
        } else {
            &mut []
        };
        let flipped = &mut sc.flipped;
        flipped.clear();
        #[cfg(feature = "rayon")]
        if threads && contacts.len() >= PARALLEL_MIN_CONTACTS {
            let mid = contacts.len() / 2;
            let (c0, c1) = contacts.split_at_mut(mid);
            let (f0, f1) = flips.split_at_mut(mid.min(flips.len()));
            let second = &mut sc.flipped_second;
            second.clear();
            let (a, b) = rayon::join(|| run(0, c0, f0, flipped), || run(mid, c1, f1, second));
            flipped.extend_from_slice(second);
            sc.frictionless_changes = a[0] + b[0];
            sc.opened_or_closed = a[1] + b[1];
            return flipped.len();
        }
        let [frictionless, opened_or_closed] = run(0, contacts, flips, flipped);
        sc.frictionless_changes = frictionless;
        sc.opened_or_closed = opened_or_closed;
        flipped.len()
    }
}

/// Fewest contacts for which the contact law decides the open-close iteration's states
/// on two threads, in two halves of the contact list (where a step's work goes to the
/// pool: [`crate::RunOptions::parallel`], or a system solved iteratively): below it,
/// waking the pool costs more than it saves. Our choice, about the contacts of
/// 4,000 blocks; on the 28,325-block column's first 15 steps the assembly phase (where
/// the decisions are counted) took 1.65-1.73 s against 1.84-1.94 s on one thread, three
/// alternating runs.
pub const PARALLEL_MIN_CONTACTS: usize = 16_384;

/// Projection ratio of contact `c`'s vertex on its edge at the trial positions (`motions`
/// of the blocks whose step-start shapes are `shapes`).
pub(crate) fn trial_ratio(c: &Contact, shapes: &[BlockShape], motions: &[Motion]) -> f64 {
    let (p1, p2, p3) = contact_points(c, shapes);
    let k = c.key;
    let (mv, me) = (
        &motions[k.vertex_block as usize],
        &motions[k.edge_block as usize],
    );
    VertexEdge::new(mv.apply(p1), me.apply(p2), me.apply(p3)).r
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_contact::ContactKey;

    const LAW: Law = Law {
        normal_penalty: 1e10,
        shear_penalty: 4e9,
        open_band: 1e-11,
    };

    fn joint(friction_deg: f64) -> JointProps {
        JointProps {
            tan_phi: friction_deg.to_radians().tan(),
            ..JointProps::default()
        }
    }

    fn contact(state: ContactState) -> Contact {
        let key = ContactKey {
            vertex_block: 0,
            vertex: 0,
            edge_block: 1,
            edge: 0,
        };
        Contact {
            state,
            ..Contact::new(key, 0.0, 0.5, true)
        }
    }

    fn decided(c: &Contact, j: &JointProps, d: f64, band: f64, s: f64) -> Contact {
        decide(c, j, &LAW, Trial { d, band }, |_| s, || 0.5, || 0.5)
    }

    /// An open contact closes (locked, with friction) when it would penetrate with a
    /// force above the band, and stays open below it; a closed one opens when it would
    /// hold a tension above the band, and stays closed below it.
    #[test]
    fn open_and_closed_change_only_beyond_the_band() {
        let j = joint(30.0);
        let band = 100.0; // N: 1e-8 m of the normal penalty
        let open = contact(ContactState::Open);
        assert_eq!(
            decided(&open, &j, -2e-8, band, 0.0).state,
            ContactState::Locked
        );
        assert_eq!(
            decided(&open, &j, -0.5e-8, band, 0.0).state,
            ContactState::Open
        );
        let locked = contact(ContactState::Locked);
        assert_eq!(
            decided(&locked, &j, 2e-8, band, 0.0).state,
            ContactState::Open
        );
        let kept = decided(&locked, &j, 0.5e-8, band, 0.0);
        assert_eq!(kept.state, ContactState::Locked);
        assert_eq!(kept.normal_force, -LAW.normal_penalty * 0.5e-8);
        // Without a band, signs decide (beyond the open band of rounding).
        assert_eq!(
            decided(&open, &j, -1e-15, 0.0, 0.0).state,
            ContactState::Locked
        );
        assert_eq!(
            decided(&locked, &j, 1e-10, 0.0, 0.0).state,
            ContactState::Open
        );
        // A frictionless joint's contact closes sliding.
        assert_eq!(
            decided(&open, &joint(0.0), -2e-8, band, 0.0).state,
            ContactState::Sliding
        );
    }

    /// A locked contact slides when its shear spring's force exceeds the Mohr-Coulomb
    /// limit by more than the band, in the direction of the shear displacement.
    #[test]
    fn locked_contacts_slide_beyond_the_friction_limit_and_the_band() {
        let j = joint(30.0);
        let locked = contact(ContactState::Locked);
        let d = -1e-6; // N = 1e4 N, limit N tan 30 = 5,774 N
        let limit = 1e4 * j.tan_phi;
        let s_at = |f: f64| f / LAW.shear_penalty;
        let slid = decided(&locked, &j, d, 0.0, -s_at(limit * 1.01));
        assert_eq!((slid.state, slid.slide_dir), (ContactState::Sliding, -1.0));
        let band = 0.05 * limit;
        assert_eq!(
            decided(&locked, &j, d, band, s_at(limit * 1.01)).state,
            ContactState::Locked
        );
        assert_eq!(
            decided(&locked, &j, d, band, s_at(limit * 1.1)).state,
            ContactState::Sliding
        );
    }

    /// A sliding contact whose motion reverses against friction locks again, unless the
    /// reversal's spring force is within the band.
    #[test]
    fn sliding_contacts_lock_when_the_motion_reverses() {
        let j = joint(30.0);
        let sliding = Contact {
            slide_dir: 1.0,
            ..contact(ContactState::Sliding)
        };
        assert_eq!(
            decided(&sliding, &j, -1e-6, 0.0, -1e-7).state,
            ContactState::Locked
        );
        assert_eq!(
            decided(&sliding, &j, -1e-6, 1e3, -1e-7).state,
            ContactState::Sliding
        );
        assert_eq!(
            decided(&sliding, &j, -1e-6, 0.0, 1e-7).state,
            ContactState::Sliding
        );
    }

    /// Past the cycle limit a contact may close or begin to slide but neither open nor
    /// lock again: a sliding one that would lock stays sliding, one that would open is
    /// decided at rest (and that decision stands); below the limit every decision stands.
    #[test]
    fn cycles_end_closed_and_sliding() {
        let sliding = Contact {
            slide_dir: 1.0,
            normal_force: 10.0,
            ..contact(ContactState::Sliding)
        };
        let open = contact(ContactState::Open);
        let locked = Contact {
            normal_force: 0.0,
            ..contact(ContactState::Locked)
        };
        assert_eq!(end_cycle(&sliding, open, CYCLE_LIMIT, || locked), locked);
        let kept = end_cycle(&sliding, locked, CYCLE_LIMIT, || open);
        assert_eq!(kept.state, ContactState::Sliding);
        assert_eq!(kept.normal_force, 0.0);
        let at_rest = Contact {
            normal_force: 0.0,
            ..sliding
        };
        assert_eq!(end_cycle(&sliding, open, CYCLE_LIMIT, || at_rest), at_rest);
        assert_eq!(end_cycle(&sliding, open, CYCLE_LIMIT - 1, || locked), open);
        // Closing and beginning to slide stand past the limit.
        assert_eq!(end_cycle(&open, locked, CYCLE_LIMIT, || open), locked);
        let locked_loaded = contact(ContactState::Locked);
        assert_eq!(
            end_cycle(&locked_loaded, sliding, CYCLE_LIMIT, || open),
            sliding
        );
    }

    /// A contact sliding in +1 on a 30-degree joint under 5 kN: its joint, the contact,
    /// its friction limit and the normal distance that carries its normal force.
    fn sliding_at_5kn() -> (JointProps, Contact, f64, f64) {
        let j = joint(30.0);
        let normal_force = 5e3;
        let sliding = Contact {
            slide_dir: 1.0,
            normal_force,
            ..contact(ContactState::Sliding)
        };
        let d = -normal_force / LAW.normal_penalty;
        (j, sliding, normal_force * j.tan_phi, d)
    }

    /// A sliding contact whose motion reverses, kept from locking past the cycle limit,
    /// slides the way its spring would push at the trial had it locked: back, its
    /// friction against the motion it now has, where the reversal's own spring force
    /// p_s |s| passes the friction force N tan(phi); on as before where it does not (the
    /// friction then pushes along the reversal by at most p_s |s| more than the spring
    /// would: work below (N tan(phi))^2 / p_s). Kept sliding as before whatever the
    /// reversal, a collapsing arch's hinges slipped 0.44 mm a step with their friction
    /// pushing along and created 12% of the reference energy in one step.
    #[test]
    fn a_contact_kept_from_locking_slides_against_its_motion() {
        let (j, sliding, limit, d) = sliding_at_5kn();
        let ended = |s: f64| {
            let n = decided(&sliding, &j, d, 1.0, s);
            assert_eq!(n.state, ContactState::Locked, "reversal {s}");
            end_cycle(&sliding, n, CYCLE_LIMIT, || sliding)
        };
        let strong = ended(-3.0 * limit / LAW.shear_penalty);
        assert_eq!(
            (strong.state, strong.slide_dir),
            (ContactState::Sliding, -1.0)
        );
        let weak = ended(-0.5 * limit / LAW.shear_penalty);
        assert_eq!((weak.state, weak.slide_dir), (ContactState::Sliding, 1.0));
        // Below the cycle limit it locks, either way.
        let n = decided(&sliding, &j, d, 1.0, -3.0 * limit / LAW.shear_penalty);
        assert_eq!(
            end_cycle(&sliding, n, CYCLE_LIMIT - 1, || sliding).state,
            ContactState::Locked
        );
    }

    /// A sliding contact turns the way its spring would push past the cycle limit, and
    /// each such turn counts as a change; at the freeze limit a reversal locks it, as
    /// below the cycle limit; past it no decision changes its state or direction, only
    /// its normal force follows the trial.
    #[test]
    fn a_contact_that_keeps_turning_sticks_and_stays() {
        let (j, sliding, limit, d) = sliding_at_5kn();
        let reversal = decided(&sliding, &j, d, 1.0, -3.0 * limit / LAW.shear_penalty);
        assert_eq!(reversal.state, ContactState::Locked);
        // Between the limits it turns, and the turn counts.
        for flips in CYCLE_LIMIT..FREEZE_LIMIT {
            let turned = end_cycle(&sliding, reversal, flips, || sliding);
            assert_eq!(
                (turned.state, turned.slide_dir),
                (ContactState::Sliding, -1.0)
            );
            assert!(counts_as_change(&sliding, &turned, flips));
            assert!(!counts_as_change(&sliding, &turned, CYCLE_LIMIT - 1));
        }
        // At the freeze limit the reversal stands: it locks.
        assert_eq!(
            end_cycle(&sliding, reversal, FREEZE_LIMIT, || sliding),
            reversal
        );
        // Past it nothing changes but the normal force.
        let open = contact(ContactState::Open);
        for n in [
            reversal,
            open,
            Contact {
                slide_dir: -1.0,
                ..sliding
            },
        ] {
            let kept = end_cycle(&sliding, n, FREEZE_LIMIT + 1, || open);
            assert_eq!(
                kept,
                Contact {
                    normal_force: n.normal_force,
                    ..sliding
                }
            );
        }
        let locked = contact(ContactState::Locked);
        let kept = end_cycle(&locked, sliding, FREEZE_LIMIT + 1, || open);
        assert_eq!(
            (kept.state, kept.slide_dir),
            (locked.state, locked.slide_dir)
        );
    }

    /// A contact that sticks again keeps its friction: locked after sliding in +1 against
    /// the friction force f = N tan(phi), its shear spring at the trial carries -f (the
    /// friction's direction) less the reversal's own spring force, where locked at its
    /// projection it would carry the reversal's force alone.
    #[test]
    fn a_contact_that_sticks_again_carries_its_friction() {
        let (j, sliding, friction, d) = sliding_at_5kn();
        // The trial's tangential displacement from the point at ratio a along an edge of
        // length 2 m, the vertex at ratio 0.5 having moved back by 1e-8 m.
        let (length, back) = (2.0, -1e-8);
        let shear = |a: f64| back - (a - 0.5) * length;
        let locked = decide(
            &sliding,
            &j,
            &LAW,
            Trial { d, band: 0.0 },
            shear,
            || 0.5,
            || 1.0,
        );
        assert_eq!(locked.state, ContactState::Locked);
        let force = -LAW.shear_penalty * shear(locked.locked_r);
        let expected = -friction - LAW.shear_penalty * back;
        assert!(
            (force - expected).abs() < 1e-9 * friction,
            "spring force {force} N, friction {friction} N"
        );
    }

    /// A block's force scale is the larger of its weight and the largest normal force a
    /// closed contact of it carries: the bottom block of a stack of ten carries the
    /// weight of all ten on its base, at most four contacts (two corners, a cover from
    /// each block at each), so one of them carries more than twice its own weight, and
    /// its band is a thousandth of that; the top block's contacts carry its weight alone.
    #[test]
    fn a_block_deep_in_a_stack_scales_its_band_by_the_forces_it_carries() {
        use crate::scene::{Format, Scene};
        let mut text = String::from(
            "name = \"stack\"\n[analysis]\nduration = 0.01\ntime_step = 0.001\n\
             max_displacement = 0.001\nnormal_penalty = 1e10\ngravity = [0.0, -9.81]\n\
             [materials.rock]\ndensity = 2500.0\nyoung = 1e10\npoisson = 0.25\n\
             [joints.default]\nfriction_deg = 30.0\n\
             [[blocks]]\nid = \"ground\"\nmaterial = \"rock\"\nfixed = true\n\
             vertices = [[-2.0, -1.0], [3.0, -1.0], [3.0, 0.0], [-2.0, 0.0]]\n",
        );
        for k in 0..10 {
            let (y0, y1) = (k as f64, k as f64 + 1.0);
            text += &format!(
                "[[blocks]]\nid = \"b{k}\"\nmaterial = \"rock\"\n\
                 vertices = [[0.0, {y0}], [1.0, {y0}], [1.0, {y1}], [0.0, {y1}]]\n"
            );
        }
        let (_, model) = Scene::parse(&text, Format::Toml, "stack.toml").unwrap();
        let mut sim = Simulation::new(model, crate::RunOptions::default());
        sim.step().unwrap();
        sim.set_force_scale();
        let weight = 2500.0 * 9.81;
        // The largest normal force of a closed contact of block i, read from the contacts.
        let carried = |i: u32| {
            sim.contacts()
                .contacts
                .iter()
                .filter(|c| c.active && c.state.is_closed())
                .filter(|c| c.key.vertex_block == i || c.key.edge_block == i)
                .map(|c| c.normal_force)
                .fold(0.0, f64::max)
        };
        let (bottom, top) = (1, 10);
        let scale = &sim.scratch.force_scale;
        assert!(carried(bottom) > 2.0 * weight, "{} N", carried(bottom));
        assert_eq!(scale[bottom as usize], carried(bottom));
        assert!(
            carried(top) <= weight * (1.0 + DECISION_BAND),
            "{} N",
            carried(top)
        );
        let own = scale[top as usize];
        assert!(
            (own - weight).abs() <= weight * DECISION_BAND,
            "{own} N, weight {weight} N"
        );
        assert_eq!(scale[0], f64::INFINITY);
    }
}
