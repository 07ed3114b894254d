//! `dda render DIR`: redraws `frames/*.svg` and `report.html` of a finished run from
//! its scene.json, summary.json, history.csv and frames.jsonl, without simulating again.
//! `dda run` draws them the same way when it ends.

use super::outdir::{check_run_folder, output_error};
use super::{Failure, bad, validate};
use dda::report::{
    Frame, Report, frame_svg, parse_bolts, parse_history, parse_points, report_html, run_view,
};
use dda_core::{Model, Scene, Summary};
use std::path::Path;
use std::process::ExitCode;

/// Writes `text` to `path` (a temporary sibling renamed into place).
pub fn write_new(path: &Path, text: &str) -> Result<(), Failure> {
    dda_core::checkpoint::write_atomically(path, text.as_bytes()).map_err(|e| output_error(e, path))
}

fn read(path: &Path) -> Result<String, Failure> {
    std::fs::read_to_string(path).map_err(|e| bad(format!("{}: {e}", path.display())))
}

/// Reads frames.jsonl, checking every frame against `model`; errors name the line.
fn read_frames(path: &Path, model: &Model) -> Result<Vec<Frame>, Failure> {
    let text = read(path)?;
    let mut frames = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let at = |m: String| bad(format!("{}: line {}: {m}", path.display(), k + 1));
        let f: Frame = serde_json::from_str(line).map_err(|e| at(e.to_string()))?;
        let fits = f.blocks.len() == model.blocks.len()
            && f.speed.len() == model.blocks.len()
            && f.blocks.iter().zip(&model.blocks).all(|(b, m)| {
                // A block an excavation removed is drawn no more: no vertices.
                (b.is_empty() && m.removed_at.is_some())
                    || (b.len() >= 6 && b.len().is_multiple_of(2))
            })
            && f.contacts.len().is_multiple_of(2)
            && (f.stress.is_empty() || f.stress.len() == 3 * model.blocks.len());
        if !fits {
            return Err(at(format!(
                "the frame does not fit the scene's {} blocks",
                model.blocks.len()
            )));
        }
        frames.push(f);
    }
    Ok(frames)
}

/// The rows of the table `name` in `dir` read by `parse`; none if the run has no such
/// table (its scene did not call for it).
fn read_table<T>(
    dir: &Path,
    name: &str,
    parse: fn(&str) -> Result<Vec<T>, String>,
) -> Result<Vec<T>, Failure> {
    let path = dir.join(name);
    if !path.exists() {
        return Ok(Vec::new());
    }
    parse(&read(&path)?).map_err(|e| bad(format!("{}: {e}", path.display())))
}

/// Draws frames/*.svg (one per frame marked `svg`) and report.html in `dir`.
pub fn render_outputs(
    dir: &Path,
    scene: &Scene,
    model: &Model,
    summary: &Summary,
) -> Result<(), Failure> {
    let frames = read_frames(&dir.join("frames.jsonl"), model)?;
    let history_path = dir.join("history.csv");
    let history = parse_history(&read(&history_path)?)
        .map_err(|e| bad(format!("{}: {e}", history_path.display())))?;
    // The per-step tables a scene may call for, when the run has them.
    let points = read_table(dir, "measurements.csv", parse_points)?;
    let bolts = read_table(dir, "bolts.csv", parse_bolts)?;
    let view = run_view(model, &frames);
    let frames_dir = dir.join("frames");
    // The folder holds only our pictures (checked before: `check_run_folder` or a
    // staging folder of ours); they are drawn anew.
    if frames_dir.is_dir() {
        for f in std::fs::read_dir(&frames_dir).map_err(|e| output_error(e, &frames_dir))? {
            let f = f.map_err(|e| output_error(e, &frames_dir))?;
            std::fs::remove_file(f.path()).map_err(|e| output_error(e, &f.path()))?;
        }
    } else {
        std::fs::create_dir(&frames_dir).map_err(|e| output_error(e, &frames_dir))?;
    }
    // The pictures on a thread of their own beside the report (they share nothing but
    // what they read): 6 of the 69 ms that drawing took at the end of the 93-block
    // column's run.
    let svgs = || -> Result<(), Failure> {
        for (k, f) in frames.iter().filter(|f| f.svg).enumerate() {
            let path = frames_dir.join(format!("frame-{k:04}.svg"));
            write_new(&path, &frame_svg(model, f, &view))?;
        }
        Ok(())
    };
    std::thread::scope(|s| {
        let pictures = s.spawn(svgs);
        let html = report_html(&Report {
            scene,
            model,
            summary,
            history: &history,
            points: &points,
            bolts: &bolts,
            frames: &frames,
            view,
        });
        let report = write_new(&dir.join("report.html"), &html);
        let pictures = pictures
            .join()
            .unwrap_or_else(|_| Err(Failure::Output("drawing the frames failed".into())));
        pictures.and(report)
    })
}

/// Runs `dda render DIR`.
pub fn render(dir: &Path) -> Result<ExitCode, Failure> {
    check_run_folder(dir)?;
    let scene_path = dir.join("scene.json");
    let scene: Scene = serde_json::from_str(&read(&scene_path)?)
        .map_err(|e| bad(format!("{}: {e}", scene_path.display())))?;
    let model = validate(&scene, &scene_path.display().to_string(), None)?;
    let summary_path = dir.join("summary.json");
    let summary: Summary = serde_json::from_str(&read(&summary_path)?)
        .map_err(|e| bad(format!("{}: {e}", summary_path.display())))?;
    render_outputs(dir, &scene, &model, &summary)?;
    eprintln!(
        "drew {} and {}",
        dir.join("frames").display(),
        dir.join("report.html").display()
    );
    Ok(ExitCode::SUCCESS)
}
