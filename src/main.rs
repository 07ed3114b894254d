//! The `dda` command: run, check and list scenes (DESIGN 5.2).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::main()
}
