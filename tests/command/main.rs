//! The `dda` command as a user meets it: its contract (outputs, exit codes, the output
//! folder's rules, signals, hostile input), a fuzz of scene files, and the report in a
//! browser. One test binary, so that the suite links once for all of them.

mod cli;
mod fuzz_scenes;
mod report_browser;
