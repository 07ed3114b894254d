//! The cover-based contact detector, CB-CD (Zhuang, Zheng et al. 2021, section 2).
//!
//! For a neighbour pair (A, B) the vertex-edge loop (a_i ~ b_j b_j+1) and the edge-vertex
//! loop (a_i a_i+1 ~ b_j) keep the pairs that pass the entrance filter (eq. 5-6) and the
//! distance filter (eq. 7-10): the contact cover list C^L, a local part of the boundary of
//! the entrance block E(A, B). At step start the covers attaining
//! d_RE2 = max over C^L of d_n (eq. 11) with r in [0, 1] are active. During open-close
//! iteration a cover the vertex enters through becomes active (trajectory tracking,
//! eq. 12-13).
//!
//! Choices where the paper is silent:
//! - Quasi-parallel edges (paper fig. 7B): a cover with r in [0, 1] whose entrance-block
//!   face is parallel, within theta_e, to the face of a cover attaining d_RE2 is active
//!   too. Such covers lie on (nearly) the same face of E, so two edges in contact give two
//!   active covers, one per end, as a face-to-face contact needs. Covers of C^L are all
//!   within d_tol already, so no further distance bound is applied.
//! - d_RE2 is the maximum of d_n over the covers of C^L that are faces of the entrance
//!   block (both edges at the vertex point outward of the edge: the entrance filter with
//!   zero angle tolerance), not over all of C^L. With theta_e > 0 a vertex next to the true
//!   support vertex also passes the filter when its edges are within theta_e of parallel;
//!   its cover is a translate of a face of E lying inside E, and its d_n is too large.
//!   On a smooth polygon (turning angles below theta_e) such a cover can exceed the true
//!   maximum, flip the sign of d_RE2 and leave two overlapping blocks with no active cover
//!   (found by the property tests). Restricting the maximum to faces makes d_RE2 the
//!   separating distance of the paper's intent; the other covers stay in C^L, can be
//!   active as quasi-parallel companions and can be activated by trajectory tracking.
//!   If no face of E is in C^L the maximum is taken over all of C^L.
//! - "Attaining d_RE2" is d_n >= d_RE2 - 1e-9 d_tol, so that rounding does not split ties
//!   ([`ROUNDING`]).
//! - Only vertices inside the other block's box grown by d_tol are looped over: a vertex
//!   outside it cannot pass the distance filter, so the result is the same, only cheaper,
//!   and the cost stays flat as d_tol grows.
//! - The distance filter runs before the entrance filter (both must pass; the cheaper
//!   rejection first).
//! - Penetrations deeper than d_tol, which a penalty too soft for d_tol allows (the paper
//!   assumes they do not occur, section 2.6), keep pushing the blocks apart rather than
//!   let them pass through each other, where the distance filter (eq. 10) would drop
//!   the covers that matter. For a pair in closed contact at the end of the last step:
//!   if it now overlaps deeper than d_tol, its active covers are the faces of the
//!   entrance block attaining d_RE2 without the distance filter, whose d_n is minus the
//!   overlap (see [`deep_covers`]), and during the open-close iteration the spring
//!   follows the face that is deepest at the trial positions ([`follow_deepest`]);
//!   otherwise a cover closed then stays active while its vertex is behind its edge's
//!   line, moved to the adjacent edge when the vertex slides past an end of its edge
//!   and that edge's line is nearer; a cover the detector lists but does not choose
//!   stays only where it chose no other (or the cover carries a bond), so that a vertex
//!   behind two faces keeps the spring of its shortest exit (eq. 11). Found by the
//!   hard-pair property tests: a 3 deg wedge at 1 m/s with p = 1e6 and d_tol = 1.2 mm
//!   went through a 15 deg wedge; a chamfered square's corner slid 13 mm deep past the
//!   end of the edge it entered and went through; a spinning wedge's tip swept into the
//!   block its edge was pressed against. The type-based detectors keep the paper's
//!   behaviour.

use crate::contact::{Contact, ContactKey, ContactSet};
use crate::detector::{ContactDetector, DetectionParams};
use crate::neighbour::NeighbourPair;
use crate::shape::BlockShape;
use crate::tracking;
use dda_geom::{DVec2, Motion, VertexEdge};

/// The cover-based detector, CB-CD.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CoverDetector;

/// Appends the covers of vertices of `vs` (block `vb`) against edges of `es` (block `eb`)
/// that pass the distance filter (eq. 7-10) and the entrance filter (eq. 5-6).
#[inline]
pub(crate) fn vertex_edge_loop(
    vs: &BlockShape,
    vb: u32,
    es: &BlockShape,
    eb: u32,
    params: &DetectionParams,
    out: &mut Vec<Contact>,
) {
    let tol = params.d_tol;
    let tol2 = tol * tol;
    let sin_e = params.sin_theta_e();
    for (i, a) in vs.vertices_near(es, tol) {
        let (e_prev, e_next) = vs.vertex_edges(i);
        for j in 0..es.len() {
            let b0 = es.vertices[j];
            let t = es.tangents[j];
            let w = a - b0;
            let d_n = w.x * t.y - w.y * t.x; // eq. 7 with n = (t.y, -t.x)
            if d_n.abs() > tol {
                continue;
            }
            let along = w.dot(t);
            let len = es.lengths[j];
            // Eq. 10: the band (10a), else the disk about the nearer node (10b, 10c).
            let in_region = if along < 0.0 {
                w.length_squared() <= tol2
            } else if along > len {
                (a - es.vertices[es.next(j)]).length_squared() <= tol2
            } else {
                true
            };
            if !in_region {
                continue;
            }
            let n = DVec2::new(t.y, -t.x);
            if !dda_geom::entrance_filter(e_prev, e_next, n, sin_e) {
                continue;
            }
            out.push(Contact::new(
                ContactKey {
                    vertex_block: vb,
                    vertex: i as u32,
                    edge_block: eb,
                    edge: j as u32,
                },
                d_n,
                along / len,
                false,
            ));
        }
    }
}

/// Direction of a cover's entrance-block face, oriented as on E(A, B) for the pair `ids`:
/// an edge of B keeps its direction, an edge of A is reversed (it belongs to -A).
#[inline]
pub(crate) fn face_direction(
    c: &Contact,
    ids: NeighbourPair,
    a: &BlockShape,
    b: &BlockShape,
) -> DVec2 {
    if c.key.edge_block == ids.b {
        b.tangents[c.key.edge as usize]
    } else {
        -a.tangents[c.key.edge as usize]
    }
}

/// Whether a cover is a face of the entrance block: both edges at its vertex point
/// outward of its edge (the entrance filter with zero angle tolerance).
#[inline]
fn is_face(c: &Contact, ids: NeighbourPair, a: &BlockShape, b: &BlockShape) -> bool {
    let (vs, es) = if c.key.vertex_block == ids.a {
        (a, b)
    } else {
        (b, a)
    };
    let (e_prev, e_next) = vs.vertex_edges(c.key.vertex as usize);
    let n = es.normal(c.key.edge as usize);
    e_prev.dot(n) >= 0.0 && e_next.dot(n) >= 0.0
}

/// d_RE2 of a cover list (eq. 11, over the covers that are faces of E; see the module
/// docs), or `None` for an empty list.
pub(crate) fn d_re2(
    covers: &[Contact],
    ids: NeighbourPair,
    a: &BlockShape,
    b: &BlockShape,
) -> Option<f64> {
    let max = |it: &mut dyn Iterator<Item = f64>| {
        it.fold(None, |m: Option<f64>, x| Some(m.map_or(x, |m| m.max(x))))
    };
    max(&mut covers
        .iter()
        .filter(|c| is_face(c, ids, a, b))
        .map(|c| c.d_n))
    .or_else(|| max(&mut covers.iter().map(|c| c.d_n)))
}

/// The rounding of detection, as a fraction of d_tol: two covers whose d_n differ by
/// less attain d_RE2 alike, and a cover kept closed on the face the detector chose may lie
/// that far past its edge's end (`keep_closed` in the detector module). Our choice: far
/// below any overlap a penalty leaves, far above the rounding of coordinates (2e-15 of an
/// edge was seen).
pub(crate) const ROUNDING: f64 = 1e-9;

/// Marks active the covers attaining d_RE2 (eq. 11) with r in [0, 1], and their
/// quasi-parallel companions (see the module docs). Returns d_RE2.
pub(crate) fn choose_active(
    covers: &mut [Contact],
    ids: NeighbourPair,
    a: &BlockShape,
    b: &BlockShape,
    params: &DetectionParams,
) -> Option<f64> {
    let d_re2 = d_re2(covers, ids, a, b)?;
    let tie = d_re2 - ROUNDING * params.d_tol;
    let any_face = covers.iter().any(|c| is_face(c, ids, a, b));
    let sin_e = params.sin_theta_e();
    for k in 0..covers.len() {
        let c = covers[k];
        if !(0.0..=1.0).contains(&c.r) {
            continue;
        }
        let dk = face_direction(&c, ids, a, b);
        let active = covers.iter().any(|m| {
            m.d_n >= tie
                && (!any_face || is_face(m, ids, a, b))
                && crate::detector::quasi_parallel(dk, face_direction(m, ids, a, b), sin_e)
        });
        covers[k].active = active;
    }
    Some(d_re2)
}

/// Whether convex blocks `a` and `b` overlap deeper than `d`: every edge of each has a
/// vertex of the other more than `d` behind its line (the separating-axis test, each edge
/// stopping at the first such vertex).
fn overlap_deeper(a: &BlockShape, b: &BlockShape, d: f64) -> bool {
    [(a, b), (b, a)].iter().all(|(vs, es)| {
        (0..es.len()).all(|j| {
            let (b0, t) = (es.vertices[j], es.tangents[j]);
            vs.vertices.iter().any(|&v| {
                let w = v - b0;
                w.x * t.y - w.y * t.x < -d
            })
        })
    })
}

/// The covers of a pair of blocks that were in closed contact at the end of the previous
/// step and now overlap deeper than d_tol, where the distance filter (eq. 10) would drop
/// the covers that matter: the pair's candidates (`list[start..]`) take their activity
/// from the whole cover list without the distance filter, whose active covers are added,
/// and so are its covers within d_tol of their edge's line, inactive, which may become
/// the deepest face during the step ([`follow_deepest`]). Returns false, changing
/// nothing, if the overlap is not deeper than d_tol.
///
/// Our choice (the paper assumes penetrations below d_tol, section 2.6, which a penalty
/// too soft for d_tol breaks). The active covers are then faces of the entrance block
/// attaining d_RE2 (eq. 11) over the whole list, whose d_n is minus the overlap (the
/// least translation that separates the blocks): the face rule of eq. 11 without the
/// distance filter, and without quasi-parallel companions. A spring on such a face
/// measures the overlap itself, a continuous function of the positions (where the
/// deepest face changes, the two faces' d_n are equal), so the springs store p d^2 / 2 of
/// the overlap d and the energy bounds it. No spring starts this deep beside those
/// closed at the end of the previous step (`before`): one would store energy from nowhere
/// (found by the tests: a plate's end turning parallel to the face it was pressed 19 mm
/// into gained a second spring and 30% of the energy). Keeping the contacts closed last
/// step instead (found by the hard-pair property tests) left a spinning wedge's tip to
/// sweep into the block its edge was pressed against, with no candidate listed for the
/// tip.
pub(crate) fn deep_covers(
    a: &BlockShape,
    b: &BlockShape,
    ids: NeighbourPair,
    params: &DetectionParams,
    before: &[Contact],
    start: usize,
    list: &mut Vec<Contact>,
) -> bool {
    if !overlap_deeper(a, b, params.d_tol) {
        return false;
    }
    let mut all = Vec::new();
    let unfiltered = params.with_d_tol(f64::INFINITY);
    vertex_edge_loop(a, ids.a, b, ids.b, &unfiltered, &mut all);
    vertex_edge_loop(b, ids.b, a, ids.a, &unfiltered, &mut all);
    let Some(d_re2) = d_re2(&all, ids, a, b) else {
        return false;
    };
    // Only faces attaining d_RE2 carry springs this deep: those closed at the end of the
    // last step, or else one of them (the first in key order), which takes over from the
    // last deepest face at the d_n it had. A spring joining beside them would start this
    // deep and store energy from nowhere (a plate's end turning parallel to the face it
    // is pressed into brings its second vertex in at the first one's depth).
    let tie = d_re2 - ROUNDING * params.d_tol;
    let attains = |m: &Contact| m.d_n >= tie && is_face(m, ids, a, b) && (0.0..=1.0).contains(&m.r);
    for m in all.iter_mut() {
        let closed = before
            .iter()
            .any(|o| o.key == m.key && o.active && o.state.is_closed());
        m.active = closed && attains(m);
    }
    if !all.iter().any(|m| m.active)
        && let Some(m) = all.iter_mut().filter(|m| attains(m)).min_by_key(|m| m.key)
    {
        m.active = true;
    }
    for c in list[start..].iter_mut() {
        c.active = all.iter().any(|m| m.active && m.key == c.key);
    }
    // Listed too, inactive: the covers that may become the deepest face during the step
    // (see [`follow_deepest`]); a vertex more than d_tol outside an edge's line cannot.
    for m in all.iter().filter(|m| m.active || m.d_n < params.d_tol) {
        if !list[start..].iter().any(|c| c.key == m.key) {
            list.push(*m);
        }
    }
    true
}

/// Open-close iteration of the deep pairs of [`deep_covers`]: the spring follows the
/// entrance block's face that attains d_RE2 at the trial positions (block i moved by
/// `trial[i]`). Where the face closed in a deep pair no longer attains it in the trial,
/// the contact moves to the attaining face (the first by key; with its trial r in
/// [0, 1]) with the same state, and the OCI goes on. Returns how many pairs moved, and
/// appends the contacts they moved to to `activated`.
///
/// Our choice, completing the deep rule: the spring measures the overlap, p d^2 / 2, only
/// if it sits on the face that is deepest where the step ends. Left on the face deepest at
/// step start while a turning block brings another vertex deeper (a wedge's base rocking
/// on a plate), the step ends with more overlap than its spring saw, and the difference,
/// p d Delta per switch, came back as kinetic energy: 14% of it in the hard-pair sample
/// that found it. Contacts open at step start (d_n > 0) are left to trajectory tracking.
pub(crate) fn follow_deepest(
    shapes: &[BlockShape],
    trial: &[Motion],
    set: &mut ContactSet,
    activated: &mut Vec<u32>,
) -> usize {
    let mut moved = 0;
    for pk in 0..set.pairs.len() {
        let pc = set.pairs[pk];
        if !pc.deep {
            continue;
        }
        let range = pc.start as usize..pc.end as usize;
        // The trial measure of each candidate, and whether it is a face of the entrance
        // block there (`is_face` at the trial positions).
        let measure = |c: &Contact| {
            let (a, b0, b1) = crate::detector::trial_points(shapes, trial, c.key);
            let (vs, mv) = (
                &shapes[c.key.vertex_block as usize],
                &trial[c.key.vertex_block as usize],
            );
            let i = c.key.vertex as usize;
            let e = b1 - b0;
            let n = DVec2::new(e.y, -e.x);
            let face = (mv.apply(vs.vertices[vs.prev(i)]) - a).dot(n) >= 0.0
                && (mv.apply(vs.vertices[vs.next(i)]) - a).dot(n) >= 0.0;
            (VertexEdge::new(a, b0, b1), face)
        };
        let mut d_re2 = f64::NEG_INFINITY;
        for c in &set.contacts[range.clone()] {
            let (m, face) = measure(c);
            if face {
                d_re2 = d_re2.max(m.d_n);
            }
        }
        // Separated in the trial (the springs open by themselves), or no face listed.
        if d_re2 >= 0.0 || d_re2 == f64::NEG_INFINITY {
            continue;
        }
        let tie = d_re2 - 1e-9 * d_re2.abs();
        let attains = |c: &Contact| {
            let (m, face) = measure(c);
            face && m.d_n >= tie && (0.0..=1.0).contains(&m.r)
        };
        let held = |c: &Contact| c.active && c.state.is_closed() && c.d_n <= 0.0;
        let contacts = &mut set.contacts[range];
        let Some(old) = contacts.iter().find(|c| held(c)).copied() else {
            continue;
        };
        if contacts.iter().any(|c| held(c) && attains(c)) {
            continue;
        }
        // Moves only to a face less deep at step start than the one left (ties by key):
        // every move goes up that order, so the iteration cannot cycle between two
        // vertices of a face turning through parallel, where each spring tips the other
        // vertex deeper; it stays on the last one, which started less deep.
        let later = |c: &Contact| (c.d_n, c.key) > (old.d_n, old.key);
        let Some(new) = contacts.iter().position(|c| later(c) && attains(c)) else {
            continue;
        };
        for c in contacts.iter_mut().filter(|c| held(c)) {
            c.active = false;
        }
        activated.push((pc.start as usize + new) as u32);
        let r = measure(&contacts[new]).0.r;
        let c = &mut contacts[new];
        c.active = true;
        c.state = old.state;
        c.locked_r = r.clamp(0.0, 1.0);
        c.slide_dir = 0.0;
        c.normal_force = old.normal_force;
        moved += 1;
    }
    moved
}

impl CoverDetector {
    /// The contact cover list C^L of the pair `ids` (vertex-edge loop, then edge-vertex
    /// loop), appended to `out` with initial activity; returns d_RE2 (eq. 11), or `None`
    /// when C^L is empty.
    pub fn cover_list(
        &self,
        a: &BlockShape,
        b: &BlockShape,
        ids: NeighbourPair,
        params: &DetectionParams,
        out: &mut Vec<Contact>,
    ) -> Option<f64> {
        let start = out.len();
        vertex_edge_loop(a, ids.a, b, ids.b, params, out);
        vertex_edge_loop(b, ids.b, a, ids.a, params, out);
        choose_active(&mut out[start..], ids, a, b, params)
    }
}

impl ContactDetector for CoverDetector {
    fn name(&self) -> &str {
        "cover"
    }

    fn detect_pair(
        &self,
        a: &BlockShape,
        b: &BlockShape,
        ids: NeighbourPair,
        params: &DetectionParams,
        out: &mut Vec<Contact>,
    ) {
        self.cover_list(a, b, ids, params, out);
    }

    fn tracks_trajectories(&self) -> bool {
        true
    }

    fn activates(&self, start: VertexEdge, trial: VertexEdge) -> bool {
        tracking::enters_through(start, trial)
    }

    fn keeps_closed_contacts(&self) -> bool {
        true
    }

    fn keeps_corners(&self) -> bool {
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::ContactSet;
    use crate::detector::track;

    use crate::test_util::{IDS, pair_set, shape, tuple};

    fn params() -> DetectionParams {
        DetectionParams::new(0.1, 2f64.to_radians())
    }

    fn keys(cs: &[Contact], active: bool) -> Vec<(u32, u32, u32, u32)> {
        cs.iter()
            .filter(|c| c.active == active)
            .map(|c| tuple(c.key))
            .collect()
    }

    #[test]
    fn flat_block_on_a_wider_one_has_two_active_covers() {
        // A (block 0) rests 0.01 above B's top edge (edge 2 of B, from (3,1) to (0,1)).
        let a = shape(&[[1.0, 1.01], [2.0, 1.01], [2.0, 2.0], [1.0, 2.0]]);
        let b = shape(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let mut out = Vec::new();
        let d = CoverDetector.cover_list(&a, &b, IDS, &params(), &mut out);
        assert!((d.expect("covers") - 0.01).abs() < 1e-12);
        // Both bottom vertices of A against B's top edge: the quasi-parallel case.
        assert_eq!(keys(&out, true), vec![(0, 0, 1, 2), (0, 1, 1, 2)]);
        assert!(out.iter().all(|c| c.state == crate::ContactState::Open));
    }

    #[test]
    fn tilted_block_keeps_both_ends_within_theta_e() {
        // A's bottom edge tilted 1 degree (< theta_e = 4 degrees): still two active covers.
        let t = 1f64.to_radians().tan();
        let a = shape(&[[1.0, 1.01], [2.0, 1.01 + t], [2.0, 2.0], [1.0, 2.0]]);
        let b = shape(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let mut out = Vec::new();
        let d = CoverDetector.cover_list(&a, &b, IDS, &params(), &mut out);
        // d_RE2 is the gap at the lower vertex, a face of E (not the raised vertex's).
        assert!((d.expect("covers") - 0.01).abs() < 1e-12);
        assert_eq!(keys(&out, true), vec![(0, 0, 1, 2), (0, 1, 1, 2)]);
        // Tilted 10 degrees: the raised vertex fails the entrance filter.
        let t = 10f64.to_radians().tan();
        let a = shape(&[[1.0, 1.01], [2.0, 1.01 + t], [2.0, 2.0], [1.0, 2.0]]);
        let mut out = Vec::new();
        CoverDetector.cover_list(&a, &b, IDS, &params(), &mut out);
        assert_eq!(keys(&out, true), vec![(0, 0, 1, 2)]);
    }

    #[test]
    fn penetrating_vertex_exits_the_shortest_way() {
        // A's apex 0.05 into B's top edge, near its left end: the shortest exit is up
        // through the top edge, not sideways through the left edge (0.2 away).
        let a = shape(&[[0.2, 0.95], [0.7, 1.5], [-0.3, 1.5]]);
        let b = shape(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let mut out = Vec::new();
        let d = CoverDetector.cover_list(&a, &b, IDS, &params(), &mut out);
        assert!((d.expect("covers") + 0.05).abs() < 1e-12);
        assert_eq!(keys(&out, true), vec![(0, 0, 1, 2)]);
        let c = out.iter().find(|c| c.active).expect("active");
        assert_eq!(c.state, crate::ContactState::Locked);
    }

    /// Step-start detection of the pair `IDS` of `shapes` after the contacts `previous`.
    fn detect_pair_set(shapes: &[BlockShape], previous: &ContactSet) -> ContactSet {
        let mut set = ContactSet::default();
        crate::detect(
            &CoverDetector,
            shapes,
            &[IDS],
            &params(),
            previous,
            false,
            &mut set,
        );
        set
    }

    #[test]
    fn a_deep_overlap_pushes_along_the_least_separating_translation() {
        // A's corner (0.85, 0.8) entered B's top edge (edge 2) and closed there; it is now
        // 0.2 below that edge and 0.15 inside B's right edge (edge 1), deeper than
        // d_tol = 0.1 both ways. The least translation that separates the blocks is 0.15
        // to the right: the face of A's corner against B's right edge carries the spring,
        // not the 0.2 of the edge it entered (which the distance filter no longer lists).
        let a = shape(&[[0.85, 0.8], [1.85, 0.8], [1.85, 1.8], [0.85, 1.8]]);
        let b = shape(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let shapes = [a, b];
        let closed = |edge: u32| {
            let mut c = Contact::new(
                ContactKey {
                    vertex_block: 0,
                    vertex: 0,
                    edge_block: 1,
                    edge,
                },
                -0.2,
                0.85,
                true,
            );
            c.state = crate::ContactState::Sliding;
            c
        };
        let detect_after = |before: Vec<Contact>| detect_pair_set(&shapes, &pair_set(before));
        let set = detect_after(vec![closed(2)]);
        let active: Vec<_> = set.active().map(|c| (tuple(c.key), c.d_n)).collect();
        assert_eq!(active.len(), 1, "{active:?}");
        assert_eq!(active[0].0, (0, 0, 1, 1));
        assert!((active[0].1 + 0.15).abs() < 1e-12);
        // Already closed on that face, it stays the only spring: B's corner (1, 1) against
        // A's left edge attains the same d_n but would start a second spring this deep.
        let set = detect_after(vec![closed(1)]);
        let active: Vec<_> = set.active().map(|c| tuple(c.key)).collect();
        assert_eq!(active, vec![(0, 0, 1, 1)]);
        // Not closed last step (a pair that was apart): no deep rule, nothing listed.
        let mut apart = closed(2);
        apart.state = crate::ContactState::Open;
        assert_eq!(detect_after(vec![apart]).active().count(), 0);
    }

    #[test]
    fn a_deep_spring_follows_the_vertex_that_turns_deepest() {
        // A's base, tilted 0.02 over its 1 m, was closed 0.2 deep in B's top edge (edge 2)
        // at its lower vertex 0; d_tol = 0.1, so the pair is deep and that vertex's face
        // carries the only spring.
        let a = shape(&[[1.0, 0.8], [2.0, 0.82], [2.0, 1.8], [1.0, 1.8]]);
        let b = shape(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let shapes = [a, b];
        let key = |vertex| ContactKey {
            vertex_block: 0,
            vertex,
            edge_block: 1,
            edge: 2,
        };
        let mut closed = Contact::new(key(0), -0.2, 2.0 / 3.0, true);
        closed.state = crate::ContactState::Sliding;
        let previous = pair_set(vec![closed]);
        let set = detect_pair_set(&shapes, &previous);
        assert!(set.pairs[0].deep);
        assert_eq!(keys(&set.contacts, true), vec![tuple(key(0))]);
        let turn = |phi: f64| {
            [
                dda_geom::Motion::new(shapes[0].centroid, &[0.0, 0.0, phi, 0.0, 0.0, 0.0]),
                dda_geom::Motion::new(shapes[1].centroid, &[0.0; 6]),
            ]
        };
        // Turned 0.04 rad clockwise, vertex 1 ends 0.02 lower than vertex 0: the spring
        // moves to it, sliding as before, and the iteration must go on.
        let mut moved = set.clone();
        assert_eq!(track(&CoverDetector, &shapes, &turn(-0.04), &mut moved), 1);
        assert_eq!(keys(&moved.contacts, true), vec![tuple(key(1))]);
        let now = moved.find(&key(1)).expect("listed");
        assert_eq!(now.state, crate::ContactState::Sliding);
        // Turned back, vertex 0 is deepest again, but it started deeper than vertex 1:
        // no move back, so the iteration cannot cycle.
        let mut back = moved.clone();
        assert_eq!(track(&CoverDetector, &shapes, &turn(0.04), &mut back), 0);
        assert_eq!(keys(&back.contacts, true), vec![tuple(key(1))]);
        // Without the turn, vertex 0 stays deepest: nothing moves.
        let mut still = set.clone();
        assert_eq!(track(&CoverDetector, &shapes, &turn(0.0), &mut still), 0);
        // Lifted clear of B in the trial: the springs open by themselves, nothing moves.
        let lift = [
            dda_geom::Motion::new(shapes[0].centroid, &[0.0, 0.5, -0.04, 0.0, 0.0, 0.0]),
            dda_geom::Motion::new(shapes[1].centroid, &[0.0; 6]),
        ];
        let mut lifted = set.clone();
        assert_eq!(track(&CoverDetector, &shapes, &lift, &mut lifted), 0);
    }

    #[test]
    fn corner_to_corner_is_decided_by_the_trajectory() {
        // A's lower-right corner (1, 1.05) approaches B's upper-left corner (1.05, 1)
        // diagonally; no cover has r in [0, 1] at step start, so none is active.
        let a = shape(&[[0.0, 1.05], [1.0, 1.05], [1.0, 2.05], [0.0, 2.05]]);
        let b = shape(&[[1.05, 0.0], [2.05, 0.0], [2.05, 1.0], [1.05, 1.0]]);
        let shapes = [a, b];
        let set = detect_pair_set(&shapes, &ContactSet::default());
        assert!(!set.is_empty());
        assert_eq!(set.active().count(), 0);
        // A moves by (0.12, -0.08), B fixed: A's corner crosses the line of B's top edge
        // (edge 2) at x = 1.075, on the edge, and in A's frame B's corner crosses the line
        // of A's bottom edge (edge 0) at x = 0.975, on that edge: both covers activate,
        // while the covers through the side edges (crossed beyond their ends) do not.
        let motions = |d: [[f64; 6]; 2]| {
            [
                dda_geom::Motion::new(shapes[0].centroid, &d[0]),
                dda_geom::Motion::new(shapes[1].centroid, &d[1]),
            ]
        };
        let trial = motions([[0.12, -0.08, 0.0, 0.0, 0.0, 0.0], [0.0; 6]]);
        let mut moved = set.clone();
        assert_eq!(track(&CoverDetector, &shapes, &trial, &mut moved), 2);
        let act: Vec<_> = moved.active().map(|c| tuple(c.key)).collect();
        assert_eq!(act, vec![(0, 1, 1, 2), (1, 3, 0, 0)]);
        assert!(
            moved
                .active()
                .all(|c| c.state == crate::ContactState::Locked)
        );
        // Moving sideways only, nothing enters.
        let trial = motions([[0.1, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0; 6]]);
        let mut side = set.clone();
        assert_eq!(track(&CoverDetector, &shapes, &trial, &mut side), 0);
    }
}
