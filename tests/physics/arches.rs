//! Masonry arches of voussoirs under their own weight: a thick semicircular arch stands,
//! and a thin one collapses by hinges (its voussoirs turning about their corners)
//! without the contact law creating energy.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use crate::guarded;
use dda::core::{Format, Scene};
use std::fmt::Write;

/// The start of a scene of stone blocks (E = 20 GPa) under gravity, joints at `friction`
/// degrees, for `duration` s: a fixed ground 1 m deep from x = -`half_width` to
/// `half_width`, its top at y = 0.
fn stone_scene(name: &str, duration: f64, friction: f64, half_width: f64) -> String {
    format!(
        r#"name = "{name}"
[analysis]
duration = {duration}
time_step = 0.002
max_displacement = 0.002
normal_penalty = 1e10
gravity = [0.0, -9.81]
[materials.stone]
density = 2400
young = 2e10
poisson = 0.2
[joints.default]
friction_deg = {friction}
[[blocks]]
id = "ground"
material = "stone"
fixed = true
vertices = [[{a:?}, -1.0], [{b:?}, -1.0], [{b:?}, 0.0], [{a:?}, 0.0]]
"#,
        a = -half_width,
        b = half_width
    )
}

/// Appends a free stone block `id` of `vertices` (counter-clockwise) to scene `s`.
fn push_block(s: &mut String, id: &str, vertices: &[[f64; 2]]) {
    let v: Vec<String> = vertices
        .iter()
        .map(|p| format!("[{:.15}, {:.15}]", p[0], p[1]))
        .collect();
    let _ = write!(
        s,
        "[[blocks]]\nid = \"{id}\"\nmaterial = \"stone\"\nvertices = [{}]\n",
        v.join(", ")
    );
}

/// A semicircular arch of `n` voussoirs, centre-line radius 1 m, thickness `t`, on a
/// fixed base, joints at 40 degrees of friction, deformable stone (E = 20 GPa), for
/// `duration` s.
fn arch(n: usize, t: f64, duration: f64) -> String {
    let mut s = stone_scene("arch", duration, 40.0, 2.0 + t / 2.0);
    for (k, v) in voussoirs(n, t).iter().enumerate() {
        push_block(&mut s, &format!("v{k}"), v);
    }
    s
}

/// The voussoirs of [`arch`], from the left springing to the right: each one's corners
/// counter-clockwise, intrados then extrados (inner at its left joint, inner at its
/// right joint, outer at its right joint, outer at its left joint).
fn voussoirs(n: usize, t: f64) -> Vec<[[f64; 2]; 4]> {
    let (ri, ro) = (1.0 - t / 2.0, 1.0 + t / 2.0);
    let angle = |j: usize| std::f64::consts::PI * (1.0 - j as f64 / n as f64);
    (0..n)
        .map(|k| {
            let (a0, a1) = (angle(k), angle(k + 1));
            [(ri, a0), (ri, a1), (ro, a1), (ro, a0)].map(|(r, a)| [r * a.cos(), r * a.sin()])
        })
        .collect()
}

/// Runs the arch under the physics guard (a step that creates energy beyond 1% of the
/// reference, or penetrates beyond d_tol, is an error); how far its crown's voussoir
/// fell.
fn crown_drop(n: usize, t: f64, duration: f64) -> f64 {
    crown_drop_detected(n, t, duration, "cover")
}

/// [`crown_drop`] with the contact detector named.
fn crown_drop_detected(n: usize, t: f64, duration: f64, detector: &str) -> f64 {
    let scene = arch(n, t, duration).replacen(
        "[analysis]\n",
        &format!("[analysis]\ndetector = \"{detector}\"\n"),
        1,
    );
    drop_of(
        &scene,
        1 + n / 2,
        &format!("{n} voussoirs, t = {t} m, {detector}"),
    )
}

/// A semicircular arch thicker than Heyman's least thickness under its own weight
/// (t / R = 0.1075 for a continuous arch; voussoirs can only turn at their joints, which
/// only holds it better) stands: nine voussoirs at t / R = 0.15, the crown within 1 mm
/// of where it was after 1 s. Nine at t / R = 0.08 collapse, hinges opening at the
/// joints, and the run keeps the guard to its end (its crown fell 0.81 m in 2 s,
/// measured; more than 0.5 m asserted). Before a sliding contact kept from locking slid back against its reversed
/// motion, a hinge's contacts there slipped 0.44 mm a step with their friction pushing
/// along, and the run stopped at 0.22 s on 12% of its reference energy created
/// (`dda_core::contact_law::end_cycle`).
#[test]
fn a_thick_arch_stands_and_a_thin_one_collapses_keeping_the_energy() {
    let stood = crown_drop(9, 0.15, 1.0);
    assert!(stood.abs() < 1e-3, "the thick arch's crown fell {stood} m");
    let fell = crown_drop(9, 0.08, 2.0);
    assert!(fell > 0.5, "the thin arch's crown fell {fell} m");
}

/// The thick arch stands under the conventional detectors too. Its joints' extrados
/// corners are acute (80 degrees), and the joints' compression pushes each past the
/// other voussoir's outer face (by c cos alpha, nanometres): the type-based detectors'
/// rule that a vertex outside the other block has no contact dropped each joint's
/// extrados end, every joint became a hinge about its intrados corner, and the arch fell
/// (its crown 0.91 m in 1 s under type-1, 0.89 m under type-2, measured) until the
/// contact Shi's rule picks for a flush joint's end was kept (`dda_contact::territory`,
/// docs/method.md section 5).
#[test]
fn a_thick_arch_stands_under_the_type_based_detectors() {
    for detector in ["type-1", "type-2"] {
        let stood = crown_drop_detected(9, 0.15, 1.0, detector);
        assert!(stood.abs() < 1e-3, "{detector}: the crown fell {stood} m");
    }
}

/// The user's arch of 2026-11-27: 13 voussoirs (intrados radius 3 m, 0.6 m deep) on two
/// free piers 0.6 m x 2 m standing on fixed ground, 60 kN down at the quarter span's
/// extrados, friction 35 degrees. Under the load it is a mechanism: the loaded haunch
/// turns in, the far pier tips about its toe, and the settling's static steps move
/// steadily. Taken back round after round by its groups' mean translations as if it
/// slid, the arch was lifted off its piers, the energy supplied fell to -8.8 J/m
/// against 4.6 J/m of strain energy, and the run stopped at its first step on energy
/// created. A mechanism is not taken back (`Simulation::was_a_slide`): the run
/// keeps the guard, and the arch collapses (the crown falls).
#[test]
fn a_settled_arch_on_free_piers_under_a_point_load_keeps_the_energy() {
    let (n, ri, ro) = (13usize, 3.0f64, 3.6f64);
    let mut s = stone_scene("arch-on-piers", 0.2, 35.0, 6.0);
    push_block(
        &mut s,
        "pier-right",
        &[[3.0, 0.0], [3.6, 0.0], [3.6, 2.0], [3.0, 2.0]],
    );
    push_block(
        &mut s,
        "pier-left",
        &[[-3.6, 0.0], [-3.0, 0.0], [-3.0, 2.0], [-3.6, 2.0]],
    );
    let at = |r: f64, a: f64| [r * a.cos(), 2.0 + r * a.sin()];
    for k in 0..n {
        let (a0, a1) = (
            std::f64::consts::PI * k as f64 / n as f64,
            std::f64::consts::PI * (k + 1) as f64 / n as f64,
        );
        // Counter-clockwise: inner at a0, outer at a0, outer at a1, inner at a1; the
        // springings exactly on the piers.
        let mut v = [at(ri, a0), at(ro, a0), at(ro, a1), at(ri, a1)];
        if k == 0 {
            (v[0], v[1]) = ([3.0, 2.0], [3.6, 2.0]);
        }
        if k == n - 1 {
            (v[2], v[3]) = ([-3.6, 2.0], [-3.0, 2.0]);
        }
        push_block(&mut s, &format!("v{k}"), &v);
        if k == 9 {
            let p = at(ro - 0.05, 0.5 * (a0 + a1));
            let _ = writeln!(
                s,
                "loads = [{{ at = [{}, {}], force = [0.0, -60000.0] }}]",
                p[0], p[1]
            );
        }
    }
    let fell = drop_of(&s, 3 + n / 2, "the arch on piers");
    assert!(
        fell > 1e-3,
        "the loaded arch's crown fell {fell} m in 0.2 s"
    );
}

/// The collapse load, by the kinematic theorem of limit analysis, of a downward point
/// load at `at` on voussoir `loaded` of an arch whose joint `j` runs from `joints[j][0]`
/// (intrados) to `joints[j][1]` (extrados), voussoir `k` lying between joints `k` and
/// `k + 1` and the ground beyond joints 0 and n, the voussoirs of `areas` and `centroids`
/// weighing `weight` N per m^2: the least load whose work balances the weight's over
/// every mechanism of four hinges (rigid voussoirs, turning about a corner of a joint
/// that opens, and no sliding), infinite if none is driven by it. Computed here by
/// virtual work, apart from the engine: three rigid segments between the hinges, the
/// outer two turning about their hinges at the supports' side, the middle one about the
/// intersection of the lines through its neighbours' hinges.
fn limit_load(
    joints: &[[[f64; 2]; 2]],
    areas: &[f64],
    centroids: &[[f64; 2]],
    weight: f64,
    loaded: usize,
    at: [f64; 2],
) -> f64 {
    let n = areas.len();
    // The velocity of point p of a body turning at w about c.
    let turn = |w: f64, c: [f64; 2], p: [f64; 2]| [-w * (p[1] - c[1]), w * (p[0] - c[0])];
    // The rate of turn about c that moves point p at velocity v (its component across
    // the arm c p).
    let rate = |v: [f64; 2], c: [f64; 2], p: [f64; 2]| {
        let r = [p[0] - c[0], p[1] - c[1]];
        (-v[0] * r[1] + v[1] * r[0]) / (r[0] * r[0] + r[1] * r[1])
    };
    let mut least = f64::INFINITY;
    for a in 0..=n {
        for b in a + 1..=n {
            for c in b + 1..=n {
                for d in c + 1..=n {
                    for sides in 0..16u32 {
                        let side = |i: u32| ((sides >> i) & 1) as usize;
                        let h = [
                            joints[a][side(0)],
                            joints[b][side(1)],
                            joints[c][side(2)],
                            joints[d][side(3)],
                        ];
                        // The middle segment's centre: lines h0 h1 and h2 h3 meet.
                        let (e1, e2) = (
                            [h[1][0] - h[0][0], h[1][1] - h[0][1]],
                            [h[3][0] - h[2][0], h[3][1] - h[2][1]],
                        );
                        let den = e1[0] * e2[1] - e1[1] * e2[0];
                        if den.abs() < 1e-12 {
                            continue;
                        }
                        let s = ((h[2][0] - h[0][0]) * e2[1] - (h[2][1] - h[0][1]) * e2[0]) / den;
                        let centre = [h[0][0] + s * e1[0], h[0][1] + s * e1[1]];
                        let w1 = 1.0;
                        let w2 = rate(turn(w1, h[0], h[1]), centre, h[1]);
                        let w3 = rate(turn(w2, centre, h[2]), h[3], h[2]);
                        // Voussoir k's velocity at p (the ground's beyond the hinges).
                        let v = |k: usize, p: [f64; 2]| {
                            if k < a || k >= d {
                                [0.0, 0.0]
                            } else if k < b {
                                turn(w1, h[0], p)
                            } else if k < c {
                                turn(w2, centre, p)
                            } else {
                                turn(w3, h[3], p)
                            }
                        };
                        // Every hinge opens: the corner across the joint from it moves
                        // away from the voussoir before (or the ground), one way for all
                        // four.
                        let mut opening = [0.0; 4];
                        for (i, &j) in [a, b, c, d].iter().enumerate() {
                            let q = joints[j][1 - side(i as u32)];
                            let after = if j < n { v(j, q) } else { [0.0, 0.0] };
                            let before = if j > 0 { v(j - 1, q) } else { [0.0, 0.0] };
                            // The joint's normal, from the voussoir before it to the one after.
                            let inner = if j < n { centroids[j] } else { q };
                            let outer = if j > 0 { centroids[j - 1] } else { q };
                            let t = [q[0] - h[i][0], q[1] - h[i][1]];
                            let mut normal = [-t[1], t[0]];
                            let toward = [inner[0] - outer[0], inner[1] - outer[1]];
                            if normal[0] * toward[0] + normal[1] * toward[1] < 0.0 {
                                normal = [t[1], -t[0]];
                            }
                            opening[i] = (after[0] - before[0]) * normal[0]
                                + (after[1] - before[1]) * normal[1];
                        }
                        let sign = if opening.iter().all(|&o| o >= -1e-12) {
                            1.0
                        } else if opening.iter().all(|&o| o <= 1e-12) {
                            -1.0
                        } else {
                            continue;
                        };
                        // Work rates of the weight and of a unit load, both downward.
                        let own: f64 = (0..n)
                            .map(|k| -weight * areas[k] * v(k, centroids[k])[1])
                            .sum::<f64>()
                            * sign;
                        let load = -v(loaded, at)[1] * sign;
                        if load > 1e-12 && -own / load >= 0.0 {
                            least = least.min(-own / load);
                        }
                    }
                }
            }
        }
    }
    least
}

/// How far block `block`'s centroid fell in the run of `scene` under the physics guard
/// (a step that creates energy beyond 1% of the reference, or penetrates beyond d_tol,
/// is an error, which names the run as `what`).
fn drop_of(scene: &str, block: usize, what: &str) -> f64 {
    let (_, model) = Scene::parse(scene, Format::Toml, "arch.toml").unwrap();
    let y0 = model.blocks[block].polygon.centroid().y;
    let mut sim = guarded(model);
    sim.run(|_, _| {}).unwrap_or_else(|e| panic!("{what}: {e}"));
    y0 - sim.blocks()[block].polygon.centroid().y
}

/// A point load on an arch: it stands below the collapse load that limit analysis gives
/// (`limit_load`, the least over the mechanisms of four hinges) and collapses above it.
/// Nine voussoirs at t / R = 0.15, friction 40 degrees, the load at the extrados of the
/// crown's voussoir and of the second voussoir beside it. The rigid-block limit
/// analysis leaves out what the engine adds: the contact springs (a hinge's corner
/// sinks by its force over the penalty, 1e-6 of the depth), the stone's strain (1e-5)
/// and the contact law's band (1e-3 of a block's forces), so the engine's threshold
/// lies within a few thousandths of the limit load; just above it a mechanism starts
/// slowly, and 3% above it the loaded voussoir falls by more than a centimetre in the
/// second the run lasts. Measured: 9e-6 m and 7e-6 m at 0.97 (the stone's own strain),
/// 0.91 m and 0.42 m at 1.03; on a 15-voussoir arch of 5 m radius (rigid, friction 45
/// degrees) standing at 0.99 and falling at 1.01 of the limit load under the cover
/// detector, and at 0.97 and 1.03 under the type-based detectors and with deformable
/// voussoirs (not measured closer).
#[test]
fn an_arch_under_a_point_load_stands_below_its_limit_load_and_collapses_above_it() {
    let (n, t) = (9, 0.15);
    let stones = voussoirs(n, t);
    let joints: Vec<[[f64; 2]; 2]> = (0..=n)
        .map(|j| {
            if j < n {
                [stones[j][0], stones[j][3]]
            } else {
                [stones[n - 1][1], stones[n - 1][2]]
            }
        })
        .collect();
    let (areas, centroids): (Vec<f64>, Vec<[f64; 2]>) = stones
        .iter()
        .map(|v| {
            let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
            for i in 0..4 {
                let (p, q) = (v[i], v[(i + 1) % 4]);
                let c = p[0] * q[1] - q[0] * p[1];
                (a, cx, cy) = (a + c, cx + (p[0] + q[0]) * c, cy + (p[1] + q[1]) * c);
            }
            (a / 2.0, [cx / (3.0 * a), cy / (3.0 * a)])
        })
        .unzip();
    for loaded in [n / 2, n / 2 + 2] {
        let v = stones[loaded];
        let at = [(v[2][0] + v[3][0]) / 2.0, (v[2][1] + v[3][1]) / 2.0];
        let limit = limit_load(&joints, &areas, &centroids, 2400.0 * 9.81, loaded, at);
        assert!(limit.is_finite(), "voussoir {loaded}: no mechanism");
        let fall = |share: f64| {
            let mut s = stone_scene("arch", 1.0, 40.0, 2.0 + t / 2.0);
            for (k, v) in stones.iter().enumerate() {
                push_block(&mut s, &format!("v{k}"), v);
                if k == loaded {
                    let _ = writeln!(
                        s,
                        "loads = [{{ at = [{:.15}, {:.15}], force = [0.0, {:.6}] }}]",
                        at[0],
                        at[1],
                        -share * limit
                    );
                }
            }
            // The ground is block 0.
            drop_of(
                &s,
                1 + loaded,
                &format!("voussoir {loaded} at {share} of the limit"),
            )
        };
        let (below, above) = (fall(0.97), fall(1.03));
        println!("voussoir {loaded}: limit {limit:.1} N/m, drops {below:.3e} m and {above:.3e} m");
        assert!(
            below.abs() < 1e-3,
            "voussoir {loaded}: fell {below} m at 0.97 of {limit} N/m"
        );
        assert!(
            above > 1e-2,
            "voussoir {loaded}: fell {above} m at 1.03 of {limit} N/m"
        );
    }
}
