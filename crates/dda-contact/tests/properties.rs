//! Property tests of the contact layer: the cover detector against the geometry layer's
//! signed distance, activity when blocks overlap, swap symmetry for every detector,
//! slivers without NaN or panic, neighbour search against brute force, parallel
//! detection identical to sequential, and trajectory tracking through a step's
//! [`TrackList`] identical to a scan of every candidate.

use dda_contact::{
    BlockShape, Contact, ContactDetector, ContactKey, ContactSet, ContactState, CoverDetector,
    DetectionParams, NeighbourPair, TrackList, detect, detector_by_name, neighbour_pairs,
};
use dda_geom::{Aabb, ConvexPolygon, CoverSource, DVec2, Motion, VertexEdge, signed_distance};
use proptest::prelude::*;

use dda_geom::test_support as polygons;
use polygons::near_pair;

const IDS: NeighbourPair = NeighbourPair { a: 0, b: 1 };

/// A pair of polygons moved so that their signed distance is near `frac` times d_tol,
/// with d_tol = 5% of A's diameter; returns the shapes, the tolerances and the distance.
fn pair_within_tolerance() -> impl Strategy<Value = (ConvexPolygon, ConvexPolygon, DetectionParams)>
{
    (near_pair(), -0.9f64..0.9, 0.5f64..4.0).prop_map(|((a, b), frac, theta_deg)| {
        let d_tol = 0.05 * a.diameter();
        let params = DetectionParams::new(d_tol, theta_deg.to_radians());
        let s = signed_distance(&a, &b);
        // Moving B against the nearest face's normal of E changes the distance by the
        // same amount while the nearest feature stays.
        let n = match s.source {
            CoverSource::VertexEdge { edge, .. } => -b.normal(edge),
            CoverSource::EdgeVertex { edge, .. } => a.normal(edge),
        };
        let b = b.translated(n * (frac * d_tol - s.distance));
        (a, b, params)
    })
}

fn detect_one(
    name: &str,
    a: &ConvexPolygon,
    b: &ConvexPolygon,
    params: &DetectionParams,
) -> Vec<Contact> {
    let det = detector_by_name(name).expect("built-in detector");
    let shapes = [BlockShape::new(a), BlockShape::new(b)];
    let mut out = Vec::new();
    det.detect_pair(&shapes[0], &shapes[1], IDS, params, &mut out);
    out.sort_by_key(|c| c.key);
    out
}

fn mirror(k: ContactKey) -> ContactKey {
    ContactKey {
        vertex_block: 1 - k.vertex_block,
        vertex: k.vertex,
        edge_block: 1 - k.edge_block,
        edge: k.edge,
    }
}

proptest! {
    #![proptest_config(polygons::config(512))]

    /// d_RE2 (eq. 11) is the signed distance whenever the blocks overlap or the nearest
    /// feature pair is a vertex-edge pair (its foot inside the edge); it is never above it
    /// (each face's line is no farther than the entrance block itself).
    #[test]
    fn d_re2_is_the_signed_distance((a, b, params) in pair_within_tolerance()) {
        let s = signed_distance(&a, &b);
        prop_assume!(s.distance.abs() <= params.d_tol);
        let shapes = [BlockShape::new(&a), BlockShape::new(&b)];
        let mut covers = Vec::new();
        let d_re2 = CoverDetector.cover_list(&shapes[0], &shapes[1], IDS, &params, &mut covers);
        let d_re2 = d_re2.expect("the nearest face is within d_tol, so C^L is not empty");
        // The nearest face's measures: a vertex-edge pair if its foot lies inside the edge.
        let (v, (e0, e1)) = match s.source {
            CoverSource::VertexEdge { vertex, edge } => (a.vertex(vertex), b.edge(edge)),
            CoverSource::EdgeVertex { edge, vertex } => (b.vertex(vertex), a.edge(edge)),
        };
        let m = VertexEdge::new(v, e0, e1);
        let scale = 1e-12 * (1.0 + a.diameter() + b.diameter() + b.centroid().length());
        prop_assert!(d_re2 <= s.distance + scale, "d_RE2 {} above {}", d_re2, s.distance);
        if s.distance <= 0.0 || (0.0..=1.0).contains(&m.r) {
            prop_assert!((d_re2 - s.distance).abs() <= scale, "d_RE2 {} vs {}", d_re2, s.distance);
        }
    }

    /// Overlapping blocks (depth within d_tol) always have an active cover.
    #[test]
    fn overlap_has_an_active_cover((a, b, params) in pair_within_tolerance()) {
        let s = signed_distance(&a, &b);
        prop_assume!(s.distance < 0.0 && s.distance >= -params.d_tol);
        let covers = detect_one("cover", &a, &b, &params);
        prop_assert!(covers.iter().any(|c| c.active), "{} covers, none active", covers.len());
    }

    /// Swapping A and B gives the same contacts, mirrored, for every detector, bit for bit;
    /// nothing is NaN.
    #[test]
    fn swap_symmetry((a, b, params) in pair_within_tolerance()) {
        for name in ["cover", "type-1", "type-2"] {
            let ab = detect_one(name, &a, &b, &params);
            let mut ba: Vec<Contact> = detect_one(name, &b, &a, &params)
                .into_iter()
                .map(|c| Contact { key: mirror(c.key), ..c })
                .collect();
            ba.sort_by_key(|c| c.key);
            prop_assert_eq!(&ab, &ba, "detector {}", name);
            for c in &ab {
                prop_assert!(c.d_n.is_finite() && c.r.is_finite());
            }
        }
    }

}

proptest! {
    // Each case is a brute-force O(N^2) reference over up to 5,000 boxes: fewer cases.
    #![proptest_config(polygons::config(48))]

    /// Neighbour search finds exactly the brute-force pairs on random scenes of boxes.
    #[test]
    fn neighbour_search_is_brute_force(
        n in 2usize..=5000,
        seed in any::<u64>(),
        gap in 0.0f64..0.05,
        tall in any::<bool>(),
    ) {
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (w, h) = if tall { (1.0, 10.0) } else { (10.0, 1.0) };
        let side = (w * h / n as f64).sqrt();
        let boxes: Vec<Aabb> = (0..n)
            .map(|_| {
                let min = DVec2::new(next() * w, next() * h);
                Aabb { min, max: min + DVec2::new(next() * side, next() * side) }
            })
            .collect();
        let mut fast = Vec::new();
        neighbour_pairs(&boxes, gap, &mut fast);
        let mut brute = Vec::new();
        for i in 0..n {
            for j in i + 1..n {
                if boxes[i].expanded(0.5 * gap).overlaps(&boxes[j].expanded(0.5 * gap)) {
                    brute.push(NeighbourPair::new(i as u32, j as u32));
                }
            }
        }
        prop_assert_eq!(fast, brute);
    }
}

#[test]
fn cover_detector_is_object_safe_and_named() {
    let boxed: Box<dyn dda_contact::ContactDetector> = Box::new(CoverDetector);
    assert_eq!(boxed.name(), "cover");
    assert_eq!(
        detector_by_name("type-2").map(|d| d.name().to_string()),
        Ok("type-2".to_string())
    );
    assert!(detector_by_name("type-3").is_err());
}

/// The blocks of a 10 m x 20 m region cut by two joint sets (60 and 15 degrees).
fn jointed_column() -> Vec<BlockShape> {
    let region =
        dda_geom::shapes::rectangle(DVec2::ZERO, DVec2::new(10.0, 20.0)).expect("rectangle");
    let sets = [
        dda_geom::JointSet {
            dip_deg: 60.0,
            spacing: 0.48,
            offset: 0.13,
        },
        dda_geom::JointSet {
            dip_deg: 15.0,
            spacing: 0.4,
            offset: 0.07,
        },
    ];
    let cut = dda_geom::cut_by_joint_sets(&region, &sets, 1e-4).expect("cut");
    cut.blocks.iter().map(BlockShape::new).collect()
}

/// Trajectory tracking as paper 2.3.2 states it, by a scan of every candidate: an
/// inactive one whose vertex was outside its edge's line at step start and is behind it
/// in the trial becomes active, locked where it crossed, if the detector says so.
fn track_by_scan(
    det: &dyn ContactDetector,
    shapes: &[BlockShape],
    trial: &[Motion],
    set: &mut ContactSet,
) -> usize {
    let mut changed = 0;
    for c in set.contacts.iter_mut() {
        if c.active || c.d_n <= 0.0 {
            continue;
        }
        let k = c.key;
        let (vs, es) = (
            &shapes[k.vertex_block as usize],
            &shapes[k.edge_block as usize],
        );
        let (mv, me) = (
            &trial[k.vertex_block as usize],
            &trial[k.edge_block as usize],
        );
        let j = k.edge as usize;
        let a1 = mv.apply(vs.vertices[k.vertex as usize]);
        let (b0, b1) = (me.apply(es.vertices[j]), me.apply(es.vertices[es.next(j)]));
        let (e, w) = (b1 - b0, a1 - b0);
        if w.x * e.y - w.y * e.x >= 0.0 {
            continue;
        }
        let m = VertexEdge::new(a1, b0, b1);
        if det.activates(VertexEdge { d_n: c.d_n, r: c.r }, m) {
            let t = c.d_n / (c.d_n - m.d_n);
            c.active = true;
            c.state = ContactState::Locked;
            c.locked_r = (c.r + t * (m.r - c.r)).clamp(0.0, 1.0);
            changed += 1;
        }
    }
    changed
}

proptest! {
    #![proptest_config(polygons::config(24))]

    /// Over two open-close iterations with random block motions (the second after the
    /// first one's activations), tracking through the list made at step start activates
    /// exactly what a scan of every candidate does, with the same locked points, and
    /// lists the candidates it made active.
    #[test]
    fn track_list_is_a_scan_of_every_candidate(seed in any::<u64>()) {
        let shapes = jointed_column();
        let boxes: Vec<Aabb> = shapes.iter().map(|s| s.aabb).collect();
        let params = DetectionParams::new(0.05, 2f64.to_radians());
        let mut pairs = Vec::new();
        neighbour_pairs(&boxes, params.d_tol, &mut pairs);
        let mut set = ContactSet::default();
        detect(&CoverDetector, &shapes, &pairs, &params, &ContactSet::default(), false, &mut set);
        let mut list = TrackList::new();
        list.rebuild(&CoverDetector, &shapes, &set);
        let mut by_scan = set.clone();
        // Motions of up to d_tol and 0.02 rad, from a xorshift stream.
        let mut x = seed | 1;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut activated = 0;
        for _ in 0..2 {
            let trial: Vec<Motion> = shapes
                .iter()
                .map(|s| {
                    let d = [0.05 * next(), 0.05 * next(), 0.02 * next(), 1e-3 * next(), 1e-3 * next(), 1e-3 * next()];
                    Motion::new(s.centroid, &d)
                })
                .collect();
            let before: Vec<bool> = set.contacts.iter().map(|c| c.active).collect();
            let n = list.track(&CoverDetector, &shapes, &trial, &mut set);
            prop_assert_eq!(n, track_by_scan(&CoverDetector, &shapes, &trial, &mut by_scan));
            prop_assert_eq!(&set, &by_scan);
            // The list names every candidate made active, and only those.
            let made: Vec<u32> = (0..set.contacts.len() as u32)
                .filter(|&k| set.contacts[k as usize].active && !before[k as usize])
                .collect();
            let mut listed = list.activated().to_vec();
            listed.sort_unstable();
            prop_assert_eq!(listed, made);
            activated += n;
        }
        prop_assert!(activated > 0, "no candidate was activated: the test tests nothing");
    }
}

/// Parallel detection over a jointed column equals the sequential run, for every detector.
/// (Needs the `rayon` feature, which the workspace enables through the facade.)
#[cfg(feature = "rayon")]
#[test]
fn parallel_detection_is_sequential_detection() {
    let shapes = jointed_column();
    let boxes: Vec<Aabb> = shapes.iter().map(|s| s.aabb).collect();
    let params = DetectionParams::new(0.05, 2f64.to_radians());
    let mut pairs = Vec::new();
    neighbour_pairs(&boxes, params.d_tol, &mut pairs);
    assert!(pairs.len() > 1000);
    for name in ["cover", "type-1", "type-2"] {
        let det = detector_by_name(name).expect("built-in");
        let prev = ContactSet::default();
        let (mut seq, mut par) = (ContactSet::default(), ContactSet::default());
        detect(
            det.as_ref(),
            &shapes,
            &pairs,
            &params,
            &prev,
            false,
            &mut seq,
        );
        detect(
            det.as_ref(),
            &shapes,
            &pairs,
            &params,
            &prev,
            true,
            &mut par,
        );
        assert!(!seq.is_empty());
        assert_eq!(seq, par, "detector {name}");
    }
}
