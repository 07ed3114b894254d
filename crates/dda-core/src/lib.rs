//! The implicit 2D DDA engine of dda-rs (Shi 1988; docs/method.md).
//!
//! A scene file ([`Scene`]) is validated into a [`Model`]; the [`Effects`] it calls for
//! decide which terms are assembled; a [`Simulation`] advances it step by step:
//! blocks -> neighbour pairs -> contacts ([`dda_contact`]) -> block-sparse system
//! ([`BlockSystem`]) -> solve -> open-close iteration -> update. A [`Summary`] and per-step
//! [`StepRecord`]s describe the run.

// Index loops mirror the matrix formulas they implement.
#![allow(clippy::needless_range_loop)]

mod assembly;
mod bolts;
pub mod checkpoint;
mod contact_law;
mod detection;
pub mod diagnosis;
pub mod effects;
pub mod guard;
pub mod iterative;
pub mod kinematics;
pub mod limits;
mod locate;
mod model;
mod open_close;
mod pattern;
mod regions;
pub mod scene;
pub mod seismic;
mod settle;
pub mod simulation;
pub mod solver;
pub mod springs;
pub mod state;
pub mod summary;
pub mod time_step;
pub mod timing;
mod update;

pub use self::bolts::{BoltState, affine_coordinates, from_affine};
pub use self::checkpoint::{Checkpoint, CheckpointError};
pub use self::contact_law::PARALLEL_MIN_CONTACTS;
pub use self::diagnosis::{ContactNote, Diagnosis, SimError};
pub use self::effects::Effects;
pub use self::guard::{ENERGY_TOLERANCE, EnergyBalance, Violation};
pub use self::locate::LineIndex;
pub use self::scene::{Format, Invalid, Model, Scene, SceneError};
pub use self::settle::{SettleProgress, Settling};
pub use self::simulation::{RunOptions, Simulation, on_pool};
pub use self::solver::{BlockSystem, RankOne, SolveError, SolverCounters};
pub use self::state::{BlockState, RunState, Snapshot, StepRecord, Totals};
pub use self::summary::{
    BlockSummary, BoltSummary, Broken, HeldBy, Removed, Seconds, SettlingSummary, Summary,
};
pub use self::timing::Phase;
