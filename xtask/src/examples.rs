//! `cargo xtask examples`: runs every scene of `examples/` to its end and writes
//! `docs/examples.md`, each example's description (the comment at the top of its file),
//! its blocks and work counts, and a picture of its start and of its end
//! (`docs/results/examples/NAME-start.svg`, `-end.svg`).

use dda_core::{RunOptions, Scene, Simulation};
use dda_report::{Frame, frame_resolution, frame_svg, frame_view, run_view};
use std::fmt::Write as _;
use std::path::Path;

/// Runs the examples and writes the page and its pictures.
pub fn run(root: &Path) -> Result<(), String> {
    let dir = root.join("examples");
    let pictures = root.join("docs/results/examples");
    std::fs::create_dir_all(&pictures).map_err(|e| format!("{}: {e}", pictures.display()))?;
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    let mut md = String::from(
        "# Examples\n\n\
         Scenes a rock engineer would recognise, in `examples/`, each written with regions \
         and joint sets (docs/scene-format.md). Run one with `cargo run --release -- run \
         examples/NAME.toml`; `dda build examples/NAME.toml` lists its blocks. This page \
         and its pictures are made by `cargo xtask examples`, which runs each to its end: \
         the pictures show the start and the end (fixed blocks grey, excavated rock \
         gone). The tests in `tests/physics/regions.rs` check what each is meant to \
         show.\n",
    );
    for path in files {
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("example")
            .to_string();
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let (_, model) = Scene::load(&path).map_err(|e| e.to_string())?;
        let resolution = frame_resolution(&frame_view(&model));
        let free = model.blocks.iter().filter(|b| !b.fixed).count();
        let bodies = model.blocks.iter().filter(|b| b.body.is_some()).count();
        let mut sim = Simulation::new(model.clone(), RunOptions::default());
        let start = Frame::of(&sim, true, resolution);
        sim.run(|_, _| {}).map_err(|e| format!("{name}: {e}"))?;
        let end = Frame::of(&sim, true, resolution);
        // Both pictures in one view, which holds the blocks at the start and the end.
        let view = run_view(&model, &[start.clone(), end.clone()]);
        for (which, frame) in [("start", start), ("end", end)] {
            let svg = frame_svg(&model, &frame, &view);
            let file = pictures.join(format!("{name}-{which}.svg"));
            std::fs::write(&file, svg).map_err(|e| format!("{}: {e}", file.display()))?;
        }
        let t = sim.totals();
        let about: Vec<&str> = text
            .lines()
            .take_while(|l| l.starts_with('#'))
            .map(|l| l.trim_start_matches('#').trim())
            .collect();
        let _ = write!(
            md,
            "\n## {name}\n\n{}\n\n`examples/{name}.toml`: {} blocks ({free} free, {} fixed; \
             {bodies} of them convex parts of non-convex blocks); {} s in {} steps, {} \
             open-close iterations, {} time-step cuts; largest penetration {:.2e} m.\n\n\
             | start | end (t = {} s) |\n| --- | --- |\n\
             | ![{name} at the start](results/examples/{name}-start.svg) \
             | ![{name} at the end](results/examples/{name}-end.svg) |\n",
            about.join(" "),
            model.blocks.len(),
            model.blocks.len() - free,
            model.params.duration,
            t.steps,
            t.oci_iterations,
            t.cuts,
            t.max_penetration,
            model.params.duration,
        );
    }
    let page = root.join("docs/examples.md");
    std::fs::write(&page, md).map_err(|e| format!("{}: {e}", page.display()))?;
    Ok(())
}
