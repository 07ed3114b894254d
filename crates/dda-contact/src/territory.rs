//! The conventional type-based detectors TB-CD-1 and TB-CD-2 (paper figures 1 and 2).
//!
//! The figures are not in the text; this is the reading implemented (docs/method.md,
//! section 5). Each vertex of one block is classified against the other block by
//! *territory*:
//! - type-1 (distance territories): a vertex's territory is the disk of radius d_tol about
//!   it; an edge's territory is the band |d_n| <= d_tol, r in [0, 1], minus the two disks
//!   at its ends.
//! - type-2 (normal-bounded territories): a vertex's territory is the outer wedge between
//!   the outward normals of its two edges, within d_tol of the vertex; an edge's territory
//!   is the band |d_n| <= d_tol between the normals at its two ends (r in [0, 1]).
//!
//! A vertex in an edge's territory makes a vertex-edge contact with that edge, if the pair
//! passes the entrance filter (eq. 5-6, as conventional DDA codes check angles too). A
//! vertex in another vertex's territory makes a vertex-vertex contact, resolved locally by
//! Shi's rule: of the four vertex-edge pairs formed by each vertex with the two edges at
//! the other, those passing the entrance filter compete and the one with the largest d_n
//! wins (first entrance when apart, shortest exit when overlapping), judged from that
//! vertex pair alone. Every contact found is active; open or closed by the sign of d_n.
//!
//! The decisions are local to one vertex pair. That is what makes these detectors fragile
//! on small edges and sharp corners (a vertex sees several vertices within d_tol, or picks
//! an edge that is not the one the blocks meet on), and it is deliberately not fixed here:
//! they are the baselines the cover-based detector is compared with.

use crate::contact::{Contact, ContactKey};
use crate::detector::{ContactDetector, DetectionParams};
use crate::neighbour::NeighbourPair;
use crate::shape::BlockShape;
use dda_geom::{DVec2, VertexEdge, entrance_filter};

/// Which territory definition a [`TerritoryDetector`] uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Territory {
    /// Paper figure 1: distance territories (TB-CD-1).
    Distance,
    /// Paper figure 2: normal-bounded territories (TB-CD-2).
    NormalBounded,
}

/// A conventional type-based detector (TB-CD-1 or TB-CD-2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TerritoryDetector {
    territory: Territory,
}

impl TerritoryDetector {
    /// TB-CD-1, distance territories (paper figure 1).
    pub fn type1() -> Self {
        TerritoryDetector {
            territory: Territory::Distance,
        }
    }

    /// TB-CD-2, normal-bounded territories (paper figure 2).
    pub fn type2() -> Self {
        TerritoryDetector {
            territory: Territory::NormalBounded,
        }
    }

    /// The territory definition.
    pub fn territory(&self) -> Territory {
        self.territory
    }

    /// Whether `p` lies in the vertex territory of vertex `j` of `s`.
    fn in_vertex_territory(&self, p: DVec2, s: &BlockShape, j: usize, tol2: f64) -> bool {
        let w = p - s.vertices[j];
        if w.length_squared() > tol2 {
            return false;
        }
        match self.territory {
            Territory::Distance => true,
            // Outside both edges' normal strips: behind the start of edge j and beyond the
            // end of edge j-1.
            Territory::NormalBounded => {
                w.dot(s.tangents[j]) < 0.0 && w.dot(s.tangents[s.prev(j)]) > 0.0
            }
        }
    }

    /// Vertex-edge contacts of vertices of `vs` in edge territories of `es`, and
    /// vertex-vertex contacts of vertices of `vs` in vertex territories of `es`.
    #[allow(clippy::too_many_arguments)]
    fn classify(
        &self,
        vs: &BlockShape,
        vb: u32,
        es: &BlockShape,
        eb: u32,
        params: &DetectionParams,
        with_vertex_pairs: bool,
        out: &mut Vec<Contact>,
        flush_ends: &mut Vec<ContactKey>,
    ) {
        let tol = params.d_tol;
        let tol2 = tol * tol;
        let sin_e = params.sin_theta_e();
        let slack = OUTSIDE * tol;
        for (i, a) in vs.vertices_near(es, tol) {
            if with_vertex_pairs {
                for j in 0..es.len() {
                    // Corners within d_tol whose edges run along each other are the ends
                    // of an edge-edge contact, whatever the territories say (Shi's code
                    // finds vertex pairs by distance): type-2's bands end at the normals
                    // of an edge's end, and a joint's corner would flicker across them.
                    let ends = (a - es.vertices[j]).length_squared() <= tol2
                        && flush_corners(vs, i, es, j, sin_e);
                    if ends || self.in_vertex_territory(a, es, j, tol2) {
                        // Resolve a vertex pair the same way from either side (lower block
                        // first), so a pair found twice gives one contact.
                        if vb < eb {
                            resolve_vertex_pair(
                                vs, vb, i, es, eb, j, sin_e, slack, out, flush_ends,
                            );
                        } else {
                            resolve_vertex_pair(
                                es, eb, j, vs, vb, i, sin_e, slack, out, flush_ends,
                            );
                        }
                    }
                }
            }
            let (e_prev, e_next) = vs.vertex_edges(i);
            for j in 0..es.len() {
                let m = VertexEdge::new(a, es.vertices[j], es.vertices[es.next(j)]);
                if m.d_n.abs() > tol || !(0.0..=1.0).contains(&m.r) {
                    continue;
                }
                if self.territory == Territory::Distance
                    && ((a - es.vertices[j]).length_squared() <= tol2
                        || (a - es.vertices[es.next(j)]).length_squared() <= tol2)
                {
                    continue; // in a vertex territory instead
                }
                if entrance_filter(e_prev, e_next, es.normal(j), sin_e) {
                    let key = ContactKey {
                        vertex_block: vb,
                        vertex: i as u32,
                        edge_block: eb,
                        edge: j as u32,
                    };
                    out.push(Contact::new(key, m.d_n, m.r, true));
                }
            }
        }
    }
}

/// Shi's local rule for the vertex pair (vertex `i` of `p`, vertex `j` of `q`), its
/// contacts appended to `out`:
/// - where an edge at one vertex faces an edge at the other, anti-parallel within
///   theta_e, the two corners are the ends of an edge-edge contact: the corner lying on
///   the other's edge (its projection ratio in [0, 1]) touches that edge; if both do,
///   the deeper behind it, and if they are as deep, the vertex whose next edge is in the
///   flush pair touches the other block's previous edge (one vertex-edge contact per
///   flush pair, the same whichever block is `p`, with shear and friction); its key goes
///   to `flush_ends` where its corner is behind the edge's line, along the edge (r in
///   [0, 1]) and outside the other block, so that [`exits`] keeps it;
/// - otherwise the pair is a vertex-vertex contact: of the pairs (vertex i, each edge at
///   j) and (vertex j, each edge at i) passing the entrance filter, the one with the
///   largest d_n, marked [`Contact::vertex_vertex`] (a normal spring only).
#[allow(clippy::too_many_arguments)]
fn resolve_vertex_pair(
    p: &BlockShape,
    pb: u32,
    i: usize,
    q: &BlockShape,
    qb: u32,
    j: usize,
    sin_e: f64,
    slack: f64,
    out: &mut Vec<Contact>,
    flush_ends: &mut Vec<ContactKey>,
) {
    let contact = |vs: &BlockShape, vb: u32, v: usize, es: &BlockShape, eb: u32, e: usize| {
        let m = VertexEdge::new(vs.vertices[v], es.vertices[e], es.vertices[es.next(e)]);
        let key = ContactKey {
            vertex_block: vb,
            vertex: v as u32,
            edge_block: eb,
            edge: e as u32,
        };
        Contact::new(key, m.d_n, m.r, true)
    };
    let flush = |a: DVec2, b: DVec2| flush_edges(a, b, sin_e);
    // Of a flush pair's two corners, the one inside the other block holds the joint's
    // end (a wedge's tip turning into its neighbour), the other being clear of it; both
    // or neither inside, the one on the other's edge (r in [0, 1]; the other lies beyond
    // that edge's end), then the one deeper behind it. Equal, the first.
    let inside = |c: &Contact| {
        let (vs, es) = if c.key.vertex_block == pb {
            (p, q)
        } else {
            (q, p)
        };
        !outside(vs.vertices[c.key.vertex as usize], es, slack)
    };
    let end_of = |first: Contact, second: Contact| {
        let rank = |c: &Contact| (inside(c), (0.0..=1.0).contains(&c.r));
        match rank(&second).cmp(&rank(&first)) {
            std::cmp::Ordering::Greater => second,
            std::cmp::Ordering::Equal if second.d_n < first.d_n => second,
            _ => first,
        }
    };
    let (ip, jp) = (p.prev(i), q.prev(j));
    let mut edge_edge = false;
    // A joint's end whose corner lies along the other's edge but outside the other block
    // (past the face at the edge's end, as the joint's compression pushes an acute
    // corner): `exits` keeps it.
    let mut end = |c: Contact| {
        if c.d_n < 0.0 && (0.0..=1.0).contains(&c.r) && !inside(&c) {
            flush_ends.push(c.key);
        }
        out.push(c);
    };
    if flush(p.tangents[i], q.tangents[jp]) {
        end(end_of(
            contact(p, pb, i, q, qb, jp),
            contact(q, qb, j, p, pb, i),
        ));
        edge_edge = true;
    }
    if flush(p.tangents[ip], q.tangents[j]) {
        end(end_of(
            contact(q, qb, j, p, pb, ip),
            contact(p, pb, i, q, qb, j),
        ));
        edge_edge = true;
    }
    if edge_edge {
        return;
    }
    let candidates = [
        (p, pb, i, q, qb, jp),
        (p, pb, i, q, qb, j),
        (q, qb, j, p, pb, ip),
        (q, qb, j, p, pb, i),
    ];
    let mut best: Option<Contact> = None;
    for (vs, vb, v, es, eb, e) in candidates {
        let (e_prev, e_next) = vs.vertex_edges(v);
        if !entrance_filter(e_prev, e_next, es.normal(e), sin_e) {
            continue;
        }
        let c = contact(vs, vb, v, es, eb, e);
        if best.is_none_or(|b| c.d_n > b.d_n) {
            best = Some(c);
        }
    }
    out.extend(best.map(|c| Contact {
        vertex_vertex: true,
        ..c
    }));
}

impl ContactDetector for TerritoryDetector {
    fn name(&self) -> &str {
        match self.territory {
            Territory::Distance => "type-1",
            Territory::NormalBounded => "type-2",
        }
    }

    /// TB-CD-2 only (our choice, measured on 40 generated jointed masses, 2026-11-28):
    /// with it TB-CD-2 took as many open-close iterations, a quarter fewer cut steps,
    /// and its standing masses ended at most at 1e-3 m/s instead of 2e-2; TB-CD-1, whose
    /// distance territories already keep a grid's corners between walls at rest, took 16%
    /// more iterations, 58% more cut steps, and one mass that stood fell.
    fn keeps_corners(&self) -> bool {
        self.territory == Territory::NormalBounded
    }

    fn detect_pair(
        &self,
        a: &BlockShape,
        b: &BlockShape,
        ids: NeighbourPair,
        params: &DetectionParams,
        out: &mut Vec<Contact>,
    ) {
        let start = out.len();
        let mut flush_ends = Vec::new();
        self.classify(a, ids.a, b, ids.b, params, true, out, &mut flush_ends);
        // Disk territories are symmetric: vertex pairs were all found from A's side.
        let again = self.territory == Territory::NormalBounded;
        self.classify(b, ids.b, a, ids.a, params, again, out, &mut flush_ends);
        // A vertex pair and an edge territory may name the same vertex-edge pair: the
        // vertex is then in the edge's territory, and the contact is a vertex-edge one.
        let mine = &mut out[start..];
        mine.sort_unstable_by_key(|c| (c.key, c.vertex_vertex));
        let mut keep = start;
        for k in start..out.len() {
            if k == start || out[k].key != out[keep - 1].key {
                out[keep] = out[k];
                keep += 1;
            }
        }
        out.truncate(keep);
        let shape = |id: u32| if id == ids.a { a } else { b };
        exits(out, start, shape, params.d_tol, &flush_ends);
    }
}

/// How far in front of an edge's line a vertex must be to count as outside the block,
/// over d_tol: blocks cut from one rock touch to rounding (as the contact law's band).
const OUTSIDE: f64 = 1e-9;

/// Whether edge directions `a` and `b` are anti-parallel within theta_e (`sin_e` its sine).
fn flush_edges(a: DVec2, b: DVec2, sin_e: f64) -> bool {
    crate::detector::quasi_parallel(a, -b, sin_e)
}

/// Whether an edge at vertex `i` of `p` runs along an edge at vertex `j` of `q` (the
/// next edge of one anti-parallel to the previous edge of the other).
fn flush_corners(p: &BlockShape, i: usize, q: &BlockShape, j: usize, sin_e: f64) -> bool {
    flush_edges(p.tangents[i], q.tangents[q.prev(j)], sin_e)
        || flush_edges(p.tangents[p.prev(i)], q.tangents[j], sin_e)
}

/// Whether `p` is outside `s`: in front of the line of one of its edges by more than
/// `slack`.
fn outside(p: DVec2, s: &BlockShape, slack: f64) -> bool {
    (0..s.len()).any(|j| s.normal(j).dot(p - s.vertices[j]) > slack)
}

/// Settles the contacts of each vertex behind edges' lines (those of `out[start..]`,
/// sorted by key; `shape` gives a block's shape by id):
/// - a vertex outside the other block (in front of the line of one of its edges by more
///   than [`OUTSIDE`] d_tol) has no contact behind a line: it lies beyond a sharp corner,
///   in the strip of an edge that does not bound it there, and a spring would push it
///   through a penetration it does not have; except the contact Shi's rule chose for the
///   end of a flush joint (`flush_ends`, from [`resolve_vertex_pair`]): a joint's
///   compression c pushes an acute corner at its end past the other block's outer face
///   (by c cos alpha), and without that contact the joint would turn about its other end;
/// - a vertex inside keeps only the contact it is least deep behind: it leaves the block
///   by the shortest exit, as Shi's rule decides for a vertex pair, rather than be pushed
///   out through two faces at once (a second contact appearing already penetrated
///   releases energy never stored).
fn exits<'s>(
    out: &mut Vec<Contact>,
    start: usize,
    shape: impl Fn(u32) -> &'s BlockShape,
    d_tol: f64,
    flush_ends: &[ContactKey],
) {
    let slack = OUTSIDE * d_tol;
    let mut keep = start;
    let mut k = start;
    while k < out.len() {
        let vertex = |c: &Contact| (c.key.vertex_block, c.key.vertex);
        let end = k + out[k..].partition_point(|c| vertex(c) == vertex(&out[k]));
        let key = out[k].key;
        let (vs, es) = (shape(key.vertex_block), shape(key.edge_block));
        // Measured only for a vertex behind some line: most contacts are not.
        let behind = (k..end).any(|m| out[m].d_n < 0.0);
        let inside = behind && !outside(vs.vertices[key.vertex as usize], es, slack);
        let exit = (k..end)
            .filter(|&m| out[m].d_n < 0.0 && inside)
            .max_by(|&a, &b| out[a].d_n.total_cmp(&out[b].d_n).then(b.cmp(&a)));
        for m in k..end {
            // Listed only for a corner outside the other block (`resolve_vertex_pair`).
            let joint_end = flush_ends.contains(&out[m].key);
            if out[m].d_n >= 0.0 || Some(m) == exit || joint_end {
                out[keep] = out[m];
                keep += 1;
            }
        }
        k = end;
    }
    out.truncate(keep);
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::contact::{ContactSet, ContactState};
    use crate::test_util::{IDS, pair_set, shape, tuple};

    fn run(
        det: TerritoryDetector,
        a: &BlockShape,
        b: &BlockShape,
        tol: f64,
    ) -> Vec<(u32, u32, u32, u32)> {
        let mut out = Vec::new();
        det.detect_pair(
            a,
            b,
            IDS,
            &DetectionParams::new(tol, 2f64.to_radians()),
            &mut out,
        );
        assert!(out.iter().all(|c| c.active));
        out.iter().map(|c| tuple(c.key)).collect()
    }

    #[test]
    fn vertex_over_an_edge_is_a_vertex_edge_contact() {
        // A's apex 0.05 above the middle of B's top edge (edge 2).
        let a = shape(&[[1.5, 1.05], [2.0, 2.0], [1.0, 2.0]]);
        let b = shape(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        assert_eq!(
            run(TerritoryDetector::type1(), &a, &b, 0.1),
            vec![(0, 0, 1, 2)]
        );
        assert_eq!(
            run(TerritoryDetector::type2(), &a, &b, 0.1),
            vec![(0, 0, 1, 2)]
        );
    }

    #[test]
    fn tiny_edge_makes_type1_see_two_vertices() {
        // B's top-left corner is chamfered by a 0.02 edge; A's apex hovers 0.03 above the
        // chamfer. With d_tol = 0.1 both chamfer vertices are within A's vertex disk: two
        // vertex-vertex contacts, each resolved locally.
        let b = shape(&[
            [0.0, 0.0],
            [3.0, 0.0],
            [3.0, 1.0],
            [0.014, 1.0],
            [0.0, 0.986],
        ]);
        let a = shape(&[[0.03, 1.02], [0.6, 2.0], [-0.5, 2.0]]);
        let t1 = run(TerritoryDetector::type1(), &a, &b, 0.1);
        assert!(t1.len() >= 2, "{t1:?}");
        // Type-2: the apex lies in the band of the chamfer edge or in a vertex wedge, one
        // decision per territory it is in.
        let t2 = run(TerritoryDetector::type2(), &a, &b, 0.1);
        assert!(!t2.is_empty());
        assert_eq!(TerritoryDetector::type1().name(), "type-1");
        assert_eq!(
            TerritoryDetector::type2().territory(),
            Territory::NormalBounded
        );
    }

    #[test]
    fn corner_to_corner_resolves_one_edge() {
        // A's lower-right corner 0.03 up-left of B's upper-left corner: a vertex pair.
        let a = shape(&[[0.0, 1.02], [0.98, 1.02], [0.98, 2.0], [0.0, 2.0]]);
        let b = shape(&[[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]]);
        for det in [TerritoryDetector::type1(), TerritoryDetector::type2()] {
            let got = contacts(det, &a, &b, 0.1);
            assert_eq!(got.len(), 1, "{}: {got:?}", det.name());
            // No edge at one corner runs along an edge at the other: a vertex-vertex
            // contact, a normal spring only.
            assert!(got[0].vertex_vertex, "{}: {got:?}", det.name());
        }
    }

    fn contacts(det: TerritoryDetector, a: &BlockShape, b: &BlockShape, tol: f64) -> Vec<Contact> {
        let mut out = Vec::new();
        let params = DetectionParams::new(tol, 2f64.to_radians());
        det.detect_pair(a, b, IDS, &params, &mut out);
        out
    }

    #[test]
    fn a_flush_joint_is_an_edge_edge_contact_from_either_side() {
        // Two unit squares side by side, A's right edge (1) on B's left edge (3), B moved
        // 1e-4 right and up, so that each corner of the joint lies in the other's vertex
        // territory for both detectors. The joint's two ends are vertex-edge contacts with
        // shear, each held by the corner that lies on the other block's edge: at the top
        // A's corner 2 on B's edge 3 (B's corner 3 is above A's), at the bottom B's corner
        // 0 on A's edge 1 (A's corner 1 is below B's); none is a vertex-vertex contact.
        // Type-1's disks also hold the corners with B turned by 1 degree about the joint's
        // middle (within theta_e = 4 degrees of flush).
        let a = shape(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let b_at = |deg: f64| {
            let (sin, cos) = deg.to_radians().sin_cos();
            let pivot = DVec2::new(1.0, 0.5);
            let pts: Vec<[f64; 2]> = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]]
                .iter()
                .map(|&[x, y]| {
                    let w = DVec2::new(x, y) - pivot;
                    let p = pivot + DVec2::new(cos * w.x - sin * w.y, sin * w.x + cos * w.y);
                    [p.x + 1e-4, p.y + 1e-4]
                })
                .collect();
            shape(&pts)
        };
        let cases = [
            (TerritoryDetector::type1(), 0.0),
            (TerritoryDetector::type1(), 1.0),
            (TerritoryDetector::type2(), 0.0),
        ];
        for (det, deg) in cases {
            let b = b_at(deg);
            let got = contacts(det, &a, &b, 0.02);
            let mut keys: Vec<_> = got.iter().map(|c| tuple(c.key)).collect();
            keys.sort_unstable();
            assert_eq!(keys, [(0, 2, 1, 3), (1, 0, 0, 1)], "{} {deg}", det.name());
            assert!(
                got.iter().all(|c| !c.vertex_vertex),
                "{}: {got:?}",
                det.name()
            );
            // The same contacts, mirrored, with the blocks swapped.
            let mut swapped: Vec<_> = contacts(det, &b, &a, 0.02)
                .iter()
                .map(|c| {
                    let (vb, v, eb, e) = tuple(c.key);
                    (1 - vb, v, 1 - eb, e)
                })
                .collect();
            swapped.sort_unstable();
            assert_eq!(keys, swapped, "{} {deg}", det.name());
        }
    }

    #[test]
    fn a_vertex_inside_a_corner_leaves_by_the_shortest_exit() {
        // B's lower-left corner 0.001 below A's top edge (2) and 0.003 left of A's right
        // edge (1), and so A's upper-right corner 0.001 above B's bottom edge (0) and
        // 0.003 right of B's left edge (3): each corner is behind both lines and in both
        // edges' bands (type-2) or the pair in each other's disk (type-1). No corner is
        // pushed out through the far face: every contact behind its line is on the top or
        // bottom edge, 0.001 deep, and no vertex has two.
        let a = shape(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let b = shape(&[
            [0.997, 0.999],
            [1.997, 0.999],
            [1.997, 1.999],
            [0.997, 1.999],
        ]);
        for det in [TerritoryDetector::type1(), TerritoryDetector::type2()] {
            let got = contacts(det, &a, &b, 0.02);
            let behind: Vec<_> = got.iter().filter(|c| c.d_n < 0.0).collect();
            assert!(!behind.is_empty(), "{}", det.name());
            for c in &behind {
                let (vb, _, _, e) = tuple(c.key);
                assert_eq!(e, if vb == 1 { 2 } else { 0 }, "{}: {got:?}", det.name());
                assert!((c.d_n + 0.001).abs() < 1e-12, "{}: {c:?}", det.name());
            }
            let mut vertices: Vec<_> = behind
                .iter()
                .map(|c| tuple(c.key))
                .map(|k| (k.0, k.1))
                .collect();
            vertices.dedup();
            assert_eq!(vertices.len(), behind.len(), "{}: {got:?}", det.name());
        }
    }

    #[test]
    fn a_joint_end_is_held_by_the_corner_on_the_other_edge() {
        // B beside A, 1e-4 to the right and 0.01 up (within d_tol = 0.02 of flush): at the
        // top A's corner 2 lies on B's left edge (3), B's corner 3 above A's; at the
        // bottom B's corner 0 lies on A's right edge (1), A's corner 1 below B's.
        let a = shape(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        let b = shape(&[
            [1.0001, 0.01],
            [2.0001, 0.01],
            [2.0001, 1.01],
            [1.0001, 1.01],
        ]);
        let det = TerritoryDetector::type1();
        let mut keys: Vec<_> = contacts(det, &a, &b, 0.02)
            .iter()
            .map(|c| tuple(c.key))
            .collect();
        keys.sort_unstable();
        assert_eq!(keys, [(0, 2, 1, 3), (1, 0, 0, 1)]);
    }

    #[test]
    fn a_vertex_beyond_a_sharp_corner_has_no_contact_behind_a_line() {
        // B's corner 1 at the origin is sharp (45 degrees): edge 0 (B's underside) arrives
        // along +x, edge 1 leaves towards (-1, 1). A's corner 0, pointing up at
        // (-0.002, 0.005), is 0.005 behind edge 0's line, inside its band, and could enter
        // it, but it is in front of edge 1's line by 0.0021: outside B. (The blocks do
        // overlap, A's edges crossing B's underside: B's corner 1 is inside A.)
        let b = shape(&[[-1.0, 0.0], [0.0, 0.0], [-1.0, 1.0]]);
        let a = shape(&[[-0.002, 0.005], [-0.3, -0.3], [0.3, -0.3]]);
        for det in [TerritoryDetector::type1(), TerritoryDetector::type2()] {
            let got = contacts(det, &a, &b, 0.02);
            let behind: Vec<_> = got
                .iter()
                .filter(|c| c.key.vertex_block == 0 && c.d_n < 0.0)
                .collect();
            assert!(behind.is_empty(), "{}: {got:?}", det.name());
            assert!(
                got.iter().any(|c| tuple(c.key).0 == 1 && c.d_n < 0.0),
                "{}: {got:?}",
                det.name()
            );
        }
    }

    #[test]
    fn a_compressed_joint_keeps_its_end_between_acute_corners() {
        // A voussoir-like pair: the joint runs up x = 0, a right-angled end at y = 0 and an
        // end of two acute corners (78.7 degrees) at y = 1, where the blocks' upper faces
        // fall away from the joint. B is pressed 1e-6 into A, so each top corner is
        // 1e-6 behind the other's joint face and 2e-7 in front of its upper face: outside
        // the other block. The joint keeps one contact at each end, with shear (an arch's
        // joint that lost its top end turned about its bottom one); the top end's other
        // corner, in type-2's edge band, gets none (two springs at one end). (At the
        // right-angled end, whose corners lie exactly on each other's lower face, type-2
        // gives each corner its contact, as before.)
        let c = 1e-6;
        let a = shape(&[[-1.0, 0.0], [0.0, 0.0], [0.0, 1.0], [-1.0, 0.8]]);
        let b = shape(&[[-c, 0.0], [1.0 - c, 0.0], [1.0 - c, 0.8], [-c, 1.0]]);
        for det in [TerritoryDetector::type1(), TerritoryDetector::type2()] {
            let got = contacts(det, &a, &b, 0.02);
            let at = |y: f64| -> Vec<&Contact> {
                got.iter()
                    .filter(|k| {
                        let s = if k.key.vertex_block == 0 { &a } else { &b };
                        k.d_n < 0.0 && s.vertices[k.key.vertex as usize].y == y
                    })
                    .collect()
            };
            let (top, bottom) = (at(1.0), at(0.0));
            assert_eq!(top.len(), 1, "{}: {got:?}", det.name());
            assert!(!bottom.is_empty(), "{}: {got:?}", det.name());
            assert!((top[0].d_n + c).abs() < 1e-12, "{}: {top:?}", det.name());
            assert!(!top[0].vertex_vertex, "{}: {top:?}", det.name());
        }
    }

    #[test]
    fn a_bond_outlives_the_outside_rule() {
        // The geometry of the sharp-corner test above: A's corner 0 is 0.005 behind B's
        // underside (edge 0) but outside B, so neither type-based detector lists it. A
        // bonded contact it closed in the step before is carried on, active, with its
        // state (a glued seam's end or a cohesive joint holds until the contact law
        // breaks it); an unbonded one is not.
        let b = shape(&[[-1.0, 0.0], [0.0, 0.0], [-1.0, 1.0]]);
        let a = shape(&[[-0.002, 0.005], [-0.3, -0.3], [0.3, -0.3]]);
        let key = ContactKey {
            vertex_block: 0,
            vertex: 0,
            edge_block: 1,
            edge: 0,
        };
        let shapes = [a, b];
        let params = DetectionParams::new(0.02, 2f64.to_radians());
        for det in [TerritoryDetector::type1(), TerritoryDetector::type2()] {
            for bonded in [true, false] {
                let old = Contact {
                    bonded,
                    locked_r: 0.9,
                    ..Contact::new(key, -0.004, 0.998, true)
                };
                let previous = pair_set(vec![old]);
                let mut out = ContactSet::default();
                crate::detect(&det, &shapes, &[IDS], &params, &previous, false, &mut out);
                let kept = out.find(&key);
                if bonded {
                    let c = kept.unwrap_or_else(|| panic!("{}: {out:?}", det.name()));
                    assert!(c.active && c.bonded, "{}: {c:?}", det.name());
                    assert_eq!(c.state, ContactState::Locked, "{}", det.name());
                    assert_eq!(c.locked_r, 0.9, "{}", det.name());
                    assert!((c.d_n + 0.005).abs() < 1e-12, "{}: {c:?}", det.name());
                } else {
                    assert!(kept.is_none(), "{}: {out:?}", det.name());
                }
            }
        }
    }
}
