//! Axis-aligned bounding boxes, the currency of the neighbour search.

use glam::DVec2;
use serde::{Deserialize, Serialize};

/// An axis-aligned bounding box `[min, max]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb {
    /// Lower-left corner.
    pub min: DVec2,
    /// Upper-right corner.
    pub max: DVec2,
}

impl Aabb {
    /// The smallest box holding all `points` (an inverted empty box if there are none).
    pub fn from_points(points: &[DVec2]) -> Self {
        let mut b = Aabb {
            min: DVec2::splat(f64::INFINITY),
            max: DVec2::splat(f64::NEG_INFINITY),
        };
        for &p in points {
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        b
    }

    /// This box grown by `d` on every side (used with the contact tolerance d_tol).
    pub fn expanded(&self, d: f64) -> Self {
        Aabb {
            min: self.min - DVec2::splat(d),
            max: self.max + DVec2::splat(d),
        }
    }

    /// Whether the two boxes share at least one point (touching counts).
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.x <= other.max.x
            && other.min.x <= self.max.x
            && self.min.y <= other.max.y
            && other.min.y <= self.max.y
    }

    /// Whether `p` lies in the closed box.
    pub fn contains(&self, p: DVec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }

    /// Width and height.
    pub fn size(&self) -> DVec2 {
        self.max - self.min
    }

    /// The distances between the two boxes along x and along y: each 0 where their
    /// intervals on that axis overlap or touch.
    pub fn axis_gaps(&self, other: &Aabb) -> DVec2 {
        DVec2::new(
            (other.min.x - self.max.x)
                .max(self.min.x - other.max.x)
                .max(0.0),
            (other.min.y - self.max.y)
                .max(self.min.y - other.max.y)
                .max(0.0),
        )
    }

    /// The distance between the two boxes: 0 where they overlap or touch. It is at
    /// least the larger of [`Aabb::axis_gaps`], and a box inside a third box is no
    /// nearer to a fourth than the third is along either axis (the rounding of each
    /// difference keeps that order), which is what lets a tree of boxes prune exactly.
    pub fn gap(&self, other: &Aabb) -> f64 {
        let d = self.axis_gaps(other);
        d.x.hypot(d.y)
    }

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Self {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Aabb;
    use glam::DVec2;

    fn square(x: f64, y: f64, side: f64) -> Aabb {
        Aabb {
            min: DVec2::new(x, y),
            max: DVec2::new(x + side, y + side),
        }
    }

    /// Boxes apart on both axes are as far as their nearest corners (a 3-4-5 triangle);
    /// apart on one axis, as far as that axis says; touching or overlapping, 0. Either
    /// order gives the same.
    #[test]
    fn the_gap_is_the_distance_between_the_nearest_points() {
        let a = square(0.0, 0.0, 1.0);
        for (b, axes, gap) in [
            (square(4.0, 5.0, 1.0), DVec2::new(3.0, 4.0), 5.0),
            (square(3.0, 0.5, 1.0), DVec2::new(2.0, 0.0), 2.0),
            (square(-0.5, -3.0, 1.0), DVec2::new(0.0, 2.0), 2.0),
            (square(1.0, 1.0, 1.0), DVec2::ZERO, 0.0),
            (square(0.25, 0.25, 0.5), DVec2::ZERO, 0.0),
        ] {
            assert_eq!(a.axis_gaps(&b), axes);
            assert_eq!(b.axis_gaps(&a), axes);
            assert_eq!(a.gap(&b), gap);
            assert_eq!(b.gap(&a), gap);
        }
    }
}
