//! What a run is at the end of a step: the blocks' states, the counters, and the
//! [`Snapshot`] a checkpoint saves to go on bit for bit ([`Simulation::snapshot`],
//! [`Simulation::restore`]); and the record of one step (a row of history.csv).

use crate::guard::{EnergyBalance, Violation};
use crate::kinematics::Vec6;
use crate::scene::Model;
use crate::simulation::{RunOptions, Simulation};
use crate::solver::SolverCounters;
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
    /// The block whose motion held the step below the one asked for (docs/method.md
    /// section 7), if a block's did: the one whose velocity at the step's start set the
    /// step (its vertices' speed against d_max, or its spin against theta_max where that
    /// limit holds it), or, after an easy step below the initial step whose growth its
    /// motion bounded, the one that moved most for those limits.
    #[serde(default)]
    pub held_by: Option<u32>,
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
    /// Current polygon; saved as its vertices and restored bit for bit
    /// ([`ConvexPolygon::restore`]).
    #[serde(with = "saved_polygon")]
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
    /// Acceleration of the last step (rates of the velocity's components), which the
    /// average-acceleration and damped rules carry into the next step (the first its
    /// end's, the second the step's own); zero under the constant-acceleration rule,
    /// which does not need it.
    pub acceleration: Vec6,
}

/// The state of a run at the end of a step: everything the next step reads that is not
/// rebuilt from it. Saved whole by a checkpoint (with the solver's, see [`Snapshot`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunState {
    /// Simulated time, s.
    pub t: f64,
    /// The controlled step size, s.
    pub dt: f64,
    /// Counters so far (timing included).
    pub totals: Totals,
    /// The blocks.
    pub blocks: Vec<BlockState>,
    /// The contacts at the end of the last step, with their states (inherited by the
    /// next step).
    pub contacts: ContactSet,
    /// The sticky block pattern of the global matrix (free-block index pairs).
    pub pattern: Vec<(u32, u32)>,
    /// The physics guard's energy balance.
    pub energy: EnergyBalance,
    /// Violations recorded by a run that goes on through them.
    pub violations: Vec<Violation>,
    /// What has come of each bolt.
    pub bolts: Vec<crate::bolts::BoltState>,
    /// Whether the blocks' accelerations are those of a step taken (the
    /// average-acceleration and damped rules take their first step by the
    /// constant-acceleration one, which needs none).
    pub accelerations_known: bool,
    /// Whether the blocks have been settled before the run (`analysis.settle`), or the
    /// run has gone past where they would be.
    pub settled: bool,
}

/// Everything a run needs to go on from the end of a step exactly as it would have
/// ([`Simulation::snapshot`], [`Simulation::restore`]): the run's state, and the matrix
/// of the last factorisation (the next step's state predictor solves with its factor)
/// with the solver's counters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    /// The run's state.
    pub state: RunState,
    /// The matrix of the last factorisation, whose factor predicts the next step.
    pub factored_values: Option<Vec<f64>>,
    /// The solver's work so far.
    pub counters: SolverCounters,
}

/// A polygon saved as its vertices and restored bit for bit: a run's polygons are affine
/// images of validated ones, which tolerance-based validation could repair.
mod saved_polygon {
    use dda_geom::{ConvexPolygon, DVec2};
    use serde::{Deserialize, Deserializer, Serialize, Serializer, de::Error};

    pub fn serialize<S: Serializer>(p: &ConvexPolygon, s: S) -> Result<S::Ok, S::Error> {
        p.vertices().serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<ConvexPolygon, D::Error> {
        ConvexPolygon::restore(Vec::<DVec2>::deserialize(d)?).map_err(D::Error::custom)
    }
}

impl Simulation {
    /// The state a resumed run needs to go on exactly as this one would (see
    /// [`Snapshot`]). Everything else is rebuilt at the start of every step.
    pub fn snapshot(&self) -> Snapshot {
        Snapshot {
            state: self.state.clone(),
            factored_values: self.scratch.system.factored_values().map(|v| v.to_vec()),
            counters: self.solver_counters(),
        }
    }

    /// A run of `model` resumed from `snap` (taken from a run of the same model): it goes
    /// on bit for bit as the run it was taken from. Errors, naming what does not fit,
    /// when the snapshot is not of this model.
    pub fn restore(model: Model, options: RunOptions, snap: Snapshot) -> Result<Self, String> {
        let mut sim = Simulation::new(model, options);
        let Snapshot {
            state: snap,
            factored_values,
            counters,
        } = snap;
        let n = sim.state.blocks.len();
        if snap.blocks.len() != n {
            return Err(format!(
                "the checkpoint has {} blocks, the scene {n}",
                snap.blocks.len()
            ));
        }
        if !(snap.t.is_finite() && snap.dt.is_finite() && snap.dt > 0.0) {
            return Err(format!("invalid time {} or step {}", snap.t, snap.dt));
        }
        for (i, (b, start)) in snap.blocks.iter().zip(&sim.state.blocks).enumerate() {
            if b.polygon.len() != start.polygon.len()
                || b.loads.len() != start.loads.len()
                || b.fixed_points.len() != start.fixed_points.len()
            {
                let id = &sim.model.blocks[i].id;
                return Err(format!("block `{id}` does not match the scene's"));
            }
        }
        if snap.bolts.len() != sim.model.bolts.len() {
            return Err(format!(
                "the checkpoint has {} bolts, the scene {}",
                snap.bolts.len(),
                sim.model.bolts.len()
            ));
        }
        let blocks = &snap.blocks;
        let fits = |k: &dda_contact::ContactKey| {
            let (v, e) = (k.vertex_block as usize, k.edge_block as usize);
            v < n
                && e < n
                && v != e
                && (k.vertex as usize) < blocks[v].polygon.len()
                && (k.edge as usize) < blocks[e].polygon.len()
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
        // The blocks excavated by the checkpoint's time are out of the system it saved.
        sim.remove_due(snap.t);
        let nf = sim.n_free as u32;
        if !snap.pattern.windows(2).all(|w| w[0] < w[1])
            || !snap.pattern.iter().all(|&(a, b)| a < b && b < nf)
        {
            return Err("its matrix pattern does not fit the scene's blocks".into());
        }
        for (shape, b) in sim.scratch.shapes.iter_mut().zip(&snap.blocks) {
            *shape = BlockShape::new(&b.polygon);
        }
        sim.state = snap;
        if sim.state.totals.steps > 0 {
            // The system holds the pattern of the last step (set at every step).
            sim.scratch
                .system
                .set_pattern(sim.n_free, sim.nd, &sim.state.pattern)
                .map_err(|e| format!("its matrix pattern: {e}"))?;
            if let Some(values) = &factored_values {
                sim.scratch
                    .system
                    .restore_factor(values)
                    .map_err(|e| format!("its saved matrix: {e}"))?;
            }
        }
        sim.scratch.system.set_counters(counters);
        Ok(sim)
    }
}
