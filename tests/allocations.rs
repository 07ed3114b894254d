//! The step loop allocates nothing once its buffers have grown: every work buffer of
//! detection, assembly, the open-close iteration and the solve is kept from step to step.
//! dhat's global allocator (this test binary only) counts the allocations. One test, as
//! dhat's testing profiler is one per process.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda_core::{RunOptions, Scene, Simulation};
use std::path::Path;

#[global_allocator]
static ALLOC: dhat::Alloc = dhat::Alloc;

/// Heap blocks allocated so far (dhat counts every allocation and reallocation).
fn allocations() -> u64 {
    dhat::HeapStats::get().total_blocks
}

/// Allocations made by each of the next `n` steps.
fn per_step(sim: &mut Simulation, n: usize) -> Vec<u64> {
    (0..n)
        .map(|_| {
            let before = allocations();
            sim.step().unwrap();
            allocations() - before
        })
        .collect()
}

#[test]
fn steps_allocate_nothing_once_buffers_have_grown() {
    let _profiler = dhat::Profiler::builder().testing().build();

    // A block sliding on a fixed base: the same contacts every step.
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/scenes/sliding-block.toml"
    );
    let (scene, _) = Scene::load(Path::new(path)).unwrap();
    let mut sim = Simulation::new(scene.validate().unwrap(), RunOptions::default());
    // Warm-up: the buffers grow to the scene's size in the first steps.
    per_step(&mut sim, 5);
    let counts = per_step(&mut sim, 30);
    assert!(
        counts.iter().all(|&c| c == 0),
        "sliding block, allocations per step: {counts:?}"
    );

    // The 20-block column collapsing: contacts open, close and move from step to step, so
    // a buffer may still grow to a new largest size now and then. Buffers grow
    // geometrically, so such steps are rare; an allocation made by every step (or every
    // OCI iteration), which is what this guards against, would show in every step.
    let scene = dda_bench::builtin("paper-5.1a-column-20").unwrap();
    let mut sim = Simulation::new(scene.validate().unwrap(), RunOptions::default());
    per_step(&mut sim, 20);
    let counts = per_step(&mut sim, 200);
    let allocating = counts.iter().filter(|&&c| c > 0).count();
    println!("column: {allocating} of 200 steps allocated: {counts:?}");
    assert!(allocating < 20, "column, allocations per step: {counts:?}");
}
