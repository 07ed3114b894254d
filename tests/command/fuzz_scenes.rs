//! Hostile scene files: mutants of the built-in and test scenes (deleted and renamed
//! keys, wrong types, extreme and non-finite numbers, deep nesting, truncation, random
//! bytes), drawn from a fixed seed, each through `dda check` under a time limit. Every
//! answer must be exit 0 or 2 (never a panic, an abort or a hang), and every exit-2
//! message must name the file. A sample of the mutants that pass check then runs with
//! `--max-steps`: exit 0, 1 or 2 only.
//!
//! `DDA_FUZZ_SEED=N` draws other mutants; `DDA_FUZZ_CASES=N` sets how many (default
//! 1,200).

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use super::cli::dda_within;
use serde_json::Value;
use std::path::Path;
use std::time::Duration;

/// The seed of the mutants unless `DDA_FUZZ_SEED` is set.
const SEED: u64 = 20261124;

/// A small deterministic generator (xorshift64*).
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// Every node of `v` as a JSON pointer, in document order.
fn pointers(v: &Value, at: String, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                let p = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
                out.push(p.clone());
                pointers(x, p, out);
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                let p = format!("{at}/{i}");
                out.push(p.clone());
                pointers(x, p, out);
            }
        }
        _ => {}
    }
}

/// The parent pointer and last token of `p`.
fn split(p: &str) -> (&str, &str) {
    let i = p.rfind('/').unwrap_or(0);
    (&p[..i], &p[(i + 1).min(p.len())..])
}

/// A structural mutant of `base`.
fn mutate_value(base: &Value, rng: &mut Rng) -> Value {
    let mut v = base.clone();
    let mut all = Vec::new();
    pointers(&v, String::new(), &mut all);
    if all.is_empty() {
        return v;
    }
    let p = all[rng.below(all.len())].clone();
    let (parent, last) = split(&p);
    match rng.below(5) {
        0 => {
            // Delete the node.
            match v.pointer_mut(parent) {
                Some(Value::Object(m)) => {
                    m.remove(last);
                }
                Some(Value::Array(a)) => {
                    if let Ok(i) = last.parse::<usize>()
                        && i < a.len()
                    {
                        a.remove(i);
                    }
                }
                _ => {}
            }
        }
        1 => {
            // Rename the key (or a misspelling of it).
            if let Some(Value::Object(m)) = v.pointer_mut(parent)
                && let Some(x) = m.remove(last)
            {
                let names = [
                    format!("{last}s"),
                    last.to_uppercase(),
                    "colour".into(),
                    String::new(),
                ];
                m.insert(names[rng.below(names.len())].clone(), x);
            }
        }
        2 => {
            let wrong = [
                Value::String("x".into()),
                Value::Bool(true),
                Value::Array(vec![]),
                serde_json::json!({}),
                serde_json::json!(1),
                serde_json::json!([1.0, 2.0, 3.0]),
                serde_json::json!([[0.0, 0.0]]),
            ];
            if let Some(x) = v.pointer_mut(&p) {
                *x = wrong[rng.below(wrong.len())].clone();
            }
        }
        3 => {
            let extreme = [
                1e308,
                -1e308,
                0.0,
                -0.0,
                1e-320,
                1e30,
                -1.0,
                1e15,
                5e-324,
                123456789.0,
            ];
            if let Some(x) = v.pointer_mut(&p) {
                *x = serde_json::json!(extreme[rng.below(extreme.len())]);
            }
        }
        _ => {
            // Deep nesting around the node.
            if let Some(x) = v.pointer_mut(&p) {
                let depth = 50 + rng.below(3000);
                let mut inner = x.clone();
                for _ in 0..depth {
                    inner = if rng.below(2) == 0 {
                        Value::Array(vec![inner])
                    } else {
                        serde_json::json!({ "a": inner })
                    };
                }
                *x = inner;
            }
        }
    }
    v
}

/// A text mutant: truncation, random bytes, a non-finite number, or stray brackets.
fn mutate_text(text: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut t = text.to_vec();
    if t.is_empty() {
        return t;
    }
    match rng.below(4) {
        0 => t.truncate(rng.below(t.len())),
        1 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(t.len());
                t[i] = rng.next() as u8;
            }
        }
        2 => {
            let digits: Vec<usize> = (0..t.len()).filter(|&i| t[i].is_ascii_digit()).collect();
            if !digits.is_empty() {
                let i = digits[rng.below(digits.len())];
                let word = ["nan", "inf", "-inf", "1e999", "NaN", "Infinity", "-0"][rng.below(7)];
                t.splice(i..i + 1, word.bytes());
            }
        }
        _ => {
            let i = rng.below(t.len());
            let junk = [
                "[}",
                "{",
                "]]]",
                "[[[[[[",
                "\"",
                "{\"a\":[}",
                "= =",
                "\n[x]\n",
            ][rng.below(8)];
            t.splice(i..i, junk.bytes());
        }
    }
    t
}

/// The scenes the mutants start from: the small built-ins, the test scene, and scenes
/// with regions and excavations, unexpanded.
fn bases() -> Vec<Value> {
    let mut scenes: Vec<dda::core::Scene> = dda::bench::BUILTINS
        .iter()
        .filter(|b| !b.name.contains("229") && !b.name.contains("826"))
        .map(|b| (b.build)())
        .collect();
    let test_scene = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/scenes/sliding-block.toml"
    );
    scenes.push(dda::core::Scene::load(Path::new(test_scene)).unwrap().0);
    // Rock masses: regions, statistical and non-persistent joint sets, non-convex
    // outlines, excavations.
    for file in [
        "/tests/scenes/excavation.toml",
        "/examples/toppling.toml",
        "/examples/tunnel.toml",
    ] {
        let path = format!("{}{file}", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        scenes.push(toml::from_str(&text).unwrap());
    }
    scenes
        .iter()
        .map(|s| serde_json::to_value(s).unwrap())
        .collect()
}

#[test]
fn hostile_scenes_get_exit_0_or_2_naming_the_file() {
    let seed = std::env::var("DDA_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(SEED);
    let cases: usize = std::env::var("DDA_FUZZ_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1200);
    let dir = super::cli::scratch("fuzz");
    let bases = bases();
    let mut rng = Rng(seed | 1);
    // The mutants, made in order from the seed.
    let mut files = Vec::with_capacity(cases);
    for k in 0..cases {
        let base = &bases[rng.below(bases.len())];
        let toml = rng.below(2) == 0;
        let structural = rng.below(3) != 0;
        let value = if structural {
            mutate_value(base, &mut rng)
        } else {
            base.clone()
        };
        let text = if toml {
            toml::to_string(&value).ok().map(String::into_bytes)
        } else {
            None
        }
        .unwrap_or_else(|| serde_json::to_vec_pretty(&value).unwrap());
        let ext = if toml && text.first() != Some(&b'{') {
            "toml"
        } else {
            "json"
        };
        let text = if structural && rng.below(4) != 0 {
            text
        } else {
            mutate_text(&text, &mut rng)
        };
        let file = dir.join(format!("m{k:05}.{ext}"));
        std::fs::write(&file, &text).unwrap();
        files.push(file);
    }
    // Checked on two threads; each answer depends on its file alone.
    let passed = std::sync::Mutex::new(Vec::new());
    let failures = std::sync::Mutex::new(Vec::new());
    let (passed_ref, failures_ref) = (&passed, &failures);
    std::thread::scope(|s| {
        for part in files.chunks(files.len().div_ceil(2)) {
            s.spawn(move || {
                let (passed, failures) = (passed_ref, failures_ref);
                for file in part {
                    let name = file.file_name().unwrap().to_string_lossy().into_owned();
                    let Some(o) =
                        dda_within(&["check", file.to_str().unwrap()], Duration::from_secs(10))
                    else {
                        failures.lock().unwrap().push(format!("{name}: check hung"));
                        continue;
                    };
                    let err = String::from_utf8_lossy(&o.stderr);
                    match o.status.code() {
                        Some(0) => passed.lock().unwrap().push(file.clone()),
                        Some(2) if err.contains(&name) && !err.contains("panicked") => {}
                        code => failures
                            .lock()
                            .unwrap()
                            .push(format!("{name}: check exit {code:?}: {err}")),
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {cases}:\n{}",
        failures.len(),
        failures.join("\n")
    );
    // A sample of those that pass check, run for a few steps.
    let mut passed = passed.into_inner().unwrap();
    passed.sort();
    let sample: Vec<_> = passed
        .iter()
        .step_by(passed.len().div_ceil(24).max(1))
        .collect();
    for file in &sample {
        let name = file.file_name().unwrap().to_string_lossy().into_owned();
        let out = dir.join(format!("run-{name}"));
        let o = dda_within(
            &[
                "run",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
                "--quiet",
                "--max-steps",
                "20",
            ],
            Duration::from_secs(120),
        )
        .unwrap_or_else(|| panic!("{name}: run hung"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            matches!(o.status.code(), Some(0..=2)) && !err.contains("panicked"),
            "{name}: run exit {:?}: {err}",
            o.status.code()
        );
    }
    eprintln!(
        "{cases} mutants from seed {seed}: {} passed check, {} run",
        passed.len(),
        sample.len()
    );
}
