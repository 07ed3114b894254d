//! Geometry benchmarks: signed distance through the entrance block (ours) against parry2d's
//! `query::distance` and `query::contact` on the same random convex pairs.
//!
//! Each measurement runs a batch of `PAIRS` pairs, half apart and half overlapping; the
//! throughput line gives pairs per second.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dda::geom::{ConvexPolygon, DVec2, EntranceBlock, signed_distance};
use parry2d_f64::math::Pose;
use parry2d_f64::query;
use parry2d_f64::shape::ConvexPolygon as ParryPolygon;
use std::hint::black_box;

const PAIRS: usize = 256;

/// SplitMix64: a tiny deterministic generator, so the bench needs no rand crate.
struct Rng(u64);
impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A random convex n-gon: n points on a random ellipse at jittered angles.
fn random_polygon(rng: &mut Rng, n: usize, center: DVec2) -> ConvexPolygon {
    let (rx, ry) = (0.5 + rng.next_f64(), 0.5 + rng.next_f64());
    let rot = rng.next_f64() * std::f64::consts::TAU;
    let step = std::f64::consts::TAU / n as f64;
    let pts: Vec<DVec2> = (0..n)
        .map(|i| {
            let t = step * (i as f64 + 0.8 * rng.next_f64());
            let p = DVec2::new(rx * t.cos(), ry * t.sin());
            center + DVec2::from_angle(rot).rotate(p)
        })
        .collect();
    ConvexPolygon::new(pts).expect("random ellipse polygon is convex")
}

fn pairs(n: usize) -> Vec<(ConvexPolygon, ConvexPolygon)> {
    let mut rng = Rng(0x5EED ^ n as u64);
    (0..PAIRS)
        .map(|k| {
            let a = random_polygon(&mut rng, n, DVec2::ZERO);
            // Half the pairs apart (centres 3 apart), half overlapping (centres 1 apart).
            let dist = if k.is_multiple_of(2) { 3.0 } else { 1.0 };
            let dir = DVec2::from_angle(rng.next_f64() * std::f64::consts::TAU);
            let b = random_polygon(&mut rng, n, dir * dist);
            (a, b)
        })
        .collect()
}

fn to_parry(p: &ConvexPolygon) -> ParryPolygon {
    ParryPolygon::from_convex_polyline_unmodified(p.vertices().to_vec())
        .expect("a valid polygon is a valid parry polygon")
}

fn bench_signed_distance(c: &mut Criterion) {
    let mut group = c.benchmark_group("signed_distance");
    group.throughput(Throughput::Elements(PAIRS as u64));
    for n in [4usize, 8, 18, 64] {
        let ours = pairs(n);
        let theirs: Vec<_> = ours
            .iter()
            .map(|(a, b)| (to_parry(a), to_parry(b)))
            .collect();
        let id = Pose::identity();
        group.bench_with_input(BenchmarkId::new("entrance_block", n), &ours, |bench, ps| {
            bench.iter(|| {
                ps.iter()
                    .map(|(a, b)| signed_distance(black_box(a), black_box(b)).distance)
                    .sum::<f64>()
            })
        });
        group.bench_with_input(
            BenchmarkId::new("parry_distance", n),
            &theirs,
            |bench, ps| {
                bench.iter(|| {
                    ps.iter()
                        .map(|(a, b)| {
                            query::distance(&id, black_box(a), &id, black_box(b))
                                .map(|d| d.distance)
                                .unwrap_or(f64::NAN)
                        })
                        .sum::<f64>()
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("parry_contact", n),
            &theirs,
            |bench, ps| {
                bench.iter(|| {
                    ps.iter()
                        .map(|(a, b)| {
                            query::contact(&id, black_box(a), &id, black_box(b), 10.0)
                                .ok()
                                .flatten()
                                .map_or(f64::NAN, |c| c.dist)
                        })
                        .sum::<f64>()
                })
            },
        );
    }
    group.finish();
    let mut group = c.benchmark_group("entrance_block_build");
    group.throughput(Throughput::Elements(PAIRS as u64));
    for n in [4usize, 18, 64] {
        let ours = pairs(n);
        group.bench_with_input(BenchmarkId::from_parameter(n), &ours, |bench, ps| {
            bench.iter(|| {
                ps.iter()
                    .map(|(a, b)| EntranceBlock::new(a, b, DVec2::ZERO).faces().len())
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_signed_distance);
criterion_main!(benches);
