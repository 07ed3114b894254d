//! What a run is at the end of a step: the blocks' states, the counters, and the
//! [`Snapshot`] a checkpoint saves to go on bit for bit ([`Simulation::snapshot`],
//! [`Simulation::restore`]); and the record of one step (a row of history.csv).

use crate::guard::{EnergyBalance, Violation};
use crate::kinematics::Vec6;
use crate::scene::Model;
use crate::simulation::{RunOptions, Simulation};
use dda_contact::{BlockShape, ContactSet};
use dda_geom::{ConvexPolygon, DVec2};
use serde::{Deserialize, Serialize};

/// What one completed step did (a row of history.csv).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    /// Step number, from 1.
    pub step: u64,
    /// Simulated time at the end of the step, s.
    pub t: f64,
    /// Step size used, s.
    pub dt: f64,
    /// OCI iterations of the accepted attempt.
    pub oci: u32,
    /// Attempts thrown away (dt cuts) before this step was accepted.
    pub cuts: u32,
    /// Candidate contacts.
    pub candidates: usize,
    /// Active contacts at the end of the step.
    pub active_contacts: usize,
    /// Active closed contacts at the end of the step.
    pub closed_contacts: usize,
    /// Largest penetration of a closed contact after the step, m.
    pub max_penetration: f64,
    /// Kinetic energy after the step, J (per unit thickness).
    pub kinetic_energy: f64,
    /// Wall seconds in contact detection (step start and trajectory tracking).
    pub detection_s: f64,
    /// Wall seconds assembling the system.
    pub assembly_s: f64,
    /// Wall seconds factorising and solving.
    pub solve_s: f64,
}

/// Cumulative counters of a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Totals {
    /// Completed steps.
    pub steps: u64,
    /// OCI iterations, including those of discarded attempts.
    pub oci_iterations: u64,
    /// Discarded attempts (dt cuts).
    pub cuts: u64,
    /// Shear springs assembled (summed over OCI iterations).
    pub shear_springs: u64,
    /// Normal springs assembled (summed over OCI iterations).
    pub normal_springs: u64,
    /// Friction forces applied (summed over OCI iterations).
    pub friction_forces: u64,
    /// Largest penetration seen after any step, m.
    pub max_penetration: f64,
    /// Wall seconds stepping.
    pub total_s: f64,
    /// Wall seconds in contact detection.
    pub detection_s: f64,
    /// Wall seconds in assembly.
    pub assembly_s: f64,
    /// Wall seconds in factorisation and solve.
    pub solve_s: f64,
}

/// A block's state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockState {
    /// Current polygon.
    pub polygon: ConvexPolygon,
    /// Velocity (rates of u0, v0, r0, ex, ey, gxy).
    pub velocity: Vec6,
    /// Stress (sx, sy, txy), Pa.
    pub stress: [f64; 3],
    /// Accumulated rotation, rad.
    pub rotation: f64,
    /// Point loads: current point, force.
    pub loads: Vec<(DVec2, DVec2)>,
    /// Fixed points: current material point, its fixed place.
    pub fixed_points: Vec<(DVec2, DVec2)>,
}

/// A block's state in a [`Snapshot`]: its polygon as a plain vertex list (restored bit
/// for bit, see [`ConvexPolygon::restore`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockSnapshot {
    /// Vertices, counter-clockwise.
    pub vertices: Vec<DVec2>,
    /// Velocity (rates of u0, v0, r0, ex, ey, gxy).
    pub velocity: Vec6,
    /// Stress (sx, sy, txy), Pa.
    pub stress: [f64; 3],
    /// Accumulated rotation, rad.
    pub rotation: f64,
    /// Point loads: current point, force.
    pub loads: Vec<(DVec2, DVec2)>,
    /// Fixed points: current material point, its fixed place.
    pub fixed_points: Vec<(DVec2, DVec2)>,
}

/// Everything a run needs to go on from the end of a step exactly as it would have
/// ([`Simulation::snapshot`], [`Simulation::restore`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// Simulated time, s.
    pub t: f64,
    /// The controlled step size, s.
    pub dt: f64,
    /// Counters so far (timing included).
    pub totals: Totals,
    /// The blocks.
    pub blocks: Vec<BlockSnapshot>,
    /// The contacts at the end of the last step, with their states.
    pub contacts: ContactSet,
    /// The sticky block pattern of the global matrix (free-block index pairs).
    pub pattern: Vec<(u32, u32)>,
    /// The matrix of the last factorisation, whose factor predicts the next step.
    pub factored_values: Option<Vec<f64>>,
    /// Symbolic factorisations, numeric factorisations and low-rank solves so far.
    pub counters: [u64; 3],
    /// The physics guard's energy balance.
    pub energy: EnergyBalance,
    /// Violations recorded by a run that goes on through them.
    pub violations: Vec<Violation>,
}

impl Simulation {
    /// The state a resumed run needs to go on exactly as this one would: blocks, time,
    /// step size, counters, the contacts with their states (inherited by the next step),
    /// the sticky matrix pattern and the matrix of the last factorisation (the next
    /// step's state predictor solves with its factor). Everything else is rebuilt at the
    /// start of every step.
    pub fn snapshot(&self) -> Snapshot {
        let (symbolic, numeric, low_rank) = self.factorisations();
        Snapshot {
            t: self.t,
            dt: self.dt,
            totals: self.totals,
            blocks: self
                .blocks
                .iter()
                .map(|b| BlockSnapshot {
                    vertices: b.polygon.vertices().to_vec(),
                    velocity: b.velocity,
                    stress: b.stress,
                    rotation: b.rotation,
                    loads: b.loads.clone(),
                    fixed_points: b.fixed_points.clone(),
                })
                .collect(),
            contacts: self.contacts.clone(),
            pattern: self.pattern.clone(),
            factored_values: self.system.factored_values().map(|v| v.to_vec()),
            counters: [symbolic, numeric, low_rank],
            energy: self.energy,
            violations: self.violations.clone(),
        }
    }

    /// A run of `model` resumed from `snap` (taken from a run of the same model): it goes
    /// on bit for bit as the run it was taken from. Errors, naming what does not fit,
    /// when the snapshot is not of this model.
    pub fn restore(model: Model, options: RunOptions, snap: Snapshot) -> Result<Self, String> {
        let mut sim = Simulation::new(model, options);
        let n = sim.blocks.len();
        if snap.blocks.len() != n {
            return Err(format!(
                "the checkpoint has {} blocks, the scene {n}",
                snap.blocks.len()
            ));
        }
        if !(snap.t.is_finite() && snap.dt.is_finite() && snap.dt > 0.0) {
            return Err(format!("invalid time {} or step {}", snap.t, snap.dt));
        }
        for (i, b) in snap.blocks.into_iter().enumerate() {
            let id = &sim.model.blocks[i].id;
            let polygon =
                ConvexPolygon::restore(b.vertices).map_err(|e| format!("block `{id}`: {e}"))?;
            let state = &mut sim.blocks[i];
            if polygon.len() != state.polygon.len()
                || b.loads.len() != state.loads.len()
                || b.fixed_points.len() != state.fixed_points.len()
            {
                return Err(format!("block `{id}` does not match the scene's"));
            }
            sim.shapes[i] = BlockShape::new(&polygon);
            *state = BlockState {
                polygon,
                velocity: b.velocity,
                stress: b.stress,
                rotation: b.rotation,
                loads: b.loads,
                fixed_points: b.fixed_points,
            };
        }
        let fits = |k: &dda_contact::ContactKey| {
            let (v, e) = (k.vertex_block as usize, k.edge_block as usize);
            v < n
                && e < n
                && v != e
                && (k.vertex as usize) < sim.blocks[v].polygon.len()
                && (k.edge as usize) < sim.blocks[e].polygon.len()
        };
        let c = &snap.contacts;
        let ranges_fit = c.pairs.iter().all(|p| {
            p.start <= p.end
                && (p.end as usize) <= c.contacts.len()
                && c.contacts[p.start as usize..p.end as usize]
                    .iter()
                    .all(|x| x.key.pair() == p.pair)
        });
        if !(ranges_fit && c.contacts.iter().all(|x| fits(&x.key))) {
            return Err("its contacts do not fit the scene's blocks".into());
        }
        let nf = sim.n_free as u32;
        if !snap.pattern.windows(2).all(|w| w[0] < w[1])
            || !snap.pattern.iter().all(|&(a, b)| a < b && b < nf)
        {
            return Err("its matrix pattern does not fit the scene's blocks".into());
        }
        sim.t = snap.t;
        sim.dt = snap.dt;
        sim.totals = snap.totals;
        sim.contacts = snap.contacts;
        sim.pattern = snap.pattern;
        sim.energy = snap.energy;
        sim.violations = snap.violations;
        if sim.totals.steps > 0 {
            // The system holds the pattern of the last step (set at every step).
            sim.system
                .set_pattern(sim.n_free, sim.nd, &sim.pattern)
                .map_err(|e| format!("its matrix pattern: {e}"))?;
            if let Some(values) = &snap.factored_values {
                sim.system
                    .restore_factor(values)
                    .map_err(|e| format!("its saved matrix: {e}"))?;
            }
        }
        let [s, nn, l] = snap.counters;
        sim.system.set_counters(s, nn, l);
        Ok(sim)
    }
}
