//! Property tests of rock-mass cutting (`dda_geom::cut_mass`) over random outlines, convex
//! and not (3 to 40 vertices), cut by 1 to 3 joint families, persistent and not, regular
//! and statistical: the pieces tile the outline, no two parts overlap (parry2d's contact
//! as the oracle), every part is a strictly valid convex polygon, and the glued parts of
//! each piece are connected through intact rock while parts of different pieces meet only
//! along joint traces.

use dda_geom::{
    Aabb, ConvexPolygon, DVec2, Joint, JointFamily, JointSet, Outline, PolygonOptions, cut_mass,
};
use parry2d_f64::math::Pose;
use parry2d_f64::query;
use parry2d_f64::shape::ConvexPolygon as ParryPolygon;
use proptest::prelude::*;
use std::f64::consts::TAU;

use dda_geom::test_support as polygons;

/// A star-shaped outline of `n` vertices about the origin, radius 5 to 10 (non-convex
/// wherever the radii dip), or convex when `convex`.
fn outline() -> impl Strategy<Value = Outline> {
    (
        3usize..=40,
        any::<bool>(),
        prop::collection::vec(0.0f64..1.0, 40),
        prop::collection::vec(0.5f64..=1.0, 40),
    )
        .prop_filter_map("not a valid outline", |(n, convex, jitter, radii)| {
            let step = TAU / n as f64;
            let pts: Vec<DVec2> = (0..n)
                .map(|i| {
                    let t = step * (i as f64 + 0.8 * jitter[i]);
                    let r = if convex { 10.0 } else { 10.0 * radii[i] };
                    r * DVec2::from_angle(t)
                })
                .collect();
            Outline::new(pts).ok()
        })
}

/// A joint family: dip, spacing 1 to 6 m, and with even odds each of: spacing varying,
/// dips spread, traces of 2 to 10 m with bridges of 0.5 to 5 m.
fn family() -> impl Strategy<Value = JointFamily> {
    (
        -90.0f64..90.0,
        1.0f64..6.0,
        0.0f64..1.0,
        prop::option::of(0.05f64..0.5),
        prop::option::of(1.0f64..15.0),
        prop::option::of((2.0f64..10.0, 0.5f64..5.0)),
        any::<u64>(),
    )
        .prop_map(
            |(dip_deg, spacing, offset, cv, spread, trace, seed)| JointFamily {
                set: JointSet {
                    dip_deg,
                    spacing,
                    offset,
                },
                spacing_cv: cv.unwrap_or(0.0),
                dip_spread_deg: spread.unwrap_or(0.0),
                trace,
                trace_origin: DVec2::ZERO,
                seed,
            },
        )
}

fn to_parry(p: &ConvexPolygon) -> ParryPolygon {
    ParryPolygon::from_convex_polyline_unmodified(p.vertices().to_vec())
        .expect("a valid polygon is a valid parry polygon")
}

/// The stretch (of more than `eps`) along which edges of `a` and `b` run against each
/// other, if any.
fn shared(a: &ConvexPolygon, b: &ConvexPolygon, eps: f64) -> Option<(DVec2, DVec2)> {
    for (p0, p1) in a.edges() {
        let dir = (p1 - p0).normalize();
        for (q0, q1) in b.edges() {
            let off = |q: DVec2| (dir.x * (q - p0).y - dir.y * (q - p0).x).abs();
            if off(q0) > eps || off(q1) > eps || dir.dot(q1 - q0) >= 0.0 {
                continue;
            }
            let lo = dir.dot(q1 - p0).max(0.0);
            let hi = dir.dot(q0 - p0).min(dir.dot(p1 - p0));
            if hi - lo > eps {
                return Some((p0 + lo * dir, p0 + hi * dir));
            }
        }
    }
    None
}

/// Whether the stretch a-b lies on a trace of one of the joints (measured here, from the
/// joints' definition).
fn on_trace(a: DVec2, b: DVec2, joints: &[Joint], eps: f64) -> bool {
    joints.iter().any(|j| {
        let n = j.line.normal;
        let on_line =
            (n.dot(a) - j.line.offset).abs() <= eps && (n.dot(b) - j.line.offset).abs() <= eps;
        let t = j.direction().dot(0.5 * (a + b));
        on_line
            && j.traces
                .as_ref()
                .is_none_or(|tr| tr.iter().any(|&[lo, hi]| lo <= t && t <= hi))
    })
}

proptest! {
    #![proptest_config(polygons::config(200))]

    #[test]
    fn pieces_tile_the_outline_and_glue_only_intact_rock(
        outline in outline(),
        families in prop::collection::vec(family(), 1..=3),
    ) {
        let bounds: Aabb = outline.aabb();
        let mut joints = Vec::new();
        for (k, f) in families.iter().enumerate() {
            joints.extend(f.joints(k, &bounds, 10_000).expect("joints"));
        }
        let area = outline.area();
        let min_area = 1e-6 * area;
        let cut = cut_mass(&outline, &joints, min_area).expect("cut");
        let total: f64 = cut.pieces.iter().map(|p| p.area()).sum::<f64>() + cut.dropped_area;
        prop_assert!((total - area).abs() <= 1e-12 * area, "area {} of {}", total, area);
        let size = bounds.size().length();
        let eps = 1e-9 * size;
        let parts: Vec<(usize, &ConvexPolygon)> = cut
            .pieces
            .iter()
            .enumerate()
            .flat_map(|(k, p)| p.parts.iter().map(move |q| (k, q)))
            .collect();
        for (piece, p) in &cut.pieces.iter().enumerate().collect::<Vec<_>>() {
            prop_assert!(p.area() >= min_area);
            prop_assert_eq!(p.parts.len(), p.edge_sets.len());
            for (q, sets) in p.parts.iter().zip(&p.edge_sets) {
                prop_assert_eq!(q.len(), sets.len());
                let (again, repairs) =
                    ConvexPolygon::with_options(q.vertices().to_vec(), &PolygonOptions::strict())
                        .expect("a part re-validates strictly: convex, counter-clockwise");
                prop_assert!(repairs.is_empty());
                prop_assert_eq!(&again, q);
            }
            // The parts of one piece are connected through shared stretches of intact rock.
            let n = p.parts.len();
            let mut reached = vec![false; n];
            reached[0] = true;
            let mut stack = vec![0];
            while let Some(i) = stack.pop() {
                let next: Vec<usize> = (0..n)
                    .filter(|&j| {
                        !reached[j]
                            && shared(&p.parts[i], &p.parts[j], eps)
                                .is_some_and(|(a, b)| !on_trace(a, b, &joints, eps))
                    })
                    .collect();
                for j in next {
                    reached[j] = true;
                    stack.push(j);
                }
            }
            prop_assert!(reached.iter().all(|&r| r), "piece {} is not connected", piece);
        }
        let id = Pose::identity();
        for (i, (pa, a)) in parts.iter().enumerate() {
            for (pb, b) in &parts[i + 1..] {
                let gap = query::contact(&id, &to_parry(a), &id, &to_parry(b), 0.0)
                    .expect("supported")
                    .map_or(f64::INFINITY, |c| c.dist);
                prop_assert!(gap >= -eps, "parts overlap by {}", -gap);
                if pa != pb && let Some((x, y)) = shared(a, b, eps) {
                    prop_assert!(on_trace(x, y, &joints, eps),
                        "pieces {} and {} meet on intact rock at {:?}-{:?}", pa, pb, x, y);
                }
            }
        }
    }
}
