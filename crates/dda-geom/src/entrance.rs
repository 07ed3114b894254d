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
    // Current vertex of A (in -A) and of B, and the edges leaving them; indices wrap by
    // comparison, not by `%`, which would cost an integer division per face.
    let (mut i, mut j) = (start_vertex(av, -1.0), start_vertex(bv, 1.0));
    let (mut i1, mut j1) = (wrap(i + 1, na), wrap(j + 1, nb));
    let mut da = av[i] - av[i1];
    let mut db = bv[j1] - bv[j];
    let (mut left_a, mut left_b) = (na, nb);
    let mut point = bv[j] - av[i] + a0;
    while left_a + left_b > 0 {
        if left_a == 0 || (left_b > 0 && not_after(db, da)) {
            let next = point + db;
            f(EntranceFace {
                start: point,
                end: next,
                source: CoverSource::VertexEdge { vertex: i, edge: j },
            });
            point = next;
            left_b -= 1;
            j = j1;
            j1 = wrap(j1 + 1, nb);
            db = bv[j1] - bv[j];
        } else {
            let next = point + da;
            f(EntranceFace {
                start: point,
                end: next,
                source: CoverSource::EdgeVertex { edge: i, vertex: j },
            });
            point = next;
            left_a -= 1;
            i = i1;
            i1 = wrap(i1 + 1, na);
            da = av[i] - av[i1];
        }
    }
}

#[inline(always)]
fn wrap(k: usize, n: usize) -> usize {
    if k >= n { k - n } else { k }
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
        let mut sat = SatMax::new(self.reference);
        let mut k = 0;
        for (n, f) in self.faces.iter().enumerate() {
            let before = sat.face;
            sat.add(f);
            if sat.face != before {
                k = n;
            }
        }
        let m = self.faces.len();
        sat.finish([self.faces[(k + m - 1) % m], self.faces[(k + 1) % m]])
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

/// The face of E with the largest outward distance h of the point p (a separating-axis
/// maximum), found without square roots or divisions: h1 > h2 is compared as
/// c1|c1| dd2 > c2|c2| dd1 with c = |d| h and dd = |d|^2 for face direction d.
struct SatMax {
    p: DVec2,
    face: EntranceFace,
    c: f64,
    dd: f64,
}

impl SatMax {
    #[inline]
    fn new(p: DVec2) -> Self {
        SatMax {
            p,
            face: EntranceFace {
                start: DVec2::ZERO,
                end: DVec2::ZERO,
                source: CoverSource::VertexEdge { vertex: 0, edge: 0 },
            },
            // Any real face (dd > 0) compares better than c = -1, dd = 0.
            c: -1.0,
            dd: 0.0,
        }
    }

    #[inline(always)]
    fn add(&mut self, f: &EntranceFace) {
        let d = f.end - f.start;
        let w = self.p - f.start;
        let dd = d.dot(d);
        let c = w.x * d.y - w.y * d.x;
        if c * c.abs() * self.dd > self.c * self.c.abs() * dd {
            *self = SatMax {
                p: self.p,
                face: *f,
                c,
                dd,
            };
        }
    }

    /// Signed distance, given the segments that may hold the nearest point when p is
    /// outside: the best face's neighbours on E (or any superset of segments inside E).
    ///
    /// If p is inside, the best h is the signed distance (shortest exit). If p is outside,
    /// the nearest point of E lies on the best face or, when it is a vertex, at an end of
    /// it (the faces next to the nearest vertex maximise h); a collinear neighbour (parallel
    /// edges of A and B) can tie, hence the neighbours. Segments inside E never come nearer
    /// than E itself, so extra candidates do no harm.
    #[inline]
    fn finish(self, neighbours: impl IntoIterator<Item = EntranceFace>) -> SignedDistance {
        if self.c <= 0.0 {
            return SignedDistance {
                distance: self.c / self.dd.sqrt(),
                source: self.face.source,
            };
        }
        let seg_d2 = |f: &EntranceFace| {
            let d = f.end - f.start;
            let w = self.p - f.start;
            let t = (w.dot(d) / d.dot(d)).clamp(0.0, 1.0);
            (w - d * t).length_squared()
        };
        let mut best = (seg_d2(&self.face), self.face.source);
        for g in neighbours {
            let d2 = seg_d2(&g);
            if d2 < best.0 {
                best = (d2, g.source);
            }
        }
        SignedDistance {
            distance: best.0.sqrt(),
            source: best.1,
        }
    }
}

/// The segments of B - A + a0 that can precede or follow `face` on the boundary of E: the
/// two faces sharing each of its ends. Each is a subset of E whether or not it is a face.
fn around(
    a: &ConvexPolygon,
    b: &ConvexPolygon,
    a0: DVec2,
    face: &EntranceFace,
) -> [EntranceFace; 4] {
    let (na, nb) = (a.len(), b.len());
    let (i, j) = match face.source {
        CoverSource::VertexEdge { vertex, edge } => (vertex, edge),
        CoverSource::EdgeVertex { edge, vertex } => (edge, vertex),
    };
    let ve = |vertex: usize, edge: usize| EntranceFace {
        start: b.vertex(edge) - a.vertex(vertex) + a0,
        end: b.vertex(edge + 1) - a.vertex(vertex) + a0,
        source: CoverSource::VertexEdge { vertex, edge },
    };
    let ev = |edge: usize, vertex: usize| EntranceFace {
        start: b.vertex(vertex) - a.vertex(edge) + a0,
        end: b.vertex(vertex) - a.vertex(edge + 1) + a0,
        source: CoverSource::EdgeVertex { edge, vertex },
    };
    // A face's start is b_j - a_i; its end is b_j+1 - a_i (VE) or b_j - a_i+1 (EV).
    let (ie, je) = match face.source {
        CoverSource::VertexEdge { .. } => (i, (j + 1) % nb),
        CoverSource::EdgeVertex { .. } => ((i + 1) % na, j),
    };
    [
        ve(i, (j + nb - 1) % nb),
        ev((i + na - 1) % na, j),
        ve(ie, je),
        ev(ie, je),
    ]
}

/// Signed distance between convex polygons A and B through their entrance block: the gap
/// when apart, minus the penetration depth when overlapping, with the face realising it.
/// O(n + m), no allocation.
pub fn signed_distance(a: &ConvexPolygon, b: &ConvexPolygon) -> SignedDistance {
    let mut sat = SatMax::new(DVec2::ZERO);
    for_each_face(a, b, DVec2::ZERO, |f| sat.add(&f));
    let near = around(a, b, DVec2::ZERO, &sat.face);
    sat.finish(near)
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
    fn parallel_edges_tie() {
        // A unit square 1 above a wider block, slid along it: the gap is 1 wherever it
        // is, though the nearest face of E may be either of two collinear faces.
        let b = poly(&[[0.5, 0.0], [3.0, 0.0], [3.0, 1.0], [0.5, 1.0]]);
        for k in 0..=40 {
            let x = -0.45 + 0.07 * k as f64;
            let a = poly(&[[x, 2.0], [x + 1.0, 2.0], [x + 1.0, 3.0], [x, 3.0]]);
            let s = signed_distance(&a, &b);
            let e = EntranceBlock::new(&a, &b, DVec2::ZERO).signed_distance();
            assert!((s.distance - 1.0).abs() < 1e-14, "x = {x}: {}", s.distance);
            assert!((e.distance - 1.0).abs() < 1e-14, "x = {x}: {}", e.distance);
        }
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
