//! What a run writes: history.csv rows and SVG frames of the blocks; pictures of a
//! collision's outcome for the robustness report.

use dda_core::{Simulation, StepRecord};
use dda_geom::{Aabb, ConvexPolygon, DVec2};
use std::fmt::Write as _;

/// Header of history.csv.
pub const HISTORY_HEADER: &str = "step,t,dt,oci,cuts,candidates,active_contacts,closed_contacts,\
max_penetration,kinetic_energy,detection_s,assembly_s,solve_s";

/// One row of history.csv (no trailing newline).
pub fn history_row(r: &StepRecord) -> String {
    format!(
        "{},{:e},{:e},{},{},{},{},{},{:e},{:e},{:e},{:e},{:e}",
        r.step,
        r.t,
        r.dt,
        r.oci,
        r.cuts,
        r.candidates,
        r.active_contacts,
        r.closed_contacts,
        r.max_penetration,
        r.kinetic_energy,
        r.detection_s,
        r.assembly_s,
        r.solve_s
    )
}

/// The box every frame of a run shows: the free blocks' extent at the start with a
/// margin of a quarter of its size (room to move), or every block's if none is free.
pub fn frame_view(sim: &Simulation) -> Aabb {
    let free: Vec<Aabb> = sim
        .blocks()
        .iter()
        .zip(&sim.model().blocks)
        .filter(|(_, m)| !m.fixed)
        .map(|(b, _)| b.polygon.aabb())
        .collect();
    let all: Vec<Aabb> = sim.blocks().iter().map(|b| b.polygon.aabb()).collect();
    let b = if free.is_empty() { all } else { free }
        .into_iter()
        .reduce(|a, b| a.union(&b))
        .unwrap_or(Aabb {
            min: glam::DVec2::ZERO,
            max: glam::DVec2::ONE,
        });
    b.expanded(0.25 * b.size().max_element())
}

/// An SVG picture of the blocks now, in the fixed `view` (y up), fixed blocks grey.
pub fn frame_svg(sim: &Simulation, view: &Aabb) -> String {
    let size = view.size();
    let width = 800.0;
    let height = (width * size.y / size.x).clamp(100.0, 4000.0);
    let stroke = 0.6 * size.x / width;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width:.0}" height="{height:.0}" viewBox="{} {} {} {}">"#,
        view.min.x, -view.max.y, size.x, size.y
    );
    let _ = writeln!(
        s,
        r#"<title>{} t = {:.4} s</title><g stroke="black" stroke-width="{stroke}" stroke-linejoin="round">"#,
        escape(&sim.model().name),
        sim.time()
    );
    for (b, m) in sim.blocks().iter().zip(&sim.model().blocks) {
        let fill = if m.fixed { "#b0b0b0" } else { "#e8c890" };
        let pts: Vec<String> = b
            .polygon
            .vertices()
            .iter()
            .map(|v| format!("{:.6},{:.6}", v.x, -v.y))
            .collect();
        let _ = writeln!(
            s,
            r#"<polygon fill="{fill}" points="{}"><title>{}</title></polygon>"#,
            pts.join(" "),
            escape(&m.id)
        );
    }
    s.push_str("</g>\n</svg>\n");
    s
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
    let mut s = frame_svg(sim, view);
    let size = view.size();
    let stroke = 0.6 * size.x / 800.0;
    let mut extra = String::new();
    let _ = writeln!(
        extra,
        r#"<g fill="none" stroke="black" stroke-width="{stroke}" stroke-dasharray="{} {}">"#,
        4.0 * stroke,
        3.0 * stroke
    );
    for p in start {
        let pts: Vec<String> = p
            .vertices()
            .iter()
            .map(|v| format!("{:.6},{:.6}", v.x, -v.y))
            .collect();
        let _ = writeln!(extra, r#"<polygon points="{}"/>"#, pts.join(" "));
    }
    let pts: Vec<String> = path
        .iter()
        .map(|v| format!("{:.6},{:.6}", v.x, -v.y))
        .collect();
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

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
