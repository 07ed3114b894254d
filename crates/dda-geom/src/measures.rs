//! The paper's vertex-edge measures (Zhuang, Zheng et al. 2021, section 2.2): the entrance
//! filter (eq. 5-6), the perpendicular distance d_n (eq. 7), the projection ratio r
//! (eq. 8), the vertex-node distances (eq. 9) and the contact region of an edge (eq. 10).
//!
//! Edges run counter-clockwise around their block, so the block's interior is on the left
//! of an edge and its outward normal on the right.

use glam::DVec2;

/// Outward unit normal of the edge `b0 -> b1` of a counter-clockwise polygon.
#[inline]
pub fn outward_normal(b0: DVec2, b1: DVec2) -> DVec2 {
    let d = b1 - b0;
    DVec2::new(d.y, -d.x) / d.length()
}

/// Perpendicular distance d_n of vertex `a` from edge `b0 -> b1` (paper eq. 7): positive
/// outside the edge's block, negative inside.
#[inline]
pub fn normal_distance(a: DVec2, b0: DVec2, b1: DVec2) -> f64 {
    (a - b0).dot(outward_normal(b0, b1))
}

/// Projection ratio r of vertex `a` on edge `b0 -> b1` (paper eq. 8): 0 at `b0`, 1 at `b1`.
#[inline]
pub fn projection_ratio(a: DVec2, b0: DVec2, b1: DVec2) -> f64 {
    let e = b1 - b0;
    (a - b0).dot(e) / e.dot(e)
}

/// Distances of vertex `a` to the edge's nodes `b0` and `b1` (paper eq. 9).
#[inline]
pub fn node_distances(a: DVec2, b0: DVec2, b1: DVec2) -> [f64; 2] {
    [a.distance(b0), a.distance(b1)]
}

/// The perpendicular distance and projection ratio of one vertex-edge pair together
/// (paper eq. 7-8), sharing the work.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexEdge {
    /// d_n, paper eq. 7 (positive outside).
    pub d_n: f64,
    /// r, paper eq. 8.
    pub r: f64,
}

impl VertexEdge {
    /// Measures vertex `a` against edge `b0 -> b1`.
    #[inline]
    pub fn new(a: DVec2, b0: DVec2, b1: DVec2) -> Self {
        let e = b1 - b0;
        let w = a - b0;
        let ee = e.dot(e);
        VertexEdge {
            d_n: (w.x * e.y - w.y * e.x) / ee.sqrt(),
            r: w.dot(e) / ee,
        }
    }
}

/// Which sub-region of an edge's contact region (paper eq. 10) holds a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ContactSubregion {
    /// Omega^C1 (eq. 10a): the band |d_n| <= d_tol with r in [0, 1].
    Band,
    /// Omega^C2 (eq. 10b): the disk of radius d_tol about the start node b_j.
    StartDisk,
    /// Omega^C3 (eq. 10c): the disk of radius d_tol about the end node b_j+1.
    EndDisk,
}

/// Distance filter (paper eq. 10): the sub-region of edge `b0 -> b1`'s contact region that
/// holds vertex `a`, or `None` when the vertex is outside it. The band is tested first,
/// then the disk about the nearer node.
#[inline]
pub fn contact_region(a: DVec2, b0: DVec2, b1: DVec2, d_tol: f64) -> Option<ContactSubregion> {
    let m = VertexEdge::new(a, b0, b1);
    if m.d_n.abs() <= d_tol && (0.0..=1.0).contains(&m.r) {
        return Some(ContactSubregion::Band);
    }
    let t2 = d_tol * d_tol;
    if m.r < 0.5 {
        (a.distance_squared(b0) <= t2).then_some(ContactSubregion::StartDisk)
    } else {
        (a.distance_squared(b1) <= t2).then_some(ContactSubregion::EndDisk)
    }
}

/// Entrance filter (paper eq. 5-6): a vertex passes against an edge with outward unit
/// normal `n` when both unit vectors along its own edges, `e_prev` (towards the previous
/// vertex) and `e_next` (towards the next), satisfy e . n > -sin(theta_e).
#[inline]
pub fn entrance_filter(e_prev: DVec2, e_next: DVec2, n: DVec2, sin_theta_e: f64) -> bool {
    e_prev.dot(n) > -sin_theta_e && e_next.dot(n) > -sin_theta_e
}

#[cfg(test)]
mod tests {
    use super::*;

    const B0: DVec2 = DVec2::new(0.0, 0.0);
    const B1: DVec2 = DVec2::new(2.0, 0.0);

    #[test]
    fn measures_against_a_horizontal_edge() {
        // Edge runs +x, so the block is above it (left) and outside is -y.
        let a = DVec2::new(0.5, -0.25);
        assert_eq!(normal_distance(a, B0, B1), 0.25);
        assert_eq!(projection_ratio(a, B0, B1), 0.25);
        let m = VertexEdge::new(a, B0, B1);
        assert_eq!((m.d_n, m.r), (0.25, 0.25));
        let [d0, d1] = node_distances(DVec2::new(0.0, -3.0), B0, B1);
        assert_eq!(d0, 3.0);
        assert!((d1 - 13f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn each_contact_subregion() {
        let tol = 0.1;
        let at = |x, y| contact_region(DVec2::new(x, y), B0, B1, tol);
        assert_eq!(at(1.0, -0.05), Some(ContactSubregion::Band));
        assert_eq!(at(1.0, 0.05), Some(ContactSubregion::Band));
        assert_eq!(at(1.0, -0.2), None);
        assert_eq!(at(-0.06, -0.06), Some(ContactSubregion::StartDisk));
        assert_eq!(at(-0.08, -0.08), None); // inside the band's corner square, not the disk
        assert_eq!(at(2.06, 0.06), Some(ContactSubregion::EndDisk));
        assert_eq!(at(2.2, 0.0), None);
    }

    #[test]
    fn entrance_filter_quasi_parallel() {
        let n = DVec2::new(0.0, -1.0);
        let s = (4f64).to_radians().sin();
        // A vertex whose edges leave it along +-x, tilted 2 degrees into the edge: passes.
        let t = 2f64.to_radians();
        let e_prev = DVec2::new(-t.cos(), t.sin());
        let e_next = DVec2::new(1.0, 0.0);
        assert!(entrance_filter(e_prev, e_next, n, s));
        // Tilted 6 degrees: fails.
        let t = 6f64.to_radians();
        assert!(!entrance_filter(
            DVec2::new(-t.cos(), t.sin()),
            e_next,
            n,
            s
        ));
    }
}
