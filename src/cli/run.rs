//! `dda run`: runs a scene and writes summary.json, history.csv and frames/*.svg.
//!
//! Outputs are written into a staging directory next to the target and moved into place
//! when the run ends, so a directory that exists is never half-written; a failed run
//! still moves its outputs (up to the last good state) into place, with the diagnosis in
//! summary.json.

use super::{BadInput, default_out, resolve_scene, validate};
use clap::Args;
use dda::report::{HISTORY_HEADER, frame_svg, frame_view, history_row};
use dda_core::{RunOptions, Simulation, Summary};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::{BufWriter, IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// Arguments of `dda run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scene file (.toml or .json) or built-in scene name; default: the jointed column.
    scene: Option<String>,
    /// Output directory (default: runs/<scene name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Contact detector: cover, type-1 or type-2 (overrides the scene).
    #[arg(long)]
    detector: Option<String>,
    /// Contact tolerance ratio r_tol: multiplies the contact tolerance and the largest
    /// step displacement together (paper eq. 15).
    #[arg(long)]
    rtol: Option<f64>,
    /// No progress bar and no report on the terminal.
    #[arg(long)]
    quiet: bool,
}

/// Runs the command.
pub fn run(args: RunArgs) -> Result<ExitCode, BadInput> {
    let source = args
        .scene
        .clone()
        .unwrap_or_else(|| dda_bench::DEFAULT_BUILTIN.to_string());
    let mut scene = resolve_scene(args.scene.as_deref())?;
    if let Some(d) = &args.detector {
        scene.analysis.detector = d.clone();
    }
    if let Some(r) = args.rtol {
        if !(r.is_finite() && r > 0.0) {
            return Err(BadInput(format!(
                "--rtol must be a positive number, got {r}"
            )));
        }
        scene.scale_tolerances(r);
    }
    let model = validate(&scene, &source)?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&scene));
    let staging = staging_dir(&out);
    let io =
        |e: std::io::Error, what: &Path| BadInput(format!("cannot write {}: {e}", what.display()));
    if staging.exists() {
        std::fs::remove_dir_all(&staging).map_err(|e| io(e, &staging))?;
    }
    std::fs::create_dir_all(staging.join("frames")).map_err(|e| io(e, &staging))?;

    let mut sim = Simulation::new(model, RunOptions::default());
    let p = sim.model().params.clone();
    if !args.quiet {
        eprintln!(
            "scene `{}`: {} blocks ({} unknowns), detector {}, d_tol {} m, d_max {} m",
            sim.model().name,
            sim.blocks().len(),
            sim.unknowns(),
            sim.detector_name(),
            p.d_tol,
            p.d_max
        );
        eprintln!("effects: {}", sim.effects().names().join(", "));
    }
    let view = frame_view(&sim);
    let mut frame = 0u32;
    let write_frame = |sim: &Simulation, frame: u32| -> Result<(), BadInput> {
        let path = staging.join("frames").join(format!("frame-{frame:04}.svg"));
        std::fs::write(&path, frame_svg(sim, &view)).map_err(|e| io(e, &path))
    };
    if p.frames > 0 {
        write_frame(&sim, 0)?;
    }
    let history_path = staging.join("history.csv");
    let file = std::fs::File::create(&history_path).map_err(|e| io(e, &history_path))?;
    let mut history = BufWriter::new(file);
    writeln!(history, "{HISTORY_HEADER}").map_err(|e| io(e, &history_path))?;

    let bar = if !args.quiet && std::io::stderr().is_terminal() {
        let bar = ProgressBar::new(1000);
        bar.set_style(
            ProgressStyle::with_template(
                "{elapsed_precise} [{bar:40}] t = {msg} s  ({per_sec}, eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        Some(bar)
    } else {
        None
    };

    let mut io_error = None;
    let result = sim.run(|sim, rec| {
        if io_error.is_some() {
            return;
        }
        if let Err(e) = writeln!(history, "{}", history_row(rec)) {
            io_error = Some(io(e, &history_path));
        }
        if p.frames > 0 {
            let next = (frame + 1) as f64 * p.duration / p.frames as f64;
            if sim.time() >= next * (1.0 - 1e-9) {
                frame += 1;
                if let Err(e) = write_frame(sim, frame) {
                    io_error = Some(e);
                }
            }
        }
        if let Some(bar) = &bar {
            bar.set_position((1000.0 * sim.time() / p.duration) as u64);
            bar.set_message(format!("{:.4}", sim.time()));
        }
    });
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    if let Some(e) = io_error {
        return Err(e);
    }
    history.flush().map_err(|e| io(e, &history_path))?;
    let error = result.as_ref().err().map(|e| e.to_string());
    if error.is_some() && p.frames > 0 {
        // The last good state, as the final frame.
        write_frame(&sim, frame + 1)?;
    }
    let summary = Summary::of(&sim, error.clone());
    let summary_path = staging.join("summary.json");
    let json = serde_json::to_string_pretty(&summary)
        .map_err(|e| BadInput(format!("cannot serialise the summary: {e}")))?;
    std::fs::write(&summary_path, json + "\n").map_err(|e| io(e, &summary_path))?;
    if out.exists() {
        std::fs::remove_dir_all(&out).map_err(|e| io(e, &out))?;
    }
    std::fs::rename(&staging, &out).map_err(|e| io(e, &out))?;

    if !args.quiet {
        let s = &summary;
        eprintln!(
            "{} s simulated in {} steps ({} OCI iterations, {} dt cuts); \
             {:.3} s wall: detection {:.3} s, assembly {:.3} s, solve {:.3} s; \
             max penetration {:.3e} m",
            s.time_simulated,
            s.steps,
            s.oci_iterations,
            s.time_step_cuts,
            s.seconds.total,
            s.seconds.contact_detection,
            s.seconds.assembly,
            s.seconds.solve,
            s.max_penetration
        );
        eprintln!("wrote {}", out.display());
    }
    match error {
        Some(e) => {
            eprintln!("error: the simulation cannot go on: {e}");
            Ok(ExitCode::from(1))
        }
        None => Ok(ExitCode::SUCCESS),
    }
}

/// A sibling of `out` to write into before moving the result into place.
fn staging_dir(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    out.with_file_name(format!(".{name}.partial"))
}
