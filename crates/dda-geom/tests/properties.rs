//! Property tests of the geometry layer over random convex polygons, slivers (angles down to
//! 1 degree) and chamfered corners (edges down to 1e-4 of the diameter), given clockwise and
//! counter-clockwise: distances against parry2d-f64 and an independent separating-axis
//! computation, entrance-block size and area, cutting, moments and motion.

use dda_geom::{
    ConvexPolygon, DVec2, EntranceBlock, JointSet, PolygonOptions, cut_by_joint_sets,
    signed_distance,
};
use parry2d_f64::math::Pose;
use parry2d_f64::query;
use parry2d_f64::shape::ConvexPolygon as ParryPolygon;
use proptest::prelude::*;
use std::f64::consts::PI;

use dda_geom::test_support as polygons;
use polygons::{near_pair, polygon_at};

const EPS: f64 = f64::EPSILON;

fn to_parry(p: &ConvexPolygon) -> ParryPolygon {
    ParryPolygon::from_convex_polyline_unmodified(p.vertices().to_vec())
        .expect("a valid polygon is a valid parry polygon")
}

/// Penetration depth by the separating-axis theorem: the smallest overlap of the two
/// polygons' projections over all edge normals of both (exact for convex polygons in 2D).
fn sat_depth(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    let proj = |p: &ConvexPolygon, n: DVec2| {
        p.vertices()
            .iter()
            .map(|v| v.dot(n))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            })
    };
    a.normals()
        .into_iter()
        .chain(b.normals())
        .map(|n| {
            let (alo, ahi) = proj(a, n);
            let (blo, bhi) = proj(b, n);
            (ahi - blo).min(bhi - alo)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Mixed area V(A, -B) = 1/2 sum over edges e of -B of h_A(u_e) |e|, with h_A the support
/// function of A (Minkowski's formula), computed without any entrance block.
fn mixed_area_a_minus_b(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    let support = |n: DVec2| {
        a.vertices()
            .iter()
            .map(|v| v.dot(n))
            .fold(f64::NEG_INFINITY, f64::max)
    };
    (0..b.len())
        .map(|j| {
            let (p, q) = b.edge(j);
            // The edge of -B from -p to -q has outward normal -n_j.
            0.5 * support(-b.normal(j)) * p.distance(q)
        })
        .sum()
}

/// Size of the configuration: the largest coordinate magnitude, to scale absolute bounds.
fn extent(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    a.vertices()
        .iter()
        .chain(b.vertices())
        .map(|v| v.abs().max_element())
        .fold(1.0, f64::max)
}

proptest! {
    #![proptest_config(polygons::config(512))]

    /// Distance agrees with parry2d-f64 (GJK) and penetration depth with the separating-axis
    /// computation (exact for convex polygons), to 1e-9 relative, 1e-12 absolute. parry's
    /// depth comes from EPA, which grows a polygon inside the Minkowski difference: the
    /// distance to its nearest face is a lower bound on the depth, reached only if EPA runs
    /// to the end. On a 1-degree sliver it can stop early (saved case b311ba3d: parry
    /// 0.193, SAT and ours 0.326), so parry's depth is checked as that bound.
    #[test]
    fn signed_distance_matches_parry((a, b) in near_pair()) {
        let ours = signed_distance(&a, &b).distance;
        // The materialised entrance block gives the same answer.
        let e = EntranceBlock::new(&a, &b, DVec2::ZERO).signed_distance().distance;
        prop_assert!((e - ours).abs() <= 1e-12 * extent(&a, &b));
        let id = Pose::identity();
        let (pa, pb) = (to_parry(&a), to_parry(&b));
        let tol = |x: f64| 1e-9 * x.abs() + 1e-12 * extent(&a, &b);
        let gap = query::distance(&id, &pa, &id, &pb).expect("supported").distance;
        if ours > 0.0 {
            prop_assert!((ours - gap).abs() <= tol(gap), "gap: ours {ours} parry {gap}");
        } else {
            prop_assert!(gap <= tol(0.0), "overlap but parry gap {gap}");
            let depth = sat_depth(&a, &b);
            prop_assert!((ours + depth).abs() <= tol(depth), "depth: ours {ours} SAT {depth}");
            let contact = query::contact(&id, &pa, &id, &pb, 0.0)
                .expect("supported")
                .expect("overlapping shapes are in contact");
            prop_assert!(-contact.dist <= depth + tol(depth),
                "depth: ours {ours} parry {} beyond SAT", contact.dist);
        }
    }

    /// The entrance block has exactly n + m faces (at most n + m, as required) and area
    /// |A| + |B| + 2 V(A, -B).
    #[test]
    fn entrance_block_size_and_area((a, b) in near_pair()) {
        let e = EntranceBlock::new(&a, &b, DVec2::new(0.3, -0.7));
        prop_assert_eq!(e.faces().len(), a.len() + b.len());
        let expected = a.area() + b.area() + 2.0 * mixed_area_a_minus_b(&a, &b);
        // Each of k shoelace terms has rounding at most ~4 eps |p||q| with |p|,|q| <= R,
        // the size of E; the mixed-area sum the same. So the bound is 8 k eps R^2.
        let r = e.vertices().iter().map(|v| v.distance(e.faces()[0].start)).fold(0.0, f64::max);
        let k = (a.len() + b.len()) as f64;
        prop_assert!((e.area() - expected).abs() <= 8.0 * k * EPS * r * r * 4.0,
            "area {} expected {}", e.area(), expected);
    }

    /// Clockwise input gives the same polygon (up to the starting vertex) and bit-identical
    /// distances: the merge starts from the lowest vertices whatever the input order.
    #[test]
    fn clockwise_input_is_the_same_polygon((a, cw) in polygon_at(DVec2::ZERO), (b, _) in polygon_at(DVec2::new(1.0, 0.5))) {
        let mut rev = a.vertices().to_vec();
        rev.reverse();
        let (a2, repairs) = ConvexPolygon::with_options(rev, &PolygonOptions::default()).expect("valid");
        prop_assert!(repairs.reversed);
        prop_assert_eq!(a2.len(), a.len());
        prop_assert_eq!(signed_distance(&a2, &b), signed_distance(&a, &b));
        let _ = cw;
    }

    /// Moments agree with an independent fan triangulation about the vertex mean.
    #[test]
    fn moments_match_triangulation((p, _) in polygon_at(DVec2::new(3.0, -2.0))) {
        let m = p.moments();
        let v = p.vertices();
        let o = v.iter().copied().sum::<DVec2>() / v.len() as f64;
        let mut tris = Vec::new();
        for i in 0..v.len() {
            let (q, r) = (v[i], v[(i + 1) % v.len()]);
            let area = 0.5 * (q - o).perp_dot(r - o);
            let c = (o + q + r) / 3.0;
            // Second moments of a triangle about its own centroid: A/12 * sum of squares of
            // the vertex offsets from the centroid.
            let offs = [o - c, q - c, r - c];
            let sxx = area / 12.0 * offs.iter().map(|d| d.x * d.x).sum::<f64>();
            let syy = area / 12.0 * offs.iter().map(|d| d.y * d.y).sum::<f64>();
            let sxy = area / 12.0 * offs.iter().map(|d| d.x * d.y).sum::<f64>();
            tris.push((area, c, sxx, syy, sxy));
        }
        let area: f64 = tris.iter().map(|t| t.0).sum();
        let c = tris.iter().map(|t| t.1 * t.0).sum::<DVec2>() / area;
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for (a, tc, txx, tyy, txy) in &tris {
            let d = *tc - c;
            sxx += txx + a * d.x * d.x;
            syy += tyy + a * d.y * d.y;
            sxy += txy + a * d.x * d.y;
        }
        // Sums of n positive terms, each with a few roundings: relative error below
        // ~32 n eps of the polar moment J (which also bounds |Sxy|).
        let j = m.sxx + m.syy;
        let tol = 32.0 * v.len() as f64 * EPS;
        prop_assert!((m.area - area).abs() <= tol * area);
        prop_assert!((m.centroid - c).length() <= tol * p.diameter());
        prop_assert!((m.sxx - sxx).abs() <= tol * j, "sxx {} vs {}", m.sxx, sxx);
        prop_assert!((m.syy - syy).abs() <= tol * j, "syy {} vs {}", m.syy, syy);
        prop_assert!((m.sxy - sxy).abs() <= tol * j, "sxy {} vs {}", m.sxy, sxy);
    }

    /// Cutting by one or two joint sets preserves the total area (kept plus dropped) to
    /// 1e-12 relative; every piece re-validates strictly and no two pieces overlap.
    #[test]
    fn cutting_preserves_area(
        (p, _) in polygon_at(DVec2::ZERO),
        dips in prop::collection::vec(-90.0f64..90.0, 1..=2),
        spacing in 0.05f64..0.6,
        offset in 0.0f64..1.0,
    ) {
        let sets: Vec<JointSet> = dips
            .iter()
            .map(|&dip_deg| JointSet { dip_deg, spacing: spacing * p.diameter(), offset })
            .collect();
        let min_area = 1e-6 * p.area();
        let cut = cut_by_joint_sets(&p, &sets, min_area).expect("valid joint sets");
        let total: f64 = cut.blocks.iter().map(ConvexPolygon::area).sum::<f64>() + cut.dropped_area;
        prop_assert!((total - p.area()).abs() <= 1e-12 * p.area(), "area {} of {}", total, p.area());
        let scale = p.diameter();
        for (i, b) in cut.blocks.iter().enumerate() {
            let (again, repairs) = ConvexPolygon::with_options(b.vertices().to_vec(), &PolygonOptions::strict())
                .expect("piece re-validates strictly");
            prop_assert!(repairs.is_empty());
            prop_assert_eq!(&again, b);
            prop_assert!(b.area() >= min_area);
            for other in &cut.blocks[i + 1..] {
                let d = signed_distance(b, other).distance;
                prop_assert!(d >= -1e-9 * scale, "pieces overlap by {}", -d);
            }
        }
    }

    /// The DDA motion with exact rotation scales area by det(R + E) and moves the centroid
    /// by (u0, v0); a pure rotation keeps every edge length.
    #[test]
    fn displacement_is_affine((p, _) in polygon_at(DVec2::new(1.0, 2.0)),
        u in -1.0f64..1.0, v in -1.0f64..1.0, r in -PI..PI,
        ex in -0.01f64..0.01, ey in -0.01f64..0.01, g in -0.01f64..0.01) {
        let c = p.centroid();
        let q = p.displaced(c, &[u, v, r, ex, ey, g]).expect("small strain keeps orientation");
        let (s, co) = r.sin_cos();
        let det = (co + ex) * (co + ey) - (-s + 0.5 * g) * (s + 0.5 * g);
        let tol = 64.0 * p.len() as f64 * EPS;
        // Each moved vertex carries a rounding error of a few eps times its coordinates'
        // size, |c| + |(u, v)| + diameter <= |c| + 2 + diameter, and moving n vertices by
        // delta changes the area by at most n delta diameter: an absolute error that a
        // sliver (area far below diameter^2) does not scale down. Bound: 8 n eps diameter
        // (|c| + 2 + diameter), plus the relative error of the two areas' sums.
        let diameter = p.diameter();
        let moved = 8.0 * p.len() as f64 * EPS * diameter * (c.length() + 2.0 + diameter);
        prop_assert!((q.area() - det * p.area()).abs() <= tol * p.area() + moved,
            "area {} against {}", q.area(), det * p.area());
        prop_assert!((q.centroid() - (c + DVec2::new(u, v))).length() <= tol * (1.0 + p.diameter() + c.length()));
        let rigid = p.displaced(c, &[u, v, r, 0.0, 0.0, 0.0]).expect("rotation");
        for i in 0..p.len() {
            let (a0, a1) = p.edge(i);
            let (b0, b1) = rigid.edge(i);
            prop_assert!((a0.distance(a1) - b0.distance(b1)).abs() <= 16.0 * EPS * (p.diameter() + c.length()));
        }
    }

    /// Every point `contains_within` accepts lies in `reach_bounds`: points along each
    /// corner's bisector up to and past its mitre point (eps / sin(a / 2) out, where the
    /// moved lines meet, the farthest an accepted point reaches) and along each moved
    /// edge line, and the box is no larger than the polygon's grown by the longest
    /// mitre of its reach and a hundredth (so that an unbounded box fails).
    #[test]
    fn the_reach_bounds_hold_every_point_the_reach_accepts(
        (p, _) in polygon_at(DVec2::new(-7.0, 40.0)),
        log_eps in -9.0f64..-1.0,
        ts in prop::collection::vec(0.0f64..1.0, 8),
    ) {
        let eps = 10f64.powf(log_eps) * p.diameter();
        let bounds = p.reach_bounds(eps);
        let n = p.len();
        let mut longest: f64 = 0.0;
        for (i, angle) in p.interior_angles().into_iter().enumerate() {
            let (n0, n1) = (p.normal(i + n - 1), p.normal(i));
            let bisector = (n0 + n1).normalize();
            let mitre = eps / (0.5 * angle).sin();
            longest = longest.max(mitre);
            let v = p.vertex(i);
            let along = p.vertex(i + 1) - v;
            let points = [0.5, 0.999_999, 1.0, 1.000_001, 1.5]
                .into_iter()
                .map(|t| v + bisector * (t * mitre))
                .chain(ts.iter().map(|&t| v + n1 * eps + along * t));
            for q in points {
                if p.contains_within(q, eps) {
                    prop_assert!(bounds.contains(q), "{:?} accepted outside {:?}", q, bounds);
                }
            }
        }
        // The reach the bounds are taken for: eps with room for the test's rounding.
        let size = p.aabb().size();
        let reach = eps * (1.0 + 1e-6) + 1e-9 * size.x.max(size.y);
        let grown = p.aabb().expanded(1.01 * longest * reach / eps);
        prop_assert!(
            grown.min.x <= bounds.min.x && grown.min.y <= bounds.min.y
                && bounds.max.x <= grown.max.x && bounds.max.y <= grown.max.y,
            "{:?} beyond {:?}", bounds, grown
        );
    }
}
