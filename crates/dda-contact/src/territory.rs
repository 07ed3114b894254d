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
    ) {
        let tol = params.d_tol;
        let tol2 = tol * tol;
        let sin_e = params.sin_theta_e();
        for (i, a) in vs.vertices_near(es, tol) {
            if with_vertex_pairs {
                for j in 0..es.len() {
                    if self.in_vertex_territory(a, es, j, tol2) {
                        // Resolve a vertex pair the same way from either side (lower block
                        // first), so a pair found twice gives one contact.
                        let c = if vb < eb {
                            resolve_vertex_pair(vs, vb, i, es, eb, j, sin_e)
                        } else {
                            resolve_vertex_pair(es, eb, j, vs, vb, i, sin_e)
                        };
                        out.extend(c);
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

/// Shi's local rule for the vertex pair (vertex `i` of `p`, vertex `j` of `q`): of the
/// pairs (vertex i, each edge at j) and (vertex j, each edge at i) passing the entrance
/// filter, the one with the largest d_n.
fn resolve_vertex_pair(
    p: &BlockShape,
    pb: u32,
    i: usize,
    q: &BlockShape,
    qb: u32,
    j: usize,
    sin_e: f64,
) -> Option<Contact> {
    let candidates = [
        (p, pb, i, q, qb, q.prev(j)),
        (p, pb, i, q, qb, j),
        (q, qb, j, p, pb, p.prev(i)),
        (q, qb, j, p, pb, i),
    ];
    let mut best: Option<Contact> = None;
    for (vs, vb, v, es, eb, e) in candidates {
        let (e_prev, e_next) = vs.vertex_edges(v);
        if !entrance_filter(e_prev, e_next, es.normal(e), sin_e) {
            continue;
        }
        let m = VertexEdge::new(vs.vertices[v], es.vertices[e], es.vertices[es.next(e)]);
        if best.is_none_or(|b| m.d_n > b.d_n) {
            let key = ContactKey {
                vertex_block: vb,
                vertex: v as u32,
                edge_block: eb,
                edge: e as u32,
            };
            best = Some(Contact::new(key, m.d_n, m.r, true));
        }
    }
    best
}

impl ContactDetector for TerritoryDetector {
    fn name(&self) -> &str {
        match self.territory {
            Territory::Distance => "type-1",
            Territory::NormalBounded => "type-2",
        }
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
        self.classify(a, ids.a, b, ids.b, params, true, out);
        // Disk territories are symmetric: vertex pairs were all found from A's side.
        let again = self.territory == Territory::NormalBounded;
        self.classify(b, ids.b, a, ids.a, params, again, out);
        // A vertex pair and an edge territory may name the same vertex-edge pair.
        let mine = &mut out[start..];
        mine.sort_unstable_by_key(|c| c.key);
        let mut keep = start;
        for k in start..out.len() {
            if k == start || out[k].key != out[keep - 1].key {
                out[keep] = out[k];
                keep += 1;
            }
        }
        out.truncate(keep);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::test_util::{IDS, shape, tuple};

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
            let got = run(det, &a, &b, 0.1);
            assert_eq!(got.len(), 1, "{}: {got:?}", det.name());
        }
    }
}
