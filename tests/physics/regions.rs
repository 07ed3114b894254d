//! A rock mass written as a region cut by joint sets behaves as its joints say:
//! `examples/planar-slope.toml`, a slope whose bedding dips 30 degrees out of its face,
//! stands when the joints' friction is above the dip and slides along the bedding when
//! it is below.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda::core::{Format, RunOptions, Scene, Simulation};
use dda::geom::DVec2;

const SLOPE: &str = include_str!("../../examples/planar-slope.toml");

/// Runs the slope with the joints' friction `phi` degrees; each free block's movement.
fn moves(phi: f64) -> Vec<(String, DVec2)> {
    let text = SLOPE.replace("friction_deg = 40.0", &format!("friction_deg = {phi}"));
    let (_, model) = Scene::parse(&text, Format::Toml, "planar-slope.toml").unwrap();
    let start: Vec<DVec2> = model.blocks.iter().map(|b| b.polygon.centroid()).collect();
    let ids: Vec<String> = model.blocks.iter().map(|b| b.id.clone()).collect();
    let fixed: Vec<bool> = model.blocks.iter().map(|b| b.fixed).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    sim.blocks()
        .iter()
        .enumerate()
        .filter(|(i, _)| !fixed[*i])
        .map(|(i, b)| (ids[i].clone(), b.polygon.centroid() - start[i]))
        .collect()
}

/// Friction 40 degrees, above the bedding's 30: no block moves by 5 mm in 0.5 s (the
/// flush-joint issue's standard for standing). Friction 20 degrees: the layer at the
/// face slides down the bedding, out of the face, at least half as far as a block on a
/// 30-degree plane would in 0.5 s, g (sin 30 - cos 30 tan 20) t^2 / 2 = 0.227 m, and
/// every block that slides goes down and out of the face.
#[test]
fn a_daylighting_bedding_slides_below_its_friction_and_stands_above() {
    let stood = moves(40.0);
    let most = stood.iter().map(|(_, d)| d.length()).fold(0.0, f64::max);
    assert!(most < 5e-3, "moved {most} m with friction 40 deg");

    let slid = moves(20.0);
    let (id, d) = slid
        .iter()
        .max_by(|a, b| a.1.length().total_cmp(&b.1.length()))
        .unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    let t = 0.5;
    let single = 0.5 * 9.81 * (s - c * 20f64.to_radians().tan()) * t * t;
    assert!(
        d.length() > 0.5 * single,
        "{id} moved {d:?}, a block would {single} m"
    );
    // Every block that slid went down and out of the face (towards -x, -y), none back
    // into the slope.
    for (id, d) in slid.iter().filter(|(_, d)| d.length() > 0.01) {
        assert!(d.x < 0.0 && d.y < 0.0, "{id} moved {d:?}");
    }
}
