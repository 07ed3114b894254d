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
//! a spring of stiffness p holding a distance d stores p d^2 / 2, so d <= sqrt(2.02 E0 / p)
//! =: d_E. The spring measures d to first order in the step's motion (docs/method.md) while
//! blocks move with the exact rotation, so the overlap after a step can exceed the
//! spring's d by the second-order part of the step's gap, d = (P - E0) x (E1 - E0) / l for
//! vertex P and edge E0 E1 of length l. With B fixed and A turned by theta <= theta_max:
//! - a point at radius rho from A's centroid lies e(theta) rho from its first-order
//!   position, e = |(1 - cos theta, theta - sin theta)|: at most e r_A for P or E0 on A;
//! - E1 - E0 on A differs from its first-order value by e l <= e l_A (A's longest edge),
//!   against |P - E0| <= l_A + d (r in [0, 1]; d <= d_E + d_tol);
//! - the product of the first-order motions, (u_P - u_0) x (u_1 - u_0) / l: with the edge
//!   on A, u_P = 0, |u_0| <= d_max and |u_1 - u_0| <= theta l; with the edge on B, zero.
//!
//! So the overlap is at most d_E + e(theta_max) (r_A + l_A + d_E + d_tol) + d_max
//! theta_max. That is the bound for rows linearised at step start. The engine linearises at
//! the step's predicted midpoint (`dda_core::springs`), where the second-order part missed
//! is q''(D - D_pred) D / 2 rather than q'' D D / 2: no larger while the prediction D_pred
//! errs by less than the step's own motion D, which we assume here rather than prove. (The
//! first failure of this test without the second term: two chamfered squares at 0.1 m/s,
//! theta 1.9 deg per step, overlap 3.4e-5 m against 1.0e-5 m; without the third, a
//! chamfered square sliding along a 7.5 deg wedge with steps of 16 mm, overlap 5.7e-4 m
//! against 2.4e-4 m.)
//!
//! Three properties:
//!
//! - `no_nan_no_panic`, over the whole range: every run ends with finite states.
//! - `cover_keeps_hard_pairs_physical`: energy and the overlap bound over the whole range
//!   of tolerances, with penalties stiff enough for the contact tolerance, i.e. the
//!   penetration they allow, d_E, is below d_tol (the paper's working rule, section 2.6).
//! - `soft_penalties_keep_the_overlap_bound`: the same with penalties from 1e6 N/m up to
//!   that, too soft for d_tol, where penetrations go deeper than d_tol.
//!
//! And two sets of cases the sampling found (see there):
//! `a_wedge_rocking_deep_in_a_plate_creates_no_energy` and
//! `a_block_spinning_in_contact_creates_no_energy`.
//!
//! The properties run a fixed sample of 256 cases each (seeded: `polygons::config`;
//! `PROPTEST_RNG_SEED` draws another), so that CI sees the same cases every run. Wider
//! samples are drawn outside CI: 10,000 pairs over the whole range (`pair()` with a
//! deterministic runner, every penalty) all kept the energy within 1% and the overlap
//! bound once contact rows were linearised at the step's predicted midpoint
//! (`dda_core::springs`); with the step-start rows, 2 of the first 4,000 created energy.

#![allow(clippy::unwrap_used)]

use dda::bench::{collision_scene, judge_collision, paper_analysis};
use dda::core::{RunOptions, Scene, Simulation};
use proptest::prelude::*;
use proptest::test_runner::TestCaseError;

use dda_geom::test_support as polygons;

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

/// The bound on the blocks' overlap (see the module docs), for a run of `model` whose
/// initial kinetic energy is `e0`.
fn overlap_bound(model: &dda::core::Model, e0: f64) -> f64 {
    let p = &model.params;
    let a = &model.blocks[0].polygon;
    let v = a.vertices();
    let r_a = v
        .iter()
        .map(|x| x.distance(a.centroid()))
        .fold(0.0, f64::max);
    let l_a = (0..v.len())
        .map(|i| v[i].distance(v[(i + 1) % v.len()]))
        .fold(0.0, f64::max);
    let t = p.theta_max;
    let e = (1.0 - t.cos()).hypot(t - t.sin());
    let d_e = (2.02 * e0 / p.normal_penalty).sqrt();
    d_e + e * (r_a + l_a + d_e + p.d_tol) + p.d_max * t
}

/// The pair `p` with its penalty exponent mapped from the drawn [6, 11] onto
/// [lo, hi], where `lo` and `hi` are given as functions of the least penalty that keeps
/// the penetration d_E within d_tol; `None` if that range is empty.
fn with_penalty(mut p: Pair, range: impl Fn(f64) -> (f64, f64)) -> Option<Pair> {
    let probe = p.scene().validate().unwrap();
    let d_tol = probe.params.d_tol;
    let e0 = Simulation::new(probe, RunOptions::default()).kinetic_energy();
    let floor = (2.02 * e0 / (d_tol * d_tol)).log10();
    let (lo, hi) = range(floor);
    if lo >= hi {
        return None;
    }
    p.log_penalty = lo + (p.log_penalty - 6.0) / 5.0 * (hi - lo);
    Some(p)
}

/// Runs `p` and returns the outcome with the overlap bound.
fn run(p: &Pair) -> (dda::bench::Outcome, f64) {
    let model = p.scene().validate().unwrap();
    let mut sim = Simulation::new(model.clone(), RunOptions::default());
    let bound = overlap_bound(&model, sim.kinetic_energy());
    (judge_collision(&mut sim), bound)
}

/// The physical outcome the properties ask of a run (see the module docs): finite, no
/// energy created beyond 1%, the overlap within `bound`, and the run not stopped.
fn physical(o: &dda::bench::Outcome, bound: f64) -> Result<(), TestCaseError> {
    prop_assert!(o.velocity.iter().all(|v| v.is_finite()), "{:?}", o);
    prop_assert!(o.max_energy_ratio <= 1.01, "energy created: {:?}", o);
    prop_assert!(
        o.max_overlap <= bound,
        "overlap {} above {}: {:?}",
        o.max_overlap,
        bound,
        o
    );
    prop_assert!(
        !o.failures.iter().any(|f| f.starts_with("the run stopped")),
        "{:?}",
        o
    );
    Ok(())
}

proptest! {
    #![proptest_config(polygons::config(256))]

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
        // Penalties from the least that keeps the penetration within d_tol up to 1e11.
        let p = with_penalty(p, |floor| (floor.max(6.0), 11.0));
        prop_assume!(p.is_some());
        let (o, bound) = run(&p.unwrap());
        physical(&o, bound)?;
    }

    #[test]
    fn soft_penalties_keep_the_overlap_bound(p in pair()) {
        // Penalties from 1e6 up to the least that keeps the penetration within d_tol.
        let p = with_penalty(p, |floor| (6.0, floor.min(11.0)));
        prop_assume!(p.is_some());
        let (o, bound) = run(&p.unwrap());
        physical(&o, bound)?;
    }
}

/// Two wedges thrown base first onto thin plates with penalties too soft for d_tol (the
/// energy allows 2.5 and 3 times d_tol of penetration), found by sampling the `pair()`
/// strategy: the base rocks on the plate 10 to 20 mm deep, and the vertex that is deepest
/// changes within a step. With the spring left on the vertex deepest at step start, they
/// gained 7.5% and 14% of their energy; the spring must follow the deepest face during
/// the open-close iteration.
#[test]
fn a_wedge_rocking_deep_in_a_plate_creates_no_energy() {
    let cases = [
        Pair {
            a: Shape::Wedge(17.714694236154322),
            b: Shape::Flat(81.98802842690074),
            turn_a: 3.3792069856756526,
            turn_b: 0.09200745125965928,
            from: 1.2838672210743738,
            aim: 0.2980776739661445,
            gap: 0.036568581631742925,
            speed: 9.361572589373823,
            tol_factor: 2.784508766079231,
            log_penalty: 7.234363851787796,
        },
        Pair {
            a: Shape::Wedge(19.599557695120648),
            b: Shape::Flat(52.761215357938),
            turn_a: 5.769421512368453,
            turn_b: 2.7753939229931146,
            from: 1.465614345725081,
            aim: -0.10561402841536707,
            gap: 0.02647102670972748,
            speed: 6.086004803450507,
            tol_factor: 1.0770764346295874,
            log_penalty: 7.4768514029322715,
        },
    ];
    for p in &cases {
        let (o, bound) = run(p);
        physical(&o, bound).unwrap();
    }
}

/// Three cases the sampling found in which a block spins at about theta_max per step
/// (20-30 rad/s) while a spring presses on it: a wedge on a chamfered square's corner
/// with a penalty too soft for d_tol, a plate on a wedge's tip and two 3 degree wedges
/// sliding tip on flank, both with stiff penalties and tolerances 5-6.5 times the basic
/// one. With rows linearised at step start they gained 3.3%, 1.04% and 8.4% of their
/// energy: each step moved a point at radius rho theta^2 rho / 2 nearer than the spring
/// saw, and the spring's force did work no motion paid for (see `dda_core::springs`).
#[test]
fn a_block_spinning_in_contact_creates_no_energy() {
    let cases = [
        Pair {
            a: Shape::Wedge(17.583049040987316),
            b: Shape::Chamfered(0.03196803885922779),
            turn_a: 4.18140485826902,
            turn_b: 4.430482905249157,
            from: 0.5025403186151896,
            aim: -0.002118052973339787,
            gap: 0.0382864804223564,
            speed: 4.815943765972649,
            tol_factor: 4.5498166135051825,
            log_penalty: 6.182357714326068,
        },
        Pair {
            a: Shape::Flat(7.990432631662983),
            b: Shape::Wedge(4.74934533090693),
            turn_a: 4.175825183468409,
            turn_b: 6.068241151988675,
            from: 1.6216460129983956,
            aim: -0.09651340048863692,
            gap: 0.03931863626319402,
            speed: 6.601266577570028,
            tol_factor: 6.4800344757805135,
            log_penalty: 7.338087644651385,
        },
        // Drawn by the stiff property, whose penalty range maps log_penalty 6 to the
        // least penalty that keeps d_E within d_tol.
        with_penalty(
            Pair {
                a: Shape::Wedge(3.0),
                b: Shape::Wedge(3.0),
                turn_a: 0.7652467695371143,
                turn_b: 4.333305438191978,
                from: 4.140999676518209,
                aim: 0.0,
                gap: 0.005,
                speed: 4.154136102452844,
                tol_factor: 5.536319753574476,
                log_penalty: 6.0,
            },
            |floor| (floor.max(6.0), 11.0),
        )
        .unwrap(),
    ];
    for p in &cases {
        let (o, bound) = run(p);
        physical(&o, bound).unwrap();
    }
}
