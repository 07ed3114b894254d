//! A running simulation, and the one place that states the sequence of a step:
//!
//! ```text
//! detection at step start -> pattern -> linearisation and block terms -> state
//! prediction -> open-close iteration (assemble, solve, contact law, tracking) ->
//! time-step control -> physics guard -> update
//! ```
//!
//! Each stage lives in a file of its own: `detection`, `pattern`, `assembly`,
//! `open_close` (with the state predictor and the low-rank path), `contact_law`,
//! `time_step`, `guard`, `update`; `state` holds what a checkpoint saves and
//! `diagnosis` why a run stops. `docs/method.md` states the formulation.

use crate::assembly::{ShearRows, Spring};
use crate::detection::NEIGHBOUR_SKIN;
use crate::diagnosis::{Diagnosis, SimError};
use crate::effects::Effects;
use crate::guard::{self, Checked, EnergyBalance, Violation};
use crate::iterative::solves_iteratively;
use crate::kinematics::{Mat6, Vec6, mass_matrix};
use crate::scene::Model;
use crate::settle::Settling;
use crate::solver::{BlockSystem, Entry, RankOne, SolverCounters};
use crate::springs::{HalfStep, Row};
use crate::state::{BlockState, RunState, StepRecord, Totals};
use crate::time_step::{DT_FLOOR, LANDING_SPLIT, MAX_GROWTH, easy_oci, motion_room, step_growth};
use crate::timing::{Phase, Stopwatch};
use dda_contact::{
    BlockShape, BoxTrees, ContactDetector, ContactSet, DetectionParams, NeighbourPair,
    NeighbourSearch, TrackList, detector_by_name,
};
use dda_geom::{Aabb, Motion};

/// A running simulation of a validated scene: what the model fixes, the saved state
/// ([`RunState`], what a checkpoint holds) and the scratch of a step (`Scratch`,
/// rebuilt, never saved).
pub struct Simulation {
    pub(crate) model: Model,
    pub(crate) effects: Effects,
    pub(crate) detector: Box<dyn ContactDetector>,
    pub(crate) detection: DetectionParams,
    pub(crate) options: RunOptions,
    pub(crate) nd: usize,
    /// Free-block index of each block (None: fixed).
    pub(crate) free: Vec<Option<u32>>,
    /// Material of each block, packed: the joint lookups of every contact in every OCI
    /// iteration read it (the model's blocks are large records, mostly cache misses).
    pub(crate) material: Vec<u32>,
    /// Block index of each free block: the inverse of `free`.
    pub(crate) free_blocks: Vec<u32>,
    /// Whether each block has been removed (excavated): out of detection and the system,
    /// its state frozen. A function of the time: the blocks whose `removed_at` is at
    /// or before it (`Simulation::remove_due`).
    pub(crate) removed: Vec<bool>,
    /// Each block's body as the parts that remain hold together (`Model::bodies`): made
    /// again when blocks are removed.
    pub(crate) bodies: Vec<Option<u32>>,
    pub(crate) n_free: usize,
    /// Energy below the model's resolution, added to the guard's reference (see
    /// `guard`): every free block lowered by d_tol, and a spring over the start overlap.
    pub(crate) energy_floor: f64,
    /// Whether the first step closes every active contact touching to rounding (its
    /// vertex within the open band of its edge's line, `Simulation::open_band`): set
    /// for the settling's copy of the model (`settle`).
    pub(crate) close_touching: bool,
    /// What this process's settling did (see `settle`).
    pub(crate) settling: Option<Settling>,
    /// The state at the end of the last step: what a checkpoint saves.
    pub(crate) state: RunState,
    /// Work buffers of a step, reused from step to step, never saved.
    pub(crate) scratch: Scratch,
}

/// The work buffers of a step: rebuilt from the state (or reused), never saved.
pub(crate) struct Scratch {
    pub(crate) shapes: Vec<BlockShape>,
    pub(crate) system: BlockSystem,
    pub(crate) prev: ContactSet,
    /// The candidates trajectory tracking may activate in this step.
    pub(crate) track_list: TrackList,
    pub(crate) neighbours: NeighbourSearch,
    pub(crate) pairs: Vec<NeighbourPair>,
    /// The contacts at step start, restored when an attempt is cut.
    pub(crate) saved: Vec<dda_contact::Contact>,
    /// Neighbour pairs within the pattern margin (only when a new pattern is made).
    pub(crate) pattern_pairs: Vec<NeighbourPair>,
    /// The blocks' boxes at step start (`Simulation::detect_step_start`).
    pub(crate) aabbs: Vec<Aabb>,
    pub(crate) block_pairs: Vec<(u32, u32)>,
    pub(crate) pair_entry: Vec<Option<Entry>>,
    /// Each block's half step, where the attempt's contact rows are linearised.
    pub(crate) half: Vec<HalfStep>,
    /// Whether an impact holds the step down (`Simulation::impact_room`), set at the
    /// step's start: the step's rule under `Integration::AverageInImpacts`.
    pub(crate) in_impact: bool,
    /// Which blocks the rotation limit theta_max holds in this step
    /// (`Simulation::mark_turn_limited`): those with a contact, a fixed point, a load or
    /// a bolt.
    pub(crate) turn_limited: Vec<bool>,
    /// Each block's bound on its vertices' motion in this step
    /// (`Simulation::set_flight_room`): d_max, or for a block in flight half its gap to
    /// the nearest other block less d_tol, where that is more.
    pub(crate) flight_room: Vec<f64>,
    /// Trees of the blocks' boxes at step start (`aabbs`), for the gap of each block in
    /// flight to its nearest (`Simulation::set_flight_room`); built only in a step that
    /// has such a block.
    pub(crate) nearest: BoxTrees,
    /// Each active contact's normal row for the attempt (an inactive one's is a NaN
    /// placeholder until it becomes active: only active contacts' rows are read).
    pub(crate) rows: Vec<Row>,
    pub(crate) springs: Vec<Spring>,
    /// The shear rows of the springs' and friction forces' contact states.
    pub(crate) sheared: ShearRows,
    /// Friction forces in effect: contact, magnitude, row; and the releases of contacts
    /// open since the step's start (`Simulation::release`).
    pub(crate) forces: Vec<(u32, f64, Row)>,
    /// The releases among `forces`: the part of the accelerations carried into the step
    /// that the step took back, which the accelerations it carries on leave out.
    pub(crate) released: Vec<(u32, f64, Row)>,
    /// Per block (scene index), where the step's system left the rule's forces: those
    /// of `released`, less the shares of `engaged` contacts' end forces it left out
    /// (the step's update, `update.rs`).
    pub(crate) taken_back: Vec<Vec6>,
    /// The contacts closed within the step under the average-acceleration rule, with the
    /// share of the step before they closed (`Simulation::engaged`): their forces enter
    /// the step's system at the share after it, and the step's end acceleration whole.
    pub(crate) engaged: Vec<(u32, f64)>,
    pub(crate) factored_springs: Vec<Spring>,
    pub(crate) factored_forces: Vec<(u32, f64, Row)>,
    pub(crate) changes: Vec<RankOne>,
    pub(crate) rhs_changes: Vec<RankOne>,
    /// Whether the system's factor is of this attempt's matrix (with `factored_springs`).
    pub(crate) factor_current: bool,
    pub(crate) base_k: Vec<Mat6>,
    pub(crate) base_f: Vec<Vec6>,
    pub(crate) mass: Vec<Mat6>,
    pub(crate) d: Vec<Vec6>,
    /// The trial motion of each block as a map of its points.
    pub(crate) motions: Vec<Motion>,
    /// The step size of the attempt under way.
    pub(crate) attempt_dt: f64,
    /// The iterative solve's largest reach of a vertex in the attempt
    /// (`crate::iterative`).
    pub(crate) reach: f64,
    /// Whether the iterative solve's start and data are made for this attempt.
    pub(crate) iteration_ready: bool,
    /// Contacts whose state changed in the last OCI iteration (for a diagnosis).
    pub(crate) flipped: Vec<u32>,
    /// Those of the second half of a contact list decided in two halves
    /// (`Simulation::update_states`), before they join `flipped`.
    #[cfg(feature = "rayon")]
    pub(crate) flipped_second: Vec<u32>,
    /// Contacts of `flipped` whose joint has no friction (no shear).
    pub(crate) frictionless_changes: usize,
    /// Contacts of `flipped` that opened or closed.
    pub(crate) opened_or_closed: usize,
    /// Changes of state of each contact in this attempt's open-close iteration.
    pub(crate) flips: Vec<u8>,
    /// Each contact's last friction trial in this attempt's open-close iteration
    /// (`Simulation::relax_friction`).
    pub(crate) friction_trials: Vec<crate::open_close::FrictionTrial>,
    /// Each candidate contact's joint in this step (`assembly::joint_of`), made at
    /// detection: a candidate's key, and the bodies of its blocks, hold for the step.
    pub(crate) joints: Vec<crate::scene::JointProps>,
    /// Each block's force scale for the contact law's decisions: the larger of the
    /// external force on it (weight and point loads) and the largest normal force of its
    /// closed contacts at the step's start; infinite for a fixed block.
    pub(crate) force_scale: Vec<f64>,
    /// The dashpots beside the contacts' normal springs in this attempt.
    pub(crate) dashpots: crate::assembly::Dashpots,
    /// Why the run stopped, once it has.
    pub(crate) diagnosis: Option<Diagnosis>,
    /// Each free block's gain of kinetic energy in the step (scratch of the guard).
    pub(crate) gains: Vec<(f64, usize)>,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("scene", &self.model.name)
            .field("t", &self.state.t)
            .field("dt", &self.state.dt)
            .field("blocks", &self.state.blocks.len())
            .finish()
    }
}

/// Runs `work` (a run's stepping) on a thread of a pool of the machine's threads. The
/// work a step splits in two halves (`rayon::join`: the iterative solve's passes, the
/// contact law's) then runs one half on that thread and hands the other to the pool's
/// next; called from outside any pool, each split is handed over whole and waited for,
/// at a system call each. Measured on the 10,131-block column's first 30 steps (three
/// alternating runs): 0.383-0.387 ms a CG iteration against 0.450-0.455 ms, the same
/// bits. Where no pool can be made (or without the `rayon` feature) `work` runs here;
/// the results are the same bits either way (`tests/physics/resume.rs`).
pub fn on_pool<R: Send>(work: impl FnOnce() -> R + Send) -> R {
    #[cfg(feature = "rayon")]
    if let Ok(pool) = rayon::ThreadPoolBuilder::new().build() {
        return pool.install(work);
    }
    work()
}

/// Options of a run that are not part of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RunOptions {
    /// Take a step's work that splits (detection, the blocks' own terms, the contact
    /// law) on the thread pool; results are identical either way. A system solved
    /// iteratively does so whatever this says.
    pub parallel: bool,
    /// Stop with [`SimError::BrokenPhysics`] at the first step that breaks physics
    /// (penetration beyond d_tol, energy created beyond [`crate::ENERGY_TOLERANCE`]), keeping
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

impl Simulation {
    /// Whether a step's work that splits goes to the thread pool: when asked
    /// ([`RunOptions::parallel`]), or when the system is solved iteratively, which is on
    /// two threads already and where the blocks are many. Measured on the 28,325-block
    /// column's first 15 steps (two alternating runs): detection 0.73-0.83 s against
    /// 0.81-0.88 s, assembly 1.58-1.59 s against 1.62-1.66 s, the same bits.
    pub(crate) fn threads(&self) -> bool {
        self.options.parallel || self.scratch.system.threads
    }

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
                acceleration: [0.0; 6],
            })
            .collect();
        let shapes = blocks.iter().map(|b| BlockShape::new(&b.polygon)).collect();
        let material = model.blocks.iter().map(|b| b.material as u32).collect();
        let n = blocks.len();
        let skin = NEIGHBOUR_SKIN * model.params.d_max;
        let n_free_blocks = free.iter().flatten().count();
        let mut system = if solves_iteratively(p.solver, n_free_blocks) {
            BlockSystem::iterative()
        } else {
            BlockSystem::new()
        };
        system.memory_limit = options.max_memory;
        // The iterative solve's products run on two threads: the same sums in the same
        // order as on one (`solver::iterative`), 1.6 times faster at 28,325 blocks.
        system.threads = system.is_iterative();
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
            initial += own_energy(&model, effects.elasticity, b, i);
        }
        let dt0 = p.dt0;
        let n_bolts = model.bolts.len();
        let bodies = model.bodies(&vec![false; free.len()]);
        let mut sim = Simulation {
            nd: effects.dofs_per_block(),
            model,
            effects,
            detector,
            detection,
            options,
            free_blocks: (0..free.len() as u32)
                .filter(|&i| free[i as usize].is_some())
                .collect(),
            material,
            removed: vec![false; free.len()],
            bodies,
            free,
            n_free: n_free as usize,
            energy_floor,
            close_touching: false,
            settling: None,
            state: RunState {
                t: 0.0,
                dt: dt0,
                totals: Totals::default(),
                blocks,
                contacts: ContactSet::default(),
                pattern: Vec::new(),
                energy: EnergyBalance {
                    supplied: initial,
                    supplied_max: initial,
                    worst_ratio: 0.0,
                },
                violations: Vec::new(),
                bolts: vec![Default::default(); n_bolts],
                accelerations_known: false,
                settled: false,
            },
            scratch: Scratch {
                shapes,
                system,
                prev: ContactSet::default(),
                track_list: TrackList::new(),
                neighbours: NeighbourSearch::with_skin(skin),
                pairs: Vec::new(),
                saved: Vec::new(),
                pattern_pairs: Vec::new(),
                aabbs: Vec::with_capacity(n),
                block_pairs: Vec::new(),
                pair_entry: Vec::new(),
                half: Vec::with_capacity(n),
                in_impact: false,
                turn_limited: Vec::new(),
                flight_room: Vec::new(),
                nearest: BoxTrees::new(),
                rows: Vec::new(),
                springs: Vec::new(),
                sheared: ShearRows::default(),
                forces: Vec::new(),
                released: Vec::new(),
                taken_back: Vec::new(),
                engaged: Vec::new(),
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
                attempt_dt: dt0,
                reach: 0.0,
                iteration_ready: false,
                flipped: Vec::new(),
                #[cfg(feature = "rayon")]
                flipped_second: Vec::new(),
                frictionless_changes: 0,
                opened_or_closed: 0,
                flips: Vec::new(),
                friction_trials: Vec::new(),
                joints: Vec::new(),
                force_scale: Vec::new(),
                dashpots: Default::default(),
                diagnosis: None,
                gains: Vec::new(),
            },
        };
        sim.excavate_due(0.0);
        sim
    }

    /// Removes the blocks excavated by `t` ([`Simulation::remove_due`]), and their
    /// kinetic and strain energy from the energy the physics guard counts as supplied:
    /// the rock takes its energy out of the system with it. Left in the supply, an
    /// excavated block's strain energy (large under in-situ stress) would let the rest
    /// of the run create as much unseen.
    pub(crate) fn excavate_due(&mut self, t: f64) {
        let due = self.due(t);
        let taken: f64 = (due.iter().copied())
            .filter(|&i| !self.model.blocks[i].fixed)
            .map(|i| {
                own_energy(
                    &self.model,
                    self.effects.elasticity,
                    &self.state.blocks[i],
                    i,
                )
            })
            .sum();
        self.state.energy.supplied -= taken;
        self.remove(&due);
    }

    /// The blocks excavated by `t` and not removed yet.
    fn due(&self, t: f64) -> Vec<usize> {
        (0..self.removed.len())
            .filter(|&i| {
                !self.removed[i] && self.model.blocks[i].removed_at.is_some_and(|at| at <= t)
            })
            .collect()
    }

    /// Removes the blocks whose `removed_at` is at or before `t` and not removed yet: they
    /// leave the system (the free blocks are numbered again and the matrix pattern is
    /// made anew) and the contact search; their state stays as it was, at rest.
    pub(crate) fn remove_due(&mut self, t: f64) {
        let due = self.due(t);
        self.remove(&due);
    }

    /// Removes blocks `due` (see [`Simulation::remove_due`]).
    fn remove(&mut self, due: &[usize]) {
        if due.is_empty() {
            return;
        }
        for &i in due {
            self.removed[i] = true;
            self.state.blocks[i].velocity = [0.0; 6];
        }
        self.bodies = self.model.bodies(&self.removed);
        let mut n = 0u32;
        for (i, f) in self.free.iter_mut().enumerate() {
            *f = if self.model.blocks[i].fixed || self.removed[i] {
                None
            } else {
                n += 1;
                Some(n - 1)
            };
        }
        self.n_free = n as usize;
        self.free_blocks = (0..self.free.len() as u32)
            .filter(|&i| self.free[i as usize].is_some())
            .collect();
        self.state.pattern.clear();
    }

    /// The time the next step must land on: the run's end, or an excavation before it.
    pub(crate) fn next_event(&self) -> f64 {
        let t = self.state.t;
        self.model
            .blocks
            .iter()
            .zip(&self.removed)
            .filter_map(|(b, &gone)| b.removed_at.filter(|&at| !gone && at > t))
            .fold(self.model.params.duration, f64::min)
    }

    /// The body acceleration in effect, m/s^2: the scene's gravity while the gravity
    /// effect is on, else none.
    pub(crate) fn gravity(&self) -> dda_geom::DVec2 {
        match self.model.params.gravity {
            Some(g) if self.effects.gravity => g,
            _ => dda_geom::DVec2::ZERO,
        }
    }

    /// Block `i`'s mass per metre of thickness, kg/m.
    pub(crate) fn block_mass(&self, i: usize) -> f64 {
        let mat = self.model.materials[self.material[i] as usize];
        mat.density * self.state.blocks[i].polygon.area()
    }

    /// Whether block `i` has been removed (excavated).
    pub fn is_removed(&self, i: usize) -> bool {
        self.removed[i]
    }

    /// Violations of physics recorded so far by a run that goes on through them
    /// ([`crate::RunOptions::stop_on_violation`] off).
    pub fn violations(&self) -> &[Violation] {
        &self.state.violations
    }

    /// The physics guard's energy balance so far.
    pub fn energy_balance(&self) -> &EnergyBalance {
        &self.state.energy
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
        self.state.t
    }

    /// The current (controlled) step size, s.
    pub fn time_step(&self) -> f64 {
        self.state.dt
    }

    /// Whether the run has reached its duration.
    pub fn finished(&self) -> bool {
        self.state.t >= self.model.params.duration
    }

    /// The blocks' states.
    pub fn blocks(&self) -> &[BlockState] {
        &self.state.blocks
    }

    /// The contacts at the end of the last step.
    pub fn contacts(&self) -> &ContactSet {
        &self.state.contacts
    }

    /// Counters so far.
    pub fn totals(&self) -> &Totals {
        &self.state.totals
    }

    /// Unknowns of the global system.
    pub fn unknowns(&self) -> usize {
        self.n_free * self.nd
    }

    /// Whether the global system is solved iteratively (`analysis.solver`).
    pub fn solves_iteratively(&self) -> bool {
        self.scratch.system.is_iterative()
    }

    /// The solver's work so far: factorisations and low-rank solves.
    pub fn solver_counters(&self) -> SolverCounters {
        self.scratch.system.counters()
    }

    /// Why the run stopped, once a step has failed: the blocks and contacts involved.
    pub fn diagnosis(&self) -> Option<&Diagnosis> {
        self.scratch.diagnosis.as_ref()
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
        let mut last_dt = self.state.dt;
        let mut worst = None;
        self.settle_watched(|_| true)?;
        let result = self.try_step(&mut last_dt, &mut worst);
        match &result {
            Err(e) => self.diagnose(e, last_dt, worst),
            // Bolts break, and excavations take effect, at the end of the step that
            // reaches them.
            Ok(_) => {
                self.break_bolts();
                self.excavate_due(self.state.t);
            }
        }
        result
    }

    /// [`Simulation::step`], reporting the last attempted step size and the block that
    /// moved most in the last attempt.
    pub(crate) fn try_step(
        &mut self,
        last_dt: &mut f64,
        worst: &mut Option<usize>,
    ) -> Result<StepRecord, SimError> {
        let started = Stopwatch::start();
        let mut rec = StepRecord::default();
        let mut watch = Stopwatch::start();
        self.detect_step_start();
        watch.lap(&mut rec, Phase::Detection);
        rec.candidates = self.state.contacts.len();

        self.set_pattern()?;
        watch.lap(&mut rec, Phase::Assembly);
        self.scratch.saved.clone_from(&self.state.contacts.contacts);
        let p = &self.model.params;
        let (d_max, theta_max, max_oci, dt0) = (p.d_max, p.theta_max, p.max_oci, p.dt0);
        // The step lands on the run's end and on every excavation's time.
        let target = self.next_event();
        let remaining = target - self.state.t;
        // The step respects the motion it starts with: no block's current velocity may
        // carry a vertex beyond d_max, or turn it beyond theta_max, within it.
        let impact = self.impact_room();
        self.scratch.in_impact = impact.is_finite();
        self.mark_turn_limited();
        self.set_flight_room();
        let (room, fastest) = self.velocity_room();
        let planned = self.state.dt.min(room).min(impact);
        // The block whose velocity holds the step below the one asked for, if one does.
        rec.held_by = (room < self.state.dt && room <= impact)
            .then_some(fastest)
            .flatten()
            .map(|i| i as u32);
        // Land on `duration`; a remainder within 1e-6 of a step is taken with it rather
        // than left as a sliver step, and one shorter than one and a half steps is taken
        // in two equal steps (`LANDING_SPLIT`), so that no step before the end is
        // shorter than half the one asked for.
        let landing = planned * (1.0 + 1e-6) >= remaining;
        let split = !landing && remaining < LANDING_SPLIT * planned;
        let mut dt = if landing {
            remaining
        } else if split {
            0.5 * remaining
        } else {
            planned
        };

        let mut first_attempt = true;
        loop {
            *last_dt = dt;
            let mut watch = Stopwatch::start();
            self.linearise(dt);
            self.base_terms(dt);
            self.set_force_scale();
            self.set_dashpots();
            watch.lap(&mut rec, Phase::Assembly);
            // The first OCI iteration of every attempt factorises its own matrix (solved
            // iteratively: starts from the one the state predictor assembled, of this
            // attempt too).
            self.scratch.factor_current = false;
            if first_attempt {
                self.predict_states(&mut rec)?;
                first_attempt = false;
            }
            let (converged, iterations, not_hard) = self.open_close_iteration(&mut rec)?;
            self.state.totals.oci_iterations += iterations as u64;
            let reason;
            // An attempt that went past `max_oci` (`OCI_GRACE`) is kept only where its
            // result keeps the physics guard; otherwise it is cut as one that did not
            // converge.
            let checked = (converged && iterations > max_oci).then(|| self.check_physics(dt));
            let graced_badly = checked.as_ref().is_some_and(Checked::broken);
            if graced_badly {
                dt /= 3.0;
                reason = "open-close iteration past max_oci broke physics";
            } else if converged {
                let (disp, rot, moved_most) = self.largest_motion();
                *worst = moved_most;
                if disp <= d_max && rot <= theta_max {
                    rec.oci = iterations;
                    // Iterations that changed no state, or only stick and slip, are no
                    // sign of a hard step.
                    let decided = iterations - not_hard;
                    let growth = step_growth(decided, max_oci, disp, rot, d_max, theta_max);
                    // An easy step whose growth its motion bounded below the step asked
                    // for: the block that moved most for its limits holds dt.
                    if rec.held_by.is_none()
                        && dt < dt0
                        && decided <= easy_oci(max_oci)
                        && growth < MAX_GROWTH
                    {
                        rec.held_by = moved_most.map(|i| i as u32);
                    }
                    self.accept(dt, &mut rec, checked)?;
                    if landing {
                        self.state.t = target;
                    } else if split && rec.cuts == 0 {
                        // The step was shortened to land, not for its difficulty: the
                        // step asked for stands (as it does after landing).
                        self.state.dt = self.state.dt.max(dt * growth).min(dt0);
                    } else {
                        self.state.dt = (dt * growth).min(dt0);
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
            self.state.totals.cuts += 1;
            self.state
                .contacts
                .contacts
                .copy_from_slice(&self.scratch.saved);
            if dt < DT_FLOOR * dt0 {
                return Err(SimError::TimeStepCollapsed {
                    t: self.state.t,
                    dt,
                    reason: reason.to_string(),
                });
            }
        }
        self.state.totals.steps += 1;
        rec.step = self.state.totals.steps;
        rec.t = self.state.t;
        rec.active_contacts = self.state.contacts.active().count();
        rec.closed_contacts = self.state.contacts.closed_count();
        rec.kinetic_energy = self.kinetic_energy();
        self.state.totals.max_penetration =
            self.state.totals.max_penetration.max(rec.max_penetration);
        self.state.totals.detection_s += rec.detection_s;
        self.state.totals.assembly_s += rec.assembly_s;
        self.state.totals.solve_s += rec.solve_s;
        self.state.totals.total_s += started.seconds();
        Ok(rec)
    }
}

/// Block `i`'s kinetic energy and, where blocks are elastic, its strain energy, J/m: its
/// share of the energy the physics guard counts (`crate::guard`).
fn own_energy(model: &Model, elastic: bool, b: &BlockState, i: usize) -> f64 {
    let mat = model.materials[model.blocks[i].material];
    let m = b.polygon.moments();
    let mut e = guard::kinetic(&mass_matrix(&m, mat.density), &b.velocity);
    if elastic {
        e += guard::strain(m.area, &b.stress, mat.young, mat.poisson);
    }
    e
}
