//! Bad polygon input: each defect gets its own error naming the vertex, never a panic.

use dda_geom::{ConvexPolygon, DVec2, PolygonError, PolygonOptions};

fn build(c: &[[f64; 2]]) -> Result<ConvexPolygon, PolygonError> {
    ConvexPolygon::from_coords(c)
}

fn strict(c: &[[f64; 2]]) -> Result<ConvexPolygon, PolygonError> {
    let v: Vec<DVec2> = c.iter().map(|&p| DVec2::from(p)).collect();
    ConvexPolygon::with_options(v, &PolygonOptions::strict()).map(|(p, _)| p)
}

#[test]
fn fewer_than_three_vertices() {
    assert_eq!(build(&[]), Err(PolygonError::TooFewVertices { count: 0 }));
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0]]),
        Err(PolygonError::TooFewVertices { count: 2 })
    );
}

#[test]
fn nan_coordinate() {
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, f64::NAN], [0.0, 1.0]]),
        Err(PolygonError::NonFinite { vertex: 1 })
    );
}

#[test]
fn infinite_coordinate() {
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0], [f64::INFINITY, 1.0]]),
        Err(PolygonError::NonFinite { vertex: 2 })
    );
}

#[test]
fn duplicate_adjacent_vertex() {
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
        Err(PolygonError::DuplicateVertex { vertex: 2, of: 1 })
    );
}

#[test]
fn duplicate_first_and_last_vertex() {
    // A closed ring (first vertex repeated at the end) is a duplicate, not silently accepted.
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]]),
        Err(PolygonError::DuplicateVertex { vertex: 3, of: 0 })
    );
}

#[test]
fn duplicate_non_adjacent_vertex() {
    assert_eq!(
        build(&[[0.0, 0.0], [2.0, 0.0], [0.0, 0.0], [0.0, 2.0], [1.0, 1.0]]).map(|_| ()),
        Err(PolygonError::DuplicateVertex { vertex: 2, of: 0 })
    );
}

#[test]
fn collinear_vertex_strict() {
    assert_eq!(
        strict(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]),
        Err(PolygonError::CollinearVertex { vertex: 1 })
    );
    // With the default options it is merged.
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0]]).map(|p| p.len()),
        Ok(3)
    );
}

#[test]
fn clockwise_strict() {
    assert_eq!(
        strict(&[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]]),
        Err(PolygonError::Clockwise)
    );
}

#[test]
fn non_convex() {
    // An arrowhead: vertex 3 is reflex.
    assert_eq!(
        build(&[[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]]),
        Err(PolygonError::NotConvex { vertex: 3 })
    );
}

#[test]
fn self_intersecting_bowtie() {
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]]),
        Err(PolygonError::SelfIntersecting {
            edge_a: 0,
            edge_b: 2
        })
    );
}

#[test]
fn self_intersecting_pentagram() {
    // Every turn is a left turn, but the boundary winds twice.
    let star: Vec<[f64; 2]> = (0..5)
        .map(|k| {
            let t = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
            [t.cos(), t.sin()]
        })
        .collect();
    assert!(matches!(
        build(&star),
        Err(PolygonError::SelfIntersecting { .. })
    ));
}

#[test]
fn zero_area() {
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
        Err(PolygonError::ZeroArea)
    );
    assert_eq!(
        build(&[[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [2.0, 0.0]]),
        Err(PolygonError::ZeroArea)
    );
}

#[test]
fn errors_read_well() {
    let e = build(&[[0.0, 0.0], [2.0, 1.0], [0.0, 2.0], [0.5, 1.0]]).expect_err("reflex");
    assert_eq!(
        e.to_string(),
        "polygon is not convex: it turns the wrong way at vertex 3"
    );
}
