//! Rock bolts and measured points (docs/scene-format.md, "Bolts and measured points"):
//! a block hanging from a bolt stretches it by its weight over the stiffness; a bolt
//! weaker than the weight breaks at the first step and the block falls freely; a bolt
//! across a sliding plane holds a block that slides without it; a measured point in
//! rock an excavation removes ends with it, and the scene warns of it; a bar swinging
//! about a fixed point keeps its amplitude and period, and bodies turning about a fixed
//! point or on a bolt keep their energy.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use crate::by_hand::Turned;
use dda::core::{Format, RunOptions, Scene, Simulation};
use dda::geom::DVec2;

/// A 1 m x 1 m block (2600 kg/m^3) hanging 1.5 m below a fixed roof from a vertical bolt
/// of stiffness `k` between (0, 1.5) in the roof and (0, -0.6) in the block, with
/// `extra` lines added to the bolt, `mode` the analysis mode and `dt` the step.
fn hanging(mode: &str, k: f64, extra: &str, duration: f64, dt: f64) -> String {
    format!(
        r#"
name = "hanging"
[analysis]
mode = "{mode}"
duration = {duration}
time_step = {dt}
max_displacement = 0.01
normal_penalty = 1e9
gravity = [0.0, -9.81]
[materials.rock]
density = 2600.0
young = 1e10
poisson = 0.25
[[blocks]]
id = "roof"
material = "rock"
vertices = [[-1.0, 1.0], [1.0, 1.0], [1.0, 2.0], [-1.0, 2.0]]
fixed = true
[[blocks]]
id = "block"
material = "rock"
vertices = [[-0.5, -1.5], [0.5, -1.5], [0.5, -0.5], [-0.5, -0.5]]
[[bolts]]
from = [0.0, 1.5]
to = [0.0, -0.6]
stiffness = {k:e}
{extra}
[[measure]]
id = "foot"
at = [0.0, -1.5]
"#
    )
}

/// Static: the bolt's stretch, measured between its two material points, is m g / k =
/// 2600 x 9.81 / 1e7 = 2.55 mm, to 1e-6 relative.
#[test]
fn a_hanging_block_stretches_its_bolt_by_its_weight_over_the_stiffness() {
    let (_, model) = Scene::parse(
        &hanging("static", 1e7, "", 1.0, 0.01),
        Format::Toml,
        "h.toml",
    )
    .unwrap();
    let bolt = model.bolts[0].clone();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    let from = sim.material_point(bolt.from_block, bolt.from);
    let to = sim.material_point(bolt.to_block, bolt.to);
    let stretch = from.distance(to) - bolt.from.distance(bolt.to);
    let expected = 2600.0 * 9.81 / 1e7;
    assert!(
        (stretch - expected).abs() < 1e-6 * expected,
        "stretch {stretch} m, m g / k = {expected} m"
    );
    let tension = sim.bolt_tension(0).unwrap();
    assert!(
        (tension - 2600.0 * 9.81).abs() < 1e-6 * 2600.0 * 9.81,
        "{tension}"
    );
}

/// Dynamic, the bolt's strength half the weight and its stiffness (1e11 N/m) far above
/// the block's inertia over a step (2 m / dt^2 = 1.3e9 N/m at dt = 2 ms), so that the
/// first step loads it with nearly the whole weight (settled before the run, with all
/// of it): it breaks in that step, and the block falls freely from then on: in
/// T = 0.5 s its measured foot drops g T^2 / 2 = 1.226 m and moves at g T, less what
/// the first step held back, at most g dt T and g dt (settled, the bolt holds the block
/// through the first step exactly, and the stretch it settled into relaxes as the
/// block's strain rings: the foot's speed within 1e-6 of that).
#[test]
fn a_bolt_weaker_than_the_weight_breaks_and_the_block_falls() {
    let dt = 0.002;
    let text = hanging("dynamic", 1e11, "strength = 12753.0", 0.5, dt);
    let (_, model) = Scene::parse(&text, Format::Toml, "h.toml").unwrap();
    let foot = model.measures[0].clone();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.step().unwrap();
    let (t, force) = sim.bolt_states()[0]
        .broken
        .expect("broken at the first step");
    assert_eq!(t, sim.time());
    assert!(force > 12753.0, "{force}");
    assert_eq!(sim.bolt_tension(0), None);
    sim.run(|_, _| {}).unwrap();
    let (g, big_t) = (9.81, 0.5);
    let drop = foot.at.y - sim.material_point(foot.block, foot.at).y;
    let free_fall = 0.5 * g * big_t * big_t;
    assert!(
        drop <= free_fall * (1.0 + 1e-9) && drop >= free_fall - g * dt * big_t,
        "dropped {drop} m, free fall {free_fall} m"
    );
    let v = sim.material_velocity(foot.block, foot.at);
    assert!(
        -v.y <= g * big_t * (1.0 + 1e-9) && -v.y >= (g * big_t - g * dt) * (1.0 - 1e-6),
        "velocity {v:?}"
    );
    assert!(v.x.abs() < 1e-9, "{v:?}");
}

/// A block on a 35-degree plane with friction 20 degrees slides; with a bolt across the
/// plane, from the block down into the fixed base 2 m up the slope (so that sliding
/// stretches it), it stops: the bolt takes the out-of-balance force m g (sin 35 -
/// cos 35 tan 20) = 7.0 kN on a stiffness of 1e8 N/m, a tenth of a millimetre. Without
/// it, the block slides g (sin 35 - cos 35 tan 20) t^2 / 2 = 0.34 m in 0.5 s.
#[test]
fn a_bolt_across_a_sliding_plane_stops_the_block() {
    let (s, c) = 35f64.to_radians().sin_cos();
    // The plane through the origin rising at 35 degrees; the base below it, the block
    // (1 m square) on it at 2 m along.
    let along = DVec2::new(c, s);
    let up = DVec2::new(-s, c);
    let pt = |a: f64, b: f64| {
        let p = a * along + b * up;
        format!("[{}, {}]", p.x, p.y)
    };
    let scene = |bolt: &str| {
        format!(
            r#"
name = "plane"
[analysis]
duration = 0.5
time_step = 0.002
max_displacement = 0.002
normal_penalty = 1e10
gravity = [0.0, -9.81]
[materials.rock]
density = 2600.0
young = 1e10
poisson = 0.25
[joints.default]
friction_deg = 20.0
[[blocks]]
id = "base"
material = "rock"
vertices = [{}, {}, {}, {}]
fixed = true
[[blocks]]
id = "block"
material = "rock"
vertices = [{}, {}, {}, {}]
{bolt}
"#,
            pt(-1.0, -1.0),
            pt(6.0, -1.0),
            pt(6.0, 0.0),
            pt(-1.0, 0.0),
            pt(2.0, 0.0),
            pt(3.0, 0.0),
            pt(3.0, 1.0),
            pt(2.0, 1.0),
        )
    };
    let slide = |text: &str| {
        let (_, model) = Scene::parse(text, Format::Toml, "plane.toml").unwrap();
        let start = model.blocks[1].polygon.centroid();
        let mut sim = Simulation::new(model, RunOptions::default());
        sim.run(|_, _| {}).unwrap();
        (sim.blocks()[1].polygon.centroid() - start).length()
    };
    let free = slide(&scene(""));
    let expected = 0.5 * 9.81 * (s - c * 20f64.to_radians().tan()) * 0.25;
    assert!(free > 0.5 * expected, "slid {free} m without the bolt");
    let bolt = format!(
        "[[bolts]]\nfrom = {}\nto = {}\nstiffness = 1e8\n",
        pt(2.5, 0.5),
        pt(4.5, -0.8)
    );
    let held = slide(&scene(&bolt));
    assert!(held < 2e-3, "moved {held} m with the bolt");
}

/// A measured point in rock an excavation removes is followed until the removal and has
/// no rows after it, and the scene warns of it; a bolt with an end there is warned of
/// too (it goes with the rock). The hanging block's lower half (below y = -1, the
/// measured foot in it) is excavated at 0.1 s; in a second scene the bolt's lower end
/// is moved into that half.
#[test]
fn a_point_in_excavated_rock_ends_with_it_and_is_warned_of() {
    let excavation = r#"
[[excavations]]
id = "cut"
vertices = [[-1.0, -2.0], [1.0, -2.0], [1.0, -1.0], [-1.0, -1.0]]
at = 0.1
"#;
    let text = hanging("dynamic", 1e7, "", 0.2, 0.01) + excavation;
    let (_, model) = Scene::parse(&text, Format::Toml, "h.toml").unwrap();
    let keys: Vec<&str> = model.warnings.iter().map(|w| w.key.as_str()).collect();
    assert!(keys.contains(&"measure[0].at"), "{keys:?}");
    assert!(!keys.iter().any(|k| k.starts_with("bolts")), "{keys:?}");
    let mut sim = Simulation::new(model, RunOptions::default());
    let mut rows = Vec::new();
    sim.run(|s, _| rows.push((s.time(), dda::report::measurement_rows(s).len())))
        .unwrap();
    assert!(rows.iter().any(|&(t, _)| t > 0.15), "the run goes on");
    for (t, n) in rows {
        assert_eq!(n, usize::from(t < 0.1 - 1e-12), "{n} rows at t = {t}");
    }

    let moved = text.replace("to = [0.0, -0.6]", "to = [0.0, -1.2]");
    let (_, model) = Scene::parse(&moved, Format::Toml, "h.toml").unwrap();
    let bolt = model.warnings.iter().find(|w| w.key == "bolts[0].to");
    assert!(bolt.is_some_and(|w| w.message.contains("the bolt goes with it")));
}

/// A rigid steel bar 1 m x 0.2 m hanging from a fixed point at the middle of its top
/// edge, let go 10 degrees from the vertical, pulled either by gravity at its centroid
/// or by a point load of its weight at its lower end (no gravity): a physical pendulum
/// of period 2 pi sqrt(I / (m g d)) (I = m (L^2 / 3 + h^2 / 12) about the point, d = L /
/// 2 under gravity, L under the load), times 1 + a^2 / 16 + 11 a^4 / 3072 at amplitude
/// a; the step's error on it is of the order of (w dt)^2 (w = 2 pi / T, dt = 2 ms:
/// 5.8e-5 and 1.2e-4). Its energy is kept, so each swing reaches the same 0.9 sin 10
/// degrees with its point 0.9 m down the bar, to 1e-3. Before the lever arms of springs
/// held at a point and of loads were taken half way through the step's turn, the bar
/// gained 1.2% of its amplitude a swing under gravity (the guard stopped it at 2.3 s on
/// energy created) and 0.84% under the load (which the guard, counting the load's work
/// by the same rows, did not see).
#[test]
fn a_bar_swinging_about_a_fixed_point_keeps_its_amplitude_and_period() {
    let (l, h, g, a) = (1.0f64, 0.2f64, 9.81, 10f64.to_radians());
    let (s, c) = a.sin_cos();
    let along = |t: f64, w: f64| [s * t + c * w, -c * t + s * w];
    let corners = [
        along(0.0, -h / 2.0),
        along(0.0, h / 2.0),
        along(l, h / 2.0),
        along(l, -h / 2.0),
    ];
    // Counter-clockwise: the bar's top edge, then down its side.
    let vertices: Vec<String> = corners
        .iter()
        .rev()
        .map(|p| format!("[{:.12}, {:.12}]", p[0], p[1]))
        .collect();
    let (tip, end) = (along(0.9, 0.0), along(l, 0.0));
    let weight = 7800.0 * l * h * g;
    let gravity = format!("gravity = [0.0, -{g}]");
    let load = format!(
        "loads = [{{ at = [{:.12}, {:.12}], force = [0.0, -{weight}] }}]",
        end[0], end[1]
    );
    for (pull, analysis, block, arm) in [
        ("gravity", gravity.as_str(), "", l / 2.0),
        ("the load", "", load.as_str(), l),
    ] {
        let text = format!(
            r#"
name = "pendulum"
[analysis]
duration = 8.0
time_step = 0.002
max_displacement = 0.01
normal_penalty = 1e9
deformable = false
{analysis}
[materials.steel]
density = 7800.0
[[blocks]]
id = "bar"
material = "steel"
vertices = [{}]
fixed_points = [[0.0, 0.0]]
{block}
[[measure]]
id = "tip"
at = [{:.12}, {:.12}]
"#,
            vertices.join(", "),
            tip[0],
            tip[1]
        );
        let options = RunOptions {
            stop_on_violation: true,
            ..RunOptions::default()
        };
        let (_, model) = Scene::parse(&text, Format::Toml, "pendulum.toml").unwrap();
        let point = model.measures[0].clone();
        let mut sim = Simulation::new(model, options);
        let mut path = Vec::new();
        sim.run(|s, _| path.push((s.time(), s.material_point(point.block, point.at).x)))
            .unwrap_or_else(|e| panic!("{pull}: {e}"));
        // Each swing's reach to the right, and the times it passes the vertical going
        // left.
        let (mut reach, mut crossings) = (Vec::new(), Vec::new());
        let mut best = f64::NEG_INFINITY;
        for w in path.windows(2) {
            let ((t0, x0), (t1, x1)) = (w[0], w[1]);
            best = best.max(x1);
            if x0 > 0.0 && x1 <= 0.0 {
                crossings.push(t0 + x0 / (x0 - x1) * (t1 - t0));
                reach.push(best);
                best = f64::NEG_INFINITY;
            }
        }
        assert!(reach.len() >= 4, "{pull}: {} swings", reach.len());
        let expected = 0.9 * s;
        for r in &reach {
            assert!(
                (r / expected - 1.0).abs() <= 1e-3,
                "{pull}: reached {r} m, {expected} m: {reach:?}"
            );
        }
        let period0 =
            2.0 * std::f64::consts::PI * ((l * l / 3.0 + h * h / 12.0) / (g * arm)).sqrt();
        let period = period0 * (1.0 + a * a / 16.0 + 11.0 * a.powi(4) / 3072.0);
        let w_dt = 2.0 * std::f64::consts::PI / period * 0.002;
        for pair in crossings.windows(2) {
            let t = pair[1] - pair[0];
            assert!(
                (t / period - 1.0).abs() <= w_dt * w_dt,
                "{pull}: period {t} s, {period} s"
            );
        }
    }
}

/// A bar turning at 2 rad/s about a fixed point at its end, without gravity, and two
/// blocks joined by a stiff bolt (1e10 N/m) turning at 2 rad/s about their middle in
/// flight: uniform rotations, whose kinetic energy stays as it was. The step's predicted
/// turn is the turn it takes, so the springs' rows are exact to the second order and
/// the energy is kept to 1e-6 (measured: 1e-7). Before the lever arms of springs held at
/// a point, and the bolt's direction, were taken half way through the step's turn, both
/// gained some 0.6% of their energy a second at dt 2 ms.
#[test]
fn bodies_turning_about_a_fixed_point_or_on_a_bolt_keep_their_energy() {
    let header = r#"
name = "turning"
[analysis]
duration = 4.0
time_step = 0.002
max_displacement = 0.01
normal_penalty = 1e9
deformable = false
[materials.rock]
density = 2600.0
"#;
    let pinned = r#"
[[blocks]]
id = "bar"
material = "rock"
vertices = [[-0.1, -1.0], [0.1, -1.0], [0.1, 0.0], [-0.1, 0.0]]
fixed_points = [[0.0, 0.0]]
velocity = [1.0, 0.0]
angular_velocity = 2.0
"#;
    let bolted = r#"
[[blocks]]
id = "a"
material = "rock"
vertices = [[-1.2, -0.2], [-0.8, -0.2], [-0.8, 0.2], [-1.2, 0.2]]
velocity = [0.0, -2.0]
angular_velocity = 2.0
[[blocks]]
id = "b"
material = "rock"
vertices = [[0.8, -0.2], [1.2, -0.2], [1.2, 0.2], [0.8, 0.2]]
velocity = [0.0, 2.0]
angular_velocity = 2.0
[[bolts]]
from = [-0.81, 0.0]
to = [0.81, 0.0]
stiffness = 1e10
"#;
    for (name, blocks) in [("pinned", pinned), ("bolted", bolted)] {
        let text = format!("{header}{blocks}");
        let (_, model) = Scene::parse(&text, Format::Toml, "turning.toml").unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        let e0 = sim.kinetic_energy();
        let mut worst = 0.0f64;
        sim.run(|s, _| worst = worst.max((s.kinetic_energy() / e0 - 1.0).abs()))
            .unwrap();
        assert!(
            worst <= 1e-6,
            "{name}: kinetic energy off by {worst:e} of its start"
        );
    }
}

/// A point written on a face finds the block of that face: a bolt from the bottom face
/// of a block hung under a roof to the roof's top face, and a measured point on the
/// block's side face, the scene turned 58.7 degrees and written to 6 decimals, so that
/// each point lies up to 7e-7 m off its face, outside the rock as often as in it. Each
/// is attached to the block whose face it is on; a point in the rock goes to the block
/// holding it, even where another is within 2e-6 m (a point written 1.5e-6 m into the
/// block from the roof's face lies 1.2e-6 m inside it and 1.4e-6 m outside the roof,
/// which comes first). Until 2026-11-27 a point had to lie
/// within 1e-9 of a block's size of it, and all three were refused as lying in no block.
#[test]
fn a_point_written_on_a_face_finds_its_block() {
    let hand = Turned::new(58.7);
    let (turn, outline) = (|x, y| hand.written(x, y), |p: &[_]| hand.outline(p));
    let text = format!(
        "name = \"on faces\"\n[analysis]\nduration = 0.01\ntime_step = 0.002\n\
         max_displacement = 0.001\nnormal_penalty = 1e10\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e10\npoisson = 0.25\n\
         [[blocks]]\nid = \"roof\"\nmaterial = \"rock\"\nfixed = true\nvertices = {}\n\
         [[blocks]]\nid = \"key\"\nmaterial = \"rock\"\nvertices = {}\n\
         [[bolts]]\nfrom = {}\nto = {}\nstiffness = 1e8\n\
         [[measure]]\nid = \"side\"\nat = {}\n\
         [[measure]]\nid = \"in the key\"\nat = {}\n",
        outline(&[(-2.0, 0.0), (2.0, 0.0), (2.0, 1.0), (-2.0, 1.0)]),
        outline(&[(-0.5, -1.0), (0.5, -1.0), (0.5, 0.0), (-0.5, 0.0)]),
        turn(0.3, -1.0),
        turn(0.3, 1.0),
        turn(0.5, -0.37),
        turn(0.2, -0.0000015),
    );
    let (_, model) = Scene::parse(&text, Format::Toml, "faces.toml").unwrap();
    let (roof, key) = (0, 1);
    assert_eq!(
        (model.bolts[0].from_block, model.bolts[0].to_block),
        (key, roof)
    );
    assert_eq!(model.measures[0].block, key);
    assert_eq!(model.measures[1].block, key);
}
