//! Two-set columns the paper did not run: the 10 m x 20 m column of section 5.2 cut by
//! six other pairs of joint sets, collapsing under gravity for 1 s with every detector,
//! judged by the collapse verdict (`dda_bench::collapse`) and d_tol. Their joints leave
//! slivers with edges of 2 to 21 mm, so d_tol is 0.2 x max(smallest edge, 0.05 m) =
//! 0.01 m, d_max half of it, penalty 3e9 N/m, dt 0.02 s, as the paper's 229-block column.
//! `cargo run --release -p dda-bench --example other_columns` (a few minutes).

use dda_bench::{ColumnSpec, column_scene, jointed_column, paper_analysis, run_watched};
use dda_core::{RunOptions, Simulation};
use dda_geom::JointSet;

/// (dip in degrees, spacing in m, first joint as a fraction of the spacing) of each set.
type Set = (f64, f64, f64);

const COLUMNS: [(Set, Set); 6] = [
    ((45.0, 0.9, 0.3), (120.0, 0.8, 0.6)),
    ((70.0, 0.7, 0.1), (10.0, 1.1, 0.5)),
    ((30.0, 1.0, 0.2), (100.0, 0.9, 0.4)),
    ((55.0, 0.6, 0.5), (145.0, 0.75, 0.2)),
    ((80.0, 1.2, 0.7), (20.0, 0.65, 0.9)),
    ((40.0, 0.8, 0.45), (5.0, 0.95, 0.15)),
];

fn main() {
    println!(
        "| sets (dip, spacing) | blocks | smallest edge (m) | detector | steps | permissible | fastest block / 3 g t | largest penetration (m) |"
    );
    println!("|---|---:|---:|---|---:|---|---:|---:|");
    for (s1, s2) in COLUMNS {
        let set = |(dip_deg, spacing, first): Set| JointSet {
            dip_deg,
            spacing,
            offset: first * spacing,
        };
        let spec = ColumnSpec {
            width: 10.0,
            height: 20.0,
            sets: vec![set(s1), set(s2)],
            min_area: 0.005,
        };
        let blocks = match jointed_column(&spec) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("{s1:?} {s2:?}: {e}");
                continue;
            }
        };
        let min_edge = blocks
            .iter()
            .map(|b| b.shortest_edge().1)
            .fold(f64::INFINITY, f64::min);
        let d_tol = 0.2 * min_edge.max(0.05);
        for detector in ["cover", "type-1", "type-2"] {
            let analysis = paper_analysis(1.0, 0.02, d_tol / 2.0, d_tol, 3e9, Some([0.0, -9.8]));
            let mut scene = column_scene("other", &blocks, analysis);
            scene.analysis.detector = detector.into();
            let model = match scene.validate() {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("{s1:?} {s2:?}: {}", e.message);
                    continue;
                }
            };
            let mut sim = Simulation::new(model, RunOptions::default());
            let (watch, stop) = run_watched(&mut sim, 5000);
            let deepest = sim.totals().max_penetration;
            let ok = stop.is_none() && deepest < d_tol && watch.permissible();
            println!(
                "| ({}, {}) ({}, {}) | {} | {:.3} | {detector} | {} | {} | {:.2} | {:.1e} |",
                s1.0,
                s1.1,
                s2.0,
                s2.1,
                blocks.len(),
                min_edge,
                sim.totals().steps,
                if ok { "yes" } else { "**no**" },
                watch.speed.value,
                deepest
            );
        }
    }
}
