//! `dda run` and `dda resume`: run a scene, writing summary.json, history.csv,
//! frames.jsonl, frames/*.svg, report.html and (on request, on interruption, and
//! always when the run does not reach its end) checkpoint.bin.
//!
//! A run works in a staging folder beside its output folder (`.NAME.partial`, see
//! `outdir`) and moves it into place when it ends, so an output folder that exists is
//! never half-written, and a run never deletes or overwrites a file it did not write.
//! A run with `--checkpoint-every N` saves its full state there every N steps, and
//! every run saves it when a signal interrupts it; `dda resume OUT` continues from the
//! last checkpoint, cutting history.csv and frames.jsonl back to where it was taken,
//! and ends exactly as the uninterrupted run would have. A run that does not reach its
//! end (failure, broken physics, `--max-steps`) moves its outputs into place with the
//! diagnosis in summary.json and report.html and the last good state in
//! checkpoint.bin.

use super::outdir::{Staging, check_out, output_error, staging_dir, work_and_out};
use super::render::{render_outputs, write_new};
use super::signals::{self, Signals};
use super::{Failure, Resolved, bad, build_scene, default_out, resolve_scene, validate};
use clap::Args;
use dda::report::{
    BOLTS_HEADER, Frame, HISTORY_HEADER, MEASUREMENTS_HEADER, bolt_rows, counted, frame_resolution,
    frame_view, history_row, measurement_rows, shown,
};
use dda_core::{
    Checkpoint, HeldBy, RunOptions, Scene, SettleProgress, SettlingSummary, Simulation, StepRecord,
    Summary,
};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::io::{BufWriter, IsTerminal, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The checkpoint file's name in a run directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.bin";

/// How far a run's output files had got when a checkpoint was taken, so that a resume
/// cuts them back to that point and appends exactly what the run would have; kept in
/// the checkpoint as the command's own record (JSON).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct OutputMarks {
    /// Bytes of history.csv written.
    history_bytes: u64,
    /// Bytes of frames.jsonl written.
    frames_bytes: u64,
    /// The next instant of the animation grid to record in frames.jsonl.
    animation_next: u64,
    /// The next instant of the SVG-frame grid (the scene's `frames`) to record.
    svg_next: u64,
    /// Steps between checkpoints (0: only at the end or on failure).
    checkpoint_every: u64,
    /// Whether the run goes on through violations of physics (`--keep-going`).
    keep_going: bool,
    /// Bytes of measurements.csv written (a scene with measured points).
    #[serde(default)]
    measurements_bytes: u64,
    /// Bytes of bolts.csv written (a scene with bolts).
    #[serde(default)]
    bolts_bytes: u64,
    /// The scene file or built-in scene the run was made from, as named.
    #[serde(default)]
    source: Option<String>,
    /// What the settling did, once it has settled (summary.json's `settling`; kept here
    /// so that a resumed run's summary says it too).
    #[serde(default)]
    settling: Option<SettlingSummary>,
    /// The steps each block held dt below the step asked for (summary.json's
    /// `held_by`; kept here so that a resumed run counts them all).
    #[serde(default)]
    held: std::collections::BTreeMap<String, u64>,
}

/// Options of `run` and `resume` that bound or relax a run.
#[derive(Debug, Args)]
pub struct Limits {
    /// Go on through steps that break physics (penetration beyond d_tol, energy
    /// created), recording them in summary.json's `warnings`; without it such a step
    /// stops the run (exit 1) with the last good state.
    #[arg(long)]
    keep_going: bool,
    /// Stop after this many steps of this process (exit 1, the state kept for `dda resume`).
    #[arg(long, value_name = "N")]
    max_steps: Option<u64>,
    /// Most memory the global matrix's factor may take, in bytes or with a suffix K, M
    /// or G (default: the memory available when the run starts).
    #[arg(long, value_name = "SIZE", value_parser = parse_size)]
    max_memory: Option<u64>,
}

/// Arguments of `dda run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Scene file (.toml or .json) or built-in scene name; default: the jointed column.
    scene: Option<String>,
    /// Output folder (default: runs/<scene name>): a new folder, or one an earlier
    /// `dda run` wrote, which is replaced.
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
    /// killed.
    #[arg(long, value_name = "N")]
    checkpoint_every: Option<u64>,
    /// No progress bar and no report on the terminal.
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    limits: Limits,
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
    #[command(flatten)]
    limits: Limits,
}

/// A byte count: digits with an optional suffix K, M or G (powers of 1024).
fn parse_size(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let (digits, unit) = match t.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&t[..i], c.to_ascii_uppercase()),
        _ => (t, 'B'),
    };
    let scale: u64 = match unit {
        'B' => 1,
        'K' => 1 << 10,
        'M' => 1 << 20,
        'G' => 1 << 30,
        _ => return Err(format!("`{s}`: use a number of bytes, or K, M or G")),
    };
    digits
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(scale))
        .filter(|&n| n > 0)
        .ok_or_else(|| format!("`{s}`: use a positive number of bytes, or K, M or G"))
}

/// Memory available now, from /proc/meminfo (None where it cannot be read).
fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

impl Limits {
    /// The run options these limits ask for.
    fn options(&self, keep_going: bool) -> RunOptions {
        RunOptions {
            stop_on_violation: !keep_going,
            max_memory: self.max_memory.or_else(available_memory),
            ..RunOptions::default()
        }
    }
}

/// A run under way: its scene, state, directories and output files.
struct Job {
    scene: Scene,
    sim: Simulation,
    staging: Staging,
    work: PathBuf,
    out: PathBuf,
    max_steps: Option<u64>,
    signals: Signals,
    marks: OutputMarks,
    history: BufWriter<File>,
    frames: BufWriter<File>,
    /// measurements.csv and bolts.csv ([`TABLES`]), when the scene has measured points
    /// or bolts.
    tables: [Option<BufWriter<File>>; 2],
    animation_frames: u64,
    resolution: f64,
    quiet: bool,
}

/// The per-step tables a scene may call for, in the order of [`Job::tables`]:
/// measurements.csv (measured points) and bolts.csv (bolts).
const TABLES: [&str; 2] = ["measurements.csv", "bolts.csv"];

/// Wall time between the progress lines of a run whose standard error is not a
/// terminal (in place of the progress bar): a batch job's log says how far a long run
/// has come.
const PROGRESS_EVERY: std::time::Duration = std::time::Duration::from_secs(30);

/// The progress bar of the run's steps: simulated time against the duration, and the
/// wall time left at the pace so far. (Its position counts thousandths of the duration:
/// a rate of them would mean nothing to a user.)
fn run_style() -> ProgressStyle {
    ProgressStyle::with_template("{elapsed_precise} [{bar:40}] {msg}  (eta {eta})")
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ")
}

/// How far the settling has come, as the terminal shows it: static steps, their size
/// against the settling's own, and how far the motion is from steady (the settling
/// ends when it changes by 1e-5 of its scale from one step to the next).
fn settle_progress(p: &SettleProgress) -> String {
    // A round's first step has no step before it to compare with.
    let change = if p.change.is_finite() {
        format!(
            "the motion changing by {:.1e} of the first step's",
            p.change
        )
    } else {
        "a new round".to_string()
    };
    format!(
        "settling: {} static steps, dt {:.1e} s (growing to {:.1e} s), {change} (settled at \
         1e-5)",
        p.steps, p.dt, p.full_dt
    )
}

/// Runs `dda run`.
pub fn run(args: RunArgs) -> Result<ExitCode, Failure> {
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
            return Err(bad(format!("--rtol must be a positive number, got {r}")));
        }
        scene.scale_tolerances(r);
    }
    if args.checkpoint_every == Some(0) {
        return Err(bad("--checkpoint-every must be at least 1"));
    }
    if args.limits.max_steps == Some(0) {
        return Err(bad("--max-steps must be at least 1"));
    }
    // The scene as run, its regions cut into the blocks run: `dda run` of its record
    // repeats the run.
    let (explicit, model) = build_scene(&scene, &source, lines.as_ref())?;
    let out = args.out.clone().unwrap_or_else(|| default_out(&scene));
    check_out(&out)?;
    let signals = Signals::install();
    let staging = Staging::create(&staging_dir(&out), &out)?;
    let work = staging.dir.clone();
    // From here on the staging folder is ours: an output failure removes it.
    let started = (|| {
        let scene_json = serde_json::to_string_pretty(&*explicit)
            .map_err(|e| Failure::Output(format!("cannot serialise the scene: {e}")))?;
        write_new(&work.join("scene.json"), &(scene_json + "\n"))?;
        let history_path = work.join("history.csv");
        let frames_path = work.join("frames.jsonl");
        let history = BufWriter::new(
            File::create(&history_path).map_err(|e| output_error(e, &history_path))?,
        );
        let frames =
            BufWriter::new(File::create(&frames_path).map_err(|e| output_error(e, &frames_path))?);
        Ok((history, frames))
    })();
    let (history, frames) = match started {
        Ok(files) => files,
        Err(e) => {
            staging.abandon();
            return Err(e);
        }
    };
    let options = args.limits.options(args.limits.keep_going);
    let sim = Simulation::new(model, options);
    let mut job = Job::new(scene, sim, staging, out, history, frames, args.quiet);
    job.marks.checkpoint_every = args.checkpoint_every.unwrap_or(0);
    job.marks.source = Some(source);
    job.marks.keep_going = args.limits.keep_going;
    job.max_steps = args.limits.max_steps;
    job.signals = signals;
    job.finish(|job| {
        job.open_tables(true)?;
        job.write_history(HISTORY_HEADER)?;
        job.write_frame(job.sim.model().params.frames > 0)?;
        job.announce("scene");
        dda_core::on_pool(|| job.drive())
    })
}

/// Runs `dda resume`.
pub fn resume(args: ResumeArgs) -> Result<ExitCode, Failure> {
    let (work, out) = work_and_out(&args.dir);
    // A run that stopped before its end (--max-steps, a failure) was moved into place
    // with its checkpoint: once that checkpoint is known to load, the run goes back to
    // staging to go on, and is moved into place again however the resumed process
    // ends; if the resume is refused before it starts, it is put back as it was.
    let stopped = out.join(CHECKPOINT_FILE);
    let moved = !work.exists() && stopped.is_file();
    if moved {
        check_out(&out)?;
        let failed = std::fs::read_to_string(out.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<Summary>(&t).ok())
            .is_some_and(|s| s.status == "failed");
        if failed && !args.limits.keep_going {
            return Err(bad(format!(
                "{} is a run that failed (see its summary.json): resumed as it is, it would \
                 fail the same way; `dda resume {} --keep-going` goes on through a step \
                 that breaks physics",
                out.display(),
                out.display()
            )));
        }
    }
    // The checkpoint of a stopped run, loaded where the user has it (and named so in
    // messages), before the run goes back to staging.
    let loaded = if moved {
        let ck = Checkpoint::load(&stopped).map_err(|e| bad(e.to_string()))?;
        std::fs::rename(&out, &work).map_err(|e| output_error(e, &work))?;
        Some((ck, stopped))
    } else {
        None
    };
    let result = resume_staged(args, &work, &out, loaded);
    if moved && matches!(result, Err(Failure::Input(_))) && !out.exists() {
        let _ = std::fs::rename(&work, &out);
        let _ = std::fs::remove_file(out.join(super::outdir::LOCK));
    }
    result
}

/// [`resume`] of the run whose staging folder is `work` and output folder `out`;
/// `loaded`, its checkpoint and the path messages name it by, if [`resume`] loaded it
/// already (else it is loaded from the staging folder).
fn resume_staged(
    args: ResumeArgs,
    work: &Path,
    out: &Path,
    loaded: Option<(Checkpoint, PathBuf)>,
) -> Result<ExitCode, Failure> {
    let (work, out) = (work.to_path_buf(), out.to_path_buf());
    let path = work.join(CHECKPOINT_FILE);
    // A folder in use is named as such before anything else is said of it.
    let staging = if work.is_dir() {
        Some(Staging::resume(&work)?)
    } else {
        None
    };
    if !path.exists() {
        let done = out.join("summary.json").exists();
        return Err(bad(if done {
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
    if args.limits.max_steps == Some(0) {
        return Err(bad("--max-steps must be at least 1"));
    }
    check_out(&out)?;
    let signals = Signals::install();
    let Some(staging) = staging else {
        return Err(bad(format!("{} does not exist", work.display())));
    };
    let (ck, named) = match loaded {
        Some(loaded) => loaded,
        None => (
            Checkpoint::load(&path).map_err(|e| bad(e.to_string()))?,
            path,
        ),
    };
    let named = named.as_path();
    let scene = ck.scene(named).map_err(|e| bad(e.to_string()))?;
    let model = validate(&scene, &named.display().to_string(), None)?;
    let mut marks: OutputMarks = serde_json::from_str(&ck.client).map_err(|e| {
        bad(format!(
            "{}: its record of the outputs: {e}",
            named.display()
        ))
    })?;
    marks.keep_going |= args.limits.keep_going;
    let sim = ck
        .resume(model, args.limits.options(marks.keep_going), named)
        .map_err(|e| bad(e.to_string()))?;
    let history = reopen(&work.join("history.csv"), marks.history_bytes)?;
    let frames = reopen(&work.join("frames.jsonl"), marks.frames_bytes)?;
    let mut job = Job::new(scene, sim, staging, out, history, frames, args.quiet);
    job.marks = marks;
    job.max_steps = args.limits.max_steps;
    job.signals = signals;
    job.finish(|job| {
        job.open_tables(false)?;
        job.announce("resuming");
        dda_core::on_pool(|| job.drive())
    })
}

/// Opens `path` for appending after cutting it back to `len` bytes.
fn reopen(path: &Path, len: u64) -> Result<BufWriter<File>, Failure> {
    let bad = |e: std::io::Error| bad(format!("cannot resume {}: {e}", path.display()));
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(bad)?;
    let have = f.metadata().map_err(bad)?.len();
    if have < len {
        return Err(super::bad(format!(
            "cannot resume: {} has {have} bytes, the checkpoint was taken after {len}",
            path.display()
        )));
    }
    f.set_len(len).map_err(bad)?;
    f.seek(SeekFrom::End(0)).map_err(bad)?;
    Ok(BufWriter::new(f))
}

/// Most numbers (coordinates, speeds, stresses) the animation holds over all its
/// frames; fewer frames for larger models keep report.html to a few megabytes and the
/// run folder small. Measured on the 826-block column (31 frames recorded): report.html
/// 1.18 MB and the run folder 6.4 MB, against 1.83 and 9.2 MB at 500,000 (51 frames).
const ANIMATION_BUDGET: usize = 300_000;

/// Most numbers the animation holds however few frames that leaves (down to its first
/// and last): about 3 MB of report.html at the 2.2 bytes a number measured on the
/// 10,131-block column (a frame of 121,000 numbers packed into 270 kB), so 12 frames
/// there and 2 at 100,000 blocks.
const ANIMATION_CAP: usize = 1_500_000;

/// How many intervals of the run the animation records (plus its first instant):
/// ANIMATION_BUDGET numbers, at least 20 intervals and at most 200, and never more than
/// ANIMATION_CAP numbers unless that leaves fewer than one interval.
fn animation_intervals(per_frame: usize) -> u64 {
    let per_frame = per_frame.max(1);
    let wanted = (ANIMATION_BUDGET / per_frame).clamp(20, 200);
    let most = (ANIMATION_CAP / per_frame).saturating_sub(1).max(1);
    wanted.min(most) as u64
}

impl Job {
    fn new(
        scene: Scene,
        sim: Simulation,
        staging: Staging,
        out: PathBuf,
        history: BufWriter<File>,
        frames: BufWriter<File>,
        quiet: bool,
    ) -> Self {
        // The numbers a frame holds: two coordinates a vertex, a speed a block, and three
        // stresses a block when the blocks are elastic.
        let vertices: usize = sim.blocks().iter().map(|b| b.polygon.len()).sum();
        let per_block = if sim.effects().elasticity { 4 } else { 1 };
        let per_frame = 2 * vertices + per_block * sim.blocks().len();
        let animation_frames = animation_intervals(per_frame);
        let resolution = frame_resolution(&frame_view(sim.model()));
        Job {
            scene,
            sim,
            work: staging.dir.clone(),
            staging,
            out,
            max_steps: None,
            signals: Signals::default(),
            marks: OutputMarks {
                animation_next: 1,
                svg_next: 1,
                ..OutputMarks::default()
            },
            history,
            frames,
            tables: [None, None],
            animation_frames,
            resolution,
            quiet,
        }
    }

    /// Runs `work` on the job; if it fails to write an output, cleans the staging folder
    /// up (see [`Staging::abandon`]) before reporting it.
    fn finish(
        self,
        work: impl FnOnce(&mut Job) -> Result<ExitCode, Failure>,
    ) -> Result<ExitCode, Failure> {
        let mut job = self;
        match work(&mut job) {
            Ok(code) => Ok(code),
            Err(e) => {
                let Job { staging, .. } = job;
                staging.abandon();
                Err(e)
            }
        }
    }

    fn announce(&self, what: &str) {
        if self.quiet {
            return;
        }
        let sim = &self.sim;
        let p = &sim.model().params;
        let fixed = sim.model().blocks.iter().filter(|b| b.fixed).count();
        eprintln!(
            "{what} `{}` at t = {} s: {} and {fixed} fixed ({} unknowns), detector {}, \
             d_tol {} m, d_max {} m",
            sim.model().name,
            shown(sim.time()),
            counted((sim.blocks().len() - fixed) as u64, "block"),
            sim.unknowns(),
            sim.detector_name(),
            p.d_tol,
            p.d_max
        );
        eprintln!("effects: {}", sim.effects().names().join(", "));
        eprintln!(
            "solve: {}",
            if sim.solves_iteratively() {
                "iterative (conjugate gradients, analysis.solver)"
            } else {
                "direct (sparse Cholesky factor, analysis.solver)"
            }
        );
        if let Some(rule) = p.stepping_rule() {
            eprintln!("integration: {} (analysis.integration)", rule.name());
        }
        if self.marks.checkpoint_every > 0 {
            eprintln!(
                "checkpoint every {} steps: {} (continue with `dda resume {}`)",
                self.marks.checkpoint_every,
                self.work.join(CHECKPOINT_FILE).display(),
                self.out.display()
            );
        }
    }

    fn write_history(&mut self, line: &str) -> Result<(), Failure> {
        let path = self.work.join("history.csv");
        writeln!(self.history, "{line}").map_err(|e| output_error(e, &path))?;
        self.marks.history_bytes += line.len() as u64 + 1;
        Ok(())
    }

    /// Opens measurements.csv and bolts.csv where the scene calls for them: new, with
    /// their headers (`fresh`), or cut back to the checkpoint's marks (a resume).
    fn open_tables(&mut self, fresh: bool) -> Result<(), Failure> {
        let model = self.sim.model();
        let wanted = [
            (!model.measures.is_empty(), MEASUREMENTS_HEADER),
            (!model.bolts.is_empty(), BOLTS_HEADER),
        ];
        for (k, (want, header)) in wanted.into_iter().enumerate() {
            if !want {
                continue;
            }
            let path = self.work.join(TABLES[k]);
            let file = if fresh {
                let mut w =
                    BufWriter::new(File::create(&path).map_err(|e| output_error(e, &path))?);
                writeln!(w, "{header}").map_err(|e| output_error(e, &path))?;
                *self.table_bytes(k) = header.len() as u64 + 1;
                w
            } else {
                reopen(&path, *self.table_bytes(k))?
            };
            self.tables[k] = Some(file);
        }
        Ok(())
    }

    /// The bytes written of table `k` of [`TABLES`].
    fn table_bytes(&mut self, k: usize) -> &mut u64 {
        if k == 0 {
            &mut self.marks.measurements_bytes
        } else {
            &mut self.marks.bolts_bytes
        }
    }

    /// Appends this step's rows to measurements.csv and bolts.csv.
    fn write_tables(&mut self) -> Result<(), Failure> {
        let rows = [measurement_rows(&self.sim), bolt_rows(&self.sim)];
        for (k, rows) in rows.into_iter().enumerate() {
            let Some(w) = self.tables[k].as_mut() else {
                continue;
            };
            let path = self.work.join(TABLES[k]);
            let mut bytes = 0;
            for r in rows {
                writeln!(w, "{r}").map_err(|e| output_error(e, &path))?;
                bytes += r.len() as u64 + 1;
            }
            *self.table_bytes(k) += bytes;
        }
        Ok(())
    }

    /// Appends the current state to frames.jsonl.
    fn write_frame(&mut self, svg: bool) -> Result<(), Failure> {
        let path = self.work.join("frames.jsonl");
        let frame = Frame::of(&self.sim, svg, self.resolution);
        if !frame.is_finite() {
            // JSON would print them as `null`, which no reader takes back.
            return Err(Failure::Output(format!(
                "the frame at t = {} s holds a number that is not finite (a fault of dda, \
                 not of the scene)",
                frame.t
            )));
        }
        let line = serde_json::to_string(&frame)
            .map_err(|e| Failure::Output(format!("cannot serialise a frame: {e}")))?;
        writeln!(self.frames, "{line}").map_err(|e| output_error(e, &path))?;
        self.marks.frames_bytes += line.len() as u64 + 1;
        Ok(())
    }

    /// Records a frame if the step crossed an instant of the animation grid or of the
    /// SVG-frame grid.
    fn sample_frames(&mut self) -> Result<(), Failure> {
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
    fn flush(&mut self, sync: bool) -> Result<(), Failure> {
        let mut files: Vec<(&mut BufWriter<File>, &str)> = vec![
            (&mut self.history, "history.csv"),
            (&mut self.frames, "frames.jsonl"),
        ];
        for (w, name) in self.tables.iter_mut().zip(TABLES) {
            files.extend(w.as_mut().map(|w| (w, name)));
        }
        for (w, name) in files {
            let path = self.work.join(name);
            w.flush().map_err(|e| output_error(e, &path))?;
            if sync {
                w.get_ref()
                    .sync_data()
                    .map_err(|e| output_error(e, &path))?;
            }
        }
        Ok(())
    }

    /// Flushes the output files to disk and saves the checkpoint atomically.
    fn checkpoint(&mut self) -> Result<(), Failure> {
        self.flush(true)?;
        let marks = serde_json::to_string(&self.marks)
            .map_err(|e| Failure::Output(format!("cannot serialise the checkpoint: {e}")))?;
        let ck = Checkpoint::of(&self.sim, &self.scene, marks)
            .map_err(|e| Failure::Output(format!("cannot build the checkpoint: {e}")))?;
        ck.save(&self.work.join(CHECKPOINT_FILE))
            .map_err(|e| Failure::Output(format!("cannot write the checkpoint: {e}")))
    }

    /// What holds the step, for the progress line: where a block's velocity held `rec`'s
    /// dt below the step asked for, that block with its speed and spin; empty otherwise.
    fn held_by(&self, rec: &StepRecord) -> String {
        let Some(i) = rec.held_by else {
            return String::new();
        };
        let i = i as usize;
        let v = self.sim.blocks()[i].velocity;
        format!(
            " (held by `{}`: {:.3e} m/s, spin {:.3e} rad/s)",
            self.sim.model().blocks[i].id,
            v[0].hypot(v[1]),
            v[2].abs()
        )
    }

    /// Settles the blocks before t = 0 (`Simulation::settle_watched`), their progress
    /// shown as the run's is (`bar`, or a line every `PROGRESS_EVERY` since `logged`), a
    /// signal heeded between the static steps (the blocks then left unsettled, to settle
    /// again on resume), and what they took said afterwards; `began` is when the
    /// settling began, for the wall time shown. Returns how the run goes on:
    /// `End::Done` to step.
    fn settle_first(
        &mut self,
        began: std::time::Instant,
        bar: Option<&ProgressBar>,
        logged: &mut Option<std::time::Instant>,
    ) -> End {
        let signals = &self.signals;
        let mut caught = None;
        // The settling has no end known in advance: its bar shows how far the motion is
        // from steady, with no rate or time left.
        if let Some(bar) = bar {
            bar.set_style(
                ProgressStyle::with_template("{elapsed_precise} {msg}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
        }
        let outcome = self.sim.settle_watched(|p| {
            caught = signals.caught();
            if let Some(bar) = bar {
                bar.set_message(settle_progress(p));
                bar.tick();
            }
            if let Some(last) = logged.as_mut()
                && last.elapsed() >= PROGRESS_EVERY
            {
                *last = std::time::Instant::now();
                eprintln!(
                    "{}; {:.0} s of wall time",
                    settle_progress(p),
                    began.elapsed().as_secs_f64()
                );
            }
            caught.is_none()
        });
        // The run's rate and time left count from its first step.
        if let Some(bar) = bar {
            bar.set_style(run_style());
            bar.reset();
            bar.set_message(format!("t = {:.4} s", self.sim.time()));
        }
        match outcome {
            Ok(true) => {
                // This process's settling (none on resume, where it was done before).
                if let Some(done) = self.sim.settling() {
                    let seconds = began.elapsed().as_secs_f64();
                    self.marks.settling = Some(SettlingSummary {
                        solver: Some(done.solver),
                        static_steps: done.steps,
                        converged: done.converged,
                        seconds,
                        kept_step: done.kept_step,
                    });
                    if !self.quiet {
                        let line = format!(
                            "settled in {}{}, solved {} ({seconds:.3} s)",
                            counted(done.steps as u64, "static step"),
                            match (done.converged, done.kept_step) {
                                (true, _) => String::new(),
                                (false, Some(k)) => format!(
                                    ", stopped without converging (the run starts from \
                                     its steadiest, step {k})"
                                ),
                                (false, None) => {
                                    ", stopped without converging (the run starts from its \
                                     last static step)"
                                        .to_string()
                                }
                            },
                            done.solver.adverb(),
                        );
                        match bar {
                            Some(bar) => bar.println(line),
                            None => eprintln!("{line}"),
                        }
                    }
                } else if !self.quiet {
                    // Settled with nothing to settle: no free block rests on a fixed one.
                    let line = "settling: nothing to settle (no free block rests, directly or \
                                through others, on a fixed block); the run starts as written";
                    match bar {
                        Some(bar) => bar.println(line),
                        None => eprintln!("{line}"),
                    }
                }
                End::Done
            }
            Ok(false) => End::Signal(caught.unwrap_or(2)),
            Err(e) => End::Failed(e.to_string()),
        }
    }

    /// Steps to the end, a failure, the step limit or a signal. At a signal, saves a
    /// checkpoint and leaves the run in its staging folder for `dda resume`; otherwise
    /// writes the summary and the report and moves the outputs into place.
    fn drive(&mut self) -> Result<ExitCode, Failure> {
        let settling = self.sim.settles().then(std::time::Instant::now);
        if settling.is_some() && !self.quiet {
            eprintln!("settling: static steps onto the contacts before t = 0 (analysis.settle)");
        }
        let bar = if !self.quiet && std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(1000);
            bar.set_style(run_style());
            Some(bar)
        } else {
            None
        };
        // Without a terminal (a batch job, a log), a line every PROGRESS_EVERY instead.
        let mut logged = (!self.quiet && bar.is_none()).then(std::time::Instant::now);
        let started = std::time::Instant::now();
        let duration = self.sim.model().params.duration;
        // --max-steps counts this process's steps (a resumed run's from where it resumed).
        let first = self.sim.totals().steps;
        let mut end = End::Done;
        if let Some(began) = settling {
            end = self.settle_first(began, bar.as_ref(), &mut logged);
        }
        while matches!(end, End::Done) && !self.sim.finished() {
            if let Some(sig) = self.signals.caught() {
                end = End::Signal(sig);
                break;
            }
            if let Some(n) = self.max_steps
                && self.sim.totals().steps - first >= n
            {
                end = End::Stopped(format!(
                    "stopped after {n} steps (--max-steps) at t = {:.6} s of {duration} s",
                    self.sim.time()
                ));
                break;
            }
            match self.sim.step() {
                Ok(rec) => {
                    if let Some(i) = rec.held_by {
                        let id = &self.sim.model().blocks[i as usize].id;
                        match self.marks.held.get_mut(id) {
                            Some(n) => *n += 1,
                            None => {
                                self.marks.held.insert(id.clone(), 1);
                            }
                        }
                    }
                    self.write_history(&history_row(&rec))?;
                    self.write_tables()?;
                    self.sample_frames()?;
                    let every = self.marks.checkpoint_every;
                    if every > 0 && rec.step.is_multiple_of(every) && !self.sim.finished() {
                        self.checkpoint()?;
                    }
                    if let Some(bar) = &bar {
                        bar.set_position((1000.0 * self.sim.time() / duration) as u64);
                        bar.set_message(format!(
                            "t = {:.4} s, dt {:.1e} s{}",
                            self.sim.time(),
                            rec.dt,
                            self.held_by(&rec)
                        ));
                    }
                    if let Some(last) = logged.as_mut()
                        && last.elapsed() >= PROGRESS_EVERY
                    {
                        *last = std::time::Instant::now();
                        let totals = self.sim.totals();
                        eprintln!(
                            "t = {:.6} s of {duration} s ({:.0}%): {} steps, {} OCI iterations, \
                             {} dt cuts, dt {:.3e} s{}; {:.0} s of wall time",
                            self.sim.time(),
                            100.0 * self.sim.time() / duration,
                            totals.steps,
                            totals.oci_iterations,
                            totals.cuts,
                            rec.dt,
                            self.held_by(&rec),
                            started.elapsed().as_secs_f64()
                        );
                    }
                }
                Err(e) => {
                    end = End::Failed(e.to_string());
                    break;
                }
            }
        }
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        if let End::Signal(sig) = end {
            self.checkpoint()?;
            eprintln!(
                "interrupted by {} at t = {} s after {} steps; the state is saved: \
                 `dda resume {}` continues the run",
                signals::name(sig),
                self.sim.time(),
                self.sim.totals().steps,
                self.out.display()
            );
            return Ok(ExitCode::from((128 + sig) as u8));
        }
        let (status, error) = match &end {
            End::Done => ("completed", None),
            End::Failed(e) => ("failed", Some(e.clone())),
            End::Stopped(e) => ("stopped", Some(e.clone())),
            End::Signal(_) => unreachable!("handled above"),
        };
        if error.is_some() {
            // The last good state: as a checkpoint, then as the final frame (after the
            // checkpoint, so that a resume drops it and goes on as the run would have).
            self.checkpoint()?;
            self.write_frame(true)?;
            self.flush(true)?;
        } else {
            self.flush(false)?;
        }
        let mut summary = Summary::of(&self.sim, error.clone());
        summary.status = status.to_string();
        summary.source.clone_from(&self.marks.source);
        summary.settling = self.marks.settling;
        let mut held: Vec<HeldBy> = self
            .marks
            .held
            .iter()
            .map(|(block, &steps)| HeldBy {
                block: block.clone(),
                steps,
            })
            .collect();
        held.sort_by(|a, b| b.steps.cmp(&a.steps).then_with(|| a.block.cmp(&b.block)));
        held.truncate(5);
        summary.held_by = held;
        let json = serde_json::to_string_pretty(&summary)
            .map_err(|e| Failure::Output(format!("cannot serialise the summary: {e}")))?;
        write_new(&self.work.join("summary.json"), &(json + "\n"))?;
        self.staging.publish(&self.out)?;
        // A finished run's checkpoint goes only now: killed before this point, the run
        // is still resumable from its staging folder.
        let published_checkpoint = self.out.join(CHECKPOINT_FILE);
        if error.is_none() && published_checkpoint.exists() {
            std::fs::remove_file(&published_checkpoint)
                .map_err(|e| output_error(e, &published_checkpoint))?;
        }
        // The pictures and the report are drawn from the published files, so that a
        // failure to draw them loses nothing of the run: exit 1, the run in place.
        render_outputs(&self.out, &self.scene, self.sim.model(), &summary).map_err(|e| {
            let (Failure::Input(m) | Failure::Output(m)) = e;
            Failure::Output(format!(
                "{m}; the run is in {} without its report: `dda render {}` draws it again",
                self.out.display(),
                self.out.display()
            ))
        })?;

        if !self.quiet {
            let s = &summary;
            eprintln!(
                "{} s simulated in {} ({}, {}); \
                 {:.3} s wall: detection {:.3} s, assembly {:.3} s, solve {:.3} s; \
                 max penetration {:.3e} m",
                shown(s.time_simulated),
                counted(s.steps, "step"),
                counted(s.oci_iterations, "OCI iteration"),
                counted(s.time_step_cuts, "dt cut"),
                s.seconds.total,
                s.seconds.contact_detection,
                s.seconds.assembly,
                s.seconds.solve,
                s.max_penetration
            );
            // One block that held dt in half the run's steps or more sets its pace: say so
            // (summary.json lists the blocks that held it in any case).
            if let Some(most) = s.held_by.first().filter(|m| 2 * m.steps >= s.steps) {
                let all: u64 = self.marks.held.values().sum();
                eprintln!(
                    "a block's motion held dt below the step asked for in {}, most often `{}` \
                     ({}; summary.json `held_by`)",
                    counted(all, "step"),
                    most.block,
                    counted(most.steps, "step")
                );
            }
            eprintln!("wrote {}", self.out.display());
        }
        for w in &summary.warnings {
            eprintln!("warning: {w}");
        }
        match error {
            Some(e) => {
                let what = if status == "stopped" {
                    "the run stopped"
                } else {
                    "the simulation cannot go on"
                };
                eprintln!("error: {what}: {e}");
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

/// How the stepping ended.
enum End {
    /// The duration was reached.
    Done,
    /// A step failed or broke physics.
    Failed(String),
    /// `--max-steps` was reached.
    Stopped(String),
    /// A signal arrived.
    Signal(i32),
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The settling's progress names its static steps, their size against the
    /// settling's own and how far the motion is from steady (a round's first step has no
    /// change to show), and promises no time left.
    #[test]
    fn the_settling_s_progress_says_how_far_the_motion_is_from_steady() {
        let mut p = SettleProgress {
            steps: 285,
            change: 3.4e-2,
            dt: 5.2e-4,
            full_dt: 1.34e-2,
        };
        let line = settle_progress(&p);
        assert_eq!(
            line,
            "settling: 285 static steps, dt 5.2e-4 s (growing to 1.3e-2 s), the motion \
             changing by 3.4e-2 of the first step's (settled at 1e-5)"
        );
        p.change = f64::INFINITY;
        assert!(
            settle_progress(&p).contains("a new round"),
            "{}",
            settle_progress(&p)
        );
    }

    /// The animation's frames (its intervals and first instant) hold at most
    /// ANIMATION_CAP numbers unless only the first and last are left, at least 21 frames
    /// while the budget allows, and more frames for smaller models.
    #[test]
    fn the_animation_keeps_to_its_budget_and_cap() {
        let mut last = u64::MAX;
        for per_frame in (1..2_000).map(|k| k * 1_000).chain([1, 7, 3_000_000]) {
            let n = animation_intervals(per_frame);
            let numbers = (n as usize + 1) * per_frame;
            assert!(n >= 1, "{per_frame}");
            assert!(numbers <= ANIMATION_CAP || n == 1, "{per_frame}: {n}");
            if 21 * per_frame <= ANIMATION_CAP {
                assert!(n >= 20, "{per_frame}: {n}");
            }
            if (1_000..3_000_000).contains(&per_frame) {
                assert!(n <= last, "{per_frame}: {n} after {last}");
                last = n;
            }
        }
        assert_eq!(animation_intervals(1), 200);
    }
}
