//! The block displacement function of Shi's DDA (docs/method.md) and the per-block matrices
//! built from it: T(x, y), the mass matrix rho * integral(T^T T dA) and the plane
//! elasticity matrix. Small fixed-size algebra on the stack; a rigid block uses the first 3
//! columns.

use crate::solver::{chol, forward_solve};
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

/// Where point `p` of a block whose centroid is `c` lies half way through a step that
/// turns the block by `turn`: the lever arm of a spring held at a point (a fixed point, a
/// bolt's end) or of a point load. Its linear row then moves the point along the chord
/// of the arc the exact rotation takes it on, where the lever arm at the step's start
/// moves it along the tangent: a body turning about a point so held, or swung by a
/// load, gained energy at the second order of its turn a step (docs/method.md section
/// 4, "Springs held at a point, and point loads").
pub fn half_turned(p: DVec2, c: DVec2, turn: f64) -> DVec2 {
    let (s, co) = (0.5 * turn).sin_cos();
    let v = p - c;
    c + DVec2::new(co * v.x - s * v.y, s * v.x + co * v.y)
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

/// A block's own strain damping time, s: 2 / w, w the lowest angular frequency of its
/// strain (the constant-strain modes of its mass matrix `mass` against its elastic
/// stiffness `area` C, the rotation held), so that its strain vibration is critically
/// damped at that frequency and over it: a block deforms under its loads without
/// ringing (docs/method.md section 12). 0 where the frequency is not defined.
pub fn own_damping(mass: &Mat6, area: f64, c: &[[f64; 3]; 3]) -> f64 {
    // w^2 is the smallest eigenvalue of L^-1 K L^-T, L the Cholesky factor of the
    // strain block of the mass matrix and K = area C.
    let mut strain_mass = [[0.0; 6]; 6];
    for (i, row) in strain_mass.iter_mut().take(3).enumerate() {
        row[..3].copy_from_slice(&mass[3 + i][3..6]);
    }
    let Some(l) = chol(&strain_mass, 3) else {
        return 0.0;
    };
    let solve = |mut b: [f64; 6]| {
        forward_solve(&l, 3, &mut b);
        b
    };
    // X = L^-1 K (column by column), then A = X L^-T = L^-1 (L^-1 K)^T.
    let x: [[f64; 3]; 3] = {
        let cols: [[f64; 6]; 3] = std::array::from_fn(|j| {
            solve([
                area * c[0][j],
                area * c[1][j],
                area * c[2][j],
                0.0,
                0.0,
                0.0,
            ])
        });
        std::array::from_fn(|i| std::array::from_fn(|j| cols[j][i]))
    };
    let a: [[f64; 3]; 3] = {
        let cols: [[f64; 6]; 3] =
            std::array::from_fn(|i| solve([x[i][0], x[i][1], x[i][2], 0.0, 0.0, 0.0]));
        std::array::from_fn(|i| std::array::from_fn(|j| 0.5 * (cols[i][j] + cols[j][i])))
    };
    let lowest = smallest_eigenvalue(&a);
    if lowest.is_finite() && lowest > 0.0 {
        2.0 / lowest.sqrt()
    } else {
        0.0
    }
}

/// The smallest eigenvalue of a symmetric 3 x 3 matrix (the trigonometric solution of its
/// characteristic cubic).
fn smallest_eigenvalue(a: &[[f64; 3]; 3]) -> f64 {
    let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if off == 0.0 {
        return a[0][0].min(a[1][1]).min(a[2][2]);
    }
    let q = (a[0][0] + a[1][1] + a[2][2]) / 3.0;
    let p2 = (a[0][0] - q).powi(2) + (a[1][1] - q).powi(2) + (a[2][2] - q).powi(2) + 2.0 * off;
    let p = (p2 / 6.0).sqrt();
    let b: [[f64; 3]; 3] = std::array::from_fn(|i| {
        std::array::from_fn(|j| (a[i][j] - if i == j { q } else { 0.0 }) / p)
    });
    let det = b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]);
    let phi = (0.5 * det).clamp(-1.0, 1.0).acos() / 3.0;
    // The three roots are q + 2 p cos(phi + 2 pi k / 3); the smallest is k = 1.
    q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
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

    /// A block's own damping time: for a 2 m x 1 m rectangle with nu = 0 the strain
    /// modes decouple (its product of inertia vanishes), with w^2 = A E / (rho Ixx) for
    /// the stretch along x (Ixx = w^3 h / 12, the second moment the stretch moves),
    /// A E / (rho Iyy) along y and 2 A E / (rho (Ixx + Iyy)) in shear: the lowest is the
    /// stretch along the long side, 3 E / rho; beta = 2 / sqrt(3 E / rho).
    #[test]
    fn own_damping_is_critical_at_the_lowest_strain_frequency() {
        let p =
            ConvexPolygon::from_coords(&[[0.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]]).unwrap();
        let (rho, e) = (2500.0, 1e10);
        let m = p.moments();
        let beta = own_damping(&mass_matrix(&m, rho), m.area, &elasticity(e, 0.0));
        let want = 2.0 / (3.0 * e / rho).sqrt();
        assert!((beta / want - 1.0).abs() < 1e-12, "{beta} against {want}");
    }

    /// The smallest eigenvalue of a rotated diag(1, 2, 5) is 1 (to rounding), and of one
    /// with a double root (diag(3, 3, 7)) 3, to the square root of the rounding: at a
    /// double root the cubic's angle sits at the end of acos's range, where a rounding
    /// error eps in its argument moves the angle by sqrt(2 eps).
    #[test]
    fn smallest_eigenvalue_of_symmetric_3x3() {
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let (c2, s2) = (1.1f64.cos(), 1.1f64.sin());
        // R = Rz(0.3) Rx(1.1).
        let r = [[c, -s * c2, s * s2], [s, c * c2, -c * s2], [0.0, s2, c2]];
        let root_eps = (2.0 * f64::EPSILON).sqrt();
        for (d, want, tol) in [
            ([1.0, 2.0, 5.0], 1.0, 1e-12),
            ([3.0, 3.0, 7.0], 3.0, 10.0 * root_eps),
        ] {
            let a: [[f64; 3]; 3] = std::array::from_fn(|i| {
                std::array::from_fn(|j| (0..3).map(|k| r[i][k] * d[k] * r[j][k]).sum())
            });
            let got = smallest_eigenvalue(&a);
            assert!((got - want).abs() < tol, "{got} against {want}");
        }
    }

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
