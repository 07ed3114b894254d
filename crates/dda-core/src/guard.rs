//! The physics guard: after every step's open-close iteration, before the step is
//! committed, two checks that a result is still physics:
//!
//! - **Penetration.** No closed contact deeper than the contact tolerance d_tol:
//!   contacts are found within d_tol (paper section 2.6), so a deeper one means the
//!   penalty is too soft for the motion, or a contact was lost.
//! - **Energy.** The mechanical energy (kinetic plus elastic strain) never exceeds what
//!   the scene supplied, its initial kinetic and strain energy plus the work that
//!   gravity, point loads, bolts and a moving ground have done since, less the energy
//!   of the rock excavated (`Simulation::excavate_due`), by more than
//!   [`ENERGY_TOLERANCE`] of a reference: the largest supply so far plus the energy
//!   the model cannot resolve (every free block lowered by d_tol under gravity, and a
//!   contact spring pressed by the overlap validation allows at the start, 1e-9 of the
//!   block's size). Contact and fixed-point springs store energy and friction
//!   dissipates it, so neither can make the balance rise; only a numerical fault can (a
//!   lost contact releasing a compressed spring, a step far beyond the motion's scale).
//!
//! What happens on a violation is the run's choice ([`crate::RunOptions`]): stop with
//! the last good state, or record it and go on.

use crate::diagnosis::SimError;
use crate::kinematics::{Mat6, Vec6, elasticity};
use crate::scene::Mode;
use crate::simulation::Simulation;
use dda_geom::{DVec2, displace_point};
use serde::{Deserialize, Serialize};

/// Fraction of the reference energy (see the module docs) by which the mechanical
/// energy may exceed what was supplied before the guard calls it created. Our choice:
/// the collision verdict of the paper's section 4 cases uses the same 1%. The margins
/// measured on the built-in scenes are in `docs/cli.md` ("The physics guard").
pub const ENERGY_TOLERANCE: f64 = 0.01;

/// The running energy balance of a run, J per metre of thickness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyBalance {
    /// Initial kinetic and strain energy plus the work of gravity, point loads, bolts
    /// and a moving ground so far, less the kinetic and strain energy of the blocks
    /// excavated.
    pub supplied: f64,
    /// Largest `supplied` so far.
    pub supplied_max: f64,
    /// Largest excess of the mechanical energy over `supplied` so far, over the
    /// reference at that step: the guard's margin as used (below [`ENERGY_TOLERANCE`]
    /// unless a violation was recorded).
    pub worst_ratio: f64,
}

/// A kind of violation recorded by a run that goes on through them.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Violation {
    /// "penetration" or "energy".
    pub kind: String,
    /// What happened the first time, in words.
    pub first: String,
    /// Simulated time at the start of the first step that broke it, s.
    pub first_t: f64,
    /// Steps that broke it.
    pub steps: u64,
    /// The worst value seen: penetration in m, or created energy over the reference.
    pub worst: f64,
}

impl Violation {
    /// The violation as a warning line for summary.json.
    pub fn warning(&self) -> String {
        let worst = match self.kind.as_str() {
            "penetration" => format!("deepest {:.3e} m", self.worst),
            _ => format!("worst {:.3} of the reference energy", self.worst),
        };
        format!(
            "{} steps broke physics ({}), first at t = {:.6} s: {}; {worst}",
            self.steps, self.kind, self.first_t, self.first
        )
    }
}

/// 1/2 v^T M v.
pub fn kinetic(mass: &Mat6, v: &Vec6) -> f64 {
    let mut e = 0.0;
    add_kinetic(&mut e, mass, v);
    e
}

/// Adds 1/2 v^T M v to `e`, term by term (a run's total adds its blocks' terms in one
/// sum, in this order, so that history.csv's column stays the same to the bit).
pub fn add_kinetic(e: &mut f64, mass: &Mat6, v: &Vec6) {
    for a in 0..6 {
        for b in 0..6 {
            *e += 0.5 * v[a] * mass[a][b] * v[b];
        }
    }
}

/// Strain energy of a block of area `area` under stress `s` (sx, sy, txy), with the
/// (effective) Young's modulus and Poisson's ratio of plane elasticity:
/// A/2 s^T C^-1 s.
pub fn strain(area: f64, s: &[f64; 3], young: f64, poisson: f64) -> f64 {
    let ex = (s[0] - poisson * s[1]) / young;
    let ey = (s[1] - poisson * s[0]) / young;
    let g = 2.0 * (1.0 + poisson) * s[2] / young;
    0.5 * area * (s[0] * ex + s[1] * ey + s[2] * g)
}

/// What the physics guard found on a trial solution ([`Simulation::check_physics`]).
pub(crate) struct Checked {
    /// The checks it broke: kind ("penetration" or "energy"), what happened in words,
    /// the blocks involved, and the worst value (m, or a share of the reference).
    broken: Vec<(&'static str, String, Vec<String>, f64)>,
    /// The energy supplied up to the end of the step, J/m.
    supplied: f64,
    /// The energy created over the reference (negative: none).
    ratio: f64,
    /// The penetration of the deepest closed contact, m (0 if none penetrates).
    pub(crate) max_pen: f64,
}

impl Checked {
    /// Whether the trial broke physics.
    pub(crate) fn broken(&self) -> bool {
        !self.broken.is_empty()
    }
}

impl Simulation {
    /// The deepest closed contact of the trial solution: its penetration (0 if none
    /// penetrates) and its index.
    fn deepest_contact(&self) -> (f64, Option<usize>) {
        let (mut max_pen, mut deepest) = (0.0f64, None);
        for (k, c) in self.state.contacts.contacts.iter().enumerate() {
            if c.active && c.state.is_closed() {
                let pen = -self.scratch.rows[k].eval(&self.scratch.d);
                if pen > max_pen {
                    (max_pen, deepest) = (pen, Some(k));
                }
            }
        }
        (max_pen, deepest)
    }

    /// The physics guard (see `guard`) on a trial solution, given what its checks found
    /// ([`Simulation::check_physics`]): a violation stops the run before the step is
    /// committed, or is recorded, as the run's options say. Reads the state only, and
    /// updates the energy balance.
    pub(crate) fn guard(&mut self, checked: Checked) -> Result<(), SimError> {
        let Checked {
            broken,
            supplied,
            ratio,
            ..
        } = checked;
        if let Some((_, what, blocks, _)) = broken.first()
            && self.options.stop_on_violation
        {
            return Err(SimError::BrokenPhysics {
                t: self.state.t,
                what: what.clone(),
                blocks: blocks.clone(),
            });
        }
        for (kind, what, _, worst) in broken {
            match self.state.violations.iter_mut().find(|v| v.kind == kind) {
                Some(v) => {
                    v.steps += 1;
                    v.worst = v.worst.max(worst);
                }
                None => self.state.violations.push(Violation {
                    kind: kind.to_string(),
                    first: what,
                    first_t: self.state.t,
                    steps: 1,
                    worst,
                }),
            }
        }
        self.state.energy.supplied = supplied;
        self.state.energy.supplied_max = self.state.energy.supplied_max.max(supplied);
        self.state.energy.worst_ratio = self.state.energy.worst_ratio.max(ratio);
        Ok(())
    }

    /// The guard's checks on the trial solution of a step of `dt` (see
    /// [`Simulation::guard`]), with no effect on the run.
    pub(crate) fn check_physics(&mut self, dt: f64) -> Checked {
        let (max_pen, deepest) = self.deepest_contact();
        let p = &self.model.params;
        let dynamic = p.mode == Mode::Dynamic;
        let rule = self.step_rule();
        let gravity = self.gravity();
        let (mut mechanical, mut work) = (0.0, 0.0);
        let mut gains = std::mem::take(&mut self.scratch.gains);
        gains.clear();
        for (f, &i) in self.free_blocks.iter().enumerate() {
            let i = i as usize;
            let (d, b, s) = (
                &self.scratch.d[i],
                &self.state.blocks[i],
                &self.scratch.shapes[i],
            );
            let mat = self.model.materials[self.material[i] as usize];
            let mass = &self.scratch.mass[f];
            let area = mass[0][0] / mat.density;
            let ke = if dynamic {
                let v: Vec6 = std::array::from_fn(|a| {
                    rule.end_velocity(d[a], b.velocity[a], b.acceleration[a], dt)
                });
                kinetic(mass, &v)
            } else {
                0.0
            };
            let mut u = 0.0;
            if self.effects.elasticity {
                let e = elasticity(mat.young, mat.poisson);
                let stress: [f64; 3] = std::array::from_fn(|a| {
                    b.stress[a] + (0..3).map(|q| e[a][q] * d[3 + q]).sum::<f64>()
                });
                u = strain(area, &stress, mat.young, mat.poisson);
            }
            mechanical += ke + u;
            work += mat.density * area * gravity.dot(DVec2::new(d[0], d[1]));
            // A load works along its point's path as the step moves it, the turn exact.
            for &(at, force) in &b.loads {
                work += force.dot(displace_point(at, s.centroid, d) - at);
            }
            gains.push((ke - kinetic(mass, &b.velocity), i));
        }
        work += self.bolt_work() + self.ground_work();
        let supplied = self.state.energy.supplied + work;
        let reference = self.state.energy.supplied_max.max(supplied) + self.energy_floor;
        let excess = mechanical - supplied;
        let ratio = if reference > 0.0 {
            excess / reference
        } else if excess > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        let id = |i: usize| self.model.blocks[i].id.clone();
        let mut broken = Vec::new();
        if max_pen > p.d_tol {
            let (what, blocks) = match deepest.map(|k| self.state.contacts.contacts[k].key) {
                Some(k) => (
                    format!(
                        "penetration {max_pen:.3e} m beyond the contact tolerance {:.3e} m, \
                         vertex {} of `{}` into edge {} of `{}`: analysis.normal_penalty \
                         ({:.3e} N/m) is too soft for this motion, or d_tol too small",
                        p.d_tol,
                        k.vertex,
                        id(k.vertex_block as usize),
                        k.edge,
                        id(k.edge_block as usize),
                        p.normal_penalty
                    ),
                    vec![id(k.vertex_block as usize), id(k.edge_block as usize)],
                ),
                None => (String::new(), Vec::new()),
            };
            broken.push(("penetration", what, blocks, max_pen));
        }
        if ratio > ENERGY_TOLERANCE {
            gains.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let blocks: Vec<String> = gains.iter().take(3).map(|g| id(g.1)).collect();
            let what = format!(
                "energy created: kinetic + strain energy {mechanical:.4e} J/m exceeds the \
                 energy supplied ({supplied:.4e} J/m: initial energy and the work of gravity, \
                 loads, bolts and the ground) by {:.2}% of the reference {reference:.4e} J/m (more \
                 than {}%); the fastest-gaining blocks: {}",
                100.0 * ratio,
                100.0 * ENERGY_TOLERANCE,
                blocks.join(", ")
            );
            broken.push(("energy", what, blocks, ratio));
        }
        self.scratch.gains = gains;
        Checked {
            broken,
            supplied,
            ratio,
            max_pen,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::elasticity;

    /// The strain energy of a stress equals the work of that stress over the strain that
    /// causes it: 1/2 s . e with s = C e, for a few strains and both signs of shear.
    #[test]
    fn strain_energy_is_half_stress_times_strain() {
        let (young, poisson, area) = (2.0e9, 0.27, 1.7);
        let c = elasticity(young, poisson);
        for e in [[1e-4, 0.0, 0.0], [2e-4, -1e-4, 3e-4], [0.0, 0.0, -5e-4]] {
            let s: [f64; 3] = std::array::from_fn(|a| (0..3).map(|b| c[a][b] * e[b]).sum());
            let direct = 0.5 * area * (0..3).map(|a| s[a] * e[a]).sum::<f64>();
            let u = strain(area, &s, young, poisson);
            assert!((u - direct).abs() <= 1e-12 * direct.abs(), "{u} {direct}");
        }
    }
}
