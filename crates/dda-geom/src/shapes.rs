//! Ready-made convex shapes: rectangles, regular polygons, wedges and chamfered corners,
//! for scene generators, tests and benchmarks.

use crate::error::PolygonError;
use crate::polygon::ConvexPolygon;
use glam::DVec2;

/// The axis-aligned rectangle with corners `min` and `max`.
pub fn rectangle(min: DVec2, max: DVec2) -> Result<ConvexPolygon, PolygonError> {
    ConvexPolygon::new(vec![
        min,
        DVec2::new(max.x, min.y),
        max,
        DVec2::new(min.x, max.y),
    ])
}

/// A regular `n`-gon of circumradius `radius` about `center`, its first vertex at angle
/// `phase` (radians).
pub fn regular(
    n: usize,
    radius: f64,
    center: DVec2,
    phase: f64,
) -> Result<ConvexPolygon, PolygonError> {
    let step = std::f64::consts::TAU / n as f64;
    ConvexPolygon::new(
        (0..n)
            .map(|i| center + radius * DVec2::from_angle(phase + step * i as f64))
            .collect::<Vec<_>>(),
    )
}

/// An isosceles triangle with tip at `tip`, pointing along `direction` (radians), legs of
/// length `leg` and tip angle `tip_angle` (radians, in (0, pi)).
pub fn wedge(
    tip: DVec2,
    direction: f64,
    tip_angle: f64,
    leg: f64,
) -> Result<ConvexPolygon, PolygonError> {
    let back = direction + std::f64::consts::PI;
    ConvexPolygon::new(vec![
        tip,
        tip + leg * DVec2::from_angle(back - 0.5 * tip_angle),
        tip + leg * DVec2::from_angle(back + 0.5 * tip_angle),
    ])
}

/// `poly` with its corner `vertex` cut off by a chamfer whose two new vertices lie
/// `cut` along each of the corner's edges (`cut` below half of both edges' lengths).
pub fn chamfer(
    poly: &ConvexPolygon,
    vertex: usize,
    cut: f64,
) -> Result<ConvexPolygon, PolygonError> {
    let n = poly.len();
    let v = poly.vertex(vertex);
    let prev = poly.vertex(vertex + n - 1);
    let next = poly.vertex(vertex + 1);
    let mut pts = Vec::with_capacity(n + 1);
    for i in 0..n {
        if i == vertex % n {
            pts.push(v + (prev - v).normalize() * cut);
            pts.push(v + (next - v).normalize() * cut);
        } else {
            pts.push(poly.vertex(i));
        }
    }
    ConvexPolygon::new(pts)
}
