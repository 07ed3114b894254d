//! Bad scene input: every error names the file, the key path and the line, for TOML and
//! JSON, whether the parser or the validation finds it.

use dda_core::{Format, Scene, SceneError};

const GOOD: &str = include_str!("../../../tests/scenes/sliding-block.toml");

/// `GOOD` with the first line starting with `from` replaced by `to`.
fn edit(from: &str, to: &str) -> String {
    let mut done = false;
    GOOD.lines()
        .map(|l| {
            if !done && l.starts_with(from) {
                done = true;
                to.to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The 1-based line of `GOOD` starting with `from`.
fn line_of(text: &str, from: &str) -> usize {
    text.lines()
        .position(|l| l.starts_with(from))
        .expect("line present")
        + 1
}

fn error(text: &str) -> SceneError {
    match Scene::parse(text, Format::Toml, "scene.toml") {
        Ok(_) => panic!("accepted a bad scene:\n{text}"),
        Err(e) => e,
    }
}

#[test]
fn the_good_scene_parses() {
    let (scene, model) = Scene::parse(GOOD, Format::Toml, "scene.toml").expect("valid");
    assert_eq!(scene.name, "sliding-block");
    assert_eq!(model.blocks.len(), 2);
}

#[test]
fn unknown_key_is_named_with_its_line() {
    let text = edit("time_step", "time_stpe = 0.001");
    let e = error(&text);
    assert_eq!(e.file, "scene.toml");
    assert!(e.message.contains("time_stpe"), "{e}");
    assert_eq!(e.line, Some(line_of(&text, "time_stpe")), "{e}");
    assert!(e.key.starts_with("analysis"), "{e}");
}

#[test]
fn wrong_type_is_named_with_key_and_line() {
    let text = edit("duration", "duration = \"long\"");
    let e = error(&text);
    assert_eq!(e.key, "analysis.duration", "{e}");
    assert_eq!(e.line, Some(line_of(&text, "duration")), "{e}");
}

#[test]
fn invalid_values_are_named_with_key_and_line() {
    let cases = [
        ("duration", "duration = -1.0", "analysis.duration"),
        (
            "normal_penalty",
            "normal_penalty = 0.0",
            "analysis.normal_penalty",
        ),
        ("detector", "detector = \"magic\"", "analysis.detector"),
        ("poisson", "poisson = 0.5", "materials.rock.poisson"),
        (
            "friction_deg",
            "friction_deg = 95.0",
            "joints.default.friction_deg",
        ),
        ("velocity", "velocity = [1.0, nan]", "blocks[1].velocity[1]"),
    ];
    for (from, to, key) in cases {
        let text = edit(from, to);
        let e = error(&text);
        assert_eq!(e.key, key, "{e}");
        assert_eq!(e.line, Some(line_of(&text, from)), "{e}");
        let shown = e.to_string();
        assert!(shown.starts_with("scene.toml:"), "{shown}");
        assert!(shown.contains(key), "{shown}");
    }
}

#[test]
fn bad_block_geometry_names_the_vertex() {
    // A reflex vertex (index 2) makes the slider non-convex.
    let text = edit(
        "vertices = [[0.0, 1.0]",
        "vertices = [[0.0, 1.0], [1.0, 1.0], [0.5, 1.2], [1.0, 2.0], [0.0, 2.0]]",
    );
    let e = error(&text);
    assert!(e.key.starts_with("blocks[1].vertices"), "{e}");
    assert!(e.message.contains("slider"), "{e}");
    // The way to write rock that is not convex.
    assert!(e.message.contains("[[regions]]"), "{e}");
    assert_eq!(
        e.line,
        Some(line_of(&text, "vertices = [[0.0, 1.0]")),
        "{e}"
    );
}

#[test]
fn missing_material_and_duplicate_id() {
    let text = edit("material = \"rock\"", "material = \"granite\"");
    let e = error(&text);
    assert_eq!(e.key, "blocks[0].material", "{e}");
    assert!(e.message.contains("granite"), "{e}");
    let text = edit("id = \"slider\"", "id = \"base\"");
    let e = error(&text);
    assert_eq!(e.key, "blocks[1].id", "{e}");
}

/// Line (1-based) of the `n`th line (from 0) of `text` starting with `from`.
fn nth_line_of(text: &str, from: &str, n: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.starts_with(from))
        .nth(n)
        .expect("line present")
        .0
        + 1
}

/// Every kind of bad input the issue lists is refused with its key and its line (TOML).
#[test]
fn every_bad_input_names_key_and_line() {
    const SLIDER: &str = "vertices = [[0.0, 1.0]";
    let cases: [(&str, &str, &str, &str); 18] = [
        // (what, line to replace, replacement, expected key)
        (
            "clockwise",
            SLIDER,
            "vertices = [[0.0, 1.0], [0.0, 2.0], [1.0, 2.0], [1.0, 1.0]]",
            "blocks[1].vertices",
        ),
        (
            "duplicate vertex",
            SLIDER,
            "vertices = [[0.0, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]",
            "blocks[1].vertices[2]",
        ),
        (
            "collinear vertex",
            SLIDER,
            "vertices = [[0.0, 1.0], [0.5, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]",
            "blocks[1].vertices[1]",
        ),
        (
            "fewer than 3 vertices",
            SLIDER,
            "vertices = [[0.0, 1.0], [1.0, 1.0]]",
            "blocks[1].vertices",
        ),
        (
            "NaN vertex",
            SLIDER,
            "vertices = [[0.0, 1.0], [1.0, nan], [1.0, 2.0], [0.0, 2.0]]",
            "blocks[1].vertices[1]",
        ),
        (
            "zero area",
            SLIDER,
            "vertices = [[0.0, 1.0], [1.0, 1.0], [2.0, 1.0]]",
            "blocks[1].vertices",
        ),
        ("E <= 0", "young", "young = 0.0", "materials.rock.young"),
        (
            "nu <= -1",
            "poisson",
            "poisson = -1.0",
            "materials.rock.poisson",
        ),
        (
            "nu >= 0.5",
            "poisson",
            "poisson = 0.5",
            "materials.rock.poisson",
        ),
        (
            "density <= 0",
            "density",
            "density = -2600.0",
            "materials.rock.density",
        ),
        (
            "damping < 0",
            "poisson",
            "poisson = 0.3\ndamping = -1e-3",
            "materials.rock.damping",
        ),
        (
            "damping > 1 s",
            "poisson",
            "poisson = 0.3\ndamping = 5.0",
            "materials.rock.damping",
        ),
        (
            "time step <= 0",
            "time_step",
            "time_step = 0.0",
            "analysis.time_step",
        ),
        (
            "contact damping < 0",
            "frames",
            "frames = 2\ncontact_damping = -0.1",
            "analysis.contact_damping",
        ),
        (
            "contact damping > 10",
            "frames",
            "frames = 2\ncontact_damping = 11.0",
            "analysis.contact_damping",
        ),
        (
            "blocks overlapping at the start",
            SLIDER,
            "vertices = [[0.0, 0.5], [1.0, 0.5], [1.0, 1.5], [0.0, 1.5]]",
            "blocks[1].vertices",
        ),
        (
            "unknown material",
            "material = \"rock\"",
            "material = \"granite\"",
            "blocks[0].material",
        ),
        ("unknown key", "frames", "frame = 2", "analysis"),
    ];
    for (what, from, to, key) in cases {
        let text = edit(from, to);
        let e = error(&text);
        assert!(e.key.starts_with(key), "{what}: {e}");
        let line = if to.starts_with("frame =") {
            line_of(&text, "frame =")
        } else if let Some((_, added)) = to.rsplit_once('\n') {
            line_of(&text, added)
        } else {
            line_of(&text, to)
        };
        assert_eq!(e.line, Some(line), "{what}: {e}");
    }
    // A negative Poisson's ratio above -1 is valid.
    assert!(Scene::parse(&edit("poisson", "poisson = -0.2"), Format::Toml, "s.toml").is_ok());
}

/// A static scene with a block resting on nothing is refused (its equilibrium is
/// singular), naming the block's table.
#[test]
fn static_scene_with_a_free_block_is_refused() {
    let text = edit("mode", "mode = \"static\"").replace(
        SLIDER_LINE,
        "vertices = [[0.0, 3.0], [1.0, 3.0], [1.0, 4.0], [0.0, 4.0]]",
    );
    let e = error(&text);
    assert_eq!(e.key, "blocks[1]", "{e}");
    assert_eq!(e.line, Some(nth_line_of(&text, "[[blocks]]", 1)), "{e}");
    assert!(e.message.contains("slider"), "{e}");
    // Resting on the base, it is accepted.
    let resting = edit("mode", "mode = \"static\"");
    assert!(Scene::parse(&resting, Format::Toml, "s.toml").is_ok());
}

/// A contact tolerance below twice the max displacement is a warning, not an error.
#[test]
fn small_contact_tolerance_warns() {
    let (_, model) = Scene::parse(
        &edit("contact_tolerance", "contact_tolerance = 0.0015"),
        Format::Toml,
        "s.toml",
    )
    .expect("accepted");
    assert_eq!(model.warnings.len(), 1);
    assert_eq!(model.warnings[0].key, "analysis.contact_tolerance");
    let (_, model) = Scene::parse(GOOD, Format::Toml, "s.toml").expect("valid");
    assert!(model.warnings.is_empty());
}

/// A rigid analysis given an initial stress is warned that it ignores it (its blocks have
/// no strain), naming the first key that gives one; a deformable one is not.
#[test]
fn initial_stress_in_a_rigid_analysis_is_warned_of() {
    let stressed = GOOD.replace(
        "fixed = true",
        "fixed = true\n[[blocks]]\nid = \"slab\"\nmaterial = \"rock\"\n\
         vertices = [[2.0, 1.0], [3.0, 1.0], [3.0, 2.0], [2.0, 2.0]]\n\
         stress = [-1e5, -2e5, 0.0]",
    );
    let (_, model) = Scene::parse(&stressed, Format::Toml, "s.toml").expect("valid");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
    let rigid = stressed.replace("deformable = true", "deformable = false");
    let (_, model) = Scene::parse(&rigid, Format::Toml, "s.toml").expect("valid");
    assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
    let w = &model.warnings[0];
    assert_eq!(w.key, "blocks[1].stress", "{w:?}");
    assert!(w.message.contains("rigid"), "{w:?}");
}

/// A free block written smaller than d_tol^2 (here 1 mm square against d_tol = 2 mm) is
/// warned of, naming it: contact detection does not resolve it; under Shi's rule
/// (`integration = "constant-acceleration"`) such a sliver can spin up numerically too,
/// and the warning names the default, damped rule, which damps that spin. The scene
/// still runs; one larger than d_tol^2 is not warned of.
#[test]
fn a_block_smaller_than_the_contact_tolerance_is_warned_of() {
    let chip = |size: f64| {
        GOOD.replace(
            "fixed = true",
            &format!(
                "fixed = true\n[[blocks]]\nid = \"chip\"\nmaterial = \"rock\"\n\
                 vertices = [[3.0, 1.0], [{x}, 1.0], [{x}, {y}], [3.0, {y}]]",
                x = 3.0 + size,
                y = 1.0 + size
            ),
        )
    };
    let (_, model) = Scene::parse(&chip(0.001), Format::Toml, "s.toml").expect("valid");
    assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
    let w = &model.warnings[0];
    assert_eq!(w.key, "blocks[1].vertices", "{w:?}");
    assert!(
        w.message.contains("`chip`")
            && w.message.contains("d_tol^2")
            && !w.message.contains("spin"),
        "{w:?}"
    );
    // Under Shi's rule the sliver can spin up too, and the damped rule is named.
    let shi = chip(0.001).replacen(
        "[analysis]",
        "[analysis]\nintegration = \"constant-acceleration\"",
        1,
    );
    let (_, model) = Scene::parse(&shi, Format::Toml, "s.toml").expect("valid");
    assert_eq!(model.warnings.len(), 1, "{:?}", model.warnings);
    let w = &model.warnings[0].message;
    assert!(
        w.contains("`chip`") && w.contains("spin") && w.contains("damped-constant-acceleration"),
        "{w}"
    );
    let (_, model) = Scene::parse(&chip(0.0025), Format::Toml, "s.toml").expect("valid");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
}

/// A load or a fixed point off its block is warned of, naming its key: one on the
/// block's face, or 1.5e-6 m off it (a point written to 6 decimals on a face that is
/// neither level nor upright misses it by up to 7e-7 m), is not.
#[test]
fn a_load_or_fixed_point_off_its_block_is_warned_of() {
    let text = GOOD.replace(
        "velocity = [1.0, 0.0]",
        "velocity = [1.0, 0.0]\n\
         loads = [{ at = [0.5, 2.0], force = [0.0, -1.0] }, { at = [0.5, 2.5], force = [0.0, -1.0] }]\n\
         fixed_points = [[1.0000015, 1.5], [3.0, 1.5]]",
    );
    assert_ne!(text, GOOD);
    let (_, model) = Scene::parse(&text, Format::Toml, "s.toml").expect("valid");
    let keys: Vec<&str> = model.warnings.iter().map(|w| w.key.as_str()).collect();
    assert_eq!(
        keys,
        ["blocks[1].loads[1].at", "blocks[1].fixed_points[1]"],
        "{:?}",
        model.warnings
    );
    assert!(
        model.warnings[0].message.contains("`slider`"),
        "{:?}",
        model.warnings
    );
}

const SLIDER_LINE: &str = "vertices = [[0.0, 1.0], [1.0, 1.0], [1.0, 2.0], [0.0, 2.0]]";

#[test]
fn syntax_error_has_a_line() {
    let text = edit("gravity", "gravity = [0.0, -9.81");
    let e = error(&text);
    assert!(e.line.is_some(), "{e}");
}

#[test]
fn json_errors_name_key_and_line() {
    let json = r#"{
  "name": "j",
  "analysis": {
    "duration": 1.0,
    "time_step": 0.01,
    "max_displacement": 0.01,
    "normal_penalty": -5
  },
  "materials": {"rock": {"density": 2600, "young": 1e9, "poisson": 0.3}},
  "blocks": [{"id": "a", "material": "rock", "vertices": [[0,0],[1,0],[1,1]]}]
}"#;
    let e = Scene::parse(json, Format::Json, "s.json").expect_err("invalid");
    assert_eq!(e.key, "analysis.normal_penalty", "{e}");
    assert_eq!(e.line, Some(7), "{e}");
    let e = Scene::parse(
        &json.replace("\"time_step\"", "\"timestep\""),
        Format::Json,
        "s.json",
    )
    .expect_err("unknown key");
    assert!(e.message.contains("timestep"), "{e}");
    assert_eq!(e.line, Some(5), "{e}");
    // Written by an editor on Windows: a byte order mark and CRLF line ends. Its error
    // names the same key and line; valid, it reads as the plain text does (the mark
    // was taken for a value: "s.json:1: expected value").
    let windows = format!("\u{feff}{}", json.replace('\n', "\r\n"));
    let e = Scene::parse(&windows, Format::Json, "s.json").expect_err("invalid");
    assert_eq!(
        (e.key.as_str(), e.line),
        ("analysis.normal_penalty", Some(7)),
        "{e}"
    );
    let valid = |text: &str| {
        let (scene, _) = Scene::parse(&text.replace("-5", "1e9"), Format::Json, "s.json")
            .unwrap_or_else(|e| panic!("{e}"));
        scene
    };
    assert_eq!(valid(&windows), valid(json));
}

/// Two 1 m blocks sharing a face whose coordinates, written by hand to 6 decimals, differ
/// in the last digit (1.000000 in one, 0.999999 in the other): they overlap by 1e-6 m,
/// which is accepted; 1e-4 m into each other they are refused, with what to do.
#[test]
fn blocks_written_to_six_decimals_may_share_a_face() {
    let scene = |x: &str| {
        format!(
            "name = \"pair\"\n[analysis]\nduration = 0.1\ntime_step = 0.01\n\
             max_displacement = 0.01\nnormal_penalty = 1e9\n\
             [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n\
             [[blocks]]\nid = \"a\"\nmaterial = \"rock\"\n\
             vertices = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]\n\
             [[blocks]]\nid = \"b\"\nmaterial = \"rock\"\n\
             vertices = [[{x}, 0.0], [2.0, 0.0], [2.0, 1.0], [{x}, 1.0]]\n"
        )
    };
    Scene::parse(&scene("0.999999"), Format::Toml, "pair.toml").expect("a shared face");
    let e = error_of(&scene("0.9999"));
    assert_eq!(e.key, "blocks[1].vertices", "{e}");
    assert!(
        e.message.contains("overlaps block `a`") && e.message.contains("move it clear"),
        "{e}"
    );
}

fn error_of(text: &str) -> SceneError {
    match Scene::parse(text, Format::Toml, "pair.toml") {
        Ok(_) => panic!("accepted overlapping blocks:\n{text}"),
        Err(e) => e,
    }
}

/// Values that are admissible but look like a slip of units are warned of, with the key:
/// Young's modulus in MPa (5000 for 5e9 Pa), density in t/m^3 (2.6), friction as tan(phi)
/// (0.6); the scene still runs.
#[test]
fn unit_slips_are_warned_of_with_their_keys() {
    let text = GOOD
        .lines()
        .map(|l| {
            if l.starts_with("young") {
                "young = 5000.0".to_string()
            } else if l.starts_with("density") {
                "density = 2.6".to_string()
            } else if l.starts_with("friction_deg") {
                "friction_deg = 0.6".to_string()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let (_, model) = Scene::parse(&text, Format::Toml, "scene.toml").expect("admissible");
    let keys: Vec<&str> = model.warnings.iter().map(|w| w.key.as_str()).collect();
    for key in ["young", "density", "friction_deg"] {
        assert!(keys.iter().any(|k| k.ends_with(key)), "{key}: {keys:?}");
    }
    let (_, good) = Scene::parse(GOOD, Format::Toml, "scene.toml").unwrap();
    assert!(good.warnings.is_empty(), "{:?}", good.warnings);
}
