//! Convex polygons: validated construction, mass properties, and the DDA block motion.
//!
//! A [`ConvexPolygon`] is the shape of one DDA block. Construction validates once
//! (enough vertices, finite, counter-clockwise, convex, no degenerate edge); afterwards the
//! polygon is moved only by affine maps with positive determinant, which keep it valid.

use crate::aabb::Aabb;
use crate::error::PolygonError;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// Default relative tolerance of validation, as a fraction of the polygon's size (the
/// diagonal of its bounding box): vertices closer than this coincide, a vertex closer than
/// this to the line through its neighbours is collinear.
pub const DEFAULT_REL_TOL: f64 = 1e-9;

/// How strictly [`ConvexPolygon::with_options`] treats input that can be repaired.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolygonOptions {
    /// Relative tolerance (see [`DEFAULT_REL_TOL`]).
    pub rel_tol: f64,
    /// Reverse clockwise input instead of rejecting it.
    pub reverse_clockwise: bool,
    /// Drop collinear (and within-tolerance reflex) vertices instead of rejecting them.
    pub merge_collinear: bool,
}

impl Default for PolygonOptions {
    fn default() -> Self {
        Self {
            rel_tol: DEFAULT_REL_TOL,
            reverse_clockwise: true,
            merge_collinear: true,
        }
    }
}

impl PolygonOptions {
    /// Options that repair nothing: clockwise or collinear input is an error.
    pub fn strict() -> Self {
        Self {
            rel_tol: DEFAULT_REL_TOL,
            reverse_clockwise: false,
            merge_collinear: false,
        }
    }
}

/// What validation changed in the input to make it a valid polygon.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Repairs {
    /// The input ran clockwise and was reversed.
    pub reversed: bool,
    /// Input positions of vertices dropped as collinear, ascending.
    pub merged: Vec<usize>,
}

impl Repairs {
    /// Whether the input was used exactly as given.
    pub fn is_empty(&self) -> bool {
        !self.reversed && self.merged.is_empty()
    }
}

/// Area, centroid and second moments of area about the centroid (exact for polygons).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Area A.
    pub area: f64,
    /// Centroid (x0, y0).
    pub centroid: DVec2,
    /// S_xx = integral of (x - x0)^2 dA.
    pub sxx: f64,
    /// S_yy = integral of (y - y0)^2 dA.
    pub syy: f64,
    /// S_xy = integral of (x - x0)(y - y0) dA.
    pub sxy: f64,
}

/// A convex polygon with counter-clockwise vertices, no two coincident and no three
/// collinear. Serialised as its list of vertices; deserialising validates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "Vec<DVec2>", into = "Vec<DVec2>")]
pub struct ConvexPolygon {
    vertices: Vec<DVec2>,
}

impl TryFrom<Vec<DVec2>> for ConvexPolygon {
    type Error = PolygonError;
    fn try_from(v: Vec<DVec2>) -> Result<Self, PolygonError> {
        ConvexPolygon::new(v)
    }
}

impl From<ConvexPolygon> for Vec<DVec2> {
    fn from(p: ConvexPolygon) -> Self {
        p.vertices
    }
}

/// Twice the signed area of triangle (o, a, b): positive when a -> b turns left about o.
#[inline]
fn cross(a: DVec2, b: DVec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Whether the closed segments p0p1 and q0q1 cross at a point interior to both.
fn segments_cross(p0: DVec2, p1: DVec2, q0: DVec2, q1: DVec2) -> bool {
    let d1 = cross(p1 - p0, q0 - p0);
    let d2 = cross(p1 - p0, q1 - p0);
    let d3 = cross(q1 - q0, p0 - q0);
    let d4 = cross(q1 - q0, p1 - q0);
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

impl ConvexPolygon {
    /// Validates `vertices` with the default options: clockwise input is reversed and
    /// collinear vertices are merged silently (use [`Self::with_options`] to see repairs).
    pub fn new(vertices: impl Into<Vec<DVec2>>) -> Result<Self, PolygonError> {
        Self::with_options(vertices, &PolygonOptions::default()).map(|(p, _)| p)
    }

    /// Validates `[x, y]` pairs with the default options.
    pub fn from_coords(coords: &[[f64; 2]]) -> Result<Self, PolygonError> {
        Self::new(coords.iter().map(|&c| DVec2::from(c)).collect::<Vec<_>>())
    }

    /// Validates `vertices`, returning the polygon and what was repaired to make it.
    pub fn with_options(
        vertices: impl Into<Vec<DVec2>>,
        opts: &PolygonOptions,
    ) -> Result<(Self, Repairs), PolygonError> {
        let input: Vec<DVec2> = vertices.into();
        let n = input.len();
        if n < 3 {
            return Err(PolygonError::TooFewVertices { count: n });
        }
        if let Some(i) = input.iter().position(|v| !v.is_finite()) {
            return Err(PolygonError::NonFinite { vertex: i });
        }
        let bounds = Aabb::from_points(&input);
        let scale = bounds.size().length();
        let eps = opts.rel_tol * scale;
        for i in 0..n {
            let j = (i + 1) % n;
            if input[i].distance(input[j]) <= eps {
                let (vertex, of) = if j == 0 { (i, 0) } else { (j, i) };
                return Err(PolygonError::DuplicateVertex { vertex, of });
            }
        }
        // Signed area about a local origin, for orientation.
        let o = input[0];
        let twice_area: f64 = (0..n)
            .map(|i| cross(input[i] - o, input[(i + 1) % n] - o))
            .sum();
        let mut repairs = Repairs::default();
        // Work on input positions in counter-clockwise order.
        let mut ring: Vec<usize> = (0..n).collect();
        if twice_area < 0.0 {
            ring.reverse();
        }
        // Classify each corner by the signed distance of the vertex from the chord of its
        // neighbours (positive: a left, convex turn). Drop collinear vertices one at a time,
        // re-checking neighbours, until every corner is a strict left turn or fails.
        let mut k = 0;
        let mut unchanged = 0;
        let mut bad_corner = None;
        while unchanged < ring.len() && ring.len() >= 3 {
            let m = ring.len();
            let p = input[ring[(k + m - 1) % m]];
            let v = input[ring[k % m]];
            let q = input[ring[(k + 1) % m]];
            let chord = q - p;
            let chord_len = chord.length();
            let dist = if chord_len > 0.0 {
                cross(v - p, chord) / chord_len
            } else {
                0.0
            };
            if dist > eps {
                k = (k + 1) % m;
                unchanged += 1;
                continue;
            }
            let forward = (v - p).dot(q - v) > 0.0;
            if dist >= -eps && forward && chord_len > eps {
                if !opts.merge_collinear {
                    return Err(PolygonError::CollinearVertex {
                        vertex: ring[k % m],
                    });
                }
                repairs.merged.push(ring[k % m]);
                ring.remove(k % m);
                k %= ring.len().max(1);
                k = (k + ring.len() - 1) % ring.len().max(1);
                unchanged = 0;
                continue;
            }
            bad_corner = Some(ring[k % m]);
            break;
        }
        let turning_ok = bad_corner.is_none() && ring.len() >= 3 && {
            // A locally convex closed polygon is simple iff it turns once around.
            let m = ring.len();
            let total: f64 = (0..m)
                .map(|i| {
                    let p = input[ring[(i + m - 1) % m]];
                    let v = input[ring[i]];
                    let q = input[ring[(i + 1) % m]];
                    let (a, b) = (v - p, q - v);
                    cross(a, b).atan2(a.dot(b))
                })
                .sum();
            (total - std::f64::consts::TAU).abs() < 1.0
        };
        let area_ok = twice_area.abs() > eps * scale;
        if !(turning_ok && area_ok) {
            return Err(Self::diagnose(&input, eps, scale, twice_area, bad_corner));
        }
        if twice_area < 0.0 {
            if !opts.reverse_clockwise {
                return Err(PolygonError::Clockwise);
            }
            repairs.reversed = true;
        }
        repairs.merged.sort_unstable();
        let vertices = ring.iter().map(|&i| input[i]).collect();
        Ok((ConvexPolygon { vertices }, repairs))
    }

    /// Names the most specific defect of a vertex list that failed the convexity check.
    fn diagnose(
        input: &[DVec2],
        eps: f64,
        scale: f64,
        twice_area: f64,
        bad_corner: Option<usize>,
    ) -> PolygonError {
        let n = input.len();
        for i in 0..n {
            for j in (i + 2)..n {
                if input[i].distance(input[j]) <= eps {
                    return PolygonError::DuplicateVertex { vertex: j, of: i };
                }
            }
        }
        for i in 0..n {
            for j in (i + 2)..n {
                if i == 0 && j == n - 1 {
                    continue; // adjacent through the wrap
                }
                let (p0, p1) = (input[i], input[(i + 1) % n]);
                let (q0, q1) = (input[j], input[(j + 1) % n]);
                if segments_cross(p0, p1, q0, q1) {
                    return PolygonError::SelfIntersecting {
                        edge_a: i,
                        edge_b: j,
                    };
                }
            }
        }
        if twice_area.abs() <= eps * scale {
            return PolygonError::ZeroArea;
        }
        match bad_corner {
            Some(vertex) => PolygonError::NotConvex { vertex },
            // Turns more than once around without a proper crossing: edges overlap.
            None => PolygonError::SelfIntersecting {
                edge_a: 0,
                edge_b: 0,
            },
        }
    }

    /// The stretches of edge `k` that edges of `other` run along (anti-parallel, both
    /// ends on the edge's line within `eps`, overlapping by more than `eps`), as ratios
    /// `(from, to)` along edge `k`, in `other`'s edge order.
    pub fn edge_contacts(&self, k: usize, other: &ConvexPolygon, eps: f64) -> Vec<(f64, f64)> {
        let (a, c) = self.edge(k);
        let len = a.distance(c);
        let d = (c - a) / len;
        let on = |q: DVec2| d.perp_dot(q - a).abs() <= eps;
        other
            .edges()
            .filter(|&(q0, q1)| on(q0) && on(q1) && d.dot(q1 - q0) < 0.0)
            .filter_map(|(q0, q1)| {
                let (lo, hi) = (d.dot(q1 - a).max(0.0), d.dot(q0 - a).min(len));
                (hi - lo > eps).then_some((lo / len, hi / len))
            })
            .collect()
    }

    /// Whether `p` lies in the polygon, its boundary included, or within `eps` outside
    /// every edge's line.
    pub fn contains_within(&self, p: DVec2, eps: f64) -> bool {
        self.edges()
            .all(|(a, c)| (c - a).perp_dot(p - a) >= -eps * (c - a).length())
    }

    /// A box holding every point that [`ConvexPolygon::contains_within`] accepts at
    /// `eps`: the polygon with each edge's line moved out by eps, whose corners move out
    /// along their bisectors (by eps / sin(a / 2) at an interior angle a), for a reach
    /// grown by far more than that test's rounding (1e-6 of eps, and 1e-9 of the
    /// polygon's size). Unbounded where a corner is too sharp to say (an interior angle
    /// below some 1e-6 rad).
    pub fn reach_bounds(&self, eps: f64) -> Aabb {
        let size = self.aabb().size();
        let reach = eps * (1.0 + 1e-6) + 1e-9 * size.x.max(size.y);
        let n = self.len();
        let mut bounds = Aabb::from_points(&[]);
        for i in 0..n {
            let (n0, n1) = (self.normal(i + n - 1), self.normal(i));
            // The corner's point on both moved lines, c . n0 = c . n1 = reach.
            let m = 1.0 + n0.dot(n1);
            if m.is_nan() || m <= 1e-12 {
                return Aabb {
                    min: DVec2::splat(f64::NEG_INFINITY),
                    max: DVec2::splat(f64::INFINITY),
                };
            }
            let c = self.vertices[i] + (n0 + n1) * (reach / m);
            bounds.min = bounds.min.min(c);
            bounds.max = bounds.max.max(c);
        }
        bounds
    }

    /// Rebuilds a polygon saved from a run, keeping its vertices bit for bit: checks only
    /// that there are at least three, all finite, enclosing a positive area. Polygons a
    /// run produces are affine images of validated ones, which tolerance-based validation
    /// could repair and so change; a resumed run must see exactly what was saved.
    pub fn restore(vertices: Vec<DVec2>) -> Result<Self, PolygonError> {
        if vertices.len() < 3 {
            return Err(PolygonError::TooFewVertices {
                count: vertices.len(),
            });
        }
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(PolygonError::NonFinite { vertex: i });
        }
        let p = Self::from_valid(vertices);
        if p.area() > 0.0 {
            Ok(p)
        } else {
            Err(PolygonError::ZeroArea)
        }
    }

    /// Builds a polygon from vertices known to be valid (for affine images of valid ones).
    fn from_valid(vertices: Vec<DVec2>) -> Self {
        ConvexPolygon { vertices }
    }

    /// The vertices, counter-clockwise.
    #[inline]
    pub fn vertices(&self) -> &[DVec2] {
        &self.vertices
    }

    /// Number of vertices (and of edges).
    #[inline]
    #[allow(clippy::len_without_is_empty)] // a polygon is never empty
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Vertex `i` (indices wrap around).
    #[inline]
    pub fn vertex(&self, i: usize) -> DVec2 {
        self.vertices[i % self.vertices.len()]
    }

    /// Edge `i`, from vertex `i` to vertex `i + 1`.
    #[inline]
    pub fn edge(&self, i: usize) -> (DVec2, DVec2) {
        (self.vertex(i), self.vertex(i + 1))
    }

    /// All edges in order, each as (start, end).
    pub fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        (0..self.len()).map(move |i| self.edge(i))
    }

    /// Outward unit normal of edge `i` (right of the counter-clockwise edge direction).
    pub fn normal(&self, i: usize) -> DVec2 {
        let (p, q) = self.edge(i);
        crate::measures::outward_normal(p, q)
    }

    /// Outward unit normals of all edges.
    pub fn normals(&self) -> Vec<DVec2> {
        (0..self.len()).map(|i| self.normal(i)).collect()
    }

    /// Interior angle at each vertex, radians, each in (0, pi).
    pub fn interior_angles(&self) -> Vec<f64> {
        let n = self.len();
        (0..n)
            .map(|i| {
                let v = self.vertices[i];
                let a = self.vertex(i + n - 1) - v;
                let b = self.vertex(i + 1) - v;
                cross(b, a).atan2(a.dot(b))
            })
            .collect()
    }

    /// The shortest edge: its index and length.
    pub fn shortest_edge(&self) -> (usize, f64) {
        self.edges().map(|(p, q)| p.distance(q)).enumerate().fold(
            (0, f64::INFINITY),
            |best, (i, l)| if l < best.1 { (i, l) } else { best },
        )
    }

    /// The smallest interior angle: its vertex and size in radians.
    pub fn smallest_angle(&self) -> (usize, f64) {
        self.interior_angles()
            .into_iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (i, a)| if a < best.1 { (i, a) } else { best },
            )
    }

    /// The bounding box.
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// The range of `n . x` over the vertices: the polygon's projection on `n`.
    pub fn extent(&self, n: DVec2) -> (f64, f64) {
        self.vertices
            .iter()
            .map(|v| n.dot(*v))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            })
    }

    /// The largest distance between two vertices.
    pub fn diameter(&self) -> f64 {
        let v = &self.vertices;
        let mut d2: f64 = 0.0;
        for i in 0..v.len() {
            for j in (i + 1)..v.len() {
                d2 = d2.max(v[i].distance_squared(v[j]));
            }
        }
        d2.sqrt()
    }

    /// Area (positive).
    pub fn area(&self) -> f64 {
        let o = self.vertices[0];
        let n = self.len();
        0.5 * (0..n)
            .map(|i| cross(self.vertices[i] - o, self.vertex(i + 1) - o))
            .sum::<f64>()
    }

    /// Centroid (area-weighted).
    pub fn centroid(&self) -> DVec2 {
        let o = self.vertices[0];
        let n = self.len();
        let (mut a2, mut c) = (0.0, DVec2::ZERO);
        for i in 0..n {
            let (p, q) = (self.vertices[i] - o, self.vertex(i + 1) - o);
            let w = cross(p, q);
            a2 += w;
            c += (p + q) * w;
        }
        o + c / (3.0 * a2)
    }

    /// Area, centroid and second moments about the centroid, exact for polygons
    /// (computed with vertices relative to the centroid to avoid cancellation).
    pub fn moments(&self) -> Moments {
        let c = self.centroid();
        let n = self.len();
        let (mut a2, mut ixx, mut iyy, mut ixy) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n {
            let (p, q) = (self.vertices[i] - c, self.vertex(i + 1) - c);
            let w = cross(p, q);
            a2 += w;
            ixx += w * (p.x * p.x + p.x * q.x + q.x * q.x);
            iyy += w * (p.y * p.y + p.y * q.y + q.y * q.y);
            ixy += w * (2.0 * p.x * p.y + p.x * q.y + q.x * p.y + 2.0 * q.x * q.y);
        }
        Moments {
            area: 0.5 * a2,
            centroid: c,
            sxx: ixx / 12.0,
            syy: iyy / 12.0,
            sxy: ixy / 24.0,
        }
    }

    /// This polygon translated by `t`.
    pub fn translated(&self, t: DVec2) -> Self {
        Self::from_valid(self.vertices.iter().map(|&v| v + t).collect())
    }

    /// This polygon moved by the DDA displacement function of a block whose reference point
    /// (its centroid) is `center`, with unknowns `d = (u0, v0, r0, ex, ey, gxy)`
    /// (docs/method.md, section 1). The rotation r0 is applied exactly; the strains
    /// linearly.
    pub fn displaced(&self, center: DVec2, d: &[f64; 6]) -> Result<Self, PolygonError> {
        let mut moved = self.clone();
        moved.displace(center, d)?;
        Ok(moved)
    }

    /// [`ConvexPolygon::displaced`] in place, without allocating; on error (the motion
    /// would turn the polygon inside out, see [`check_displacement`]) it is unchanged.
    pub fn displace(&mut self, center: DVec2, d: &[f64; 6]) -> Result<(), PolygonError> {
        let m = displacement_matrix(d);
        keeps_orientation(&m)?;
        let t = DVec2::new(d[0], d[1]);
        for p in self.vertices.iter_mut() {
            *p = apply(&m, center, t, *p);
        }
        Ok(())
    }
}

/// Whether the DDA displacement `d` keeps a polygon's orientation (its linear part has a
/// positive determinant): [`ConvexPolygon::displace`] fails exactly when this does.
pub fn check_displacement(d: &[f64; 6]) -> Result<(), PolygonError> {
    keeps_orientation(&displacement_matrix(d))
}

/// Whether the linear part `m` of a motion has a positive determinant.
#[inline]
fn keeps_orientation(m: &[f64; 4]) -> Result<(), PolygonError> {
    if m[0] * m[3] - m[1] * m[2] <= 0.0 {
        return Err(PolygonError::Inverted);
    }
    Ok(())
}

/// Linear part [m00, m01, m10, m11] of the block motion: exact rotation plus strain.
#[inline]
fn displacement_matrix(d: &[f64; 6]) -> [f64; 4] {
    let (s, c) = d[2].sin_cos();
    let g = 0.5 * d[5];
    [c + d[3], -s + g, s + g, c + d[4]]
}

#[inline]
fn apply(m: &[f64; 4], center: DVec2, t: DVec2, p: DVec2) -> DVec2 {
    let r = p - center;
    center + t + DVec2::new(m[0] * r.x + m[1] * r.y, m[2] * r.x + m[3] * r.y)
}

/// Where the block motion `d` (docs/method.md section 1, rotation exact) takes point `p` of
/// a block whose reference point is `center`.
pub fn displace_point(p: DVec2, center: DVec2, d: &[f64; 6]) -> DVec2 {
    Motion::new(center, d).apply(p)
}

/// A block motion `d` about `center` (docs/method.md section 1, rotation exact) as an
/// affine map, computed once to move many points (one `sin_cos` instead of one per point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Motion {
    m: [f64; 4],
    center: DVec2,
    t: DVec2,
}

impl Motion {
    /// The motion `d` of a block whose reference point is `center`.
    pub fn new(center: DVec2, d: &[f64; 6]) -> Self {
        Motion {
            m: displacement_matrix(d),
            center,
            t: DVec2::new(d[0], d[1]),
        }
    }

    /// Where the motion takes point `p`; equals [`displace_point`] bit for bit.
    #[inline]
    pub fn apply(&self, p: DVec2) -> DVec2 {
        apply(&self.m, self.center, self.t, p)
    }
}

/// Signed separation of two convex polygons by separating axes: the largest gap over
/// the edge normals of both (positive: apart by at least that much; negative: the
/// least overlap), and the axis it is along, pointing from `b` to `a`.
pub fn separation(a: &ConvexPolygon, b: &ConvexPolygon) -> (f64, DVec2) {
    let mut best = (f64::NEG_INFINITY, DVec2::Y);
    for (p, q, flip) in [(a, b, -1.0), (b, a, 1.0)] {
        for i in 0..p.len() {
            let n = p.normal(i);
            let (lo_q, _) = q.extent(n);
            let (_, hi_p) = p.extent(n);
            // q beyond p's face i by lo_q - hi_p along p's outward normal n.
            let gap = lo_q - hi_p;
            if gap > best.0 {
                best = (gap, flip * n);
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Separation of unit squares: apart, touching, overlapping, with the axis from b to a.
    #[test]
    fn separation_of_squares() {
        let square = |x: f64, y: f64| {
            ConvexPolygon::from_coords(&[[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]])
                .expect("square")
        };
        let b = square(0.0, 0.0);
        let (gap, n) = separation(&square(0.0, 1.5), &b);
        assert!((gap - 0.5).abs() < 1e-12 && (n - DVec2::Y).length() < 1e-12);
        let (gap, n) = separation(&square(-1.25, 0.0), &b);
        assert!((gap - 0.25).abs() < 1e-12 && (n + DVec2::X).length() < 1e-12);
        let (gap, _) = separation(&square(0.0, 0.9), &b);
        assert!((gap + 0.1).abs() < 1e-12);
    }

    fn square() -> Vec<DVec2> {
        vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 1.0),
            DVec2::new(0.0, 1.0),
        ]
    }

    #[test]
    fn rectangle_properties() {
        let p = ConvexPolygon::new(square()).expect("valid");
        let m = p.moments();
        assert_eq!(m.area, 2.0);
        assert_eq!(m.centroid, DVec2::new(1.0, 0.5));
        // b h^3 / 12 about the centroid: Sxx = h b^3/12 = 1*8/12, Syy = 2*1/12.
        assert!((m.sxx - 8.0 / 12.0).abs() < 1e-15);
        assert!((m.syy - 2.0 / 12.0).abs() < 1e-15);
        assert!(m.sxy.abs() < 1e-15);
        assert_eq!(p.shortest_edge(), (1, 1.0));
    }

    #[test]
    fn clockwise_is_reversed_and_reported() {
        let mut v = square();
        v.reverse();
        let (p, r) =
            ConvexPolygon::with_options(v.clone(), &PolygonOptions::default()).expect("valid");
        assert!(r.reversed);
        assert!(p.area() > 0.0);
        assert_eq!(
            ConvexPolygon::with_options(v, &PolygonOptions::strict()),
            Err(PolygonError::Clockwise)
        );
    }

    #[test]
    fn collinear_vertex_is_merged_and_reported() {
        let mut v = square();
        v.insert(1, DVec2::new(1.0, 0.0));
        let (p, r) =
            ConvexPolygon::with_options(v.clone(), &PolygonOptions::default()).expect("valid");
        assert_eq!(r.merged, vec![1]);
        assert_eq!(p.len(), 4);
        assert_eq!(
            ConvexPolygon::with_options(v, &PolygonOptions::strict()),
            Err(PolygonError::CollinearVertex { vertex: 1 })
        );
    }

    #[test]
    fn exact_rotation_keeps_shape() {
        let p = ConvexPolygon::new(square()).expect("valid");
        let c = p.centroid();
        let q = p
            .displaced(c, &[0.5, -1.0, 1.0, 0.0, 0.0, 0.0])
            .expect("valid");
        assert!((q.area() - p.area()).abs() < 1e-14);
        assert!((q.centroid() - (c + DVec2::new(0.5, -1.0))).length() < 1e-14);
    }
}
