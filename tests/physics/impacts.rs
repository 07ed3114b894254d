//! Impacts resolved in time (`analysis.impact_steps`, docs/method.md section 12).
//!
//! Closed forms: two equal rigid blocks meeting head on, frictionless, with elastic
//! penalty springs, part with their velocities exchanged (restitution 1, momentum
//! kept); a rigid block dropped on a fixed base rebounds with its impact speed. With
//! `impact_steps = 10` (and the average-acceleration rule it brings) both are met
//! within 5%, while the constant-acceleration rule with whole-step contacts loses a
//! quarter to a half of the speed. Elastic blocks keep part of the impact's energy as
//! vibration (strain), which is the model's physics, not a loss: their kinetic plus
//! strain energy is kept.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use crate::guarded;
use dda::core::{Format, Model, RunOptions, Scene, Simulation, guard};

/// Two 1 m squares 0.5 mm apart on a line, no gravity, frictionless, the left one
/// moving right at 1 m/s (p = 1e9 N/m, dt 5 ms, d_max 5 mm: the issue's setting);
/// `analysis` lines added to [analysis], `rock` to the material.
fn collision(analysis: &str, rock: &str) -> Model {
    let text = format!(
        r#"
name = "collision"
[analysis]
duration = 0.02
time_step = 0.005
max_displacement = 0.005
normal_penalty = 1e9
{analysis}
[materials.rock]
density = 2600.0
{rock}
[[blocks]]
id = "left"
material = "rock"
vertices = [[-1.0005, 0.0], [-0.0005, 0.0], [-0.0005, 1.0], [-1.0005, 1.0]]
velocity = [1.0, 0.0]
[[blocks]]
id = "right"
material = "rock"
vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
"#
    );
    Scene::parse(&text, Format::Toml, "collision.toml")
        .unwrap()
        .1
}

/// The drop's block: a 1 m square whose base is 0.5 m above the fixed base.
const SQUARE: &str = r#"
[[blocks]]
id = "block"
material = "rock"
vertices = [[0.0, 0.5], [1.0, 0.5], [1.0, 1.5], [0.0, 1.5]]
"#;

/// A 1 m square whose base is 0.5 m above a fixed base, dropped from rest under
/// gravity, frictionless (p = 1e10 N/m, dt 1 ms, d_max 1 mm: the issue's setting).
fn drop(analysis: &str, rock: &str) -> Model {
    drop_of(analysis, rock, SQUARE)
}

/// The drop of `blocks` (TOML `[[blocks]]` entries) onto the fixed base.
fn drop_of(analysis: &str, rock: &str, blocks: &str) -> Model {
    let text = format!(
        r#"
name = "drop"
[analysis]
duration = 0.45
time_step = 0.001
max_displacement = 0.001
normal_penalty = 1e10
gravity = [0.0, -9.81]
{analysis}
[materials.rock]
density = 2600.0
{rock}
[[blocks]]
id = "base"
material = "rock"
vertices = [[-2.0, -1.0], [3.0, -1.0], [3.0, 0.0], [-2.0, 0.0]]
fixed = true
{blocks}"#
    );
    Scene::parse(&text, Format::Toml, "drop.toml").unwrap().1
}

const RIGID: &str = "deformable = false";
const NO_ELASTICITY: &str = "";

/// Kinetic plus strain energy of the free blocks, J/m.
fn mechanical(sim: &Simulation) -> f64 {
    let m = sim.model();
    let mut e = sim.kinetic_energy();
    if sim.effects().elasticity {
        for (b, mb) in sim.blocks().iter().zip(&m.blocks) {
            let mat = m.materials[mb.material];
            e += guard::strain(b.polygon.area(), &b.stress, mat.young, mat.poisson);
        }
    }
    e
}

/// The collision at the run's end: restitution (relative speed after over before),
/// the change of momentum over the momentum, and the mechanical energy over the
/// initial kinetic energy.
fn collide(analysis: &str, rock: &str) -> (f64, f64, f64) {
    let mut sim = guarded(collision(analysis, rock));
    let e0 = mechanical(&sim);
    sim.run(|_, _| {}).unwrap();
    let (l, r) = (sim.blocks()[0].velocity, sim.blocks()[1].velocity);
    // Equal masses: momentum per unit mass, 1 m/s at the start.
    let dp = (l[0] + r[0] - 1.0).abs() + (l[1] + r[1]).abs();
    (r[0] - l[0], dp, mechanical(&sim) / e0)
}

/// The drop's restitution: the block's largest upward speed after the impact over its
/// speed just before it, sqrt(2 g h).
fn bounce(analysis: &str, rock: &str) -> f64 {
    let mut sim = guarded(drop(analysis, rock));
    let mut up = 0.0f64;
    sim.run(|s, _| up = up.max(s.blocks()[1].velocity[1]))
        .unwrap();
    up / (2.0 * 9.81 * 0.5f64).sqrt()
}

/// Rigid blocks: restitution at least 0.95 with `impact_steps = 10` (the issue's
/// acceptance), and within 1e-3 of 1: the springs act in the steps they close and open
/// in for the share of the step they are closed, taken to a thousandth of itself, so
/// each event is right to a thousandth of the impact's energy (see the elastic blocks'
/// test below; measured 1.0000 for the collision and 0.9998 for the drop; 0.9973 and
/// 1.0000 before, a loss at the closing and a push at the opening that happened to
/// cancel). Momentum kept to 1e-9. Without the key the same scenes lose a quarter and a
/// half of the speed (0.754 and 0.497 measured), so the test would fail without the
/// mechanism.
#[test]
fn rigid_impacts_resolved_in_ten_steps_keep_their_speed() {
    let analysis = format!("{RIGID}\nimpact_steps = 10");
    let (e, dp, _) = collide(&analysis, NO_ELASTICITY);
    assert!(
        e >= 0.95 && (e - 1.0).abs() <= 1e-3,
        "collision restitution {e}"
    );
    assert!(dp < 1e-9, "momentum changed by {dp}");
    let b = bounce(&analysis, NO_ELASTICITY);
    assert!(b >= 0.95 && (b - 1.0).abs() <= 1e-3, "drop restitution {b}");
    let (e0, dp0, _) = collide(RIGID, NO_ELASTICITY);
    let b0 = bounce(RIGID, NO_ELASTICITY);
    assert!(e0 < 0.8 && b0 < 0.8, "without the key: {e0}, {b0}");
    assert!(dp0 < 1e-9, "momentum changed by {dp0}");
    // The rule alone, the step not held down: the contact (3.6 ms) lies within one step
    // of 5 ms. The step the contact opens in carries only the part of its step-start
    // force that acts until the blocks part (`Simulation::release`), and carries on the
    // acceleration of that step's own end: no energy is created, and the blocks part
    // slower than they met (0.76 measured). Carried whole, the push gained 59% of the
    // reference energy, and the guard stopped the run.
    let rule = format!("{RIGID}\nintegration = \"average-acceleration\"");
    let mut sim = guarded(collision(&rule, NO_ELASTICITY));
    let e0 = mechanical(&sim);
    sim.run(|_, _| {}).unwrap();
    let (l, r) = (sim.blocks()[0].velocity, sim.blocks()[1].velocity);
    assert!(mechanical(&sim) <= e0, "{} against {e0}", mechanical(&sim));
    assert!(r[0] - l[0] > 0.0, "the blocks did not part: {l:?} {r:?}");
}

/// Elastic blocks (E = 1e10 Pa, as stiff as the contact): the impact leaves part of its
/// energy in the blocks' strain, so the rebound speed falls short of 1 (0.986 for the
/// collision at N = 10). Kinetic plus strain energy, taken at the first step after the
/// blocks part, is kept: the rule conserves it while the contacts are closed, and in
/// the steps they close and open in, their springs act for the share of the step they
/// are closed (`Simulation::engaged`, `Simulation::release`), so that their mean force
/// does the work of the energy the spring stores or gives back. The shares are taken to
/// a thousandth of themselves (`SHARE_TOLERANCE`), and the gap crosses zero at a steady
/// rate to second order (a linear spring's force, and so the acceleration it causes,
/// vanishes there): each of the two events is right to a thousandth of the spring's
/// energy, at most the impact's: kept to 1e-3 (4e-5 measured at E = 1e10 Pa). Before,
/// the step they closed in lost up to pi^2 / 800 of the energy (0.75% measured), and the
/// one they opened in pushed for half of it: blocks of E = 2e10 to 1e11 Pa parted faster
/// than they met. After the impact the rule is Shi's again, whose damping takes the
/// blocks' vibration. Stiffer blocks (E = 1e12 Pa) rebound at restitution 0.95 and more.
#[test]
fn elastic_blocks_keep_the_impacts_energy_as_motion_and_strain() {
    let bound = 1e-3;
    for young in ["1e10", "2e10", "5e10", "1e11"] {
        let elastic = format!("young = {young}\npoisson = 0.25");
        let mut sim = guarded(collision("impact_steps = 10", &elastic));
        let e0 = mechanical(&sim);
        let (mut closed, mut parted) = (false, None);
        sim.run(|s, rec| {
            closed |= rec.closed_contacts > 0;
            if closed && rec.closed_contacts == 0 && parted.is_none() {
                parted = Some(mechanical(s) / e0);
            }
        })
        .unwrap();
        let kept = parted.unwrap();
        assert!(
            (kept - 1.0).abs() <= bound,
            "E = {young}: energy kept {kept} at the parting (bound {bound})"
        );
        let (l, r) = (sim.blocks()[0].velocity, sim.blocks()[1].velocity);
        let (e, dp) = (r[0] - l[0], (l[0] + r[0] - 1.0).abs() + (l[1] + r[1]).abs());
        assert!(e < 1.0, "E = {young}: restitution {e}");
        assert!(dp < 1e-9, "E = {young}: momentum changed by {dp}");
    }
    let stiff = "young = 1e12\npoisson = 0.25";
    let (e, _, _) = collide("impact_steps = 10", stiff);
    assert!(e >= 0.95, "collision restitution {e}");
    let b = bounce("impact_steps = 10", stiff);
    assert!(b >= 0.95, "drop restitution {b}");
}

/// The library's own impact scenes (`dda::bench::analytic::collision` and `rebound`,
/// built on `analytic_analysis` at the issue's settings: p = 1e9 N/m, dt 5 ms, d_max
/// 5 mm for the collision; p = 1e10 N/m, dt 1 ms, d_max 1 mm for the 0.5 m drop) with
/// `impact_steps = 10`: restitution at least 0.95 (0.997 and 1.000 measured) and the
/// collision's momentum kept to 1e-9. Their blocks are rigid, the bodies of the closed
/// forms: with the analysis's deformable blocks (E = 1e9 Pa) they were 0.760 and 0.943.
#[test]
fn the_librarys_impact_scenes_keep_their_speed_with_impact_steps() {
    use dda::bench::analytic::{Restitution, analytic_analysis, collision, rebound};
    for (drop, p, dt, d_max, duration) in [
        (false, 1e9, 0.005, 0.005, 0.1),
        (true, 1e10, 0.001, 0.001, 0.7),
    ] {
        let mut analysis = analytic_analysis(duration, dt, d_max, None, p);
        analysis.impact_steps = Some(10);
        let scene = if drop {
            rebound(analysis)
        } else {
            collision(analysis)
        };
        let mut sim = Simulation::new(scene.validate().unwrap(), RunOptions::default());
        let mut r = Restitution::default();
        let mut momentum = 0.0f64;
        sim.run(|s, _| {
            r.step(s);
            if !drop {
                // Equal masses: the sum of the speeds is the momentum over one mass.
                let v: f64 = s.blocks().iter().map(|b| b.velocity[0]).sum();
                momentum = momentum.max((v - 1.0).abs());
            }
        })
        .unwrap();
        let e = if drop { r.rebound() } else { r.collision() };
        assert!(e >= 0.95, "drop {drop}: restitution {e}");
        assert!(momentum <= 1e-9, "momentum off by {momentum}");
    }
}

/// The parts of one body never strike each other: their seams are intact rock, bonded,
/// and their vibration against each other on those bonds is no impact. Two 1 m square
/// parts of one body, no gravity, pressed together at 1 m/s (each 0.5 m/s towards the
/// other), with `impact_steps = 10`: every step is the scene's 1 ms, where an impact
/// of the two (pi sqrt(m / (2 p)) for their reduced mass of 1,300 kg on the seam's two
/// springs, 8.0e-4 s) would hold it at 8.0e-5 s. Counted as impacts (until
/// 2026-11-27), such seams held a jointed slope with rock bridges at steps of 7.8e-6 s
/// after its toe was cut.
#[test]
fn the_parts_of_one_body_do_not_hold_the_step_as_an_impact() {
    let text = r#"
name = "glued pair"
[analysis]
duration = 0.02
time_step = 1e-3
max_displacement = 1e-2
normal_penalty = 1e9
impact_steps = 10
settle = false
[materials.rock]
density = 2600.0
young = 1e9
poisson = 0.25
[[blocks]]
id = "left"
material = "rock"
body = "pair"
vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]
velocity = [0.5, 0.0]
[[blocks]]
id = "right"
material = "rock"
body = "pair"
vertices = [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]]
velocity = [-0.5, 0.0]
"#;
    let model = Scene::parse(text, Format::Toml, "pair.toml").unwrap().1;
    let mut sim = Simulation::new(model, RunOptions::default());
    for _ in 0..20 {
        let rec = sim.step().unwrap();
        // The last step lands on the duration: 1 ms less the rounding of the sum of t.
        assert!(
            (rec.dt - 1e-3).abs() < 1e-15,
            "dt {} at t = {}",
            rec.dt,
            rec.t
        );
    }
}

/// A part of a body strikes with its body's mass: the drop's block written as a body
/// of two glued parts, a 0.999 m wide one and a 1 mm sliver (2.6 kg of its 2,600), is
/// held to the steps its whole mass M calls for, pi sqrt(M / (n p)) / 10 for the n
/// contacts of one pair in impact (the sliver's two corners, or the big part's two:
/// 1.1e-4 s), not to its sliver's (3.6e-6 s), and rebounds as the one block does
/// (restitution at least 0.95).
#[test]
fn a_sliver_part_of_a_body_strikes_with_its_body_s_mass() {
    let parts = r#"
[[blocks]]
id = "big"
material = "rock"
body = "block"
vertices = [[0.0, 0.5], [0.999, 0.5], [0.999, 1.5], [0.0, 1.5]]
[[blocks]]
id = "sliver"
material = "rock"
body = "block"
vertices = [[0.999, 0.5], [1.0, 0.5], [1.0, 1.5], [0.999, 1.5]]
"#;
    let model = drop_of(&format!("{RIGID}\nimpact_steps = 10"), NO_ELASTICITY, parts);
    let mut sim = guarded(model);
    let (mut up, mut smallest) = (0.0f64, f64::INFINITY);
    sim.run(|s, rec| {
        up = up.max(s.blocks()[1].velocity[1]);
        // The last step lands on the run's end, as short as that is.
        if !s.finished() {
            smallest = smallest.min(rec.dt);
        }
    })
    .unwrap();
    let whole = std::f64::consts::PI * (2600.0 / (2.0 * 1e10f64)).sqrt() / 10.0;
    assert!(
        smallest >= whole,
        "smallest step {smallest:e} s, {whole:e} s for the body"
    );
    let restitution = up / (2.0 * 9.81 * 0.5f64).sqrt();
    assert!(restitution >= 0.95, "{restitution}");
}

/// A rigid block that is not symmetric (a quadrilateral, its product of inertia not
/// zero) dropped 0.5 m onto the base with `impact_steps = 10` lands, rocks and settles
/// under the physics guard (energy created within 1% of the reference, penetration
/// within d_tol). The average-acceleration rule's carried acceleration had parts in a
/// rigid block's strain components, which are no unknowns of it: the forces of contacts
/// released within a step, never solved there, accumulated in them, and the mass
/// matrix's coupling of rotation and strain (its product of inertia) turned them into a
/// torque. The run stopped at the landing on 72% of its reference energy created.
#[test]
fn a_rigid_block_not_symmetric_lands_under_impact_steps_keeping_its_energy() {
    let quad = r#"
[[blocks]]
id = "rock"
material = "rock"
vertices = [[0.0, 0.6], [1.3, 0.5], [1.1, 1.4], [0.2, 1.6]]
"#;
    let mut model = drop_of(&format!("{RIGID}\nimpact_steps = 10"), NO_ELASTICITY, quad);
    model.params.duration = 0.6;
    let mut sim = guarded(model);
    let mut lowest = f64::INFINITY;
    sim.run(|s, _| {
        let p = &s.blocks()[1].polygon;
        lowest = lowest.min(
            (0..p.len())
                .map(|k| p.vertex(k).y)
                .fold(f64::INFINITY, f64::min),
        );
    })
    .unwrap();
    // It reached the base (its lowest vertex started 0.5 m above it).
    assert!(
        sim.finished() && lowest < 1e-3,
        "lowest vertex at {lowest} m"
    );
}

/// A chip 3 cm square thrown up spinning at 300 rad/s flies free for 0.5 s and lands on
/// a fixed floor 2 m below. In flight nothing holds it (no contact within d_tol, no fixed
/// point, load or bolt), so the rotation limit theta_max (2 degrees) does not hold its
/// steps, where it would ask for 300 x 0.5 / 0.0349 = 4,297 steps in flight; nor does
/// d_max (10 mm, where its vertices move up to 11.8 mm in a step of the 1 ms asked for):
/// clear of the floor it may move half its gap to it less d_tol
/// (`Simulation::set_flight_room`), so its 0.5 s take the 500 steps asked for, none held.
/// Its flight is exact at any turn or reach a step (the update moves a block exactly;
/// nothing acts on it but gravity): its rotation is w t and its centroid at
/// x0 + v t + g t^2 / 2 to 1e-9 at 0.5 s. It then lands under the guard, d_max holding
/// its steps again as it nears the floor (some 14 m/s there) and the rotation limit once
/// it has a contact.
#[test]
fn a_chip_spinning_in_flight_is_not_held_to_the_rotation_limit() {
    let (w, vx, vy, g) = (300.0, 2.0, 5.0, 9.81);
    let text = |duration: f64| {
        format!(
            r#"
name = "chip"
[analysis]
duration = {duration}
time_step = 0.001
max_displacement = 0.01
normal_penalty = 1e9
gravity = [0.0, -{g}]
[materials.rock]
density = 2600.0
young = 1e10
poisson = 0.25
[[blocks]]
id = "floor"
material = "rock"
fixed = true
vertices = [[-1.0, -3.0], [5.0, -3.0], [5.0, -2.0], [-1.0, -2.0]]
[[blocks]]
id = "chip"
material = "rock"
vertices = [[-0.015, -0.015], [0.015, -0.015], [0.015, 0.015], [-0.015, 0.015]]
velocity = [{vx}, {vy}]
angular_velocity = {w}
"#
        )
    };
    let (t, parse) = (0.5, |s: &str| {
        Scene::parse(s, Format::Toml, "chip.toml").unwrap().1
    });
    let mut sim = guarded(parse(&text(t)));
    let mut held = 0;
    // The last step lands on the duration, a hair short of the one asked for (the sum
    // of the steps' rounding): its motion then names the chip.
    sim.run(|s, r| held += usize::from(r.held_by == Some(1) && !s.finished()))
        .unwrap();
    let steps = sim.totals().steps;
    assert_eq!(
        (steps, held),
        (500, 0),
        "steps in flight, and held by the chip"
    );
    let chip = &sim.blocks()[1];
    let c = chip.polygon.centroid();
    assert!(
        (chip.rotation - w * t).abs() <= 1e-9 * w * t,
        "{}",
        chip.rotation
    );
    assert!((c.x - vx * t).abs() <= 1e-9, "{c}");
    assert!((c.y - (vy * t - 0.5 * g * t * t)).abs() <= 1e-9, "{c}");
    // It reaches the floor (2 m below its start) at about 1.4 s, its steps held to d_max
    // as it nears it, and lies on it at 2 s.
    let mut sim = guarded(parse(&text(2.0)));
    let mut held = 0;
    sim.run(|_, r| held += usize::from(r.held_by == Some(1)))
        .unwrap();
    assert!(held > 0, "never held by the chip");
    assert!(sim.blocks()[1].polygon.centroid().y < -1.9);
}

/// The rubble pile of `tests/scenes/rubble.toml` (40 random convex rocks, 3 cm to 1 m,
/// dropped into a V of fixed rock) runs its 2 s under the physics guard with every
/// detector: no penetration beyond d_tol, no energy created. No rock passes through the
/// V: every centroid lies above its faces, y > -2 + (2/3) |x| within them (or the rock
/// has left the V over its rims at x = +-6 m).
#[test]
fn a_rubble_pile_of_random_rocks_falls_into_its_v_under_the_guard_with_every_detector() {
    const SCENE: &str = include_str!("../scenes/rubble.toml");
    for detector in ["cover", "type-1", "type-2"] {
        let text = SCENE.replace(
            "gravity = ",
            &format!("detector = \"{detector}\"\ngravity = "),
        );
        let (_, model) = Scene::parse(&text, Format::Toml, "rubble.toml").unwrap();
        let mut sim = guarded(model);
        sim.run(|_, _| {}).unwrap();
        assert!(sim.time() >= 2.0, "{detector}");
        for b in &sim.blocks()[2..] {
            let c = b.polygon.centroid();
            assert!(
                c.x.abs() > 6.0 || c.y > -2.0 + 2.0 / 3.0 * c.x.abs(),
                "{detector}: a rock at {c} is inside the V's rock"
            );
        }
    }
}
