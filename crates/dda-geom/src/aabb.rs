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

    /// The smallest box holding both.
    pub fn union(&self, other: &Aabb) -> Self {
        Aabb {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }
}
