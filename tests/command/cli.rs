//! The `dda` command's contract (docs/cli.md): outputs, exit codes, overrides, and that bad
//! input writes nothing.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const SCENE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/scenes/sliding-block.toml"
);

fn dda(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_dda"))
        .args(args)
        .output()
        .unwrap()
}

/// `dda run SCENE --out OUT` with `extra` arguments.
fn run_scene(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run", SCENE, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    dda(&args)
}

/// A fresh scratch directory for one test.
pub(crate) fn scratch(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("dda-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

/// A test's scratch folder, removed when the test ends, passed or failed (a failing
/// assertion unwinds through the drop).
pub(crate) struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes the test scene with each `(from, to)` replaced (every `from` must be there)
/// into `dir/name`, and returns its path.
fn variant(dir: &Path, name: &str, changes: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(SCENE).unwrap();
    for (from, to) in changes {
        assert!(text.contains(from), "{from}");
        text = text.replace(from, to);
    }
    let file = dir.join(name);
    std::fs::write(&file, text).unwrap();
    file
}

/// `dda run FILE --out OUT --quiet` with `extra` arguments.
fn run_file(file: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ];
    args.extend_from_slice(extra);
    dda(&args)
}

/// Writes `text` as a scene `dir/scene.toml` and runs it, not quiet, into `dir/out`: the
/// output folder and what the run did (its standard error is the terminal report).
fn run_text(dir: &Path, text: &str) -> (PathBuf, Output) {
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = dda(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    (out, o)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn run_writes_summary_history_and_frames() {
    let dir = scratch("run");
    let out = dir.join("out");
    let o = run_scene(&out, &["--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["scene"], "sliding-block");
    assert_eq!(s["source"], SCENE);
    assert_eq!(s["detector"], "cover");
    // The scene names no rule: the default.
    assert_eq!(s["integration"], "damped-constant-acceleration");
    assert_eq!(s["status"], "completed");
    assert_eq!(s["time_simulated"], 0.2);
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains(SCENE), "the report names the scene file");
    let effects: Vec<&str> = s["effects"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    for e in [
        "elasticity",
        "inertia",
        "gravity",
        "fixed-blocks",
        "contact",
        "friction",
    ] {
        assert!(effects.contains(&e), "missing effect {e}: {effects:?}");
    }
    let steps = s["steps"].as_u64().unwrap();
    assert!(
        steps >= 200,
        "0.2 s at dt <= 0.001 needs at least 200 steps, got {steps}"
    );
    for key in ["total", "contact_detection", "assembly", "solve"] {
        assert!(s["seconds"][key].is_f64(), "seconds.{key}");
    }
    // The scene settles (a scene file does by default): how, and how long, is said.
    let settling = &s["settling"];
    assert!(settling["static_steps"].as_u64().unwrap() > 0, "{settling}");
    assert!(settling["converged"].is_boolean(), "{settling}");
    assert!(settling["seconds"].as_f64().unwrap() >= 0.0, "{settling}");
    // A few blocks under `auto`: settled by the direct solve.
    assert_eq!(settling["solver"], "direct", "{settling}");
    assert!(report.contains("settling before t = 0"));
    assert!(report.contains("solved directly"));
    assert_eq!(s["blocks"][1]["id"], "slider");
    let history = std::fs::read_to_string(out.join("history.csv")).unwrap();
    let mut lines = history.lines();
    assert!(lines.next().unwrap().starts_with("step,t,dt,oci"));
    assert_eq!(lines.count() as u64, steps);
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("<canvas") && report.contains("Kinetic energy"));
    assert!(
        !report.contains("http://") || !report.contains("src=\"http"),
        "no network"
    );
    let scene: dda_core::Scene =
        serde_json::from_str(&std::fs::read_to_string(out.join("scene.json")).unwrap()).unwrap();
    assert_eq!(scene.name, "sliding-block");
    for k in 0..=2 {
        let f = out.join(format!("frames/frame-{k:04}.svg"));
        assert!(
            std::fs::read_to_string(&f).unwrap().contains("<polygon"),
            "{f:?}"
        );
    }
}

/// The world box (min x, min y, max x, max y) an SVG frame shows, as its description
/// states it ("view: x A to B m, y C to D m; ...").
fn frame_box(svg: &str) -> [f64; 4] {
    let at = svg.find("<desc>view: x ").unwrap() + "<desc>view: x ".len();
    // "A to B m, y C to D m; ..."
    let words: Vec<&str> = svg[at..].split_whitespace().take(8).collect();
    let num = |w: &str| w.parse::<f64>().unwrap();
    [num(words[0]), num(words[5]), num(words[2]), num(words[7])]
}

/// A block that travels far from its start stays in every picture: the frames' view
/// holds where the run took it, not only where it started. The slider (1 m square) runs
/// 4 m along a frictionless base, four times its size, so a view of the start with its
/// quarter margin would lose it.
#[test]
fn pictures_show_a_block_that_travels_beyond_its_start() {
    let dir = scratch("travel");
    let file = variant(
        &dir,
        "far.toml",
        &[
            ("velocity = [1.0, 0.0]", "velocity = [10.0, 0.0]"),
            ("friction_deg = 20.0", "friction_deg = 0.0"),
            ("duration = 0.2", "duration = 0.4"),
        ],
    );
    let out = dir.join("out");
    let o = run_file(&file, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = &summary(&out)["blocks"][1]["centroid"];
    let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
    assert!(x > 3.5, "the slider went {x} m, not 4");
    let pictures: Vec<_> = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .map(|f| std::fs::read_to_string(f.unwrap().path()).unwrap())
        .collect();
    assert!(pictures.len() > 1);
    for svg in &pictures {
        let b = frame_box(svg);
        // The whole slider, start and end, with room around it.
        assert!(b[0] < 0.0 && b[2] > x + 0.5, "{b:?} misses x = {x}");
        assert!(b[1] < y - 0.5 && b[3] > y + 0.5, "{b:?} misses y = {y}");
    }
}

#[test]
fn same_scene_twice_gives_identical_summaries_apart_from_timing() {
    let dir = scratch("twice");
    let mut runs = Vec::new();
    for k in 0..2 {
        let out = dir.join(format!("r{k}"));
        assert!(run_scene(&out, &["--quiet"]).status.success());
        runs.push(untimed_summary(&out));
    }
    assert_eq!(runs[0], runs[1]);
}

#[test]
fn rtol_scales_tolerance_and_step_displacement_together() {
    let dir = scratch("rtol");
    let out = dir.join("out");
    let o = run_scene(&out, &["--rtol", "3", "--quiet"]);
    assert!(o.status.success());
    let s = summary(&out);
    assert!((s["contact_tolerance"].as_f64().unwrap() - 0.006).abs() < 1e-15);
    assert!((s["max_displacement"].as_f64().unwrap() - 0.003).abs() < 1e-15);
    let o = run_scene(&out, &["--rtol", "-1"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn detector_override_is_used() {
    let dir = scratch("det");
    let out = dir.join("out");
    let o = run_scene(&out, &["--detector", "type-2", "--quiet"]);
    assert!(o.status.success());
    assert_eq!(summary(&out)["detector"], "type-2");
    let o = run_scene(&out, &["--detector", "nope"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("analysis.detector"));
}

#[test]
fn bad_input_exits_2_names_file_key_line_and_writes_nothing() {
    let dir = scratch("bad");
    let text = std::fs::read_to_string(SCENE)
        .unwrap()
        .replace("normal_penalty = 1e9", "normal_penalty = -1e9");
    let bad = dir.join("bad.toml");
    std::fs::write(&bad, &text).unwrap();
    let line = text
        .lines()
        .position(|l| l.starts_with("normal_penalty"))
        .unwrap()
        + 1;
    let out = dir.join("out");
    for args in [
        vec!["run", bad.to_str().unwrap(), "--out", out.to_str().unwrap()],
        vec!["check", bad.to_str().unwrap()],
    ] {
        let o = dda(&args);
        assert_eq!(o.status.code(), Some(2));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(&format!("bad.toml:{line}")), "{err}");
        assert!(err.contains("analysis.normal_penalty"), "{err}");
    }
    assert!(!out.exists(), "bad input must not write outputs");
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1, "only bad.toml");
    // Geometry and setup errors found after parsing: exit 2 naming the key, nothing
    // written.
    let slider = "vertices = [[0.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]";
    let good = std::fs::read_to_string(SCENE).unwrap();
    for (name, text, key) in [
        (
            "clockwise.toml",
            good.replace(
                slider,
                "vertices = [[0.0, 1.0], [0.0, 2.0], [1.0, 2.0], [1.0, 1.0]]",
            ),
            "blocks[1].vertices",
        ),
        (
            "overlap.toml",
            good.replace(
                slider,
                "vertices = [[0.0, 0.5], [1.0, 0.5], [1.0, 1.5], [0.0, 1.5]]",
            ),
            "blocks[1].vertices",
        ),
        (
            "static.toml",
            good.replace("mode = \"dynamic\"", "mode = \"static\"")
                .replace(
                    slider,
                    "vertices = [[0.0, 3.0], [1.0, 3.0], [1.0, 4.0], [0.0, 4.0]]",
                ),
            "blocks[1]",
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, &text).unwrap();
        for args in [
            vec![
                "run",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
            vec!["check", file.to_str().unwrap()],
        ] {
            let o = dda(&args);
            assert_eq!(o.status.code(), Some(2), "{name}");
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(err.contains(&format!("{name}:")), "{err}");
            assert!(err.contains(key), "{err}");
        }
        assert!(!out.exists(), "{name}: bad input must not write outputs");
    }
    let o = dda(&["run", dir.join("missing.toml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let o = dda(&["run", "no-such-builtin"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn check_and_scenes() {
    let o = dda(&["check", SCENE]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("ok"));
    let o = dda(&["scenes"]);
    assert!(o.status.success());
    let listed = String::from_utf8_lossy(&o.stdout);
    for b in dda::bench::BUILTINS {
        assert!(listed.contains(b.name), "{listed}");
    }
}

/// A simulation that cannot go on (here: a penalty too soft for the motion, so that a
/// contact penetrates beyond d_tol) exits 1 and keeps its outputs up to the last good
/// state, with the reason.
#[test]
fn failed_simulation_exits_1_and_keeps_last_good_state() {
    let dir = scratch("fail");
    let scene = variant(
        &dir,
        "fail.toml",
        &[("normal_penalty = 1e9", "normal_penalty = 2e6")],
    );
    let out = dir.join("out");
    let o = run_file(&scene, &out, &[]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert!(
        s["error"].as_str().unwrap().contains("penetration"),
        "{}",
        s["error"]
    );
    let t = s["time_simulated"].as_f64().unwrap();
    assert!(t < 0.2);
    assert!(out.join("history.csv").exists());

    // The diagnosis: which blocks and contacts, the last step size tried.
    let f = &s["failure"];
    assert_eq!(f["t"].as_f64().unwrap(), t, "{f}");
    assert!(f["last_dt"].as_f64().unwrap() > 0.0, "{f}");
    let blocks: Vec<&str> = f["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b.as_str().unwrap())
        .collect();
    assert!(blocks.contains(&"slider"), "{f}");
    for c in f["contacts"].as_array().unwrap() {
        for k in ["vertex_block", "edge_block"] {
            assert!(blocks.contains(&c[k].as_str().unwrap()), "{c}");
        }
    }
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(
        report.contains("Why the run stopped"),
        "report shows the failure"
    );
    assert!(report.contains("slider"));

    // The last good state: a loadable checkpoint at the time reached, and the last frame.
    let path = out.join("checkpoint.bin");
    let ck = dda_core::Checkpoint::load(&path).unwrap();
    assert_eq!(ck.engine.state.t, t);
    let frames = std::fs::read_to_string(out.join("frames.jsonl")).unwrap();
    let last: serde_json::Value = serde_json::from_str(frames.lines().last().unwrap()).unwrap();
    assert_eq!(last["t"].as_f64().unwrap(), t);
    // A failed run resumes only with --keep-going: as it is, it would fail again the
    // same way.
    let before = listing(&out);
    let o = dda(&["resume", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--keep-going"));
    assert_eq!(listing(&out), before);
    let o = dda(&["resume", out.to_str().unwrap(), "--keep-going", "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["status"], "completed");
    assert!(s["time_simulated"].as_f64().unwrap() > t);
}

#[test]
fn render_redraws_frames_and_report_without_simulating() {
    let dir = scratch("render");
    let out = dir.join("out");
    assert!(run_scene(&out, &["--quiet"]).status.success());
    let read = |p: &str| std::fs::read(out.join(p)).unwrap();
    let report = read("report.html");
    let frame = read("frames/frame-0001.svg");
    let history = read("history.csv");
    std::fs::remove_dir_all(out.join("frames")).unwrap();
    std::fs::remove_file(out.join("report.html")).unwrap();
    let o = dda(&["render", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(read("report.html"), report);
    assert_eq!(read("frames/frame-0001.svg"), frame);
    assert_eq!(read("history.csv"), history, "render does not simulate");
    // A damaged frames.jsonl is bad input, named with its line.
    std::fs::write(out.join("frames.jsonl"), "{\"t\": 0}\n").unwrap();
    let o = dda(&["render", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("frames.jsonl: line 1"));
}

/// history.csv without its wall-clock columns (the last three).
fn untimed_history(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .map(|l| l.rsplitn(4, ',').last().unwrap().to_string())
        .collect()
}

fn untimed_summary(dir: &Path) -> serde_json::Value {
    let mut s = summary(dir);
    s["seconds"] = serde_json::Value::Null;
    if s["settling"].is_object() {
        s["settling"]["seconds"] = serde_json::Value::Null;
    }
    s
}

/// A run killed with SIGKILL at a random moment leaves a loadable checkpoint, damaged
/// copies of it are refused, and `dda resume` ends exactly as the uninterrupted run.
#[test]
fn killed_run_resumes_to_the_uninterrupted_result() {
    let dir = scratch("kill");
    let scene = "paper-5.1b-column-93";
    let whole = dir.join("whole");
    let o = dda(&["run", scene, "--out", whole.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));

    let seed = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos();
    let mut killed = None;
    for attempt in 0..4u32 {
        let out = dir.join(format!("run{attempt}"));
        let work = dir.join(format!(".run{attempt}.partial"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_dda"))
            .args(["run", scene, "--out", out.to_str().unwrap()])
            .args(["--checkpoint-every", "3", "--quiet"])
            .spawn()
            .unwrap();
        let started = std::time::Instant::now();
        while !work.join("checkpoint.bin").exists() {
            assert!(started.elapsed().as_secs() < 120, "no checkpoint written");
            if child.try_wait().unwrap().is_some() {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        // A random moment after the first checkpoint, shorter on each retry.
        let delay = (seed.wrapping_mul(2_654_435_761).wrapping_add(attempt) % 400) >> attempt;
        std::thread::sleep(std::time::Duration::from_millis(u64::from(delay)));
        let alive = child.try_wait().unwrap().is_none();
        child.kill().unwrap_or(()); // SIGKILL on Unix
        child.wait().unwrap();
        // Killed after it moved its results into place, the run had finished.
        if alive && !out.exists() {
            killed = Some((out, work, delay));
            break;
        }
    }
    let (out, work, delay) = killed.expect("the run always finished before it could be killed");
    let ck_path = work.join("checkpoint.bin");
    let ck = dda_core::Checkpoint::load(&ck_path)
        .unwrap_or_else(|e| panic!("killed {delay} ms after the first checkpoint: {e}"));
    assert!(ck.engine.state.totals.steps.is_multiple_of(3) && ck.engine.state.totals.steps > 0);
    assert!(!out.exists(), "an interrupted run is not moved into place");

    // Damaged copies are refused with the reason, and nothing is written.
    let good = std::fs::read(&ck_path).unwrap();
    for (name, bytes, says) in [
        ("cut", good[..good.len() / 2].to_vec(), "truncated"),
        (
            "flip",
            {
                let mut b = good.clone();
                let k = b.len() - 7;
                b[k] ^= 1;
                b
            },
            "corrupted",
        ),
    ] {
        let copy_work = dir.join(format!(".{name}.partial"));
        std::fs::create_dir_all(&copy_work).unwrap();
        for f in ["history.csv", "frames.jsonl", "scene.json", ".dda-run"] {
            std::fs::copy(work.join(f), copy_work.join(f)).unwrap();
        }
        std::fs::write(copy_work.join("checkpoint.bin"), bytes).unwrap();
        let o = dda(&["resume", dir.join(name).to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(says) && err.contains("checkpoint.bin"),
            "{err}"
        );
        assert!(!dir.join(name).exists(), "{name}: nothing written");
    }

    // A new run into the same output refuses to overwrite the interrupted one.
    let o = dda(&["run", scene, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("dda resume"));

    let o = dda(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!work.exists() && !out.join("checkpoint.bin").exists());
    assert_eq!(
        untimed_summary(&out),
        untimed_summary(&whole),
        "killed {delay} ms after the first checkpoint"
    );
    assert_eq!(
        untimed_history(&out.join("history.csv")),
        untimed_history(&whole.join("history.csv"))
    );
    for f in ["frames.jsonl", "scene.json", "frames/frame-0005.svg"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(whole.join(f)).unwrap(),
            "{f}"
        );
    }
}

/// A warning found by validation names the file and the line of its key, like an error.
#[test]
fn warnings_name_file_and_line() {
    let dir = scratch("warn");
    let text = std::fs::read_to_string(SCENE)
        .unwrap()
        .replace("contact_tolerance = 0.002", "contact_tolerance = 0.0015");
    let line = text
        .lines()
        .position(|l| l.starts_with("contact_tolerance"))
        .unwrap()
        + 1;
    let file = dir.join("warn.toml");
    std::fs::write(&file, &text).unwrap();
    let o = dda(&["check", file.to_str().unwrap()]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning"), "{err}");
    assert!(err.contains(&format!("warn.toml:{line}")), "{err}");
}

/// A penalty too soft for the contact tolerance (paper section 2.6) lets a contact
/// penetrate beyond d_tol: the run stops there (exit 1) with a diagnosis naming the
/// contact's blocks and the last good state; `--keep-going` goes on and records the
/// violation in summary.json's `warnings`. A penalty stiff enough runs through.
#[test]
fn a_penetration_beyond_the_tolerance_stops_the_run_unless_keep_going() {
    let dir = scratch("soft-penalty");
    for (penalty, name) in [("1e9", "stiff"), ("2e6", "soft")] {
        let penalty = format!("normal_penalty = {penalty}");
        let file = variant(
            &dir,
            &format!("{name}.toml"),
            &[("normal_penalty = 1e9", &penalty)],
        );
        for keep_going in [false, true] {
            let out = dir.join(format!("{name}-{keep_going}"));
            let o = run_file(
                &file,
                &out,
                if keep_going { &["--keep-going"] } else { &[] },
            );
            let err = String::from_utf8_lossy(&o.stderr);
            let s = summary(&out);
            let deeper =
                s["max_penetration"].as_f64().unwrap() > s["contact_tolerance"].as_f64().unwrap();
            let warned = s["warnings"].as_array().is_some_and(|w| !w.is_empty());
            match (name, keep_going) {
                ("stiff", _) => {
                    assert!(o.status.success(), "{err}");
                    assert!(!deeper && !warned, "{s}");
                }
                ("soft", false) => {
                    assert_eq!(o.status.code(), Some(1), "{err}");
                    assert_eq!(s["status"], "failed");
                    assert!(
                        err.contains("penetration") && err.contains("slider"),
                        "{err}"
                    );
                    let blocks = s["failure"]["blocks"].to_string();
                    assert!(blocks.contains("slider") && blocks.contains("base"), "{s}");
                    // The last good state is kept: no step beyond d_tol was taken.
                    assert!(!deeper, "{s}");
                    assert!(out.join("checkpoint.bin").exists());
                }
                _ => {
                    assert!(o.status.success(), "{err}");
                    assert!(deeper && warned, "{s}");
                    assert!(s["warnings"][0].as_str().unwrap().contains("penetration"));
                }
            }
        }
    }
}

/// Runs `dda` with `args`, killing it after `limit`: None if it had to be killed.
pub(crate) fn dda_within(args: &[&str], limit: std::time::Duration) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_dda"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let started = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > limit {
            child.kill().unwrap_or(());
            child.wait().unwrap();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    Some(child.wait_with_output().unwrap())
}

/// Names of the entries of `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Data loss: `--out` naming a folder of the user's, the working directory or an
/// ancestor of it is refused (exit 2) with every file left as it was; an earlier run
/// of ours is replaced, but not once the user has put a file of their own into it.
#[test]
fn run_never_deletes_or_overwrites_a_file_it_did_not_write() {
    let dir = scratch("data-loss");
    let mine = dir.join("mine");
    std::fs::create_dir_all(&mine).unwrap();
    std::fs::write(mine.join("notes.txt"), "mine").unwrap();
    std::fs::write(mine.join("summary.json"), "my own summary").unwrap();
    let o = run_scene(&mine, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("mine") && err.contains("not a dda run folder"),
        "{err}"
    );
    assert_eq!(listing(&mine), ["notes.txt", "summary.json"]);
    assert_eq!(
        std::fs::read_to_string(mine.join("summary.json")).unwrap(),
        "my own summary"
    );
    assert_eq!(listing(&dir), ["mine"], "no staging folder left");

    // The working directory and its ancestors.
    let cwd = dir.join("work").join("here");
    std::fs::create_dir_all(&cwd).unwrap();
    std::fs::write(cwd.join("keep.txt"), "keep").unwrap();
    for out in [".", "..", cwd.to_str().unwrap(), "../.."] {
        let o = Command::new(env!("CARGO_BIN_EXE_dda"))
            .args(["run", SCENE, "--out", out, "--quiet"])
            .current_dir(&cwd)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--out {out}");
        assert_eq!(listing(&cwd), ["keep.txt"], "--out {out}");
    }
    assert_eq!(listing(&dir.join("work")), ["here"]);

    // An earlier run of ours is replaced; with a file of the user's in it, it is not.
    let ours = dir.join("ours");
    assert!(run_scene(&ours, &["--quiet"]).status.success());
    assert!(run_scene(&ours, &["--quiet"]).status.success());
    std::fs::write(ours.join("frames").join("annotated.svg"), "mine").unwrap();
    let o = run_scene(&ours, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("frames/annotated.svg"));
    assert!(ours.join("frames").join("annotated.svg").exists());
    assert!(ours.join("summary.json").exists());
}

/// `--out` naming a symbolic link to an earlier run of ours is refused (exit 2): a run
/// replaces its folder whole, which would replace the link (the user's) after removing
/// the files of the run it points to. Before, the run removed those files through the
/// link, could not move its results over the link (exit 1, "Not a directory"), and left
/// them in a staging folder. A stopped run resumed through a link is refused the same way.
#[cfg(unix)]
#[test]
fn an_out_that_is_a_symbolic_link_is_refused_keeping_the_run_behind_it() {
    let dir = scratch("out-link");
    let ours = dir.join("ours");
    assert!(run_scene(&ours, &["--quiet"]).status.success());
    let before = listing(&ours);
    let summary = std::fs::read_to_string(ours.join("summary.json")).unwrap();
    let link = dir.join("link");
    std::os::unix::fs::symlink(&ours, &link).unwrap();
    let o = run_scene(&link, &["--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("link") && err.contains("symbolic link"),
        "{err}"
    );
    assert_eq!(listing(&ours), before);
    assert_eq!(
        std::fs::read_to_string(ours.join("summary.json")).unwrap(),
        summary
    );
    assert_eq!(listing(&dir), ["link", "ours"], "no staging folder left");

    // A stopped run, resumed through a link to it.
    let stopped = dir.join("stopped");
    let o = run_scene(&stopped, &["--quiet", "--max-steps", "2"]);
    assert_eq!(o.status.code(), Some(1));
    let before = listing(&stopped);
    let to_stopped = dir.join("to-stopped");
    std::os::unix::fs::symlink(&stopped, &to_stopped).unwrap();
    let o = dda(&["resume", to_stopped.to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("symbolic link"));
    assert_eq!(listing(&stopped), before);
    assert!(stopped.join("checkpoint.bin").is_file());
}

/// Malformed JSON whose key/line locator once looped forever (`[}`) gets an answer at
/// once: exit 2 naming the file.
#[test]
fn malformed_json_is_answered_at_once() {
    let dir = scratch("json-hang");
    for (k, text) in ["[}", "{\"a\":[}", "{\"name\": [1 }", "[[[[}"]
        .iter()
        .enumerate()
    {
        let file = dir.join(format!("m{k}.json"));
        std::fs::write(&file, text).unwrap();
        for cmd in ["check", "run"] {
            let o = dda_within(
                &[cmd, file.to_str().unwrap(), "--quiet"][..if cmd == "check" { 2 } else { 3 }],
                std::time::Duration::from_secs(20),
            )
            .unwrap_or_else(|| panic!("`dda {cmd}` hung on {text}"));
            assert_eq!(o.status.code(), Some(2), "{text}");
            assert!(String::from_utf8_lossy(&o.stderr).contains(&format!("m{k}.json")));
        }
    }
}

/// A scene file that is not a regular file gets an answer at once, exit 2 naming it:
/// a pipe named like a scene blocked the read until a writer came (forever), and a
/// link to /dev/zero read without end.
#[cfg(unix)]
#[test]
fn a_scene_that_is_no_regular_file_is_refused_at_once() {
    let dir = scratch("not-a-file");
    let zero = dir.join("zero.toml");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let folder = dir.join("folder.toml");
    std::fs::create_dir(&folder).unwrap();
    let mut files = vec![zero, folder];
    let pipe = dir.join("pipe.toml");
    if Command::new("mkfifo")
        .arg(&pipe)
        .status()
        .is_ok_and(|s| s.success())
    {
        files.push(pipe);
    }
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        for cmd in ["check", "run"] {
            let o = dda_within(
                &[cmd, file.to_str().unwrap()],
                std::time::Duration::from_secs(20),
            )
            .unwrap_or_else(|| panic!("`dda {cmd}` hung on {name}"));
            assert_eq!(o.status.code(), Some(2), "{name}");
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                err.contains(&name) && err.contains("not a regular file"),
                "{err}"
            );
        }
    }
}

/// Nesting 50,000 deep once overflowed the stack (exit 134): now exit 2, naming the
/// file, the line and the documented depth, in either format.
#[test]
fn deep_nesting_is_refused_not_a_crash() {
    let dir = scratch("deep");
    let n = 50_000;
    for (name, text) in [
        (
            "deep.json",
            format!("{}1{}", "{\"a\":".repeat(n), "}".repeat(n)),
        ),
        (
            "deep-array.json",
            format!("{}{}", "[".repeat(n), "]".repeat(n)),
        ),
        (
            "deep.toml",
            format!("name = \"x\"\na = {}{}", "[".repeat(n), "]".repeat(n)),
        ),
        (
            "deep-table.toml",
            format!("a = {}1{}", "{b=".repeat(n), "}".repeat(n)),
        ),
    ] {
        let file = dir.join(name);
        std::fs::write(&file, text).unwrap();
        let o = dda_within(
            &["check", file.to_str().unwrap()],
            std::time::Duration::from_secs(20),
        )
        .unwrap_or_else(|| panic!("{name} hung"));
        assert_eq!(o.status.code(), Some(2), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(name) && err.contains("deeper than 64"),
            "{err}"
        );
    }
}

/// Waits until `path` exists (a run has got that far), for at most a minute.
fn wait_for(path: &Path) {
    let started = std::time::Instant::now();
    while !path.exists() {
        assert!(
            started.elapsed().as_secs() < 60,
            "{} never appeared",
            path.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// One process per run folder: while a run works, a second `run` or `resume` into its
/// folder exits 2 at once naming the process that holds it; once the first has ended
/// (here killed, so its lock died with it), a new run may start.
#[test]
fn a_second_run_into_a_busy_folder_is_refused_naming_the_process() {
    let dir = scratch("lock");
    let out = dir.join("out");
    let mut first = Command::new(env!("CARGO_BIN_EXE_dda"))
        .args([
            "run",
            "paper-5.2b-column-826",
            "--out",
            out.to_str().unwrap(),
            "--quiet",
        ])
        .spawn()
        .unwrap();
    wait_for(&dir.join(".out.partial").join("history.csv"));
    for args in [
        vec![
            "run",
            "paper-5.2b-column-826",
            "--out",
            out.to_str().unwrap(),
        ],
        vec!["resume", out.to_str().unwrap()],
    ] {
        let o = dda(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("in use") && err.contains(&first.id().to_string()),
            "{err}"
        );
    }
    let alive = first.try_wait().unwrap().is_none();
    first.kill().unwrap_or(());
    first.wait().unwrap();
    assert!(alive, "the first run ended before it could be raced");
    // Killed without a checkpoint: its staging folder is a leftover of ours, reused.
    assert!(run_scene(&out, &["--quiet"]).status.success());
}

/// SIGINT, SIGTERM and SIGHUP end a run at the end of a step with a checkpoint (no
/// `--checkpoint-every` given), outputs flushed, exit 130 / 143 / 129 and a line naming
/// `dda resume`; the resumed run ends exactly as the uninterrupted one.
#[cfg(unix)]
#[test]
fn signals_end_a_run_with_a_checkpoint_that_resumes_bit_for_bit() {
    let dir = scratch("signals");
    let scene = "paper-5.2a-column-229";
    let whole = dir.join("whole");
    assert!(
        dda(&["run", scene, "--out", whole.to_str().unwrap(), "--quiet"])
            .status
            .success()
    );
    for (signal, code) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        let out = dir.join(signal);
        let child = Command::new(env!("CARGO_BIN_EXE_dda"))
            .args(["run", scene, "--out", out.to_str().unwrap(), "--quiet"])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let work = dir.join(format!(".{signal}.partial"));
        // Some steps in, so that the checkpoint is not of the start.
        let history = work.join("history.csv");
        let started = std::time::Instant::now();
        while std::fs::metadata(&history).map_or(0, |m| m.len()) < 4096 {
            assert!(started.elapsed().as_secs() < 60, "the run never got going");
            std::thread::sleep(std::time::Duration::from_millis(2));
        }
        let sent = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(sent.success());
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "SIG{signal}: {err}");
        assert!(
            err.contains(&format!("SIG{signal}")) && err.contains("dda resume"),
            "{err}"
        );
        let ck = dda_core::Checkpoint::load(&work.join("checkpoint.bin")).unwrap();
        assert!(ck.engine.state.totals.steps > 0);
        assert!(!out.exists(), "an interrupted run is not moved into place");
        let o = dda(&["resume", out.to_str().unwrap(), "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(
            untimed_summary(&out),
            untimed_summary(&whole),
            "SIG{signal}"
        );
        assert_eq!(
            untimed_history(&out.join("history.csv")),
            untimed_history(&whole.join("history.csv")),
            "SIG{signal}"
        );
        assert_eq!(
            std::fs::read(out.join("frames.jsonl")).unwrap(),
            std::fs::read(whole.join("frames.jsonl")).unwrap()
        );
    }
}

/// A wall of `courses` courses of twenty 1 m x 0.5 m bricks in running bond, soft
/// against the penalty (E = 1e9 Pa, p = 1e10 N/m), on a fixed base tilted 40 degrees,
/// friction 30: its settling takes hundreds of static steps (a second or so), and the
/// run 0.01 s.
fn settling_wall(courses: usize) -> String {
    let (s, c) = 40f64.to_radians().sin_cos();
    let pt = |x: f64, y: f64| format!("[{}, {}]", x * c - y * s, x * s + y * c);
    let mut t = String::from(
        "name = \"settling-wall\"\n[analysis]\nduration = 0.01\ntime_step = 0.001\n\
         max_displacement = 0.002\nnormal_penalty = 1e10\ngravity = [0.0, -9.81]\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n\
         [joints.default]\nfriction_deg = 30.0\n",
    );
    let block = |t: &mut String, id: String, x0: f64, x1: f64, y0: f64, y1: f64, fixed: bool| {
        t.push_str(&format!(
            "[[blocks]]\nid = \"{id}\"\nmaterial = \"rock\"\nvertices = [{}, {}, {}, {}]\n{}",
            pt(x0, y0),
            pt(x1, y0),
            pt(x1, y1),
            pt(x0, y1),
            if fixed { "fixed = true\n" } else { "" }
        ));
    };
    block(&mut t, "base".into(), -5.0, 30.0, -1.0, 0.0, true);
    for r in 0..courses {
        let (y0, y1) = (0.5 * r as f64, 0.5 * (r + 1) as f64);
        let mut xs = vec![0.0];
        let first = if r % 2 == 1 { 0.5 } else { 1.0 };
        xs.extend((0..20).map(|k| first + k as f64).filter(|&x| x < 20.0));
        xs.push(20.0);
        for (k, w) in xs.windows(2).enumerate() {
            block(&mut t, format!("b{r}-{k}"), w[0], w[1], y0, y1, false);
        }
    }
    t
}

/// A scene whose free blocks all start in flight has nothing to settle (they are held
/// where they are while the others settle, and here there are no others): the run says
/// so after announcing the settling, rather than falling silent, and starts as written.
#[test]
fn a_run_with_nothing_resting_says_it_had_nothing_to_settle() {
    let dir = scratch("nothing-to-settle");
    let (out, o) = run_text(
        &dir,
        "name = \"drop\"\n[analysis]\nduration = 0.01\ntime_step = 0.001\n\
         max_displacement = 0.002\nnormal_penalty = 1e10\ngravity = [0.0, -9.81]\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n\
         [[blocks]]\nid = \"floor\"\nmaterial = \"rock\"\nfixed = true\n\
         vertices = [[0.0, -1.0], [4.0, -1.0], [4.0, 0.0], [0.0, 0.0]]\n\
         [[blocks]]\nid = \"stone\"\nmaterial = \"rock\"\n\
         vertices = [[1.0, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]]\n",
    );
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    assert!(said.contains("settling: static steps"), "{said}");
    assert!(said.contains("nothing to settle"), "{said}");
    assert!(!said.contains("settled in"), "{said}");
    assert!(summary(&out).get("settling").is_none());
}

/// A run names the block whose motion held its time step: a chip sliding at 20 m/s on a
/// frictionless floor, the only free block, holds dt to d_max over its speed (0.5 ms),
/// below the 1 ms asked for, in most of its steps, and summary.json's `held_by` lists it
/// first, with the steps it held. (A block in flight, clear of every other, is no longer
/// held to d_max: `Simulation::set_flight_room`.)
#[test]
fn a_run_names_the_block_that_held_its_time_step() {
    let dir = scratch("held-by");
    let (out, o) = run_text(
        &dir,
        "name = \"chip\"\n[analysis]\nduration = 0.3\ntime_step = 0.001\n\
         max_displacement = 0.01\nnormal_penalty = 1e9\ngravity = [0.0, -9.81]\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e10\npoisson = 0.25\n\
         [[blocks]]\nid = \"floor\"\nmaterial = \"rock\"\nfixed = true\n\
         vertices = [[-1.0, -3.0], [10.0, -3.0], [10.0, -2.0], [-1.0, -2.0]]\n\
         [[blocks]]\nid = \"chip\"\nmaterial = \"rock\"\n\
         vertices = [[0.0, -2.0], [0.03, -2.0], [0.03, -1.97], [0.0, -1.97]]\n\
         velocity = [20.0, 0.0]\n",
    );
    let said = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{said}");
    let s = summary(&out);
    let steps = s["steps"].as_u64().unwrap();
    let held = &s["held_by"][0];
    assert_eq!(held["block"], "chip", "{s}");
    assert!(held["steps"].as_u64().unwrap() * 2 > steps, "{s}");
    assert!(said.contains("most often `chip`"), "{said}");
}

/// A signal while the blocks settle (before t = 0) ends the settling at its next static
/// step: exit 130, a checkpoint holding the blocks as the scene gave them (no step
/// taken, not settled), a line naming `dda resume`; resumed, the run settles again and
/// ends exactly as the uninterrupted one.
#[cfg(unix)]
#[test]
fn a_signal_while_settling_ends_it_and_the_run_resumes_bit_for_bit() {
    use std::io::BufRead;
    let dir = scratch("settle-signal");
    let scene = dir.join("wall.toml");
    std::fs::write(&scene, settling_wall(12)).unwrap();
    let scene = scene.to_str().unwrap();
    let whole = dir.join("whole");
    let o = dda(&["run", scene, "--out", whole.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(summary(&whole)["steps"].as_u64().unwrap() > 0);
    let out = dir.join("int");
    let mut child = Command::new(env!("CARGO_BIN_EXE_dda"))
        .args(["run", scene, "--out", out.to_str().unwrap()])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut said = String::new();
    while !said.contains("settling:") {
        let mut line = String::new();
        assert!(err.read_line(&mut line).unwrap() > 0, "{said}");
        said.push_str(&line);
    }
    let sent = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut err, &mut rest).unwrap();
    said.push_str(&rest);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{said}");
    assert!(
        said.contains("SIGINT") && said.contains("dda resume"),
        "{said}"
    );
    assert!(
        !said.contains("settled in"),
        "the settling ended before the signal: {said}"
    );
    let ck = dda_core::Checkpoint::load(&dir.join(".int.partial").join("checkpoint.bin")).unwrap();
    assert_eq!(ck.engine.state.totals.steps, 0);
    assert!(!ck.engine.state.settled);
    let o = dda(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(untimed_summary(&out), untimed_summary(&whole));
    assert_eq!(
        untimed_history(&out.join("history.csv")),
        untimed_history(&whole.join("history.csv"))
    );
}

/// Absurd values are refused by `dda check` with file, key and line, where they once
/// passed and failed late or never ended; arrays of the wrong length are errors in TOML
/// as in JSON (TOML once dropped the extra components).
#[test]
fn absurd_values_and_wrong_lengths_are_refused_by_check() {
    let dir = scratch("absurd");
    let good = std::fs::read_to_string(SCENE).unwrap();
    let slider_vertices = "vertices = [[0.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]";
    for (name, from, to, key) in [
        (
            "speed",
            "velocity = [1.0, 0.0]",
            "velocity = [1e308, 0.0]",
            "blocks[1].velocity[0]",
        ),
        (
            "long",
            "duration = 0.2",
            "duration = 1e308",
            "analysis.duration",
        ),
        (
            "short",
            "duration = 0.2",
            "duration = 1e-300",
            "analysis.duration",
        ),
        (
            "dense",
            "density = 2600.0",
            "density = 1e308",
            "materials.rock.density",
        ),
        (
            "steps",
            "duration = 0.2",
            "duration = 1e7",
            "analysis.duration",
        ),
        (
            "penalty",
            "normal_penalty = 1e9",
            "normal_penalty = 1e300",
            "analysis.normal_penalty",
        ),
        (
            "vertex3",
            slider_vertices,
            "vertices = [[0.0, 1.0, 5.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]",
            "blocks[1].vertices[0]",
        ),
        (
            "gravity4",
            "gravity = [0.0, -9.81]",
            "gravity = [0.0, -9.81, 0.0, 1.0]",
            "analysis.gravity",
        ),
        (
            "gravity1",
            "gravity = [0.0, -9.81]",
            "gravity = [-9.81]",
            "analysis.gravity",
        ),
    ] {
        assert!(good.contains(from), "{name}");
        let text = good.replace(from, to);
        let line = text
            .lines()
            .position(|l| l.contains(to.lines().next().unwrap()))
            .unwrap()
            + 1;
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, &text).unwrap();
        let o = dda(&["check", file.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(&format!("{name}.toml:{line}")),
            "{name}: {err}"
        );
        assert!(err.contains(key), "{name}: {err}");
        // The same scene as JSON is refused the same way.
        let (scene, _) = dda_core::Scene::load(Path::new(SCENE)).unwrap();
        let mut v = serde_json::to_value(&scene).unwrap();
        if name == "vertex3" {
            v["blocks"][1]["vertices"][0] = serde_json::json!([0.0, 1.0, 5.0]);
            let json = dir.join(format!("{name}.json"));
            std::fs::write(&json, serde_json::to_string_pretty(&v).unwrap()).unwrap();
            let o = dda(&["check", json.to_str().unwrap()]);
            assert_eq!(o.status.code(), Some(2));
            assert!(String::from_utf8_lossy(&o.stderr).contains(key));
        }
    }
}

/// A scene whose blocks are all fixed once passed check and failed with an internal
/// message of the solver; it is refused at check time in the user's words.
#[test]
fn a_scene_with_nothing_free_to_move_is_refused_at_check() {
    let dir = scratch("all-fixed");
    let file = variant(
        &dir,
        "fixed.toml",
        &[("velocity = [1.0, 0.0]", "fixed = true")],
    );
    for cmd in ["check", "run"] {
        let o = dda(&[cmd, file.to_str().unwrap()]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains("nothing can move") && err.contains("fixed.toml"),
            "{err}"
        );
        assert!(
            !err.contains("faer") && !err.contains("simplicial"),
            "{err}"
        );
    }
}

/// A block driven at 1,000 m/s into the base once passed through it, creating energy,
/// and the run "completed": now the run stops with exit 1 at the first step whose
/// penetration passes d_tol, names the blocks, and keeps the last good state.
#[test]
fn broken_physics_is_a_failure_not_a_success() {
    let dir = scratch("broken");
    let file = variant(
        &dir,
        "fast.toml",
        &[("velocity = [1.0, 0.0]", "velocity = [0.0, -1000.0]")],
    );
    let out = dir.join("out");
    let o = run_file(&file, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    let blocks = s["failure"]["blocks"].to_string();
    assert!(blocks.contains("slider") && blocks.contains("base"), "{s}");
    assert!(
        s["max_penetration"].as_f64().unwrap() <= s["contact_tolerance"].as_f64().unwrap(),
        "the last good state is before the violation: {s}"
    );
    // The slider never passed the base's top (y = 1) by more than d_tol.
    let y = s["blocks"][1]["centroid"][1].as_f64().unwrap();
    assert!(
        y - 0.5 >= 1.0 - s["contact_tolerance"].as_f64().unwrap(),
        "{s}"
    );
}

/// `--max-steps` caps any run: exit 1, status "stopped", the state kept.
#[test]
fn max_steps_caps_a_run() {
    let dir = scratch("max-steps");
    let out = dir.join("out");
    let o = run_scene(&out, &["--quiet", "--max-steps", "7"]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["status"], "stopped");
    assert_eq!(s["steps"], 7);
    assert!(out.join("checkpoint.bin").exists());
    assert_eq!(
        run_scene(&out, &["--max-steps", "0"]).status.code(),
        Some(2)
    );
}

/// A step far larger than the motion allows is no longer taken: the sliding block at
/// 1 m/s with `time_step = 10` s once ended where it started at 1 m/s after two steps.
/// Friction mu g must stop it after v0^2 / (2 mu g) = 0.140 m (mu = tan 20 deg); the
/// tolerance allows the distance the block covers in the steps around its stop, a few
/// d_max (1 mm) each, and a residual speed of 1% of v0.
#[test]
fn the_step_respects_the_motion_it_starts_with() {
    let dir = scratch("big-step");
    let changes = [
        ("time_step = 0.001", "time_step = 10"),
        ("duration = 0.2", "duration = 20"),
    ];
    let file = variant(&dir, "big.toml", &changes);
    let out = dir.join("out");
    let o = run_file(&file, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let mu = 20f64.to_radians().tan();
    let expected = 1.0 / (2.0 * mu * 9.81);
    let moved = s["blocks"][1]["centroid"][0].as_f64().unwrap() - 0.5;
    assert!(
        (moved - expected).abs() < 5e-3,
        "moved {moved} m, expected {expected} m"
    );
    let v = s["blocks"][1]["velocity"][0].as_f64().unwrap();
    assert!(v.abs() < 0.01, "still moving at {v} m/s");
}

/// A factor too large for the memory allowed is an error (exit 1) with the estimate,
/// the system's size and the solve that needs no factor, not an abort.
#[test]
fn a_factor_too_large_for_memory_exits_1_with_the_estimate() {
    let dir = scratch("memory");
    let out = dir.join("out");
    let o = run_scene(&out, &["--quiet", "--max-memory", "1K"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("needs about")
            && err.contains("unknowns")
            && err.contains("solver = \"iterative\""),
        "{err}"
    );
    assert_eq!(summary(&out)["status"], "failed");
    assert_eq!(
        run_scene(&out, &["--max-memory", "lots"]).status.code(),
        Some(2)
    );
}

/// Write failures (a file where a folder must go, a file size limit standing in for a
/// full disk) name the path and the system's error, exit 1 (not the bad-input 2), and
/// leave no staging folder or temporary file behind.
#[test]
fn write_failures_exit_1_naming_the_path_and_leave_nothing_behind() {
    let dir = scratch("write-fail");
    std::fs::write(dir.join("afile"), "x").unwrap();
    let out = dir.join("afile").join("out");
    let o = run_scene(&out, &["--quiet"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("afile"), "{err}");
    assert_eq!(listing(&dir), ["afile"]);
    #[cfg(unix)]
    for blocks in [40, 400] {
        // `ulimit -f` (512-byte blocks) makes a write past the limit fail with EFBIG;
        // the shell ignores SIGXFSZ, which `exec` passes on.
        let out = dir.join(format!("fsize{blocks}"));
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -f {blocks}; trap '' XFSZ; exec \"$0\" run paper-5.1b-column-93 \
                 --out \"$1\" --quiet --checkpoint-every 5"
            ))
            .arg(env!("CARGO_BIN_EXE_dda"))
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{blocks}: {err}");
        assert!(err.contains(".fsize") && err.contains("too large"), "{err}");
        assert_eq!(listing(&dir), ["afile"], "{blocks}");
    }
}

/// A reader that has gone before `dda` writes (`dda scenes | head -0`) ends the listing
/// quietly: exit 0 and no panic, where `println!` panicked on the broken pipe.
#[test]
fn a_closed_standard_output_is_not_a_panic() {
    for args in [&["scenes"][..], &["check", "paper-5.1a-column-20"][..]] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let o = Command::new(env!("CARGO_BIN_EXE_dda"))
            .args(args)
            .stdout(writer)
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
    }
}

/// The terminal counts the free blocks and the fixed ones apart: the 20-block column
/// stands on a fixed base, 21 blocks in all; the sliding block's scene has one of each.
#[test]
fn the_terminal_counts_free_and_fixed_blocks_apart() {
    let dir = scratch("counts");
    let out = dir.join("out");
    let o = dda(&[
        "run",
        "paper-5.1a-column-20",
        "--max-steps",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(": 20 blocks and 1 fixed ("), "{err}");
    // One free block is one block; a run stopped between steps says its time as a
    // person reads it (six significant digits), not to the last bit.
    let one = dda(&[
        "run",
        SCENE,
        "--max-steps",
        "3",
        "--out",
        dir.join("one").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&one.stderr);
    assert!(err.contains(": 1 block and 1 fixed ("), "{err}");
    let t = err
        .split(" s simulated")
        .next()
        .unwrap()
        .rsplit('\n')
        .next()
        .unwrap();
    let digits = t
        .trim_start_matches(['0', '.'])
        .chars()
        .filter(char::is_ascii_digit);
    assert!(
        t.parse::<f64>().is_ok() && digits.count() <= 6,
        "{t:?} in {err}"
    );
}

const SLOPE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/scenes/jointed-slope.toml"
);

/// `dda build` writes the scene with its regions cut into blocks, every block listed, and
/// never replaces a file; the run of a scene with regions records the same explicit
/// scene, which runs again to the same history.
#[test]
fn build_writes_the_explicit_scene_and_a_run_records_it() {
    let dir = scratch("build");
    let built = dir.join("built.json");
    let o = dda(&["build", SLOPE, "--out", built.to_str().unwrap()]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = std::fs::read_to_string(&built).unwrap();
    let explicit: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(explicit.get("regions").is_none() && explicit.get("joint_sets").is_none());
    let ids: Vec<&str> = explicit["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["id"].as_str().unwrap())
        .collect();
    assert_eq!(ids[0], "base.1");
    assert!(ids.contains(&"slope.1") && ids.len() > 20, "{ids:?}");
    // Never replaced: exit 2, the file as it was.
    let again = dda(&["build", SLOPE, "--out", built.to_str().unwrap()]);
    assert_eq!(again.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(&built).unwrap(), text);
    // A short run records the explicit scene; running that repeats the history.
    let short = dir.join("short.toml");
    let scene = std::fs::read_to_string(SLOPE)
        .unwrap()
        .replace("duration = 0.5", "duration = 0.01");
    std::fs::write(&short, scene).unwrap();
    let (first, second) = (dir.join("first"), dir.join("second"));
    let o = dda(&[
        "run",
        short.to_str().unwrap(),
        "--out",
        first.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let recorded = first.join("scene.json");
    let recorded_text = std::fs::read_to_string(&recorded).unwrap();
    assert!(!recorded_text.contains("\"regions\""));
    let o = dda(&[
        "run",
        recorded.to_str().unwrap(),
        "--out",
        second.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let history = |d: &Path| -> Vec<String> {
        std::fs::read_to_string(d.join("history.csv"))
            .unwrap()
            .lines()
            .map(|l| l.split(',').take(10).collect::<Vec<_>>().join(","))
            .collect()
    };
    assert_eq!(history(&first), history(&second));
}

/// An excavation: `summary.json` lists what it removed and when, its `blocks` only those
/// present at the end; the frames after it draw the removed pieces no more, and `dda
/// render` redraws the run from them; the recorded `scene.json` runs to the same history.
#[test]
fn an_excavation_is_reported_and_its_run_renders_and_repeats() {
    let dir = scratch("excavation");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/excavation.toml");
    let out = dir.join("out");
    let o = run_file(Path::new(scene), &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let removed = s["removed"].as_array().unwrap();
    assert_eq!(removed.len(), 1);
    assert_eq!(removed[0]["id"], "wall.2.6");
    assert_eq!(removed[0]["t"], 0.05);
    let ids: Vec<&str> = s["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| b["id"].as_str().unwrap())
        .collect();
    assert!(
        !ids.contains(&"wall.2.6") && ids.contains(&"wall.2.5"),
        "{ids:?}"
    );
    let frames = std::fs::read_to_string(out.join("frames.jsonl")).unwrap();
    let last: serde_json::Value = serde_json::from_str(frames.lines().last().unwrap()).unwrap();
    let first: serde_json::Value = serde_json::from_str(frames.lines().next().unwrap()).unwrap();
    // Block 7 of the scene as run (the ground, then wall.1, wall.2.1, ...) is wall.2.6.
    assert!(!first["blocks"][7].as_array().unwrap().is_empty());
    assert!(last["blocks"][7].as_array().unwrap().is_empty());
    let o = dda(&["render", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The report plots the measured point and the bolt from their tables.
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    for title in [
        "Displacement of `crest`",
        "Velocity of `crest`",
        "Bolt tension",
    ] {
        assert!(report.contains(title), "{title}");
    }
    let again = dir.join("again");
    let o = run_file(&out.join("scene.json"), &again, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let cut = |p: &Path| -> Vec<String> {
        std::fs::read_to_string(p.join("history.csv"))
            .unwrap()
            .lines()
            .map(|l| l.split(',').take(9).collect::<Vec<_>>().join(","))
            .collect()
    };
    assert_eq!(cut(&out), cut(&again));
    // The bolt and the measured point: a row each per step.
    let steps = s["steps"].as_u64().unwrap() as usize;
    let table = |p: &Path, name: &str| std::fs::read_to_string(p.join(name)).unwrap();
    assert_eq!(table(&out, "measurements.csv").lines().count(), steps + 1);
    assert_eq!(table(&out, "bolts.csv").lines().count(), steps + 1);
    assert_eq!(s["bolts"][0]["from_block"], "wall.4");
    // The wall settles under gravity onto the contact springs beneath it, shortening
    // the bolt from its pretension of 1000 N; bolts.csv's last row says the same.
    let tension = s["bolts"][0]["tension"].as_f64().unwrap();
    assert!(tension < 1000.0 - 1.0, "{tension}");
    let last = table(&out, "bolts.csv").lines().last().unwrap().to_string();
    let field: f64 = last.split(',').nth(4).unwrap().parse().unwrap();
    assert_eq!(field, tension, "{last}");
}

/// summary.json gives each block's stress: the test scene's 1 m block at rest on the
/// base (a static analysis) carries its weight, so its mean vertical stress is
/// -rho g h / 2 = -2600 x 9.81 x 1 / 2 = -12,753 Pa (the stress falls linearly from the
/// base to the free top; a DDA block's stress is its mean), within 1e-3.
#[test]
fn summary_gives_each_blocks_stress() {
    let dir = scratch("stress");
    let file = variant(
        &dir,
        "rest.toml",
        &[
            ("mode = \"dynamic\"", "mode = \"static\""),
            ("velocity = [1.0, 0.0]", ""),
        ],
    );
    let out = dir.join("out");
    let o = run_file(&file, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    let slider = s["blocks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|b| b["id"] == "slider")
        .unwrap();
    let syy = slider["stress"][1].as_f64().unwrap();
    let expected = -2600.0 * 9.81 * 1.0 / 2.0;
    assert!(
        (syy - expected).abs() < 1e-3 * expected.abs(),
        "syy {syy} Pa, expected {expected}"
    );
    let base = &s["blocks"][0]["stress"];
    assert_eq!(base, &serde_json::json!([0.0, 0.0, 0.0]), "the fixed base");
}

/// A seismic record's faults are bad input: exit 2 naming the record's file and line
/// (or, for a record that cannot be read, the scene's file, key and line), nothing
/// written; a good record's run gives the effect and a measured point.
#[test]
fn seismic_records_are_read_beside_the_scene_and_their_faults_named() {
    let dir = scratch("seismic");
    let here = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes");
    let scene = std::fs::read_to_string(format!("{here}/quake.toml")).unwrap();
    let record = std::fs::read_to_string(format!("{here}/quake.csv")).unwrap();
    std::fs::write(dir.join("quake.toml"), &scene).unwrap();
    let out = dir.join("out");
    let key_line = scene.lines().position(|l| l.starts_with("record")).unwrap() + 1;
    // No record file: the scene's key and line.
    let o = run_file(&dir.join("quake.toml"), &out, &[]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("quake.toml:{key_line}"))
            && err.contains("seismic.record")
            && err.contains("quake.csv"),
        "{err}"
    );
    assert!(!out.exists());
    // A non-numeric cell on line 5, times going back on line 7: the record's line.
    let lines: Vec<String> = record.lines().map(String::from).collect();
    for (line, cell, says) in [
        (5, "0.04, 1.5x, 0", "`1.5x`"),
        (7, "0.01, 0, 0", "increase"),
    ] {
        let mut bad = lines.clone();
        bad[line - 1] = cell.to_string();
        std::fs::write(dir.join("quake.csv"), bad.join("\n")).unwrap();
        for args in [
            vec!["check", dir.join("quake.toml").to_str().unwrap()],
            vec![
                "run",
                dir.join("quake.toml").to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ],
        ] {
            let o = dda(&args);
            assert_eq!(o.status.code(), Some(2));
            let err = String::from_utf8_lossy(&o.stderr);
            assert!(
                err.contains(&format!("quake.csv:{line}")) && err.contains(says),
                "{err}"
            );
        }
        assert!(!out.exists());
    }
    // A record cut in mid-swing leaves the ground moving: a warning, not an error.
    std::fs::write(dir.join("quake.csv"), lines[..12].join("\n")).unwrap();
    let o = dda(&["check", dir.join("quake.toml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains(&format!("quake.toml:{}", key_line - 1)) && err.contains("baseline"),
        "{err}"
    );
    std::fs::write(dir.join("quake.csv"), lines.join("\n")).unwrap();
    let o = run_file(&dir.join("quake.toml"), &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        o.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert!(
        s["effects"].as_array().unwrap().contains(&"seismic".into()),
        "{}",
        s["effects"]
    );
    // The scene as run holds the record itself, and runs again without the file.
    std::fs::remove_file(dir.join("quake.csv")).unwrap();
    let again = dir.join("again");
    let o = run_file(&out.join("scene.json"), &again, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(out.join("measurements.csv")).unwrap(),
        std::fs::read(again.join("measurements.csv")).unwrap()
    );
}

/// A run stopped by `--max-steps` resumes from its output folder, `--max-steps` at a
/// time, to the uninterrupted run's outputs: history.csv (timing aside), frames.jsonl,
/// measurements.csv and bolts.csv, and the summary. A resume refused before it starts
/// (a damaged checkpoint) leaves the stopped run as it was.
#[test]
fn a_stopped_run_resumes_step_budget_by_budget_to_the_whole_run() {
    let dir = scratch("budget");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/excavation.toml");
    let whole = dir.join("whole");
    assert!(run_file(Path::new(scene), &whole, &[]).status.success());
    let out = dir.join("out");
    let o = run_file(Path::new(scene), &out, &["--max-steps", "20"]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(summary(&out)["steps"], 20);

    // A damaged checkpoint: refused (exit 2), the folder left as it was.
    let ck = out.join("checkpoint.bin");
    let good = std::fs::read(&ck).unwrap();
    std::fs::write(&ck, &good[..good.len() / 2]).unwrap();
    let before = listing(&out);
    let o = dda(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(listing(&out), before);
    assert!(!dir.join(".out.partial").exists());
    std::fs::write(&ck, &good).unwrap();

    let o = dda(&[
        "resume",
        out.to_str().unwrap(),
        "--quiet",
        "--max-steps",
        "15",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert_eq!(summary(&out)["steps"], 35);
    let o = dda(&["resume", out.to_str().unwrap(), "--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!out.join("checkpoint.bin").exists());
    assert_eq!(untimed_summary(&out), untimed_summary(&whole));
    assert_eq!(
        untimed_history(&out.join("history.csv")),
        untimed_history(&whole.join("history.csv"))
    );
    for f in ["frames.jsonl", "measurements.csv", "bolts.csv"] {
        assert_eq!(
            std::fs::read(out.join(f)).unwrap(),
            std::fs::read(whole.join(f)).unwrap(),
            "{f}"
        );
    }
}

/// A resumed run's messages name its checkpoint where the user has it, in the output
/// folder, not in the staging folder the run goes back to while it resumes (which no
/// longer exists when the user reads them): the warnings of the scene the checkpoint
/// holds (`tests/scenes/rock-mass.toml` drops slivers below its `min_area`).
#[test]
fn a_resumed_run_names_its_checkpoint_where_the_user_has_it() {
    let dir = scratch("resume-names");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/rock-mass.toml");
    let out = dir.join("out");
    let o = run_file(Path::new(scene), &out, &["--max-steps", "2"]);
    assert_eq!(o.status.code(), Some(1));
    let o = dda(&["resume", out.to_str().unwrap(), "--max-steps", "1"]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    let named = format!(
        "{}: key `regions[1].min_area`",
        out.join("checkpoint.bin").display()
    );
    assert!(err.contains(&named), "{err}");
    assert!(!err.contains(".out.partial"), "{err}");
}

/// A settling that stops without converging says which static step the run starts from,
/// on the terminal, in `summary.json` and on the report page. A column of 20 blocks whose
/// static steps d_max (1e-7 m) holds below the settling's first stalls while still
/// loading, and has no steadiest step to go back to (docs/method.md section 13;
/// `tests/physics/stacks.rs`): it starts from its last.
#[test]
fn an_unconverged_settling_says_where_the_run_starts() {
    let dir = scratch("unconverged-settling");
    let mut text = String::from(
        "name = \"stack\"\n[analysis]\nduration = 0.001\ntime_step = 0.0001\n\
         max_displacement = 1e-7\ncontact_tolerance = 1e-3\nnormal_penalty = 1e10\n\
         gravity = [0.0, -9.81]\nframes = 0\n[materials.rock]\ndensity = 2600.0\n\
         young = 1.0e10\npoisson = 0.25\n[joints.default]\nfriction_deg = 30.0\n\
         [[blocks]]\nid = \"base\"\nmaterial = \"rock\"\nfixed = true\n\
         vertices = [[-1.0, -1.0], [1.5, -1.0], [1.5, 0.0], [-1.0, 0.0]]\n",
    );
    for r in 0..20 {
        let (y0, y1) = (0.5 * f64::from(r), 0.5 * f64::from(r) + 0.5);
        text.push_str(&format!(
            "[[blocks]]\nid = \"b{r}\"\nmaterial = \"rock\"\n\
             vertices = [[0.0, {y0}], [0.5, {y0}], [0.5, {y1}], [0.0, {y1}]]\n"
        ));
    }
    let (out, o) = run_text(&dir, &text);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("stopped without converging (the run starts from its last static step)"),
        "{stderr}"
    );
    let settling = &summary(&out)["settling"];
    assert_eq!(settling["converged"], false, "{settling}");
    assert!(settling.get("kept_step").is_none(), "{settling}");
    let report = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(report.contains("the run starting from its last static step"));
}
