//! The `dda` command's contract (DESIGN 5.2): outputs, exit codes, overrides, and that bad
//! input writes nothing.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

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
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("dda-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn run_writes_summary_history_and_frames() {
    let out = scratch("run").join("out");
    let o = run_scene(&out, &["--quiet"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = summary(&out);
    assert_eq!(s["scene"], "sliding-block");
    assert_eq!(s["detector"], "cover");
    assert_eq!(s["status"], "completed");
    assert_eq!(s["time_simulated"], 0.2);
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

#[test]
fn same_scene_twice_gives_identical_summaries_apart_from_timing() {
    let dir = scratch("twice");
    let mut runs = Vec::new();
    for k in 0..2 {
        let out = dir.join(format!("r{k}"));
        assert!(run_scene(&out, &["--quiet"]).status.success());
        let mut s = summary(&out);
        s["seconds"] = serde_json::Value::Null;
        runs.push(s);
    }
    assert_eq!(runs[0], runs[1]);
}

#[test]
fn rtol_scales_tolerance_and_step_displacement_together() {
    let out = scratch("rtol").join("out");
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
    let out = scratch("det").join("out");
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

/// A simulation that cannot go on (one OCI iteration allowed while contacts must change
/// state) exits 1 and keeps its outputs up to the last good state, with the reason.
#[test]
fn failed_simulation_exits_1_and_keeps_last_good_state() {
    let dir = scratch("fail");
    let text = std::fs::read_to_string(SCENE)
        .unwrap()
        .replace("frames = 2", "frames = 2\nmax_oci = 1");
    let scene = dir.join("fail.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let o = dda(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["status"], "failed");
    assert!(
        s["error"].as_str().unwrap().contains("time step"),
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
    assert_eq!(ck.state.t, t);
    let frames = std::fs::read_to_string(out.join("frames.jsonl")).unwrap();
    let last: serde_json::Value = serde_json::from_str(frames.lines().last().unwrap()).unwrap();
    assert_eq!(last["t"].as_f64().unwrap(), t);
    // A failed run is not resumable: it would fail again the same way.
    let o = dda(&["resume", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn render_redraws_frames_and_report_without_simulating() {
    let out = scratch("render").join("out");
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
        if alive {
            killed = Some((out, work, delay));
            break;
        }
    }
    let (out, work, delay) = killed.expect("the run always finished before it could be killed");
    let ck_path = work.join("checkpoint.bin");
    let ck = dda_core::Checkpoint::load(&ck_path)
        .unwrap_or_else(|e| panic!("killed {delay} ms after the first checkpoint: {e}"));
    assert!(ck.state.totals.steps % 3 == 0 && ck.state.totals.steps > 0);
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
        for f in ["history.csv", "frames.jsonl", "scene.json"] {
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

/// A penalty too soft for the contact tolerance (paper section 2.6) gets a warning after
/// the run, exactly when the summary's largest penetration exceeds the tolerance.
#[test]
fn a_penalty_too_soft_for_the_tolerance_is_warned_of() {
    let dir = scratch("soft-penalty");
    for (penalty, name) in [("1e9", "stiff"), ("2e6", "soft")] {
        let text = std::fs::read_to_string(SCENE).unwrap().replace(
            "normal_penalty = 1e9",
            &format!("normal_penalty = {penalty}"),
        );
        let file = dir.join(format!("{name}.toml"));
        std::fs::write(&file, &text).unwrap();
        let out = dir.join(name);
        let o = dda(&[
            "run",
            file.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{o:?}");
        let s = summary(&out);
        let deeper =
            s["max_penetration"].as_f64().unwrap() > s["contact_tolerance"].as_f64().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.contains("too soft"), deeper, "{name}: {err}");
        // The soft one does go deeper than d_tol; the stiff one does not.
        assert_eq!(deeper, name == "soft", "{name}: {s}");
    }
}
