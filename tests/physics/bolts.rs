//! Rock bolts and measured points (docs/scene-format.md, "Bolts and measured points"):
//! a block hanging from a bolt stretches it by its weight over the stiffness; a bolt
//! weaker than the weight breaks at the first step and the block falls freely; a bolt
//! across a sliding plane holds a block that slides without it; a measured point in
//! rock an excavation removes ends with it, and the scene warns of it.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

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
