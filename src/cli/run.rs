//! `dda run` and `dda resume`: run a scene, writing summary.json, history.csv,
//! frames.jsonl, frames/*.svg, report.html and (on request, and always on failure)
//! checkpoint.bin.
//!
//! A run works in a staging directory next to its output directory (`.NAME.partial`)
//! and moves it into place when it ends, so an output directory that exists is never
//! half-written. A run with `--checkpoint-every N` saves its full state there every N
//! steps; if it is killed, `dda resume OUT` continues from the last checkpoint, cutting
//! history.csv and frames.jsonl back to where the checkpoint was taken, and ends exactly
//! as the uninterrupted run would have. A failed run moves its outputs into place with
//! the diagnosis in summary.json and report.html and the last good state in
//! checkpoint.bin.

use super::render::{render_outputs, write_new};
use super::{BadInput, Resolved, default_out, resolve_scene, validate};
use clap::Args;
use dda::report::{Frame, HISTORY_HEADER, frame_resolution, frame_view, history_row};
use dda_core::{Checkpoint, OutputMarks, RunOptions, Scene, Simulation, Summary};
use indicatif::{ProgressBar, ProgressStyle};
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The checkpoint file's name in a run directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

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
    /// Save the full state every N steps, to continue with `dda resume` if the run is
    /// interrupted.
    #[arg(long, value_name = "N")]
    checkpoint_every: Option<u64>,
    /// No progress bar and no report on the terminal.
    #[arg(long)]
    quiet: bool,
}

/// Arguments of `dda resume`.
#[derive(Debug, Args)]
pub struct ResumeArgs {
    /// The output directory of the interrupted run (or its `.NAME.partial` staging
    /// directory).
    dir: PathBuf,
    /// No progress bar and no report on the terminal.
    #[arg(long)]
    quiet: bool,
}

/// A run under way: its scene, state, directories and output files.
struct Job {
    scene: Scene,
    sim: Simulation,
    work: PathBuf,
    out: PathBuf,
    marks: OutputMarks,
    history: BufWriter<File>,
    frames: BufWriter<File>,
    animation_frames: u64,
    resolution: f64,
    quiet: bool,
}

fn io_err(e: std::io::Error, what: &Path) -> BadInput {
    BadInput(format!("cannot write {}: {e}", what.display()))
}

/// Runs `dda run`.
pub fn run(args: RunArgs) -> Result<ExitCode, BadInput> {
    let source = args
        .scene
        .clone()
        .unwrap_or_else(|| dda_bench::DEFAULT_BUILTIN.to_string());
    let Resolved { mut scene, lines } = resolve_scene(args.scene.as_deref())?;
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
    if args.checkpoint_every == Some(0) {
        return Err(BadInput("--checkpoint-every must be at least 1".into()));
    }
    let model = validate(&scene, &source, lines.as_ref())?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&scene));
    let work = staging_dir(&out);
    if work.join(CHECKPOINT_FILE).exists() {
        return Err(BadInput(format!(
            "{} holds an interrupted run of this output: `dda resume {}` continues it; \
             delete {} to start afresh",
            work.display(),
            out.display(),
            work.display()
        )));
    }
    if work.exists() {
        std::fs::remove_dir_all(&work).map_err(|e| io_err(e, &work))?;
    }
    std::fs::create_dir_all(&work).map_err(|e| io_err(e, &work))?;
    let scene_json = serde_json::to_string_pretty(&scene)
        .map_err(|e| BadInput(format!("cannot serialise the scene: {e}")))?;
    write_new(&work.join("scene.json"), &(scene_json + "\n"))?;

    let sim = Simulation::new(model, RunOptions::default());
    let history_path = work.join("history.csv");
    let frames_path = work.join("frames.jsonl");
    let history =
        BufWriter::new(File::create(&history_path).map_err(|e| io_err(e, &history_path))?);
    let frames = BufWriter::new(File::create(&frames_path).map_err(|e| io_err(e, &frames_path))?);
    let mut job = Job::new(scene, sim, work, out, history, frames, args.quiet);
    job.marks.checkpoint_every = args.checkpoint_every.unwrap_or(0);
    job.write_history(HISTORY_HEADER)?;
    job.write_frame(job.sim.model().params.frames > 0)?;
    job.announce("scene");
    job.drive()
}

/// Runs `dda resume`.
pub fn resume(args: ResumeArgs) -> Result<ExitCode, BadInput> {
    let (work, out) = work_and_out(&args.dir);
    let path = work.join(CHECKPOINT_FILE);
    if !path.exists() {
        let done = out.join("summary.json").exists();
        return Err(BadInput(if done {
            format!(
                "{} is a finished run (see its summary.json): nothing to resume",
                out.display()
            )
        } else {
            format!(
                "no checkpoint to resume: {} does not exist (run with --checkpoint-every N)",
                path.display()
            )
        }));
    }
    let ck = Checkpoint::load(&path).map_err(|e| BadInput(e.to_string()))?;
    let scene = ck.scene(&path).map_err(|e| BadInput(e.to_string()))?;
    let model = validate(&scene, &path.display().to_string(), None)?;
    let marks = ck.outputs.clone();
    let sim = ck
        .resume(model, RunOptions::default(), &path)
        .map_err(|e| BadInput(e.to_string()))?;
    let history = reopen(&work.join("history.csv"), marks.history_bytes)?;
    let frames = reopen(&work.join("frames.jsonl"), marks.frames_bytes)?;
    let mut job = Job::new(scene, sim, work, out, history, frames, args.quiet);
    job.marks = marks;
    job.announce("resuming");
    job.drive()
}

/// Opens `path` for appending after cutting it back to `len` bytes.
fn reopen(path: &Path, len: u64) -> Result<BufWriter<File>, BadInput> {
    let bad = |e: std::io::Error| BadInput(format!("cannot resume {}: {e}", path.display()));
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(bad)?;
    let have = f.metadata().map_err(bad)?.len();
    if have < len {
        return Err(BadInput(format!(
            "cannot resume: {} has {have} bytes, the checkpoint was taken after {len}",
            path.display()
        )));
    }
    f.set_len(len).map_err(bad)?;
    f.seek(SeekFrom::End(0)).map_err(bad)?;
    Ok(BufWriter::new(f))
}

/// The staging (work) directory and the output directory named by `dir`, which may be
/// either.
fn work_and_out(dir: &Path) -> (PathBuf, PathBuf) {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    match name
        .strip_prefix('.')
        .and_then(|n| n.strip_suffix(".partial"))
    {
        Some(base) => (dir.to_path_buf(), dir.with_file_name(base)),
        None => (staging_dir(dir), dir.to_path_buf()),
    }
}

/// Most coordinates the animation holds over all its frames; fewer frames for larger
/// models keep report.html to a few megabytes.
const ANIMATION_BUDGET: usize = 500_000;

impl Job {
    fn new(
        scene: Scene,
        sim: Simulation,
        work: PathBuf,
        out: PathBuf,
        history: BufWriter<File>,
        frames: BufWriter<File>,
        quiet: bool,
    ) -> Self {
        let vertices: usize = sim.blocks().iter().map(|b| b.polygon.len()).sum();
        let animation_frames = (ANIMATION_BUDGET / (2 * vertices).max(1)).clamp(20, 200) as u64;
        let resolution = frame_resolution(&frame_view(sim.model()));
        Job {
            scene,
            sim,
            work,
            out,
            marks: OutputMarks {
                animation_next: 1,
                svg_next: 1,
                ..OutputMarks::default()
            },
            history,
            frames,
            animation_frames,
            resolution,
            quiet,
        }
    }

    fn announce(&self, what: &str) {
        if self.quiet {
            return;
        }
        let sim = &self.sim;
        let p = &sim.model().params;
        eprintln!(
            "{what} `{}` at t = {} s: {} blocks ({} unknowns), detector {}, d_tol {} m, d_max {} m",
            sim.model().name,
            sim.time(),
            sim.blocks().len(),
            sim.unknowns(),
            sim.detector_name(),
            p.d_tol,
            p.d_max
        );
        eprintln!("effects: {}", sim.effects().names().join(", "));
        if self.marks.checkpoint_every > 0 {
            eprintln!(
                "checkpoint every {} steps: {} (continue with `dda resume {}`)",
                self.marks.checkpoint_every,
                self.work.join(CHECKPOINT_FILE).display(),
                self.out.display()
            );
        }
    }

    fn write_history(&mut self, line: &str) -> Result<(), BadInput> {
        let path = self.work.join("history.csv");
        writeln!(self.history, "{line}").map_err(|e| io_err(e, &path))?;
        self.marks.history_bytes += line.len() as u64 + 1;
        Ok(())
    }

    /// Appends the current state to frames.jsonl.
    fn write_frame(&mut self, svg: bool) -> Result<(), BadInput> {
        let path = self.work.join("frames.jsonl");
        let frame = Frame::of(&self.sim, svg, self.resolution);
        let line = serde_json::to_string(&frame)
            .map_err(|e| BadInput(format!("cannot serialise a frame: {e}")))?;
        writeln!(self.frames, "{line}").map_err(|e| io_err(e, &path))?;
        self.marks.frames_bytes += line.len() as u64 + 1;
        Ok(())
    }

    /// Records a frame if the step crossed an instant of the animation grid or of the
    /// SVG-frame grid.
    fn sample_frames(&mut self) -> Result<(), BadInput> {
        let p = &self.sim.model().params;
        let (t, duration, svg_frames) = (self.sim.time(), p.duration, u64::from(p.frames));
        let due = |next: u64, n: u64| {
            n > 0 && next <= n && t >= next as f64 * duration / n as f64 * (1.0 - 1e-9)
        };
        let animation = due(self.marks.animation_next, self.animation_frames);
        let svg = due(self.marks.svg_next, svg_frames);
        while due(self.marks.animation_next, self.animation_frames) {
            self.marks.animation_next += 1;
        }
        while due(self.marks.svg_next, svg_frames) {
            self.marks.svg_next += 1;
        }
        if animation || svg {
            self.write_frame(svg)?;
        }
        Ok(())
    }

    /// Flushes history.csv and frames.jsonl, and with `sync` forces them to disk.
    fn flush(&mut self, sync: bool) -> Result<(), BadInput> {
        for (w, name) in [
            (&mut self.history, "history.csv"),
            (&mut self.frames, "frames.jsonl"),
        ] {
            let path = self.work.join(name);
            w.flush().map_err(|e| io_err(e, &path))?;
            if sync {
                w.get_ref().sync_data().map_err(|e| io_err(e, &path))?;
            }
        }
        Ok(())
    }

    /// Flushes the output files to disk and saves the checkpoint atomically.
    fn checkpoint(&mut self) -> Result<(), BadInput> {
        self.flush(true)?;
        let ck = Checkpoint::of(&self.sim, &self.scene, self.marks.clone())
            .map_err(|e| BadInput(format!("cannot build the checkpoint: {e}")))?;
        ck.save(&self.work.join(CHECKPOINT_FILE))
            .map_err(|e| BadInput(e.to_string()))
    }

    /// Steps to the end (or a failure), then writes the summary and the report and moves
    /// the outputs into place.
    fn drive(mut self) -> Result<ExitCode, BadInput> {
        let bar = if !self.quiet && std::io::stderr().is_terminal() {
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
        let duration = self.sim.model().params.duration;
        let mut error = None;
        while !self.sim.finished() {
            match self.sim.step() {
                Ok(rec) => {
                    self.write_history(&history_row(&rec))?;
                    self.sample_frames()?;
                    let every = self.marks.checkpoint_every;
                    if every > 0 && rec.step % every == 0 && !self.sim.finished() {
                        self.checkpoint()?;
                    }
                    if let Some(bar) = &bar {
                        bar.set_position((1000.0 * self.sim.time() / duration) as u64);
                        bar.set_message(format!("{:.4}", self.sim.time()));
                    }
                }
                Err(e) => {
                    error = Some(e.to_string());
                    break;
                }
            }
        }
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        let checkpoint_path = self.work.join(CHECKPOINT_FILE);
        if error.is_some() {
            // The last good state: as the final frame, and as a checkpoint.
            self.write_frame(true)?;
            self.checkpoint()?;
        } else {
            self.flush(false)?;
            if checkpoint_path.exists() {
                std::fs::remove_file(&checkpoint_path).map_err(|e| io_err(e, &checkpoint_path))?;
            }
        }
        let summary = Summary::of(&self.sim, error.clone());
        let json = serde_json::to_string_pretty(&summary)
            .map_err(|e| BadInput(format!("cannot serialise the summary: {e}")))?;
        write_new(&self.work.join("summary.json"), &(json + "\n"))?;
        render_outputs(&self.work, &self.scene, self.sim.model(), &summary)?;
        if self.out.exists() {
            std::fs::remove_dir_all(&self.out).map_err(|e| io_err(e, &self.out))?;
        }
        std::fs::rename(&self.work, &self.out).map_err(|e| io_err(e, &self.out))?;

        if !self.quiet {
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
            eprintln!("wrote {}", self.out.display());
        }
        if summary.max_penetration > summary.contact_tolerance {
            // The paper's working rule (section 2.6): contacts are found within d_tol, so a
            // deeper penetration means the penalty is too soft for the tolerance.
            eprintln!(
                "warning: the largest penetration, {:.3e} m, exceeded the contact tolerance \
                 {:.3e} m: `analysis.normal_penalty` ({:.3e} N/m) is too soft for it \
                 (paper section 2.6); raise it, or `analysis.contact_tolerance`",
                summary.max_penetration,
                summary.contact_tolerance,
                self.sim.model().params.normal_penalty
            );
        }
        match error {
            Some(e) => {
                eprintln!("error: the simulation cannot go on: {e}");
                if let Some(d) = &summary.failure
                    && !d.blocks.is_empty()
                {
                    eprintln!("  blocks involved: {}", d.blocks.join(", "));
                }
                eprintln!(
                    "  last good state: {} (diagnosis in {})",
                    self.out.join(CHECKPOINT_FILE).display(),
                    self.out.join("summary.json").display()
                );
                Ok(ExitCode::from(1))
            }
            None => Ok(ExitCode::SUCCESS),
        }
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
