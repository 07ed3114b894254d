//! `cargo xtask`: project automation for dda-rs.
//!
//! - `robustness`: the paper's section 4 cases with every detector, judged and drawn, into
//!   `docs/robustness.md`.
//! - `sweep`: the paper's section 5 columns over detectors and r_tol: steps, OCI cycles,
//!   seconds and accuracy as CSV, JSON, a table and plots.
//! - `scaling`: time per step against the number of blocks (columns up to 100k blocks),
//!   into `docs/scaling.md`.
//! - `accuracy`: error against wall time on problems with a closed-form answer, and the
//!   columns' penetration and energy against time, into `docs/accuracy.md`.
//! - `target`: the 826-block column's speed targets over an ensemble of trajectories.

mod accuracy;
mod args;
mod robustness;
mod scaling;
mod sweep;
mod target;

use std::path::PathBuf;
use std::process::ExitCode;

/// The workspace root (xtask lives one level below it).
fn root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(PathBuf::from).unwrap_or(here)
}

fn main() -> ExitCode {
    let task = std::env::args().nth(1);
    match task.as_deref() {
        None | Some("help" | "--help" | "-h") => {
            println!(
                "usage: cargo xtask <task>\n\ntasks:\n  robustness   section 4 cases x detectors -> docs/robustness.md\n  scaling [--blocks 826,3300,10000,30000,100000] [--duration 0.1] [--out DIR] [--write-scenes DIR]   time per step against blocks -> docs/scaling.md (or the columns as scene files)\n  accuracy [--out DIR]   error against wall time; the columns' penetration and energy -> docs/accuracy.md\n  sweep [--models 20,93,229,826] [--detectors cover,type-1,type-2] [--rtol 1,2,4,6,8,10] [--jobs N] [--max-steps N] [--out DIR]\n  target [--runs 5] [--repeat 1] [--model 826] [--out DIR]   the 5.2b column's speed targets over perturbed trajectories (medians, ms per OCI iteration; with --repeat R each trajectory's fastest of R runs)"
            );
            ExitCode::SUCCESS
        }
        Some("robustness") => match robustness::run(&root()) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("xtask robustness: {e}");
                ExitCode::FAILURE
            }
        },
        Some("accuracy") => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            let out = match args.as_slice() {
                [] => root().join("docs"),
                [flag, dir] if flag == "--out" => PathBuf::from(dir),
                _ => {
                    eprintln!("xtask accuracy: usage: cargo xtask accuracy [--out DIR]");
                    return ExitCode::from(2);
                }
            };
            match accuracy::run(&out) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("xtask accuracy: {e}");
                    ExitCode::FAILURE
                }
            }
        }
        Some("scaling") => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            match scaling::parse(&args, &root()).and_then(|o| scaling::run(&o)) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("xtask scaling: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Some("sweep") => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            let result = sweep::parse(&args).and_then(|o| sweep::run(&root(), &o));
            match result {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("xtask sweep: {e}");
                    ExitCode::from(2)
                }
            }
        }
        Some("target") => {
            let args: Vec<String> = std::env::args().skip(2).collect();
            // Bad options exit 2; a measurement that cannot be made or repeated (a
            // trajectory whose repeats differ, an output that cannot be written) exits 1,
            // as `dda run` does for a simulation that cannot go on.
            match target::parse(&args) {
                Err(e) => {
                    eprintln!("xtask target: {e}");
                    ExitCode::from(2)
                }
                Ok(o) => match target::run(&root(), &o) {
                    Ok(()) => ExitCode::SUCCESS,
                    Err(e) => {
                        eprintln!("xtask target: {e}");
                        ExitCode::from(1)
                    }
                },
            }
        }
        Some(other) => {
            eprintln!("xtask: unknown task `{other}` (try `cargo xtask help`)");
            ExitCode::from(2)
        }
    }
}
