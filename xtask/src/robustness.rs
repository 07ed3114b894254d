//! `cargo xtask robustness`: runs the paper's section 4 cases with every detector, judges
//! each outcome (`dda_bench::verdict`), draws it, and writes `docs/robustness.md` with
//! our verdicts beside the paper's.

use dda_bench::{HARD_CASES, judge_collision, judge_collision_with};
use dda_core::{RunOptions, Simulation};
use dda_geom::{DVec2, separation};
use dda_report::{frame_view, outcome_svg};
use std::fmt::Write as _;
use std::path::Path;

/// The detectors, as the paper names them and as `dda` does.
const DETECTORS: [(&str, &str); 3] = [
    ("type-1", "TB-CD-1"),
    ("type-2", "TB-CD-2"),
    ("cover", "CB-CD"),
];

/// The paper's verdict (section 4 text): true where it calls the result correct.
fn paper_says(case: &str, detector: &str) -> bool {
    match (case, detector) {
        (_, "cover") => true,
        ("4.1", "type-1") => false,
        ("4.2", "type-2") => false,
        ("4.3a" | "4.4a" | "4.4c", _) => false,
        _ => true,
    }
}

/// Runs the cases and writes `docs/robustness.md` and its pictures under `root`.
pub fn run(root: &Path) -> Result<(), String> {
    let docs = root.join("docs");
    let pictures = docs.join("results").join("robustness");
    std::fs::create_dir_all(&pictures).map_err(|e| format!("{}: {e}", pictures.display()))?;
    let mut rows = String::new();
    let (mut agree, mut total) = (0, 0);
    let mut disagreements = Vec::new();
    let mut cover_wrong = Vec::new();
    for case in HARD_CASES {
        for (detector, paper_name) in DETECTORS {
            let mut scene = case.scene();
            scene.analysis.detector = detector.into();
            let model = scene
                .validate()
                .map_err(|e| format!("{}: {}", case.name(), e.message))?;
            let mut sim = Simulation::new(model, RunOptions::default());
            let view = frame_view(sim.model());
            let view = view.expanded(0.5 * view.size().max_element());
            let start: Vec<_> = sim.blocks().iter().map(|b| b.polygon.clone()).collect();
            let mut path = vec![sim.blocks()[0].polygon.centroid()];
            let o = judge_collision_with(&mut sim, |s| path.push(s.blocks()[0].polygon.centroid()));
            // Keep the path readable where a block flew off.
            path.retain(|p: &DVec2| {
                p.is_finite() && view.expanded(view.size().max_element()).contains(*p)
            });
            let file = format!("{}-{detector}.svg", case.name());
            std::fs::write(
                pictures.join(&file),
                outcome_svg(&sim, &start, &path, &view),
            )
            .map_err(|e| format!("{file}: {e}"))?;
            let paper = paper_says(case.case, detector);
            if detector == "cover" && !o.permissible {
                cover_wrong.push(case.case);
            }
            total += 1;
            if paper == o.permissible {
                agree += 1;
            } else {
                disagreements.push(format!("{} {paper_name}", case.case));
            }
            let word = |ok: bool| if ok { "right" } else { "wrong" };
            let why = if o.failures.is_empty() {
                String::new()
            } else {
                o.failures.join("; ")
            };
            let _ = writeln!(
                rows,
                "| {} | {paper_name} | {} | {} | {} | {:.3} | ({:.3}, {:.3}) | {} | [picture](results/robustness/{file}) |",
                case.case,
                word(paper),
                word(o.permissible),
                if paper == o.permissible {
                    "yes"
                } else {
                    "**no**"
                },
                1e3 * o.max_overlap,
                o.velocity[0],
                o.velocity[1],
                why,
            );
        }
    }
    let cover = if cover_wrong.is_empty() {
        "The cover detector is right in every case, as in the paper.".to_string()
    } else {
        format!("The cover detector is wrong in {}.", cover_wrong.join(", "))
    };
    let variants = variants_table()?;
    let md = format!(
        "# Robustness: the paper's section 4 cases\n\n\
         Written by `cargo xtask robustness` (do not edit by hand). Each of the paper's\n\
         section 4 cases (geometry and choices in `crates/dda-bench/src/hard_cases.rs`,\n\
         parameters of Tables 1 and 2) is run with each detector, and the outcome is judged\n\
         by the criteria in `crates/dda-bench/src/verdict.rs`: the run completes without\n\
         NaN; the blocks' geometric overlap stays below d_tol; A ends apart and moving away\n\
         from B, or at rest on it; kinetic plus elastic energy never rises more than 0.2%;\n\
         no spin beyond that energy. \"Paper\" is the paper's verdict from its text.\n\n\
         **{agree} of {total} verdicts agree with the paper.** {cover}\n\n\
         | case | detector | paper | ours | agree | max overlap (mm) | final velocity of A (m/s) | criteria not met | |\n\
         |---|---|---|---|---|---|---|---|---|\n{rows}\n\
         In the pictures the dashed outlines are the blocks at the start, the filled ones\n\
         at the end, and the red line is the path of A's centroid.\n\n\
         ## Where we disagree\n\n\
         Disagreements: {}.\n\n\
         Why we think they differ:\n\n\
         - **Geometry.** The paper gives its blocks only as figures (14-17). Ours match every\n\
           number in its text (11.4 deg tips, 18 edges of 0.35 m, 0.02 m edges, speeds), but\n\
           not the sizes, offsets and approach angles, and a type-based detector fails only\n\
           where a wrong vertex-edge pair falls within d_tol of the contact at the moment of\n\
           impact. A failure of the paper's that we do not reproduce needs the paper's exact\n\
           configuration, which the text does not give. The evidence, from the same cases\n\
           with A's approach moved (table below): in 4.4a the type-based detectors are\n\
           wrong in most of the 15 configurations around ours, as the paper found them in\n\
           its own; in 4.2, 4.3a and 4.4c they are right wherever the cover detector is.\n\
           In 4.4a they were right more often (TB-CD-1 in 11, TB-CD-2 in all 15) until\n\
           a flush joint's end kept its contact under them (2026-11-27, `docs/method.md`\n\
           section 5): a corner just outside the other block, along its edge and behind\n\
           its line, keeps the contact Shi's rule picks there, as the end of a compressed\n\
           joint must (an arch fell without it). That change was found by bisection;\n\
           how it turns these collisions was not traced.\n\
           In 4.2, 4.3a and 4.4c the paper's failures come from decisions of its type-based\n\
           code that ours, resolving vertex pairs as Shi's code does, does not make; its\n\
           text does not say which.\n\
         - **Energy and penetration in 4.4c.** We made block A small (7.2 kg) so that the\n\
           penalty of 3e6 N/m can stop it within d_tol = 0.01 m at all (90 J over 7.7 mm).\n\
           A block over 12 kg at 5 m/s could not be stopped within d_tol by any detector\n\
           (p d_tol^2 / 2 = 150 J); ours is stopped within it, so the type-based detectors\n\
           do not lose the contact either.\n\
         - **4.1 and 4.4a TB-CD-1.** Our type-based detectors resolve vertex pairs as\n\
           Shi's code does and give no vertex outside the other block a contact behind an\n\
           edge's line (`docs/method.md`, section 5). Before those rules TB-CD-1 threw A\n\
           out of both collisions, spinning, with 490 to 113,000 times its initial energy,\n\
           as the paper found; with them it is right. (They also made 4.1 TB-CD-2 right,\n\
           as the paper found it.) The paper's own type-based code is not published, so\n\
           which of its decisions failed there is not known.\n\n\
         ## Across approaches\n\n\
         Each case again with A's approach moved: shifted in x by -d_tol, -d_tol/2, 0,\n\
         d_tol/2 and d_tol, and turned by -2, 0 and 2 degrees about its lowest vertex\n\
         (`HardCase::scene_moved`), 15 configurations less those where A starts\n\
         overlapping B, each run three times as long as the case (a moved block may strike\n\
         later, or twice); each cell counts the configurations judged right.\n\n\
         | case | configurations | TB-CD-1 right | TB-CD-2 right | CB-CD right |\n\
         |---|---:|---:|---:|---:|\n{variants}\n\
         The one configuration of 4.3a that every detector gets wrong (shifted by d_tol,\n\
         not turned) ends with A still touching B and rising at 0.48 m/s after 0.9 s: the\n\
         run ends mid-bounce, and the verdict's last criterion cannot tell; no detector\n\
         finds a wrong contact there.\n\n\
         Reproduce: `cargo xtask robustness` (under a minute).\n",
        if disagreements.is_empty() {
            "none".to_string()
        } else {
            disagreements.join(", ")
        }
    );
    let path = docs.join("robustness.md");
    std::fs::write(&path, md).map_err(|e| format!("{}: {e}", path.display()))?;
    println!(
        "wrote {} ({agree} of {total} verdicts agree with the paper)",
        path.display()
    );
    Ok(())
}

/// The cases with A's approach moved (`HardCase::scene_moved`): per case, how many
/// configurations each detector gets right, as table rows.
fn variants_table() -> Result<String, String> {
    let mut rows = String::new();
    for case in HARD_CASES {
        let d_tol = case.contact_tolerance;
        let mut counted = 0;
        let mut right = [0usize; 3];
        for k in -2..=2 {
            for turn in [-2.0, 0.0, 2.0] {
                let dx = f64::from(k) * d_tol / 2.0;
                let mut scene = case.scene_moved(dx, turn);
                // A moved may strike later or twice: time for the collision to end.
                scene.analysis.duration *= 3.0;
                let validate = |scene: &dda_core::Scene| {
                    scene
                        .validate()
                        .map_err(|e| format!("{} moved: {}", case.name(), e.message))
                };
                let model = validate(&scene)?;
                let [a, b] = [&model.blocks[0].polygon, &model.blocks[1].polygon];
                if separation(a, b).0 <= 0.0 {
                    continue;
                }
                counted += 1;
                for (d, (detector, _)) in DETECTORS.iter().enumerate() {
                    scene.analysis.detector = (*detector).into();
                    let mut sim = Simulation::new(validate(&scene)?, RunOptions::default());
                    if judge_collision(&mut sim).permissible {
                        right[d] += 1;
                    }
                }
            }
        }
        let _ = writeln!(
            rows,
            "| {} | {counted} | {} | {} | {} |",
            case.case, right[0], right[1], right[2]
        );
    }
    Ok(rows)
}
