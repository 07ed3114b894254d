//! Trajectory tracking in open-close iteration (paper section 2.3.2, eq. 12-13).
//!
//! When a vertex goes from outside an edge's line (d_n0 > 0 at step start) to inside it
//! (d_n1 < 0 in the trial solution), the point where its trajectory crosses the line, in
//! the frame moving with the edge, has ratio r(t) = r0 + t (r1 - r0) at
//! t = d_n0 / (d_n0 - d_n1). The vertex entered through this edge when 0 <= r(t) <= 1;
//! the paper splits the two bounds into three cases each, compared here by
//! cross-multiplication so no ratio divides by zero.

use dda_geom::VertexEdge;

/// Which case of paper eq. 12 puts the crossing forward of b_j (r(t) >= 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Forward {
    /// Eq. 12a: r0 > 0 and r1 >= 0.
    A,
    /// Eq. 12b: r0 > 0, r1 < 0 and |r0 / r1| >= |d0 / d1|.
    B,
    /// Eq. 12c: r0 <= 0, r1 > 0 and |r0 / r1| <= |d0 / d1|.
    C,
}

/// Which case of paper eq. 13 puts the crossing backward of b_j+1 (r(t) <= 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backward {
    /// Eq. 13a: r0 > 1, r1 < 1 and |(r0 - 1) / (r1 - 1)| <= |d0 / d1|.
    A,
    /// Eq. 13b: r0 <= 1, r1 > 1 and |(r0 - 1) / (r1 - 1)| >= |d0 / d1|.
    B,
    /// Eq. 13c: r0 <= 1 and r1 <= 1.
    C,
}

/// Paper eq. 12: the case that holds, or `None` when the crossing is behind b_j.
pub fn forward(r0: f64, r1: f64, d0: f64, d1: f64) -> Option<Forward> {
    let (d0, d1) = (d0.abs(), d1.abs());
    if r0 > 0.0 && r1 >= 0.0 {
        Some(Forward::A)
    } else if r0 > 0.0 && r1 < 0.0 && r0.abs() * d1 >= r1.abs() * d0 {
        Some(Forward::B)
    } else if r0 <= 0.0 && r1 > 0.0 && r0.abs() * d1 <= r1.abs() * d0 {
        Some(Forward::C)
    } else {
        None
    }
}

/// Paper eq. 13: the case that holds, or `None` when the crossing is beyond b_j+1.
pub fn backward(r0: f64, r1: f64, d0: f64, d1: f64) -> Option<Backward> {
    let (d0, d1) = (d0.abs(), d1.abs());
    let (s0, s1) = (r0 - 1.0, r1 - 1.0);
    if r0 > 1.0 && r1 < 1.0 && s0.abs() * d1 <= s1.abs() * d0 {
        Some(Backward::A)
    } else if r0 <= 1.0 && r1 > 1.0 && s0.abs() * d1 >= s1.abs() * d0 {
        Some(Backward::B)
    } else if r0 <= 1.0 && r1 <= 1.0 {
        Some(Backward::C)
    } else {
        None
    }
}

/// Whether the vertex entered through this edge segment between the step start and the
/// trial (triggered only by d_n0 > 0 and d_n1 < 0).
pub fn enters_through(start: VertexEdge, trial: VertexEdge) -> bool {
    start.d_n > 0.0
        && trial.d_n < 0.0
        && forward(start.r, trial.r, start.d_n, trial.d_n).is_some()
        && backward(start.r, trial.r, start.d_n, trial.d_n).is_some()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// r at the crossing, computed directly, for checking the cases.
    fn r_cross(r0: f64, r1: f64, d0: f64, d1: f64) -> f64 {
        let t = d0 / (d0 - d1);
        r0 + t * (r1 - r0)
    }

    #[test]
    fn each_forward_case() {
        // (r0, r1, d0, d1) chosen by hand; d0 > 0 > d1 throughout.
        assert_eq!(forward(0.5, 0.2, 1.0, -1.0), Some(Forward::A));
        // 12b: r goes 0.6 -> -0.2 crossing at t = 0.5: r = 0.2 >= 0.
        assert_eq!(forward(0.6, -0.2, 1.0, -1.0), Some(Forward::B));
        assert!(r_cross(0.6, -0.2, 1.0, -1.0) >= 0.0);
        // Not 12b: 0.2 -> -0.6 crosses at r = -0.2.
        assert_eq!(forward(0.2, -0.6, 1.0, -1.0), None);
        // 12c: -0.2 -> 0.6 crosses at r = 0.2.
        assert_eq!(forward(-0.2, 0.6, 1.0, -1.0), Some(Forward::C));
        // Not 12c: -0.6 -> 0.2 crosses at r = -0.2.
        assert_eq!(forward(-0.6, 0.2, 1.0, -1.0), None);
        assert_eq!(forward(-0.1, -0.3, 1.0, -1.0), None);
    }

    #[test]
    fn each_backward_case() {
        // 13a: 1.2 -> 0.6 with d 1 -> -1 crosses at r = 0.9 <= 1.
        assert_eq!(backward(1.2, 0.6, 1.0, -1.0), Some(Backward::A));
        // Not 13a: 1.6 -> 0.8 crosses at 1.2.
        assert_eq!(backward(1.6, 0.8, 1.0, -1.0), None);
        // 13b: 0.6 -> 1.2 crosses at 0.9.
        assert_eq!(backward(0.6, 1.2, 1.0, -1.0), Some(Backward::B));
        // Not 13b: 0.9 -> 1.5 crosses at 1.2.
        assert_eq!(backward(0.9, 1.5, 1.0, -1.0), None);
        assert_eq!(backward(0.3, 0.9, 1.0, -1.0), Some(Backward::C));
        assert_eq!(backward(1.1, 1.3, 1.0, -1.0), None);
    }

    #[test]
    fn unequal_depths_weigh_the_crossing() {
        // d0 = 0.1, d1 = -0.3: t = 0.25. r 0.4 -> -0.8 crosses at r = 0.1: forward (12b).
        assert_eq!(forward(0.4, -0.8, 0.1, -0.3), Some(Forward::B));
        assert!((r_cross(0.4, -0.8, 0.1, -0.3) - 0.1).abs() < 1e-15);
        let m = |d_n, r| VertexEdge { d_n, r };
        assert!(enters_through(m(0.1, 0.4), m(-0.3, -0.8)));
        // Same path from inside: no trigger.
        assert!(!enters_through(m(-0.1, 0.4), m(-0.3, -0.8)));
    }

    #[test]
    fn cases_agree_with_the_crossing_ratio() {
        // A grid of trajectories: the two tests accept exactly when 0 <= r(t) <= 1.
        let vals = [-1.3, -0.5, -0.1, 0.0, 0.2, 0.5, 0.9, 1.0, 1.1, 1.7];
        for &r0 in &vals {
            for &r1 in &vals {
                for &(d0, d1) in &[(1.0, -1.0), (0.2, -0.7), (0.9, -0.1)] {
                    let rc = r_cross(r0, r1, d0, d1);
                    let ok =
                        forward(r0, r1, d0, d1).is_some() && backward(r0, r1, d0, d1).is_some();
                    // Exactly on a node the paper's strict inequalities may go either way.
                    if (rc.abs() > 1e-12) && ((rc - 1.0).abs() > 1e-12) {
                        assert_eq!(ok, (0.0..=1.0).contains(&rc), "r0 {r0} r1 {r1} d {d0} {d1}");
                    }
                }
            }
        }
    }
}
