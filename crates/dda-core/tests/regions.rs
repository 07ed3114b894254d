//! Rock masses from a scene file: `[[regions]]` cut by `[joint_sets]` into blocks that
//! tile the region, named after it, and every bad region or set refused with its key and
//! line.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda_core::scene::{JointSetSpec, RegionSpec};
use dda_core::{Format, Scene, SceneError};
use dda_geom::{ConvexPolygon, separation};
use proptest::prelude::*;

const SLOPE: &str = include_str!("../../../tests/scenes/jointed-slope.toml");

fn error(text: &str) -> SceneError {
    match Scene::parse(text, Format::Toml, "slope.toml") {
        Ok(_) => panic!("accepted a bad scene:\n{text}"),
        Err(e) => e,
    }
}

/// The 1-based line of `text` starting with `from`, the `nth` such line (from 0).
fn line_of(text: &str, from: &str, nth: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.starts_with(from))
        .nth(nth)
        .unwrap()
        .0
        + 1
}

#[test]
fn a_region_is_cut_into_blocks_named_after_it() {
    let (scene, model) = Scene::parse(SLOPE, Format::Toml, "slope.toml").unwrap();
    let explicit = scene.expanded().unwrap();
    assert!(explicit.regions.is_empty() && explicit.joint_sets.is_empty());
    assert_eq!(explicit.blocks.len(), model.blocks.len());
    // The base (no joint sets) is one block; the slope's are slope.1, slope.2, ...
    assert_eq!(explicit.blocks[0].id, "base.1");
    assert!(explicit.blocks[0].fixed);
    let slope: Vec<_> = explicit
        .blocks
        .iter()
        .filter(|b| b.id.starts_with("slope."))
        .collect();
    assert!(slope.len() > 20, "{} blocks", slope.len());
    for (k, b) in slope.iter().enumerate() {
        assert_eq!(b.id, format!("slope.{}", k + 1));
        assert!(!b.fixed);
    }
    // The slope's blocks fill its outline: 40 x 12 m less a triangle 25 x 12 / 2.
    let area: f64 = slope
        .iter()
        .map(|b| ConvexPolygon::from_coords(&b.vertices).unwrap().area())
        .sum();
    let outline = 40.0 * 12.0 - 25.0 * 12.0 / 2.0;
    assert!(
        (area - outline).abs() < 1e-12 * outline,
        "{area} vs {outline}"
    );
}

/// A set placed through a point one of its joints passes (`through`, a joint mapped at
/// a known place) cuts the blocks that the offset of that line cuts: here the slope's
/// bedding (dip 35 degrees, offset 0.3 m) through the point 0.3 m along its normal, and
/// through that point moved 7 m along the joint. The same blocks, to rounding.
/// Four persistent sets 1 m apart at 0, 45, 90 and 135 degrees over a 35 m square cross
/// it 35, 49.5, 35 and 49.5 times: the product of those counts, the estimate that
/// refused such a mass before 2026-11-28, is 3e6, past the limit of a million blocks,
/// where lines cut a convex region into at most 1 + L + I pieces (L lines crossing it,
/// I crossing points inside it, at most n m for two sets of n and m lines): some 6,000.
/// The mass is cut, into no more pieces than that bound.
#[test]
fn four_joint_sets_over_a_mass_are_not_taken_for_a_spacing_in_the_wrong_unit() {
    let sets: String = [0, 45, 90, 135]
        .iter()
        .map(|d| format!("[joint_sets.s{d}]\ndip_deg = {d}.0\nspacing = 1.0\n"))
        .collect();
    let text = format!(
        "name = \"four sets\"\n[analysis]\nduration = 0.1\ntime_step = 0.001\n\
         max_displacement = 0.001\nnormal_penalty = 1e10\ngravity = [0.0, -9.81]\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e10\npoisson = 0.25\n{sets}\
         [[regions]]\nid = \"mass\"\nmaterial = \"rock\"\n\
         vertices = [[0.0, 0.0], [35.0, 0.0], [35.0, 35.0], [0.0, 35.0]]\n\
         joint_sets = [\"s0\", \"s45\", \"s90\", \"s135\"]\nfixed = true\n\
         [[blocks]]\nid = \"top\"\nmaterial = \"rock\"\n\
         vertices = [[0.0, 35.0], [1.0, 35.0], [1.0, 36.0], [0.0, 36.0]]\n"
    );
    // Each set's lines across the square: its extent along the set's normal over 1 m.
    let counts: Vec<f64> = [0.0f64, 45.0, 90.0, 135.0]
        .iter()
        .map(|d| {
            let (s, c) = d.to_radians().sin_cos();
            35.0 * (s.abs() + c.abs())
        })
        .collect();
    assert!(counts.iter().map(|n| n + 1.0).product::<f64>() > 1e6);
    let lines: f64 = counts.iter().map(|n| n + 1.0).sum();
    let crossings: f64 = (0..4)
        .flat_map(|i| (0..i).map(move |j| (i, j)))
        .map(|(i, j)| (counts[i] + 1.0) * (counts[j] + 1.0))
        .sum();
    let (_, model) = Scene::parse(&text, Format::Toml, "four.toml").unwrap();
    let pieces = model.blocks.len() - 1;
    assert!(
        pieces > 1000 && (pieces as f64) <= 1.0 + lines + crossings,
        "{pieces} pieces, bound {}",
        1.0 + lines + crossings
    );
}

#[test]
fn a_set_placed_through_a_point_cuts_as_its_offset_does() {
    let blocks = |text: &str| {
        let (scene, _) = Scene::parse(text, Format::Toml, "slope.toml").unwrap();
        scene.expanded().unwrap().blocks
    };
    let by_offset = blocks(SLOPE);
    let (s, c) = 35f64.to_radians().sin_cos();
    let (normal, along) = ([-s, c], [c, s]);
    for shift in [0.0, 7.0] {
        let p = [
            0.3 * normal[0] + shift * along[0],
            0.3 * normal[1] + shift * along[1],
        ];
        let text = SLOPE.replacen(
            "offset = 0.3",
            &format!("through = [{:?}, {:?}]", p[0], p[1]),
            1,
        );
        assert_ne!(text, SLOPE);
        let by_point = blocks(&text);
        assert_eq!(by_point.len(), by_offset.len(), "shift {shift}");
        for (a, b) in by_point.iter().zip(&by_offset) {
            assert_eq!((&a.id, a.vertices.len()), (&b.id, b.vertices.len()));
            for (u, v) in a.vertices.iter().zip(&b.vertices) {
                assert!(
                    (u[0] - v[0]).abs() < 1e-9 && (u[1] - v[1]).abs() < 1e-9,
                    "{}: {u:?} against {v:?}",
                    a.id
                );
            }
        }
    }
}

/// A rock mass whose sets are placed through points moves with them: the tunnel
/// example's outline cut by a set of traces with rock bridges, statistical spacing and
/// dip, and a persistent one, each placed `through` a point, then the same scene moved
/// by (1234.5, -678.25) m, its points with it. The same blocks, moved, to 1e-9 m (the
/// traces' random starts are measured from the point a set is placed through; from the
/// origin, they stayed where they were and the moved mass was cut otherwise).
#[test]
fn a_mass_placed_through_points_moves_with_them() {
    let scene = |dx: f64, dy: f64| {
        let p = |x: f64, y: f64| format!("[{:?}, {:?}]", x + dx, y + dy);
        format!(
            "name = \"moved\"\n[analysis]\nduration = 0.1\ntime_step = 0.002\n\
             max_displacement = 0.005\nnormal_penalty = 1e10\n[materials.rock]\n\
             density = 2600.0\nyoung = 1e10\npoisson = 0.25\n\
             [joint_sets.steep]\ndip_deg = 65.0\nspacing = 2.5\nthrough = {}\n\
             [joint_sets.flat]\ndip_deg = -25.0\nspacing = 2.0\nthrough = {}\n\
             spacing_cv = 0.2\ndip_spread_deg = 4.0\ntrace_length = 8.0\nbridge = 2.0\n\
             seed = 1\n[[regions]]\nid = \"mass\"\nmaterial = \"rock\"\n\
             vertices = [{}, {}, {}, {}]\njoint_sets = [\"steep\", \"flat\"]\n\
             [[regions]]\nid = \"ground\"\nmaterial = \"rock\"\nfixed = true\n\
             vertices = [{}, {}, {}, {}]\n",
            p(3.0, 1.0),
            p(10.0, 7.5),
            p(0.0, 0.0),
            p(30.0, 0.0),
            p(30.0, 20.0),
            p(0.0, 20.0),
            p(0.0, -3.0),
            p(30.0, -3.0),
            p(30.0, 0.0),
            p(0.0, 0.0),
        )
    };
    let blocks = |text: &str| {
        let (scene, _) = Scene::parse(text, Format::Toml, "moved.toml").unwrap();
        scene.expanded().unwrap().blocks
    };
    let (here, there) = (blocks(&scene(0.0, 0.0)), blocks(&scene(1234.5, -678.25)));
    assert!(here.len() > 50, "{} blocks", here.len());
    assert!(
        here.iter().any(|b| b.body.is_some()),
        "no trace ends inside the rock"
    );
    assert_eq!(here.len(), there.len());
    for (a, b) in here.iter().zip(&there) {
        assert_eq!((&a.id, a.vertices.len()), (&b.id, b.vertices.len()));
        for (u, v) in a.vertices.iter().zip(&b.vertices) {
            assert!(
                (u[0] + 1234.5 - v[0]).abs() < 1e-9 && (u[1] - 678.25 - v[1]).abs() < 1e-9,
                "{}: {u:?} moved to {v:?}",
                a.id
            );
        }
    }
}

#[test]
fn bad_regions_and_sets_are_named_with_key_and_line() {
    let cases: [(&str, &str, &str, &str, usize); 15] = [
        // (line to replace, replacement, expected key, words in the message, nth line)
        (
            "joint_sets = [\"bedding\", \"cross\"]",
            "joint_sets = [\"bedding\", \"crosss\"]",
            "regions[1].joint_sets[1]",
            "no joint set named `crosss`",
            0,
        ),
        (
            "spacing = 2.0",
            "spacing = 0.0",
            "joint_sets.bedding.spacing",
            "positive",
            0,
        ),
        (
            // Edge 1, (40, 0) to (0, 12), crosses edge 3, (40, 12) to (0, 0).
            "vertices = [[0.0, 0.0], [40.0, 0.0]",
            "vertices = [[0.0, 0.0], [40.0, 0.0], [0.0, 12.0], [40.0, 12.0]]",
            "regions[1].vertices[1]",
            "edge 1 crosses edge 3",
            0,
        ),
        (
            "vertices = [[0.0, 0.0], [40.0, 0.0]",
            "vertices = [[0.0, 0.0], [25.0, 12.0], [40.0, 12.0], [40.0, 0.0]]",
            "regions[1].vertices",
            "counter-clockwise",
            0,
        ),
        (
            "spacing = 2.0",
            "spacing = 2.0\njoint = \"beding\"",
            "joint_sets.bedding.joint",
            "no joint named `beding`",
            0,
        ),
        (
            "spacing = 2.0",
            "spacing = 2.0\ntrace_length = 5.0",
            "joint_sets.bedding.bridge",
            "needs bridge",
            0,
        ),
        (
            // Traces of a nanometre: billions of them, refused before any is made.
            "spacing = 2.0",
            "spacing = 2.0\ntrace_length = 1e-9\nbridge = 1e-9",
            "joint_sets.bedding.spacing",
            "joints or traces",
            0,
        ),
        (
            "spacing = 2.0",
            "spacing = 2.0\nspacing_cv = 0.9",
            "joint_sets.bedding.spacing_cv",
            "between 0 and 0.5",
            0,
        ),
        (
            "vertices = [[0.0, 0.0], [40.0, 0.0]",
            "vertices = [[0.0, -1.0], [40.0, -1.0], [40.0, 12.0], [25.0, 12.0]]",
            "regions[1].vertices",
            "overlaps region `base`",
            0,
        ),
        (
            "spacing = 3.0",
            "spacing = 1e-4",
            "regions[1].joint_sets",
            "wrong unit",
            0,
        ),
        (
            // The slope's material misspelt: named on the region, not on a block it is
            // cut into (which has no line of its own).
            "material = \"rock\"",
            "material = \"rocks\"",
            "regions[1].material",
            "no material named `rocks` (defined: rock)",
            1,
        ),
        (
            // Every piece of the slope (a few m^2 each) below its min_area.
            "joint_sets = [\"bedding\", \"cross\"]",
            "joint_sets = [\"bedding\", \"cross\"]\nmin_area = 100.0",
            "regions[1].min_area",
            "nothing is left of it",
            0,
        ),
        (
            // The bedding placed twice.
            "offset = 0.3",
            "offset = 0.3\nthrough = [1.0, 2.0]",
            "joint_sets.bedding.through",
            "one of offset and through",
            0,
        ),
        (
            // Two regions of one id: it names their blocks, and selects them.
            "id = \"slope\"",
            "id = \"base\"",
            "regions[1].id",
            "`base` is also the id of regions[0]",
            0,
        ),
        (
            // A block of the scene's with the id the slope's first piece takes.
            "[[regions]]",
            "[[blocks]]\nid = \"slope.1\"\nmaterial = \"rock\"\nfixed = true\n\
             vertices = [[100.0, 0.0], [101.0, 0.0], [101.0, 1.0]]\n[[regions]]",
            "regions[1].id",
            "names a block `slope.1`, the id of blocks[0]",
            0,
        ),
    ];
    for (from, to, key, words, nth) in cases {
        let line = line_of(SLOPE, from, nth);
        let text: String = SLOPE
            .lines()
            .enumerate()
            .map(|(k, l)| if k + 1 == line { to } else { l })
            .collect::<Vec<_>>()
            .join("\n");
        let e = error(&text);
        assert_eq!(e.key, key, "{e}");
        assert!(e.message.contains(words), "{e}");
        assert!(e.line.is_some(), "{e}");
    }
}

/// A random convex polygon: `n` points on an ellipse of semi-axes `a`, `b`, turned by
/// `turn`, at random angles (sorted), so counter-clockwise and convex.
fn region() -> impl Strategy<Value = Vec<[f64; 2]>> {
    (
        3usize..=40,
        1.0f64..20.0,
        1.0f64..20.0,
        0.0f64..6.3,
        any::<u64>(),
    )
        .prop_map(|(n, a, b, turn, seed)| {
            let mut state = seed | 1;
            let mut angles: Vec<f64> = (0..n)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 7;
                    state ^= state << 17;
                    (state >> 11) as f64 / (1u64 << 53) as f64 * std::f64::consts::TAU
                })
                .collect();
            angles.sort_by(f64::total_cmp);
            angles.dedup_by(|x, y| (*x - *y).abs() < 0.05);
            let (s, c) = turn.sin_cos();
            angles
                .iter()
                .map(|t| {
                    let (x, y) = (a * t.cos(), b * t.sin());
                    [c * x - s * y, s * x + c * y]
                })
                .collect()
        })
}

fn set() -> impl Strategy<Value = JointSetSpec> {
    (-90.0f64..270.0, 0.3f64..5.0, -3.0f64..3.0).prop_map(|(dip_deg, spacing, offset)| {
        JointSetSpec {
            dip_deg,
            spacing,
            offset: Some(offset),
            ..Default::default()
        }
    })
}

proptest! {
    #![proptest_config(dda_geom::test_support::config(200))]

    /// Random convex regions (3 to 40 vertices) cut by 1 to 3 sets: the blocks tile the
    /// region (their areas and the dropped slivers' sum to its area, to 1e-12
    /// relative), no two overlap, and each is a valid convex, counter-clockwise polygon.
    #[test]
    fn blocks_tile_the_region(outline in region(), sets in prop::collection::vec(set(), 1..=3)) {
        prop_assume!(outline.len() >= 3);
        let Ok(shape) = ConvexPolygon::from_coords(&outline) else {
            return Err(TestCaseError::reject("not a valid outline"));
        };
        let mut scene = Scene::parse(SLOPE, Format::Toml, "slope.toml").unwrap().0;
        scene.regions.truncate(0);
        scene.joint_sets.clear();
        let names: Vec<String> = (0..sets.len()).map(|k| format!("s{k}")).collect();
        for (name, s) in names.iter().zip(&sets) {
            scene.joint_sets.insert(name.clone(), s.clone());
        }
        scene.regions.push(RegionSpec {
            id: "r".into(),
            material: "rock".into(),
            vertices: outline.clone(),
            joint_sets: names,
            fixed: false,
            min_area: Some(0.0),
            stress: None,
            stress_gradient: None,
        });
        let explicit = scene.expanded().unwrap();
        let blocks: Vec<ConvexPolygon> = explicit
            .blocks
            .iter()
            .map(|b| ConvexPolygon::from_coords(&b.vertices).unwrap())
            .collect();
        let area: f64 = blocks.iter().map(|b| b.area()).sum();
        prop_assert!((area - shape.area()).abs() <= 1e-12 * shape.area(),
            "{} blocks: {area} vs {}", blocks.len(), shape.area());
        for b in &blocks {
            prop_assert!(b.area() > 0.0);
            let v = b.vertices();
            for k in 0..v.len() {
                let (p, q, r) = (v[k], v[(k + 1) % v.len()], v[(k + 2) % v.len()]);
                prop_assert!((q - p).perp_dot(r - q) > 0.0, "not convex and counter-clockwise");
            }
        }
        let scale = shape.diameter();
        for i in 0..blocks.len() {
            for j in i + 1..blocks.len() {
                let depth = -separation(&blocks[i], &blocks[j]).0;
                prop_assert!(depth <= 1e-9 * scale, "blocks {i} and {j} overlap by {depth}");
            }
        }
    }
}

/// Regions that share an edge written with numbers differing in the last of 6 decimals
/// overlap by 1e-6 m, and are accepted as blocks written so are: the slope's foot at
/// y = -0.000001 on the base's top at y = 0.
#[test]
fn regions_written_to_six_decimals_may_share_an_edge() {
    let text = SLOPE.replacen(
        "vertices = [[0.0, 0.0], [40.0, 0.0]",
        "vertices = [[0.0, -0.000001], [40.0, -0.000001]",
        1,
    );
    assert_ne!(text, SLOPE);
    Scene::parse(&text, Format::Toml, "slope.toml").expect("a shared edge, rounded");
}

/// Bad excavations are refused with their key and line: a time after the run, an outline
/// that removes nothing, one that crosses itself, one that removes all there is to move.
#[test]
fn bad_excavations_are_named_with_key_and_line() {
    let cases = [
        (
            "at = 0.6\nvertices = [[10.0, 1.0], [12.0, 1.0], [12.0, 3.0], [10.0, 3.0]]",
            "excavations[0].at",
            "duration",
        ),
        (
            "at = 0.1\nvertices = [[100.0, 1.0], [102.0, 1.0], [102.0, 3.0], [100.0, 3.0]]",
            "excavations[0].vertices",
            "removes no rock",
        ),
        (
            "at = 0.1\nvertices = [[10.0, 1.0], [12.0, 3.0], [12.0, 1.0], [10.0, 3.0]]",
            "excavations[0].vertices[0]",
            "crosses",
        ),
        (
            "at = 0.1\nvertices = [[-1.0, 0.0], [41.0, 0.0], [41.0, 13.0], [-1.0, 13.0]]",
            "excavations[0].vertices",
            "every free block",
        ),
    ];
    for (body, key, words) in cases {
        let text = format!("{SLOPE}\n[[excavations]]\nid = \"pit\"\n{body}\n");
        let e = error(&text);
        assert_eq!(e.key, key, "{e}");
        assert!(e.message.contains(words), "{e}");
        assert!(e.line.is_some(), "{e}");
    }
    // A good one: the pieces inside are removed at its time, the rest are not.
    let text = format!(
        "{SLOPE}\n[[excavations]]\nid = \"pit\"\nat = 0.1\nvertices = [[10.0, 1.0], \
         [12.0, 1.0], [12.0, 3.0], [10.0, 3.0]]\n"
    );
    let (scene, _) = Scene::parse(&text, Format::Toml, "slope.toml").unwrap();
    let explicit = scene.expanded().unwrap();
    let removed: f64 = explicit
        .blocks
        .iter()
        .filter(|b| b.removed_at == Some(0.1))
        .map(|b| ConvexPolygon::from_coords(&b.vertices).unwrap().area())
        .sum();
    assert!(
        (removed - 4.0).abs() < 1e-9,
        "removed {removed} m^2 of a 2 x 2 m pit"
    );
}

/// A body is its parts joined by seams of intact rock, and comes apart where the parts
/// that join them go: four unit squares of one body, `a`, `b` and `c` side by side and
/// `d` touching `c` only at a corner. `a`, `b` and `c` make one body and `d` none (a
/// corner is no seam), with a warning naming it; with `b` removed, `a` and `c` are
/// blocks on their own.
#[test]
fn a_body_is_its_parts_joined_by_seams() {
    let square = |id: &str, x: f64, y: f64| {
        format!(
            "[[blocks]]\nid = \"{id}\"\nmaterial = \"rock\"\nbody = \"rock\"\n\
             vertices = [[{x}, {y}], [{}, {y}], [{}, {}], [{x}, {}]]\n",
            x + 1.0,
            x + 1.0,
            y + 1.0,
            y + 1.0
        )
    };
    let text = format!(
        "name = \"parts\"\n[analysis]\nduration = 0.1\ntime_step = 0.01\n\
         max_displacement = 0.01\nnormal_penalty = 1e9\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n{}{}{}{}",
        square("a", 0.0, 0.0),
        square("b", 1.0, 0.0),
        square("c", 2.0, 0.0),
        square("d", 3.0, 1.0)
    );
    let (_, model) = Scene::parse(&text, Format::Toml, "parts.toml").unwrap();
    assert_eq!(model.seams, vec![[0, 1], [1, 2]]);
    assert_eq!(
        model.bodies(&[false; 4]),
        vec![Some(0), Some(0), Some(0), None]
    );
    assert_eq!(model.bodies(&[false, true, false, false]), vec![None; 4]);
    // The scene is told of `d`, and of nothing else of its bodies.
    let told: Vec<&str> = model
        .warnings
        .iter()
        .filter(|w| w.message.contains("shares no seam"))
        .map(|w| w.key.as_str())
        .collect();
    assert_eq!(told, ["blocks[3].body"]);
    // The parts an excavation makes are not the scene's to mend: one that cuts a region's
    // block 2e-6 m from its side leaves the part inside, the body's only one, the strip
    // outside dropped as a sliver.
    let text = String::from(
        "name = \"one part\"\n[analysis]\nduration = 0.1\ntime_step = 0.002\n\
         max_displacement = 0.002\nnormal_penalty = 1e9\ngravity = [0.0, -9.81]\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n\
         [[blocks]]\nid = \"keep\"\nmaterial = \"rock\"\n\
         vertices = [[5.0, 0.0], [6.0, 0.0], [6.0, 1.0], [5.0, 1.0]]\n\
         [[regions]]\nid = \"m\"\nmaterial = \"rock\"\n\
         vertices = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]]\n\
         [[excavations]]\nid = \"cut\"\nat = 0.05\n\
         vertices = [[0.000002, -0.5], [4.5, -0.5], [4.5, 4.5], [0.000002, 4.5]]\n",
    );
    let (_, model) = Scene::parse(&text, Format::Toml, "one-part.toml").unwrap();
    let parts: Vec<_> = model.blocks.iter().filter(|b| b.body.is_some()).collect();
    assert_eq!(
        parts.len(),
        1,
        "{:?}",
        parts.iter().map(|b| &b.id).collect::<Vec<_>>()
    );
    assert!(
        model
            .warnings
            .iter()
            .all(|w| !w.message.contains("shares no seam")),
        "{:?}",
        model.warnings
    );
}

/// An excavation that cuts a block keeps the load written on the block's face: a 1 m
/// block turned 58.7 degrees and written to 6 decimals, a load at a point of its top
/// face 4.4e-7 m outside it as written, the block's other half excavated. The load goes
/// with the half that holds it, within what a point written so misses its face by (2e-6
/// m). Until 2026-11-27 the pieces held a load to 1e-9 of their size, and this one went
/// to none: the run lost it without a word.
#[test]
fn an_excavation_keeps_a_load_written_on_a_face() {
    let (sin, cos) = 58.7f64.to_radians().sin_cos();
    let turn = |x: f64, y: f64| format!("[{:.6}, {:.6}]", x * cos - y * sin, x * sin + y * cos);
    let outline = |points: &[(f64, f64)]| {
        let v: Vec<String> = points.iter().map(|&(x, y)| turn(x, y)).collect();
        format!("[{}]", v.join(", "))
    };
    let text = format!(
        "name = \"load on a face\"\n[analysis]\nduration = 0.1\ntime_step = 0.002\n\
         max_displacement = 0.002\nnormal_penalty = 1e9\n\
         [materials.rock]\ndensity = 2600.0\nyoung = 1e9\npoisson = 0.25\n\
         [[blocks]]\nid = \"key\"\nmaterial = \"rock\"\nvertices = {}\n\
         loads = [{{ at = {}, force = [0.0, -1000.0] }}]\n\
         [[excavations]]\nid = \"half\"\nat = 0.05\nvertices = {}\n",
        outline(&[(-0.5, -1.0), (0.5, -1.0), (0.5, 0.0), (-0.5, 0.0)]),
        turn(0.3, 0.0),
        outline(&[(-1.0, -2.0), (0.0, -2.0), (0.0, 1.0), (-1.0, 1.0)]),
    );
    let (_, model) = Scene::parse(&text, Format::Toml, "load.toml").unwrap();
    let loaded: Vec<_> = model
        .blocks
        .iter()
        .filter(|b| !b.loads.is_empty())
        .map(|b| (b.id.as_str(), b.loads.len(), b.removed_at))
        .collect();
    assert_eq!(loaded.len(), 1, "{loaded:?}");
    assert_eq!((loaded[0].1, loaded[0].2), (1, None), "{loaded:?}");
    assert!(model.warnings.is_empty(), "{:?}", model.warnings);
}
