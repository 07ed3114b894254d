//! The admissible range of every number a scene holds. `dda check` (and every run)
//! refuses a value outside its range with the file, key and line, so that a typing
//! slip (`1e308`, a duration in milliseconds) is reported before it runs, not as a
//! failed factorisation hours later. The ranges are wide: each admits every value a
//! rock-engineering model uses, and stops where f64 arithmetic of a DDA step (inertia
//! 2 M / dt^2, penalties, areas from coordinates) would overflow or lose all precision.
//! `docs/scene-format.md` lists them with their keys.

/// A closed range `[min, max]` of a quantity, with its unit for messages.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    /// Smallest admissible value.
    pub min: f64,
    /// Largest admissible value.
    pub max: f64,
    /// Unit, as messages print it.
    pub unit: &'static str,
}

impl Range {
    /// Whether `v` is finite and within the range.
    pub fn contains(&self, v: f64) -> bool {
        v.is_finite() && (self.min..=self.max).contains(&v)
    }

    /// The message for a value outside the range.
    pub fn message(&self, v: f64) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!(
            "must be between {:e} and {:e}{unit}, got {v:e}",
            self.min, self.max
        )
    }
}

/// `analysis.duration`: simulated time (1 microsecond to about 116 days).
pub const DURATION: Range = Range {
    min: 1e-6,
    max: 1e7,
    unit: "s",
};
/// `analysis.time_step`: the initial and largest step.
pub const TIME_STEP: Range = Range {
    min: 1e-9,
    max: 1e3,
    unit: "s",
};
/// Most steps the duration may span at the initial step size (`duration / time_step`).
pub const MAX_NOMINAL_STEPS: f64 = 1e9;
/// `analysis.max_displacement` (d_max) and `analysis.contact_tolerance` (d_tol).
pub const TOLERANCE: Range = Range {
    min: 1e-9,
    max: 1e3,
    unit: "m",
};
/// `analysis.max_rotation_deg` (theta_max).
pub const ROTATION_DEG: Range = Range {
    min: 1e-6,
    max: 30.0,
    unit: "degrees",
};
/// `analysis.normal_penalty` and `analysis.shear_penalty`.
pub const PENALTY: Range = Range {
    min: 1e3,
    max: 1e16,
    unit: "N/m",
};
/// `analysis.fixed_penalty`.
pub const FIXED_PENALTY: Range = Range {
    min: 1e3,
    max: 1e18,
    unit: "N/m",
};
/// Each component of `analysis.gravity` (1,000 g covers centrifuge models).
pub const GRAVITY: Range = Range {
    min: -1e4,
    max: 1e4,
    unit: "m/s^2",
};
/// `materials.*.density`.
pub const DENSITY: Range = Range {
    min: 1e-3,
    max: 1e5,
    unit: "kg/m^3",
};
/// `materials.*.young`.
pub const YOUNG: Range = Range {
    min: 1e3,
    max: 1e13,
    unit: "Pa",
};
/// `materials.*.damping`: the stiffness-proportional damping time of the blocks' strain
/// (0 to 1 s; a second damps a strain vibration of 2 rad/s critically).
pub const DAMPING: Range = Range {
    min: 0.0,
    max: 1.0,
    unit: "s",
};
/// `analysis.contact_damping`: the damping ratio of the contact springs at their own
/// frequencies (0: none; 1: critical; up to 10 times critical).
pub const CONTACT_DAMPING: Range = Range {
    min: 0.0,
    max: 10.0,
    unit: "",
};
/// `joints.*.cohesion` and `joints.*.tensile_strength`.
pub const STRENGTH: Range = Range {
    min: 0.0,
    max: 1e11,
    unit: "Pa",
};
/// Each coordinate of a vertex, a load's point or a fixed point.
pub const COORDINATE: Range = Range {
    min: -1e7,
    max: 1e7,
    unit: "m",
};
/// Each component of a block's initial `velocity`.
pub const SPEED: Range = Range {
    min: -1e4,
    max: 1e4,
    unit: "m/s",
};
/// A block's initial `angular_velocity`.
pub const SPIN: Range = Range {
    min: -1e4,
    max: 1e4,
    unit: "rad/s",
};
/// Each component of a block's initial `stress`.
pub const STRESS: Range = Range {
    min: -1e11,
    max: 1e11,
    unit: "Pa",
};
/// Each component of a region's `stress_gradient`: some 30 times the weight of the
/// densest rock the scene admits (1e5 kg/m^3 at 1e4 m/s^2 would be 1e9).
pub const STRESS_GRADIENT: Range = Range {
    min: -1e9,
    max: 1e9,
    unit: "Pa/m",
};
/// Each component of a point load's `force`.
pub const FORCE: Range = Range {
    min: -1e13,
    max: 1e13,
    unit: "N",
};
/// Nesting depth of arrays and tables beyond which a scene file is refused before it
/// is parsed (a scene needs 4: `blocks[i].loads[j].at`).
pub const MAX_NESTING: usize = 64;
/// `blocks[].removed_at`, s: a time of the run.
pub const REMOVAL: Range = Range {
    min: 0.0,
    max: 1e7,
    unit: "s",
};
/// `bolts[].pretension` and `bolts[].strength`, N.
pub const BOLT_FORCE: Range = Range {
    min: 0.0,
    max: 1e13,
    unit: "N",
};
/// Most blocks the `[[regions]]` of a scene may be cut into, estimated before cutting
/// from the joints crossing each region (a spacing typed in mm for m would otherwise
/// cut for hours and exhaust memory).
pub const MAX_REGION_BLOCKS: f64 = 1e6;
/// How far two blocks may overlap at the start, m (or 1e-9 of their size, if larger):
/// coordinates written to 6 decimals (in m) move each vertex by at most 0.71e-6 m, so
/// two blocks that share a face may overlap by up to 1.4e-6 m as written.
pub const START_OVERLAP: f64 = 2e-6;
/// `seismic` record times, s.
pub const RECORD_TIME: Range = Range {
    min: 0.0,
    max: 1e7,
    unit: "s",
};
/// Most samples a `seismic` record may hold (a day sampled at 10 Hz is 864,000).
pub const MAX_RECORD_SAMPLES: f64 = 1e6;
/// Largest `seismic` record file read, bytes: 1e6 samples of three numbers written in
/// full precision take about 70 MB.
pub const MAX_RECORD_BYTES: u64 = 128 << 20;
/// Largest scene file read, bytes: a run's `scene.json` of a million blocks, each
/// listed with its vertices in full precision, and a record of a million samples take
/// some 0.5 GB.
pub const MAX_SCENE_BYTES: u64 = 1 << 30;
/// `seismic.scale`.
pub const RECORD_SCALE: Range = Range {
    min: -1e3,
    max: 1e3,
    unit: "",
};
