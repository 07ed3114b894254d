//! `cargo xtask`: project automation for dda-rs.
//!
//! - `robustness`: the paper's section 4 cases with every detector, judged and drawn, into
//!   `docs/robustness.md`.

mod robustness;

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
                "usage: cargo xtask <task>\n\ntasks:\n  robustness   section 4 cases x detectors -> docs/robustness.md"
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
        Some(other) => {
            eprintln!("xtask: unknown task `{other}` (try `cargo xtask help`)");
            ExitCode::from(2)
        }
    }
}
