//! Joint layouts for generated columns: where each joint of each set goes so that no block
//! gets an edge shorter than a chosen least edge.
//!
//! Joints of one set are parallel and nominally `spacing` apart. Uniformly spaced sets put
//! joint ends and crossings arbitrarily close together near the column's boundary (two
//! sets' ends on a side are two arithmetic progressions), which makes tiny triangles there;
//! the paper's columns have a smallest edge of 0.13-0.243 m (Table 3), so its joints were
//! not placed that way, and the paper gives no generator. Our choice: joints are placed
//! set by set, each at its nominal position or, if that would make an edge shorter than
//! `min_edge`, at the nearest position (in steps of `min_edge / 8`, within half a spacing
//! either way) that does not; a joint with no such position is left out. An edge of the
//! cut is a piece of the boundary between joint ends and corners, or a piece of a joint
//! between its crossings with other joints and the boundary, so checking those pieces
//! checks every edge.

use dda_geom::{DVec2, Line};

/// One joint set of a layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SetLayout {
    /// Dip angle in degrees from +x (counter-clockwise).
    pub dip_deg: f64,
    /// Nominal perpendicular spacing, m.
    pub spacing: f64,
    /// Position of the first joint past the column's extent along the set's normal, as a
    /// fraction of `spacing` (0-1).
    pub start: f64,
}

/// A joint layout: the sets, in placement order, and the least edge it may make.
#[derive(Clone, Debug, PartialEq)]
pub struct JointLayout {
    /// The joint sets.
    pub sets: Vec<SetLayout>,
    /// Least edge length a joint may make, m.
    pub min_edge: f64,
}

/// A joint placed so far: its line, its set, and its two ends on the boundary.
struct Placed {
    line: Line,
    set: usize,
    ends: [DVec2; 2],
}

/// The joints of `layout` across the rectangle [0, width] x [0, height].
pub fn place_joints(width: f64, height: f64, layout: &JointLayout) -> Vec<Line> {
    let rect = Rect { width, height };
    let e = layout.min_edge;
    let mut placed: Vec<Placed> = Vec::new();
    for (set_index, set) in layout.sets.iter().enumerate() {
        if !(set.spacing.is_finite() && set.spacing > 0.0 && e.is_finite() && e >= 0.0) {
            continue;
        }
        let (s, c) = set.dip_deg.to_radians().sin_cos();
        let normal = DVec2::new(-s, c);
        let (lo, hi) = rect
            .corners()
            .iter()
            .map(|&p| normal.dot(p))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                (lo.min(x), hi.max(x))
            });
        let step = (e / 8.0).max(set.spacing * 1e-3);
        let reach = (0.5 * set.spacing / step) as i64;
        let mut nominal = lo + set.start * set.spacing;
        while nominal < hi {
            let candidates = (0..=reach).flat_map(|k| [k, -k]).skip(1);
            for k in std::iter::once(0).chain(candidates) {
                let line = Line {
                    normal,
                    offset: nominal + k as f64 * step,
                };
                if let Some(ends) = rect.ends(&line)
                    && fits(&rect, &placed, &line, set_index, ends, e)
                {
                    placed.push(Placed {
                        line,
                        set: set_index,
                        ends,
                    });
                    break;
                }
            }
            nominal += set.spacing;
        }
    }
    placed.into_iter().map(|p| p.line).collect()
}

/// Whether a new joint keeps every edge it makes at least `e` long.
fn fits(rect: &Rect, placed: &[Placed], line: &Line, set: usize, ends: [DVec2; 2], e: f64) -> bool {
    // Along the boundary: its ends against corners and other joints' ends.
    let boundary_ok = ends.iter().all(|h| {
        rect.corners()
            .iter()
            .chain(placed.iter().flat_map(|p| p.ends.iter()))
            .all(|q| h.distance(*q) >= e)
    });
    if !boundary_ok {
        return false;
    }
    // Along the new joint, and along each joint it crosses: the crossing against that
    // joint's ends and its other crossings.
    let mut along_new: Vec<DVec2> = ends.to_vec();
    for p in placed.iter().filter(|p| p.set != set) {
        let Some(x) = crossing(line, &p.line).filter(|x| rect.contains(*x)) else {
            continue;
        };
        along_new.push(x);
        let others = placed
            .iter()
            .filter(|q| q.set != p.set)
            .filter_map(|q| crossing(&p.line, &q.line))
            .filter(|y| rect.contains(*y));
        if p.ends
            .iter()
            .copied()
            .chain(others)
            .any(|y| x.distance(y) < e)
        {
            return false;
        }
    }
    let dir = line.normal.perp();
    along_new.sort_by(|a, b| dir.dot(*a).total_cmp(&dir.dot(*b)));
    along_new.windows(2).all(|w| w[0].distance(w[1]) >= e)
}

/// Where two lines cross (None if parallel).
fn crossing(a: &Line, b: &Line) -> Option<DVec2> {
    let det = a.normal.perp_dot(b.normal);
    if det.abs() < 1e-12 {
        return None;
    }
    Some(DVec2::new(
        (a.offset * b.normal.y - b.offset * a.normal.y) / det,
        (a.normal.x * b.offset - b.normal.x * a.offset) / det,
    ))
}

/// The column's rectangle [0, width] x [0, height].
struct Rect {
    width: f64,
    height: f64,
}

impl Rect {
    fn corners(&self) -> [DVec2; 4] {
        [
            DVec2::ZERO,
            DVec2::new(self.width, 0.0),
            DVec2::new(self.width, self.height),
            DVec2::new(0.0, self.height),
        ]
    }

    fn contains(&self, p: DVec2) -> bool {
        (0.0..=self.width).contains(&p.x) && (0.0..=self.height).contains(&p.y)
    }

    /// Where a line crosses the boundary, if it crosses the interior.
    fn ends(&self, line: &Line) -> Option<[DVec2; 2]> {
        let c = self.corners();
        let mut hits = Vec::with_capacity(2);
        for i in 0..4 {
            let (a, b) = (c[i], c[(i + 1) % 4]);
            let (da, db) = (
                line.normal.dot(a) - line.offset,
                line.normal.dot(b) - line.offset,
            );
            if (da < 0.0) != (db < 0.0) {
                hits.push(a + (b - a) * (da / (da - db)));
            }
        }
        (hits.len() == 2).then(|| [hits[0], hits[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// No edge of the cut is shorter than the layout's least edge.
    #[test]
    fn cut_keeps_the_least_edge() {
        let layout = JointLayout {
            sets: vec![
                SetLayout {
                    dip_deg: 60.0,
                    spacing: 0.5,
                    start: 0.3,
                },
                SetLayout {
                    dip_deg: 15.0,
                    spacing: 0.4,
                    start: 0.5,
                },
            ],
            min_edge: 0.15,
        };
        let (w, h) = (10.0, 20.0);
        let lines = place_joints(w, h, &layout);
        assert!(lines.len() > 60, "{} joints", lines.len());
        let region = dda_geom::shapes::rectangle(DVec2::ZERO, DVec2::new(w, h)).unwrap();
        let cut = dda_geom::cut_by_lines(&region, &lines, 0.0).unwrap();
        let shortest = cut
            .blocks
            .iter()
            .map(|b| b.shortest_edge().1)
            .fold(f64::INFINITY, f64::min);
        assert!(shortest >= layout.min_edge * (1.0 - 1e-9), "{shortest}");
    }
}
