//! The verdict on a block system collapsing under gravity from rest (the paper's section 5
//! columns), computed at every step of a run. Ours, as the paper judges its figures by
//! eye; stricter than the engine's physics guard (`docs/cli.md`), which stops a run only
//! when energy is created beyond 1% of what the scene supplied:
//!
//! - **Energy.** Gravity is the only source: at every instant the blocks' kinetic energy
//!   stays within the potential energy released so far plus 0.2% of m g H (m the free
//!   blocks' mass, H their height). Strain energy is stored, not created, so it is left
//!   out: the check is lenient by it, and strict in its margin.
//! - **Speed.** No block runs faster than 3 g t at time t: free fall from rest reaches
//!   g t, and a block thrown by contacts that create energy runs faster.
//!
//! Each criterion's worst instant is kept, with its time, to be reported beside the
//! verdict.

use crate::verdict::kinetic_energy;
use dda_core::Simulation;
use serde::Serialize;

/// The energy margin: kinetic energy may exceed the potential energy released by this
/// fraction of m g H.
pub const ENERGY_MARGIN: f64 = 0.002;

/// The speed bound, as a multiple of g t.
pub const SPEED_FACTOR: f64 = 3.0;

/// The worst instant of a criterion: its value and when.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct Worst {
    /// The criterion's value there (see [`CollapseWatch`]).
    pub value: f64,
    /// Simulated time, s.
    pub t: f64,
}

impl Worst {
    fn keep(&mut self, value: f64, t: f64) {
        if value > self.value {
            *self = Worst { value, t };
        }
    }
}

/// Watches a collapse step by step and judges it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CollapseWatch {
    /// m g H of the free blocks, J/m.
    pub scale: f64,
    /// |g|, m/s^2.
    g: f64,
    /// The free blocks' potential energy at the start, J/m.
    potential0: f64,
    /// Kinetic energy less the potential energy released, over m g H (permissible at most
    /// [`ENERGY_MARGIN`]).
    pub energy: Worst,
    /// The fastest block's speed over [`SPEED_FACTOR`] g t (permissible at most 1).
    pub speed: Worst,
}

impl CollapseWatch {
    /// Starts watching `sim` at its current state (observed as the first instant).
    pub fn new(sim: &Simulation) -> Self {
        let model = sim.model();
        let g = model.params.gravity.unwrap_or_default().length();
        let (mut mass, mut low, mut high) = (0.0, f64::INFINITY, f64::NEG_INFINITY);
        for (b, m) in sim.blocks().iter().zip(&model.blocks) {
            if m.fixed {
                continue;
            }
            mass += model.materials[m.material].density * b.polygon.area();
            for v in b.polygon.vertices() {
                (low, high) = (low.min(v.y), high.max(v.y));
            }
        }
        let height = if high > low { high - low } else { 0.0 };
        let mut watch = CollapseWatch {
            scale: (mass * g * height).max(f64::MIN_POSITIVE),
            g,
            potential0: potential_energy(sim),
            energy: Worst {
                value: f64::NEG_INFINITY,
                t: 0.0,
            },
            speed: Worst::default(),
        };
        watch.observe(sim);
        watch
    }

    /// Records the state of `sim` after a step.
    pub fn observe(&mut self, sim: &Simulation) {
        let t = sim.time();
        let kinetic = kinetic_energy(sim);
        let released = self.potential0 - potential_energy(sim);
        self.energy.keep((kinetic - released) / self.scale, t);
        let model = sim.model();
        let fastest = sim
            .blocks()
            .iter()
            .zip(&model.blocks)
            .filter(|(_, m)| !m.fixed)
            .map(|(b, _)| b.velocity[0].hypot(b.velocity[1]))
            .fold(0.0, f64::max);
        let bound = SPEED_FACTOR * self.g * t;
        let ratio = if bound > 0.0 {
            fastest / bound
        } else if fastest > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        self.speed.keep(ratio, t);
    }

    /// Whether every instant observed met both criteria.
    pub fn permissible(&self) -> bool {
        self.energy.value <= ENERGY_MARGIN && self.speed.value <= 1.0
    }

    /// The criteria not met, in words.
    pub fn failures(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.energy.value > ENERGY_MARGIN {
            out.push(format!(
                "kinetic energy exceeded the potential energy released by {:.3}% of m g H at t = {:.4} s (at most {}%)",
                100.0 * self.energy.value,
                self.energy.t,
                100.0 * ENERGY_MARGIN
            ));
        }
        if self.speed.value > 1.0 {
            out.push(format!(
                "a block ran at {:.2} times {SPEED_FACTOR} g t at t = {:.4} s",
                self.speed.value, self.speed.t
            ));
        }
        out
    }
}

/// Why [`run_watched`] ended a run before its end.
#[derive(Clone, Debug, PartialEq)]
pub enum Stop {
    /// It had taken the most steps allowed.
    Steps,
    /// A step failed, with the engine's message.
    Failed(String),
}

/// Runs `sim` to its end, watching every step, or until it has taken `max_steps` steps
/// or a step fails; the watch, and why the run ended early, if it did.
pub fn run_watched(sim: &mut Simulation, max_steps: u64) -> (CollapseWatch, Option<Stop>) {
    let mut watch = CollapseWatch::new(sim);
    while !sim.finished() {
        if sim.totals().steps >= max_steps {
            return (watch, Some(Stop::Steps));
        }
        if let Err(e) = sim.step() {
            return (watch, Some(Stop::Failed(e.to_string())));
        }
        watch.observe(sim);
    }
    (watch, None)
}

/// Potential energy of gravity of the free blocks, -sum m g . centroid, J/m.
pub fn potential_energy(sim: &Simulation) -> f64 {
    let model = sim.model();
    let g = model.params.gravity.unwrap_or_default();
    sim.blocks()
        .iter()
        .zip(&model.blocks)
        .filter(|(_, m)| !m.fixed)
        .map(|(b, m)| {
            -model.materials[m.material].density * b.polygon.area() * g.dot(b.polygon.centroid())
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Masonry;
    use dda_core::RunOptions;

    /// One 1 m block of rock falling freely for 0.1 s (the grid's base removed), with
    /// initial velocity `v0` upwards.
    fn falling(v0: f64) -> Simulation {
        let mut scene = Masonry {
            duration: 0.1,
            ..Masonry::grid(1, 1, 1.0)
        }
        .scene("fall");
        scene.blocks.remove(0);
        scene.blocks[0].velocity = Some([0.0, v0]);
        let model = scene.validate().expect("valid");
        Simulation::new(model, RunOptions::default())
    }

    fn watched(mut sim: Simulation) -> CollapseWatch {
        let (watch, stop) = run_watched(&mut sim, u64::MAX);
        assert_eq!(stop, None, "a free fall runs");
        watch
    }

    /// Falling from rest, the block's kinetic energy is the potential energy released
    /// (the step integrates a constant acceleration exactly, so the excess is rounding:
    /// 1e-12 of m g H), and its speed is g t, a third of the bound.
    #[test]
    fn a_free_fall_is_permissible_at_a_third_of_the_speed_bound() {
        let w = watched(falling(0.0));
        assert!(w.permissible(), "{:?}", w.failures());
        assert!(w.energy.value.abs() < 1e-12, "{:?}", w.energy);
        assert!(
            (w.speed.value - 1.0 / SPEED_FACTOR).abs() < 1e-9,
            "{:?}",
            w.speed
        );
        // m g H of a 1 m block of density 2600 under 9.81 m/s^2.
        assert!((w.scale - 2600.0 * 9.81).abs() < 1e-9 * w.scale);
    }

    /// Thrown up at 1 m/s, the block has kinetic energy that gravity did not release
    /// (0.5 v0^2 / (g H) = 5.1% of m g H, the same at every instant as the block rises),
    /// and it runs faster than 3 g t from the start: both criteria fail.
    #[test]
    fn a_block_thrown_from_the_start_is_not() {
        let w = watched(falling(1.0));
        assert!(!w.permissible());
        assert_eq!(w.failures().len(), 2, "{:?}", w.failures());
        assert!((w.energy.value - 0.5 / 9.81).abs() < 1e-9, "{:?}", w.energy);
        assert!(
            w.speed.value.is_infinite() && w.speed.t == 0.0,
            "{:?}",
            w.speed
        );
    }
}
