//! The time-stepping engine: one step is
//! blocks -> neighbour pairs -> contacts -> system -> solve -> open-close iteration ->
//! update (docs/method.md).
//!
//! - Detection runs once per step at its start. The pattern of the global matrix must hold
//!   every pair with candidates; it is set to all free neighbour pairs and kept, step
//!   after step, until a needed pair is missing.
//! - Each attempt linearises the active contacts' rows at its predicted midpoint: every
//!   block moved by half of V dt (`springs::HalfStep`, `linearise`); a contact tracking
//!   activates is linearised there when it is.
//! - Before the OCI, contact states are predicted from the step's right-hand side solved
//!   with the previous step's factor (`predict_states`).
//! - The open-close iteration (OCI) assembles the springs of the active closed contacts,
//!   solves, and re-checks every contact: open/closed by the sign of the normal distance
//!   (or the tensile strength of a bonded contact), locked/sliding by Mohr-Coulomb; with
//!   the cover detector, inactive covers the trial motion enters through become active
//!   (paper eq. 12-13). It ends when nothing changes.
//! - Solving: an attempt's first iteration assembles and factorises the system. Later
//!   iterations differ from the factorised matrix only by the springs that opened or
//!   closed since; while there are at most `MAX_RANK` of them, the iteration solves
//!   through a low-rank update of that factor (Woodbury, `BlockSystem::solve_low_rank`),
//!   its right-hand side changes included, and assembles nothing; beyond that it
//!   factorises anew.
//! - Time-step control: if OCI has not converged in `max_oci` iterations the step is
//!   redone with dt / 3; if the largest vertex displacement exceeds d_max or the largest
//!   rotation exceeds theta_max, with dt scaled down in proportion. After an easy step
//!   (OCI in at most two thirds of the bound, [`easy_oci`]) dt grows by up to 1.25, as
//!   far as the step's motion scaled with dt stays within 0.8 of d_max and theta_max
//!   ([`step_growth`]), never past the initial step. The last step is shortened to land
//!   on `duration`. These factors are our choice: Shi's formulation and the paper fix only
//!   the criteria.
//! - Update: vertices move by T D with the rotation applied exactly; stresses accumulate
//!   C (ex, ey, gxy); velocities V <- 2 D / dt - V (dynamic) or 0 (static).

use crate::effects::Effects;
use crate::guard::{self, ENERGY_TOLERANCE, EnergyBalance, Violation};
use crate::kinematics::{Mat6, Vec6, along, elasticity, mass_matrix, point_displacement};
use crate::scene::{JointProps, Mode, Model};
use crate::springs::{HalfStep, Row, contact_length, contact_points, normal_row, shear_row};
use crate::system::{BlockSystem, Entry, RankOne, SolveError};
use dda_contact::{
    BlockShape, ContactDetector, ContactSet, ContactState, DetectionParams, NeighbourPair,
    NeighbourSearch, TrackList, detector_by_name,
};
use dda_geom::{
    Aabb, ConvexPolygon, DVec2, Motion, VertexEdge, check_displacement, displace_point, separation,
};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Why a simulation cannot go on; the state stays at the last completed step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The time step shrank below its floor without a step converging.
    #[error("time step collapsed to {dt:.3e} s at t = {t:.6} s: {reason} (last good state kept)")]
    TimeStepCollapsed {
        /// Simulated time of the last good state.
        t: f64,
        /// The step size that failed.
        dt: f64,
        /// What kept failing.
        reason: String,
    },
    /// The global system could not be solved.
    #[error("at t = {t:.6} s: {source} (last good state kept)")]
    Solve {
        /// Simulated time of the last good state.
        t: f64,
        /// The solver's error.
        source: SolveError,
    },
    /// The solution of the global system is not finite (NaN or infinite).
    #[error(
        "at t = {t:.6} s: the solution is not finite for block `{block}` (last good state kept)"
    )]
    NonFinite {
        /// Simulated time of the last good state.
        t: f64,
        /// Id of the first block with a non-finite motion.
        block: String,
    },
    /// A block would be turned inside out by the step.
    #[error("at t = {t:.6} s: block `{block}` would be inverted (last good state kept)")]
    Inverted {
        /// Simulated time of the last good state.
        t: f64,
        /// Block id.
        block: String,
    },
    /// The step would break physics: a penetration deeper than d_tol, or energy created
    /// beyond [`ENERGY_TOLERANCE`] ([`RunOptions::stop_on_violation`]).
    #[error("at t = {t:.6} s: {what} (last good state kept)")]
    BrokenPhysics {
        /// Simulated time of the last good state.
        t: f64,
        /// What broke, in words.
        what: String,
        /// Ids of the blocks involved.
        blocks: Vec<String>,
    },
}

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

/// What a failed run was doing when it stopped: which blocks and contacts were involved
/// and the step size that failed (summary.json's `failure`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Diagnosis {
    /// The error, in words.
    pub reason: String,
    /// Simulated time of the last good state, s.
    pub t: f64,
    /// The step size of the last failed attempt, s.
    pub last_dt: f64,
    /// Ids of the blocks involved (at most [`DIAGNOSIS_LIMIT`]).
    pub blocks: Vec<String>,
    /// The contacts involved (at most [`DIAGNOSIS_LIMIT`]).
    pub contacts: Vec<ContactNote>,
}

/// Most blocks and contacts a [`Diagnosis`] lists.
pub const DIAGNOSIS_LIMIT: usize = 20;

/// A contact named in a [`Diagnosis`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ContactNote {
    /// Id of the block owning the vertex.
    pub vertex_block: String,
    /// Vertex index in that block.
    pub vertex: u32,
    /// Id of the block owning the edge.
    pub edge_block: String,
    /// Edge index in that block (from vertex `edge` to `edge + 1`).
    pub edge: u32,
    /// State at the last good state: "open", "locked" or "sliding".
    pub state: String,
    /// Normal distance at the start of the failed step, m (negative: penetrating).
    pub d_n: f64,
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

/// Options of a run that are not part of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunOptions {
    /// Detect contacts on the thread pool (results are identical either way).
    pub parallel: bool,
    /// Stop with [`SimError::BrokenPhysics`] at the first step that breaks physics
    /// (penetration beyond d_tol, energy created beyond [`ENERGY_TOLERANCE`]), keeping
    /// the state before it. Off, the step is taken and the violation recorded
    /// ([`Simulation::violations`]). The `dda` command turns it on unless
    /// `--keep-going`; off by default for library users who judge runs themselves (the
    /// sweeps and the robustness study record what a detector does wrong).
    pub stop_on_violation: bool,
    /// Most bytes the factor of the global matrix may take (None: no bound but the
    /// allocator's, whose failure is still an error, not an abort).
    pub max_memory: Option<u64>,
}

impl Default for RunOptions {
    /// Sequential. Measured on this project's 2-core machine, the thread pool did not pay
    /// at any size tried: paper 5.2b (826 blocks), detection 0.72-0.80 s with threads
    /// against 0.60-0.64 s without over the run, per-block terms in assembly 1.19-1.29 s
    /// against 1.12-1.17 s; 10,131 blocks, detection 17.7 against 16.8 ms per step. Most
    /// of the detection time is tracking in the open-close iteration and the neighbour
    /// search, which are sequential, and the parallel parts are too short per step to
    /// pay for waking the pool.
    fn default() -> Self {
        RunOptions {
            parallel: false,
            stop_on_violation: false,
            max_memory: None,
        }
    }
}

/// Fewest free blocks for which per-block terms are computed on the thread pool (when
/// [`RunOptions::parallel`] is on): below it, waking the pool costs more than it saves.
const PARALLEL_MIN_BLOCKS: usize = 256;

/// Most OCI iterations of an easy step (after which dt may grow): two thirds of the bound
/// `max_oci`, rounded up (4 of 6). Our choice; Shi's formulation and the paper fix only the
/// criteria. In a large column a few of its many contacts change state in almost every
/// iteration, so a bound of half (3 of 6) held dt back as N grew. Measured with 4 against
/// 3 (counts, `docs/performance.md`): 111,460 blocks (0.1 s) 954 OCI iterations and 601
/// factorisations against 1,287 and 844; 3,472 blocks 574 and 293 against 641 and 334;
/// 10,131 blocks 691 and 380 against 725 and 361; the 826-block column over five
/// trajectories (`cargo xtask target`) 17,712 and 5,927 against 17,902 and 5,785. 5 of 6
/// gave 20 step cuts at 3,472 blocks and no gain.
pub fn easy_oci(max_oci: u32) -> u32 {
    (2 * max_oci).div_ceil(3)
}

/// Largest factor by which dt grows after one step.
const MAX_GROWTH: f64 = 1.25;

/// Fraction of d_max and theta_max that the next step's motion, scaled in proportion to
/// dt, may reach when dt grows after an easy step. Our choice. Until this rule dt grew by
/// 1.25 only after a step that moved at most half of d_max (0.625 of d_max predicted),
/// and a collapsing column, whose steps are limited by d_max, stayed at one dt for
/// hundreds of steps. Measured over the five trajectories of `cargo xtask target`
/// (826 blocks): steps, OCI iterations and factorisations 4,775, 18,308 and 6,173 under
/// the old rule; with this rule at 0.625, 0.7, 0.8 and 0.9 of d_max: 4,357, 17,456 and
/// 5,828; 4,198, 17,116 and 5,811; 4,032, 16,910 and 5,886; 3,889, 16,697 and 6,039
/// (more cuts, 166 against 91). The 3,472- and 10,131-block columns (0.1 s) are OCI
/// limited and took the same steps either way.
const GROWTH_TARGET: f64 = 0.8;

/// Factor by which dt grows after an accepted step that took `iterations` OCI iterations
/// (of at most `max_oci`) and whose largest vertex displacement and rotation were `disp`
/// and `rot`: 1 unless the step was easy ([`easy_oci`]); otherwise as far as that motion,
/// scaled in proportion to dt, stays within `GROWTH_TARGET` of `d_max` and `theta_max`,
/// between 1 and `MAX_GROWTH`.
pub fn step_growth(
    iterations: u32,
    max_oci: u32,
    disp: f64,
    rot: f64,
    d_max: f64,
    theta_max: f64,
) -> f64 {
    if iterations > easy_oci(max_oci) {
        return 1.0;
    }
    (GROWTH_TARGET * motion_room(disp, rot, d_max, theta_max)).clamp(1.0, MAX_GROWTH)
}

/// How many times a step's largest displacement `disp` and rotation `rot` fit within
/// `d_max` and `theta_max` (the smaller ratio): below 1 the step moved too far, and dt
/// scales by it either way, down after a cut and up in [`step_growth`].
fn motion_room(disp: f64, rot: f64, d_max: f64, theta_max: f64) -> f64 {
    (d_max / disp.max(f64::MIN_POSITIVE)).min(theta_max / rot.max(f64::MIN_POSITIVE))
}

/// Floor of the time step, relative to the initial step: below it the run stops.
const DT_FLOOR: f64 = 1e-9;

/// Most springs that may differ from the factorised matrix before an OCI iteration
/// assembles and factorises anew rather than solving through a low-rank update. Measured
/// on paper 5.2b (4,956 unknowns, one run each) with the half-sweep low-rank solve
/// (`BlockSystem::solve_low_rank`): solve seconds per OCI iteration 1.43 ms at 24, 1.34
/// at 48, 1.12 at 64, 1.11 at 80, 1.03 at 96, 1.11 at 128 and 1.14 at 200 (a
/// factorisation costs about 2.7 ms; beyond about 100 terms the capacitance matrix and
/// the Gram products of the new columns cost as much). With full solves per column it
/// had been 1.85 ms at 24 and 2.02 at 64. Measured again after the dt growth rule: a
/// low-rank solve of rank 100-149 costs 1.25 ms and one of 150-199 2.41 ms; at a bound
/// of 200 the run saved 302 factorisations and lost more in low-rank solves
/// (`docs/performance.md`).
const MAX_RANK: usize = 96;

/// How near (in d_tol, by separating-axis gap) two free blocks must be for a new matrix
/// pattern to couple them before they have contacts. Measured on paper 5.2b (826 blocks,
/// one run each): coupling every pair whose boxes are within d_tol gave 58 symbolic
/// analyses and 530-580k nonzeros in L, 3.2 ms per factorisation; coupling only the
/// needed pairs, 340 analyses and 335k nonzeros (2.3 ms), but each analysis costs the
/// next step its predicted states; margins of 2, 3, 4 and 6 d_tol gave 34, 21, 14 and
/// 9 analyses with 374k, 384k, 408k and 443k nonzeros (2.71, 2.76, 2.82 and 2.80 ms).
const PATTERN_MARGIN: f64 = 2.0;

/// The neighbour search's skin, in d_max: its pairs are found for d_tol plus twice the
/// skin and reused while no block's box has moved by more than the skin
/// ([`NeighbourSearch::with_skin`]). The pairs are the same whatever the skin; only
/// the number of sweeps changes. Measured on paper 5.2b (826 blocks, 844 steps): skins
/// of 1, 2, 3 and 5 d_max swept at 416, 289, 222 and 162 steps, and the search took
/// 0.81%, 0.60%, 0.61% and 0.48% of the run's samples against 1.20% sweeping every
/// step; at r_tol = 10, 1 and 2 d_max swept 68 and 38 times in 635 steps, 0.38% and
/// 0.44% against 0.87%.
const NEIGHBOUR_SKIN: f64 = 2.0;

/// A spring in effect in an OCI iteration: its contact, whether it is the shear spring
/// (else the normal one), its penalty, where it couples in the system, and what its row
/// depends on besides the attempt's geometry: nothing for a normal spring (its row is
/// the contact's in `rows`), the locked point for a shear spring. Two springs of one
/// attempt that compare equal have the same row ([`Simulation::spring_row`]).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Spring {
    contact: u32,
    shear: bool,
    penalty: f64,
    /// The system entry coupling its two blocks, if both are free.
    entry: Option<Entry>,
    /// The shear spring's locked point (ratio along the edge); 0 for a normal spring.
    anchor: f64,
}

impl Spring {
    /// Its row in the attempt whose contact rows are `rows` (see
    /// [`Simulation::spring_row`]).
    #[inline]
    fn row(&self, rows: &[Row], set: &ContactSet, shapes: &[BlockShape], half: &[HalfStep]) -> Row {
        let k = self.contact as usize;
        if self.shear {
            shear_row(&set.contacts[k], shapes, half, self.anchor)
        } else {
            rows[k]
        }
    }
}

/// The row of an inactive contact until it becomes active: NaN, so that a read of it
/// could not pass unseen.
const NO_ROW: Row = Row {
    g0: f64::NAN,
    blocks: [0, 0],
    c: [[0.0; 6]; 2],
};

/// A running simulation of a validated scene.
pub struct Simulation {
    model: Model,
    effects: Effects,
    detector: Box<dyn ContactDetector>,
    detection: DetectionParams,
    options: RunOptions,
    nd: usize,
    blocks: Vec<BlockState>,
    shapes: Vec<BlockShape>,
    /// Free-block index of each block (None: fixed).
    free: Vec<Option<u32>>,
    /// Material of each block, packed: the joint lookups of every contact in every OCI
    /// iteration read it (the model's blocks are large records, mostly cache misses).
    material: Vec<u32>,
    /// Block index of each free block: the inverse of `free`.
    free_blocks: Vec<u32>,
    n_free: usize,
    t: f64,
    dt: f64,
    totals: Totals,
    contacts: ContactSet,
    // Work buffers, reused from step to step.
    system: BlockSystem,
    prev: ContactSet,
    /// The candidates trajectory tracking may activate in this step.
    track_list: TrackList,
    neighbours: NeighbourSearch,
    pairs: Vec<NeighbourPair>,
    /// The contacts at step start, restored when an attempt is cut.
    saved: Vec<dda_contact::Contact>,
    /// Neighbour pairs within the pattern margin (only when a new pattern is made).
    pattern_pairs: Vec<NeighbourPair>,
    aabbs: Vec<Aabb>,
    block_pairs: Vec<(u32, u32)>,
    /// The system's pattern: the needed pairs when it was last set, widened.
    pattern: Vec<(u32, u32)>,
    pair_entry: Vec<Option<Entry>>,
    /// Each block's half step, where the attempt's contact rows are linearised.
    half: Vec<HalfStep>,
    /// Each active contact's normal row for the attempt (an inactive one's is a NaN
    /// placeholder until it becomes active: only active contacts' rows are read).
    rows: Vec<Row>,
    springs: Vec<Spring>,
    /// Friction forces in effect: contact, magnitude, row.
    forces: Vec<(u32, f64, Row)>,
    factored_springs: Vec<Spring>,
    factored_forces: Vec<(u32, f64, Row)>,
    changes: Vec<RankOne>,
    rhs_changes: Vec<RankOne>,
    /// Whether the system's factor is of this attempt's matrix (with `factored_springs`).
    factor_current: bool,
    base_k: Vec<Mat6>,
    base_f: Vec<Vec6>,
    mass: Vec<Mat6>,
    d: Vec<Vec6>,
    /// The trial motion of each block as a map of its points.
    motions: Vec<Motion>,
    /// Contacts whose state changed in the last OCI iteration (for a diagnosis).
    flipped: Vec<u32>,
    /// Why the run stopped, once it has.
    diagnosis: Option<Diagnosis>,
    /// The physics guard's energy balance (saved).
    energy: EnergyBalance,
    /// Energy below the model's resolution, added to the guard's reference (see
    /// `guard`): every free block lowered by d_tol, and a spring over the start overlap.
    energy_floor: f64,
    /// Violations recorded so far (saved).
    violations: Vec<Violation>,
    /// Each free block's gain of kinetic energy in the step (scratch of the guard).
    gains: Vec<(f64, usize)>,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("scene", &self.model.name)
            .field("t", &self.t)
            .field("dt", &self.dt)
            .field("blocks", &self.blocks.len())
            .finish()
    }
}

impl Simulation {
    /// Sets up a run of `model` at t = 0.
    pub fn new(model: Model, options: RunOptions) -> Self {
        let effects = Effects::of(&model);
        let p = &model.params;
        // Validation accepted the name, so this only falls back on a programming error.
        let detector =
            detector_by_name(&p.detector).unwrap_or_else(|_| Box::new(dda_contact::CoverDetector));
        let detection = DetectionParams::new(p.d_tol, p.theta_max);
        let mut free = Vec::with_capacity(model.blocks.len());
        let mut n_free = 0u32;
        for b in &model.blocks {
            if b.fixed {
                free.push(None);
            } else {
                free.push(Some(n_free));
                n_free += 1;
            }
        }
        let blocks: Vec<BlockState> = model
            .blocks
            .iter()
            .map(|b| BlockState {
                polygon: b.polygon.clone(),
                velocity: if b.fixed { [0.0; 6] } else { b.velocity },
                stress: if effects.elasticity {
                    b.stress
                } else {
                    [0.0; 3]
                },
                rotation: 0.0,
                loads: b.loads.clone(),
                fixed_points: b.fixed_points.iter().map(|&q| (q, q)).collect(),
            })
            .collect();
        let shapes = blocks.iter().map(|b| BlockShape::new(&b.polygon)).collect();
        let material = model.blocks.iter().map(|b| b.material as u32).collect();
        let n = blocks.len();
        let skin = NEIGHBOUR_SKIN * model.params.d_max;
        let mut system = BlockSystem::new();
        system.memory_limit = options.max_memory;
        let mut energy_floor = 0.0;
        let mut initial = 0.0;
        for (i, b) in blocks.iter().enumerate() {
            if model.blocks[i].fixed {
                continue;
            }
            let mat = model.materials[model.blocks[i].material];
            let m = b.polygon.moments();
            let g = p.gravity.map_or(0.0, |g| g.length());
            let overlap = 1e-9 * b.polygon.diameter();
            energy_floor +=
                mat.density * m.area * g * p.d_tol + 0.5 * p.normal_penalty * overlap * overlap;
            initial += guard::kinetic(&mass_matrix(&m, mat.density), &b.velocity);
            if effects.elasticity {
                initial += guard::strain(m.area, &b.stress, mat.young, mat.poisson);
            }
        }
        Simulation {
            dt: p.dt0,
            nd: effects.dofs_per_block(),
            model,
            effects,
            detector,
            detection,
            options,
            blocks,
            shapes,
            free_blocks: (0..free.len() as u32)
                .filter(|&i| free[i as usize].is_some())
                .collect(),
            material,
            free,
            n_free: n_free as usize,
            t: 0.0,
            totals: Totals::default(),
            contacts: ContactSet::default(),
            system,
            prev: ContactSet::default(),
            track_list: TrackList::new(),
            neighbours: NeighbourSearch::with_skin(skin),
            pairs: Vec::new(),
            saved: Vec::new(),
            pattern_pairs: Vec::new(),
            aabbs: Vec::with_capacity(n),
            block_pairs: Vec::new(),
            pattern: Vec::new(),
            pair_entry: Vec::new(),
            half: Vec::with_capacity(n),
            rows: Vec::new(),
            springs: Vec::new(),
            forces: Vec::new(),
            factored_springs: Vec::new(),
            factored_forces: Vec::new(),
            changes: Vec::new(),
            rhs_changes: Vec::new(),
            factor_current: false,
            base_k: Vec::new(),
            base_f: Vec::new(),
            mass: Vec::new(),
            d: vec![[0.0; 6]; n],
            motions: Vec::with_capacity(n),
            flipped: Vec::new(),
            diagnosis: None,
            energy: EnergyBalance {
                supplied: initial,
                supplied_max: initial,
                worst_ratio: 0.0,
            },
            energy_floor,
            violations: Vec::new(),
            gains: Vec::new(),
        }
    }

    /// Violations of physics recorded so far by a run that goes on through them
    /// ([`RunOptions::stop_on_violation`] off).
    pub fn violations(&self) -> &[Violation] {
        &self.violations
    }

    /// The physics guard's energy balance so far.
    pub fn energy_balance(&self) -> &EnergyBalance {
        &self.energy
    }

    /// The validated scene.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The effects this run assembles.
    pub fn effects(&self) -> &Effects {
        &self.effects
    }

    /// The detector's name.
    pub fn detector_name(&self) -> &str {
        self.detector.name()
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.t
    }

    /// The current (controlled) step size, s.
    pub fn time_step(&self) -> f64 {
        self.dt
    }

    /// Whether the run has reached its duration.
    pub fn finished(&self) -> bool {
        self.t >= self.model.params.duration
    }

    /// The blocks' states.
    pub fn blocks(&self) -> &[BlockState] {
        &self.blocks
    }

    /// The contacts at the end of the last step.
    pub fn contacts(&self) -> &ContactSet {
        &self.contacts
    }

    /// Counters so far.
    pub fn totals(&self) -> &Totals {
        &self.totals
    }

    /// Unknowns of the global system.
    pub fn unknowns(&self) -> usize {
        self.n_free * self.nd
    }

    /// Number of symbolic factorisations, numeric factorisations and low-rank solves so
    /// far.
    pub fn factorisations(&self) -> (u64, u64, u64) {
        (
            self.system.symbolic_count,
            self.system.numeric_count,
            self.system.low_rank_count,
        )
    }

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

    /// Why the run stopped, once a step has failed: the blocks and contacts involved.
    pub fn diagnosis(&self) -> Option<&Diagnosis> {
        self.diagnosis.as_ref()
    }

    /// Runs to the scene's duration, calling `on_step` after every step.
    pub fn run(
        &mut self,
        mut on_step: impl FnMut(&Simulation, &StepRecord),
    ) -> Result<(), SimError> {
        while !self.finished() {
            let rec = self.step()?;
            on_step(self, &rec);
        }
        Ok(())
    }

    /// Advances one step (with as many retries as the time-step control needs). On an
    /// error the state stays at the last completed step and [`Simulation::diagnosis`]
    /// says what was involved.
    pub fn step(&mut self) -> Result<StepRecord, SimError> {
        let mut last_dt = self.dt;
        let mut worst = None;
        let result = self.try_step(&mut last_dt, &mut worst);
        if let Err(e) = &result {
            self.diagnose(e, last_dt, worst);
        }
        result
    }

    /// [`Simulation::step`], reporting the last attempted step size and the block that
    /// moved most in the last attempt.
    fn try_step(
        &mut self,
        last_dt: &mut f64,
        worst: &mut Option<usize>,
    ) -> Result<StepRecord, SimError> {
        let started = Instant::now();
        let mut rec = StepRecord::default();
        let t_det = Instant::now();
        self.detect_step_start();
        rec.detection_s += t_det.elapsed().as_secs_f64();
        rec.candidates = self.contacts.len();

        let t_pat = Instant::now();
        self.set_pattern()?;
        rec.assembly_s += t_pat.elapsed().as_secs_f64();
        self.saved.clone_from(&self.contacts.contacts);
        let p = &self.model.params;
        let (duration, d_max, theta_max, max_oci, dt0) =
            (p.duration, p.d_max, p.theta_max, p.max_oci, p.dt0);
        let remaining = duration - self.t;
        // The step respects the motion it starts with: no block's current velocity may
        // carry a vertex beyond d_max, or turn it beyond theta_max, within it.
        let planned = self.dt.min(self.velocity_room());
        // Land on `duration`; a remainder within 1e-6 of a step is taken with it rather
        // than left as a sliver step.
        let landing = planned * (1.0 + 1e-6) >= remaining;
        let mut dt = if landing { remaining } else { planned };

        let mut first_attempt = true;
        loop {
            *last_dt = dt;
            let t_asm = Instant::now();
            self.linearise(dt);
            self.base_terms(dt);
            rec.assembly_s += t_asm.elapsed().as_secs_f64();
            if first_attempt {
                self.predict_states(&mut rec);
                first_attempt = false;
            }
            // The first OCI iteration of every attempt factorises its own matrix.
            self.factor_current = false;
            let (converged, iterations) = self.open_close_iteration(&mut rec)?;
            self.totals.oci_iterations += iterations as u64;
            let reason;
            if converged {
                let (disp, rot, moved_most) = self.largest_motion();
                *worst = moved_most;
                if disp <= d_max && rot <= theta_max {
                    rec.oci = iterations;
                    let growth = step_growth(iterations, max_oci, disp, rot, d_max, theta_max);
                    self.accept(dt, &mut rec)?;
                    if landing {
                        self.t = duration;
                    } else {
                        self.dt = (dt * growth).min(dt0);
                    }
                    break;
                }
                let ratio = motion_room(disp, rot, d_max, theta_max);
                dt *= (0.9 * ratio).clamp(0.1, 0.9);
                reason = "step displacement above d_max or rotation above theta_max";
            } else {
                dt /= 3.0;
                reason = "open-close iteration did not converge";
            }
            rec.cuts += 1;
            self.totals.cuts += 1;
            self.contacts.contacts.copy_from_slice(&self.saved);
            if dt < DT_FLOOR * dt0 {
                return Err(SimError::TimeStepCollapsed {
                    t: self.t,
                    dt,
                    reason: reason.to_string(),
                });
            }
        }
        self.totals.steps += 1;
        rec.step = self.totals.steps;
        rec.t = self.t;
        rec.active_contacts = self.contacts.active().count();
        rec.closed_contacts = self.contacts.closed_count();
        rec.kinetic_energy = self.kinetic_energy();
        self.totals.max_penetration = self.totals.max_penetration.max(rec.max_penetration);
        self.totals.detection_s += rec.detection_s;
        self.totals.assembly_s += rec.assembly_s;
        self.totals.solve_s += rec.solve_s;
        self.totals.total_s += started.elapsed().as_secs_f64();
        Ok(rec)
    }

    /// Step-start detection with states inherited from the previous step, then the
    /// engine's normalisation: closed contacts of frictionless joints slide (no shear
    /// spring), and at t = 0 closed contacts of bonding joints start bonded.
    fn detect_step_start(&mut self) {
        self.aabbs.clear();
        self.aabbs.extend(self.shapes.iter().map(|s| s.aabb));
        self.neighbours
            .find(&self.aabbs, self.detection.d_tol, &mut self.pairs);
        let free = &self.free;
        self.pairs
            .retain(|p| free[p.a as usize].is_some() || free[p.b as usize].is_some());
        std::mem::swap(&mut self.prev, &mut self.contacts);
        dda_contact::detect(
            self.detector.as_ref(),
            &self.shapes,
            &self.pairs,
            &self.detection,
            &self.prev,
            self.options.parallel,
            &mut self.contacts,
        );
        let first = self.totals.steps == 0;
        for k in 0..self.contacts.contacts.len() {
            // Open contacts are left as they are: only closed ones need their joint.
            if !self.contacts.contacts[k].state.is_closed() {
                continue;
            }
            let j = self.joint(k);
            let c = &mut self.contacts.contacts[k];
            if !j.has_shear() {
                c.state = ContactState::Sliding;
            }
            if first && c.active && c.state.is_closed() && j.bonds() {
                c.bonded = true;
            }
        }
        self.track_list
            .rebuild(self.detector.as_ref(), &self.shapes, &self.contacts);
    }

    /// Fixes the pattern of the global matrix from the candidate pairs between free
    /// blocks, reusing the symbolic factorisation when the pattern is unchanged.
    fn set_pattern(&mut self) -> Result<(), SimError> {
        self.block_pairs.clear();
        for pc in &self.contacts.pairs {
            if let (Some(a), Some(b)) =
                (self.free[pc.pair.a as usize], self.free[pc.pair.b as usize])
            {
                self.block_pairs.push((a.min(b), a.max(b)));
            }
        }
        self.block_pairs.sort_unstable();
        self.block_pairs.dedup();
        if !is_subset(&self.block_pairs, &self.pattern) {
            // A new pattern: the needed pairs and every free pair whose polygons are
            // within PATTERN_MARGIN d_tol (separating-axis gap), contacts or not, so that
            // it holds while blocks shift among their neighbours. It is kept until a
            // needed pair is missing.
            self.pattern.clone_from(&self.block_pairs);
            let margin = PATTERN_MARGIN * self.detection.d_tol;
            self.neighbours
                .find(&self.aabbs, margin, &mut self.pattern_pairs);
            for q in &self.pattern_pairs {
                let (pa, pb) = (&self.blocks[q.a as usize], &self.blocks[q.b as usize]);
                if let (Some(a), Some(b)) = (self.free[q.a as usize], self.free[q.b as usize])
                    && separation(&pa.polygon, &pb.polygon).0 < margin
                {
                    self.pattern.push((a.min(b), a.max(b)));
                }
            }
            self.pattern.sort_unstable();
            self.pattern.dedup();
        }
        self.system
            .set_pattern(self.n_free, self.nd, &self.pattern)
            .map_err(|source| SimError::Solve { t: self.t, source })?;
        self.pair_entry.clear();
        for pc in &self.contacts.pairs {
            let e = match (self.free[pc.pair.a as usize], self.free[pc.pair.b as usize]) {
                (Some(a), Some(b)) => self.system.entry(a, b),
                _ => None,
            };
            self.pair_entry.push(e);
        }
        Ok(())
    }

    /// Per-block terms that do not depend on contacts (see [`block_terms`]), one per free
    /// block in free-block order. With `parallel` they are computed on the thread pool:
    /// each block's terms depend on that block alone, so the result is the same.
    fn base_terms(&mut self, dt: f64) {
        let n = self.free_blocks.len();
        self.base_k.resize(n, [[0.0; 6]; 6]);
        self.base_f.resize(n, [0.0; 6]);
        self.mass.resize(n, [[0.0; 6]; 6]);
        let (model, blocks, eff) = (&self.model, &self.blocks, self.effects);
        let terms = |(((k, f), mass), &i): (((&mut Mat6, &mut Vec6), &mut Mat6), &u32)| {
            (*k, *f, *mass) = block_terms(model, eff, &blocks[i as usize], i as usize, dt);
        };
        #[cfg(feature = "rayon")]
        if self.options.parallel && n >= PARALLEL_MIN_BLOCKS {
            use rayon::prelude::*;
            self.base_k
                .par_iter_mut()
                .zip(self.base_f.par_iter_mut())
                .zip(self.mass.par_iter_mut())
                .zip(self.free_blocks.par_iter())
                .for_each(terms);
            return;
        }
        self.base_k
            .iter_mut()
            .zip(self.base_f.iter_mut())
            .zip(self.mass.iter_mut())
            .zip(self.free_blocks.iter())
            .for_each(terms);
    }

    /// The joint of a contact.
    fn joint(&self, k: usize) -> JointProps {
        let key = self.contacts.contacts[k].key;
        let m = |b: u32| self.material[b as usize] as usize;
        *self
            .model
            .joint_of_materials(m(key.vertex_block), m(key.edge_block))
    }

    /// Sets the half step of every block for an attempt of size `dt` and the contacts'
    /// normal rows, linearised there (see `springs`).
    fn linearise(&mut self, dt: f64) {
        self.half.clear();
        for (i, s) in self.shapes.iter().enumerate() {
            self.half.push(match self.free[i] {
                Some(_) => HalfStep::new(s.centroid, &self.blocks[i].velocity, dt),
                None => HalfStep::at_rest(s.centroid),
            });
        }
        self.rows.clear();
        for c in &self.contacts.contacts {
            self.rows.push(if c.active {
                normal_row(c, &self.shapes, &self.half)
            } else {
                NO_ROW
            });
        }
    }

    /// Sets up the contacts made active since [`Simulation::linearise`] (by trajectory
    /// tracking, or a spring moved to the deepest face; the ones whose row is still
    /// [`NO_ROW`]): their rows are linearised as `linearise` would have, and those
    /// tracking brought back locked slide instead where the joint has no shear (every
    /// other closed contact of such a joint slides already: the step-start normalisation
    /// and `update_states` see to it).
    fn set_up_new_active(&mut self) {
        for k in 0..self.contacts.contacts.len() {
            let c = self.contacts.contacts[k];
            if !(c.active && self.rows[k].g0.is_nan()) {
                continue;
            }
            self.rows[k] = normal_row(&c, &self.shapes, &self.half);
            if c.state == ContactState::Locked && !self.joint(k).has_shear() {
                self.contacts.contacts[k].state = ContactState::Sliding;
            }
        }
    }

    /// Collects the springs and friction forces of the current contact states: the active
    /// closed contacts' normal springs, and, where the joint has shear, locked contacts'
    /// shear springs and sliding contacts' friction forces.
    fn collect_springs(&mut self) {
        self.springs.clear();
        self.forces.clear();
        let p = &self.model.params;
        let (pn, ps) = (p.normal_penalty, p.shear_penalty);
        for (pk, pc) in self.contacts.pairs.iter().enumerate() {
            let entry = self.pair_entry[pk];
            for k in pc.start as usize..pc.end as usize {
                let c = self.contacts.contacts[k];
                if !(c.active && c.state.is_closed()) {
                    continue;
                }
                let contact = k as u32;
                self.springs.push(Spring {
                    contact,
                    shear: false,
                    penalty: pn,
                    entry,
                    anchor: 0.0,
                });
                let j = self.joint(k);
                if !j.has_shear() {
                    continue;
                }
                match c.state {
                    ContactState::Locked => {
                        self.springs.push(Spring {
                            contact,
                            shear: true,
                            penalty: ps,
                            entry,
                            anchor: c.locked_r,
                        });
                    }
                    ContactState::Sliding if c.slide_dir != 0.0 => {
                        let mut limit = c.normal_force.max(0.0) * j.tan_phi;
                        if c.bonded {
                            limit += j.cohesion * contact_length(&c, &self.shapes);
                        }
                        let row = shear_row(&c, &self.shapes, &self.half, c.r.clamp(0.0, 1.0));
                        self.forces.push((contact, -c.slide_dir * limit, row));
                    }
                    _ => {}
                }
            }
        }
    }

    /// The row of spring `s` in this attempt: the contact's normal row, or its shear row
    /// at the spring's locked point (computed again, by the same function on the same
    /// geometry, so the same bits).
    #[inline]
    fn spring_row(&self, s: &Spring) -> Row {
        s.row(&self.rows, &self.contacts, &self.shapes, &self.half)
    }

    /// Adds the right-hand side of the base terms, the springs and the forces.
    fn assemble_rhs(&mut self) {
        for (f, rhs) in self.base_f.iter().enumerate() {
            self.system.add_rhs(f as u32, 1.0, rhs);
        }
        for s in &self.springs {
            let row = self.spring_row(s);
            for (b, c) in row.blocks.iter().zip(&row.c) {
                if let Some(f) = self.free[*b as usize] {
                    self.system.add_rhs(f, -s.penalty * row.g0, c);
                }
            }
        }
        for (_, f, row) in &self.forces {
            for (b, c) in row.blocks.iter().zip(&row.c) {
                if let Some(fi) = self.free[*b as usize] {
                    self.system.add_rhs(fi, *f, c);
                }
            }
        }
    }

    /// Assembles K (base terms and springs) and F, and factorises and solves.
    fn assemble_and_factorise(&mut self, rec: &mut StepRecord) -> Result<(), SimError> {
        let t0 = Instant::now();
        self.system.clear();
        for (f, k) in self.base_k.iter().enumerate() {
            self.system.add_diagonal(f as u32, k);
        }
        for s in &self.springs {
            let row = self.spring_row(s);
            add_spring(&mut self.system, &self.free, s.entry, s.penalty, &row);
        }
        self.assemble_rhs();
        let t1 = Instant::now();
        rec.assembly_s += (t1 - t0).as_secs_f64();
        self.system
            .solve()
            .map_err(|source| SimError::Solve { t: self.t, source })?;
        rec.solve_s += t1.elapsed().as_secs_f64();
        self.factored_springs.clone_from(&self.springs);
        self.factored_forces.clone_from(&self.forces);
        self.factor_current = true;
        Ok(())
    }

    /// Predicts the contact states of a step before its first OCI iteration: the step's
    /// right-hand side, with the states inherited from the previous step, solved with the
    /// previous step's factor (same pattern; geometry and dt one step apart), and every
    /// active contact re-checked against that approximate motion. About a tenth of a
    /// collapsing column's contacts change state at each step; found here for the price
    /// of one solve, they no longer cost a factorisation in the OCI, which still decides
    /// every state and convergence with exact solves. Skipped when the pattern changed.
    /// (Our choice: the paper starts the OCI from the previous step's states.)
    fn predict_states(&mut self, rec: &mut StepRecord) {
        if !self.system.is_factored() {
            return;
        }
        let t0 = Instant::now();
        self.collect_springs();
        self.system.clear_rhs();
        self.assemble_rhs();
        let t1 = Instant::now();
        rec.assembly_s += (t1 - t0).as_secs_f64();
        let solved = self.system.resolve();
        rec.solve_s += t1.elapsed().as_secs_f64();
        if solved {
            let t2 = Instant::now();
            self.gather_solution();
            self.update_states();
            rec.assembly_s += t2.elapsed().as_secs_f64();
        }
    }

    /// The difference between the springs in effect and those in the factorised matrix,
    /// as rank-one terms (both lists are in contact order); None if it has more than
    /// [`MAX_RANK`] terms.
    fn spring_changes(&mut self) -> Option<()> {
        self.changes.clear();
        self.rhs_changes.clear();
        let (now, then) = (&self.springs, &self.factored_springs);
        let (mut i, mut j) = (0, 0);
        let free = &self.free;
        let (rows, set, shapes, half) = (&self.rows, &self.contacts, &self.shapes, &self.half);
        let (changes, rhs_changes) = (&mut self.changes, &mut self.rhs_changes);
        // A spring added (sign 1) or removed (-1): its stiffness p c c^T and its
        // right-hand side -p g0 c.
        let mut change = |s: &Spring, sign: f64| {
            let row = s.row(rows, set, shapes, half);
            let blocks = [free[row.blocks[0] as usize], free[row.blocks[1] as usize]];
            let p = sign * s.penalty;
            changes.push(RankOne {
                blocks,
                c: row.c,
                s: p,
            });
            rhs_changes.push(RankOne {
                blocks,
                c: row.c,
                s: -p * row.g0,
            });
            changes.len() <= MAX_RANK
        };
        while i < now.len() || j < then.len() {
            let key = |s: &Spring| (s.contact, s.shear);
            let within = match (now.get(i), then.get(j)) {
                (Some(a), Some(b)) if key(a) == key(b) => {
                    i += 1;
                    j += 1;
                    // Equal springs of one attempt have equal rows.
                    a == b || {
                        change(a, 1.0);
                        change(b, -1.0)
                    }
                }
                (Some(a), Some(b)) if key(a) < key(b) => {
                    i += 1;
                    change(a, 1.0)
                }
                (Some(a), None) => {
                    i += 1;
                    change(a, 1.0)
                }
                (_, Some(b)) => {
                    j += 1;
                    change(b, -1.0)
                }
                (None, None) => break,
            };
            if !within {
                return None;
            }
        }
        Some(())
    }

    /// Adds the changes of the friction forces since the factorisation to the
    /// right-hand side changes (both lists are in contact order).
    fn force_changes(&mut self) {
        let (now, then) = (&self.forces, &self.factored_forces);
        let free = &self.free;
        let mut change = |f: f64, row: &Row| {
            self.rhs_changes.push(RankOne {
                blocks: [free[row.blocks[0] as usize], free[row.blocks[1] as usize]],
                c: row.c,
                s: f,
            });
        };
        let (mut i, mut j) = (0, 0);
        while i < now.len() || j < then.len() {
            match (now.get(i), then.get(j)) {
                (Some(a), Some(b)) if a.0 == b.0 => {
                    if a.2 == b.2 {
                        if a.1 != b.1 {
                            change(a.1 - b.1, &a.2);
                        }
                    } else {
                        change(a.1, &a.2);
                        change(-b.1, &b.2);
                    }
                    i += 1;
                    j += 1;
                }
                (Some(a), Some(b)) if a.0 < b.0 => {
                    change(a.1, &a.2);
                    i += 1;
                }
                (Some(a), None) => {
                    change(a.1, &a.2);
                    i += 1;
                }
                (_, Some(b)) => {
                    change(-b.1, &b.2);
                    j += 1;
                }
                (None, None) => break,
            }
        }
    }

    /// Solves for the current contact states: through the factor already computed when
    /// few springs changed since, otherwise by assembling and factorising anew.
    fn solve_states(&mut self, rec: &mut StepRecord) -> Result<(), SimError> {
        let t0 = Instant::now();
        self.collect_springs();
        let shear = self.springs.iter().filter(|s| s.shear).count() as u64;
        self.totals.shear_springs += shear;
        self.totals.normal_springs += self.springs.len() as u64 - shear;
        self.totals.friction_forces += self.forces.len() as u64;
        if self.factor_current && self.system.is_factored() && self.spring_changes().is_some() {
            self.force_changes();
            let t1 = Instant::now();
            rec.assembly_s += (t1 - t0).as_secs_f64();
            let solved = self.system.solve_low_rank(&self.changes, &self.rhs_changes);
            rec.solve_s += t1.elapsed().as_secs_f64();
            if solved {
                return Ok(());
            }
        } else {
            rec.assembly_s += t0.elapsed().as_secs_f64();
        }
        self.assemble_and_factorise(rec)
    }

    /// Open-close iteration at step size `dt` (base terms already built). Returns whether
    /// it converged and how many iterations it took.
    fn open_close_iteration(&mut self, rec: &mut StepRecord) -> Result<(bool, u32), SimError> {
        let max_oci = self.model.params.max_oci;
        for it in 1..=max_oci {
            self.solve_states(rec)?;
            let t2 = Instant::now();
            self.gather_solution();
            if let Some(i) = (0..self.d.len()).find(|&i| self.d[i].iter().any(|x| !x.is_finite())) {
                return Err(SimError::NonFinite {
                    t: self.t,
                    block: self.model.blocks[i].id.clone(),
                });
            }
            let mut changed = self.update_states();
            rec.assembly_s += t2.elapsed().as_secs_f64();
            let t3 = Instant::now();
            let activated = self.track_list.track(
                self.detector.as_ref(),
                &self.shapes,
                &self.motions,
                &mut self.contacts,
            );
            if activated > 0 {
                self.set_up_new_active();
            }
            changed += activated;
            rec.detection_s += t3.elapsed().as_secs_f64();
            if changed == 0 {
                return Ok((true, it));
            }
        }
        Ok((false, max_oci))
    }

    /// Copies the solution into per-block motions (zero for fixed blocks).
    fn gather_solution(&mut self) {
        let nd = self.nd;
        self.motions.clear();
        for (i, f) in self.free.iter().enumerate() {
            self.d[i] = [0.0; 6];
            if let Some(f) = f {
                self.d[i][..nd].copy_from_slice(self.system.solution(*f));
            }
            self.motions
                .push(Motion::new(self.shapes[i].centroid, &self.d[i]));
        }
    }

    /// Re-checks every active contact against the trial solution; returns how many
    /// changed state.
    fn update_states(&mut self) -> usize {
        let p = &self.model.params;
        let (pn, ps) = (p.normal_penalty, p.shear_penalty);
        // A closed contact opens only beyond a band of 1e-9 d_tol: blocks that touch to
        // rounding (joint faces cut from one rock) otherwise chatter between open and
        // closed on d of order 1e-17 m and never converge. The tension held inside the
        // band, p * 1e-9 d_tol, is negligible (our choice; the paper is silent).
        let open_band = 1e-9 * p.d_tol;
        let mut changed = 0;
        self.flipped.clear();
        for k in 0..self.contacts.contacts.len() {
            let c = self.contacts.contacts[k];
            if !c.active {
                continue;
            }
            let j = self.joint(k);
            let d = self.rows[k].eval(&self.d);
            let mut n = c;
            match c.state {
                ContactState::Open => {
                    if d < 0.0 {
                        // Closes where its trajectory crossed the edge's line.
                        let r1 = self.trial_ratio(&c);
                        let t = if c.d_n > 0.0 {
                            c.d_n / (c.d_n - d)
                        } else {
                            0.0
                        };
                        n.locked_r = (c.r + t * (r1 - c.r)).clamp(0.0, 1.0);
                        n.state = if j.has_shear() {
                            ContactState::Locked
                        } else {
                            ContactState::Sliding
                        };
                        n.slide_dir = 0.0;
                        n.normal_force = -pn * d;
                    }
                }
                ContactState::Locked | ContactState::Sliding => {
                    // Only bonds need the length: looked up (a load from the edge block's
                    // shape, often a cache miss) only for them.
                    let length = || contact_length(&c, &self.shapes);
                    let holds_tension = c.bonded
                        && j.tensile_strength > 0.0
                        && pn * d <= j.tensile_strength * length();
                    if d > open_band && !holds_tension {
                        n.state = ContactState::Open;
                        n.bonded = false;
                        n.normal_force = 0.0;
                    } else {
                        n.normal_force = -pn * d;
                        if j.has_shear() {
                            if c.state == ContactState::Locked {
                                let s = shear_row(&c, &self.shapes, &self.half, c.locked_r)
                                    .eval(&self.d);
                                let mut limit = n.normal_force.max(0.0) * j.tan_phi;
                                if c.bonded {
                                    limit += j.cohesion * length();
                                }
                                if ps * s.abs() > limit {
                                    n.state = ContactState::Sliding;
                                    n.slide_dir = s.signum();
                                    n.bonded = false;
                                }
                            } else {
                                let s =
                                    shear_row(&c, &self.shapes, &self.half, c.r.clamp(0.0, 1.0))
                                        .eval(&self.d);
                                if c.slide_dir == 0.0 {
                                    n.slide_dir = s.signum();
                                } else if s * c.slide_dir < 0.0 {
                                    // The motion reversed against friction: it sticks.
                                    n.state = ContactState::Locked;
                                    n.locked_r = c.r.clamp(0.0, 1.0);
                                }
                            }
                        }
                    }
                }
            }
            if n.state != c.state || n.slide_dir != c.slide_dir {
                changed += 1;
                self.flipped.push(k as u32);
            }
            self.contacts.contacts[k] = n;
        }
        changed
    }

    /// Projection ratio of a contact's vertex on its edge at the trial positions.
    fn trial_ratio(&self, c: &dda_contact::Contact) -> f64 {
        let (p1, p2, p3) = contact_points(c, &self.shapes);
        let k = c.key;
        let (mv, me) = (
            &self.motions[k.vertex_block as usize],
            &self.motions[k.edge_block as usize],
        );
        VertexEdge::new(mv.apply(p1), me.apply(p2), me.apply(p3)).r
    }

    /// Largest vertex displacement (first order) and largest |rotation| of the trial
    /// solution.
    fn largest_motion(&self) -> (f64, f64, Option<usize>) {
        let (mut disp, mut rot) = (0.0f64, 0.0f64);
        let (mut worst, mut worst_ratio) = (None, 0.0);
        let p = &self.model.params;
        for (i, s) in self.shapes.iter().enumerate() {
            if self.free[i].is_none() {
                continue;
            }
            let d = &self.d[i];
            rot = rot.max(d[2].abs());
            let mut block_disp = 0.0f64;
            for &v in &s.vertices {
                block_disp = block_disp.max(point_displacement(v, s.centroid, d).length());
            }
            disp = disp.max(block_disp);
            let ratio = (block_disp / p.d_max).max(d[2].abs() / p.theta_max);
            if ratio > worst_ratio {
                (worst, worst_ratio) = (Some(i), ratio);
            }
        }
        (disp, rot, worst)
    }

    /// Commits the trial solution: moves blocks, updates stresses and velocities, and
    /// records penetration.
    fn accept(&mut self, dt: f64, rec: &mut StepRecord) -> Result<(), SimError> {
        let (mut max_pen, mut deepest) = (0.0f64, None);
        for (k, c) in self.contacts.contacts.iter().enumerate() {
            if c.active && c.state.is_closed() {
                let pen = -self.rows[k].eval(&self.d);
                if pen > max_pen {
                    (max_pen, deepest) = (pen, Some(k));
                }
            }
        }
        self.guard(dt, max_pen, deepest)?;
        rec.max_penetration = max_pen;
        rec.dt = dt;
        // Check every block's motion first, so that a failure leaves the state untouched.
        let (t, model) = (self.t, &self.model);
        let inverted = |i: usize| SimError::Inverted {
            t,
            block: model.blocks[i].id.clone(),
        };
        for i in 0..self.blocks.len() {
            if self.free[i].is_some() && check_displacement(&self.d[i]).is_err() {
                return Err(inverted(i));
            }
        }
        let dynamic = model.params.mode == Mode::Dynamic;
        for i in 0..self.blocks.len() {
            if self.free[i].is_none() {
                continue;
            }
            let d = self.d[i];
            let c = self.shapes[i].centroid;
            let b = &mut self.blocks[i];
            // Cannot fail: every motion was checked above.
            b.polygon.displace(c, &d).map_err(|_| inverted(i))?;
            for v in 0..6 {
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
            self.shapes[i].set(&b.polygon);
        }
        self.t += dt;
        Ok(())
    }

    /// Records what was involved in the failure `e`: for an OCI that did not converge,
    /// the contacts still changing state and their blocks; for a step too large, the
    /// block that moved most; for an inverted or non-finite block, that block and its
    /// contacts.
    fn diagnose(&mut self, e: &SimError, last_dt: f64, worst: Option<usize>) {
        let index = |id: &str| self.model.blocks.iter().position(|b| b.id == id);
        let mut blocks: Vec<usize> = Vec::new();
        let mut contacts: Vec<usize> = Vec::new();
        match e {
            SimError::TimeStepCollapsed { reason, .. } if reason.contains("open-close") => {
                contacts.extend(self.flipped.iter().map(|&k| k as usize));
            }
            SimError::TimeStepCollapsed { .. } => blocks.extend(worst),
            SimError::Inverted { block, .. } | SimError::NonFinite { block, .. } => {
                blocks.extend(index(block));
            }
            SimError::BrokenPhysics { blocks: ids, .. } => {
                blocks.extend(ids.iter().filter_map(|id| index(id)));
            }
            _ => {}
        }
        if contacts.is_empty() {
            // The closed contacts of the blocks named.
            contacts.extend((0..self.contacts.len()).filter(|&k| {
                let c = &self.contacts.contacts[k];
                let key = c.key;
                c.active
                    && c.state.is_closed()
                    && blocks
                        .iter()
                        .any(|&b| b == key.vertex_block as usize || b == key.edge_block as usize)
            }));
        }
        contacts.truncate(DIAGNOSIS_LIMIT);
        for &k in &contacts {
            let key = self.contacts.contacts.get(k).map(|c| c.key);
            if let Some(key) = key {
                for b in [key.vertex_block as usize, key.edge_block as usize] {
                    if !blocks.contains(&b) {
                        blocks.push(b);
                    }
                }
            }
        }
        blocks.truncate(DIAGNOSIS_LIMIT);
        let id = |b: usize| self.model.blocks[b].id.clone();
        let notes = contacts
            .iter()
            .filter_map(|&k| self.contacts.contacts.get(k))
            .map(|c| ContactNote {
                vertex_block: id(c.key.vertex_block as usize),
                vertex: c.key.vertex,
                edge_block: id(c.key.edge_block as usize),
                edge: c.key.edge,
                state: match c.state {
                    ContactState::Open => "open",
                    ContactState::Locked => "locked",
                    ContactState::Sliding => "sliding",
                }
                .to_string(),
                d_n: c.d_n,
            })
            .collect();
        self.diagnosis = Some(Diagnosis {
            reason: e.to_string(),
            t: self.t,
            last_dt,
            blocks: blocks.into_iter().map(id).collect(),
            contacts: notes,
        });
    }

    /// The largest step the blocks' current velocities allow: the smaller of d_max over
    /// the fastest vertex speed (strain rates included) and theta_max over the fastest
    /// spin, infinite when nothing moves.
    fn velocity_room(&self) -> f64 {
        let p = &self.model.params;
        let (mut speed, mut spin) = (0.0f64, 0.0f64);
        for (i, s) in self.shapes.iter().enumerate() {
            if self.free[i].is_none() {
                continue;
            }
            let v = &self.blocks[i].velocity;
            spin = spin.max(v[2].abs());
            for &x in &s.vertices {
                speed = speed.max(point_displacement(x, s.centroid, v).length());
            }
        }
        (p.d_max / speed).min(p.theta_max / spin)
    }

    /// The physics guard (see `guard`) on the trial solution of a step of `dt` whose
    /// deepest closed contact is `deepest`, `max_pen` deep: a violation stops the run
    /// before the step is committed, or is recorded, as the run's options say. Reads
    /// the state only, and updates the energy balance.
    fn guard(&mut self, dt: f64, max_pen: f64, deepest: Option<usize>) -> Result<(), SimError> {
        let p = &self.model.params;
        let dynamic = p.mode == Mode::Dynamic;
        let gravity = if self.effects.gravity {
            p.gravity.unwrap_or(DVec2::ZERO)
        } else {
            DVec2::ZERO
        };
        let (mut mechanical, mut work) = (0.0, 0.0);
        let mut gains = std::mem::take(&mut self.gains);
        gains.clear();
        for (f, &i) in self.free_blocks.iter().enumerate() {
            let i = i as usize;
            let (d, b, s) = (&self.d[i], &self.blocks[i], &self.shapes[i]);
            let mat = self.model.materials[self.material[i] as usize];
            let mass = &self.mass[f];
            let area = mass[0][0] / mat.density;
            let ke = if dynamic {
                let v: Vec6 = std::array::from_fn(|a| 2.0 * d[a] / dt - b.velocity[a]);
                guard::kinetic(mass, &v)
            } else {
                0.0
            };
            let mut u = 0.0;
            if self.effects.elasticity {
                let e = elasticity(mat.young, mat.poisson);
                let stress: [f64; 3] = std::array::from_fn(|a| {
                    b.stress[a] + (0..3).map(|q| e[a][q] * d[3 + q]).sum::<f64>()
                });
                u = guard::strain(area, &stress, mat.young, mat.poisson);
            }
            mechanical += ke + u;
            work += mat.density * area * gravity.dot(DVec2::new(d[0], d[1]));
            for &(at, force) in &b.loads {
                work += force.dot(point_displacement(at, s.centroid, d));
            }
            gains.push((ke - guard::kinetic(mass, &b.velocity), i));
        }
        let supplied = self.energy.supplied + work;
        let reference = self.energy.supplied_max.max(supplied) + self.energy_floor;
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
            let (what, blocks) = match deepest.map(|k| self.contacts.contacts[k].key) {
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
                 energy supplied ({supplied:.4e} J/m: initial energy and the work of \
                 gravity and loads) by {:.2}% of the reference {reference:.4e} J/m (more \
                 than {}%); the fastest-gaining blocks: {}",
                100.0 * ratio,
                100.0 * ENERGY_TOLERANCE,
                blocks.join(", ")
            );
            broken.push(("energy", what, blocks, ratio));
        }
        self.gains = gains;
        if let Some((_, what, blocks, _)) = broken.first()
            && self.options.stop_on_violation
        {
            return Err(SimError::BrokenPhysics {
                t: self.t,
                what: what.clone(),
                blocks: blocks.clone(),
            });
        }
        for (kind, what, _, worst) in broken {
            match self.violations.iter_mut().find(|v| v.kind == kind) {
                Some(v) => {
                    v.steps += 1;
                    v.worst = v.worst.max(worst);
                }
                None => self.violations.push(Violation {
                    kind: kind.to_string(),
                    first: what,
                    first_t: self.t,
                    steps: 1,
                    worst,
                }),
            }
        }
        self.energy.supplied = supplied;
        self.energy.supplied_max = self.energy.supplied_max.max(supplied);
        self.energy.worst_ratio = self.energy.worst_ratio.max(ratio);
        Ok(())
    }

    /// Kinetic energy of the free blocks, 1/2 V^T M V.
    pub fn kinetic_energy(&self) -> f64 {
        let mut e = 0.0;
        for (i, b) in self.blocks.iter().enumerate() {
            if self.free[i].is_none() {
                continue;
            }
            let mat = self.model.materials[self.model.blocks[i].material];
            let m = mass_matrix(&b.polygon.moments(), mat.density);
            let v = &b.velocity;
            for a in 0..6 {
                for bb in 0..6 {
                    e += 0.5 * v[a] * m[a][bb] * v[bb];
                }
            }
        }
        e
    }
}

/// A free block's terms that do not depend on contacts, at step size `dt`: its stiffness
/// (inertia 2/dt^2 M, elasticity, fixed-point springs), right-hand side (inertia 2/dt M V,
/// initial stress, gravity, point loads, fixed points) and mass matrix M (each only if
/// its effect is on).
fn block_terms(
    model: &Model,
    eff: Effects,
    b: &BlockState,
    i: usize,
    dt: f64,
) -> (Mat6, Vec6, Mat6) {
    let p = &model.params;
    let m = b.polygon.moments();
    let mat = model.materials[model.blocks[i].material];
    let mass = mass_matrix(&m, mat.density);
    let mut k = [[0.0; 6]; 6];
    let mut f = [0.0; 6];
    // Inertia (constant acceleration): 2/dt^2 M, and 2/dt M V when dynamic.
    let c2 = 2.0 / (dt * dt);
    for a in 0..6 {
        for bb in 0..6 {
            k[a][bb] += c2 * mass[a][bb];
        }
    }
    if eff.inertia {
        let c1 = 2.0 / dt;
        for a in 0..6 {
            f[a] += c1 * (0..6).map(|bb| mass[a][bb] * b.velocity[bb]).sum::<f64>();
        }
    }
    if eff.elasticity {
        let e = elasticity(mat.young, mat.poisson);
        for a in 0..3 {
            for bb in 0..3 {
                k[3 + a][3 + bb] += m.area * e[a][bb];
            }
            f[3 + a] -= m.area * b.stress[a];
        }
    }
    if eff.gravity
        && let Some(g) = p.gravity
    {
        f[0] += mat.density * g.x * m.area;
        f[1] += mat.density * g.y * m.area;
    }
    for &(at, force) in &b.loads {
        let r = along(force, at, m.centroid);
        for a in 0..6 {
            f[a] += r[a];
        }
    }
    for &(now, place) in &b.fixed_points {
        // Two rows (x and y) of a spring pulling the point to its place.
        for dir in [DVec2::X, DVec2::Y] {
            let r = along(dir, now, m.centroid);
            let g0 = (now - place).dot(dir);
            for a in 0..6 {
                f[a] -= p.fixed_penalty * g0 * r[a];
                for bb in 0..6 {
                    k[a][bb] += p.fixed_penalty * r[a] * r[bb];
                }
            }
        }
    }
    (k, f, mass)
}

/// Whether sorted `a` is contained in sorted `b`.
fn is_subset(a: &[(u32, u32)], b: &[(u32, u32)]) -> bool {
    let mut j = 0;
    for x in a {
        while j < b.len() && b[j] < *x {
            j += 1;
        }
        if j == b.len() || b[j] != *x {
            return false;
        }
    }
    true
}

/// Adds the stiffness of the spring p q^2 / 2 of `row` to the matrix (fixed blocks
/// contribute nothing); its right-hand side comes with [`Simulation::assemble_rhs`].
fn add_spring(
    sys: &mut BlockSystem,
    free: &[Option<u32>],
    pair_entry: Option<Entry>,
    p: f64,
    row: &Row,
) {
    let fa = free[row.blocks[0] as usize];
    let fb = free[row.blocks[1] as usize];
    for (f, c) in [(fa, &row.c[0]), (fb, &row.c[1])] {
        if let Some(f) = f {
            sys.add_outer(sys.diagonal(f), f, f, p, c, c);
        }
    }
    if let (Some(a), Some(b), Some(e)) = (fa, fb, pair_entry) {
        sys.add_outer(e, a, b, p, &row.c[0], &row.c[1]);
    }
}

#[cfg(test)]
mod tests {
    use super::{GROWTH_TARGET, MAX_GROWTH, easy_oci, step_growth};

    /// An easy step's bound lies within the OCI bound, never falls as that bound grows,
    /// and is 4 of the paper's 6 (two thirds, rounded up).
    #[test]
    fn the_easy_bound_lies_within_the_oci_bound() {
        for m in 1..=100 {
            let e = easy_oci(m);
            assert!((1..=m).contains(&e), "max_oci {m}: {e}");
            assert!(m == 1 || e >= easy_oci(m - 1), "max_oci {m}: {e}");
        }
        assert_eq!(easy_oci(6), 4);
    }

    /// dt grows only after an easy step, by at most `MAX_GROWTH`, and never so far that
    /// the step's motion scaled with dt passes `GROWTH_TARGET` of d_max or theta_max;
    /// below that it grows as far as either allows.
    #[test]
    fn dt_grows_only_within_the_motion_bounds() {
        let (d_max, theta_max) = (0.01, 0.02);
        assert_eq!(step_growth(5, 6, 0.0, 0.0, d_max, theta_max), 1.0);
        assert_eq!(step_growth(4, 6, 0.0, 0.0, d_max, theta_max), MAX_GROWTH);
        for i in 0..=40 {
            for j in 0..=40 {
                let (disp, rot) = (d_max * i as f64 / 40.0, theta_max * j as f64 / 40.0);
                let g = step_growth(4, 6, disp, rot, d_max, theta_max);
                assert!((1.0..=MAX_GROWTH).contains(&g), "{disp} {rot}: {g}");
                let reach = (g * disp / d_max).max(g * rot / theta_max);
                if g > 1.0 {
                    assert!(
                        reach <= GROWTH_TARGET * (1.0 + 1e-15),
                        "{disp} {rot}: {reach}"
                    );
                }
                if g < MAX_GROWTH {
                    // Held back: the motion already reaches the target or beyond.
                    assert!(
                        reach >= GROWTH_TARGET * (1.0 - 1e-15),
                        "{disp} {rot}: {reach}"
                    );
                }
            }
        }
    }
}
