//! The paper's section 4 hard cases, run with every detector: each outcome (verdict, final
//! state of the moving block rounded to 1e-3, active contacts, largest overlap) is a
//! reviewed insta snapshot, and the cover detector must be physically permissible in
//! every case (criteria in `dda_bench::verdict`).

#![allow(clippy::unwrap_used)]

use dda::bench::{HARD_CASES, judge_collision};
use dda::core::{RunOptions, Simulation};
use serde::Serialize;

/// A snapshot of one run, rounded so that it states what the run did.
#[derive(Serialize)]
struct Snapshot {
    permissible: bool,
    failures: Vec<String>,
    centroid: [f64; 2],
    velocity: [f64; 2],
    rotation: f64,
    active_contacts: usize,
    max_overlap_mm: f64,
}

/// Rounds to 1e-3.
fn r3(x: f64) -> f64 {
    (x * 1e3).round() / 1e3 + 0.0
}

#[test]
fn every_case_with_every_detector() {
    for case in HARD_CASES {
        for detector in ["cover", "type-1", "type-2"] {
            let mut scene = case.scene();
            scene.analysis.detector = detector.into();
            let model = scene.validate().unwrap();
            let mut sim = Simulation::new(model, RunOptions::default());
            let o = judge_collision(&mut sim);
            if detector == "cover" {
                assert!(o.permissible, "{} with cover: {:?}", case.case, o.failures);
            }
            let snap = Snapshot {
                permissible: o.permissible,
                failures: o
                    .failures
                    .iter()
                    .map(|f| f.split(" (").next().unwrap_or(f).to_string())
                    .collect(),
                centroid: o.centroid.map(r3),
                velocity: o.velocity.map(r3),
                rotation: r3(o.rotation),
                active_contacts: o.active_contacts,
                max_overlap_mm: r3(1e3 * o.max_overlap),
            };
            insta::assert_yaml_snapshot!(format!("{}-{}", case.name(), detector), snap);
        }
    }
}
