//! Scenes as written by hand: coordinates to 6 decimals, the whole scene turned so that
//! its faces are neither level nor upright and its points miss them in the last digit.

use dda::geom::DVec2;

/// A turn by `deg` degrees counter-clockwise about the origin.
pub struct Turned {
    sin: f64,
    cos: f64,
}

impl Turned {
    /// The turn by `deg` degrees.
    pub fn new(deg: f64) -> Self {
        let (sin, cos) = deg.to_radians().sin_cos();
        Turned { sin, cos }
    }

    /// The point (x, y) turned.
    pub fn point(&self, x: f64, y: f64) -> DVec2 {
        DVec2::new(x * self.cos - y * self.sin, x * self.sin + y * self.cos)
    }

    /// The point (x, y) turned and written to 6 decimals, `[x, y]`.
    pub fn written(&self, x: f64, y: f64) -> String {
        let p = self.point(x, y);
        format!("[{:.6}, {:.6}]", p.x, p.y)
    }

    /// The outline `points` turned and written to 6 decimals, `[[x, y], ...]`.
    pub fn outline(&self, points: &[(f64, f64)]) -> String {
        let v: Vec<String> = points.iter().map(|&(x, y)| self.written(x, y)).collect();
        format!("[{}]", v.join(", "))
    }
}
