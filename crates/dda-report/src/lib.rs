//! What a dda-rs run writes for people: history.csv rows, frames.jsonl (the recorded
//! instants), SVG pictures of them, plots and the self-contained report.html; pictures of
//! a collision's outcome for the robustness report. Its own crate, so that the studies
//! (`xtask`) draw plots without the command-line facade.

mod html;
mod packed;
mod plot;

pub use self::html::{
    BoltRow, HistoryRow, PointRow, Report, parse_bolts, parse_history, parse_points, report_html,
};
pub use self::packed::pack_frames;
pub use self::plot::plot;

use dda_core::{Model, Simulation, StepRecord};
use dda_geom::{Aabb, ConvexPolygon, DVec2};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Header of history.csv.
pub const HISTORY_HEADER: &str = "step,t,dt,oci,cuts,candidates,active_contacts,closed_contacts,\
max_penetration,kinetic_energy,detection_s,assembly_s,solve_s";

/// Header of measurements.csv: one row per step and measured point (docs/outputs.md).
pub const MEASUREMENTS_HEADER: &str = "t,id,block,x,y,ux,uy,vx,vy,sxx,syy,sxy";

/// The rows of measurements.csv for the state of `sim` now: each measured point's time
/// (s), id, block, position (m), displacement since the start (m), velocity (m/s) and
/// its block's stress (Pa, tension positive); none for a point whose block an
/// excavation has removed.
pub fn measurement_rows(sim: &Simulation) -> Vec<String> {
    let t = format!("{:e}", sim.time());
    sim.model()
        .measures
        .iter()
        .filter(|m| !sim.is_removed(m.block))
        .map(|m| {
            let p = sim.material_point(m.block, m.at);
            let v = sim.material_velocity(m.block, m.at);
            let s = sim.blocks()[m.block].stress;
            let u = p - m.at;
            let mut fields = vec![
                t.clone(),
                m.id.clone(),
                sim.model().blocks[m.block].id.clone(),
            ];
            fields.extend(
                [p.x, p.y, u.x, u.y, v.x, v.y, s[0], s[1], s[2]]
                    .iter()
                    .map(|x| format!("{x:e}")),
            );
            csv_record(fields)
        })
        .collect()
}

/// Header of bolts.csv: one row per step and bolt (docs/outputs.md).
pub const BOLTS_HEADER: &str = "t,bolt,from_block,to_block,tension,state";

/// The rows of bolts.csv for the state of `sim` now: each bolt's time (s), index in the
/// scene's order, blocks, tension (N, compression negative; empty once broken) and state
/// (`holding`, `broken`, or `removed` with an excavated block).
pub fn bolt_rows(sim: &Simulation) -> Vec<String> {
    let t = format!("{:e}", sim.time());
    sim.model()
        .bolts
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let tension = sim.bolt_tension(k);
            let state = if sim.bolt_states()[k].broken.is_some() {
                "broken"
            } else if tension.is_none() {
                "removed"
            } else {
                "holding"
            };
            csv_record([
                t.clone(),
                k.to_string(),
                sim.model().blocks[b.from_block].id.clone(),
                sim.model().blocks[b.to_block].id.clone(),
                tension.map(|x| format!("{x:e}")).unwrap_or_default(),
                state.to_string(),
            ])
        })
        .collect()
}

/// One CSV record of `fields` (quoted where a field needs it), without its newline: the
/// one writer of every CSV file the project writes (history.csv, the studies' tables).
pub fn csv_record<I, F>(fields: I) -> String
where
    I: IntoIterator<Item = F>,
    F: AsRef<[u8]>,
{
    let mut w = csv::WriterBuilder::new()
        .terminator(csv::Terminator::Any(b'\n'))
        .from_writer(Vec::new());
    // Writing to memory cannot fail; a record that did would be an empty line.
    if w.write_record(fields).is_err() {
        return String::new();
    }
    let mut bytes = w.into_inner().unwrap_or_default();
    bytes.pop();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// One row of history.csv (no trailing newline).
pub fn history_row(r: &StepRecord) -> String {
    csv_record([
        r.step.to_string(),
        format!("{:e}", r.t),
        format!("{:e}", r.dt),
        r.oci.to_string(),
        r.cuts.to_string(),
        r.candidates.to_string(),
        r.active_contacts.to_string(),
        r.closed_contacts.to_string(),
        format!("{:e}", r.max_penetration),
        format!("{:e}", r.kinetic_energy),
        format!("{:e}", r.detection_s),
        format!("{:e}", r.assembly_s),
        format!("{:e}", r.solve_s),
    ])
}

/// One recorded instant of a run, as a line of frames.jsonl: what the report animates
/// and `frames/*.svg` draw. Coordinates are rounded (see [`Frame::of`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Simulated time, s.
    pub t: f64,
    /// Whether `frames/` gets an SVG picture of this instant (the scene's `frames`).
    pub svg: bool,
    /// Each block's vertices, flattened: x0, y0, x1, y1, ...; none for a block an
    /// excavation has removed.
    pub blocks: Vec<Vec<f64>>,
    /// Each block's centroid speed, m/s.
    pub speed: Vec<f64>,
    /// Where the active closed contacts are (their vertices), flattened x, y.
    pub contacts: Vec<f64>,
    /// Each block's stress, flattened sxx, syy, sxy (Pa, tension positive, four
    /// significant digits); empty for a run of rigid blocks.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub stress: Vec<f64>,
}

/// `x` to four significant digits (plenty for a colour), so that frames print short.
/// Finite for every finite `x`: below about 1e-305 (the speeds and stresses of blocks
/// at rest reach 1e-315) the scale 10^e would overflow, and x times it be NaN, which a
/// frame would print as `null`; the scale is then applied in two factors. Near
/// f64::MAX, where rounding up would overflow, `x` is kept as it is.
fn four_digits(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return 0.0;
    }
    let e = 3 - x.abs().log10().floor() as i32;
    let (a, b) = if e > 300 {
        (10f64.powi(300), 10f64.powi(e - 300))
    } else {
        (1.0, 10f64.powi(e))
    };
    let r = ((x * a) * b).round() / b / a;
    // Rounded up past f64::MAX, it keeps its digits.
    if r.is_finite() { r } else { x }
}

impl Frame {
    /// The blocks and contacts of `sim` now, coordinates rounded to `resolution` (m).
    pub fn of(sim: &Simulation, svg: bool, resolution: f64) -> Frame {
        // Dividing by a whole power of ten gives the double nearest the rounded decimal,
        // which prints short.
        let per_metre = (1.0 / resolution).round().max(1.0);
        let round = |x: f64| (x * per_metre).round() / per_metre;
        let blocks = sim
            .blocks()
            .iter()
            .enumerate()
            .map(|(i, b)| {
                if sim.is_removed(i) {
                    // Excavated: drawn no more.
                    return Vec::new();
                }
                b.polygon
                    .vertices()
                    .iter()
                    .flat_map(|v| [round(v.x), round(v.y)])
                    .collect()
            })
            .collect();
        let speed = sim
            .blocks()
            .iter()
            .map(|b| four_digits(glam::DVec2::new(b.velocity[0], b.velocity[1]).length()))
            .collect();
        let stress = if sim.effects().elasticity {
            sim.blocks()
                .iter()
                .flat_map(|b| b.stress.map(four_digits))
                .collect()
        } else {
            Vec::new()
        };
        let mut contacts = Vec::new();
        for c in sim.contacts().active().filter(|c| {
            c.state.is_closed()
                && !sim.is_removed(c.key.vertex_block as usize)
                && !sim.is_removed(c.key.edge_block as usize)
        }) {
            let b = &sim.blocks()[c.key.vertex_block as usize];
            if let Some(v) = b.polygon.vertices().get(c.key.vertex as usize) {
                contacts.extend([round(v.x), round(v.y)]);
            }
        }
        Frame {
            t: sim.time(),
            svg,
            blocks,
            speed,
            contacts,
            stress,
        }
    }

    /// Whether every number of the frame is finite (JSON has no NaN or infinity:
    /// serialised, they would print as `null`).
    pub fn is_finite(&self) -> bool {
        self.t.is_finite()
            && [&self.speed, &self.contacts, &self.stress]
                .into_iter()
                .chain(&self.blocks)
                .all(|v| v.iter().all(|x| x.is_finite()))
    }

    /// The polygon of block `i`, as points.
    pub fn polygon(&self, i: usize) -> impl Iterator<Item = DVec2> + '_ {
        self.blocks[i]
            .chunks_exact(2)
            .map(|p| DVec2::new(p[0], p[1]))
    }
}

/// The stretches of each block's outline to draw, as `(edge, s0, s1)`: edge `edge` from
/// ratio `s0` to `s1` along it; `None` for a block drawn whole. A block that is a part of
/// a non-convex body (`body`) is drawn without the stretches of its glued edges where it
/// lies against another part of its body at the start (the glue is not a joint), so the
/// body shows as one block, its joints (a trace ending inside it) drawn. Ratios, so that they follow the blocks as they move and deform.
pub fn drawn_edges(model: &Model) -> Vec<Option<Vec<(usize, f64, f64)>>> {
    model
        .blocks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let body = b.body?;
            let p = &b.polygon;
            let eps = 1e-9 * p.diameter();
            let mates: Vec<&ConvexPolygon> = model
                .blocks
                .iter()
                .enumerate()
                .filter(|&(j, m)| j != i && m.body == Some(body))
                .map(|(_, m)| &m.polygon)
                .collect();
            let mut out = Vec::new();
            for k in 0..p.len() {
                if b.glued.get(k) != Some(&true) {
                    out.push((k, 0.0, 1.0));
                    continue;
                }
                // The stretches of this edge other parts cover, as ratios.
                let mut covered: Vec<(f64, f64)> = mates
                    .iter()
                    .flat_map(|m| p.edge_contacts(k, m, eps))
                    .collect();
                covered.sort_by(|x, y| x.0.total_cmp(&y.0));
                let mut from = 0.0;
                for (lo, hi) in covered {
                    if lo > from {
                        out.push((k, from, lo));
                    }
                    from = f64::max(from, hi);
                }
                if from < 1.0 {
                    out.push((k, from, 1.0));
                }
            }
            Some(out)
        })
        .collect()
}

/// The box every frame of a run shows before the run: the free blocks' extent at the
/// start with a margin of a quarter of its size (room to move), or every block's if none
/// is free. It sets the rounding of the frames a run writes ([`frame_resolution`]);
/// the pictures drawn after the run take [`run_view`], which also holds where the blocks
/// went.
pub fn frame_view(model: &Model) -> Aabb {
    let b = start_box(model);
    b.expanded(start_margin(&b))
}

/// The free blocks' extent at the start, or every block's if none is free.
fn start_box(model: &Model) -> Aabb {
    let free: Vec<Aabb> = model
        .blocks
        .iter()
        .filter(|m| !m.fixed)
        .map(|m| m.polygon.aabb())
        .collect();
    let all: Vec<Aabb> = model.blocks.iter().map(|m| m.polygon.aabb()).collect();
    if free.is_empty() { all } else { free }
        .into_iter()
        .reduce(|a, b| a.union(&b))
        .unwrap_or(Aabb {
            min: glam::DVec2::ZERO,
            max: glam::DVec2::ONE,
        })
}

/// The margin of the view around the blocks: a quarter of the start box's larger side.
fn start_margin(start: &Aabb) -> f64 {
    0.25 * start.size().max_element()
}

/// The box a run's pictures and report show: the free blocks' extent at the start and in
/// every frame, with [`frame_view`]'s margin. A block that travels far from where it
/// started (a rockfall down its slope, a slide) stays in the picture; a run whose blocks
/// stay near their start shows [`frame_view`] itself.
pub fn run_view(model: &Model, frames: &[Frame]) -> Aabb {
    let start = start_box(model);
    let free: Vec<usize> = (0..model.blocks.len())
        .filter(|&k| !model.blocks[k].fixed)
        .collect();
    let mut b = start;
    for f in frames {
        for &k in &free {
            let Some(xy) = f.blocks.get(k) else { continue };
            for p in xy.chunks_exact(2) {
                let p = DVec2::new(p[0], p[1]);
                if p.is_finite() {
                    b = b.union(&Aabb { min: p, max: p });
                }
            }
        }
    }
    b.expanded(start_margin(&start))
}

/// The rounding of frame coordinates for a run shown in `view`: a millionth of its size.
pub fn frame_resolution(view: &Aabb) -> f64 {
    let size = view.size().max_element().max(f64::MIN_POSITIVE);
    10f64.powi((size * 1e-6).log10().floor() as i32)
}

/// An SVG picture of `frame` of a run of `model`, in the fixed `view` (y up): the time,
/// axes in metres, blocks coloured by speed (blue at rest to red at the frame's fastest
/// free block), fixed blocks grey.
pub fn frame_svg(model: &Model, frame: &Frame, view: &Aabb) -> String {
    let size = view.size();
    let width = 800.0;
    let height = (width * size.y / size.x).clamp(100.0, 4000.0);
    // The axes, in metres.
    let (xt, yt) = (
        plot::Ticks::new(view.min.x, view.max.x),
        plot::Ticks::new(view.min.y, view.max.y),
    );
    // Margins (pixels): the axes at the left and the bottom, the time and the legend on
    // top. The left one holds the y labels (7 pixels a character at 12 px, a survey
    // grid's 4000020 included) beside the axis title.
    let widest = yt
        .values()
        .filter(|&v| v >= view.min.y && v <= view.max.y)
        .map(|v| yt.label(v).chars().count())
        .max()
        .unwrap_or(0);
    let (ml, mt, mr, mb) = ((30.0 + 7.0 * widest as f64).max(50.0), 30.0, 15.0, 40.0);
    let stroke = 0.6 * size.x / width;
    let vmax = frame
        .speed
        .iter()
        .zip(&model.blocks)
        .filter(|(_, m)| !m.fixed)
        .map(|(v, _)| *v)
        .fold(0.0f64, f64::max);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" font-family="sans-serif" font-size="12">"#,
        width + ml + mr,
        height + mt + mb
    );
    let _ = writeln!(
        s,
        r##"<title>{} t = {:.4} s</title><rect width="100%" height="100%" fill="white"/>
<text x="{ml}" y="18">{}: t = {:.4} s; blocks coloured by speed, blue 0 to red {:.3} m/s; fixed blocks grey</text>"##,
        escape(&model.name),
        frame.t,
        escape(&model.name),
        frame.t,
        vmax
    );
    let px = |x: f64| ml + (x - view.min.x) / size.x * width;
    let py = |y: f64| mt + (view.max.y - y) / size.y * height;
    let _ = writeln!(
        s,
        r#"<g stroke="black"><line x1="{ml}" y1="{mt}" x2="{ml}" y2="{}"/><line x1="{ml}" y1="{}" x2="{}" y2="{}"/></g>"#,
        mt + height,
        mt + height,
        ml + width,
        mt + height
    );
    for v in xt.values().filter(|&v| v >= view.min.x && v <= view.max.x) {
        let _ = writeln!(
            s,
            r#"<line x1="{x:.1}" y1="{}" x2="{x:.1}" y2="{}" stroke="black"/><text x="{x:.1}" y="{}" text-anchor="middle">{}</text>"#,
            mt + height,
            mt + height + 5.0,
            mt + height + 18.0,
            xt.label(v),
            x = px(v)
        );
    }
    for v in yt.values().filter(|&v| v >= view.min.y && v <= view.max.y) {
        let _ = writeln!(
            s,
            r#"<line x1="{}" y1="{y:.1}" x2="{ml}" y2="{y:.1}" stroke="black"/><text x="{}" y="{:.1}" text-anchor="end">{}</text>"#,
            ml - 5.0,
            ml - 7.0,
            py(v) + 4.0,
            yt.label(v),
            y = py(v)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">x (m)</text><text x="12" y="{y}" transform="rotate(-90 12 {y})" text-anchor="middle">y (m)</text>"#,
        ml + width / 2.0,
        mt + height + 34.0,
        y = mt + height / 2.0
    );
    // The blocks, in metres from the view's top left corner (y down) in a viewport of
    // their own: a picture's renderer takes its coordinates in single precision, which
    // at a survey grid's 4e6 m is a quarter of a metre.
    let _ = writeln!(
        s,
        r#"<desc>view: x {} to {} m, y {} to {} m; the blocks' coordinates are metres from its top left corner, y down</desc>"#,
        view.min.x, view.max.x, view.min.y, view.max.y
    );
    let _ = writeln!(
        s,
        r#"<svg x="{ml}" y="{mt}" width="{width:.0}" height="{height:.0}" viewBox="0 0 {} {}" preserveAspectRatio="none">"#,
        size.x, size.y
    );
    let at = view_point(view);
    let _ = writeln!(
        s,
        r#"<g stroke="black" stroke-width="{stroke}" stroke-linejoin="round">"#
    );
    let drawn = drawn_edges(model);
    for (i, m) in model.blocks.iter().enumerate() {
        if frame.blocks[i].is_empty() {
            continue;
        }
        let fill = if m.fixed {
            "#b0b0b0".to_string()
        } else {
            let f = if vmax > 0.0 {
                (frame.speed[i] / vmax).min(1.0)
            } else {
                0.0
            };
            format!("hsl({:.0},75%,60%)", 240.0 - 240.0 * f)
        };
        let v: Vec<DVec2> = frame.polygon(i).collect();
        let pts: Vec<String> = v.iter().map(|&v| at(v)).collect();
        match &drawn[i] {
            None => {
                let _ = writeln!(
                    s,
                    r#"<polygon fill="{fill}" points="{}"><title>{}</title></polygon>"#,
                    pts.join(" "),
                    escape(&m.id)
                );
            }
            Some(stretches) => {
                // A part of a body: filled whole, outlined where it is not glued.
                let _ = writeln!(
                    s,
                    r#"<polygon fill="{fill}" stroke="{fill}" points="{}"><title>{}</title></polygon>"#,
                    pts.join(" "),
                    escape(&m.id)
                );
                let mut path = String::new();
                for &(k, s0, s1) in stretches {
                    let (a, b) = (v[k], v[(k + 1) % v.len()]);
                    let (p, q) = (a.lerp(b, s0), a.lerp(b, s1));
                    let _ = write!(path, "M{}L{}", at(p), at(q));
                }
                let _ = writeln!(s, r#"<path fill="none" d="{path}"/>"#);
            }
        }
    }
    s.push_str("</g>\n</svg>\n</svg>\n");
    s
}

/// The picture coordinates of world point `v` in `view`, written: metres from its top
/// left corner, y down ([`frame_svg`]), to the frames' resolution in `view`
/// ([`frame_resolution`]; the difference of two coordinates far from the origin
/// carries their rounding in its last digits).
fn view_point(view: &Aabb) -> impl Fn(DVec2) -> String {
    let (x0, y1) = (view.min.x, view.max.y);
    let decimals = (-frame_resolution(view).log10()).ceil().max(0.0) as usize;
    let short = move |x: f64| {
        let t = format!("{x:.decimals$}");
        let t = if t.contains('.') {
            t.trim_end_matches('0').trim_end_matches('.')
        } else {
            &t
        };
        if t == "-0" {
            "0".to_string()
        } else {
            t.to_string()
        }
    };
    move |v: DVec2| format!("{},{}", short(v.x - x0), short(y1 - v.y))
}

/// An SVG picture of a run's outcome in `view` (y up): the blocks at the start as dashed
/// outlines, the blocks now filled (fixed ones grey), and the path of the first free
/// block's centroid.
pub fn outcome_svg(
    sim: &Simulation,
    start: &[ConvexPolygon],
    path: &[DVec2],
    view: &Aabb,
) -> String {
    let frame = Frame::of(sim, true, frame_resolution(view));
    let mut s = frame_svg(sim.model(), &frame, view);
    let size = view.size();
    let stroke = 0.6 * size.x / 800.0;
    let mut extra = String::new();
    let _ = writeln!(
        extra,
        r#"<g fill="none" stroke="black" stroke-width="{stroke}" stroke-dasharray="{} {}">"#,
        4.0 * stroke,
        3.0 * stroke
    );
    let at = view_point(view);
    let point = |v: &DVec2| at(*v);
    for p in start {
        let pts: Vec<String> = p.vertices().iter().map(point).collect();
        let _ = writeln!(extra, r#"<polygon points="{}"/>"#, pts.join(" "));
    }
    let pts: Vec<String> = path.iter().map(point).collect();
    let _ = writeln!(
        extra,
        r##"</g><polyline fill="none" stroke="#c03020" stroke-width="{}" points="{}"/>"##,
        2.0 * stroke,
        pts.join(" ")
    );
    if let Some(at) = s.rfind("</svg>") {
        s.insert_str(at, &extra);
    }
    s
}

/// `n` and `noun`, the noun in the plural unless `n` is 1 ("1 step", "8 OCI
/// iterations"); for the nouns of a run's counts, whose plurals add an "s".
pub fn counted(n: u64, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}

/// `x` to six significant digits, as short as it prints ("0.0197998" for 0.0197997511,
/// "1" for 1.0): times and sizes in messages for people, where the full precision of a
/// step's arithmetic is noise. Non-finite values print as they are.
pub fn shown(x: f64) -> String {
    if !x.is_finite() || x == 0.0 {
        return format!("{x}");
    }
    let rounded: f64 = format!("{x:.5e}").parse().unwrap_or(x);
    format!("{rounded}")
}

/// `s` with the characters HTML and SVG treat specially escaped.
pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene in a survey grid's coordinates (5e5 m east, 4e6 m north) is drawn in
    /// metres from the view's corner: every coordinate of its blocks lies within the
    /// view's size (a renderer reads them in single precision, which at 4e6 m is a
    /// quarter of a metre), and the picture states the view in world coordinates.
    #[test]
    fn a_frame_far_from_the_origin_is_drawn_from_the_view_s_corner() {
        let text = "name = \"grid\"\n[analysis]\nduration = 0.01\ntime_step = 0.01\n\
                    max_displacement = 0.01\nnormal_penalty = 1e9\n[materials.rock]\n\
                    density = 2600.0\nyoung = 1e9\npoisson = 0.25\n[[blocks]]\nid = \"b\"\n\
                    material = \"rock\"\nvertices = [[500000.0, 4000000.0], [500003.0, \
                    4000000.0], [500003.0, 4000002.0], [500000.0, 4000002.0]]\n";
        let (_, model) =
            dda_core::Scene::parse(text, dda_core::Format::Toml, "grid.toml").expect("valid");
        let sim = Simulation::new(model, dda_core::RunOptions::default());
        let view = frame_view(sim.model());
        let frame = Frame::of(&sim, true, frame_resolution(&view));
        let svg = frame_svg(sim.model(), &frame, &view);
        let size = view.size();
        let points = svg
            .split("points=\"")
            .skip(1)
            .map(|p| p.split('"').next().unwrap_or_default());
        let mut seen = 0;
        for p in points {
            for xy in p.split_whitespace() {
                let (x, y) = xy.split_once(',').expect("x,y");
                let (x, y): (f64, f64) = (x.parse().expect("x"), y.parse().expect("y"));
                assert!(
                    (0.0..=size.x).contains(&x) && (0.0..=size.y).contains(&y),
                    "{xy}"
                );
                seen += 1;
            }
        }
        assert_eq!(seen, 4, "{svg}");
        let desc = format!(
            "<desc>view: x {} to {} m, y {} to {} m;",
            view.min.x, view.max.x, view.min.y, view.max.y
        );
        assert!(svg.contains(&desc), "{svg}");
    }

    /// Six significant digits, as short as they print: trailing zeros and exponents
    /// left out, zero as it is.
    #[test]
    fn shown_numbers_keep_six_significant_digits() {
        assert_eq!(shown(0.019_799_751_099_513_645), "0.0197998");
        assert_eq!(shown(1.0), "1");
        assert_eq!(shown(0.15), "0.15");
        assert_eq!(shown(123_456_789.0), "123457000");
        assert_eq!(shown(-2.5e-7), "-0.00000025");
        assert_eq!(shown(0.0), "0");
    }

    /// Counts read as English: the noun singular for one, plural otherwise (zero
    /// included).
    #[test]
    fn counts_take_the_noun_s_number() {
        assert_eq!(counted(1, "step"), "1 step");
        assert_eq!(counted(0, "dt cut"), "0 dt cuts");
        assert_eq!(counted(8, "OCI iteration"), "8 OCI iterations");
    }

    /// Four significant digits of every finite number are finite, the normal ones within
    /// half a unit of the fourth digit (5e-4 of themselves), the subnormal ones (which
    /// carry fewer digits) of their sign or zero.
    #[test]
    fn four_digits_are_finite_over_the_whole_range() {
        let normal = [
            f64::MIN_POSITIVE,
            1e-305,
            1.234_567e-300,
            9.999_9e-5,
            1.0,
            123_456.0,
            f64::MAX,
        ];
        for x in normal.into_iter().flat_map(|x| [x, -x]) {
            let r = four_digits(x);
            assert!(r.is_finite(), "{x:e} -> {r}");
            assert!((r - x).abs() <= 5e-4 * x.abs(), "{x:e} -> {r:e}");
        }
        for x in [4.671_444_386e-315, -8.435_683_709_5e-314, 5e-324] {
            let r = four_digits(x);
            assert!(
                r.is_finite() && (r == 0.0 || r.signum() == x.signum()),
                "{x:e} -> {r}"
            );
        }
        assert_eq!(four_digits(f64::NAN), 0.0);
    }

    /// A frame with a number JSON cannot hold is told apart (a run refuses to write it).
    #[test]
    fn a_frame_with_a_nan_is_not_finite() {
        let frame = Frame {
            t: 0.5,
            svg: false,
            blocks: vec![vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0]],
            speed: vec![0.25],
            contacts: vec![],
            stress: vec![1.0, 2.0, 3.0],
        };
        assert!(frame.is_finite());
        let mut vertex = frame.clone();
        vertex.blocks[0][3] = f64::NAN;
        let mut stress = frame.clone();
        stress.stress[2] = f64::INFINITY;
        assert!(!vertex.is_finite() && !stress.is_finite());
    }

    /// An L-shaped region is one body of two glued parts: what is drawn of their outlines
    /// is the L's perimeter (8 m), not the parts' (which add their seam twice).
    #[test]
    fn a_body_is_drawn_without_its_seams() {
        let text = r#"
name = "l"
[analysis]
duration = 0.1
time_step = 0.01
max_displacement = 0.001
normal_penalty = 1e9
[materials.rock]
density = 2600.0
young = 1e9
poisson = 0.2
[[regions]]
id = "l"
material = "rock"
vertices = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]
"#;
        let (_, model) =
            dda_core::Scene::parse(text, dda_core::Format::Toml, "l.toml").expect("a valid scene");
        assert_eq!(model.blocks.len(), 2);
        let drawn = drawn_edges(&model);
        let mut length = 0.0;
        for (b, stretches) in model.blocks.iter().zip(&drawn) {
            for &(k, s0, s1) in stretches.as_ref().expect("a part of a body") {
                let (p, q) = b.polygon.edge(k);
                length += (s1 - s0) * p.distance(q);
            }
        }
        assert!((length - 8.0).abs() < 1e-12, "drawn {length} m");
        let parts: f64 = model
            .blocks
            .iter()
            .map(|b| b.polygon.edges().map(|(p, q)| p.distance(q)).sum::<f64>())
            .sum();
        // The parts' own outlines are longer by the seam, twice: a diagonal of the L.
        assert!(parts - 8.0 > 2.0, "{parts}");
    }
}
