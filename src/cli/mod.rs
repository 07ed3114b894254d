//! Command-line interface: `dda run`, `dda resume`, `dda render`, `dda check`,
//! `dda build`, `dda scenes`.
//!
//! Exit codes (`docs/cli.md`):
//! - 0: done;
//! - 1: the run did not reach a good end: the simulation could not go on or broke
//!   physics (outputs written up to the last good state, with the diagnosis),
//!   `--max-steps` was reached, the factor would not fit in memory, or an output could
//!   not be written (the message names the path and the system's error; no temporary
//!   file is left);
//! - 2: bad input: a scene, option or checkpoint that cannot be used, or an output
//!   folder that is refused or in use (the message names the file, key and line, or the
//!   folder; nothing is written);
//! - 129, 130, 143: interrupted by SIGHUP, SIGINT or SIGTERM at the end of a step, with
//!   a checkpoint that `dda resume` continues.

mod outdir;
mod render;
mod run;
mod signals;

use clap::{Parser, Subcommand};
use dda_core::{LineIndex, Model, Scene, SceneError};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Discontinuous Deformation Analysis of 2D rock blocks.
#[derive(Debug, Parser)]
#[command(name = "dda", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run a scene file (.toml or .json) or a built-in scene (default: the jointed column).
    Run(run::RunArgs),
    /// Continue an interrupted run from its last checkpoint (see `run --checkpoint-every`).
    Resume(run::ResumeArgs),
    /// Redraw the frames and report.html of a finished run without simulating again.
    Render {
        /// The run's output directory.
        dir: PathBuf,
    },
    /// Validate a scene file without running it.
    Check {
        /// Scene file or built-in name.
        scene: String,
    },
    /// Write a scene with its regions cut into blocks: every block listed (JSON).
    Build {
        /// Scene file or built-in name.
        scene: String,
        /// File to write (a new one: never replaced); default: standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// List the built-in scenes.
    Scenes,
}

/// Why a command could not do its work: the message to print and the exit code.
#[derive(Debug)]
pub enum Failure {
    /// Bad input (scene, option, checkpoint, a refused output folder): exit 2, nothing
    /// written.
    Input(String),
    /// An output could not be written: exit 1.
    Output(String),
}

impl From<SceneError> for Failure {
    fn from(e: SceneError) -> Self {
        Failure::Input(e.to_string())
    }
}

/// Bad input with message `msg`.
pub fn bad(msg: impl Into<String>) -> Failure {
    Failure::Input(msg.into())
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args),
        Command::Resume(args) => run::resume(args),
        Command::Render { dir } => render::render(&dir),
        Command::Check { scene } => check(&scene),
        Command::Build { scene, out } => build(&scene, out.as_deref()),
        Command::Scenes => {
            let width = dda_bench::BUILTINS
                .iter()
                .map(|b| b.name.len())
                .max()
                .unwrap_or(0);
            for b in dda_bench::BUILTINS {
                let mark = if b.name == dda_bench::DEFAULT_BUILTIN {
                    " [default]"
                } else {
                    ""
                };
                say(format_args!("{:<width$}  {}{mark}", b.name, b.description));
            }
            Ok(ExitCode::SUCCESS)
        }
    };
    match result {
        Ok(code) => code,
        Err(Failure::Input(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
        }
        Err(Failure::Output(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(1)
        }
    }
}

/// A scene as read: the scene, and where its keys are in its file (None for a built-in).
pub struct Resolved {
    /// The scene as written, unvalidated.
    pub scene: Scene,
    /// The lines of its keys, to name them in errors and warnings found later.
    pub lines: Option<LineIndex>,
}

/// Reads a scene: a file if `name` is a path to one (or ends in .toml/.json), else a
/// built-in scene.
pub fn resolve_scene(name: Option<&str>) -> Result<Resolved, Failure> {
    let name = name.unwrap_or(dda_bench::DEFAULT_BUILTIN);
    let path = Path::new(name);
    let looks_like_file = path.exists()
        || matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("toml" | "json")
        );
    if looks_like_file {
        let (scene, _, lines) = Scene::load_indexed(path)?;
        return Ok(Resolved {
            scene,
            lines: Some(lines),
        });
    }
    dda_bench::builtin(name)
        .map(|scene| Resolved { scene, lines: None })
        .ok_or_else(|| {
            bad(format!(
                "`{name}` is neither a scene file nor a built-in scene (`dda scenes` lists them)"
            ))
        })
}

/// Validates `scene`, naming `source` (the file or built-in) and, where `lines` knows
/// it, the line of the key in errors; prints its warnings on stderr the same way.
pub fn validate(scene: &Scene, source: &str, lines: Option<&LineIndex>) -> Result<Model, Failure> {
    build_scene(scene, source, lines).map(|(_, model)| model)
}

/// [`validate`], with the scene as run: its regions cut into blocks (`Scene::build`).
pub fn build_scene<'s>(
    scene: &'s Scene,
    source: &str,
    lines: Option<&LineIndex>,
) -> Result<(Cow<'s, Scene>, Model), Failure> {
    let at = |key: String, message: String| SceneError {
        file: source.to_string(),
        line: lines.and_then(|l| l.line(&key)),
        key,
        message,
    };
    let (explicit, model) = scene
        .build()
        .map_err(|v| bad(at(v.key, v.message).to_string()))?;
    for w in &model.warnings {
        eprintln!("warning: {}", at(w.key.clone(), w.message.clone()));
    }
    Ok((explicit, model))
}

fn check(name: &str) -> Result<ExitCode, Failure> {
    let Resolved { scene, lines } = resolve_scene(Some(name))?;
    let model = validate(&scene, name, lines.as_ref())?;
    let effects = dda_core::Effects::of(&model);
    let free = model.blocks.iter().filter(|b| !b.fixed).count();
    let iterative = dda_core::iterative::solves_iteratively(model.params.solver, free);
    say(format_args!(
        "{name}: ok: scene `{}`, {} blocks, detector {}, effects: {}, solve: {}{}",
        model.name,
        model.blocks.len(),
        model.params.detector,
        effects.names().join(", "),
        if iterative { "iterative" } else { "direct" },
        model
            .params
            .stepping_rule()
            .map_or(String::new(), |r| format!(", integration: {}", r.name()))
    ));
    Ok(ExitCode::SUCCESS)
}

/// `dda build`: validates the scene (errors as `dda check` gives them), cuts its regions
/// into blocks and writes the explicit scene as JSON to `out` (a new file) or stdout.
fn build(name: &str, out: Option<&Path>) -> Result<ExitCode, Failure> {
    let Resolved { scene, lines } = resolve_scene(Some(name))?;
    let (explicit, _) = build_scene(&scene, name, lines.as_ref())?;
    let text = serde_json::to_string_pretty(&explicit)
        .map_err(|e| Failure::Output(format!("cannot serialise the scene: {e}")))?
        + "\n";
    match out {
        None => {
            use std::io::Write;
            let _ = std::io::stdout().lock().write_all(text.as_bytes());
        }
        Some(path) => {
            if path.exists() {
                return Err(bad(format!(
                    "{}: exists; `dda build` never replaces a file (name a new one)",
                    path.display()
                )));
            }
            render::write_new(path, &text)?;
            eprintln!(
                "wrote {} ({} blocks)",
                path.display(),
                explicit.blocks.len()
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes a line to standard output. A reader that has gone (`dda scenes | head`) is not
/// an error of ours: the rest is dropped quietly instead of panicking as `println!` does.
fn say(line: std::fmt::Arguments) {
    use std::io::Write;
    let _ = writeln!(std::io::stdout().lock(), "{line}");
}

/// The default output directory of a scene: `runs/` and its name, with characters other
/// than letters, digits, '-', '_' and '.' replaced by '_'.
pub fn default_out(scene: &Scene) -> PathBuf {
    let safe: String = scene
        .name
        .chars()
        .map(|c| {
            if c.is_alphanumeric() || c == '-' || c == '_' || c == '.' {
                c
            } else {
                '_'
            }
        })
        .collect();
    // No hidden or parent directory (staging directories start with '.').
    let safe = match safe.strip_prefix('.') {
        Some(rest) => format!("_{rest}"),
        None => safe,
    };
    Path::new("runs").join(safe)
}
