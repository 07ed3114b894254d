//! Walls and stacks built by `Masonry`, on bases tilted past their friction angle, run
//! for 0.5 s (settled before the run, as a scene without `settle` is): each structure's
//! worst block against the closed form g (sin a - cos a tan phi) t^2 / 2, for the sweep
//! of issue 35 recorded in docs/method.md section 13. Running-bond walls of 3, 5 and 10
//! bricks (1 m x 0.5 m, half bricks at the ends of every other course) in 2 to 6
//! courses, and columns of 2 to 10 flat blocks (2 m x 0.2 m), on eight inclines; a line
//! each, worst last:
//! `cargo run --release -p dda-bench --example incline_walls`.

use dda_bench::{Layout, Masonry};
use dda_core::{RunOptions, Simulation};

/// The inclines: slope and friction angle, degrees.
const INCLINES: [(f64, f64); 8] = [
    (35.0, 30.0),
    (40.0, 30.0),
    (45.0, 35.0),
    (30.0, 25.0),
    (40.0, 35.0),
    (50.0, 40.0),
    (30.0, 20.0),
    (25.0, 20.0),
];

/// The worst block's slide down the slope over the closed form, minus 1; or the error of
/// a run that stopped.
fn worst(m: Masonry) -> Result<f64, String> {
    let model = m
        .scene("incline")
        .validate()
        .map_err(|e| format!("{e:?}"))?;
    let start: Vec<_> = model.blocks.iter().map(|b| b.polygon.centroid()).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).map_err(|e| e.to_string())?;
    Ok(m.slide_ratios(&sim, &start)
        .iter()
        .map(|r| (r - 1.0).abs())
        .fold(0.0, f64::max))
}

fn main() {
    let mut cases = Vec::new();
    for (tilt_deg, friction_deg) in INCLINES {
        let on = |m: Masonry| Masonry {
            tilt_deg,
            friction_deg,
            duration: 0.5,
            ..m
        };
        for bricks in [3, 5, 10] {
            for courses in 2..=6 {
                let name = format!("wall {bricks} x {courses}");
                cases.push((name, on(Masonry::wall(bricks, courses, 2.5))));
            }
        }
        for rows in [2, 3, 5, 8, 10] {
            let column = Masonry {
                layout: Layout::Grid { columns: 1, rows },
                width: 2.0,
                height: 0.2,
                ..Masonry::wall(1, 1, 2.5)
            };
            cases.push((format!("column of {rows}"), on(column)));
        }
    }
    let mut results: Vec<(String, Masonry, Result<f64, String>)> = cases
        .into_iter()
        .map(|(name, m)| {
            let r = worst(m);
            (name, m, r)
        })
        .collect();
    results.sort_by(|a, b| {
        let key = |r: &Result<f64, String>| r.as_ref().map_or(f64::INFINITY, |w| *w);
        key(&a.2).total_cmp(&key(&b.2))
    });
    for (name, m, r) in &results {
        let what = match r {
            Ok(w) => format!("{:.3}%", 100.0 * w),
            Err(e) => format!("stopped: {e}"),
        };
        println!("{name:>14} on {}/{}: {what}", m.tilt_deg, m.friction_deg);
    }
}
