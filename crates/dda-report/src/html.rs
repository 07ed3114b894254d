//! report.html: one self-contained page (no network) per run: an animation of the
//! blocks (play/pause, a time slider, blocks coloured by speed, fixed blocks grey, active
//! contacts marked), time histories, the summary with any failure diagnosis, and the
//! effects and parameters used.

use super::{Frame, counted, escape, plot, shown};
use dda_core::{Model, Scene, Summary};
use dda_geom::Aabb;
use std::fmt::Write as _;

/// One row of history.csv, the columns the report plots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HistoryRow {
    /// Simulated time at the end of the step, s.
    pub t: f64,
    /// Step size, s.
    pub dt: f64,
    /// OCI iterations of the step.
    pub oci: f64,
    /// Active contacts after the step.
    pub active_contacts: f64,
    /// Largest penetration after the step, m.
    pub max_penetration: f64,
    /// Kinetic energy after the step, J/m (per metre of thickness: the model is 2D).
    pub kinetic_energy: f64,
}

/// Reads history.csv (with its header); errors name the line.
pub fn parse_history(text: &str) -> Result<Vec<HistoryRow>, String> {
    let names = [
        "t",
        "dt",
        "oci",
        "active_contacts",
        "max_penetration",
        "kinetic_energy",
    ];
    csv_columns(text, &names)?
        .into_iter()
        .map(|(line, c)| {
            let n = |k: usize| number(&c[k], line, names[k]);
            Ok(HistoryRow {
                t: n(0)?,
                dt: n(1)?,
                oci: n(2)?,
                active_contacts: n(3)?,
                max_penetration: n(4)?,
                kinetic_energy: n(5)?,
            })
        })
        .collect()
}

/// One row of measurements.csv, the columns the report plots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointRow {
    /// Simulated time, s.
    pub t: f64,
    /// The measured point's id.
    pub id: String,
    /// Displacement since the start, m.
    pub u: [f64; 2],
    /// Velocity, m/s.
    pub v: [f64; 2],
}

/// One row of bolts.csv, the columns the report plots.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BoltRow {
    /// Simulated time, s.
    pub t: f64,
    /// The bolt's index in the scene.
    pub bolt: usize,
    /// Its tension, N; None once broken or excavated.
    pub tension: Option<f64>,
}

/// The rows of a CSV `text` with a header, each as its `names` columns' cells (line
/// number first); errors name the line.
fn csv_columns(text: &str, names: &[&str]) -> Result<Vec<(u64, Vec<String>)>, String> {
    let mut reader = csv::ReaderBuilder::new().from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| format!("line 1: {e}"))?
        .clone();
    let cols = names
        .iter()
        .map(|name| {
            header
                .iter()
                .position(|h| h == *name)
                .ok_or_else(|| format!("line 1: no column `{name}`"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut rows = Vec::new();
    for record in reader.records() {
        let record = record.map_err(|e| match e.position() {
            Some(p) => format!("line {}: {e}", p.line()),
            None => e.to_string(),
        })?;
        let line = record.position().map_or(0, |p| p.line());
        let cells = cols
            .iter()
            .map(|&c| record.get(c).unwrap_or_default().to_string())
            .collect();
        rows.push((line, cells));
    }
    Ok(rows)
}

/// `cell` as a number, or the error naming `line` and `name`.
fn number(cell: &str, line: u64, name: &str) -> Result<f64, String> {
    cell.parse::<f64>()
        .map_err(|_| format!("line {line}: column {name} is not a number"))
}

/// Reads measurements.csv (with its header); errors name the line.
pub fn parse_points(text: &str) -> Result<Vec<PointRow>, String> {
    let names = ["t", "id", "ux", "uy", "vx", "vy"];
    csv_columns(text, &names)?
        .into_iter()
        .map(|(line, c)| {
            let n = |k: usize| number(&c[k], line, names[k]);
            Ok(PointRow {
                t: n(0)?,
                id: c[1].clone(),
                u: [n(2)?, n(3)?],
                v: [n(4)?, n(5)?],
            })
        })
        .collect()
}

/// Reads bolts.csv (with its header); errors name the line.
pub fn parse_bolts(text: &str) -> Result<Vec<BoltRow>, String> {
    csv_columns(text, &["t", "bolt", "tension"])?
        .into_iter()
        .map(|(line, c)| {
            Ok(BoltRow {
                t: number(&c[0], line, "t")?,
                bolt: c[1]
                    .parse()
                    .map_err(|_| format!("line {line}: column bolt is not an index"))?,
                tension: match c[2].as_str() {
                    "" => None,
                    x => Some(number(x, line, "tension")?),
                },
            })
        })
        .collect()
}

/// What report.html shows.
#[derive(Debug)]
pub struct Report<'a> {
    /// The scene as run (its analysis table is shown).
    pub scene: &'a Scene,
    /// The validated scene.
    pub model: &'a Model,
    /// summary.json.
    pub summary: &'a Summary,
    /// history.csv.
    pub history: &'a [HistoryRow],
    /// measurements.csv (empty without measured points).
    pub points: &'a [PointRow],
    /// bolts.csv (empty without bolts).
    pub bolts: &'a [BoltRow],
    /// frames.jsonl.
    pub frames: &'a [Frame],
    /// The box the animation shows.
    pub view: Aabb,
}

/// Most points a time-history plot draws (longer histories are thinned evenly).
const PLOT_POINTS: usize = 1500;

/// The page, self-contained.
pub fn report_html(r: &Report) -> String {
    let s = r.summary;
    let mut page = String::new();
    let title = format!("dda: {}", escape(&s.scene));
    let _ = write!(
        page,
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; max-width: 1100px; }}
table {{ border-collapse: collapse; margin-bottom: 1em; }}
td, th {{ border: 1px solid #ccc; padding: 2px 8px; text-align: left; }}
.failed {{ color: #b00020; }}
#controls {{ display: flex; gap: 1em; align-items: center; margin: 0.5em 0; }}
#viewing {{ margin: 0.3em 0; font-size: 90%; }}
#viewing label {{ margin-right: 1em; }}
#hover {{ font-weight: bold; }}
#slider {{ flex: 1; }}
canvas {{ border: 1px solid #ccc; background: #fff; max-width: 100%; }}
.plots {{ display: flex; flex-wrap: wrap; gap: 0.5em; }}
.plots svg {{ width: 540px; height: auto; }}
</style></head><body>
<h1>{title}</h1>
"#
    );
    let status_class = if s.status == "completed" {
        ""
    } else {
        "failed"
    };
    let _ = writeln!(
        page,
        r#"<p class="{status_class}" id="status">{}: {} s simulated in {} ({}), detector {}{}, {:.3} s wall.</p>"#,
        escape(&s.status),
        shown(s.time_simulated),
        counted(s.steps, "step"),
        counted(s.oci_iterations, "OCI iteration"),
        escape(&s.detector),
        s.integration
            .as_ref()
            .map_or(String::new(), |r| format!(", integration {}", escape(r))),
        s.seconds.total
    );
    if let Some(f) = &s.failure {
        let _ = writeln!(
            page,
            r#"<h2 class="failed">Why the run stopped</h2><p class="failed">{}</p>
<p>Last good state at t = {} s; the last step size tried was {:.3e} s. Blocks involved: {}.</p>"#,
            escape(&f.reason),
            shown(f.t),
            f.last_dt,
            if f.blocks.is_empty() {
                "none singled out".to_string()
            } else {
                escape(&f.blocks.join(", "))
            }
        );
        if !f.contacts.is_empty() {
            page.push_str(
                "<table><tr><th>vertex block</th><th>vertex</th><th>edge block</th>\
                 <th>edge</th><th>state</th><th>d_n (m)</th></tr>\n",
            );
            for c in &f.contacts {
                let _ = writeln!(
                    page,
                    "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.3e}</td></tr>",
                    escape(&c.vertex_block),
                    c.vertex,
                    escape(&c.edge_block),
                    c.edge,
                    escape(&c.state),
                    c.d_n
                );
            }
            page.push_str("</table>\n");
        }
    }

    // The animation.
    let size = r.view.size();
    let (cw, ch) = (800.0, (800.0 * size.y / size.x).clamp(150.0, 900.0));
    let _ = writeln!(
        page,
        r#"<h2>Animation</h2>
<div id="controls"><button id="play" type="button">Play</button>
<input id="slider" type="range" min="0" max="{}" value="0" step="1" aria-label="time">
<span id="time"></span></div>
<div id="viewing"><button id="fit" type="button">Fit all</button> <label><input id="follow" type="checkbox"> Follow the moving blocks</label> <span>Wheel: zoom; drag: pan; hover a block for its id. Scale bar: <span id="scale"></span>.</span> <span id="hover"></span></div>
<canvas id="view" width="{cw:.0}" height="{ch:.0}"></canvas>
<p>{colour_by}Blocks coloured by <span id="legend"></span>; fixed blocks grey; red dots: active closed contacts; dashed: the rock an excavation removes; green lines: bolts (until they break); black squares: measured points.</p>"#,
        r.frames.len().saturating_sub(1),
        colour_by = if r.frames.iter().any(|f| !f.stress.is_empty()) {
            r#"<label>Colour by <select id="colour"><option value="speed">speed</option><option value="s1">major principal stress</option><option value="s3">minor principal stress</option><option value="mean">mean normal stress</option></select></label> "#
        } else {
            ""
        }
    );

    // Time histories.
    let series = |f: fn(&HistoryRow) -> f64| {
        envelope(&r.history.iter().map(|h| (h.t, f(h))).collect::<Vec<_>>())
    };
    page.push_str("<h2>Time histories</h2>\n");
    if r.history.len() > PLOT_POINTS {
        let _ = writeln!(
            page,
            "<p>{} steps, plotted as the largest and smallest value over each {} steps.</p>",
            r.history.len(),
            r.history.len().div_ceil(PLOT_POINTS)
        );
    }
    page.push_str("<div class=\"plots\">\n");
    for (title, ylabel, f) in [
        (
            "Kinetic energy",
            "J/m",
            (|r: &HistoryRow| r.kinetic_energy) as fn(&HistoryRow) -> f64,
        ),
        ("Time step", "dt (s)", |r: &HistoryRow| r.dt),
        ("OCI iterations per step", "iterations", |r: &HistoryRow| {
            r.oci
        }),
        ("Active contacts", "contacts", |r: &HistoryRow| {
            r.active_contacts
        }),
        ("Largest penetration", "mm", |r: &HistoryRow| {
            1e3 * r.max_penetration
        }),
    ] {
        page.push_str(&plot(title, "t (s)", ylabel, &series(f), true, false));
    }
    page.push_str("</div>\n");
    point_and_bolt_plots(&mut page, r);

    // Summary and parameters.
    page.push_str("<h2>Summary</h2>\n<table>\n");
    let rows: [(&str, String); 14] = [
        ("scene", s.scene.clone()),
        (
            "made from",
            s.source.clone().unwrap_or_else(|| "(not recorded)".into()),
        ),
        ("detector", s.detector.clone()),
        ("status", s.status.clone()),
        ("simulated time (s)", shown(s.time_simulated)),
        ("steps", s.steps.to_string()),
        ("OCI iterations", s.oci_iterations.to_string()),
        ("time-step cuts", s.time_step_cuts.to_string()),
        ("unknowns", s.unknowns.to_string()),
        if s.iterative_solves > 0 {
            (
                "iterative solves (conjugate-gradient iterations)",
                format!("{} ({})", s.iterative_solves, s.cg_iterations),
            )
        } else {
            (
                "factorisations (symbolic / numeric / low-rank solves)",
                format!(
                    "{} / {} / {}",
                    s.symbolic_factorisations, s.numeric_factorisations, s.low_rank_solves
                ),
            )
        },
        (
            "wall seconds (total / detection / assembly / solve)",
            format!(
                "{:.3} / {:.3} / {:.3} / {:.3}",
                s.seconds.total, s.seconds.contact_detection, s.seconds.assembly, s.seconds.solve
            ),
        ),
        ("max penetration (m)", format!("{:.3e}", s.max_penetration)),
        ("blocks", r.model.blocks.len().to_string()),
        (
            "settling before t = 0 (static steps, wall seconds)",
            match s.settling {
                Some(st) => format!(
                    "{}, {:.3}{}{}",
                    st.static_steps,
                    st.seconds,
                    match (st.converged, st.kept_step) {
                        (true, _) => String::new(),
                        (false, Some(k)) => format!(
                            "; stopped without converging, the run starting from its \
                             steadiest, static step {k}"
                        ),
                        (false, None) => "; stopped without converging, the run starting \
                                          from its last static step"
                            .to_string(),
                    },
                    st.solver
                        .map(|s| format!("; solved {}", s.adverb()))
                        .unwrap_or_default()
                ),
                None => "none".into(),
            },
        ),
    ];
    for (k, v) in rows {
        let _ = writeln!(page, "<tr><th>{k}</th><td>{}</td></tr>", escape(&v));
    }
    page.push_str("</table>\n<h2>Effects and parameters</h2>\n<table>\n");
    let _ = writeln!(
        page,
        "<tr><th>effects assembled</th><td>{}</td></tr>",
        escape(&s.effects.join(", "))
    );
    let p = &r.model.params;
    for (k, v) in [
        ("contact tolerance d_tol (m)", p.d_tol.to_string()),
        ("max displacement d_max (m)", p.d_max.to_string()),
    ] {
        let _ = writeln!(page, "<tr><th>{k}</th><td>{}</td></tr>", escape(&v));
    }
    if let Ok(serde_json::Value::Object(analysis)) = serde_json::to_value(&r.scene.analysis) {
        for (k, v) in analysis {
            if v.is_null() {
                continue;
            }
            let _ = writeln!(
                page,
                "<tr><th>analysis.{}</th><td>{}</td></tr>",
                escape(&k),
                escape(&v.to_string())
            );
        }
    }
    page.push_str("</table>\n");
    materials_and_joints(&mut page, r.scene);

    // Data and script.
    // The page draws at a hundredth of frames.jsonl's resolution (1e-4 of the view,
    // 10,000 steps across it: below a pixel at a hundred times zoom), which packs the
    // frames in a third of the space; frames.jsonl keeps the full resolution.
    let per_metre = (0.01 / crate::frame_resolution(&r.view)).round().max(1.0);
    let packed = crate::pack_frames(r.frames, per_metre);
    let data = serde_json::json!({
        "view": [r.view.min.x, r.view.min.y, r.view.max.x, r.view.max.y],
        "fixed": r.model.blocks.iter().map(|b| b.fixed).collect::<Vec<_>>(),
        "ids": r.model.blocks.iter().map(|b| b.id.as_str()).collect::<Vec<_>>(),
        // The frames packed (see `packed`), or as JSON when they do not pack.
        "packed": packed,
        "frames": if packed.is_some() { &[] } else { r.frames },
        // Where each block's outline is drawn (null: whole): parts of a body are drawn
        // without their glued stretches.
        "drawn": crate::drawn_edges(r.model),
        // The blocks excavations remove, as they stood at the start: their outlines are
        // drawn dashed throughout, so the excavation shows before and after.
        "excavated": r
            .model
            .blocks
            .iter()
            .filter(|b| b.removed_at.is_some())
            .map(|b| {
                b.polygon
                    .vertices()
                    .iter()
                    .flat_map(|v| [v.x, v.y])
                    .collect::<Vec<f64>>()
            })
            .collect::<Vec<_>>(),
        // Bolts (both ends as affine coordinates in their blocks, and when they broke)
        // and measured points, drawn where their blocks carry them.
        "bolts": r
            .model
            .bolts
            .iter()
            .enumerate()
            .map(|(k, b)| {
                let at = |block: usize, p| {
                    dda_core::affine_coordinates(r.model.blocks[block].polygon.vertices(), p)
                };
                let broken = s.bolts.get(k).and_then(|x| x.broken).map(|x| x.t);
                serde_json::json!([b.from_block, at(b.from_block, b.from), b.to_block, at(b.to_block, b.to), broken])
            })
            .collect::<Vec<_>>(),
        "points": r
            .model
            .measures
            .iter()
            .map(|m| {
                let ab = dda_core::affine_coordinates(r.model.blocks[m.block].polygon.vertices(), m.at);
                serde_json::json!([m.block, ab, m.id])
            })
            .collect::<Vec<_>>(),
    });
    // "</" cannot appear inside a script element.
    let data = data.to_string().replace("</", "<\\/");
    let _ = write!(
        page,
        "<script id=\"data\" type=\"application/json\">{data}</script>\n<script>\n{SCRIPT}</script>\n</body></html>\n"
    );
    page
}

/// The tables of the scene's materials and joints, with their units.
fn materials_and_joints(page: &mut String, scene: &Scene) {
    let opt = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:e}"));
    page.push_str(
        "<h2>Materials and joints</h2>\n<table>\n<tr><th>material</th><th>density (kg/m^3)</th>\
         <th>Young's modulus (Pa)</th><th>Poisson's ratio</th></tr>\n",
    );
    for (name, m) in &scene.materials {
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(name),
            m.density,
            opt(m.young),
            m.poisson.map_or("-".to_string(), |x| x.to_string())
        );
    }
    page.push_str(
        "</table>\n<table>\n<tr><th>joint</th><th>friction (degrees)</th>\
         <th>cohesion (Pa)</th><th>tensile strength (Pa)</th><th>between</th></tr>\n",
    );
    for (name, j) in &scene.joints {
        let between = j
            .between
            .as_ref()
            .map_or("(where named)".to_string(), |[a, b]| format!("{a} / {b}"));
        let between = if name == "default" && j.between.is_none() {
            "every other pair".to_string()
        } else {
            between
        };
        let _ = writeln!(
            page,
            "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>",
            escape(name),
            j.friction_deg,
            j.cohesion,
            j.tensile_strength,
            escape(&between)
        );
    }
    page.push_str("</table>\n");
}

/// Most measured points the report plots (each has two plots); the others are in
/// measurements.csv.
const PLOTTED_POINTS: usize = 12;

/// The plots of the measured points (displacement and velocity against time, one pair
/// per point) and of the bolts' tensions, when the run has them.
fn point_and_bolt_plots(page: &mut String, r: &Report) {
    if !r.points.is_empty() {
        let mut ids: Vec<&str> = Vec::new();
        for p in r.points {
            if !ids.contains(&p.id.as_str()) {
                ids.push(&p.id);
            }
        }
        page.push_str("<h2>Measured points</h2>\n");
        if ids.len() > PLOTTED_POINTS {
            let _ = writeln!(
                page,
                "<p>The first {PLOTTED_POINTS} of {} points; every point is in measurements.csv.</p>",
                ids.len()
            );
        }
        page.push_str("<div class=\"plots\">\n");
        for id in ids.iter().take(PLOTTED_POINTS) {
            let rows: Vec<&PointRow> = r.points.iter().filter(|p| p.id == *id).collect();
            for (what, unit, f) in [
                (
                    "Displacement",
                    "m",
                    (|p: &PointRow| p.u) as fn(&PointRow) -> [f64; 2],
                ),
                ("Velocity", "m/s", |p: &PointRow| p.v),
            ] {
                let mut series = Vec::new();
                for (c, axis) in ["x", "y"].iter().enumerate() {
                    let points: Vec<(f64, f64)> = rows.iter().map(|p| (p.t, f(p)[c])).collect();
                    for (name, s) in envelope(&points) {
                        let name = if name.is_empty() {
                            axis.to_string()
                        } else {
                            format!("{axis} {name}")
                        };
                        series.push((name, s));
                    }
                }
                let title = format!("{what} of `{id}`");
                page.push_str(&plot(&title, "t (s)", unit, &series, true, false));
            }
        }
        page.push_str("</div>\n");
    }
    if !r.bolts.is_empty() {
        let n = r.bolts.iter().map(|b| b.bolt + 1).max().unwrap_or(0);
        let mut series = Vec::new();
        for k in 0..n {
            let points: Vec<(f64, f64)> = r
                .bolts
                .iter()
                .filter(|b| b.bolt == k)
                .filter_map(|b| b.tension.map(|x| (b.t, 1e-3 * x)))
                .collect();
            for (name, s) in envelope(&points) {
                series.push((format!("bolt {k} {name}").trim_end().to_string(), s));
            }
        }
        page.push_str("<h2>Bolts</h2>\n<div class=\"plots\">\n");
        page.push_str(&plot(
            "Bolt tension (compression negative; a line ends where its bolt broke)",
            "t (s)",
            "kN",
            &series,
            true,
            false,
        ));
        page.push_str("</div>\n");
    }
}

/// The series of (t, y) `points` for a plot: every point when there are at most
/// [`PLOT_POINTS`]; else, over each run of `points.len() / PLOT_POINTS` points (rounded
/// up), its largest and smallest value at the time of the point that has it (two series,
/// `max` and `min`), so that every peak is plotted as recorded.
fn envelope(points: &[(f64, f64)]) -> Vec<(String, Vec<(f64, f64)>)> {
    if points.len() <= PLOT_POINTS {
        return vec![(String::new(), points.to_vec())];
    }
    let stride = points.len().div_ceil(PLOT_POINTS);
    let (mut high, mut low) = (Vec::new(), Vec::new());
    for run in points.chunks(stride) {
        let by = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
        high.extend(run.iter().max_by(by).copied());
        low.extend(run.iter().min_by(by).copied());
    }
    vec![("max".into(), high), ("min".into(), low)]
}

/// The page's script: draws frame k of the data on the canvas; play/pause and the slider
/// move k. `window.ddaReport` exposes the current frame for tests.
const SCRIPT: &str = r##""use strict";
// The frames, unpacked from `data.packed` (see dda_report's `packed`) or as given.
async function ddaFrames(data) {
  if (data.packed === null || data.packed === undefined) return data.frames;
  const bin = Uint8Array.from(atob(data.packed), (c) => c.charCodeAt(0));
  const stream = new Blob([bin]).stream().pipeThrough(new DecompressionStream("deflate"));
  const buf = await new Response(stream).arrayBuffer();
  const v = new DataView(buf);
  let o = 0;
  const u32 = () => { const x = v.getUint32(o, true); o += 4; return x; };
  const nf = u32(), nb = u32();
  const pm = v.getFloat64(o, true); o += 8;
  const frames = [];
  let last = Array.from({ length: nb }, () => null);
  for (let k = 0; k < nf; k++) {
    const f = { t: v.getFloat64(o, true) }; o += 8;
    f.svg = v.getUint8(o) === 1; o += 1;
    const hasStress = v.getUint8(o) === 1; o += 1;
    f.blocks = [];
    for (let i = 0; i < nb; i++) {
      const n = v.getUint16(o, true); o += 2;
      const prev = last[i];
      const same = prev !== null && prev.length === 2 * n;
      const now = new Array(2 * n);
      for (let j = 0; j < 2 * n; j++) {
        const d = v.getInt32(o, true); o += 4;
        now[j] = same ? (prev[j] + d) | 0 : d;
      }
      last[i] = now;
      f.blocks.push(now.map((c) => c / pm));
    }
    f.speed = [];
    for (let i = 0; i < nb; i++) { f.speed.push(v.getFloat32(o, true)); o += 4; }
    if (hasStress) {
      f.stress = [];
      for (let i = 0; i < 3 * nb; i++) { f.stress.push(v.getFloat32(o, true)); o += 4; }
    }
    const nc = u32();
    f.contacts = [];
    for (let j = 0; j < 2 * nc; j++) { f.contacts.push(v.getInt32(o, true) / pm); o += 4; }
    frames.push(f);
  }
  return frames;
}
(async function () {
  const data = JSON.parse(document.getElementById("data").textContent);
  const frames = await ddaFrames(data);
  const canvas = document.getElementById("view");
  const ctx = canvas.getContext("2d");
  const slider = document.getElementById("slider");
  const play = document.getElementById("play");
  const label = document.getElementById("time");
  // The view: the world point at the canvas's lower-left corner and pixels a metre.
  // The axes take AXES pixels at the left and the bottom.
  const AXES = 40;
  let view = { x0: 0, y0: 0, scale: 1 };
  function fitTo(bx0, by0, bx1, by1) {
    const w = canvas.width - AXES - 10, h = canvas.height - AXES - 10;
    const dx = Math.max(bx1 - bx0, 1e-9), dy = Math.max(by1 - by0, 1e-9);
    const s = Math.min(w / dx, h / dy);
    view = {
      scale: s,
      x0: bx0 - (w / s - dx) / 2 - AXES / s,
      y0: by0 - (h / s - dy) / 2 - AXES / s,
    };
  }
  const fitAll = () => fitTo(data.view[0], data.view[1], data.view[2], data.view[3]);
  fitAll();
  const px = (x) => (x - view.x0) * view.scale;
  const py = (y) => canvas.height - (y - view.y0) * view.scale;
  const wx = (p) => view.x0 + p / view.scale;
  const wy = (q) => view.y0 + (canvas.height - q) / view.scale;
  // 1, 2 or 5 times a power of ten, the smallest at least `raw`.
  function niceStep(raw) {
    const mag = Math.pow(10, Math.floor(Math.log10(raw)));
    for (const f of [1, 2, 5, 10]) { if (f * mag >= raw) return f * mag; }
    return 10 * mag;
  }
  const fmt = (v, step) => {
    const d = Math.max(0, -Math.floor(Math.log10(step)));
    return Math.abs(v) < 1e-12 ? "0" : v.toFixed(Math.min(d, 6));
  };
  const follow = document.getElementById("follow");
  const hoverEl = document.getElementById("hover");
  const scaleEl = document.getElementById("scale");
  function followBlocks(f) {
    let bx0 = Infinity, by0 = Infinity, bx1 = -Infinity, by1 = -Infinity;
    f.blocks.forEach((b, i) => {
      if (data.fixed[i]) return;
      for (let j = 0; j < b.length; j += 2) {
        bx0 = Math.min(bx0, b[j]); bx1 = Math.max(bx1, b[j]);
        by0 = Math.min(by0, b[j + 1]); by1 = Math.max(by1, b[j + 1]);
      }
    });
    if (bx1 > bx0) {
      const pad = 0.1 * Math.max(bx1 - bx0, by1 - by0);
      fitTo(bx0 - pad, by0 - pad, bx1 + pad, by1 + pad);
    }
  }
  // Axes in metres along the left and bottom, and a scale bar.
  function drawAxes() {
    const w = canvas.width, h = canvas.height;
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, AXES, h);
    ctx.fillRect(0, h - AXES, w, AXES);
    ctx.strokeStyle = "#000000";
    ctx.lineWidth = 1;
    ctx.beginPath();
    ctx.moveTo(AXES, 0); ctx.lineTo(AXES, h - AXES); ctx.lineTo(w, h - AXES);
    ctx.stroke();
    ctx.fillStyle = "#000000";
    ctx.font = "11px sans-serif";
    const step = niceStep(90 / view.scale);
    ctx.textAlign = "center";
    for (let x = Math.ceil(wx(AXES) / step) * step; px(x) <= w - 10; x += step) {
      ctx.beginPath(); ctx.moveTo(px(x), h - AXES); ctx.lineTo(px(x), h - AXES + 5); ctx.stroke();
      ctx.fillText(fmt(x, step), px(x), h - AXES + 17);
    }
    ctx.fillText("x (m)", (AXES + w) / 2, h - 6);
    // Labels too long for the margin (coordinates of a survey grid, 4000020) run
    // along the axis instead of across it.
    const ys = [];
    for (let y = Math.ceil(wy(h - AXES) / step) * step; py(y) >= 10; y += step) ys.push(y);
    const along = ys.some((y) => ctx.measureText(fmt(y, step)).width > AXES - 11);
    ctx.textAlign = along ? "center" : "right";
    for (const y of ys) {
      ctx.beginPath(); ctx.moveTo(AXES, py(y)); ctx.lineTo(AXES - 5, py(y)); ctx.stroke();
      if (along) {
        ctx.save();
        ctx.translate(AXES - 9, py(y));
        ctx.rotate(-Math.PI / 2);
        ctx.fillText(fmt(y, step), 0, 0);
        ctx.restore();
      } else {
        ctx.fillText(fmt(y, step), AXES - 7, py(y) + 4);
      }
    }
    ctx.save();
    ctx.translate(11, (h - AXES) / 2);
    ctx.rotate(-Math.PI / 2);
    ctx.textAlign = "center";
    ctx.fillText("y (m)", 0, 0);
    ctx.restore();
    // The scale bar: a nice length near a fifth of the view's width.
    const bar = niceStep((w - AXES) / 5 / view.scale);
    const bx = w - 20 - bar * view.scale, by = h - AXES - 14;
    ctx.lineWidth = 3;
    ctx.beginPath(); ctx.moveTo(bx, by); ctx.lineTo(bx + bar * view.scale, by); ctx.stroke();
    ctx.lineWidth = 1;
    ctx.textAlign = "center";
    ctx.fillText(fmt(bar, bar) + " m", bx + bar * view.scale / 2, by - 6);
    scaleEl.textContent = fmt(bar, bar) + " m";
  }
  // The block under canvas point (p, q) in frame f, the last drawn first; -1 if none.
  function blockAt(f, p, q) {
    const x = wx(p), y = wy(q);
    for (let i = f.blocks.length - 1; i >= 0; i--) {
      const b = f.blocks[i], n = b.length / 2;
      if (n < 3) continue;
      let inside = true;
      for (let j = 0; j < n && inside; j++) {
        const ax = b[2 * j], ay = b[2 * j + 1];
        const bx = b[(2 * j + 2) % (2 * n)], by = b[(2 * j + 3) % (2 * n)];
        inside = (bx - ax) * (y - ay) - (by - ay) * (x - ax) >= 0;
      }
      if (inside) return i;
    }
    return -1;
  }
  // What colours a block: its speed, or a measure of its stress (tension positive).
  const measures = {
    speed: { name: "speed", unit: "m/s", of: (f, i) => f.speed[i] },
    s1: { name: "major principal stress", unit: "kPa", of: (f, i) => principal(f, i, 1) },
    s3: { name: "minor principal stress", unit: "kPa", of: (f, i) => principal(f, i, -1) },
    mean: { name: "mean normal stress", unit: "kPa", of: (f, i) => 0.5e-3 * (f.stress[3 * i] + f.stress[3 * i + 1]) },
  };
  function principal(f, i, sign) {
    const [a, b, c] = [f.stress[3 * i], f.stress[3 * i + 1], f.stress[3 * i + 2]];
    return 1e-3 * (0.5 * (a + b) + sign * Math.hypot(0.5 * (a - b), c));
  }
  const select = document.getElementById("colour");
  let measure = measures.speed, lo = 0, hi = 0;
  function setMeasure() {
    measure = measures[select ? select.value : "speed"];
    lo = measure === measures.speed ? 0 : Infinity;
    hi = measure === measures.speed ? 0 : -Infinity;
    for (const f of frames) {
      f.speed.forEach((_, i) => {
        if (data.fixed[i] || f.blocks[i].length === 0) return;
        const v = measure.of(f, i);
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      });
    }
    if (!(hi > lo)) { hi = lo + 1; }
    document.getElementById("legend").textContent = measure.name + ", from blue (" +
      lo.toPrecision(3) + " " + measure.unit + ") to red (" + hi.toPrecision(3) + " " + measure.unit + ")";
  }
  setMeasure();
  const colour = (f, i) => {
    const s = Math.min(Math.max((measure.of(f, i) - lo) / (hi - lo), 0), 1);
    return "hsl(" + (240 - 240 * s).toFixed(0) + ", 75%, 60%)";
  };
  let k = 0;
  let timer = null;
  function draw() {
    const f = frames[k];
    if (follow.checked) followBlocks(f);
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(0, 0, canvas.width, canvas.height);
    ctx.lineWidth = 0.6;
    ctx.strokeStyle = "#000000";
    f.blocks.forEach((b, i) => {
      ctx.beginPath();
      for (let j = 0; j < b.length; j += 2) {
        if (j === 0) ctx.moveTo(px(b[j]), py(b[j + 1]));
        else ctx.lineTo(px(b[j]), py(b[j + 1]));
      }
      ctx.closePath();
      ctx.fillStyle = data.fixed[i] ? "#b0b0b0" : colour(f, i);
      ctx.fill();
      const parts = data.drawn[i];
      if (parts === null) {
        ctx.stroke();
        return;
      }
      // A part of a body: its fill's colour over the seams, black where not glued.
      ctx.strokeStyle = ctx.fillStyle;
      ctx.stroke();
      ctx.strokeStyle = "#000000";
      ctx.beginPath();
      const n = b.length / 2;
      for (const [e, s0, s1] of parts) {
        const x0 = b[2 * e], y0 = b[2 * e + 1];
        const x1 = b[(2 * e + 2) % (2 * n)], y1 = b[(2 * e + 3) % (2 * n)];
        ctx.moveTo(px(x0 + s0 * (x1 - x0)), py(y0 + s0 * (y1 - y0)));
        ctx.lineTo(px(x0 + s1 * (x1 - x0)), py(y0 + s1 * (y1 - y0)));
      }
      ctx.stroke();
    });
    ctx.setLineDash([4, 3]);
    ctx.strokeStyle = "#404040";
    data.excavated.forEach((b) => {
      ctx.beginPath();
      for (let j = 0; j < b.length; j += 2) {
        if (j === 0) ctx.moveTo(px(b[j]), py(b[j + 1]));
        else ctx.lineTo(px(b[j]), py(b[j + 1]));
      }
      ctx.closePath();
      ctx.stroke();
    });
    ctx.setLineDash([]);
    // A material point of block i in frame f, from its affine coordinates.
    const at = (f, i, [a, b]) => {
      const v = f.blocks[i];
      return [v[0] + a * (v[2] - v[0]) + b * (v[4] - v[0]), v[1] + a * (v[3] - v[1]) + b * (v[5] - v[1])];
    };
    ctx.strokeStyle = "#006400";
    ctx.lineWidth = 2;
    for (const [i, ai, j, aj, broken] of data.bolts) {
      if (f.blocks[i].length === 0 || f.blocks[j].length === 0 || (broken !== null && f.t >= broken)) continue;
      const [p, q] = [at(f, i, ai), at(f, j, aj)];
      ctx.beginPath();
      ctx.moveTo(px(p[0]), py(p[1]));
      ctx.lineTo(px(q[0]), py(q[1]));
      ctx.stroke();
    }
    ctx.lineWidth = 0.6;
    ctx.fillStyle = "#000000";
    for (const [i, ab] of data.points) {
      if (f.blocks[i].length === 0) continue;
      const p = at(f, i, ab);
      ctx.fillRect(px(p[0]) - 3, py(p[1]) - 3, 6, 6);
    }
    ctx.fillStyle = "#d00000";
    for (let j = 0; j < f.contacts.length; j += 2) {
      ctx.beginPath();
      ctx.arc(px(f.contacts[j]), py(f.contacts[j + 1]), 2.5, 0, 2 * Math.PI);
      ctx.fill();
    }
    drawAxes();
    slider.value = String(k);
    label.textContent = "t = " + f.t.toFixed(4) + " s  (frame " + (k + 1) + " of " + frames.length + ")";
  }
  function stop() {
    if (timer !== null) { clearInterval(timer); timer = null; }
    play.textContent = "Play";
  }
  function start() {
    if (k >= frames.length - 1) k = 0;
    play.textContent = "Pause";
    timer = setInterval(() => {
      if (k >= frames.length - 1) { stop(); return; }
      k += 1;
      draw();
    }, 50);
  }
  play.addEventListener("click", () => { if (timer === null) start(); else stop(); });
  slider.addEventListener("input", () => { stop(); k = Number(slider.value); draw(); });
  if (select) select.addEventListener("change", () => { setMeasure(); draw(); });
  // Zoom about the pointer, pan by dragging, fit all, follow; the block under the
  // pointer named.
  canvas.addEventListener("wheel", (e) => {
    e.preventDefault();
    const r = canvas.getBoundingClientRect();
    const p = (e.clientX - r.left) * canvas.width / r.width;
    const q = (e.clientY - r.top) * canvas.height / r.height;
    const x = wx(p), y = wy(q);
    view.scale *= Math.exp(-0.0015 * e.deltaY);
    view.x0 = x - p / view.scale;
    view.y0 = y - (canvas.height - q) / view.scale;
    follow.checked = false;
    draw();
  }, { passive: false });
  let dragging = null;
  canvas.addEventListener("mousedown", (e) => { dragging = [e.clientX, e.clientY]; });
  window.addEventListener("mouseup", () => { dragging = null; });
  canvas.addEventListener("mousemove", (e) => {
    const r = canvas.getBoundingClientRect();
    const sxr = canvas.width / r.width, syr = canvas.height / r.height;
    if (dragging !== null) {
      view.x0 -= (e.clientX - dragging[0]) * sxr / view.scale;
      view.y0 += (e.clientY - dragging[1]) * syr / view.scale;
      dragging = [e.clientX, e.clientY];
      follow.checked = false;
      draw();
      return;
    }
    const f = frames[k];
    const i = blockAt(f, (e.clientX - r.left) * sxr, (e.clientY - r.top) * syr);
    if (i < 0) { hoverEl.textContent = ""; return; }
    let text = "block " + data.ids[i] + ": " + (data.fixed[i] ? "fixed" : "free") +
      ", speed " + f.speed[i].toPrecision(3) + " m/s";
    if (f.stress) {
      text += ", stress (" + [0, 1, 2].map((c) => (1e-3 * f.stress[3 * i + c]).toPrecision(3)).join(", ") + ") kPa";
    }
    hoverEl.textContent = text;
  });
  document.getElementById("fit").addEventListener("click", () => { follow.checked = false; fitAll(); draw(); });
  follow.addEventListener("change", () => { if (!follow.checked) fitAll(); draw(); });
  window.ddaReport = {
    frame: () => k,
    frames: frames.length,
    playing: () => timer !== null,
    view: () => [view.x0, view.y0, view.scale],
    // Frame k's block outlines, as the page unpacked them.
    blocks: (k) => frames[k].blocks,
    // The canvas point (client coordinates) of world point (x, y).
    client: (x, y) => {
      const r = canvas.getBoundingClientRect();
      return [r.left + px(x) * r.width / canvas.width, r.top + py(y) * r.height / canvas.height];
    },
  };
  // `#frame=N` or `#frame=last` in the address opens the page at that frame.
  const at = /frame=(\d+|last)/.exec(location.hash);
  if (at) k = at[1] === "last" ? frames.length - 1 : Math.min(Number(at[1]), frames.length - 1);
  if (frames.length > 0) draw();
})();
"##;

#[cfg(test)]
mod envelope_tests {
    use super::*;

    fn row(step: usize, value: f64) -> HistoryRow {
        HistoryRow {
            t: step as f64 * 1e-3,
            max_penetration: value,
            ..HistoryRow::default()
        }
    }

    /// A long history is plotted as per-interval extremes: the plotted maximum is the
    /// recorded maximum, at its time, however the steps fall into intervals; a short one
    /// is plotted step by step.
    #[test]
    fn a_decimated_plot_keeps_every_peak() {
        let n = 3 * PLOT_POINTS + 7;
        // One spike at an odd step, a sawtooth elsewhere.
        let h: Vec<HistoryRow> = (0..n)
            .map(|k| row(k, if k == 2017 { 9.0 } else { (k % 5) as f64 }))
            .collect();
        let points: Vec<(f64, f64)> = h.iter().map(|r| (r.t, r.max_penetration)).collect();
        let s = envelope(&points);
        assert_eq!(s.len(), 2);
        let top = s[0]
            .1
            .iter()
            .copied()
            .fold((0.0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
        assert_eq!(top, (2017.0 * 1e-3, 9.0));
        assert!(s[0].1.len() <= PLOT_POINTS && s[1].1.len() <= PLOT_POINTS);
        // Each interval holds 4 consecutive steps (4,507 over 1,500, rounded up), whose
        // residues mod 5 miss only one of 0 and 1: every plotted minimum is 0 or 1.
        assert!(s[1].1.iter().all(|p| p.1 <= 1.0));
        assert!(s[1].1.iter().any(|p| p.1 == 0.0));
        let short = envelope(&points[..10]);
        assert_eq!(short.len(), 1);
        assert_eq!(short[0].1.len(), 10);
    }
}
