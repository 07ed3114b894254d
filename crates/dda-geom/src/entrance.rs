//! The entrance block E(A,B) = B - A + a0 (paper eq. 1) and the distances d_RE (eq. 2)
//! and d_RE1 (eq. 3) between a reference point and it.
//!
//! For convex A and B the boundary of E is made of the contact covers C(0,1) (vertex of A
//! against edge of B) and C(1,0) (edge of A against vertex of B), paper eq. 4. Both
//! polygons' edges are already sorted by direction (counter-clockwise), so E is built by
//! merging the two sorted edge lists in O(n + m), never by a hull of all n*m differences.
//! A0 lies in E exactly when A and B overlap, and its distance to E is their distance.

use crate::polygon::ConvexPolygon;
use glam::DVec2;

/// Which vertex-edge pair a face of the entrance block comes from (paper eq. 4).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CoverSource {
    /// C(0,1): vertex `vertex` of A against edge `edge` (from vertex `edge` to `edge + 1`) of B.
    VertexEdge {
        /// Vertex of A.
        vertex: usize,
        /// Edge of B.
        edge: usize,
    },
    /// C(1,0): edge `edge` of A against vertex `vertex` of B.
    EdgeVertex {
        /// Edge of A.
        edge: usize,
        /// Vertex of B.
        vertex: usize,
    },
}

/// One face (edge) of an entrance block: a contact cover.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntranceFace {
    /// Start point (counter-clockwise around E).
    pub start: DVec2,
    /// End point.
    pub end: DVec2,
    /// The vertex-edge pair it comes from.
    pub source: CoverSource,
}

/// The entrance block of two convex polygons A and B with reference point a0 (paper eq. 1).
#[derive(Clone, Debug, PartialEq)]
pub struct EntranceBlock {
    reference: DVec2,
    faces: Vec<EntranceFace>,
}

/// The half-plane of a direction: 0 for angles in [0, pi), 1 for [pi, 2 pi).
#[inline]
fn half(d: DVec2) -> u8 {
    u8::from(d.y < 0.0 || (d.y == 0.0 && d.x < 0.0))
}

/// Whether direction `u` comes no later than `w` counter-clockwise from angle 0.
#[inline]
fn not_after(u: DVec2, w: DVec2) -> bool {
    let (hu, hw) = (half(u), half(w));
    if hu != hw {
        return hu < hw;
    }
    u.x * w.y - u.y * w.x >= 0.0
}

/// Index of the lowest vertex (ties: leftmost) when `sign` is 1, of the highest (ties:
/// rightmost) when `sign` is -1: the lowest-leftmost vertex of `sign * P`.
#[inline]
fn start_vertex(v: &[DVec2], sign: f64) -> usize {
    let mut best = 0;
    for i in 1..v.len() {
        let (p, q) = (v[i] * sign, v[best] * sign);
        if p.y < q.y || (p.y == q.y && p.x < q.x) {
            best = i;
        }
    }
    best
}

/// Calls `f` with every face of E(A,B) = B - A + a0, counter-clockwise, starting from its
/// lowest-leftmost vertex. E has exactly `a.len() + b.len()` faces; parallel edges of A and
/// B give two consecutive collinear faces (the quasi-parallel case). Allocates nothing.
#[inline]
pub fn for_each_face(
    a: &ConvexPolygon,
    b: &ConvexPolygon,
    a0: DVec2,
    mut f: impl FnMut(EntranceFace),
) {
    let (av, bv) = (a.vertices(), b.vertices());
    let (na, nb) = (av.len(), bv.len());
    let (ka0, jb0) = (start_vertex(av, -1.0), start_vertex(bv, 1.0));
    let (mut ka, mut jb) = (0, 0); // edges of -A and of B taken so far
    let mut point = bv[jb0] - av[ka0] + a0;
    while ka < na || jb < nb {
        let j = (jb0 + jb) % nb;
        let i = (ka0 + ka) % na;
        let take_b = if ka == na {
            true
        } else if jb == nb {
            false
        } else {
            let db = bv[(j + 1) % nb] - bv[j];
            let da = av[i] - av[(i + 1) % na];
            not_after(db, da)
        };
        if take_b {
            let next = point + (bv[(j + 1) % nb] - bv[j]);
            f(EntranceFace {
                start: point,
                end: next,
                source: CoverSource::VertexEdge { vertex: i, edge: j },
            });
            point = next;
            jb += 1;
        } else {
            let next = point + (av[i] - av[(i + 1) % na]);
            f(EntranceFace {
                start: point,
                end: next,
                source: CoverSource::EdgeVertex { edge: i, vertex: j },
            });
            point = next;
            ka += 1;
        }
    }
}

impl EntranceBlock {
    /// Builds E(A,B) = B - A + a0 (paper eq. 1) by merging edge directions in O(n + m).
    pub fn new(a: &ConvexPolygon, b: &ConvexPolygon, a0: DVec2) -> Self {
        let mut faces = Vec::with_capacity(a.len() + b.len());
        for_each_face(a, b, a0, |face| faces.push(face));
        EntranceBlock {
            reference: a0,
            faces,
        }
    }

    /// The reference point a0.
    pub fn reference(&self) -> DVec2 {
        self.reference
    }

    /// The faces (contact covers), counter-clockwise.
    pub fn faces(&self) -> &[EntranceFace] {
        &self.faces
    }

    /// The vertices, counter-clockwise (the start of each face).
    pub fn vertices(&self) -> Vec<DVec2> {
        self.faces.iter().map(|f| f.start).collect()
    }

    /// Area of E.
    pub fn area(&self) -> f64 {
        let o = self.faces[0].start;
        0.5 * self
            .faces
            .iter()
            .map(|f| {
                let (p, q) = (f.start - o, f.end - o);
                p.x * q.y - p.y * q.x
            })
            .sum::<f64>()
    }

    /// Signed distance from a0 to E (see [`signed_distance`]).
    pub fn signed_distance(&self) -> SignedDistance {
        let mut acc = DistanceAcc::new(self.reference);
        for f in &self.faces {
            acc.add(f);
        }
        acc.finish()
    }
}

/// The signed distance between two convex polygons and the entrance-block face (contact
/// cover) that realises it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SignedDistance {
    /// Positive: the gap between A and B (d_RE, eq. 2). Negative: minus the penetration
    /// depth, the shortest exit of a0 from E (d_RE1, eq. 3). Zero: touching.
    pub distance: f64,
    /// The face of E nearest to a0: the vertex-edge pair realising the distance.
    pub source: CoverSource,
}

/// Folds faces into the signed distance of a point from a convex polygon.
struct DistanceAcc {
    p: DVec2,
    /// Largest outward distance of p over all face lines, and its face.
    max_h: f64,
    max_src: Option<CoverSource>,
    /// Smallest squared distance to a face segment among faces p is outside of.
    min_d2: f64,
    min_src: Option<CoverSource>,
}

impl DistanceAcc {
    #[inline]
    fn new(p: DVec2) -> Self {
        DistanceAcc {
            p,
            max_h: f64::NEG_INFINITY,
            max_src: None,
            min_d2: f64::INFINITY,
            min_src: None,
        }
    }

    #[inline]
    fn add(&mut self, f: &EntranceFace) {
        let d = f.end - f.start;
        let w = self.p - f.start;
        let dd = d.dot(d);
        let c = w.x * d.y - w.y * d.x; // |d| times the outward distance
        let h = c / dd.sqrt();
        if h > self.max_h {
            self.max_h = h;
            self.max_src = Some(f.source);
        }
        if c > 0.0 {
            let t = (w.dot(d) / dd).clamp(0.0, 1.0);
            let d2 = (w - d * t).length_squared();
            if d2 < self.min_d2 {
                self.min_d2 = d2;
                self.min_src = Some(f.source);
            }
        }
    }

    #[inline]
    fn finish(self) -> SignedDistance {
        let fallback = CoverSource::VertexEdge { vertex: 0, edge: 0 };
        if self.max_h > 0.0 {
            SignedDistance {
                distance: self.min_d2.sqrt(),
                source: self.min_src.unwrap_or(fallback),
            }
        } else {
            SignedDistance {
                distance: self.max_h,
                source: self.max_src.unwrap_or(fallback),
            }
        }
    }
}

/// Signed distance between convex polygons A and B through their entrance block: the gap
/// when apart, minus the penetration depth when overlapping, with the face realising it.
/// O(n + m), no allocation.
pub fn signed_distance(a: &ConvexPolygon, b: &ConvexPolygon) -> SignedDistance {
    let mut acc = DistanceAcc::new(DVec2::ZERO);
    for_each_face(a, b, DVec2::ZERO, |f| acc.add(&f));
    acc.finish()
}

/// d_RE (paper eq. 2): distance from a0 to the entrance block, i.e. between A and B; zero
/// when they touch or overlap.
pub fn d_re(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    signed_distance(a, b).distance.max(0.0)
}

/// d_RE1 (paper eq. 3): distance from a0 to the boundary of the entrance block (shortest
/// entrance when apart, shortest exit when overlapping) and the face that realises it.
pub fn d_re1(a: &ConvexPolygon, b: &ConvexPolygon) -> (f64, CoverSource) {
    let s = signed_distance(a, b);
    (s.distance.abs(), s.source)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(c: &[[f64; 2]]) -> ConvexPolygon {
        ConvexPolygon::from_coords(c).expect("valid test polygon")
    }

    #[test]
    fn triangle_and_quadrangle() {
        // A above B, gap 0.5 between A's lowest vertex (1, 1.5) and B's top edge y = 1.
        let a = poly(&[[1.0, 1.5], [2.0, 2.5], [0.0, 2.5]]);
        let b = poly(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let e = EntranceBlock::new(&a, &b, DVec2::ZERO);
        assert_eq!(e.faces().len(), 7);
        let s = e.signed_distance();
        assert!((s.distance - 0.5).abs() < 1e-15);
        // B's top edge is edge 2 (from (3,1) to (0,1)); A's lowest vertex is vertex 0.
        assert_eq!(s.source, CoverSource::VertexEdge { vertex: 0, edge: 2 });
        assert_eq!(signed_distance(&a, &b), s);
        // Area of B - A: |A| + |B| + 2 V(A, -B); here by direct shoelace of E's vertices.
        assert!(e.area() > a.area() + b.area());
    }

    #[test]
    fn penetration_is_negative() {
        let a = poly(&[[1.0, 0.8], [2.0, 1.8], [0.0, 1.8]]);
        let b = poly(&[[0.0, 0.0], [3.0, 0.0], [3.0, 1.0], [0.0, 1.0]]);
        let s = signed_distance(&a, &b);
        assert!((s.distance + 0.2).abs() < 1e-15);
        assert_eq!(s.source, CoverSource::VertexEdge { vertex: 0, edge: 2 });
        assert_eq!(d_re(&a, &b), 0.0);
        assert!((d_re1(&a, &b).0 - 0.2).abs() < 1e-15);
    }

    #[test]
    fn edge_vertex_source() {
        // B's apex (1, 1) below A's bottom edge y = 1.5.
        let a = poly(&[[0.0, 1.5], [2.0, 1.5], [2.0, 2.5], [0.0, 2.5]]);
        let b = poly(&[[0.0, 0.0], [2.0, 0.0], [1.0, 1.0]]);
        let s = signed_distance(&a, &b);
        assert!((s.distance - 0.5).abs() < 1e-15);
        assert_eq!(s.source, CoverSource::EdgeVertex { edge: 0, vertex: 2 });
    }
}
