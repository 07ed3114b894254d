//! The block displacement function of Shi's DDA (docs/method.md) and the per-block matrices
//! built from it: T(x, y), the mass matrix rho * integral(T^T T dA) and the plane
//! elasticity matrix. Small fixed-size algebra on the stack; a rigid block uses the first 3
//! columns.

use dda_geom::{DVec2, Moments};

/// Six block unknowns or a row over them: (u0, v0, r0, ex, ey, gxy).
pub type Vec6 = [f64; 6];
/// A 6x6 block of the global matrix.
pub type Mat6 = [[f64; 6]; 6];

/// The two rows of T(x, y) for point `p` of a block with reference point (centroid) `c`:
/// `[u v]^T = T D` (docs/method.md).
#[inline]
pub fn t_rows(p: DVec2, c: DVec2) -> [Vec6; 2] {
    let (x, y) = (p.x - c.x, p.y - c.y);
    [
        [1.0, 0.0, -y, x, 0.0, 0.5 * y],
        [0.0, 1.0, x, 0.0, y, 0.5 * x],
    ]
}

/// `dir^T T(p)`: the generalised force of a unit force `dir` at `p`, and equally the
/// row giving the displacement of `p` along `dir` from the block unknowns.
#[inline]
pub fn along(dir: DVec2, p: DVec2, c: DVec2) -> Vec6 {
    let [r0, r1] = t_rows(p, c);
    std::array::from_fn(|k| dir.x * r0[k] + dir.y * r1[k])
}

/// `a . b` over the first `n` components.
#[inline]
pub fn dot(a: &Vec6, b: &Vec6, n: usize) -> f64 {
    (0..n).map(|k| a[k] * b[k]).sum()
}

/// Displacement of point `p` under block motion `d` (linearised: `T(p) D`).
#[inline]
pub fn point_displacement(p: DVec2, c: DVec2, d: &Vec6) -> DVec2 {
    let [r0, r1] = t_rows(p, c);
    DVec2::new(dot(&r0, d, 6), dot(&r1, d, 6))
}

/// rho * integral over the block of T^T T dA, from the area and the centred second
/// moments (the first moments vanish about the centroid).
pub fn mass_matrix(m: &Moments, density: f64) -> Mat6 {
    let (a, sxx, syy, sxy) = (m.area, m.sxx, m.syy, m.sxy);
    let mut k = [[0.0; 6]; 6];
    k[0][0] = a;
    k[1][1] = a;
    k[2][2] = sxx + syy;
    k[2][3] = -sxy;
    k[2][4] = sxy;
    k[2][5] = 0.5 * (sxx - syy);
    k[3][3] = sxx;
    k[3][5] = 0.5 * sxy;
    k[4][4] = syy;
    k[4][5] = 0.5 * sxy;
    k[5][5] = 0.25 * (sxx + syy);
    for i in 0..6 {
        for j in 0..i {
            k[i][j] = k[j][i];
        }
    }
    for row in k.iter_mut() {
        for v in row.iter_mut() {
            *v *= density;
        }
    }
    k
}

/// Plane elasticity matrix E/(1-nu^2) [[1, nu, 0], [nu, 1, 0], [0, 0, (1-nu)/2]] mapping
/// (ex, ey, gxy) to (sx, sy, txy); plane strain passes E' and nu' (see the scene model).
pub fn elasticity(young: f64, poisson: f64) -> [[f64; 3]; 3] {
    let f = young / (1.0 - poisson * poisson);
    [
        [f, f * poisson, 0.0],
        [f * poisson, f, 0.0],
        [0.0, 0.0, f * 0.5 * (1.0 - poisson)],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use dda_geom::ConvexPolygon;

    /// The mass matrix equals rho * sum over a fine grid of T^T T dA (midpoint rule on a
    /// rectangle, where the midpoint rule is exact for the quadratic integrands up to the
    /// h^2/12 per-cell term, which we add back).
    #[test]
    fn mass_matrix_matches_quadrature() {
        let (w, h) = (2.0, 1.0);
        let p = ConvexPolygon::from_coords(&[[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]]).unwrap();
        let m = mass_matrix(&p.moments(), 3.0);
        let c = p.centroid();
        let n = 40;
        let (dx, dy) = (w / n as f64, h / n as f64);
        let mut q = [[0.0; 6]; 6];
        for i in 0..n {
            for j in 0..n {
                let pt = DVec2::new((i as f64 + 0.5) * dx, (j as f64 + 0.5) * dy);
                let t = t_rows(pt, c);
                for a in 0..6 {
                    for b in 0..6 {
                        q[a][b] += 3.0 * (t[0][a] * t[0][b] + t[1][a] * t[1][b]) * dx * dy;
                    }
                }
            }
        }
        // Midpoint rule misses integral((x-xc)^2) by n^2 * dx^3 dy / 12 per direction.
        let ex = 3.0 * w * h * dx * dx / 12.0;
        let ey = 3.0 * w * h * dy * dy / 12.0;
        let fix = |a: usize, b: usize| match (a, b) {
            (2, 2) => ex + ey,
            (3, 3) => ex,
            (4, 4) => ey,
            (2, 5) | (5, 2) => 0.5 * (ex - ey),
            (5, 5) => 0.25 * (ex + ey),
            _ => 0.0,
        };
        for a in 0..6 {
            for b in 0..6 {
                let want = q[a][b] + fix(a, b);
                assert!(
                    (m[a][b] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "M[{a}][{b}] = {} vs {want}",
                    m[a][b]
                );
            }
        }
    }

    #[test]
    fn along_is_the_projected_displacement() {
        let c = DVec2::new(1.0, 2.0);
        let p = DVec2::new(3.0, -1.0);
        let d = [0.1, -0.2, 0.03, 0.004, -0.005, 0.006];
        let dir = DVec2::new(0.6, 0.8);
        let u = point_displacement(p, c, &d);
        assert!((dot(&along(dir, p, c), &d, 6) - u.dot(dir)).abs() < 1e-15);
    }
}
