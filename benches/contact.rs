//! Contact-detection benchmarks: per-pair cost of each detector on touching n-gon pairs,
//! and whole-scene detection (neighbour search + every pair) on a jointed column of about
//! 826 blocks (10 m x 20 m cut by joint sets at 60 and 15 degrees); and the nearest-box
//! gaps of a rockfall's blocks in flight (`nearest_box`), by the tree and by a scan.

use criterion::measurement::WallTime;
use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main,
};
use dda::contact::{
    BlockShape, BoxTrees, ContactSet, DetectionParams, NeighbourPair, detect, detector_by_name,
    neighbour_pairs,
};
use dda::geom::{Aabb, DVec2, shapes};
use std::hint::black_box;

const DETECTORS: [&str; 3] = ["cover", "type-1", "type-2"];

/// Two regular n-gons of radius 1, B resting on A's top with 1 mm overlap, B turned a
/// little so that vertices and edges meet at general positions.
fn ngon_pair(n: usize) -> Vec<BlockShape> {
    let a = shapes::regular(n, 1.0, DVec2::ZERO, 0.1).expect("regular polygon");
    let top = a.vertices().iter().map(|v| v.y).fold(f64::MIN, f64::max);
    let b0 = shapes::regular(n, 1.0, DVec2::ZERO, 0.37).expect("regular polygon");
    let bottom = b0.vertices().iter().map(|v| v.y).fold(f64::MAX, f64::min);
    let b = b0.translated(DVec2::new(0.05, top - bottom - 0.001));
    vec![BlockShape::new(&a), BlockShape::new(&b)]
}

/// The 10 m x 20 m column cut by joint sets at 60 and 15 degrees (826 blocks): the
/// built-in `paper-5.2b-column-826` without its base.
fn column() -> Vec<BlockShape> {
    let scene = dda::bench::builtin("paper-5.2b-column-826").expect("built-in");
    let model = scene.validate().expect("valid built-in");
    model
        .blocks
        .iter()
        .filter(|b| !b.fixed)
        .map(|b| BlockShape::new(&b.polygon))
        .collect()
}

/// Step-start detection of `pairs` with each detector (sequential), as `DETECTOR/param`.
fn bench_detectors(
    group: &mut BenchmarkGroup<'_, WallTime>,
    param: &str,
    shapes: &[BlockShape],
    pairs: &[NeighbourPair],
    params: &DetectionParams,
) {
    for name in DETECTORS {
        let det = detector_by_name(name).expect("built-in");
        let mut out = ContactSet::default();
        let prev = ContactSet::default();
        group.bench_function(BenchmarkId::new(name, param), |bench| {
            bench.iter(|| {
                detect(
                    det.as_ref(),
                    black_box(shapes),
                    pairs,
                    params,
                    &prev,
                    false,
                    &mut out,
                );
                out.len()
            })
        });
    }
}

fn bench_pairs(c: &mut Criterion) {
    let params = DetectionParams::new(0.01, 2f64.to_radians());
    let mut group = c.benchmark_group("detect_pair");
    for n in [3usize, 4, 8, 18, 64] {
        let shapes = ngon_pair(n);
        let pairs = [NeighbourPair::new(0, 1)];
        bench_detectors(&mut group, &n.to_string(), &shapes, &pairs, &params);
    }
    group.finish();
}

fn bench_scene(c: &mut Criterion) {
    let shapes = column();
    let boxes: Vec<_> = shapes.iter().map(|s| s.aabb).collect();
    let mut group = c.benchmark_group("column_scene");
    for rtol in [1.0, 10.0] {
        let params = DetectionParams::new(0.026 * rtol, 2f64.to_radians());
        let mut pairs = Vec::new();
        neighbour_pairs(&boxes, params.d_tol, &mut pairs);
        group.throughput(Throughput::Elements(pairs.len() as u64));
        group.bench_function(BenchmarkId::new("neighbour_search", rtol), |bench| {
            let mut out = Vec::new();
            bench.iter(|| {
                neighbour_pairs(black_box(&boxes), params.d_tol, &mut out);
                out.len()
            })
        });
        bench_detectors(&mut group, &rtol.to_string(), &shapes, &pairs, &params);
    }
    group.finish();
}

/// A rockfall's boxes: `n` x `n` blocks of 0.4 m at a pitch of 0.5 m, each column
/// shifted by up to 4 cm, above a fixed floor as wide as they are (the floor first).
fn rockfall_boxes(n: usize) -> Vec<Aabb> {
    let floor = Aabb {
        min: DVec2::new(-2.0, -2.0),
        max: DVec2::new(n as f64 * 0.5 + 2.0, 0.0),
    };
    let blocks = (0..n * n).map(|k| {
        let (i, j) = (k / n, k % n);
        let min = DVec2::new(
            i as f64 * 0.5 + 0.01 * ((i * 7 + j * 3) % 5) as f64,
            2.0 + j as f64 * 0.5,
        );
        Aabb {
            min,
            max: min + DVec2::splat(0.4),
        }
    });
    std::iter::once(floor).chain(blocks).collect()
}

/// Every box's gap to its nearest other (each block in flight's, as a step asks), by
/// the trees of [`BoxTrees`] (built and asked) and, at the smaller size, by a scan of
/// every box for each, as the engine did before them.
fn bench_nearest(c: &mut Criterion) {
    let mut group = c.benchmark_group("nearest_box");
    for n in [40usize, 160] {
        let boxes = rockfall_boxes(n);
        group.throughput(Throughput::Elements(boxes.len() as u64));
        group.bench_function(BenchmarkId::new("tree", boxes.len()), |bench| {
            let mut tree = BoxTrees::new();
            bench.iter(|| {
                tree.build(black_box(&boxes), |_| true);
                (0..boxes.len())
                    .map(|i| tree.nearest_gap(&boxes, i))
                    .sum::<f64>()
            })
        });
        if n == 40 {
            group.bench_function(BenchmarkId::new("scan", boxes.len()), |bench| {
                bench.iter(|| {
                    let boxes = black_box(&boxes);
                    (0..boxes.len())
                        .map(|i| {
                            (0..boxes.len())
                                .filter(|&j| j != i)
                                .map(|j| boxes[i].gap(&boxes[j]))
                                .fold(f64::INFINITY, f64::min)
                        })
                        .sum::<f64>()
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_pairs, bench_scene, bench_nearest);
criterion_main!(benches);
