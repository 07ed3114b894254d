//! Random convex polygons for property tests, shared by the workspace's test suites
//! (feature `test-support`, for tests only):
//! ellipse polygons (3 to 64 vertices, aspect up to 100), sliver wedges (tip angles down
//! to 1 degree) and chamfered polygons (edges down to 1e-4 of the size), placed at random
//! and given clockwise or counter-clockwise; and the property tests' configuration.

use crate::{ConvexPolygon, DVec2};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use std::f64::consts::TAU;

/// The seed the property tests draw their cases from unless `PROPTEST_RNG_SEED` is set.
pub const SEED: u64 = 20261121;

/// Proptest's configuration for `cases` cases, drawn from [`SEED`] so that every run of
/// the test command, CI's included, checks the same cases (and a failure repeats);
/// `PROPTEST_RNG_SEED=N cargo test` draws other cases.
pub fn config(cases: u32) -> ProptestConfig {
    let mut c = ProptestConfig {
        cases,
        ..ProptestConfig::default()
    };
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        c.rng_seed = RngSeed::Fixed(SEED);
    }
    c
}

/// A random convex polygon of unit size: one of an ellipse polygon (3 to 64 vertices,
/// aspect up to 100), a sliver wedge (tip 1 to 20 degrees) or a chamfered polygon
/// (chamfer 1e-4 to 1e-1 of the size).
pub fn unit_polygon() -> impl Strategy<Value = Vec<DVec2>> {
    let ellipse = (
        3usize..=64,
        0.01f64..=1.0,
        prop::collection::vec(0.0f64..1.0, 64),
    )
        .prop_map(|(n, aspect, jitter)| {
            let step = TAU / n as f64;
            (0..n)
                .map(|i| {
                    let t = step * (i as f64 + 0.9 * jitter[i]);
                    DVec2::new(t.cos(), aspect * t.sin())
                })
                .collect::<Vec<_>>()
        });
    let wedge = (1.0f64..=20.0, 0.2f64..=1.0).prop_map(|(tip_deg, ratio)| {
        let h = 0.5 * tip_deg.to_radians();
        // Legs of length 1 and `ratio`: a sliver, not necessarily isosceles.
        vec![
            DVec2::ZERO,
            DVec2::new(h.cos(), -h.sin()),
            ratio * DVec2::new(h.cos(), h.sin()),
        ]
    });
    let chamfered = (3usize..=8, -4.0f64..=-1.0, 0usize..8).prop_map(|(n, log_cut, corner)| {
        let step = TAU / n as f64;
        let v: Vec<DVec2> = (0..n).map(|i| DVec2::from_angle(step * i as f64)).collect();
        let k = corner % n;
        let edge = v[0].distance(v[1]);
        let cut = 10f64.powf(log_cut) * edge;
        let mut out = Vec::with_capacity(n + 1);
        for i in 0..n {
            if i == k {
                let (p, q) = (v[(i + n - 1) % n], v[(i + 1) % n]);
                out.push(v[i] + (p - v[i]).normalize() * cut);
                out.push(v[i] + (q - v[i]).normalize() * cut);
            } else {
                out.push(v[i]);
            }
        }
        out
    });
    prop_oneof![ellipse, wedge, chamfered]
}

/// A random convex polygon placed with a random rotation, scale and centre, plus whether it
/// was given clockwise. Polygons outside the envelope (an angle below 1 degree or
/// an edge below 1e-4 of the diameter, which jittered ellipses can produce) are rejected.
pub fn polygon_at(center: DVec2) -> impl Strategy<Value = (ConvexPolygon, bool)> {
    (unit_polygon(), 0.0f64..TAU, 0.2f64..=5.0, any::<bool>()).prop_filter_map(
        "outside the sliver envelope",
        move |(pts, rot, scale, clockwise)| {
            let mut pts: Vec<DVec2> = pts
                .into_iter()
                .map(|p| center + scale * DVec2::from_angle(rot).rotate(p))
                .collect();
            if clockwise {
                pts.reverse();
            }
            let p = ConvexPolygon::new(pts).ok()?;
            let ok = p.smallest_angle().1 >= 1f64.to_radians() * (1.0 - 1e-9)
                && p.shortest_edge().1 >= 1e-4 * p.diameter() * (1.0 - 1e-9);
            ok.then_some((p, clockwise))
        },
    )
}

/// Two polygons near each other: B's centre at a random direction from A's, at 0.2 to 1.5
/// times the sum of their radii, so that about half the pairs overlap.
pub fn near_pair() -> impl Strategy<Value = (ConvexPolygon, ConvexPolygon)> {
    (
        polygon_at(DVec2::ZERO),
        polygon_at(DVec2::ZERO),
        0.0f64..TAU,
        0.2f64..1.5,
    )
        .prop_map(|((a, _), (b, _), dir, f)| {
            let radius = |p: &ConvexPolygon| {
                let c = p.centroid();
                p.vertices()
                    .iter()
                    .map(|v| v.distance(c))
                    .fold(0.0, f64::max)
            };
            let d = f * (radius(&a) + radius(&b));
            let shift = DVec2::from_angle(dir) * d + a.centroid() - b.centroid();
            let b = b.translated(shift);
            (a, b)
        })
}
