//! Property tests of hard pairs with the cover detector: a moving block A thrown at a fixed
//! block B, both drawn from sharp wedges (tip 3-20 deg), squares with chamfered corners
//! (chamfer edges 1e-3 to 1e-1 m) and flat plates (aspect ratio up to 100), at random
//! offsets, orientations, approach directions and speeds up to 10 m/s, with contact
//! tolerances 0.1 to 10 times the basic one (Table 3's rule: d_tol = 2 d_max, d_max = 0.1 x
//! the smallest edge) and penalties 1e6 to 1e11 N/m.
//!
//! Every run must complete without NaN or panic, create no energy beyond 1% (kinetic plus
//! elastic), and keep the blocks' geometric overlap within the bound the penalty sets on
//! the initial kinetic energy E0. No more than E0 (+1%) can be stored in the springs, and
//! a spring of stiffness p holding a distance d stores p d^2 / 2, so d <= sqrt(2.02 E0 / p).
//! The spring measures d to first order in the step's motion (DESIGN 3) while blocks
//! move with the exact rotation: a vertex at radius r from A's centroid turned by theta
//! lies (1 - cos theta) r nearer the centroid than the first-order motion puts it, at
//! most (1 - cos theta_max) r_A in a step. The geometric overlap after any step is
//! therefore at most sqrt(2.02 E0 / p) + (1 - cos theta_max) r_A (the first failure of
//! this test without the second term: two chamfered squares at 0.1 m/s, theta 1.9 deg
//! per step, overlap 3.4e-5 m against 1.0e-5 m).
//!
//! Two properties:
//!
//! - `no_nan_no_panic`, over the whole range: every run ends with finite states.
//! - `cover_keeps_hard_pairs_physical`: energy and the overlap bound, where the penalty is
//!   stiff enough for the contact tolerance, i.e. the penetration it allows,
//!   sqrt(2.02 E0 / p), is below d_tol (the paper's working rule, section 2.6: d_tol must
//!   exceed the penetration), and for tolerances 0.1 to 1 times the basic one. Outside
//!   that range the tests found, and we leave open (see the issue notes): penetrations
//!   beyond d_tol that carry a vertex past its edge onto one the distance filter no longer
//!   lists, so the blocks pass through each other (a chamfered square onto a 3 deg wedge at
//!   2 m/s, p = 1.9e7, d_tol = 0.46 mm); and, with tolerances 1-10 times the basic one
//!   (steps up to the smallest edge), overlaps up to 1.6 times the bound and an energy
//!   gain of about 4% while a wedge slides along a plate.

#![allow(clippy::unwrap_used)]

use dda::bench::{collision_scene, judge_collision, paper_analysis};
use dda::core::{RunOptions, Scene, Simulation};
use proptest::prelude::*;

/// A shape, centred at its centroid-ish origin, before rotation.
#[derive(Clone, Debug)]
enum Shape {
    /// Isosceles triangle, tip angle in degrees, 0.5 m long.
    Wedge(f64),
    /// 0.3 m square with every corner chamfered into an edge of this length, m.
    Chamfered(f64),
    /// 1 m plate of this aspect ratio (length / thickness).
    Flat(f64),
}

impl Shape {
    fn vertices(&self) -> Vec<[f64; 2]> {
        match *self {
            Shape::Wedge(tip) => {
                let h = 0.5 * (tip.to_radians() / 2.0).tan();
                vec![[-0.25, -h], [0.25, 0.0], [-0.25, h]]
            }
            Shape::Chamfered(e) => {
                let c = e / 2f64.sqrt();
                let s = 0.15;
                vec![
                    [-s + c, -s],
                    [s - c, -s],
                    [s, -s + c],
                    [s, s - c],
                    [s - c, s],
                    [-s + c, s],
                    [-s, s - c],
                    [-s, -s + c],
                ]
            }
            Shape::Flat(aspect) => {
                let t = 0.5 / aspect;
                vec![[-0.5, -t], [0.5, -t], [0.5, t], [-0.5, t]]
            }
        }
    }
}

fn shape() -> impl Strategy<Value = Shape> {
    prop_oneof![
        (3.0..20.0f64).prop_map(Shape::Wedge),
        (-3.0..-1.0f64).prop_map(|e| Shape::Chamfered(10f64.powf(e))),
        (1.0..100.0f64).prop_map(Shape::Flat),
    ]
}

/// Rotates by `angle` and moves to `at`.
fn place(v: &[[f64; 2]], angle: f64, at: [f64; 2]) -> Vec<[f64; 2]> {
    let (s, c) = angle.sin_cos();
    v.iter()
        .map(|p| [at[0] + c * p[0] - s * p[1], at[1] + s * p[0] + c * p[1]])
        .collect()
}

/// The largest distance of a vertex from the origin.
fn radius(v: &[[f64; 2]]) -> f64 {
    v.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max)
}

/// One random collision.
#[derive(Clone, Debug)]
struct Pair {
    a: Shape,
    b: Shape,
    turn_a: f64,
    turn_b: f64,
    from: f64,
    aim: f64,
    gap: f64,
    speed: f64,
    tol_factor: f64,
    log_penalty: f64,
}

fn pair() -> impl Strategy<Value = Pair> {
    (
        shape(),
        shape(),
        (0.0..std::f64::consts::TAU, 0.0..std::f64::consts::TAU),
        0.0..std::f64::consts::TAU,
        -0.3..0.3f64,
        0.005..0.05f64,
        0.1..10.0f64,
        (-1.0..1.0f64, 6.0..11.0f64),
    )
        .prop_map(
            |(a, b, (turn_a, turn_b), from, aim, gap, speed, (tol, log_penalty))| Pair {
                a,
                b,
                turn_a,
                turn_b,
                from,
                aim,
                gap,
                speed,
                tol_factor: 10f64.powf(tol),
                log_penalty,
            },
        )
}

impl Pair {
    fn scene(&self) -> Scene {
        let (va, vb) = (self.a.vertices(), self.b.vertices());
        let dist = radius(&va) + radius(&vb) + self.gap;
        let dir = [self.from.cos(), self.from.sin()];
        let a = place(&va, self.turn_a, [dist * dir[0], dist * dir[1]]);
        let b = place(&vb, self.turn_b, [0.0, 0.0]);
        // Towards B, turned by up to 0.3 rad.
        let (s, c) = self.aim.sin_cos();
        let v = [
            -self.speed * (c * dir[0] - s * dir[1]),
            -self.speed * (s * dir[0] + c * dir[1]),
        ];
        // The basic tolerance of the paper's Table 3: twice a max displacement of 0.1 x
        // the smallest edge of the two blocks.
        let shortest = [&va, &vb]
            .iter()
            .flat_map(|v| {
                (0..v.len()).map(move |i| {
                    let (p, q) = (v[i], v[(i + 1) % v.len()]);
                    (q[0] - p[0]).hypot(q[1] - p[1])
                })
            })
            .fold(f64::INFINITY, f64::min);
        let d_tol = 0.2 * shortest * self.tol_factor;
        let d_max = 0.5 * d_tol;
        // Long enough to reach B and leave it again.
        let duration = ((2.0 * dist + 1.0) / self.speed).min(2.0);
        let analysis = paper_analysis(
            duration,
            d_max / self.speed,
            d_max,
            d_tol,
            10f64.powf(self.log_penalty),
            None,
        );
        collision_scene("hard-pair", a, b, v, analysis)
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn no_nan_no_panic(p in pair()) {
        let model = p.scene().validate().unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        let o = judge_collision(&mut sim);
        prop_assert!(o.velocity.iter().chain(&o.centroid).all(|v| v.is_finite()), "{:?}", o);
        prop_assert!(!o.failures.iter().any(|f| f.contains("not finite")), "{:?}", o);
    }

    #[test]
    fn cover_keeps_hard_pairs_physical(p in pair()) {
        // Tolerances 0.1 to 1 times the basic one: map the drawn exponent [-1, 1] to [-1, 0].
        let mut p = p;
        p.tol_factor = 10f64.powf(-1.0 + 0.5 * (p.tol_factor.log10() + 1.0));
        let probe = p.scene().validate().unwrap();
        let d_tol = probe.params.d_tol;
        let e0 = Simulation::new(probe, RunOptions::default()).kinetic_energy();
        // Penalties from the least that keeps the penetration within d_tol up to 1e11:
        // map the drawn exponent [6, 11] onto [lowest, 11].
        let lowest = (2.02 * e0 / (d_tol * d_tol)).log10().max(6.0);
        prop_assume!(lowest < 11.0);
        p.log_penalty = lowest + (p.log_penalty - 6.0) / 5.0 * (11.0 - lowest);
        let model = p.scene().validate().unwrap();
        let penalty = model.params.normal_penalty;
        let theta_max = model.params.theta_max;
        let a = &model.blocks[0].polygon;
        let r_a = a.vertices().iter().map(|v| v.distance(a.centroid())).fold(0.0, f64::max);
        let mut sim = Simulation::new(model, RunOptions::default());
        let allowed = (2.02 * e0 / penalty).sqrt();
        let o = judge_collision(&mut sim);
        prop_assert!(o.velocity.iter().all(|v| v.is_finite()), "{:?}", o);
        prop_assert!(o.max_energy_ratio <= 1.01, "energy created: {:?}", o);
        let bound = allowed + (1.0 - theta_max.cos()) * r_a;
        prop_assert!(o.max_overlap <= bound, "overlap {} above {}: {:?}", o.max_overlap, bound, o);
        prop_assert!(!o.failures.iter().any(|f| f.starts_with("the run stopped")), "{:?}", o);
    }
}
