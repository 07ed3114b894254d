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
//! - `examples`: every scene of `examples/` run to its end, into `docs/examples.md`.

mod accuracy;
mod args;
mod examples;
mod robustness;
mod scaling;
mod sweep;
mod target;

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// The workspace root (xtask lives one level below it).
fn root() -> PathBuf {
    let here = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    here.parent().map(PathBuf::from).unwrap_or(here)
}

/// Project automation for dda-rs: the studies behind `docs/`.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask")]
struct Cli {
    #[command(subcommand)]
    task: Task,
}

#[derive(Debug, Subcommand)]
enum Task {
    /// The paper's section 4 cases x detectors, judged and drawn -> docs/robustness.md.
    Robustness,
    /// Time per step against blocks -> docs/scaling.md (or the columns as scene files).
    Scaling(scaling::Options),
    /// Error against wall time; the columns' penetration and energy -> docs/accuracy.md.
    Accuracy {
        /// Output folder (default: docs/).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// The paper's section 5 columns over detectors and r_tol.
    Sweep(sweep::Options),
    /// The 826-block column's speed over perturbed trajectories (medians, ms per OCI
    /// iteration; with --repeat R each trajectory's fastest of R runs).
    Target(target::Options),
    /// Every scene of examples/ run to its end, pictured -> docs/examples.md.
    Examples,
}

/// Bad options exit 2 (clap's own exit); a study that cannot be made (a trajectory
/// whose repeats differ, an output that cannot be written) exits 1, as `dda run` does
/// for a simulation that cannot go on.
fn main() -> ExitCode {
    let cli = Cli::parse();
    let root = root();
    let (name, result) = match cli.task {
        Task::Robustness => ("robustness", robustness::run(&root)),
        Task::Scaling(o) => ("scaling", scaling::run(&o.at(&root))),
        Task::Accuracy { out } => (
            "accuracy",
            accuracy::run(&out.unwrap_or_else(|| root.join("docs"))),
        ),
        Task::Sweep(o) => ("sweep", sweep::run(&root, &o)),
        Task::Target(o) => ("target", target::run(&root, &o)),
        Task::Examples => ("examples", examples::run(&root)),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask {name}: {e}");
            ExitCode::from(1)
        }
    }
}
