//! The run summary (docs/outputs.md): the fields other tools read, plus a few more. Timing
//! fields live under `seconds` so that comparisons of two runs can leave them out.

use crate::scene::SolverChoice;
use crate::simulation::Simulation;
use serde::{Deserialize, Serialize};

/// Wall-clock seconds of a run, by phase.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Seconds {
    /// Whole run (stepping).
    pub total: f64,
    /// Contact detection (step start and trajectory tracking).
    pub contact_detection: f64,
    /// Assembly of the system and contact checks.
    pub assembly: f64,
    /// Numeric factorisation and solve.
    pub solve: f64,
}

/// A block at the end of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockSummary {
    /// Block id.
    pub id: String,
    /// Centroid, m.
    pub centroid: [f64; 2],
    /// Centroid velocity, m/s.
    pub velocity: [f64; 2],
    /// Accumulated rotation, rad.
    pub rotation: f64,
    /// Stress (sxx, syy, sxy), Pa, tension positive (zero for rigid blocks).
    #[serde(default)]
    pub stress: [f64; 3],
}

/// summary.json.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Scene name.
    pub scene: String,
    /// The scene file or built-in scene the run was made from, as the command named it
    /// (set by the `dda` command; absent for a library run).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// Detector name.
    pub detector: String,
    /// The rule a dynamic analysis steps by (`analysis.integration`, named or the
    /// default); absent for a static analysis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration: Option<String>,
    /// Effects assembled.
    pub effects: Vec<String>,
    /// "completed", "failed" (the simulation could not go on, or broke physics),
    /// "stopped" (`--max-steps` reached before the duration) or "interrupted" (a signal).
    pub status: String,
    /// Why the run stopped early, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// What was involved when the run stopped early, if it did.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub failure: Option<crate::diagnosis::Diagnosis>,
    /// Simulated time reached, s.
    pub time_simulated: f64,
    /// Completed steps.
    pub steps: u64,
    /// OCI iterations (including discarded attempts).
    pub oci_iterations: u64,
    /// Discarded attempts (time-step cuts).
    pub time_step_cuts: u64,
    /// Contact tolerance d_tol used, m.
    pub contact_tolerance: f64,
    /// Largest step displacement d_max used, m.
    pub max_displacement: f64,
    /// Unknowns of the global system.
    pub unknowns: usize,
    /// Shear springs assembled over the run (0 for a frictionless scene).
    pub shear_springs: u64,
    /// Symbolic factorisations (pattern changes).
    pub symbolic_factorisations: u64,
    /// Numeric factorisations.
    pub numeric_factorisations: u64,
    /// OCI solves done through a low-rank update of the last factor instead.
    pub low_rank_solves: u64,
    /// Iterative solves (`analysis.solver`; absent when there were none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub iterative_solves: u64,
    /// Their conjugate-gradient iterations (absent when there were none).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub cg_iterations: u64,
    /// Wall-clock seconds.
    pub seconds: Seconds,
    /// Largest penetration after any step, m.
    pub max_penetration: f64,
    /// The physics guard's largest energy excess: mechanical energy above what the scene
    /// supplied, over its reference energy (the guard stops a run beyond 0.01).
    #[serde(default)]
    pub energy_excess: f64,
    /// Violations of physics a run went on through (`--keep-going`), in words.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Blocks at the end (those an excavation removed are in `removed` instead).
    pub blocks: Vec<BlockSummary>,
    /// Blocks an excavation removed, with the time they went.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub removed: Vec<Removed>,
    /// The bolts at the end, in scene order.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bolts: Vec<BoltSummary>,
    /// What the settling did before t = 0, for a run that settled (set by the caller,
    /// which times it: [`Summary::of`] leaves it `None`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settling: Option<SettlingSummary>,
    /// The blocks whose motion held dt below the step asked for, most steps first (at
    /// most five; [`crate::StepRecord::held_by`], set by the caller, which sees every
    /// step): where a run took more steps than its time step asks, what held it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held_by: Vec<HeldBy>,
}

/// A block that held the time step ([`Summary::held_by`]).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HeldBy {
    /// The block's id.
    pub block: String,
    /// The steps it held.
    pub steps: u64,
}

/// What the settling did before t = 0 (docs/method.md section 13).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SettlingSummary {
    /// Static steps taken.
    pub static_steps: u32,
    /// Whether its motion converged; if not, it stopped on its rule for no progress or
    /// at its most steps.
    pub converged: bool,
    /// Wall time it took, s.
    pub seconds: f64,
    /// How its static steps were solved, `direct` or `iterative` (`analysis.solver`;
    /// under `auto` directly below 10,000 free blocks: docs/method.md section 13).
    /// Absent in the record of a run begun before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverChoice>,
    /// For a settling that did not converge, the static step the run starts from: the
    /// steadiest, where the motion changed least, of those not cut below the settling's
    /// first (docs/method.md section 13); absent where there was none, and the run
    /// starts from the last.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kept_step: Option<u32>,
}

/// A bolt at the end of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BoltSummary {
    /// The block holding its first end.
    pub from_block: String,
    /// The block holding its other end.
    pub to_block: String,
    /// Its tension at the end, N (compression negative); absent once broken or removed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tension: Option<f64>,
    /// When it broke, s, and its tension then, N.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub broken: Option<Broken>,
}

/// When a bolt broke.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Broken {
    /// Time, s.
    pub t: f64,
    /// Its tension then, N.
    pub tension: f64,
}

/// A block removed by an excavation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Removed {
    /// Block id.
    pub id: String,
    /// When it was removed, s.
    pub t: f64,
}

impl Summary {
    /// The summary of `sim` as it stands; `error` if the run stopped early.
    pub fn of(sim: &Simulation, error: Option<String>) -> Self {
        let t = sim.totals();
        let counters = sim.solver_counters();
        let p = &sim.model().params;
        Summary {
            scene: sim.model().name.clone(),
            source: None,
            detector: sim.detector_name().to_string(),
            integration: p.stepping_rule().map(|r| r.name().to_string()),
            effects: sim
                .effects()
                .names()
                .iter()
                .map(|s| s.to_string())
                .collect(),
            status: if error.is_some() {
                "failed"
            } else {
                "completed"
            }
            .to_string(),
            failure: error.as_ref().and_then(|_| sim.diagnosis().cloned()),
            error,
            time_simulated: sim.time(),
            steps: t.steps,
            oci_iterations: t.oci_iterations,
            time_step_cuts: t.cuts,
            contact_tolerance: p.d_tol,
            max_displacement: p.d_max,
            unknowns: sim.unknowns(),
            shear_springs: t.shear_springs,
            symbolic_factorisations: counters.symbolic,
            numeric_factorisations: counters.numeric,
            low_rank_solves: counters.low_rank,
            iterative_solves: counters.iterative,
            cg_iterations: counters.cg_iterations,
            seconds: Seconds {
                total: t.total_s,
                contact_detection: t.detection_s,
                assembly: t.assembly_s,
                solve: t.solve_s,
            },
            max_penetration: t.max_penetration,
            energy_excess: sim.energy_balance().worst_ratio,
            warnings: sim.violations().iter().map(|v| v.warning()).collect(),
            settling: None,
            held_by: Vec::new(),
            bolts: sim
                .model()
                .bolts
                .iter()
                .enumerate()
                .map(|(k, b)| BoltSummary {
                    from_block: sim.model().blocks[b.from_block].id.clone(),
                    to_block: sim.model().blocks[b.to_block].id.clone(),
                    tension: sim.bolt_tension(k),
                    broken: sim.bolt_states()[k]
                        .broken
                        .map(|(t, tension)| Broken { t, tension }),
                })
                .collect(),
            removed: sim
                .model()
                .blocks
                .iter()
                .enumerate()
                .filter(|&(i, _)| sim.is_removed(i))
                .map(|(_, m)| Removed {
                    id: m.id.clone(),
                    t: m.removed_at.unwrap_or_default(),
                })
                .collect(),
            blocks: sim
                .model()
                .blocks
                .iter()
                .zip(sim.blocks())
                .enumerate()
                .filter(|&(i, _)| !sim.is_removed(i))
                .map(|(_, (m, b))| {
                    let c = b.polygon.centroid();
                    BlockSummary {
                        id: m.id.clone(),
                        centroid: [c.x, c.y],
                        velocity: [b.velocity[0], b.velocity[1]],
                        rotation: b.rotation,
                        stress: b.stress,
                    }
                })
                .collect(),
        }
    }

    /// A copy with the timing fields zeroed, for run-to-run comparison.
    pub fn without_timing(&self) -> Self {
        Summary {
            seconds: Seconds::default(),
            settling: self.settling.map(|s| SettlingSummary { seconds: 0.0, ..s }),
            ..self.clone()
        }
    }
}

/// Whether a counter is zero (left out of the summary).
fn is_zero(n: &u64) -> bool {
    *n == 0
}
