//! Rigid-block statics of structures on a slope: whether a structure of rectangular
//! bricks can slide down a slope tilted past its friction angle as one body, the test
//! oracle of `stacks.rs`, independent of the engine.
//!
//! In the frame sliding with the structure at the closed form's acceleration
//! a = g (sin alpha - cos alpha tan phi), a brick's weight and inertia sum to
//! m g cos alpha (-tan phi, -1) in the slope's axes (x up the slope, y away from it): a
//! body force leaning down the slope at phi from the slope's normal. Divided by
//! rho g cos alpha, a brick of area A carries A (-mu, -1) at its centroid, mu = tan phi,
//! whatever the slope's angle. The structure slides as one body if contact forces exist
//! that hold every brick in equilibrium under it, with
//! - every contact pushing (N >= 0);
//! - every contact with the slope sliding: its friction mu N up the slope;
//! - every bed joint between bricks within its friction limit (|T| <= mu N);
//! - no friction relied upon in a head joint (the vertical joints between the bricks of
//!   a course): a head joint's normal force has no load path but the structure's own
//!   prestress, which a structure built unloaded does not have (with their friction, an
//!   end brick overhanging its course below by half its length counts as held, and
//!   topples in the engine and in the sliding frame alike).
//!
//! A linear feasibility problem (microlp): contact forces at the two ends of every
//! interface between bricks, and between a brick and the slope. Infeasible, some brick
//! or group must move relative to the others (tip or slip), and the closed form is not
//! every block's motion; feasible, nothing compels it to, and with a margin (the
//! structure feasible at a friction angle well above its own) the engine's blocks must
//! follow the closed form.

use microlp::{ComparisonOp, OptimizationDirection, Problem, Variable};

/// A brick as [x0, x1, y0, y1] in the slope's frame (x up the slope, y away from it; the
/// slope's surface at y = 0).
pub type Brick = [f64; 4];

/// Whether `bricks` can slide down a slope as one body at friction coefficient `mu` (see
/// the module docs).
pub fn slides_as_one_body(bricks: &[Brick], mu: f64) -> bool {
    let eps = 1e-9;
    let mut lp = Problem::new(OptimizationDirection::Minimize);
    // Per brick: its equilibrium's terms (x force, y force, moment about its centroid).
    let mut terms: Vec<[Vec<(Variable, f64)>; 3]> =
        (0..bricks.len()).map(|_| Default::default()).collect();
    // A contact force at point (px, py) with normal n (pushing brick `a`; brick `b`, if
    // any, takes the reaction), tangential friction as `friction` says.
    enum Friction {
        /// Sliding up the slope on brick `a`: T = mu N.
        Sliding,
        /// Within the limit: |T| <= mu N.
        Limited,
        /// None: T = 0.
        None,
    }
    let mut add = |a: usize, b: Option<usize>, p: [f64; 2], n: [f64; 2], friction: Friction| {
        let t = [-n[1], n[0]];
        let nv = lp.add_var(0.0, (0.0, f64::INFINITY));
        let tv = match friction {
            Friction::None => None,
            _ => Some(lp.add_var(0.0, (f64::NEG_INFINITY, f64::INFINITY))),
        };
        match friction {
            Friction::Sliding => {
                let tv = tv.expect("a tangential force");
                // T along t = (-n_y, n_x) = (-1, 0) for n = (0, 1): up the slope is -T.
                lp.add_constraint([(tv, 1.0), (nv, mu)], ComparisonOp::Eq, 0.0);
            }
            Friction::Limited => {
                let tv = tv.expect("a tangential force");
                lp.add_constraint([(tv, 1.0), (nv, -mu)], ComparisonOp::Le, 0.0);
                lp.add_constraint([(tv, -1.0), (nv, -mu)], ComparisonOp::Le, 0.0);
            }
            Friction::None => {}
        }
        for (brick, sign) in [(Some(a), 1.0), (b, -1.0)] {
            let Some(i) = brick else { continue };
            let [x0, x1, y0, y1] = bricks[i];
            let (rx, ry) = (p[0] - 0.5 * (x0 + x1), p[1] - 0.5 * (y0 + y1));
            let e = &mut terms[i];
            e[0].push((nv, sign * n[0]));
            e[1].push((nv, sign * n[1]));
            e[2].push((nv, sign * (rx * n[1] - ry * n[0])));
            if let Some(tv) = tv {
                e[0].push((tv, sign * t[0]));
                e[1].push((tv, sign * t[1]));
                e[2].push((tv, sign * (rx * t[1] - ry * t[0])));
            }
        }
    };
    for (i, &[x0, x1, y0, y1]) in bricks.iter().enumerate() {
        if y0.abs() < eps {
            for px in [x0, x1] {
                add(i, None, [px, y0], [0.0, 1.0], Friction::Sliding);
            }
        }
        for (j, &[u0, u1, v0, v1]) in bricks.iter().enumerate() {
            if j == i {
                continue;
            }
            // j below i: a bed joint.
            if (v1 - y0).abs() < eps {
                let (lo, hi) = (x0.max(u0), x1.min(u1));
                if hi - lo > eps {
                    for px in [lo, hi] {
                        add(i, Some(j), [px, y0], [0.0, 1.0], Friction::Limited);
                    }
                }
            }
            // j down the slope from i: a head joint.
            if (u1 - x0).abs() < eps {
                let (lo, hi) = (y0.max(v0), y1.min(v1));
                if hi - lo > eps {
                    for py in [lo, hi] {
                        add(i, Some(j), [x0, py], [1.0, 0.0], Friction::None);
                    }
                }
            }
        }
    }
    for (i, &[x0, x1, y0, y1]) in bricks.iter().enumerate() {
        let area = (x1 - x0) * (y1 - y0);
        let [fx, fy, m] = std::mem::take(&mut terms[i]);
        // Contact forces balance the body force A (-mu, -1) at the centroid.
        lp.add_constraint(fx, ComparisonOp::Eq, mu * area);
        lp.add_constraint(fy, ComparisonOp::Eq, area);
        lp.add_constraint(m, ComparisonOp::Eq, 0.0);
    }
    lp.solve().is_ok()
}

/// The largest friction angle, degrees, at which `bricks` can slide as one body (to
/// 0.01 degrees; 89 if at every angle tried): past it, on a slope past its friction
/// angle, some part of the structure tips or slips.
pub fn tipping_friction_deg(bricks: &[Brick]) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 89.0f64);
    if slides_as_one_body(bricks, hi.to_radians().tan()) {
        return hi;
    }
    while hi - lo > 0.01 {
        let mid = 0.5 * (lo + hi);
        if slides_as_one_body(bricks, mid.to_radians().tan()) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A column of n bricks w wide and h high slides as one body while its height over
    /// its width is below 1 / tan phi (the resultant of its leaning body force passes
    /// its toe): tan phi_crit = w / (n h), to the bisection's 0.01 degrees.
    #[test]
    fn a_column_tips_where_its_resultant_passes_its_toe() {
        for (n, w, h) in [(4, 1.0, 0.5), (3, 1.0, 0.5), (10, 2.0, 0.2), (1, 0.5, 0.8)] {
            let bricks: Vec<Brick> = (0..n)
                .map(|r| [0.0, w, r as f64 * h, (r + 1) as f64 * h])
                .collect();
            let exact = (w / (n as f64 * h)).atan().to_degrees();
            let found = tipping_friction_deg(&bricks);
            assert!(
                (found - exact).abs() < 0.02,
                "{n} x {w} x {h}: {found} against {exact}"
            );
        }
    }

    /// A brick overhanging the one below by half its length, with a neighbour up the
    /// slope in its course, has its centroid over the corner below: it tips at any
    /// friction, head joints bearing no friction; a single brick never tips below 45
    /// degrees of a square's diagonal.
    #[test]
    fn an_overhanging_brick_tips_at_any_friction() {
        let overhang = [
            [0.0, 2.0, 0.0, 0.5],
            [-1.0, 1.0, 0.5, 1.0],
            [1.0, 3.0, 0.5, 1.0],
        ];
        assert!(!slides_as_one_body(&overhang, 0.01));
        assert!(slides_as_one_body(&[[0.0, 1.0, 0.0, 1.0]], 0.99));
        assert!(!slides_as_one_body(&[[0.0, 1.0, 0.0, 1.0]], 1.01));
    }
}
