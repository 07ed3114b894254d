//! Checkpoints: a run resumed from a checkpoint goes on bit for bit as the uninterrupted
//! run, and damaged checkpoint files are refused with the reason.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda_core::{Checkpoint, CheckpointError, RunOptions, Scene, Simulation, StepRecord};
use std::path::Path;

const SLIDING_BLOCK: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/scenes/sliding-block.toml"
);

/// A wall notched by an excavation halfway through the run: resumed before it and
/// after it.
const EXCAVATION: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/excavation.toml");

/// A body split by an excavation at its fifth step: resumed before it and after it.
const SPLIT_BODY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/split-body.toml");

/// A wall on a shaking ground (its record in a file beside it).
const QUAKE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/quake.toml");

fn scenes() -> Vec<Scene> {
    let mut v = vec![Scene::load(Path::new(SLIDING_BLOCK)).unwrap().0];
    v.push(Scene::load(Path::new(EXCAVATION)).unwrap().0);
    v.push(Scene::load(Path::new(SPLIT_BODY)).unwrap().0);
    v.push(Scene::load(Path::new(QUAKE)).unwrap().0);
    // The average-acceleration rule carries each block's acceleration (impact_steps).
    let mut impacts = Scene::load(Path::new(QUAKE)).unwrap().0;
    impacts.name = "quake-impact-steps".into();
    impacts.analysis.impact_steps = Some(10);
    v.push(impacts);
    // So does the damped rule.
    let mut damped = Scene::load(Path::new(QUAKE)).unwrap().0;
    damped.name = "quake-damped".into();
    damped.analysis.integration = Some(dda_core::scene::Integration::DampedConstantAcceleration);
    v.push(damped);
    for name in ["paper-5.1a-column-20", "paper-4.1-sharp-corners"] {
        v.push(dda_bench::builtin(name).unwrap());
    }
    // Solved iteratively: each attempt starts from the state alone.
    let mut iterative = dda_bench::builtin("paper-5.1a-column-20").unwrap();
    iterative.name = "column-20-iterative".into();
    iterative.analysis.solver = Some(dda_core::scene::SolverChoice::Iterative);
    v.push(iterative);
    v
}

/// A step record without its wall-clock fields.
fn untimed(r: &StepRecord) -> StepRecord {
    StepRecord {
        detection_s: 0.0,
        assembly_s: 0.0,
        solve_s: 0.0,
        ..*r
    }
}

fn run_to_end(sim: &mut Simulation) -> Vec<StepRecord> {
    let mut recs = Vec::new();
    sim.run(|_, r| recs.push(untimed(r))).unwrap();
    recs
}

#[test]
fn resumed_run_equals_uninterrupted_run() {
    for scene in scenes() {
        for parallel in [true, false] {
            let options = RunOptions {
                parallel,
                ..RunOptions::default()
            };
            let model = scene.validate().unwrap();
            let mut whole = Simulation::new(model.clone(), options);
            let all = run_to_end(&mut whole);
            let expected = dda_core::Summary::of(&whole, None).without_timing();
            assert!(all.len() > 20, "{}: too short a run to test", scene.name);

            // Stop at several points, through the file format each time.
            for stop in [1, all.len() / 3, all.len() - 1] {
                let mut first = Simulation::new(model.clone(), options);
                for _ in 0..stop {
                    first.step().unwrap();
                }
                let path = Path::new("checkpoint.bin");
                let bytes = Checkpoint::of(&first, &scene, String::new())
                    .unwrap()
                    .to_bytes()
                    .unwrap();
                drop(first);
                let ck = Checkpoint::from_bytes(&bytes, path).unwrap();
                let saved_scene = ck.scene(path).unwrap();
                assert_eq!(saved_scene, scene);
                let mut resumed = ck
                    .resume(saved_scene.validate().unwrap(), options, path)
                    .unwrap();
                let rest = run_to_end(&mut resumed);
                assert_eq!(
                    rest,
                    all[stop..],
                    "{} (parallel {parallel}): steps after a resume at step {stop} differ",
                    scene.name
                );
                assert_eq!(
                    dda_core::Summary::of(&resumed, None).without_timing(),
                    expected,
                    "{} (parallel {parallel}): summary after a resume at step {stop}",
                    scene.name
                );
            }
        }
    }
}

/// A checkpoint of a few steps of the sliding block, as bytes.
fn checkpoint_bytes() -> Vec<u8> {
    let scene = Scene::load(Path::new(SLIDING_BLOCK)).unwrap().0;
    let mut sim = Simulation::new(scene.validate().unwrap(), RunOptions::default());
    for _ in 0..5 {
        sim.step().unwrap();
    }
    Checkpoint::of(&sim, &scene, String::new())
        .unwrap()
        .to_bytes()
        .unwrap()
}

#[test]
fn damaged_checkpoints_are_refused() {
    let good = checkpoint_bytes();
    let path = Path::new("run/checkpoint.bin");
    assert!(Checkpoint::from_bytes(&good, path).is_ok());

    for cut in [0, 5, 23, 24, good.len() / 2, good.len() - 1] {
        let e = Checkpoint::from_bytes(&good[..cut], path).unwrap_err();
        match e {
            CheckpointError::Truncated { .. } if cut >= 8 => {}
            CheckpointError::NotACheckpoint { .. } if cut < 8 => {}
            other => panic!("cut at {cut}: {other}"),
        }
        assert!(e_names_file(&Checkpoint::from_bytes(&good[..cut], path)));
    }

    // Every byte of the payload is covered by the checksum: flip one here and there.
    for at in [24, 100, good.len() / 2, good.len() - 1] {
        let mut bad = good.clone();
        bad[at] ^= 0x10;
        let e = Checkpoint::from_bytes(&bad, path).unwrap_err();
        assert!(
            matches!(e, CheckpointError::Checksum { .. }),
            "flip at {at}: {e}"
        );
    }

    let mut bad = good.clone();
    bad[8] = 99;
    let e = Checkpoint::from_bytes(&bad, path).unwrap_err();
    assert!(
        matches!(e, CheckpointError::Version { found: 99, .. })
            && e.to_string().contains("scene.json"),
        "{e}"
    );

    let mut bad = good.clone();
    bad[0] = b'X';
    let e = Checkpoint::from_bytes(&bad, path).unwrap_err();
    assert!(matches!(e, CheckpointError::NotACheckpoint { .. }), "{e}");
}

fn e_names_file(r: &Result<Checkpoint, CheckpointError>) -> bool {
    match r {
        Err(e) => e.to_string().contains("run/checkpoint.bin"),
        Ok(_) => false,
    }
}

#[test]
fn checkpoint_of_another_scene_is_refused() {
    let good = checkpoint_bytes();
    let path = Path::new("checkpoint.bin");
    let ck = Checkpoint::from_bytes(&good, path).unwrap();
    let other = dda_bench::builtin("paper-5.1a-column-20").unwrap();
    let e = ck
        .resume(other.validate().unwrap(), RunOptions::default(), path)
        .unwrap_err();
    assert!(e.to_string().contains("blocks"), "{e}");
}

/// Threads change nothing: on the 826-block column (large enough for the thread pool to
/// be used for detection and for the per-block terms), steps with and without threads
/// give the same records and the same state, bit for bit.
#[test]
fn threads_give_the_same_steps_bit_for_bit() {
    let scene = dda_bench::builtin("paper-5.2b-column-826").unwrap();
    let model = scene.validate().unwrap();
    let mut with = Simulation::new(
        model.clone(),
        RunOptions {
            parallel: true,
            ..RunOptions::default()
        },
    );
    let mut without = Simulation::new(
        model,
        RunOptions {
            parallel: false,
            ..RunOptions::default()
        },
    );
    for step in 0..15 {
        let (a, b) = (with.step().unwrap(), without.step().unwrap());
        assert_eq!(untimed(&a), untimed(&b), "step {step}");
    }
    let untimed_state = |sim: &Simulation| {
        let mut snap = sim.snapshot();
        let t = &mut snap.state.totals;
        (t.total_s, t.detection_s, t.assembly_s, t.solve_s) = (0.0, 0.0, 0.0, 0.0);
        snap
    };
    assert_eq!(untimed_state(&with), untimed_state(&without));
}

/// A column large enough that the contact law decides its contacts in two halves
/// (`dda_core::PARALLEL_MIN_CONTACTS`) takes the same steps and ends in the same state,
/// bit for bit, with the halves on two threads (`RunOptions::parallel`) as with the
/// whole list decided in one pass on one.
#[test]
fn the_contact_law_decides_alike_in_halves() {
    let column = dda_bench::PAPER_COLUMNS[3];
    let blocks = column.scaled_blocks((4_000.0 / column.blocks as f64).sqrt());
    let mut analysis = column.analysis();
    analysis.frames = 0;
    // The direct solve, so that only `parallel` sends the halves to two threads.
    analysis.solver = Some(dda_core::scene::SolverChoice::Direct);
    let model = dda_bench::column_scene("column", &blocks, analysis)
        .validate()
        .unwrap();
    let run = |parallel: bool| {
        let mut sim = Simulation::new(
            model.clone(),
            RunOptions {
                parallel,
                ..RunOptions::default()
            },
        );
        let recs: Vec<StepRecord> = (0..4).map(|_| untimed(&sim.step().unwrap())).collect();
        let mut snap = sim.snapshot();
        let t = &mut snap.state.totals;
        (t.total_s, t.detection_s, t.assembly_s, t.solve_s) = (0.0, 0.0, 0.0, 0.0);
        assert!(
            snap.state.contacts.len() >= dda_core::PARALLEL_MIN_CONTACTS,
            "{} contacts: too few to be decided in halves",
            snap.state.contacts.len()
        );
        (recs, snap)
    };
    assert_eq!(run(true), run(false));
}

/// The 826-block column solved iteratively (its products taken in two halves, on two
/// threads, `solver::iterative`) takes the same steps and ends in the same state, bit
/// for bit, in thread pools of 1, 2 and 4 threads.
#[test]
fn the_iterative_solve_gives_the_same_steps_in_any_pool() {
    let mut scene = dda_bench::builtin("paper-5.2b-column-826").unwrap();
    scene.analysis.solver = Some(dda_core::scene::SolverChoice::Iterative);
    let model = scene.validate().unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut sim = Simulation::new(model.clone(), RunOptions::default());
            let recs: Vec<StepRecord> = (0..15).map(|_| untimed(&sim.step().unwrap())).collect();
            let mut snap = sim.snapshot();
            let t = &mut snap.state.totals;
            (t.total_s, t.detection_s, t.assembly_s, t.solve_s) = (0.0, 0.0, 0.0, 0.0);
            assert!(snap.counters.iterative > 0, "solved iteratively");
            (recs, snap)
        })
    };
    let one = run(1);
    assert_eq!(run(2), one, "two threads");
    assert_eq!(run(4), one, "four threads");
}
