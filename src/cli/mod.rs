//! Command-line interface: `dda run`, `dda resume`, `dda render`, `dda check`,
//! `dda scenes` (DESIGN 5.2).
//!
//! Exit codes: 0 success, 1 a simulation that cannot go on (its outputs are written up
//! to the last good state), 2 bad input (a message naming the file, key and line, and
//! nothing written).

mod render;
mod run;

use clap::{Parser, Subcommand};
use dda_core::{LineIndex, Model, Scene, SceneError};
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
    /// List the built-in scenes.
    Scenes,
}

/// Bad input: the message to print, exit code 2.
#[derive(Debug)]
pub struct BadInput(pub String);

impl From<SceneError> for BadInput {
    fn from(e: SceneError) -> Self {
        BadInput(e.to_string())
    }
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(args),
        Command::Resume(args) => run::resume(args),
        Command::Render { dir } => render::render(&dir),
        Command::Check { scene } => check(&scene),
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
                println!("{:<width$}  {}{mark}", b.name, b.description);
            }
            Ok(ExitCode::SUCCESS)
        }
    };
    match result {
        Ok(code) => code,
        Err(BadInput(msg)) => {
            eprintln!("error: {msg}");
            ExitCode::from(2)
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
pub fn resolve_scene(name: Option<&str>) -> Result<Resolved, BadInput> {
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
            BadInput(format!(
                "`{name}` is neither a scene file nor a built-in scene (`dda scenes` lists them)"
            ))
        })
}

/// Validates `scene`, naming `source` (the file or built-in) and, where `lines` knows
/// it, the line of the key in errors; prints its warnings on stderr the same way.
pub fn validate(scene: &Scene, source: &str, lines: Option<&LineIndex>) -> Result<Model, BadInput> {
    let at = |key: String, message: String| SceneError {
        file: source.to_string(),
        line: lines.and_then(|l| l.line(&key)),
        key,
        message,
    };
    let model = scene
        .validate()
        .map_err(|v| BadInput(at(v.key, v.message).to_string()))?;
    for w in &model.warnings {
        eprintln!("warning: {}", at(w.key.clone(), w.message.clone()));
    }
    Ok(model)
}

fn check(name: &str) -> Result<ExitCode, BadInput> {
    let Resolved { scene, lines } = resolve_scene(Some(name))?;
    let model = validate(&scene, name, lines.as_ref())?;
    let effects = dda_core::Effects::of(&model);
    println!(
        "{name}: ok: scene `{}`, {} blocks, detector {}, effects: {}",
        model.name,
        model.blocks.len(),
        model.params.detector,
        effects.names().join(", ")
    );
    Ok(ExitCode::SUCCESS)
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
