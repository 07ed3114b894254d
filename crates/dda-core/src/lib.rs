//! The implicit 2D DDA engine of dda-rs (Shi 1988; docs/method.md).
//!
//! A scene file ([`Scene`]) is validated into a [`Model`]; the [`Effects`] it calls for
//! decide which terms are assembled; a [`Simulation`] advances it step by step:
//! blocks -> neighbour pairs -> contacts ([`dda_contact`]) -> block-sparse system
//! ([`BlockSystem`]) -> solve -> open-close iteration -> update. A [`Summary`] and per-step
//! [`StepRecord`]s describe the run.

// Index loops mirror the matrix formulas they implement.
#![allow(clippy::needless_range_loop)]

pub mod checkpoint;
pub mod effects;
pub mod engine;
pub mod guard;
pub mod kinematics;
pub mod limits;
mod locate;
pub mod scene;
pub mod springs;
pub mod summary;
mod supernodal;
pub mod system;

pub use self::checkpoint::{Checkpoint, CheckpointError, OutputMarks};
pub use self::effects::Effects;
pub use self::engine::{
    BlockSnapshot, BlockState, ContactNote, Diagnosis, RunOptions, SimError, Simulation, Snapshot,
    StepRecord, Totals,
};
pub use self::guard::{ENERGY_TOLERANCE, EnergyBalance, Violation};
pub use self::locate::LineIndex;
pub use self::scene::{Format, Invalid, Model, Scene, SceneError};
pub use self::summary::{BlockSummary, Seconds, Summary};
pub use self::system::{BlockSystem, RankOne, SolveError};
