//! The physics guard: after every step's open-close iteration, before the step is
//! committed, two checks that a result is still physics:
//!
//! - **Penetration.** No closed contact deeper than the contact tolerance d_tol:
//!   contacts are found within d_tol (paper section 2.6), so a deeper one means the
//!   penalty is too soft for the motion, or a contact was lost.
//! - **Energy.** The mechanical energy (kinetic plus elastic strain) never exceeds what
//!   the scene supplied, its initial kinetic and strain energy plus the work that
//!   gravity and point loads have done since, by more than [`ENERGY_TOLERANCE`] of a
//!   reference: the largest supply so far plus the energy the model cannot resolve
//!   (every free block lowered by d_tol under gravity, and a contact spring pressed by
//!   the overlap validation allows at the start, 1e-9 of the block's size). Contact
//!   and fixed-point springs store energy and friction dissipates it, so neither can
//!   make the balance rise; only a numerical fault can (a lost contact releasing a
//!   compressed spring, a step far beyond the motion's scale).
//!
//! What happens on a violation is the run's choice ([`crate::RunOptions`]): stop with
//! the last good state, or record it and go on.

use crate::kinematics::{Mat6, Vec6};
use serde::{Deserialize, Serialize};

/// Fraction of the reference energy (see the module docs) by which the mechanical
/// energy may exceed what was supplied before the guard calls it created. Our choice:
/// the collision verdict of the paper's section 4 cases uses the same 1%. The margins
/// measured on the built-in scenes are in `docs/cli.md` ("The physics guard").
pub const ENERGY_TOLERANCE: f64 = 0.01;

/// The running energy balance of a run, J per metre of thickness.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct EnergyBalance {
    /// Initial kinetic and strain energy plus the work of gravity and point loads so far.
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
    for a in 0..6 {
        for b in 0..6 {
            e += 0.5 * v[a] * mass[a][b] * v[b];
        }
    }
    e
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
