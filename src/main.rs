//! The `dda` command: run, check and list scenes (docs/cli.md).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    cli::main()
}
