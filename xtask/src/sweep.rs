//! `cargo xtask sweep`: the paper's section 5 columns run over detectors and contact
//! tolerance ratios r_tol (eq. 15), reporting steps, OCI cycles, seconds by phase and
//! accuracy together: `sweep.csv`, `sweep.json`, a table in the layout of the paper's
//! Tables 4 and 5, and SVG plots.
//!
//! Runs are independent and each is deterministic, so the results do not depend on
//! `--jobs`; only the seconds do (two runs at once on two cores share them, so timing
//! sweeps use `--jobs 1`, the default). A run still going after `--max-steps` steps
//! (default 5,000, nearly four times the paper's longest run) is stopped and counted as
//! not permissible, so that a detector whose time step collapses cannot hold up a sweep.

use crate::args;
use dda_bench::{PAPER_COLUMNS, Stop, run_watched};
use dda_core::{RunOptions, Simulation};
use dda_report::{csv_record, plot};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// What one run did.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Row {
    /// Block count of the paper's column (20, 93, 229, 826).
    pub model: usize,
    /// Detector name.
    pub detector: String,
    /// Contact tolerance ratio.
    pub r_tol: f64,
    /// Completed steps.
    pub steps: u64,
    /// OCI iterations (cycles).
    pub oci_cycles: u64,
    /// Numeric factorisations of the global matrix.
    pub factorisations: u64,
    /// Solves through a low-rank update of a factor.
    pub low_rank_solves: u64,
    /// Wall seconds in contact detection.
    pub detection_s: f64,
    /// Wall seconds in assembly.
    pub assembly_s: f64,
    /// Wall seconds in factorisation and solves.
    pub solve_s: f64,
    /// Wall seconds of the whole run.
    pub total_s: f64,
    /// Largest penetration of a closed contact, m.
    pub max_penetration: f64,
    /// The worst instant of kinetic energy less the potential energy released, over m g H
    /// (`dda_bench::collapse`; permissible at most 0.2%), and its time, s.
    pub kinetic_excess: dda_bench::Worst,
    /// The worst instant of the fastest block's speed over 3 g t (permissible at most 1),
    /// and its time, s.
    pub speed_ratio: dda_bench::Worst,
    /// Permissible: completed, finite, penetration below d_tol, and the collapse verdict's
    /// energy and speed criteria met at every step (`dda_bench::collapse`).
    pub verdict: bool,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
}

/// Options of a sweep.
#[derive(Debug, clap::Args)]
pub struct Options {
    /// Block counts of the columns to run.
    #[arg(long, value_delimiter = ',', value_parser = args::paper_column,
          default_values_t = [20, 93, 229, 826])]
    pub models: Vec<usize>,
    /// Detectors.
    #[arg(long, value_delimiter = ',', value_parser = args::detector,
          default_values_t = ["cover".to_string(), "type-1".to_string(), "type-2".to_string()])]
    pub detectors: Vec<String>,
    /// Contact tolerance ratios.
    #[arg(long = "rtol", value_delimiter = ',', value_parser = args::positive_number,
          default_values_t = [1.0, 2.0, 4.0, 6.0, 8.0, 10.0])]
    pub rtols: Vec<f64>,
    /// Runs at once.
    #[arg(long, default_value_t = 1, value_parser = args::positive_size)]
    pub jobs: usize,
    /// Steps after which a run is stopped and counted as failed.
    #[arg(long, default_value_t = MAX_STEPS, value_parser = args::positive_count)]
    pub max_steps: u64,
    /// Output directory.
    #[arg(long, default_value = "runs/sweep", global = true)]
    pub out: PathBuf,
    /// Write the page, the table and the plots again from the output directory's
    /// sweep.json, running nothing.
    #[arg(long)]
    pub render: bool,
    /// Run only shard I of N (`--shard 2/8`): the runs whose index in the sweep's order
    /// (model, detector, r_tol) is I - 1 modulo N, so that a batch scheduler's job array
    /// runs the sweep in N parts; `cargo xtask sweep merge` joins them.
    #[arg(long, value_parser = args::shard, value_name = "I/N")]
    pub shard: Option<(usize, usize)>,
    /// `merge DIR...`: join the shards' sweep.json files into one sweep (in `--out`).
    #[command(subcommand)]
    pub action: Option<Action>,
}

/// What `cargo xtask sweep` does besides running.
#[derive(Debug, clap::Subcommand)]
pub enum Action {
    /// Join the sweep.json of each shard's output folder into one sweep in `--out`: the
    /// same rows, in the same order, as one unsharded sweep (wall seconds aside).
    Merge {
        /// The shards' output folders.
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
    },
}

/// Steps after which a run is stopped and counted as not permissible, unless
/// `--max-steps` says otherwise (nearly four times the paper's longest run).
pub const MAX_STEPS: u64 = 5000;

/// Runs one combination, stopping it after `max_steps` steps, with gravity scaled by
/// `gravity_factor` (1 for the paper's scene; `cargo xtask target` perturbs it).
pub fn run_one(
    model: usize,
    detector: &str,
    r_tol: f64,
    max_steps: u64,
    gravity_factor: f64,
) -> Row {
    let column = PAPER_COLUMNS
        .iter()
        .find(|c| c.blocks == model)
        .copied()
        .unwrap_or(PAPER_COLUMNS[0]);
    let mut scene = column.scene();
    scene.analysis.detector = detector.into();
    scene.scale_tolerances(r_tol);
    if let Some(g) = scene.analysis.gravity.as_mut() {
        *g = g.map(|c| c * gravity_factor);
    }
    let mut row = Row {
        model,
        detector: detector.into(),
        r_tol,
        steps: 0,
        oci_cycles: 0,
        factorisations: 0,
        low_rank_solves: 0,
        detection_s: 0.0,
        assembly_s: 0.0,
        solve_s: 0.0,
        total_s: 0.0,
        max_penetration: 0.0,
        kinetic_excess: dda_bench::Worst::default(),
        speed_ratio: dda_bench::Worst::default(),
        verdict: false,
        error: None,
    };
    let m = match scene.validate() {
        Ok(m) => m,
        Err(e) => {
            row.error = Some(format!("{}: {}", e.key, e.message));
            return row;
        }
    };
    let d_tol = m.params.d_tol;
    let mut sim = Simulation::new(m, RunOptions::default());
    let (watch, stop) = run_watched(&mut sim, max_steps);
    let result = match stop {
        None => Ok(()),
        Some(Stop::Steps) => Err(format!(
            "stopped after {max_steps} steps at t = {:.4} s (--max-steps)",
            sim.time()
        )),
        Some(Stop::Failed(e)) => Err(e),
    };
    let t = sim.totals();
    row.steps = t.steps;
    row.oci_cycles = t.oci_iterations;
    let counters = sim.solver_counters();
    (row.factorisations, row.low_rank_solves) = (counters.numeric, counters.low_rank);
    row.detection_s = t.detection_s;
    row.assembly_s = t.assembly_s;
    row.solve_s = t.solve_s;
    row.total_s = t.total_s;
    row.max_penetration = t.max_penetration;
    (row.kinetic_excess, row.speed_ratio) = (watch.energy, watch.speed);
    let finite = sim
        .blocks()
        .iter()
        .all(|b| b.velocity.iter().all(|v| v.is_finite()));
    row.error = result.err();
    row.verdict =
        row.error.is_none() && finite && row.max_penetration < d_tol && watch.permissible();
    row
}

/// Runs the sweep and writes its files; prints the table.
pub fn run(root: &Path, o: &Options) -> Result<(), String> {
    let out = root.join(&o.out);
    if let Some(Action::Merge { dirs }) = &o.action {
        let rows = merge(&dirs.iter().map(|d| root.join(d)).collect::<Vec<_>>())?;
        std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
        write_files(&out, &rows)?;
        println!("{}", table(&rows));
        println!(
            "wrote {} ({} runs from {} shards)",
            out.display(),
            rows.len(),
            dirs.len()
        );
        return Ok(());
    }
    if o.render {
        let path = out.join("sweep.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let rows: Vec<Row> =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        write_files(&out, &rows)?;
        println!("wrote {} again from sweep.json", out.display());
        return Ok(());
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut combos = Vec::new();
    for &m in &o.models {
        for d in &o.detectors {
            for &r in &o.rtols {
                combos.push((m, d.clone(), r));
            }
        }
    }
    if let Some((i, n)) = o.shard {
        combos = combos
            .into_iter()
            .enumerate()
            .filter(|(k, _)| k % n == i)
            .map(|(_, c)| c)
            .collect();
    }
    let bar = indicatif::ProgressBar::new(combos.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} ({msg})")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let next = AtomicUsize::new(0);
    let rows: Mutex<Vec<Option<Row>>> = Mutex::new(vec![None; combos.len()]);
    std::thread::scope(|s| {
        for _ in 0..o.jobs.min(combos.len()).max(1) {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some((m, d, r)) = combos.get(i) else {
                        break;
                    };
                    bar.set_message(format!("{m} blocks, {d}, r_tol {r}"));
                    let row = run_one(*m, d, *r, o.max_steps, 1.0);
                    if bar.is_hidden() {
                        // No terminal: one line per run, so a log shows progress.
                        eprintln!(
                            "{m} blocks, {d}, r_tol {r}: {} steps, {:.2} s",
                            row.steps, row.total_s
                        );
                    }
                    if let Ok(mut rows) = rows.lock() {
                        rows[i] = Some(row);
                    }
                    bar.inc(1);
                }
            });
        }
    });
    bar.finish_and_clear();
    let mut rows: Vec<Row> = rows
        .into_inner()
        .map_err(|_| "a run panicked".to_string())?
        .into_iter()
        .flatten()
        .collect();
    // The sweep's order, whatever the options' (and a shard's rows in it, for merge).
    rows.sort_by(sweep_order);
    write_files(&out, &rows)?;
    println!("{}", table(&rows));
    println!("wrote {}", out.display());
    Ok(())
}

/// The order of a sweep's rows: by model, detector name and r_tol.
fn sweep_order(a: &Row, b: &Row) -> std::cmp::Ordering {
    a.model
        .cmp(&b.model)
        .then(a.detector.cmp(&b.detector))
        .then(a.r_tol.total_cmp(&b.r_tol))
}

/// The rows of the shards' sweep.json files in `dirs`, in the sweep's order (model,
/// detector, r_tol); an error names a file that cannot be read and a run found twice.
pub fn merge(dirs: &[PathBuf]) -> Result<Vec<Row>, String> {
    let mut rows: Vec<Row> = Vec::new();
    for d in dirs {
        let path = d.join("sweep.json");
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let shard: Vec<Row> =
            serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
        rows.extend(shard);
    }
    rows.sort_by(sweep_order);
    for w in rows.windows(2) {
        if w[0].model == w[1].model && w[0].detector == w[1].detector && w[0].r_tol == w[1].r_tol {
            return Err(format!(
                "the run {} blocks, {}, r_tol {} is in two shards",
                w[0].model, w[0].detector, w[0].r_tol
            ));
        }
    }
    Ok(rows)
}

/// The header line of `sweep.csv`.
pub const CSV_HEADER: &str = "model,detector,r_tol,steps,oci_cycles,detection_s,assembly_s,\
                              solve_s,total_s,max_penetration,kinetic_excess,kinetic_excess_t,\
                              speed_ratio,speed_ratio_t,verdict,error";

/// One run as a line of `sweep.csv`, without its newline.
pub fn csv_line(r: &Row) -> String {
    csv_record(csv_fields(r))
}

/// The fields of one run in `sweep.csv`.
pub fn csv_fields(r: &Row) -> Vec<String> {
    vec![
        r.model.to_string(),
        r.detector.clone(),
        r.r_tol.to_string(),
        r.steps.to_string(),
        r.oci_cycles.to_string(),
        format!("{:.4}", r.detection_s),
        format!("{:.4}", r.assembly_s),
        format!("{:.4}", r.solve_s),
        format!("{:.4}", r.total_s),
        format!("{:e}", r.max_penetration),
        format!("{:e}", r.kinetic_excess.value),
        format!("{}", r.kinetic_excess.t),
        format!("{:e}", r.speed_ratio.value),
        format!("{}", r.speed_ratio.t),
        if r.verdict {
            "permissible"
        } else {
            "not permissible"
        }
        .to_string(),
        r.error.clone().unwrap_or_default(),
    ]
}

fn write_files(out: &Path, rows: &[Row]) -> Result<(), String> {
    let mut csv = format!("{CSV_HEADER}\n");
    for r in rows {
        let _ = writeln!(csv, "{}", csv_line(r));
    }
    let write = |name: &str, text: String| {
        std::fs::write(out.join(name), text).map_err(|e| format!("{name}: {e}"))
    };
    write("sweep.csv", csv)?;
    write(
        "sweep.json",
        serde_json::to_string_pretty(rows).map_err(|e| e.to_string())?,
    )?;
    let mut plots = vec![
        ("speedup.svg".to_string(), speedup_plot(rows)),
        ("steps.svg".to_string(), counts_plot(rows)),
    ];
    for m in models_of(rows) {
        plots.push((format!("accuracy-{m}.svg"), accuracy_plot(rows, m)));
    }
    let mut html = String::from(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>dda sweep</title><style>body { font-family: sans-serif; margin: 1.5em; \
         max-width: 1300px; } \
         table { border-collapse: collapse; font-size: 13px; } \
         td, th { border: 1px solid #ccc; padding: 2px 6px; text-align: right; } \
         .plots { display: flex; flex-wrap: wrap; gap: 0.5em; } \
         .plots svg { width: 540px; height: auto; }</style>\
         </head><body>\n<h1>Sweep: what a larger contact tolerance buys and costs</h1>\n",
    );
    html.push_str(&conclusion(rows));
    let _ = writeln!(
        html,
        "<p>The paper's section 5 columns (Table 3's parameters) with every detector at each \
         r_tol (contact tolerance and largest step displacement scaled together, paper \
         eq. 15). \"Permissible\": the run completed, finite, with penetration below d_tol \
         and the collapse verdict held at every step (docs/performance.md). Wall seconds \
         drift 20-50% on this machine from run to run; steps and OCI cycles do not. How \
         accuracy costs time on problems with a closed-form answer: docs/accuracy.md \
         (<a href=\"../../accuracy.md\">accuracy.md</a>); the detectors on the section 4 \
         hard cases: docs/robustness.md (<a href=\"../../robustness.md\">robustness.md</a>).</p>"
    );
    html.push_str(&table_html(&table(rows)));
    html.push_str(&beside_the_paper(rows));
    let _ = writeln!(
        html,
        "<p>Raw data: <a href=\"sweep.csv\">sweep.csv</a>, <a href=\"sweep.json\">sweep.json</a>.</p>"
    );
    html.push_str("<div class=\"plots\">\n");
    for (name, svg) in plots {
        html.push_str(&svg);
        write(&name, svg)?;
    }
    html.push_str("</div>\n</body></html>\n");
    write("sweep.html", html)?;
    Ok(())
}

/// A Markdown table (as [`table`] writes it) as an HTML table; `**x**` cells in bold.
fn table_html(markdown: &str) -> String {
    let mut s = String::from("<table>\n");
    for (k, line) in markdown.lines().enumerate() {
        if line.starts_with("|---") {
            continue;
        }
        let tag = if k == 0 { "th" } else { "td" };
        s.push_str("<tr>");
        for cell in line.trim().trim_matches('|').split('|') {
            let cell = dda_report::escape(cell.trim());
            let cell = match cell.strip_prefix("**").and_then(|c| c.strip_suffix("**")) {
                Some(bold) => format!("<b>{bold}</b>"),
                None => cell,
            };
            let _ = write!(s, "<{tag}>{cell}</{tag}>");
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
    s
}

/// The paper's Tables 4 and 5 layout: per model, total steps, OCI cycles and detection
/// cost, one column per detector and r_tol.
pub fn table(rows: &[Row]) -> String {
    let mut cols: Vec<(String, f64)> = rows.iter().map(|r| (r.detector.clone(), r.r_tol)).collect();
    cols.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
    cols.dedup();
    let mut models: Vec<usize> = rows.iter().map(|r| r.model).collect();
    models.sort_unstable();
    models.dedup();
    let mut s = String::from("| model | quantity |");
    for (d, r) in &cols {
        let _ = write!(s, " {d} r_tol={r} |");
    }
    s.push_str("\n|---|---|");
    s.push_str(&"---|".repeat(cols.len()));
    s.push('\n');
    let cell = |m: usize, d: &str, r: f64| {
        rows.iter()
            .find(|x| x.model == m && x.detector == d && x.r_tol == r)
    };
    for m in models {
        for (q, f) in [
            (
                "total steps",
                (|x: &Row| format!("{}", x.steps)) as fn(&Row) -> String,
            ),
            ("OCI cycles", |x: &Row| format!("{}", x.oci_cycles)),
            ("CD cost (s)", |x: &Row| format!("{:.3}", x.detection_s)),
            ("total (s)", |x: &Row| format!("{:.2}", x.total_s)),
            ("permissible", |x: &Row| {
                if x.verdict {
                    "yes".into()
                } else {
                    "**no**".into()
                }
            }),
        ] {
            let _ = write!(s, "| {m} | {q} |");
            for (d, r) in &cols {
                let v = cell(m, d, *r).map(f).unwrap_or_else(|| "-".into());
                let _ = write!(s, " {v} |");
            }
            s.push('\n');
        }
    }
    s
}

/// r_cd = T_type-2(r_tol = 1) / T_cover(r_tol) for each model (paper eq. 16, figs. 21, 25).
fn speedup_plot(rows: &[Row]) -> String {
    let mut series = Vec::new();
    let mut models: Vec<usize> = rows.iter().map(|r| r.model).collect();
    models.sort_unstable();
    models.dedup();
    for m in models {
        let Some(base) = rows
            .iter()
            .find(|r| r.model == m && r.detector == "type-2" && r.r_tol == 1.0)
        else {
            continue;
        };
        let pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.model == m && r.detector == "cover" && r.detection_s > 0.0)
            .map(|r| (r.r_tol, base.detection_s / r.detection_s))
            .collect();
        series.push((format!("{m} blocks"), pts));
    }
    plot(
        "Detection speed-up r_cd = T_type-2(r_tol = 1) / T_cover(r_tol), paper eq. 16",
        "r_tol",
        "r_cd (baseline: type-2 at r_tol = 1)",
        &series,
        true,
        true,
    )
}

/// Steps and OCI cycles against r_tol, cover detector.
fn counts_plot(rows: &[Row]) -> String {
    let mut series = Vec::new();
    let mut models: Vec<usize> = rows.iter().map(|r| r.model).collect();
    models.sort_unstable();
    models.dedup();
    for m in models {
        let cover: Vec<&Row> = rows
            .iter()
            .filter(|r| r.model == m && r.detector == "cover")
            .collect();
        series.push((
            format!("{m}: steps"),
            cover.iter().map(|r| (r.r_tol, r.steps as f64)).collect(),
        ));
        series.push((
            format!("{m}: OCI"),
            cover
                .iter()
                .map(|r| (r.r_tol, r.oci_cycles as f64))
                .collect(),
        ));
    }
    plot(
        "Steps and OCI cycles of the cover detector against r_tol",
        "r_tol",
        "steps, OCI cycles",
        &series,
        true,
        true,
    )
}

/// Accuracy against time on model `m`: each run's largest penetration against its total
/// seconds, one series per detector (a point per r_tol).
fn accuracy_plot(rows: &[Row], m: usize) -> String {
    let mut series = Vec::new();
    let mut detectors: Vec<&str> = rows.iter().map(|r| r.detector.as_str()).collect();
    detectors.sort_unstable();
    detectors.dedup();
    for d in detectors {
        let mut pts: Vec<(f64, f64)> = rows
            .iter()
            .filter(|r| r.model == m && r.detector == d)
            .map(|r| (r.total_s, 1e3 * r.max_penetration))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        series.push((d.to_string(), pts));
    }
    plot(
        &format!("{m}-block column: max penetration against run time (a point per r_tol)"),
        "run time (s)",
        "max penetration (mm)",
        &series,
        false,
        true,
    )
}

/// The models of `rows`, ascending.
fn models_of(rows: &[Row]) -> Vec<usize> {
    let mut models: Vec<usize> = rows.iter().map(|r| r.model).collect();
    models.sort_unstable();
    models.dedup();
    models
}

/// The paper's Tables 4 and 5 as published (Zhuang, Zheng et al. 2021): per column, total
/// steps, OCI cycles and contact-detection seconds, for TB-CD-2 and for CB-CD at r_tol 1,
/// 2, 4, 6, 8 and 10. Shown beside ours for comparison only; never reported as ours.
const PAPER_TABLES: [(usize, &str, [f64; 7]); 12] = [
    (
        20,
        "total steps",
        [644.0, 633.0, 340.0, 183.0, 144.0, 111.0, 105.0],
    ),
    (
        20,
        "OCI cycles",
        [1325.0, 1270.0, 912.0, 569.0, 533.0, 467.0, 441.0],
    ),
    (
        20,
        "CD cost (s)",
        [1.773, 0.754, 0.4284, 0.2448, 0.2081, 0.1655, 0.1577],
    ),
    (
        93,
        "total steps",
        [774.0, 789.0, 427.0, 274.0, 259.0, 220.0, 222.0],
    ),
    (
        93,
        "OCI cycles",
        [2146.0, 2375.0, 1612.0, 1235.0, 1335.0, 1173.0, 1190.0],
    ),
    (
        93,
        "CD cost (s)",
        [43.37, 21.46, 12.34, 8.05, 8.86, 7.7, 8.38],
    ),
    (
        229,
        "total steps",
        [1111.0, 1138.0, 628.0, 433.0, 446.0, 447.0, 426.0],
    ),
    (
        229,
        "OCI cycles",
        [3324.0, 3485.0, 2425.0, 2105.0, 2045.0, 2242.0, 2073.0],
    ),
    (
        229,
        "CD cost (s)",
        [21.25, 15.56, 10.48, 9.68, 10.13, 11.64, 12.06],
    ),
    (
        826,
        "total steps",
        [1227.0, 1333.0, 1001.0, 965.0, 981.0, 1004.0, 971.0],
    ),
    (
        826,
        "OCI cycles",
        [5226.0, 6051.0, 5690.0, 5811.0, 5883.0, 6030.0, 5783.0],
    ),
    (
        826,
        "CD cost (s)",
        [111.3, 107.3, 106.1, 108.4, 144.6, 172.3, 191.49],
    ),
];

/// Our sweep beside the paper's Tables 4 and 5: the same quantities, ours from this
/// sweep (type-2 at r_tol 1, cover at each r_tol), the paper's as published.
fn beside_the_paper(rows: &[Row]) -> String {
    let rtols = [1.0, 2.0, 4.0, 6.0, 8.0, 10.0];
    let mut s = String::from(
        "<h2>Beside the paper's Tables 4 and 5</h2>\n<p>The paper's numbers as published \
         (its code, its machine), ours from this sweep. Counts compare; seconds do not \
         (a different code on a different machine), only their ratios along a row.</p>\n\
         <table>\n<tr><th>model</th><th>quantity</th><th>from</th><th>TB-CD-2</th>",
    );
    for r in rtols {
        let _ = write!(s, "<th>CB-CD r_tol={r}</th>");
    }
    s.push_str("</tr>\n");
    let find = |m: usize, d: &str, r: f64| {
        rows.iter()
            .find(|x| x.model == m && x.detector == d && x.r_tol == r)
    };
    for (m, q, paper) in PAPER_TABLES {
        let ours = |x: &Row| -> String {
            match q {
                "total steps" => x.steps.to_string(),
                "OCI cycles" => x.oci_cycles.to_string(),
                _ if x.detection_s < 0.01 => format!("{:.1e}", x.detection_s),
                _ => format!("{:.3}", x.detection_s),
            }
        };
        let _ = write!(s, "<tr><td>{m}</td><td>{q}</td><td>the paper</td>");
        for v in paper {
            let _ = write!(s, "<td>{v}</td>");
        }
        let _ = write!(s, "</tr>\n<tr><td>{m}</td><td>{q}</td><td><b>ours</b></td>");
        let base = find(m, "type-2", 1.0).map_or("-".into(), ours);
        let _ = write!(s, "<td>{base}</td>");
        for r in rtols {
            let v = find(m, "cover", r).map_or("-".into(), ours);
            let _ = write!(s, "<td>{v}</td>");
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
    s
}

/// The page's first paragraphs: the sweep's result in words, from its numbers.
fn conclusion(rows: &[Row]) -> String {
    let mut s = String::new();
    let find = |m: usize, d: &str, r: f64| {
        rows.iter()
            .find(|x| x.model == m && x.detector == d && x.r_tol == r)
    };
    let mut rtols: Vec<f64> = rows.iter().map(|r| r.r_tol).collect();
    rtols.sort_by(f64::total_cmp);
    rtols.dedup();
    let (Some(&lo), Some(&hi)) = (rtols.first(), rtols.last()) else {
        return s;
    };
    s.push_str("<ul>\n");
    for m in models_of(rows) {
        let (Some(a), Some(b)) = (find(m, "cover", lo), find(m, "cover", hi)) else {
            continue;
        };
        let _ = writeln!(
            s,
            "<li>{m}-block column, cover detector: raising r_tol from {lo} to {hi} takes the run \
             from {} to {} steps and from {:.2} s to {:.2} s ({:.2} times the time), while its \
             largest penetration goes from {:.3} mm to {:.3} mm; {}.</li>",
            a.steps,
            b.steps,
            a.total_s,
            b.total_s,
            b.total_s / a.total_s.max(f64::MIN_POSITIVE),
            1e3 * a.max_penetration,
            1e3 * b.max_penetration,
            if a.verdict && b.verdict {
                "both runs permissible"
            } else {
                "not both runs permissible"
            }
        );
    }
    for d in ["type-1", "type-2", "cover"] {
        let all: Vec<&Row> = rows.iter().filter(|r| r.detector == d).collect();
        if all.is_empty() {
            continue;
        }
        let good = all.iter().filter(|r| r.verdict).count();
        let _ = writeln!(s, "<li>{d}: {good} of {} runs permissible.</li>", all.len());
    }
    if let Some(m) = models_of(rows).last()
        && let Some(base) = find(*m, "type-2", lo)
    {
        let best = rows
            .iter()
            .filter(|r| r.model == *m && r.detector == "cover" && r.detection_s > 0.0)
            .map(|r| (base.detection_s / r.detection_s, r.r_tol))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((r_cd, at)) = best {
            let _ = writeln!(
                s,
                "<li>Detection speed-up r_cd against the type-2 detector at r_tol = {lo} (the \
                 baseline, paper eq. 16) on the {m}-block column: up to {r_cd:.1} at r_tol = {at}.</li>"
            );
        }
    }
    s.push_str("</ul>\n");
    s
}
