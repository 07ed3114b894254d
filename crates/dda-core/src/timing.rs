//! Wall time of a step, charged to its phases: a stopwatch runs through a stage of
//! the step and charges each lap to the [`Phase`] it belongs to in the step's record.
//! Only these numbers differ between two runs of the same scene.

use crate::state::StepRecord;
use std::time::Instant;

/// The phases a step's wall time is charged to (history.csv's last three columns).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Contact detection: at step start, and trajectory tracking in the iteration.
    Detection,
    /// Assembly of the system, and the contact law's checks.
    Assembly,
    /// Factorisation and solves.
    Solve,
}

impl StepRecord {
    /// Adds `seconds` to `phase`.
    pub fn charge(&mut self, phase: Phase, seconds: f64) {
        match phase {
            Phase::Detection => self.detection_s += seconds,
            Phase::Assembly => self.assembly_s += seconds,
            Phase::Solve => self.solve_s += seconds,
        }
    }
}

/// A stopwatch whose laps are charged to the phases of a step.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Stopwatch(Instant);

impl Stopwatch {
    /// Starts the first lap.
    pub(crate) fn start() -> Self {
        Stopwatch(Instant::now())
    }

    /// Charges the lap since the start or the last lap to `phase` of `rec`, and starts
    /// the next lap.
    pub(crate) fn lap(&mut self, rec: &mut StepRecord, phase: Phase) {
        let now = Instant::now();
        rec.charge(phase, (now - self.0).as_secs_f64());
        self.0 = now;
    }

    /// Seconds since the start or the last lap.
    pub(crate) fn seconds(&self) -> f64 {
        self.0.elapsed().as_secs_f64()
    }
}
