//! One DDA step of the 826-block jointed column (built-in `paper-5.2b-column-826`), whole and
//! broken into its phases: contact detection, assembly, numeric factorisation + solve.
//!
//! - `column_step/step`: `Simulation::step` on a running column (each iteration is the
//!   next step, including its open-close iterations and any time-step cuts); the mean
//!   per-phase seconds of the measured steps are printed after it.
//! - `column_step/detect`: step-start detection over every neighbour pair (cover).
//! - `column_step/assemble`: adding block terms and spring outer products into the
//!   block-sparse storage of the global matrix on the column's own block pattern, no solve.
//! - `column_step/factorise_solve`: numeric Cholesky + solve of the global matrix on the
//!   column's own block pattern (6 DOF per block), the symbolic analysis done once.
//! - `column_step/resolve`: the forward and backward triangular sweeps of one right-hand
//!   side with that factor.
//! - `column_step/low_rank_solve/k`: a solve through a rank-k update of that factor.

use criterion::{Criterion, criterion_group, criterion_main};
use dda::contact::{BlockShape, ContactSet, DetectionParams, detect, neighbour_pairs};
use dda::core::kinematics::Vec6;
use dda::core::{BlockSystem, RankOne, RunOptions, Simulation, StepRecord};
use std::hint::black_box;
use std::time::{Duration, Instant};

fn column() -> Simulation {
    let scene = dda::bench::builtin("paper-5.2b-column-826").expect("built-in");
    let model = scene.validate().expect("valid");
    Simulation::new(model, RunOptions::default())
}

fn bench_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("column_step");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));

    // A running column: past its first steps, where everything starts touching.
    let mut sim = column();
    for _ in 0..20 {
        sim.step().expect("step");
    }
    let mut records: Vec<StepRecord> = Vec::new();
    group.bench_function("step", |b| {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                if sim.finished() {
                    sim = column();
                }
                records.push(sim.step().expect("step"));
            }
            start.elapsed()
        })
    });
    let n = records.len().max(1) as f64;
    let mean = |f: fn(&StepRecord) -> f64| records.iter().map(f).sum::<f64>() / n;
    let oci = mean(|r| r.oci as f64);
    println!(
        "column_step/step phases over {} steps: detection {:.3} ms, assembly {:.3} ms, \
         factorise+solve {:.3} ms; {:.2} OCI iterations per step ({} unknowns)",
        records.len(),
        1e3 * mean(|r| r.detection_s),
        1e3 * mean(|r| r.assembly_s),
        1e3 * mean(|r| r.solve_s),
        oci,
        sim.unknowns()
    );

    let sim = column();
    let shapes: Vec<BlockShape> = sim
        .blocks()
        .iter()
        .map(|b| BlockShape::new(&b.polygon))
        .collect();
    let p = &sim.model().params;
    let params = DetectionParams::new(p.d_tol, p.theta_max);
    let detector = dda::contact::detector_by_name("cover").expect("cover");
    let boxes: Vec<_> = shapes.iter().map(|s| s.aabb).collect();
    let mut pairs = Vec::new();
    neighbour_pairs(&boxes, params.d_tol, &mut pairs);
    let (prev, mut out) = (ContactSet::default(), ContactSet::default());
    group.bench_function("detect", |b| {
        b.iter(|| {
            detect(
                detector.as_ref(),
                &shapes,
                &pairs,
                &params,
                &prev,
                true,
                &mut out,
            );
            black_box(out.len())
        })
    });

    // The global matrix on the column's block pattern (block 0 is the fixed base).
    let block_pairs: Vec<(u32, u32)> = pairs
        .iter()
        .filter(|q| q.a > 0)
        .map(|q| (q.a - 1, q.b - 1))
        .collect();
    let nb = shapes.len() - 1;
    let diag = {
        let mut diag = [[0.0; 6]; 6];
        for (k, row) in diag.iter_mut().enumerate() {
            row[k] = 1e9;
        }
        diag
    };
    let u: Vec6 = [1.0, -1.0, 0.3, 0.1, 0.2, -0.1];
    // The values of a column-like matrix: a block term per block, and per coupled pair
    // one spring's outer products (two diagonal, one off-diagonal).
    let assemble = |sys: &mut BlockSystem| {
        sys.clear();
        for i in 0..nb as u32 {
            sys.add_diagonal(i, &diag);
            sys.add_rhs(i, 1.0, &[1.0; 6]);
        }
        for &(i, j) in &block_pairs {
            let e = sys.entry(i, j).expect("entry");
            sys.add_outer(sys.diagonal(i), i, i, 3e8, &u, &u);
            sys.add_outer(sys.diagonal(j), j, j, 3e8, &u, &u);
            sys.add_outer(e, i, j, -3e8, &u, &u);
        }
    };
    let build = || {
        let mut sys = BlockSystem::new();
        sys.set_pattern(nb, 6, &block_pairs).expect("pattern");
        assemble(&mut sys);
        sys
    };
    let mut sys = build();
    group.bench_function("assemble", |b| {
        b.iter(|| {
            assemble(&mut sys);
            black_box(sys.is_factored())
        })
    });
    group.bench_function("factorise_solve", |b| {
        b.iter_batched_ref(
            build,
            |sys| {
                sys.solve().expect("solve");
                black_box(sys.solution(0)[0])
            },
            criterion::BatchSize::LargeInput,
        )
    });
    // Both triangular sweeps with that factor: the solve of a new right-hand side.
    let mut factored = build();
    factored.solve().expect("solve");
    group.bench_function("resolve", |b| {
        b.iter(|| {
            factored.clear_rhs();
            for i in 0..nb as u32 {
                factored.add_rhs(i, 1.0, &[1.0; 6]);
            }
            assert!(factored.resolve());
            black_box(factored.solution(0)[0])
        })
    });
    // Solves through a low-rank update of that factor, k springs changed (all new
    // columns: the cost of the first low-rank solve after a factorisation).
    for k in [1usize, 8, 32, 96] {
        let terms: Vec<RankOne> = block_pairs
            .iter()
            .step_by(block_pairs.len() / k)
            .take(k)
            .map(|&(i, j)| RankOne {
                blocks: [Some(i), Some(j)],
                c: [
                    [1.0, 0.5, 0.2, 0.1, 0.0, 0.1],
                    [-1.0, -0.5, 0.3, 0.0, 0.1, 0.0],
                ],
                s: 3e9,
            })
            .collect();
        group.bench_function(format!("low_rank_solve/{k}"), |b| {
            b.iter_batched_ref(
                || {
                    let mut sys = build();
                    sys.solve().expect("solve");
                    sys
                },
                |sys| {
                    assert!(sys.solve_low_rank(&terms, &[]));
                    black_box(sys.solution(0)[0])
                },
                criterion::BatchSize::LargeInput,
            )
        });
    }
    group.finish();
}

criterion_group!(benches, bench_step);
criterion_main!(benches);
