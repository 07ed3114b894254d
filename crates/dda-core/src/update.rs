//! The update that commits a step: after the physics guard, blocks move by their
//! solved motion with the rotation exact, stresses accumulate, velocities follow the
//! constant-acceleration scheme.

use crate::assembly::StepRule;
use crate::diagnosis::SimError;
use crate::guard::{Checked, add_kinetic};
use crate::kinematics::{Vec6, elasticity, mass_matrix};
use crate::scene::{Integration, Mode};
use crate::simulation::Simulation;
use crate::solver::{chol, chol_solve};
use crate::state::StepRecord;
use dda_geom::{check_displacement, displace_point};

impl Simulation {
    /// Commits the trial solution: moves blocks, updates stresses and velocities, and
    /// records penetration. `checked` is what the physics guard's checks found on it, if
    /// they were made already (an attempt past `max_oci`); otherwise they are made here.
    pub(crate) fn accept(
        &mut self,
        dt: f64,
        rec: &mut StepRecord,
        checked: Option<Checked>,
    ) -> Result<(), SimError> {
        let checked = checked.unwrap_or_else(|| self.check_physics(dt));
        let max_pen = checked.max_pen;
        self.guard(checked)?;
        rec.max_penetration = max_pen;
        rec.dt = dt;
        // Check every block's motion first, so that a failure leaves the state untouched.
        let (t, model) = (self.state.t, &self.model);
        let inverted = |i: usize| SimError::Inverted {
            t,
            block: model.blocks[i].id.clone(),
        };
        for i in 0..self.state.blocks.len() {
            if self.free[i].is_some() && check_displacement(&self.scratch.d[i]).is_err() {
                return Err(inverted(i));
            }
        }
        let dynamic = model.params.mode == Mode::Dynamic;
        // The average-acceleration and damped rules carry each block's acceleration: that
        // of the step just taken, by the rule it was taken by.
        let carry = dynamic && model.params.integration != Integration::ConstantAcceleration;
        let rule = self.step_rule();
        let average = rule == StepRule::Average;
        // Where the step's system left the rule's, by block (`w`): the forces it took
        // back from the accelerations carried in (contacts released since its start,
        // `Simulation::release`), less the shares of the end forces of contacts that
        // closed within it that it left out (`Simulation::engaged`). The step moved by
        // D = V dt + (A + M^-1 w + a') dt^2 / 4, a' its system's end acceleration; the
        // acceleration carried on is the step end's, whole: a' - M^-1 (shares left out),
        // that is 4 (D - V dt) / dt^2 - (A + M^-1 w).
        let mut taken_back = std::mem::take(&mut self.scratch.taken_back);
        taken_back.clear();
        taken_back.resize(self.state.blocks.len(), [0.0; 6]);
        let mut add = |s: f64, blocks: &[u32; 2], forces: &[Vec6; 2]| {
            for (b, f) in blocks.iter().zip(forces) {
                for (t, x) in taken_back[*b as usize].iter_mut().zip(f) {
                    *t += s * x;
                }
            }
        };
        for (_, f, row) in &self.scratch.released {
            add(*f, &row.blocks, &row.c);
        }
        for &(k, before) in &self.scratch.engaged {
            let k = k as usize;
            let c = self.state.contacts.contacts[k];
            add(
                -before,
                &self.scratch.rows[k].blocks,
                &self.contact_forces(k, &c, true),
            );
        }
        let ground_velocity = self.model.ground.as_ref().map(|g| g.at(t + dt).1);
        for i in 0..self.state.blocks.len() {
            if self.free[i].is_none() {
                if let (Some(v), Some(u)) = (ground_velocity, self.scratch.half[i].driven) {
                    // A driven block: moved by the ground over the step, at its velocity.
                    let c = self.scratch.shapes[i].centroid;
                    let b = &mut self.state.blocks[i];
                    b.polygon
                        .displace(c, &[u.x, u.y, 0.0, 0.0, 0.0, 0.0])
                        .map_err(|_| inverted(i))?;
                    b.velocity = [v.x, v.y, 0.0, 0.0, 0.0, 0.0];
                    self.scratch.shapes[i].set(&b.polygon);
                }
                continue;
            }
            let d = self.scratch.d[i];
            let c = self.scratch.shapes[i].centroid;
            // A + M^-1 w (w zero unless a contact of the block closed or opened within
            // the step).
            let carried_in = if average && taken_back[i] != [0.0; 6] {
                let f = self.free[i].map_or(0, |f| f as usize);
                let mut back = taken_back[i];
                match chol(&self.scratch.mass[f], self.nd) {
                    Some(l) => chol_solve(&l, self.nd, &mut back),
                    None => back = [0.0; 6],
                }
                let a = &self.state.blocks[i].acceleration;
                std::array::from_fn(|v| a[v] + back[v])
            } else {
                self.state.blocks[i].acceleration
            };
            let b = &mut self.state.blocks[i];
            // Cannot fail: every motion was checked above.
            b.polygon.displace(c, &d).map_err(|_| inverted(i))?;
            // A rigid block's strain components are no unknowns: it carries no acceleration
            // in them (the forces taken back have parts there, which its mass, solved in
            // the block's own unknowns, does not turn into accelerations).
            let nd = self.nd;
            for v in 0..6 {
                if v >= nd {
                    b.acceleration[v] = 0.0;
                    continue;
                }
                if rule == StepRule::Damped {
                    let a =
                        StepRule::damped_acceleration(d[v], b.velocity[v], b.acceleration[v], dt);
                    b.acceleration[v] = a;
                    b.velocity[v] += a * dt;
                    continue;
                }
                if carry {
                    let change = d[v] - b.velocity[v] * dt;
                    b.acceleration[v] = if average {
                        4.0 * change / (dt * dt) - carried_in[v]
                    } else {
                        2.0 * change / (dt * dt)
                    };
                }
                b.velocity[v] = if dynamic {
                    2.0 * d[v] / dt - b.velocity[v]
                } else {
                    0.0
                };
            }
            if self.effects.elasticity {
                let mat = self.model.materials[self.model.blocks[i].material];
                let e = elasticity(mat.young, mat.poisson);
                for a in 0..3 {
                    b.stress[a] += (0..3).map(|q| e[a][q] * d[3 + q]).sum::<f64>();
                }
            }
            b.rotation += d[2];
            for (at, _) in b.loads.iter_mut() {
                *at = displace_point(*at, c, &d);
            }
            for (now, _) in b.fixed_points.iter_mut() {
                *now = displace_point(*now, c, &d);
            }
            self.scratch.shapes[i].set(&b.polygon);
        }
        self.scratch.taken_back = taken_back;
        self.state.t += dt;
        self.state.accelerations_known |= carry;
        Ok(())
    }

    /// Kinetic energy of the free blocks, 1/2 V^T M V.
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for (i, b) in self.state.blocks.iter().enumerate() {
            if self.free[i].is_none() {
                continue;
            }
            let mat = self.model.materials[self.model.blocks[i].material];
            let m = mass_matrix(&b.polygon.moments(), mat.density);
            add_kinetic(&mut e, &m, &b.velocity);
        }
        e
    }
}
