//! Ground motion (docs/scene-format.md, "Seismic input"): the driven blocks follow the
//! record exactly, and a block resting on a moving base slips as Newmark's rigid
//! sliding block does.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda::core::{RunOptions, Scene, Simulation};
use dda::geom::DVec2;
use std::path::PathBuf;

/// Friction angle of the block on the base, degrees.
const PHI: f64 = 20.0;
const G: f64 = 9.81;

/// A directory of its own for a test's files.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("dda-seismic-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A half-sine pulse of the ground's x acceleration, `peak` m/s^2 over `length` s,
/// sampled every `dt_rec` s, zero after: (t, ax) rows.
fn pulse(peak: f64, length: f64, dt_rec: f64) -> Vec<(f64, f64)> {
    let n = (length / dt_rec).round() as usize;
    (0..=n)
        .map(|k| {
            let t = k as f64 * dt_rec;
            (t, peak * (std::f64::consts::PI * t / length).sin())
        })
        .collect()
}

/// Writes `rows` as a record file (header, then `t, ax, 0`) and a scene beside it: a
/// fixed 20 m x 1 m base and a 1 m block resting on it, friction PHI between them,
/// the base following the record; loads the scene through the file, as `dda run` does.
fn sliding_block(name: &str, rows: &[(f64, f64)], duration: f64) -> (Scene, dda::core::Model) {
    let dir = scratch(name);
    let mut csv = String::from("t, ax, ay\n");
    for (t, a) in rows {
        csv.push_str(&format!("{t:e}, {a:e}, 0\n"));
    }
    std::fs::write(dir.join("pulse.csv"), csv).unwrap();
    let scene = format!(
        r#"
name = "newmark"
[analysis]
duration = {duration}
time_step = 0.001
max_displacement = 0.002
normal_penalty = 1e10
gravity = [0.0, -{G}]
[materials.rock]
density = 2600.0
young = 1e10
poisson = 0.25
[joints.default]
friction_deg = {PHI}
[[blocks]]
id = "base"
material = "rock"
vertices = [[-10.0, -1.0], [10.0, -1.0], [10.0, 0.0], [-10.0, 0.0]]
fixed = true
[[blocks]]
id = "block"
material = "rock"
vertices = [[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]]
[seismic]
record = "pulse.csv"
"#
    );
    let path = dir.join("newmark.toml");
    std::fs::write(&path, scene).unwrap();
    let loaded = Scene::load(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    loaded
}

/// Runs the sliding-block `model` to its end under the physics guard: how far the base
/// and the block moved (their centroids).
fn run_guarded(model: dda::core::Model) -> [DVec2; 2] {
    let options = RunOptions {
        stop_on_violation: true,
        ..RunOptions::default()
    };
    let mut sim = Simulation::new(model, options);
    let start = [0, 1].map(|i| sim.blocks()[i].polygon.centroid());
    sim.run(|_, _| {}).unwrap();
    [0, 1].map(|i| sim.blocks()[i].polygon.centroid() - start[i])
}

/// Newmark's rigid block on a horizontal base with friction coefficient `mu`, under the
/// base acceleration `rows` held linear between samples: the slip s of the block
/// relative to the base. While it slides back (s' < 0) friction drives it forward at
/// mu g, so s'' = mu g - a; it starts when a exceeds mu g and stops when s' returns to
/// 0. Integrated by the trapezoidal rule at 1 microsecond (error far below 1e-6 m for
/// this smooth motion), independently of the engine.
fn newmark_slip(rows: &[(f64, f64)], mu: f64, duration: f64) -> f64 {
    let accel = |t: f64| -> f64 {
        let k = rows.partition_point(|r| r.0 <= t);
        if k == 0 || k == rows.len() {
            return 0.0;
        }
        let (a, b) = (rows[k - 1], rows[k]);
        a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
    };
    let h = 1e-6;
    let (mut s, mut v) = (0.0f64, 0.0f64);
    let n = (duration / h).round() as usize;
    for i in 0..n {
        let t = i as f64 * h;
        // Relative acceleration when sliding back; sticking otherwise.
        let rel = |t: f64, v: f64| {
            let a = accel(t);
            if v < 0.0 || a > mu * G {
                mu * G - a
            } else {
                0.0
            }
        };
        let a0 = rel(t, v);
        let v1 = v + h * a0;
        let a1 = rel(t + h, v1);
        let v_next = (v + 0.5 * h * (a0 + a1)).min(0.0);
        s += 0.5 * h * (v + v_next);
        v = v_next;
    }
    s
}

/// A record that exceeds g tan(phi) one way only (a half sine of twice that peak, 0.5 s
/// long, sampled at 5 ms): the block's slip relative to the base after the motion has
/// stopped matches Newmark's sliding-block integration within 2%. The base follows the
/// record exactly: its displacement is the record's double integral (a half sine's,
/// A T / pi (t - T/pi sin(pi t / T)) during it, the last velocity kept after).
#[test]
fn a_block_on_a_moving_base_slips_as_newmarks_sliding_block() {
    let mu = PHI.to_radians().tan();
    let (peak, length, duration) = (2.0 * mu * G, 0.5, 1.0);
    let rows = pulse(peak, length, 0.005);
    let (_, model) = sliding_block("newmark", &rows, duration);
    let effects = dda::core::Effects::of(&model).names();
    assert!(effects.contains(&"seismic"), "{effects:?}");
    let [base, block] = run_guarded(model);
    // The base: the piecewise-linear record's exact double integral; against the half
    // sine's closed form it differs by the chords' error, below 1e-4 relative at 5 ms.
    let v_end = peak * 2.0 * length / std::f64::consts::PI;
    let closed = peak * length / std::f64::consts::PI * length + v_end * (duration - length);
    assert!(
        (base.x - closed).abs() < 1e-4 * closed,
        "base moved {base}, closed form {closed}"
    );
    assert_eq!(base.y, 0.0);
    let slip = block.x - base.x;
    let expected = newmark_slip(&rows, mu, duration);
    assert!(expected < -0.05, "Newmark's slip {expected} m");
    assert!(
        (slip - expected).abs() < 0.02 * expected.abs(),
        "slip {slip} m, Newmark {expected} m"
    );
    // It sits on the base still: no bounce beyond the contact's resolution.
    assert!(block.y.abs() < 1e-3, "block rose {block}");
}

/// Below g tan(phi) the block does not slip: it rides on the base, within the shear
/// spring's give (m a / k_s).
#[test]
fn below_the_yield_acceleration_the_block_rides_on_the_base() {
    let mu = PHI.to_radians().tan();
    let rows = pulse(0.5 * mu * G, 0.5, 0.005);
    let (_, model) = sliding_block("rides", &rows, 0.6);
    let [base, block] = run_guarded(model);
    assert!(base.x > 0.1, "the base moved {base}");
    let slip = block.x - base.x;
    assert!(slip.abs() < 1e-4, "slipped {slip} m");
}

/// `examples/seismic-slope.toml`: a slope that stands under gravity (joints at 35
/// degrees, bedding at 30) slides out along its bedding when its ground shakes. The
/// crest's displacement relative to the ground: under the record more than 5 cm, within
/// 10 degrees of the bedding's dip and out of the face (to the left, down); with the
/// record scaled to nothing, less than 5 mm (the start settling onto the springs).
/// (Newmark's block on the bedding, g tan(35 - 30) = 0.86 m/s^2 to yield, slips 0.12 m
/// under this record; the crest moved 0.12 m.) The same with the open-close iteration
/// bounded at 20 instead of 6: before the settling began with steps whose inertia is the
/// penalty, its first static steps converged at the settling's full step there, the
/// slope's blocks slid into one another with their friction still unloaded, and the
/// slope stood through the record (the crest moved 3 mm).
#[test]
fn the_example_slope_slides_along_its_bedding_only_when_shaken() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/seismic-slope.toml");
    let (scene, _) = Scene::load(&path).unwrap();
    let crest = |scale: f64, max_oci: u32| {
        let mut scene = scene.clone();
        if let Some(s) = scene.seismic.as_mut() {
            s.scale = Some(scale);
        }
        scene.analysis.max_oci = max_oci;
        let model = scene.validate().unwrap();
        let point = model
            .measures
            .iter()
            .find(|m| m.id == "crest")
            .unwrap()
            .clone();
        let ground = model.blocks.iter().position(|b| b.id == "ground").unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        let g0 = sim.blocks()[ground].polygon.centroid();
        sim.run(|_, _| {}).unwrap();
        let ground_moved = sim.blocks()[ground].polygon.centroid() - g0;
        sim.material_point(point.block, point.at) - point.at - ground_moved
    };
    for max_oci in [scene.analysis.max_oci, 20] {
        let shaken = crest(1.0, max_oci);
        assert!(shaken.length() > 0.05, "max_oci {max_oci}: moved {shaken}");
        assert!(
            shaken.x < 0.0 && shaken.y < 0.0,
            "max_oci {max_oci}: {shaken}"
        );
        let dip = (shaken.y / shaken.x).atan().to_degrees();
        assert!(
            (dip - 30.0).abs() < 10.0,
            "max_oci {max_oci}: moved at {dip} degrees: {shaken}"
        );
    }
    let still = crest(0.0, scene.analysis.max_oci);
    assert!(still.length() < 5e-3, "moved {still} unshaken");
}
