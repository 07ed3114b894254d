//! Scenes with a closed-form answer, for accuracy studies (`cargo xtask accuracy`): free
//! fall, a block sliding down an incline with friction, a block dropped onto a fixed
//! base that bounces back, and two blocks meeting head on. Each comes with its exact answer and a measure of a run's
//! error against it. Rock of density 2600 kg/m^3, E = 1 GPa, nu = 0.25; g = 9.81 m/s^2.

use crate::column::{rock, rock_block as block};
use dda_core::Simulation;
use dda_core::scene::{Analysis, BlockSpec, Joint, Mode, Plane, Scene};
use dda_geom::DVec2;
use std::collections::BTreeMap;

/// Gravity of the analytic scenes, m/s^2.
pub const G: f64 = 9.81;

/// The analysis of an analytic scene: dynamic, cover detector, deformable in plane
/// stress, max rotation 2 deg, 6 OCI iterations, no frames; contact tolerance 2 d_max
/// (Table 3's rule) unless `d_tol` is given; settling before the run as a user's scene
/// does (`settle` unset; `cargo xtask accuracy` states `settle = false`, to measure the
/// time stepping from the unloaded start).
pub fn analytic_analysis(
    duration: f64,
    time_step: f64,
    d_max: f64,
    d_tol: Option<f64>,
    penalty: f64,
) -> Analysis {
    Analysis {
        mode: Mode::Dynamic,
        duration,
        time_step,
        max_displacement: d_max,
        max_rotation_deg: 2.0,
        contact_tolerance: d_tol,
        normal_penalty: penalty,
        shear_penalty: None,
        fixed_penalty: None,
        detector: "cover".into(),
        gravity: Some([0.0, -G]),
        deformable: true,
        plane: Plane::Stress,
        max_oci: 6,
        frames: 0,
        impact_steps: None,
        integration: None,
        settle: None,
        solver: None,
        contact_damping: None,
    }
}

fn scene(name: &str, analysis: Analysis, friction_deg: f64, blocks: Vec<BlockSpec>) -> Scene {
    Scene {
        name: name.into(),
        analysis,
        materials: rock(2600.0, 1e9, 0.25),
        joints: BTreeMap::from([(
            "default".into(),
            Joint {
                friction_deg,
                ..Joint::default()
            },
        )]),
        blocks,
        joint_sets: BTreeMap::new(),
        regions: Vec::new(),
        excavations: Vec::new(),
        bolts: Vec::new(),
        measure: Vec::new(),
        seismic: None,
    }
}

/// A unit square thrown at (1.5, 2.0) m/s, falling freely: centroid
/// (0.5 + 1.5 t, 0.5 + 2 t - g t^2 / 2).
pub fn free_fall(analysis: Analysis) -> Scene {
    let mut b = block(
        "block",
        vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        false,
    );
    b.velocity = Some([1.5, 2.0]);
    scene("free-fall", analysis, 0.0, vec![b])
}

/// Relative error of a free-fall run: centroid distance from the exact one over the
/// distance travelled.
pub fn free_fall_error(sim: &Simulation) -> f64 {
    let t = sim.time();
    let exact = DVec2::new(0.5 + 1.5 * t, 0.5 + 2.0 * t - 0.5 * G * t * t);
    let c = sim.blocks()[0].polygon.centroid();
    (c - exact).length()
        / (exact - DVec2::new(0.5, 0.5))
            .length()
            .max(f64::MIN_POSITIVE)
}

/// Slope of the incline, degrees.
pub const INCLINE_DEG: f64 = 30.0;
/// Friction angle of the incline's joint, degrees.
pub const INCLINE_FRICTION_DEG: f64 = 20.0;

/// A unit square at rest on a fixed 30 deg incline with friction 20 deg: it slides
/// g (sin 30 - cos 30 tan 20) t^2 / 2 down the slope.
pub fn incline(analysis: Analysis) -> Scene {
    let (s, c) = INCLINE_DEG.to_radians().sin_cos();
    let u = DVec2::new(c, s);
    let n = DVec2::new(-s, c);
    let p = |v: DVec2| [v.x, v.y];
    let base = block(
        "incline",
        vec![p(-5.0 * u - n), p(5.0 * u - n), p(5.0 * u), p(-5.0 * u)],
        true,
    );
    let slider = block("slider", vec![p(DVec2::ZERO), p(u), p(u + n), p(n)], false);
    scene(
        "incline",
        analysis,
        INCLINE_FRICTION_DEG,
        vec![base, slider],
    )
}

/// Relative error of an incline run: displacement along the slope against
/// g (sin - cos tan phi) t^2 / 2.
pub fn incline_error(sim: &Simulation) -> f64 {
    let (s, c) = INCLINE_DEG.to_radians().sin_cos();
    let u = DVec2::new(c, s);
    let start = 0.5 * (u + DVec2::new(-s, c));
    let t = sim.time();
    let exact = -0.5 * G * (s - c * INCLINE_FRICTION_DEG.to_radians().tan()) * t * t;
    let moved = (sim.blocks()[1].polygon.centroid() - start).dot(u);
    (moved - exact).abs() / exact.abs().max(f64::MIN_POSITIVE)
}

/// Height of the drop in [`rebound`], m.
pub const DROP: f64 = 0.5;

/// A unit square released `DROP` above a fixed frictionless base: it falls, bounces and,
/// as the contact is elastic, rises back to where it started, at
/// t = 2 sqrt(2 DROP / g) = 0.639 s. The block is rigid (`deformable = false`), the
/// body that answer is for: a deformable block keeps part of the impact's energy as
/// the vibration of its strain (docs/method.md section 12).
pub fn rebound(mut analysis: Analysis) -> Scene {
    analysis.deformable = false;
    let base = block(
        "base",
        vec![[-3.0, -1.0], [4.0, -1.0], [4.0, 0.0], [-3.0, 0.0]],
        true,
    );
    let y = DROP;
    let b = block(
        "block",
        vec![[0.0, y], [1.0, y], [1.0, y + 1.0], [0.0, y + 1.0]],
        false,
    );
    scene("rebound", analysis, 0.0, vec![base, b])
}

/// Tracks the apex of a [`rebound`] run (its last block): call [`Rebound::step`] after
/// every step.
#[derive(Debug, Default, Clone, Copy)]
pub struct Rebound {
    bounced: bool,
    apex: f64,
}

impl Rebound {
    /// Records the state after a step.
    pub fn step(&mut self, sim: &Simulation) {
        let Some(b) = sim.blocks().last() else {
            return;
        };
        if b.velocity[1] > 0.0 {
            self.bounced = true;
        }
        if self.bounced {
            self.apex = self.apex.max(b.polygon.centroid().y - 0.5);
        }
    }

    /// Relative error of the apex (the bottom's height after the bounce) against the drop
    /// height; 1 if it never bounced.
    pub fn error(&self) -> f64 {
        if self.bounced {
            (self.apex - DROP).abs() / DROP
        } else {
            1.0
        }
    }
}

/// Two unit squares on a line, 0.5 mm apart, without gravity or friction, the left one
/// moving right at 1 m/s: elastic contact springs between rigid blocks
/// (`deformable = false`) exchange their velocities (restitution 1). Deformable blocks
/// keep part of the energy as the vibration of their strain (docs/method.md section 12).
pub fn collision(mut analysis: Analysis) -> Scene {
    analysis.gravity = None;
    analysis.deformable = false;
    let mut left = block(
        "left",
        vec![
            [-1.0005, 0.0],
            [-0.0005, 0.0],
            [-0.0005, 1.0],
            [-1.0005, 1.0],
        ],
        false,
    );
    left.velocity = Some([1.0, 0.0]);
    let right = block(
        "right",
        vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
        false,
    );
    scene("collision", analysis, 0.0, vec![left, right])
}

/// The restitution of a [`collision`] run (the last two blocks' relative speed along x
/// over the 1 m/s they met at, at the end) or of a [`rebound`] run (the block's largest
/// upward speed after the impact over sqrt(2 g DROP), the speed it struck at): call
/// [`Restitution::step`] after every step.
#[derive(Debug, Default, Clone, Copy)]
pub struct Restitution {
    rebound_speed: f64,
    relative_speed: f64,
}

impl Restitution {
    /// Records the state after a step.
    pub fn step(&mut self, sim: &Simulation) {
        let b = sim.blocks();
        if let [.., a, z] = b {
            self.rebound_speed = self.rebound_speed.max(z.velocity[1]);
            self.relative_speed = z.velocity[0] - a.velocity[0];
        }
    }

    /// The restitution of a collision run.
    pub fn collision(&self) -> f64 {
        self.relative_speed
    }

    /// The restitution of a rebound run.
    pub fn rebound(&self) -> f64 {
        self.rebound_speed / (2.0 * G * DROP).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_core::RunOptions;

    fn sim(scene: Scene) -> Simulation {
        let model = scene.validate().expect("valid analytic scene");
        Simulation::new(model, RunOptions::default())
    }

    /// At t = 0 every measure compares the start with itself: free fall and incline
    /// errors are 0/0 guarded to 0, and the rebound has not bounced (error 1).
    #[test]
    fn scenes_validate_and_errors_start_where_they_should() {
        let a = analytic_analysis(1.0, 0.01, 0.005, None, 1e9);
        assert_eq!(free_fall_error(&sim(free_fall(a.clone()))), 0.0);
        assert_eq!(incline_error(&sim(incline(a.clone()))), 0.0);
        let mut r = Rebound::default();
        r.step(&sim(rebound(a)));
        assert_eq!(r.error(), 1.0);
    }

    /// The rebound's block falls DROP in sqrt(2 DROP / g) = 0.319 s; after 0.2 s it has
    /// not reached the base, and the free-fall law holds to rounding (the scheme is
    /// exact for a constant force), so the apex tracker has still seen no bounce.
    #[test]
    fn rebound_block_falls_freely_before_the_impact() {
        let mut s = sim(rebound(analytic_analysis(0.2, 0.01, 0.005, None, 1e9)));
        let mut r = Rebound::default();
        s.run(|s, _| r.step(s)).expect("run");
        let y = s.blocks()[1].polygon.centroid().y;
        let exact = DROP + 0.5 - 0.5 * G * 0.2 * 0.2;
        assert!((y - exact).abs() < 1e-9, "{y} vs {exact}");
        assert_eq!(r.error(), 1.0);
    }
}
