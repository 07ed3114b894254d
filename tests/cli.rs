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
    assert!(s["time_simulated"].as_f64().unwrap() < 0.2);
    assert!(out.join("history.csv").exists());
}
