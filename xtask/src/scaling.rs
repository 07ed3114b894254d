//! `cargo xtask scaling`: time per step against the number of blocks. Columns cut by the
//! joint layout of paper 5.2b over a region `s` times as wide and as tall (about
//! 826 s^2 blocks of the same sizes, Table 3's 5.2b parameters), run with the cover
//! detector at r_tol 1 for a short simulated time. Writes `docs/scaling.md` and
//! `docs/results/scaling.svg` (or under `--out DIR`); the readings written by hand under the
//! table of an existing `scaling.md` (its `## ` sections) are kept.
//!
//! With `--write-scenes DIR` it runs nothing and writes each column as a scene file
//! (`DIR/column-N.json`) instead, for `dda run` with `--checkpoint-every`: a column too
//! large to run in one sitting can then be resumed (`dda resume`).

use dda_bench::{PAPER_COLUMNS, column_scene};
use dda_core::iterative::solves_iteratively;
use dda_core::scene::{Scene, SolverChoice};
use dda_core::{RunOptions, Simulation};
use dda_report::plot;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `cargo xtask scaling`.
#[derive(Debug, clap::Args)]
pub struct Options {
    /// Target block counts.
    #[arg(long, value_delimiter = ',', default_values_t = [826, 3300, 10_000, 30_000, 100_000])]
    blocks: Vec<usize>,
    /// Simulated seconds per run.
    #[arg(long, default_value_t = 0.1, value_parser = crate::args::positive_number)]
    duration: f64,
    /// Where to write scaling.md and results/scaling.svg (default: docs/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Write the columns as scene files here instead of running them.
    #[arg(long)]
    write_scenes: Option<PathBuf>,
    /// How the columns' systems are solved: auto (by size), direct or iterative.
    #[arg(long, default_value = "auto", value_parser = solver_choice)]
    solver: SolverChoice,
}

/// A solver choice by its name in the scene format.
fn solver_choice(s: &str) -> Result<SolverChoice, String> {
    match s {
        "auto" => Ok(SolverChoice::Auto),
        "direct" => Ok(SolverChoice::Direct),
        "iterative" => Ok(SolverChoice::Iterative),
        _ => Err(format!("`{s}`: expected auto, direct or iterative")),
    }
}

impl Options {
    /// The options with their output folder resolved against the workspace root.
    pub fn at(mut self, root: &Path) -> Options {
        self.out.get_or_insert_with(|| root.join("docs"));
        self
    }

    fn out(&self) -> PathBuf {
        self.out.clone().unwrap_or_else(|| PathBuf::from("docs"))
    }
}

/// One run of the study.
struct Row {
    blocks: usize,
    solver: &'static str,
    unknowns: usize,
    build_s: f64,
    steps: u64,
    oci: u64,
    total_s: f64,
    detection_s: f64,
    assembly_s: f64,
    solve_s: f64,
    error: Option<String>,
}

/// The generated column of about `n` blocks, `duration` simulated seconds, no frames,
/// solved as `solver` says.
fn scaled_column(n: usize, duration: f64, solver: SolverChoice) -> (usize, Scene) {
    let column = PAPER_COLUMNS[3];
    let scale = (n as f64 / column.blocks as f64).sqrt();
    let blocks = column.scaled_blocks(scale);
    let mut analysis = column.analysis();
    analysis.duration = duration;
    analysis.frames = 0;
    analysis.solver = (solver != SolverChoice::Auto).then_some(solver);
    let name = format!("column-{}", blocks.len());
    (blocks.len(), column_scene(&name, &blocks, analysis))
}

/// Writes each column as `dir/column-N.json` (N its block count).
fn write_scenes(o: &Options, dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    for &n in &o.blocks {
        let (count, scene) = scaled_column(n, o.duration, o.solver);
        let path = dir.join(format!("column-{count}.json"));
        let text = serde_json::to_string(&scene).map_err(|e| format!("{count} blocks: {e}"))?;
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))?;
        eprintln!("scaling: wrote {} ({count} blocks)", path.display());
    }
    Ok(())
}

/// Runs the study (or writes its scenes, with `--write-scenes`).
pub fn run(o: &Options) -> Result<(), String> {
    if let Some(dir) = &o.write_scenes {
        return write_scenes(o, dir);
    }
    std::fs::create_dir_all(o.out()).map_err(|e| format!("{}: {e}", o.out().display()))?;
    let mut rows = Vec::new();
    for &n in &o.blocks {
        let t0 = Instant::now();
        let (count, scene) = scaled_column(n, o.duration, o.solver);
        let model = scene
            .validate()
            .map_err(|e| format!("{count} blocks: {}: {}", e.key, e.message))?;
        let mut sim = Simulation::new(model, RunOptions::default());
        let build_s = t0.elapsed().as_secs_f64();
        eprintln!(
            "scaling: {} blocks ({} unknowns), built in {build_s:.1} s",
            count,
            sim.unknowns()
        );
        let result = dda_core::on_pool(|| {
            sim.run(|s, _| {
                if s.totals().steps % 20 == 0 {
                    eprintln!(
                        "  t = {:.4} s, {} steps, dt {:.2e} s, {} cuts",
                        s.time(),
                        s.totals().steps,
                        s.time_step(),
                        s.totals().cuts
                    );
                }
            })
        });
        let t = sim.totals();
        rows.push(Row {
            blocks: count,
            solver: if solves_iteratively(o.solver, count) {
                "iterative"
            } else {
                "direct"
            },
            unknowns: sim.unknowns(),
            build_s,
            steps: t.steps,
            oci: t.oci_iterations,
            total_s: t.total_s,
            detection_s: t.detection_s,
            assembly_s: t.assembly_s,
            solve_s: t.solve_s,
            error: result.err().map(|e| e.to_string()),
        });
    }

    let mut doc = format!(
        "# Time per step against the number of blocks\n\n\
         Made by `cargo xtask scaling --blocks {} --duration {}{}` on this machine (2 cores).\n\
         Columns cut by paper 5.2b's joint layout (two sets, 60 and 15 deg) over a region\n\
         s times as wide and as tall as 10 m x 20 m, so the blocks keep their sizes and\n\
         their number grows as s^2; Table 3's 5.2b parameters; cover detector, r_tol 1;\n\
         {} s simulated from rest. Build: cutting, validation and set-up.\n\n\
         | blocks | solver | unknowns | build s | steps | OCI | wall s | ms per step | detection | assembly | solve | per step per 1k blocks (ms) |\n\
         | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        o.blocks
            .iter()
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(","),
        o.duration,
        match o.solver {
            SolverChoice::Auto => "",
            SolverChoice::Direct => " --solver direct",
            SolverChoice::Iterative => " --solver iterative",
        },
        o.duration
    );
    for r in &rows {
        let per = |s: f64| 1e3 * s / r.steps.max(1) as f64;
        let _ = writeln!(
            doc,
            "| {} | {} | {} | {:.1} | {} | {} | {:.2} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} |{}",
            r.blocks,
            r.solver,
            r.unknowns,
            r.build_s,
            r.steps,
            r.oci,
            r.total_s,
            per(r.total_s),
            per(r.detection_s),
            per(r.assembly_s),
            per(r.solve_s),
            per(r.total_s) / (r.blocks as f64 / 1e3),
            r.error
                .as_deref()
                .map(|e| format!(" failed: {e}"))
                .unwrap_or_default()
        );
    }
    let pts = |f: fn(&Row) -> f64| -> Vec<(f64, f64)> {
        rows.iter()
            .filter(|r| r.steps > 0)
            .map(|r| {
                (
                    (r.blocks as f64).log10(),
                    (1e3 * f(r) / r.steps as f64).log10(),
                )
            })
            .collect()
    };
    let series = vec![
        ("total".to_string(), pts(|r| r.total_s)),
        ("detection".to_string(), pts(|r| r.detection_s)),
        ("assembly".to_string(), pts(|r| r.assembly_s)),
        ("solve".to_string(), pts(|r| r.solve_s)),
    ];
    let svg = plot(
        "Time per step against blocks (log-log; slope 1 is linear)",
        "log10 blocks",
        "log10 ms per step",
        &series,
        true,
        true,
    );
    let results = o.out().join("results");
    std::fs::create_dir_all(&results).map_err(|e| format!("{}: {e}", results.display()))?;
    std::fs::write(results.join("scaling.svg"), svg).map_err(|e| format!("scaling.svg: {e}"))?;
    doc.push_str("\n![time per step](results/scaling.svg)\n");
    let path = o.out().join("scaling.md");
    // The readings written by hand under the table (its `## ` sections) are kept.
    if let Ok(old) = std::fs::read_to_string(&path) {
        doc.push_str(hand_written(&old));
    }
    std::fs::write(&path, doc).map_err(|e| format!("{}: {e}", path.display()))?;
    println!("wrote {}", path.display());
    Ok(())
}

/// The hand-written part of a scaling report: from its first `## ` section on (the
/// generated part has none), with the blank line before it; empty if there is none.
fn hand_written(doc: &str) -> &str {
    doc.find("\n## ").map_or("", |at| &doc[at..])
}

#[cfg(test)]
mod tests {
    use super::{Options, hand_written, scaled_column, write_scenes};
    use dda_core::scene::{Scene, SolverChoice};
    use std::path::PathBuf;

    /// A column written with `--write-scenes` loads back as the same scene, under the
    /// name that carries its block count.
    #[test]
    fn written_columns_load_back_unchanged() {
        let dir = std::env::temp_dir().join(format!("dda-write-scenes-{}", std::process::id()));
        let o = Options {
            blocks: vec![826],
            duration: 0.05,
            out: Some(PathBuf::from("unused")),
            write_scenes: Some(dir.clone()),
            solver: SolverChoice::Auto,
        };
        write_scenes(&o, &dir).expect("written");
        let (count, scene) = scaled_column(826, 0.05, SolverChoice::Auto);
        let (loaded, model) =
            Scene::load(&dir.join(format!("column-{count}.json"))).expect("loads");
        std::fs::remove_dir_all(&dir).ok();
        assert_eq!(loaded, scene);
        // The generated blocks and the fixed base.
        assert_eq!(model.blocks.len(), count + 1);
        assert_eq!(model.params.duration, 0.05);
    }

    #[test]
    fn regenerating_keeps_the_readings_written_by_hand() {
        let old = "# Time per step\n\n| table |\n\n![plot](scaling.svg)\n\n## Reading\n\nText.\n";
        assert_eq!(hand_written(old), "\n## Reading\n\nText.\n");
        assert_eq!(hand_written("# Time per step\n\n| table |\n"), "");
    }
}
