//! Cutting: a convex polygon split by a line, and a convex region cut into blocks by joint
//! sets (families of parallel lines), as a jointed rock mass is generated.
//!
//! A split of a convex polygon yields at most two convex pieces. Pieces whose area is below
//! a caller's threshold (slivers) are dropped and counted, so generated block systems do not
//! carry blocks no time step could resolve.

use crate::error::{JointSetError, PolygonError};
use crate::polygon::{ConvexPolygon, DEFAULT_REL_TOL};
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// The line of points x with `normal . x = offset`; `normal` is a unit vector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Line {
    /// Unit normal.
    pub normal: DVec2,
    /// Signed distance of the line from the origin along `normal`.
    pub offset: f64,
}

impl Line {
    /// The unit direction d = (normal.y, -normal.x) along the line: a point's position
    /// along it is `x . d`.
    pub fn direction(&self) -> DVec2 {
        DVec2::new(self.normal.y, -self.normal.x)
    }

    /// The line through `point` along `direction` (any non-zero length).
    pub fn through(point: DVec2, direction: DVec2) -> Self {
        let d = direction.normalize();
        let normal = DVec2::new(-d.y, d.x);
        Line {
            normal,
            offset: normal.dot(point),
        }
    }
}

/// The two sides of a polygon split by a line.
#[derive(Clone, Debug, PartialEq)]
pub struct Split {
    /// The piece where `normal . x <= offset`, if it has area.
    pub below: Option<ConvexPolygon>,
    /// The piece where `normal . x >= offset`, if it has area.
    pub above: Option<ConvexPolygon>,
}

/// Removes consecutive points closer than `eps` (the intersection of a line passing within
/// `eps` of a vertex), keeping each edge's label (`labels[i]` is the label of the edge
/// from point i to point i + 1; a point removed as a duplicate of the one before hands its
/// outgoing label to it); `None` when fewer than three remain.
pub(crate) fn clean_ring<L: Copy>(
    mut pts: Vec<DVec2>,
    mut labels: Vec<L>,
    eps: f64,
) -> Option<(Vec<DVec2>, Vec<L>)> {
    let mut k = 1;
    while k < pts.len() {
        if pts[k - 1].distance(pts[k]) <= eps {
            pts.remove(k);
            let l = labels.remove(k);
            labels[k - 1] = l;
        } else {
            k += 1;
        }
    }
    while pts.len() >= 2 && pts[0].distance(pts[pts.len() - 1]) <= eps {
        pts.pop();
        labels.pop();
    }
    (pts.len() >= 3).then_some((pts, labels))
}

/// Validates one side of a split: degenerate sides (no area) become `None`. Collinear
/// points are merged (an edge then keeps the label of its first part).
pub(crate) fn labelled_piece<L: Copy>(
    pts: Vec<DVec2>,
    labels: Vec<L>,
    eps: f64,
) -> Result<Option<(ConvexPolygon, Vec<L>)>, PolygonError> {
    let Some((pts, labels)) = clean_ring(pts, labels, eps) else {
        return Ok(None);
    };
    match ConvexPolygon::with_options(pts, &crate::polygon::PolygonOptions::default()) {
        Ok((p, repairs)) => {
            let kept: Vec<L> = labels
                .iter()
                .enumerate()
                .filter(|(i, _)| repairs.merged.binary_search(i).is_err())
                .map(|(_, &l)| l)
                .collect();
            // Validation keeps the input's order (counter-clockwise input is never
            // reversed), so the kept labels line up with the polygon's edges.
            Ok(Some((p, kept)))
        }
        Err(PolygonError::ZeroArea | PolygonError::TooFewVertices { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// A convex ring split by a line: each side's points and edge labels (unvalidated).
type SplitRings<L> = [(Vec<DVec2>, Vec<L>); 2];

/// Splits the convex ring `v` (edge labels `labels`) by `line`: the points where
/// `normal . x <= offset` and those where it is `>= offset`, with the new edges along the
/// line labelled `cut`. Vertices exactly on the line go to both sides. Also returns
/// whether any vertex lies strictly below and strictly above.
pub(crate) fn split_ring<L: Copy>(
    v: &[DVec2],
    labels: &[L],
    line: &Line,
    cut: L,
) -> (SplitRings<L>, bool, bool) {
    #[derive(Clone, Copy, PartialEq)]
    enum From {
        Vertex(usize),
        Crossing(usize),
    }
    let n = v.len();
    // Distances relative to the first vertex, to keep them accurate far from the origin.
    let base = line.normal.dot(v[0]) - line.offset;
    let s: Vec<f64> = v
        .iter()
        .map(|&p| base + line.normal.dot(p - v[0]))
        .collect();
    let mut below: Vec<(DVec2, From)> = Vec::with_capacity(n + 1);
    let mut above: Vec<(DVec2, From)> = Vec::with_capacity(n + 1);
    for i in 0..n {
        let j = (i + 1) % n;
        if s[i] <= 0.0 {
            below.push((v[i], From::Vertex(i)));
        }
        if s[i] >= 0.0 {
            above.push((v[i], From::Vertex(i)));
        }
        if (s[i] < 0.0 && s[j] > 0.0) || (s[i] > 0.0 && s[j] < 0.0) {
            let x = v[i] + (v[j] - v[i]) * (s[i] / (s[i] - s[j]));
            below.push((x, From::Crossing(i)));
            above.push((x, From::Crossing(i)));
        }
    }
    // The edge from a to b runs along the polygon's edge i when b follows a on it;
    // otherwise it runs along the cut.
    let ring = |pts: Vec<(DVec2, From)>| -> (Vec<DVec2>, Vec<L>) {
        let m = pts.len();
        let label = |k: usize| {
            let (a, b) = (pts[k].1, pts[(k + 1) % m].1);
            match (a, b) {
                (From::Vertex(i), From::Vertex(j)) if j == (i + 1) % n => labels[i],
                (From::Vertex(i), From::Crossing(j)) if i == j => labels[i],
                (From::Crossing(i), From::Vertex(j)) if j == (i + 1) % n => labels[i],
                _ => cut,
            }
        };
        let l = (0..m).map(label).collect();
        (pts.into_iter().map(|(p, _)| p).collect(), l)
    };
    let has_below = s.iter().any(|&x| x < 0.0);
    let has_above = s.iter().any(|&x| x > 0.0);
    ([ring(below), ring(above)], has_below, has_above)
}

/// Splits a convex polygon by a line. Vertices exactly on the line go to both sides; a side
/// without area is `None`. The pieces' areas add up to the polygon's to rounding.
pub fn split(poly: &ConvexPolygon, line: &Line) -> Result<Split, PolygonError> {
    let v = poly.vertices();
    let labels = vec![(); v.len()];
    let ([below, above], has_below, has_above) = split_ring(v, &labels, line, ());
    let eps = DEFAULT_REL_TOL * poly.aabb().size().length();
    let side = |(pts, l): (Vec<DVec2>, Vec<()>), present: bool| {
        if present {
            labelled_piece(pts, l, eps).map(|p| p.map(|(p, _)| p))
        } else {
            Ok(None)
        }
    };
    Ok(Split {
        below: side(below, has_below)?,
        above: side(above, has_above)?,
    })
}

/// A joint set: parallel lines at dip angle `dip_deg` (degrees, counter-clockwise from
/// the +x axis, so 60 dips up to the right), `spacing` apart, one of them at signed
/// distance `offset` from the origin along the set's normal (-sin dip, cos dip).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct JointSet {
    /// Dip angle in degrees from the +x axis.
    pub dip_deg: f64,
    /// Perpendicular distance between neighbouring joints.
    pub spacing: f64,
    /// Position of one joint along the normal.
    pub offset: f64,
}

impl JointSet {
    /// Unit normal of the set's lines.
    pub fn normal(&self) -> DVec2 {
        let (s, c) = self.dip_deg.to_radians().sin_cos();
        DVec2::new(-s, c)
    }
}

/// The blocks a region was cut into, and what was dropped.
#[derive(Clone, Debug, PartialEq)]
pub struct Cutting {
    /// The blocks, in a deterministic order.
    pub blocks: Vec<ConvexPolygon>,
    /// How many slivers (pieces below the area threshold) were dropped.
    pub dropped: usize,
    /// Their total area.
    pub dropped_area: f64,
}

/// Cuts a convex region by joint sets into convex blocks; pieces with area below
/// `min_area` are dropped and counted. Each piece is cut only by the joints crossing it.
/// A [`JointSetError::Piece`] error names the set of the joint that made the piece.
pub fn cut_by_joint_sets(
    region: &ConvexPolygon,
    sets: &[JointSet],
    min_area: f64,
) -> Result<Cutting, JointSetError> {
    if !(min_area.is_finite() && min_area >= 0.0) {
        return Err(JointSetError::MinArea { min_area });
    }
    for (k, set) in sets.iter().enumerate() {
        if !(set.dip_deg.is_finite() && set.offset.is_finite()) {
            return Err(JointSetError::NonFinite { set: k });
        }
        if !(set.spacing.is_finite() && set.spacing > 0.0) {
            return Err(JointSetError::Spacing {
                set: k,
                spacing: set.spacing,
            });
        }
    }
    // Every joint of every set that crosses the region, set by set.
    let mut lines = Vec::new();
    let mut line_set = Vec::new();
    for (set_index, set) in sets.iter().enumerate() {
        let normal = set.normal();
        let (lo, hi) = region.extent(normal);
        let first = ((lo - set.offset) / set.spacing).ceil() as i64;
        let last = ((hi - set.offset) / set.spacing).floor() as i64;
        for k in first..=last {
            lines.push(Line {
                normal,
                offset: set.offset + k as f64 * set.spacing,
            });
            line_set.push(set_index);
        }
    }
    cut_by_lines(region, &lines, min_area).map_err(|e| match e {
        JointSetError::Piece { set, error } => JointSetError::Piece {
            set: line_set[set],
            error,
        },
        e => e,
    })
}

/// Cuts a convex region by individual lines, in order, into convex blocks (each block is
/// split by every line crossing it); pieces with area below `min_area` are dropped and
/// counted. In a [`JointSetError::Piece`] error, `set` is the index of the line.
pub fn cut_by_lines(
    region: &ConvexPolygon,
    lines: &[Line],
    min_area: f64,
) -> Result<Cutting, JointSetError> {
    if !(min_area.is_finite() && min_area >= 0.0) {
        return Err(JointSetError::MinArea { min_area });
    }
    let mut blocks = vec![region.clone()];
    for (index, line) in lines.iter().enumerate() {
        if !(line.normal.is_finite() && line.offset.is_finite()) {
            return Err(JointSetError::NonFinite { set: index });
        }
        let mut next = Vec::with_capacity(blocks.len() + 8);
        for block in blocks.drain(..) {
            let (lo, hi) = block.extent(line.normal);
            let crosses = lo < line.offset && hi > line.offset;
            if !crosses {
                next.push(block);
                continue;
            }
            let sp =
                split(&block, line).map_err(|error| JointSetError::Piece { set: index, error })?;
            next.extend(sp.below);
            next.extend(sp.above);
        }
        blocks = next;
    }
    let (keep, drop): (Vec<_>, Vec<_>) = blocks.into_iter().partition(|b| b.area() >= min_area);
    Ok(Cutting {
        dropped: drop.len(),
        dropped_area: drop.iter().map(ConvexPolygon::area).sum(),
        blocks: keep,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_square_diagonally() {
        let sq = ConvexPolygon::from_coords(&[[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
            .expect("valid");
        let sp = split(&sq, &Line::through(DVec2::ZERO, DVec2::new(1.0, 1.0))).expect("split");
        let (b, a) = (sp.below.expect("below"), sp.above.expect("above"));
        assert_eq!(b.len(), 3);
        assert_eq!(a.len(), 3);
        assert!((a.area() - 0.5).abs() < 1e-15 && (b.area() - 0.5).abs() < 1e-15);
        // A line along an edge leaves one side empty.
        let sp = split(&sq, &Line::through(DVec2::ZERO, DVec2::X)).expect("split");
        assert!(sp.below.is_none());
        assert_eq!(sp.above.expect("above").len(), 4);
    }

    #[test]
    fn grid_of_squares() {
        let region = ConvexPolygon::from_coords(&[[0.0, 0.0], [4.0, 0.0], [4.0, 2.0], [0.0, 2.0]])
            .expect("valid");
        let sets = [
            JointSet {
                dip_deg: 0.0,
                spacing: 1.0,
                offset: 0.0,
            },
            JointSet {
                dip_deg: 90.0,
                spacing: 1.0,
                offset: 0.0,
            },
        ];
        let c = cut_by_joint_sets(&region, &sets, 1e-6).expect("cut");
        assert_eq!(c.blocks.len(), 8);
        // The same joints given line by line cut the same grid.
        let lines: Vec<Line> = [1.0, 2.0, 3.0]
            .iter()
            .map(|&x| Line::through(DVec2::new(x, 0.0), DVec2::Y))
            .chain([Line::through(DVec2::new(0.0, 1.0), DVec2::X)])
            .collect();
        let by_lines = cut_by_lines(&region, &lines, 1e-6).expect("cut");
        assert_eq!(by_lines.blocks.len(), 8);
        for b in &by_lines.blocks {
            assert!((b.area() - 1.0).abs() < 1e-12);
        }
        assert_eq!(c.dropped, 0);
        for b in &c.blocks {
            assert!((b.area() - 1.0).abs() < 1e-12);
        }
        assert_eq!(
            cut_by_joint_sets(
                &region,
                &[JointSet {
                    dip_deg: 0.0,
                    spacing: 0.0,
                    offset: 0.0
                }],
                0.0
            ),
            Err(JointSetError::Spacing {
                set: 0,
                spacing: 0.0
            })
        );
    }
}
