//! The engine's physics across the layers: the paper's section 4 hard cases with every
//! detector (reviewed snapshots), its two-set columns with every detector, a jointed slope written as a region, random hard pairs, structures on flush joints, bonded
//! joints, masonry arches against limit analysis, a wheel rolling between its bounds, and
//! bit-identical resume and thread counts. One test binary, so that the suite links once
//! for all of them.

mod arches;
mod bolts;
mod bonds;
mod by_hand;
mod columns;
mod flush_joints;
mod hard_cases;
mod hard_pairs;
mod impacts;
mod regions;
mod resume;
mod rolling;
mod seismic;
mod stacks;
mod statics;

use dda::core::{Model, RunOptions, Simulation};

/// A simulation of `model` under the physics guard: a step that creates energy beyond
/// 1% of the reference, or penetrates beyond d_tol, is an error.
pub(crate) fn guarded(model: Model) -> Simulation {
    let options = RunOptions {
        stop_on_violation: true,
        ..RunOptions::default()
    };
    Simulation::new(model, options)
}
