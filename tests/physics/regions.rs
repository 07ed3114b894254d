//! A rock mass written as a region cut by joint sets behaves as its joints say:
//! `examples/planar-slope.toml`, a slope whose bedding dips 30 degrees out of its face,
//! stands when the joints' friction is above the dip and slides along the bedding when
//! it is below.

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use crate::by_hand::Turned;
use dda::contact::ContactKey;
use dda::core::{Format, RunOptions, Scene, Simulation};
use dda::geom::{ConvexPolygon, DVec2};

const SLOPE: &str = include_str!("../../examples/planar-slope.toml");

/// Runs the slope with the joints' friction `phi` degrees; each free block's movement.
fn moves(phi: f64) -> Vec<(String, DVec2)> {
    let text = SLOPE.replace("friction_deg = 40.0", &format!("friction_deg = {phi}"));
    let (_, model) = Scene::parse(&text, Format::Toml, "planar-slope.toml").unwrap();
    let start: Vec<DVec2> = model.blocks.iter().map(|b| b.polygon.centroid()).collect();
    let ids: Vec<String> = model.blocks.iter().map(|b| b.id.clone()).collect();
    let fixed: Vec<bool> = model.blocks.iter().map(|b| b.fixed).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    sim.blocks()
        .iter()
        .enumerate()
        .filter(|(i, _)| !fixed[*i])
        .map(|(i, b)| (ids[i].clone(), b.polygon.centroid() - start[i]))
        .collect()
}

/// A region's in-situ stress (`regions[].stress`, `stress_gradient`): the jointed mass of
/// `tests/scenes/in-situ.toml`, laterally confined, given a lithostatic stress with K = 1,
/// keeps it through a static analysis under gravity: every block's sx and sy within 1%
/// of -rho g (5 - y) at its centroid. The joints' penalty springs (p = 1e13 N/m, two to
/// a 1 m face) give under the load, relieving a block's stress by about E' / p per
/// metre, 1e-3 of it; 1e-2 bounds that. Without the keys the blocks start unstressed
/// and the slot holds them at K = nu / (1 - nu) = 1/3 (within 1e-2 of sy likewise):
/// the keys are what keeps sx. A gradient that would take a block beyond the stress a
/// block may have is refused, naming the key.
#[test]
fn a_region_keeps_the_in_situ_stress_it_is_given() {
    const SCENE: &str = include_str!("../scenes/in-situ.toml");
    let unstressed: String = SCENE
        .lines()
        .filter(|l| !l.starts_with("stress"))
        .map(|l| format!("{l}\n"))
        .collect();
    for (text, k) in [(SCENE.to_string(), 1.0), (unstressed, 1.0 / 3.0)] {
        let (_, model) = Scene::parse(&text, Format::Toml, "in-situ.toml").unwrap();
        let ids: Vec<String> = model.blocks.iter().map(|b| b.id.clone()).collect();
        let mut sim = Simulation::new(model, RunOptions::default());
        sim.run(|_, _| {}).unwrap();
        let mut checked = 0;
        for (id, b) in ids.iter().zip(sim.blocks()) {
            if !id.starts_with("mass.") {
                continue;
            }
            let y = b.polygon.centroid().y;
            let lithostatic = -2600.0 * 9.81 * (5.0 - y);
            let [sx, sy, _] = b.stress;
            assert!((sy / lithostatic - 1.0).abs() < 1e-2, "{id}: sy {sy}");
            assert!(
                (sx / sy - k).abs() < 1e-2,
                "{id}: sx / sy {}, K {k}",
                sx / sy
            );
            checked += 1;
        }
        assert_eq!(checked, 10);
    }
    // Out of its own range (1e9 Pa/m), and taking the top blocks (y = 4.5 m) beyond 1e11 Pa.
    let steep = SCENE.replace("25506.0, 25506.0", "25506.0, 2e9");
    let beyond = SCENE
        .replace("-127530.0, -127530.0", "-127530.0, 9.9e10")
        .replace("25506.0, 25506.0", "25506.0, 1e9");
    for text in [steep, beyond] {
        let e = Scene::parse(&text, Format::Toml, "in-situ.toml").unwrap_err();
        assert!(
            e.to_string().contains("regions[0].stress_gradient[1]"),
            "{e}"
        );
    }
}

/// `examples/deep-tunnel.toml`: a tunnel excavated in a jointed mass under the stress of
/// 400 m depth (K = 1.5) converges into its opening: the crown comes down, the invert
/// up, the sidewall in, each by more than 0.1 mm and less than ten times the elastic
/// scale of a hole of radius a = 2.5 m in rock of E = 20 GPa under the larger stress,
/// sigma a (1 + nu) / E = 2.4 mm (the joints add their springs and slip to the
/// rock's elasticity). It does so in the steps its time step asks (at most twice
/// 0.4 s / 1 ms): with the two slivers of a few mm^2 the cutting leaves at the mass's
/// foot kept (`min_area = 0`), one of them spun up after the excavation and held every
/// step to 5e-7 s (339,259 steps). Run with friction 50 degrees instead of the example's
/// 35: the rim's roof wedges between the two joint sets (90 degrees apart) lock only
/// above 45 degrees ([`a_roof_wedge_that_cannot_lock_leaves_the_deep_tunnel_s_crown`]),
/// and below it they leave the rim, as the example's do.
#[test]
fn a_deep_tunnel_converges_into_its_opening_in_the_steps_it_asks() {
    let text = include_str!("../../examples/deep-tunnel.toml");
    assert!(text.contains("friction_deg = 35.0"));
    let text = text.replace("friction_deg = 35.0", "friction_deg = 50.0");
    let (_, model) = Scene::parse(&text, Format::Toml, "deep-tunnel.toml").unwrap();
    let points: Vec<_> = model.measures.iter().map(|m| (m.block, m.at)).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    let most = 2 * 400;
    while !sim.finished() && sim.totals().steps < most {
        sim.step().unwrap();
    }
    assert!(
        sim.finished(),
        "{} steps by t = {}",
        sim.totals().steps,
        sim.time()
    );
    let moved: Vec<DVec2> = points
        .iter()
        .map(|&(b, at)| sim.material_point(b, at) - at)
        .collect();
    let scale = 15.3e6 * 2.5 * 1.25 / 20e9;
    // Crown, sidewall (on the right of the tunnel), invert: each inwards.
    for (k, inward) in [(0, -moved[0].y), (1, -moved[1].x), (2, moved[2].y)] {
        assert!(
            inward > 1e-4 && inward < 10.0 * scale,
            "point {k}: {inward} m in"
        );
    }
}

/// The crown of `examples/deep-tunnel.toml` is a roof wedge: two joints, one of each set
/// (30 and 120 degrees), meet above the tunnel at a right angle and the opening cuts the
/// wedge's base. Clamped by the stress alone (its weight is a thousandth of the forces on
/// its faces), the wedge stays only if one force lies within both faces' friction cones,
/// whose axes (the inward normals) are 180 - 90 = 90 degrees apart: 2 phi >= 90 degrees.
/// At the example's 35 degrees the stress squeezes it out, and the crown point, on it,
/// leaves the rim by more than a tenth of a metre within the 0.3 s after the excavation
/// (it does not lock at 50 degrees:
/// [`a_deep_tunnel_converges_into_its_opening_in_the_steps_it_asks`]). The cover
/// detector held it until 2026-11-28: a corner of the wedge's foot met a corner of the
/// rim block beside it diagonally, both inside each other by the stress's own overlap,
/// and four springs there, one per edge, held the wedge up (2 MN), where the shortest
/// exit gives one face (docs/method.md section 5).
#[test]
fn a_roof_wedge_that_cannot_lock_leaves_the_deep_tunnel_s_crown() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/deep-tunnel.toml");
    let (_, model) = Scene::load(&file).unwrap();
    let (block, at) = (model.measures[0].block, model.measures[0].at);
    assert_eq!(model.measures[0].id, "crown");
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    let fell = at.y - sim.material_point(block, at).y;
    assert!(fell > 0.1, "the crown came down {fell} m");
}

/// The same tunnel with its slivers kept (`min_area = 0`): under Shi's rule one of them,
/// wedged at the mass's foot and disturbed by the excavation, spins up numerically and
/// holds the steps down (section 12 of docs/method.md: a mode far stiffer than 1 / dt
/// keeps its velocity, flipping sign, 1 - 8 / (w dt)^2 of it a step), and the run is
/// far from its end after twice the steps it asks; under the damped rule, which keeps
/// at most a third of such a mode a step, it ends in them (at most twice 0.4 s / 1 ms,
/// as above).
#[test]
fn a_sliver_kept_in_the_deep_tunnel_holds_shi_s_rule_and_not_the_damped_one() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/deep-tunnel.toml");
    let text = std::fs::read_to_string(file).unwrap();
    let text = text.replacen("[[regions]]", "[[regions]]\nmin_area = 0", 1);
    let most = 2 * 400;
    let run = |integration: &str| {
        let text = text.replacen(
            "[analysis]",
            &format!("[analysis]\nintegration = \"{integration}\""),
            1,
        );
        let (_, model) = Scene::parse(&text, Format::Toml, "deep-tunnel.toml").unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        while !sim.finished() && sim.totals().steps < most {
            sim.step().unwrap();
        }
        (sim.finished(), sim.time())
    };
    let (ended, t) = run("constant-acceleration");
    assert!(
        !ended && t < 0.3,
        "Shi's rule reached t = {t} s in {most} steps"
    );
    let (ended, t) = run("damped-constant-acceleration");
    assert!(ended, "the damped rule reached t = {t} s in {most} steps");
}

/// Friction 40 degrees, above the bedding's 30: no block moves by 5 mm in 0.5 s (the
/// flush-joint issue's standard for standing). Friction 20 degrees: the layer at the
/// face slides down the bedding, out of the face, at least half as far as a block on a
/// 30-degree plane would in 0.5 s, g (sin 30 - cos 30 tan 20) t^2 / 2 = 0.227 m, and
/// every block that slides goes down and out of the face.
#[test]
fn a_daylighting_bedding_slides_below_its_friction_and_stands_above() {
    let stood = moves(40.0);
    let most = stood.iter().map(|(_, d)| d.length()).fold(0.0, f64::max);
    assert!(most < 5e-3, "moved {most} m with friction 40 deg");

    let slid = moves(20.0);
    let (id, d) = slid
        .iter()
        .max_by(|a, b| a.1.length().total_cmp(&b.1.length()))
        .unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    let t = 0.5;
    let single = 0.5 * 9.81 * (s - c * 20f64.to_radians().tan()) * t * t;
    assert!(
        d.length() > 0.5 * single,
        "{id} moved {d:?}, a block would {single} m"
    );
    // Every block that slid went down and out of the face (towards -x, -y), none back
    // into the slope.
    for (id, d) in slid.iter().filter(|(_, d)| d.length() > 0.01) {
        assert!(d.x < 0.0 && d.y < 0.0, "{id} moved {d:?}");
    }
}

/// A joint set may carry contact properties of its own: with the default joint at 40
/// degrees (the slope stands, above) and the bedding's own joint at 20, the layers slide
/// along the bedding as they do when every joint is at 20.
#[test]
fn a_set_with_a_joint_of_its_own_slides_on_it() {
    let text = SLOPE.replace(
        "[joint_sets.bedding]\n",
        "[joints.bedding]\nfriction_deg = 20.0\n\n[joint_sets.bedding]\njoint = \"bedding\"\n",
    );
    let (scene, model) = Scene::parse(&text, Format::Toml, "planar-slope.toml").unwrap();
    // The explicit scene names the bedding joint on the faces along the bedding only.
    let explicit = scene.expanded().unwrap();
    let named = explicit
        .blocks
        .iter()
        .flat_map(|b| b.edge_joints.iter())
        .filter(|j| *j == "bedding")
        .count();
    let edges: usize = explicit.blocks.iter().map(|b| b.vertices.len()).sum();
    assert!(named > 0 && named < edges, "{named} of {edges} edges");
    let start: Vec<DVec2> = model.blocks.iter().map(|b| b.polygon.centroid()).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    let most = sim
        .blocks()
        .iter()
        .zip(&start)
        .map(|(b, s)| (b.polygon.centroid() - *s).length())
        .fold(0.0, f64::max);
    let (s, c) = 30f64.to_radians().sin_cos();
    let single = 0.5 * 9.81 * (s - c * 20f64.to_radians().tan()) * 0.25;
    assert!(
        most > 0.5 * single,
        "moved {most} m, a block would {single} m"
    );
}

/// A region with a re-entrant corner: a 2 x 3 m post with a 2 x 1 m arm reaching out
/// from its top, standing on fixed ground, cut into two convex parts whose seam runs
/// from corner to corner.
const POST_AND_ARM: &str = r#"
name = "post-and-arm"

[analysis]
duration = 0.5
time_step = 0.002
max_displacement = 0.005
normal_penalty = 1e10
gravity = [0.0, -9.81]

[materials.rock]
density = 2600.0
young = 5e9
poisson = 0.25

[joints.default]
friction_deg = 30.0

[[blocks]]
id = "ground"
material = "rock"
vertices = [[-2.0, -1.0], [6.0, -1.0], [6.0, 0.0], [-2.0, 0.0]]
fixed = true

[[regions]]
id = "post"
material = "rock"
vertices = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [4.0, 2.0], [4.0, 3.0], [0.0, 3.0]]
"#;

/// The post and arm is one block, carried as convex parts glued together: in 0.5 s the arm's tip drops by less than 1 mm (its weight, 51 kN,
/// on the glue's springs of 1e10 N/m deflects it by about 1e-5 m). The same parts left
/// unglued let the arm fall: at least half of the 1.23 m a free fall covers.
#[test]
fn the_parts_of_a_non_convex_block_move_as_one() {
    let (scene, _) = Scene::parse(POST_AND_ARM, Format::Toml, "post.toml").unwrap();
    let explicit = scene.expanded().unwrap();
    let parts: Vec<_> = explicit
        .blocks
        .iter()
        .filter(|b| b.body.is_some())
        .collect();
    assert!(parts.len() >= 2, "{} parts", parts.len());
    assert!(parts.iter().all(|b| b.body.as_deref() == Some("post.1")));
    let tip_drop = |scene: &Scene| {
        let model = scene.validate().unwrap();
        let tip = DVec2::new(4.0, 3.0);
        let (block, vertex) = model
            .blocks
            .iter()
            .enumerate()
            .find_map(|(i, b)| {
                b.polygon
                    .vertices()
                    .iter()
                    .position(|v| v.distance(tip) < 1e-12)
                    .map(|k| (i, k))
            })
            .unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        sim.run(|_, _| {}).unwrap();
        tip.y - sim.blocks()[block].polygon.vertices()[vertex].y
    };
    let glued = tip_drop(&explicit);
    assert!(glued.abs() < 1e-3, "the glued arm's tip dropped {glued} m");
    let mut loose = explicit.clone();
    for b in &mut loose.blocks {
        b.body = None;
        b.glued_edges = None;
    }
    let fell = tip_drop(&loose);
    assert!(
        fell > 0.5 * 0.5 * 9.81 * 0.25,
        "the loose arm's tip dropped {fell} m"
    );
}

/// A non-convex block written by hand as convex parts of one `body`, to 6 decimals: the
/// post and arm above as two blocks, the whole scene turned 61 degrees (its gravity
/// too), so that the parts' shared faces differ in the last digit. The parts find their
/// seam within what hand-written faces may differ by (2e-6 m) and hold as one, their
/// glue reaching as far: the arm's tip drops by less than 1 mm along the gravity in
/// 0.5 s, as the region's does, also where d_tol is small. With
/// the seam looked for within 1e-9 of the parts' size (until 2026-11-27) the parts had
/// none, and the arm fell.
#[test]
fn a_body_written_to_six_decimals_finds_its_seams() {
    let hand = Turned::new(61.0);
    let outline = |p: &[_]| hand.outline(p);
    let g = hand.point(0.0, -9.81);
    // d_max 5 mm, and 0.1 mm, whose 1e-3 d_tol (2e-7 m) is below what the faces differ by
    // (7.5e-7 m from the arm's lower corner to the post's face).
    for d_max in [0.005, 0.0001] {
        let text = format!(
            "name = \"post and arm by hand\"\n[analysis]\nduration = 0.5\ntime_step = 0.002\n\
             max_displacement = {d_max}\nnormal_penalty = 1e10\ngravity = [{}, {}]\n\
             [materials.rock]\ndensity = 2600.0\nyoung = 5e9\npoisson = 0.25\n\
             [joints.default]\nfriction_deg = 30.0\n\
             [[blocks]]\nid = \"ground\"\nmaterial = \"rock\"\nfixed = true\nvertices = {}\n\
             [[blocks]]\nid = \"post\"\nmaterial = \"rock\"\nbody = \"L\"\nvertices = {}\n\
             [[blocks]]\nid = \"arm\"\nmaterial = \"rock\"\nbody = \"L\"\nvertices = {}\n",
            g.x,
            g.y,
            outline(&[(-2.0, -1.0), (6.0, -1.0), (6.0, 0.0), (-2.0, 0.0)]),
            outline(&[(0.0, 0.0), (2.0, 0.0), (2.0, 3.0), (0.0, 3.0)]),
            outline(&[(2.0, 2.0), (4.0, 2.0), (4.0, 3.0), (2.0, 3.0)]),
        );
        let (_, model) = Scene::parse(&text, Format::Toml, "post.toml").unwrap();
        assert_eq!(model.seams, vec![[1, 2]], "d_max {d_max}");
        let tip = model.blocks[2].polygon.vertices()[2];
        let mut sim = Simulation::new(model, RunOptions::default());
        sim.run(|_, _| {}).unwrap();
        let down = g / g.length();
        let drop = (sim.blocks()[2].polygon.vertices()[2] - tip).dot(down);
        assert!(
            drop.abs() < 1e-3,
            "d_max {d_max}: the arm's tip dropped {drop} m"
        );
    }
}

/// The glue of non-convex blocks' parts holds their seams to the ends, where parts
/// meet corner to corner: in `tests/scenes/rock-mass.toml` (a jointed mass whose
/// non-convex pieces are glued parts) every seam contact bonded at the first step is
/// active and bonded after every step, until an excavation removes it. Where rounding or strain takes a seam end's
/// vertex past its edge's end (r just outside [0, 1]), the detector leaves its contact
/// inactive; before the glue kept it, seam ends of this mass lost their springs at
/// every step, and on a jointed pit wall under a quake a sliver part's seam end went
/// 2.8 mm deep unheld, then struck back with 6% of the reference energy.
#[test]
fn glued_seams_keep_their_springs_where_the_parts_meet_corner_to_corner() {
    let text = include_str!("../scenes/rock-mass.toml");
    let (_, model) = Scene::parse(text, Format::Toml, "rock-mass.toml").unwrap();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.step().unwrap();
    let body = |i: u32| sim.model().blocks[i as usize].body;
    let seams: Vec<_> = sim
        .contacts()
        .active()
        .filter(|c| c.bonded && body(c.key.vertex_block).is_some())
        .filter(|c| body(c.key.vertex_block) == body(c.key.edge_block))
        .map(|c| c.key)
        .collect();
    assert!(seams.len() >= 10, "{} seam contacts", seams.len());
    while !sim.finished() {
        let record = sim.step().unwrap();
        let removed = |k: &ContactKey| {
            sim.is_removed(k.vertex_block as usize) || sim.is_removed(k.edge_block as usize)
        };
        for key in seams.iter().filter(|k| !removed(k)) {
            let held = sim
                .contacts()
                .find(key)
                .is_some_and(|c| c.active && c.bonded);
            assert!(held, "step {}: seam contact {key:?} not held", record.step);
        }
    }
}

/// A body whose joining part is excavated comes apart: what the parts left share is no
/// longer intact rock. `tests/scenes/split-body.toml`: three glued parts, one above the
/// other, `L` on a fixed base, its top sloping down at 15 degrees; `M` on it, with a
/// level top; a small `T` on `M`. `M` is removed at 0.01 s, and `T` falls onto `L`'s
/// slope, a seam of the body until then, with no joint of its own between the two
/// (frictionless). It must land on it and slide
/// down it with every detector, never sinking into `L` beyond d_tol: it falls some 0.5 m
/// (0.33 s), and from rest on a frictionless 15-degree slope it would slide 0.5 g sin 15
/// t^2 = 0.57 m in the 0.67 s left, 0.55 m across; a part glued where it lands would only
/// turn about that corner onto the slope (some 0.05 m), so more than 0.2 m across. Before the bodies
/// came apart with their excavations (until 2026-11-27), `T` against `L`'s seam was
/// either no contact (farther than 1e-3 d_tol from the seam's line), and fell into `L`
/// (its centroid 1.6 m down, inside `L`, after 1 s), or glue, bonded where it touched: on
/// the unsettled pit wall of `tests/scenes/pit-wall.toml` a part the toe cut freed was
/// glued by one corner to a part it fell on, swung about it to 60 rad/s, and stopped the
/// run on energy created.
#[test]
fn a_body_split_by_an_excavation_comes_apart() {
    let text = include_str!("../scenes/split-body.toml");
    for detector in ["cover", "type-1", "type-2"] {
        let (mut scene, _) = Scene::parse(text, Format::Toml, "split-body.toml").unwrap();
        scene.analysis.detector = detector.to_string();
        let model = scene.validate().unwrap();
        let d_tol = model.params.d_tol;
        let (l, t) = (1, 3);
        let start = model.blocks[t].polygon.centroid();
        let mut sim = Simulation::new(model, RunOptions::default());
        while !sim.finished() {
            sim.step().unwrap();
            // How deep T's deepest vertex is inside L: the least of its depths behind L's
            // edges' lines (negative: outside L).
            let lp = &sim.blocks()[l].polygon;
            for &v in sim.blocks()[t].polygon.vertices() {
                let depth = lp
                    .edges()
                    .map(|(a, c)| (c - a).perp_dot(v - a) / a.distance(c))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    depth <= d_tol,
                    "{detector}: t = {}: a vertex of T {depth} m deep in L",
                    sim.time()
                );
            }
        }
        let moved = sim.blocks()[t].polygon.centroid() - start;
        assert!(
            moved.x > 0.2,
            "{detector}: T moved {moved:?}, not down L's slope"
        );
    }
}

/// Goodman and Bray's limit equilibrium of columns on a stepped base (Goodman and Bray
/// 1976; Hoek and Bray, "Rock Slope Engineering", the toppling chapter), computed here
/// from the columns alone: in the frame of the treads (x up the treads, which dip
/// `alpha`), column n has width dx, base b_n, top t_n and weight W_n; the force from the
/// column above acts at the top of their shared face, M_n = min(t_n, t_n+1) - b_n above
/// n's base, the force from the column below at L_n = min(t_n-1, t_n) - b_n. From the
/// top down, the force n passes down is the largest of what holds it against toppling,
/// (P_n (M_n - dx tan phi) + W_n / 2 (h_n sin alpha - dx cos alpha)) / L_n, against
/// sliding, P_n - W_n (cos alpha tan phi - sin alpha) / (1 - tan^2 phi), and 0. The
/// slope stands if no force is left at the toe. Returns that force, N/m.
fn goodman_bray(columns: &[(f64, f64, f64, f64)], alpha: f64, phi: f64) -> f64 {
    let (s, c) = alpha.sin_cos();
    let t = phi.tan();
    let mut p = 0.0f64;
    for n in (0..columns.len()).rev() {
        let (dx, b, top, w) = columns[n];
        let h = top - b;
        let m = columns.get(n + 1).map_or(h, |u| top.min(u.2) - b);
        let l = if n > 0 {
            columns[n - 1].2.min(top) - b
        } else {
            0.0
        };
        let moment = p * (m - dx * t) + 0.5 * w * (h * s - dx * c);
        let topple = if l > 0.0 {
            moment / l
        } else if moment > 0.0 {
            f64::INFINITY
        } else {
            0.0
        };
        let slide = p - w * (c * t - s) / (1.0 - t * t);
        p = topple.max(slide).max(0.0);
    }
    p
}

/// `examples/toppling.toml`: ten columns on a stepped base. Goodman and Bray's critical
/// friction angle phi_c, found by bisection on the columns the region is cut into (about
/// 31 degrees), separates standing from toppling in DDA too: at phi_c + 5 degrees no
/// column moves by 5 mm or turns by half a degree in 2 s; at phi_c - 5 degrees every
/// column above the toe turns towards the face (counter-clockwise) by more than 10
/// degrees: they topple.
#[test]
fn columns_on_a_stepped_base_topple_below_the_limit_equilibrium_friction() {
    let text = include_str!("../../examples/toppling.toml");
    let (scene, _) = Scene::parse(text, Format::Toml, "toppling.toml").unwrap();
    let alpha = (scene.joint_sets["columns"].dip_deg - 90.0).to_radians();
    let density = scene.materials["rock"].density;
    let explicit = scene.expanded().unwrap();
    // Each free block in the treads' frame: (x0, (width, base, top, weight)), by x0.
    let to_local = DVec2::from_angle(-alpha);
    let mut columns: Vec<(f64, (f64, f64, f64, f64))> = Vec::new();
    for b in explicit.blocks.iter().filter(|b| !b.fixed) {
        let local: Vec<DVec2> = b
            .vertices
            .iter()
            .map(|&v| to_local.rotate(DVec2::from(v)))
            .collect();
        let lo = local.iter().copied().reduce(DVec2::min).unwrap();
        let hi = local.iter().copied().reduce(DVec2::max).unwrap();
        let area = ConvexPolygon::from_coords(&b.vertices).unwrap().area();
        // A rectangle in this frame: its area is its width times its height.
        let (w, h) = (hi.x - lo.x, hi.y - lo.y);
        assert!(
            (area - w * h).abs() < 1e-6 * area,
            "{} is not a column",
            b.id
        );
        columns.push((lo.x, (w, lo.y, hi.y, density * 9.81 * area)));
    }
    columns.sort_by(|a, b| a.0.total_cmp(&b.0));
    let columns: Vec<_> = columns.into_iter().map(|(_, c)| c).collect();
    assert_eq!(columns.len(), 10);
    let (mut lo, mut hi) = (alpha, 44.9f64.to_radians());
    assert!(goodman_bray(&columns, alpha, lo) > 0.0);
    assert_eq!(goodman_bray(&columns, alpha, hi), 0.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if goodman_bray(&columns, alpha, mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let phi_c = hi.to_degrees();
    assert!((25.0..40.0).contains(&phi_c), "phi_c {phi_c}");
    // Each free block's movement and turn (of its first edge), counter-clockwise positive.
    let run = |phi: f64| {
        let text = text.replace("friction_deg = 36.0", &format!("friction_deg = {phi}"));
        let (_, model) = Scene::parse(&text, Format::Toml, "toppling.toml").unwrap();
        let edge_angle = |p: &ConvexPolygon| {
            let (a, b) = p.edge(0);
            (b - a).to_angle()
        };
        let start: Vec<Option<(DVec2, f64)>> = model
            .blocks
            .iter()
            .map(|b| (!b.fixed).then(|| (b.polygon.centroid(), edge_angle(&b.polygon))))
            .collect();
        let mut sim = Simulation::new(model, RunOptions::default());
        sim.run(|_, _| {}).unwrap();
        sim.blocks()
            .iter()
            .zip(&start)
            .filter_map(|(b, s)| {
                s.map(|(c, a)| {
                    let turn = (edge_angle(&b.polygon) - a).to_degrees();
                    ((b.polygon.centroid() - c).length(), turn)
                })
            })
            .collect::<Vec<_>>()
    };
    let stood = run((phi_c + 5.0).round());
    for (k, &(moved, turned)) in stood.iter().enumerate() {
        assert!(
            moved < 5e-3 && turned.abs() < 0.5,
            "column {k} moved {moved} m, turned {turned} deg at phi_c + 5 = {}",
            phi_c + 5.0
        );
    }
    let toppled = run((phi_c - 5.0).round());
    // The toe column (the first in the scene's order is the one cut first, so measure
    // all but the one that turned least: the toe slides rather than turns).
    let mut turns: Vec<f64> = toppled.iter().map(|&(_, t)| t).collect();
    turns.sort_by(f64::total_cmp);
    for &t in &turns[1..] {
        assert!(t > 10.0, "turns {turns:?} at phi_c - 5 = {}", phi_c - 5.0);
    }
}

/// `examples/tunnel.toml` with frictionless, persistent joints: before the excavation
/// (t = 0.25 s) the confined mass only settles (no block moves by 5 mm); after it, the
/// key block of the roof falls into the opening, at least half as far as a free fall
/// in the remaining 0.5 s, g t^2 / 2 = 1.23 m. The removed pieces are those inside
/// the tunnel's outline, and none other.
#[test]
fn rock_above_an_excavation_falls_after_it_and_not_before() {
    let text = include_str!("../../examples/tunnel.toml")
        .replace("friction_deg = 30.0", "friction_deg = 0.0")
        .lines()
        .filter(|l| {
            !["trace_length", "bridge", "seed"]
                .iter()
                .any(|k| l.starts_with(k))
        })
        .collect::<Vec<_>>()
        .join("\n");
    let (scene, model) = Scene::parse(&text, Format::Toml, "tunnel.toml").unwrap();
    let at = scene.excavations[0].at;
    let tunnel = dda::geom::Outline::new(
        scene.excavations[0]
            .vertices
            .iter()
            .map(|&v| DVec2::from(v))
            .collect(),
    )
    .unwrap();
    for b in &model.blocks {
        let inside = tunnel.contains(b.polygon.centroid());
        assert_eq!(b.removed_at.is_some(), inside, "{}", b.id);
    }
    let start: Vec<DVec2> = model.blocks.iter().map(|b| b.polygon.centroid()).collect();
    let mut sim = Simulation::new(model, RunOptions::default());
    let mut before = 0.0f64;
    while !sim.finished() {
        sim.step().unwrap();
        if sim.time() <= at {
            for (i, b) in sim.blocks().iter().enumerate() {
                before = before.max((b.polygon.centroid() - start[i]).length());
            }
        }
    }
    assert!(before < 5e-3, "moved {before} m before the excavation");
    let fell = sim
        .blocks()
        .iter()
        .enumerate()
        .filter(|&(i, _)| !sim.is_removed(i))
        .map(|(i, b)| start[i].y - b.polygon.centroid().y)
        .fold(0.0, f64::max);
    let free_fall = 0.5 * 9.81 * (0.75 - at) * (0.75 - at);
    assert!(
        fell > 0.5 * free_fall,
        "fell {fell} m, a free fall {free_fall} m"
    );
}

/// `tests/scenes/rock-mass.toml`: a non-convex slope cut by a bedding set and a
/// non-persistent, statistical cross set, excavated at 0.1 s. With the cover detector
/// and TB-CD-1 it runs past the excavation under the physics guard (no energy created
/// beyond 1%, no penetration beyond d_tol): the glue of the non-convex pieces starts
/// unloaded. (Before the glue took only seam contacts, a vertex 3 mm across a sliver
/// part was locked to a face it did not touch, and the first step created 2 times the
/// reference energy.) TB-CD-2 is left out: its bands fail on this mass's edges shorter
/// than d_tol, glued or not (docs/method.md, section 10).
#[test]
fn a_jointed_mass_with_glued_pieces_runs_under_the_guard() {
    let text = include_str!("../scenes/rock-mass.toml");
    for detector in ["cover", "type-1"] {
        let text = text.replace(
            "normal_penalty = 1e10",
            &format!("normal_penalty = 1e10\ndetector = \"{detector}\""),
        );
        let (_, model) = Scene::parse(&text, Format::Toml, "rock-mass.toml").unwrap();
        assert!(model.blocks.iter().any(|b| b.body.is_some()));
        let options = RunOptions {
            stop_on_violation: true,
            ..RunOptions::default()
        };
        let mut sim = Simulation::new(model, options);
        sim.run(|_, _| {})
            .unwrap_or_else(|e| panic!("{detector}: {e}"));
        assert!((0..sim.blocks().len()).any(|i| sim.is_removed(i)));
    }
}

/// `tests/scenes/pit-wall.toml`: a jointed pit wall of 227 blocks, many of them glued
/// parts of non-convex pieces, with two bolts, a toe cut excavated at 0.3 s and a quake
/// from 0.4 s, runs to its end under the physics guard (no energy created beyond 1%, no
/// penetration beyond d_tol). The cut removes the block holding the second bolt's head,
/// and that bolt with it; the first, pretensioned to 50 kN, still holds, in tension.
/// This scene, written as a user would, found the glue's fault at seam ends (with the
/// settling as it was then, a sliver part's seam end went 2.8 mm deep unheld during the
/// quake, and the run stopped at 0.6 s on 6% of its reference energy created); the seam
/// test above checks that fault itself. Its settling converges: with its bedding
/// bonded (cohesion 20 kPa), a vertex at a junction of three blocks had its spring on in
/// one static step and off in the next, and the settling, taking that flicker for a
/// motion that never settled, stopped without converging after 215 static steps.
#[test]
fn a_pit_wall_with_bolts_a_toe_cut_and_a_quake_runs_under_the_guard() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/pit-wall.toml");
    let (_, model) = Scene::load(&path).unwrap();
    assert!(model.blocks.iter().any(|b| b.body.is_some()));
    let options = RunOptions {
        stop_on_violation: true,
        ..RunOptions::default()
    };
    let mut sim = Simulation::new(model, options);
    sim.run(|_, _| {}).unwrap_or_else(|e| panic!("{e}"));
    assert!(sim.finished());
    let settling = sim.settling().unwrap();
    assert!(settling.converged, "{settling:?}");
    assert!((0..sim.blocks().len()).any(|i| sim.is_removed(i)));
    assert_eq!(
        sim.bolt_tension(1),
        None,
        "the second bolt outlived its head"
    );
    let tension = sim.bolt_tension(0).unwrap();
    assert!(tension > 0.0, "the first bolt's tension {tension} N");
}

/// `tests/scenes/soft-layer.toml`: a soft jointed layer over hard jointed rock, settled,
/// takes its steps at the dt asked for: 50 steps of 1 ms, none cut, under the physics
/// guard. Settled, it moves little in a step (its contacts loaded, no block near d_max),
/// so only an open-close iteration that does not converge could cut a step. Before a
/// contact that kept turning its friction locked (`contact_law::FREEZE_LIMIT`) and an
/// attempt whose contacts with friction still changed could go past `max_oci`
/// (`open_close::OCI_GRACE`), it took 102 steps, 13 of them cut.
#[test]
fn a_soft_layer_on_hard_rock_keeps_its_time_step() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/scenes/soft-layer.toml");
    let (_, model) = Scene::load(&path).unwrap();
    let (dt0, duration) = (model.params.dt0, model.params.duration);
    let options = RunOptions {
        stop_on_violation: true,
        ..RunOptions::default()
    };
    let mut sim = Simulation::new(model, options);
    let mut cuts = 0;
    sim.run(|_, rec| cuts += rec.cuts)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(sim.finished());
    let steps = sim.totals().steps;
    assert_eq!(cuts, 0, "{steps} steps");
    assert_eq!(steps, (duration / dt0).round() as u64);
}

/// Every scene of `examples/` runs to its end as written, with the physics guard on: no
/// energy created beyond 1% of its reference, no penetration beyond d_tol.
#[test]
fn every_example_runs_to_its_end_under_the_guard() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for file in files {
        let (_, model) = Scene::load(&file).unwrap();
        let options = RunOptions {
            stop_on_violation: true,
            ..RunOptions::default()
        };
        let mut sim = Simulation::new(model, options);
        sim.run(|_, _| {})
            .unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        assert!(sim.finished());
    }
}

/// A rock mass cut by two persistent sets (60 m x 30 m, bedding at 15 degrees 2 m apart,
/// cross joints at 100 degrees 3 m apart, 345 blocks, in a fixed box) settles onto its
/// contacts before the run: the settling's first static step, cut to 4.6e-5 s where
/// the junctions' contacts would not converge, takes some 150 steps to grow to the
/// settling's own (0.0125 s), and a stall counted from the first step stopped it at 256
/// steps with the contacts a third loaded: the mass started the run falling at 0.64 g
/// (0.077 m/s at 0.01 s). Settled, its contacts carry its weight, and every block's speed
/// after 0.01 s stays below a hundredth of free fall's, g t.
#[test]
fn a_jointed_mass_settles_onto_its_contacts() {
    let sets = "[joint_sets.bed]\ndip_deg = 15.0\nspacing = 2.0\njoint = \"bed\"\n\
                [joint_sets.cross]\ndip_deg = 100.0\nspacing = 3.0\n";
    starts_at_rest(&boxed_mass(0.01, "", sets, 0.0, 60.0, 30.0), "cover");
}

/// A jointed rock mass in a fixed box (floor and sides 3 m thick) filling it from x0 to
/// x1 and up to h, cut by the joint sets `sets` ("bed", its joint at 28 degrees, and
/// "cross", at the default 35): E = 10 GPa, p = 2e10 N/m, plane strain, gravity, run for
/// `duration` s; `analysis` adds to the scene's analysis.
fn boxed_mass(duration: f64, analysis: &str, sets: &str, x0: f64, x1: f64, h: f64) -> String {
    let (a, b) = (x0 - 3.0, x1 + 3.0);
    format!(
        r#"
name = "jointed-mass"
[analysis]
duration = {duration}
time_step = 0.002
max_displacement = 0.005
normal_penalty = 2e10
gravity = [0.0, -9.81]
plane = "strain"
{analysis}
[materials.rock]
density = 2600.0
young = 10e9
poisson = 0.25
[joints.default]
friction_deg = 35.0
[joints.bed]
friction_deg = 28.0
{sets}
[[blocks]]
id = "floor"
material = "rock"
fixed = true
vertices = [[{a:?}, -3.0], [{b:?}, -3.0], [{b:?}, 0.0], [{a:?}, 0.0]]
[[blocks]]
id = "left"
material = "rock"
fixed = true
vertices = [[{a:?}, 0.0], [{x0:?}, 0.0], [{x0:?}, {h:?}], [{a:?}, {h:?}]]
[[blocks]]
id = "right"
material = "rock"
fixed = true
vertices = [[{x1:?}, 0.0], [{b:?}, 0.0], [{b:?}, {h:?}], [{x1:?}, {h:?}]]
[[regions]]
id = "mass"
material = "rock"
vertices = [[{x0:?}, 0.0], [{x1:?}, 0.0], [{x1:?}, {h:?}], [{x0:?}, {h:?}]]
joint_sets = ["bed", "cross"]
"#
    )
}

/// Runs scene `text` (`what` names it in messages): its settling converges, and every
/// block's speed at the end stays below a hundredth of free fall's, g t.
fn starts_at_rest(text: &str, what: &str) {
    let (_, model) = Scene::parse(text, Format::Toml, "jointed-mass.toml").unwrap();
    let mut sim = Simulation::new(model, RunOptions::default());
    sim.run(|_, _| {}).unwrap();
    let settling = sim.settling().unwrap();
    assert!(settling.converged, "{what}: {settling:?}");
    let fastest = sim
        .blocks()
        .iter()
        .map(|b| DVec2::new(b.velocity[0], b.velocity[1]).length())
        .fold(0.0, f64::max);
    let free_fall = 9.81 * sim.time();
    assert!(
        fastest < 1e-2 * free_fall,
        "{what}: fastest block {fastest} m/s after {} s",
        sim.time()
    );
}

/// Excavated rock takes its energy out of the system with it: the energy the physics
/// guard counts as supplied drops, at the step that lands on the excavation, by the
/// removed blocks' strain energy (their kinetic energy is nil in a static analysis),
/// besides the work gravity did in the step. The stressed mass of `tests/scenes/in-situ.toml`
/// loses its top row of blocks at 0.02 s. Left in the supply (until 2026-11-27), an
/// excavated block's strain energy, large under in-situ stress, let the rest of the run
/// create as much energy unseen. The strain energy is computed here from the removed
/// blocks' stresses under plane strain, A / 2 sigma . epsilon with
/// epsilon_x = (1 + nu) / E ((1 - nu) sigma_x - nu sigma_y), gamma = 2 (1 + nu) tau / E.
#[test]
fn excavated_rock_takes_its_energy_out_of_the_balance() {
    const SCENE: &str = include_str!("../scenes/in-situ.toml");
    let text = format!(
        "{SCENE}[[excavations]]\nid = \"top\"\nat = 0.02\n\
         vertices = [[0.0, 4.0], [2.0, 4.0], [2.0, 5.0], [0.0, 5.0]]\n"
    );
    let (_, model) = Scene::parse(&text, Format::Toml, "in-situ.toml").unwrap();
    let (e, nu, rho, g) = (1e10, 0.25, 2600.0, 9.81);
    let free: Vec<usize> = (0..model.blocks.len())
        .filter(|&i| !model.blocks[i].fixed)
        .collect();
    let top: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&i| model.blocks[i].polygon.centroid().y > 4.0)
        .collect();
    assert_eq!(top.len(), 2);
    let mut sim = Simulation::new(model, RunOptions::default());
    loop {
        let supplied = sim.energy_balance().supplied;
        let before: Vec<(DVec2, f64)> = free
            .iter()
            .map(|&i| {
                let p = &sim.blocks()[i].polygon;
                (p.centroid(), p.area())
            })
            .collect();
        sim.step().unwrap();
        if sim.time() < 0.02 - 1e-12 {
            continue;
        }
        // The work gravity did in the step: each block's weight along its centroid's path.
        let work: f64 = free
            .iter()
            .zip(&before)
            .map(|(&i, (c, a))| -rho * a * g * (sim.blocks()[i].polygon.centroid().y - c.y))
            .sum();
        let strain: f64 = top
            .iter()
            .map(|&i| {
                let b = &sim.blocks()[i];
                let [sx, sy, t] = b.stress;
                let ex = (1.0 + nu) / e * ((1.0 - nu) * sx - nu * sy);
                let ey = (1.0 + nu) / e * ((1.0 - nu) * sy - nu * sx);
                let gam = 2.0 * (1.0 + nu) * t / e;
                0.5 * b.polygon.area() * (sx * ex + sy * ey + t * gam)
            })
            .sum();
        let taken = supplied + work - sim.energy_balance().supplied;
        assert!(strain > 1e-3 * supplied, "strain {strain} of {supplied}");
        assert!(
            (taken - strain).abs() <= 1e-9 * supplied,
            "supply fell by {taken} J/m; the removed blocks held {strain} J/m"
        );
        break;
    }
}

/// A settling is judged against the motion the blocks' own forces give them, not against
/// a detector's first push. The conventional type-2 detector, in a jointed mass of 65
/// blocks (a bedding set and a non-persistent cross set), pushes a block with an edge of
/// 9 mm, in the floor's corner, 0.45 mm in the settling's first step of 5e-5 s (3e5
/// m/s^2, 3e4 times g). Measured against that first step (until
/// 2026-11-27), the settling called 0.1 g of change a step converged after 17 static
/// steps, and the run started with blocks at 8.4e-3 m/s after 0.02 s; the scale is now
/// at most ten times the largest motion the blocks' forces alone give them (g here),
/// and every block after 0.02 s stays below a hundredth of free fall's speed, as in
/// `a_jointed_mass_settles_onto_its_contacts`, with every detector.
#[test]
fn a_settling_is_judged_against_the_forces_not_a_detectors_first_push() {
    let sets = "[joint_sets.bed]\ndip_deg = 19.3\nspacing = 2.4\noffset = 0.74\n\
                joint = \"bed\"\n[joint_sets.cross]\ndip_deg = 133.0\nspacing = 2.83\n\
                offset = 0.03\ntrace_length = 5.8\nbridge = 1.5\nseed = 5\n";
    for detector in ["type-2", "type-1", "cover"] {
        let analysis = format!("detector = \"{detector}\"");
        starts_at_rest(
            &boxed_mass(0.02, &analysis, sets, 10.0, 30.0, 10.0),
            detector,
        );
    }
}

/// An excavation whose outline comes to a point 6 mm above a joint (a V-shaped notch)
/// cuts a sliver smaller than d_tol^2 (1e-4 m^2) off the block under its point, outside
/// it, glued to the rest of that block. Kept, such a sliver is below what contact
/// detection resolves: in an open pit of 750 blocks under the conventional type-1
/// detector, one of 7e-5 m^2 (cut in two by the next bench) flew off at 117 and 209 m/s.
/// The cutting drops it, with a warning that names the excavation, and keeps every part
/// larger; nothing else of the block outside the outline is lost, even where d_tol^2 is
/// larger than the block (a part goes only below a tenth of its block too). A sliver
/// that holds a measured point (or a bolt's end, a load, a fixed point) is kept, so
/// that the point still lies in rock.
#[test]
fn an_excavation_drops_the_slivers_its_outline_cuts_off() {
    let scene = |point: f64, measured: &str| {
        format!(
            r#"
name = "sliver-cut"
[analysis]
duration = 0.1
time_step = 0.002
max_displacement = 0.005
normal_penalty = 2e10
gravity = [0.0, -9.81]
[materials.rock]
density = 2600.0
young = 10e9
poisson = 0.25
[[blocks]]
id = "floor"
material = "rock"
fixed = true
vertices = [[-1.0, -1.0], [5.0, -1.0], [5.0, 0.0], [-1.0, 0.0]]
[[blocks]]
id = "low"
material = "rock"
vertices = [[0.0, 0.0], [4.0, 0.0], [4.0, 1.0], [0.0, 1.0]]
[[blocks]]
id = "high"
material = "rock"
vertices = [[0.0, 1.0], [4.0, 1.0], [4.0, 2.0], [0.0, 2.0]]
[[excavations]]
id = "notch"
at = 0.05
vertices = [[2.0, {point}], [3.0, 2.5], [1.0, 2.5]]
{measured}
"#
        )
    };
    let in_sliver = "[[measure]]\nid = \"under\"\nat = [2.0, 1.001]";
    let d_tol = 2.0 * 0.005;
    // The rock of `high` (4 m x 1 m from y = 1) outside the notch, whose point is at
    // (2, point) and which is 2 m wide at y = 2.5.
    let outside = |point: f64| 4.0 - (2.0 - point).powi(2) / (2.5 - point);
    let (_, kept) =
        Scene::parse(&scene(1.006, in_sliver), Format::Toml, "sliver-cut.toml").unwrap();
    assert!(kept.warnings.is_empty(), "{:?}", kept.warnings);
    assert!(
        kept.blocks.iter().any(|b| b.polygon.area() < d_tol * d_tol),
        "the sliver holding the measured point was dropped"
    );
    // With a d_tol of 5 m (d_tol^2 = 25 m^2, more than the whole 4 m^2 block), only the
    // sliver goes: a part is dropped only below a tenth of its block as well.
    let coarse = scene(1.006, "").replace(
        "max_displacement = 0.005",
        "max_displacement = 0.005\ncontact_tolerance = 5.0",
    );
    let (_, model) = Scene::parse(&coarse, Format::Toml, "sliver-cut.toml").unwrap();
    let left: f64 = model
        .blocks
        .iter()
        .filter(|b| b.id.starts_with("high.") && b.removed_at.is_none())
        .map(|b| b.polygon.area())
        .sum();
    let lost = outside(1.006) - left;
    assert!(
        lost > 0.0 && lost < d_tol * d_tol,
        "coarse d_tol: {lost} m^2 lost"
    );
    for (point, sliver) in [(1.006, true), (1.5, false)] {
        let (_, model) = Scene::parse(&scene(point, ""), Format::Toml, "sliver-cut.toml").unwrap();
        let high: Vec<_> = model
            .blocks
            .iter()
            .filter(|b| b.id.starts_with("high."))
            .collect();
        assert!(
            high.iter().all(|b| b.polygon.area() >= d_tol * d_tol),
            "point at {point}: {:?}",
            high.iter().map(|b| b.polygon.area()).collect::<Vec<_>>()
        );
        let warned = model
            .warnings
            .iter()
            .any(|w| w.key == "excavations[0].vertices" && w.message.contains("dropped"));
        assert_eq!(warned, sliver, "point at {point}: {:?}", model.warnings);
        let kept: f64 = high
            .iter()
            .filter(|b| b.removed_at.is_none())
            .map(|b| b.polygon.area())
            .sum();
        let lost = outside(point) - kept;
        if sliver {
            assert!(
                lost > 0.0 && lost < d_tol * d_tol,
                "point at {point}: {lost}"
            );
        } else {
            assert!(lost.abs() < 1e-12, "point at {point}: {lost}");
        }
    }
}

/// `tests/scenes/wedge-over-void.toml`: a sliver wedge (`mass.40`) in a V that closes
/// downwards at 3.5 degrees, friction 35, above a void its region's `min_area` left. A
/// wedge whose faces close at less than its friction angle wedges and stands. Sliding,
/// its friction forces, each taken from the normal force of the trial before, swung
/// from trial to trial with growing amplitude (a wedge turns a small change of friction
/// into a large one of normal force), so that the open-close iteration ran to its bound
/// and ended each step with the contacts at the wedge's foot sliding on no normal force:
/// the wedge crept down at 8e-5 m/s, ten iterations a step (cover). Type-2 held it
/// against another corner, where its contacts locked at the reversals the swing made
/// and slid again, six to ten iterations a step (docs/method.md section 6, regula
/// falsi). At rest, a step's first trial changes nothing: over the run's second half
/// every step takes one iteration, and the wedge moves more slowly than the contact law
/// lets a block at rest move, a thousandth of its weight (its force scale: the normal
/// forces on it are below its weight) acting for the longest step,
/// DECISION_BAND g dt = 2e-5 m/s.
#[test]
fn a_wedge_above_a_void_wedges_and_stands() {
    const SCENE: &str = include_str!("../scenes/wedge-over-void.toml");
    let (dt, half) = (0.002, 0.25);
    let at_rest = 1e-3 * 9.81 * dt;
    for detector in ["cover", "type-1", "type-2"] {
        let text = SCENE.replacen(
            "[analysis]",
            &format!("[analysis]\ndetector = \"{detector}\""),
            1,
        );
        let (_, model) = Scene::parse(&text, Format::Toml, "wedge-over-void.toml").unwrap();
        let wedge = model.blocks.iter().position(|b| b.id == "mass.40").unwrap();
        let mut sim = Simulation::new(model, RunOptions::default());
        let (mut steps, mut iterations) = (0, 0);
        while !sim.finished() {
            let r = sim.step().unwrap();
            if r.t > half {
                steps += 1;
                iterations += r.oci;
            }
        }
        let v = sim.blocks()[wedge].velocity;
        let speed = v[0].hypot(v[1]);
        assert!(speed < at_rest, "{detector}: the wedge at {speed} m/s");
        assert_eq!(
            iterations, steps,
            "{detector}: iterations of the last steps"
        );
    }
}
