//! Contact-detection benchmarks: per-pair cost of each detector on touching n-gon pairs,
//! and whole-scene detection (neighbour search + every pair) on a jointed column of about
//! 826 blocks (10 m x 20 m cut by joint sets at 60 and 15 degrees).

use criterion::measurement::WallTime;
use criterion::{
    BenchmarkGroup, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main,
};
use dda::contact::{
    BlockShape, ContactSet, DetectionParams, NeighbourPair, detect, detector_by_name,
    neighbour_pairs,
};
use dda::geom::{DVec2, shapes};
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

criterion_group!(benches, bench_pairs, bench_scene);
criterion_main!(benches);
