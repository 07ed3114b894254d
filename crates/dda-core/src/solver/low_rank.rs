//! Solves through a low-rank (Woodbury) update of the factor: an open-close iteration
//! that changed few springs since the last factorisation solves (K + U S U^T) x = F + ...
//! with that factor, sweeping each new column along its path in the elimination tree.

use super::BlockSystem;
use super::factor::factor_of;
use super::sweeps::{axpy_over, dot_over};
use crate::kinematics::Vec6;

impl BlockSystem {
    /// Solves (K + sum s u u^T) x = F + sum g v, where K and F are the matrix and
    /// right-hand side of the last [`BlockSystem::solve`], `terms` the rank-one changes of
    /// the matrix (u, s) and `rhs_terms` the changes of the right-hand side (v with its
    /// coefficient g in `s`), by the Woodbury identity in halves of K = L L^T:
    /// x = L^-T (h - W C^-1 W^T h) with W = L^-1 U, h = L^-1 F + sum g L^-1 v and
    /// C = S^-1 + W^T W.
    ///
    /// L^-1 F is kept from the factorisation; each L^-1 u is a forward sweep along the
    /// path of u's blocks in the elimination tree, done once per factorisation and kept
    /// with its products with the other kept columns, so a row that stays in the lists
    /// from one call to the next costs nothing more. The right-hand side's changes along no
    /// kept column are summed and swept forward once; one backward sweep ends the solve.
    /// Returns false when there is no valid factor or C is numerically singular: the
    /// caller then assembles and factorises.
    pub fn solve_low_rank(&mut self, terms: &[RankOne], rhs_terms: &[RankOne]) -> bool {
        let n = self.nb * self.nd;
        if !self.factored || terms.iter().any(|t| t.s == 0.0 || !t.s.is_finite()) {
            return false;
        }
        let Some(factor) = factor_of(&self.symbolic, &self.l_values) else {
            return false;
        };
        if n == 0 {
            return true;
        }
        let mut g = std::mem::take(&mut self.gather);
        // Columns of W: reuse those already swept, sweep the new ones.
        self.term_col.clear();
        let first_new = self.z_rows.len();
        for t in terms {
            let key = (t.blocks, t.c);
            let col = match self.z_rows.iter().position(|r| *r == key) {
                Some(col) => col,
                None => {
                    let col = self.z_rows.len();
                    self.z_rows.push(key);
                    let (pos, nd) = (&self.pos, self.nd);
                    let first_rows = t.blocks.map(|b| b.map(|b| pos[b as usize] as usize * nd));
                    let cols = first_rows
                        .into_iter()
                        .flatten()
                        .flat_map(|p| [p, p + nd - 1]);
                    let at = self.paths.len();
                    self.tree.path(cols, &mut self.paths);
                    self.path_start.push(self.paths.len());
                    // Every sweep, product and update of the column reads and writes
                    // only its path's rows (see `Factor::forward_paths`): only those are
                    // zeroed, in a buffer kept from one factorisation to the next.
                    if self.z.len() < (col + 1) * n {
                        self.z.resize((col + 1) * n, 0.0);
                    }
                    let zc = &mut self.z[col * n..(col + 1) * n];
                    for rows in factor.path_rows(&self.paths[at..]) {
                        zc[rows].fill(0.0);
                    }
                    for (p, c) in first_rows.iter().zip(&t.c) {
                        if let Some(p) = p {
                            for (v, x) in zc[*p..*p + nd].iter_mut().zip(c) {
                                *v += x;
                            }
                        }
                    }
                    col
                }
            };
            self.term_col.push(col);
        }
        if self.z_rows.len() > first_new {
            let new = first_new..self.z_rows.len();
            factor.forward_paths(
                &mut self.z,
                n,
                &self.paths,
                &self.path_start,
                new.clone(),
                &mut self.sweep,
            );
            // Their products with the columns before them and themselves.
            for j in new {
                let pj = path(&self.paths, &self.path_start, j);
                for i in 0..=j {
                    let pi = path(&self.paths, &self.path_start, i);
                    let rows = factor.node_rows(common(pi, pj));
                    let (zi, zj) = (&self.z[i * n..(i + 1) * n], &self.z[j * n..(j + 1) * n]);
                    self.gram.push(dot_over(rows, zi, zj));
                }
            }
        }
        // h = L^-1 F + sum g L^-1 v. A change of the right-hand side along a kept column
        // (a spring's, beside its change of the matrix) is added from it; the others (the
        // friction forces, which change with their contacts' normal forces in almost
        // every iteration) are summed and swept forward once: as columns of W, each with
        // its products with every other, they were two thirds of a sliding wall's solve.
        self.rhs.copy_from_slice(&self.h0);
        let mut delta = std::mem::take(&mut self.delta);
        delta.clear();
        for t in rhs_terms {
            let key = (t.blocks, t.c);
            if let Some(col) = self.z_rows.iter().position(|r| *r == key) {
                let rows = factor.path_rows(path(&self.paths, &self.path_start, col));
                axpy_over(rows, t.s, &self.z[col * n..(col + 1) * n], &mut self.rhs);
                continue;
            }
            delta.resize(n, 0.0);
            for (b, c) in t.blocks.iter().zip(&t.c) {
                if let Some(b) = b {
                    let p = self.pos[*b as usize] as usize * self.nd;
                    for (v, x) in delta[p..p + self.nd].iter_mut().zip(c) {
                        *v += t.s * x;
                    }
                }
            }
        }
        if !delta.is_empty() {
            factor.forward(&mut delta, &mut g);
            for (r, d) in self.rhs.iter_mut().zip(&delta) {
                *r += d;
            }
        }
        self.delta = delta;
        let k = terms.len();

        // C = S^-1 + W^T W and W^T h.
        self.cap.clear();
        self.cap.resize(k * k, 0.0);
        self.cap_rhs.clear();
        for (i, t) in terms.iter().enumerate() {
            let ci = self.term_col[i];
            for (j, &cj) in self.term_col[..k].iter().enumerate() {
                let (lo, hi) = (ci.min(cj), ci.max(cj));
                self.cap[i * k + j] = self.gram[hi * (hi + 1) / 2 + lo];
            }
            self.cap[i * k + i] += 1.0 / t.s;
            let zc = &self.z[ci * n..(ci + 1) * n];
            self.cap_rhs.push(dot_over(
                factor.path_rows(path(&self.paths, &self.path_start, ci)),
                zc,
                &self.rhs,
            ));
        }
        if !lu_solve_in_place(&mut self.cap, &mut self.cap_rhs, k) {
            self.gather = g;
            return false;
        }
        for (&col, &w) in self.term_col[..k].iter().zip(&self.cap_rhs) {
            let rows = factor.path_rows(path(&self.paths, &self.path_start, col));
            axpy_over(rows, -w, &self.z[col * n..(col + 1) * n], &mut self.rhs);
        }
        factor.backward(&mut self.rhs, &mut g);
        self.gather = g;
        self.counters.low_rank += 1;
        true
    }
}

/// The supernodes column `col` of the kept columns may be nonzero on.
fn path<'a>(paths: &'a [u32], start: &[usize], col: usize) -> &'a [u32] {
    &paths[start[col]..start[col + 1]]
}

/// The supernodes two ascending lists have in common, ascending.
fn common<'a>(a: &'a [u32], b: &'a [u32]) -> impl Iterator<Item = u32> + 'a {
    let (mut i, mut j) = (0, 0);
    std::iter::from_fn(move || {
        while i < a.len() && j < b.len() {
            match a[i].cmp(&b[j]) {
                std::cmp::Ordering::Less => i += 1,
                std::cmp::Ordering::Greater => j += 1,
                std::cmp::Ordering::Equal => {
                    i += 1;
                    j += 1;
                    return Some(a[i - 1]);
                }
            }
        }
        None
    })
}

/// A symmetric rank-one change `s u u^T` of the factorised matrix, `u` a row over the
/// unknowns of (up to) two free blocks: a spring added (s > 0) or removed (s < 0) since the
/// factorisation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RankOne {
    /// The free blocks the row touches (`None`: a fixed block, which has no unknowns).
    pub blocks: [Option<u32>; 2],
    /// Coefficients over each block's unknowns.
    pub c: [Vec6; 2],
    /// Stiffness of the change.
    pub s: f64,
}

impl BlockSystem {
    /// Adds the rank-one term `t` (s u u^T over its blocks' rows u) to the matrix: a
    /// spring's change applied to the assembled values, for a system solved
    /// iteratively (a factor is not updated). Its blocks, if both free, must be a pair
    /// of the pattern.
    pub fn add_rank_one(&mut self, t: &RankOne) {
        for (f, c) in t.blocks.iter().zip(&t.c) {
            if let Some(f) = *f {
                self.add_outer(self.diagonal(f), f, f, t.s, c, c);
            }
        }
        if let [Some(a), Some(b)] = t.blocks
            && let Some(e) = self.entry(a, b)
        {
            self.add_outer(e, a, b, t.s, &t.c[0], &t.c[1]);
        }
    }

    /// Adds the right-hand side term `t` (s times its blocks' rows) to the right-hand
    /// side: a change of a spring's or a friction force's term, for a system solved
    /// iteratively.
    pub fn add_rhs_term(&mut self, t: &RankOne) {
        for (b, c) in t.blocks.iter().zip(&t.c) {
            if let Some(b) = *b {
                self.add_rhs(b, t.s, c);
            }
        }
    }
}

/// Solves the dense `k x k` system `a x = b` (row-major `a`, overwritten) by LU with
/// partial pivoting, leaving x in `b`; false if a pivot vanishes.
fn lu_solve_in_place(a: &mut [f64], b: &mut [f64], k: usize) -> bool {
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for col in 0..k {
        let mut piv = col;
        for r in col + 1..k {
            if a[r * k + col].abs() > a[piv * k + col].abs() {
                piv = r;
            }
        }
        let pv = a[piv * k + col];
        // A NaN pivot fails too.
        if pv.abs() <= f64::EPSILON * scale || pv.is_nan() {
            return false;
        }
        if piv != col {
            for c in 0..k {
                a.swap(piv * k + c, col * k + c);
            }
            b.swap(piv, col);
        }
        for r in col + 1..k {
            let f = a[r * k + col] / pv;
            if f != 0.0 {
                for c in col + 1..k {
                    a[r * k + c] -= f * a[col * k + c];
                }
                b[r] -= f * b[col];
            }
        }
    }
    for col in (0..k).rev() {
        let s: f64 = (col + 1..k).map(|c| a[col * k + c] * b[c]).sum();
        b[col] = (b[col] - s) / a[col * k + col];
    }
    true
}

#[cfg(test)]
mod tests {
    use super::super::tests::rng;
    use super::*;
    use crate::kinematics::Vec6;

    /// Low-rank solves after a factorisation satisfy the changed system to rounding: a
    /// spring added between two blocks, one to a fixed block (one side only), one removed,
    /// and a load added, over two successive calls that share terms (the second reuses
    /// solved columns).
    #[test]
    fn low_rank_solve_matches_changed_matrix() {
        let (nb, nd) = (5usize, 6usize);
        let n = nb * nd;
        let pairs = [(0u32, 1u32), (0, 4), (1, 2), (2, 3), (3, 4)];
        let mut sys = BlockSystem::new();
        sys.set_pattern(nb, nd, &pairs).unwrap();
        sys.clear();
        let mut rnd = rng(7);
        let mut dense = vec![vec![0.0; n]; n];
        for i in 0..nb {
            let mut k = [[0.0; 6]; 6];
            for a in 0..nd {
                for b in a..nd {
                    let v = if a == b { 10.0 } else { 0.5 * rnd() };
                    k[a][b] = v;
                    dense[i * nd + a][i * nd + b] = v;
                    dense[i * nd + b][i * nd + a] = v;
                }
            }
            sys.add_diagonal(i as u32, &k);
        }
        let f: Vec<f64> = (0..n).map(|_| rnd()).collect();
        let add_rhs = |sys: &mut BlockSystem| {
            for i in 0..nb {
                let fi: Vec6 = std::array::from_fn(|a| f[i * nd + a]);
                sys.add_rhs(i as u32, 1.0, &fi);
            }
        };
        add_rhs(&mut sys);
        sys.solve().unwrap();
        let mut row = |blocks: [Option<u32>; 2], s: f64| RankOne {
            blocks,
            c: [
                std::array::from_fn(|_| rnd()),
                std::array::from_fn(|_| rnd()),
            ],
            s,
        };
        let spring = row([Some(1), Some(2)], 30.0);
        let to_fixed = row([Some(3), None], 50.0);
        let removed = row([Some(0), Some(4)], -1.0);
        let load = row([Some(2), Some(4)], 0.7);
        for (terms, loads) in [
            (vec![spring, to_fixed], vec![]),
            (vec![spring, removed, to_fixed], vec![load]),
        ] {
            assert!(sys.solve_low_rank(&terms, &loads));
            let mut f = f.clone();
            for t in &loads {
                for (b, c) in t.blocks.iter().zip(&t.c) {
                    if let Some(b) = b {
                        for a in 0..nd {
                            f[*b as usize * nd + a] += t.s * c[a];
                        }
                    }
                }
            }
            let mut m = dense.clone();
            for t in &terms {
                let mut u = vec![0.0; n];
                for (b, c) in t.blocks.iter().zip(&t.c) {
                    if let Some(b) = b {
                        u[*b as usize * nd..(*b as usize + 1) * nd].copy_from_slice(c);
                    }
                }
                for r in 0..n {
                    for c in 0..n {
                        m[r][c] += t.s * u[r] * u[c];
                    }
                }
            }
            let x: Vec<f64> = (0..nb as u32)
                .flat_map(|i| sys.solution(i).to_vec())
                .collect();
            for r in 0..n {
                let res: f64 = (0..n).map(|c| m[r][c] * x[c]).sum::<f64>() - f[r];
                assert!(res.abs() < 1e-12, "row {r}: residual {res}");
            }
        }
        assert_eq!(sys.counters().low_rank, 2);
        // A change of the matrix drops the factor: the low-rank path declines.
        sys.add_diagonal(0, &[[1.0; 6]; 6]);
        assert!(!sys.solve_low_rank(&[spring], &[]));
    }

    /// Adds `t.s u u^T` (a spring between two blocks, or to a fixed one) to the matrix.
    fn add_rank_one(sys: &mut BlockSystem, t: &RankOne) {
        let on: Vec<(u32, &Vec6)> = t
            .blocks
            .iter()
            .zip(&t.c)
            .filter_map(|(b, c)| b.map(|b| (b, c)))
            .collect();
        for &(b, c) in &on {
            sys.add_outer(sys.diagonal(b), b, b, t.s, c, c);
        }
        if let [(i, ci), (j, cj)] = on[..] {
            let e = sys.entry(i, j).expect("coupled");
            sys.add_outer(e, i, j, t.s, ci, cj);
        }
    }

    /// K x for the stored lower triangle, x and the result in permuted order; and the
    /// largest absolute row sum of K.
    fn matvec(sys: &BlockSystem, x: &[f64]) -> (Vec<f64>, f64) {
        let n = x.len();
        let (mut y, mut rows) = (vec![0.0; n], vec![0.0; n]);
        let (ptr, idx) = (sys.pattern.col_ptr(), sys.pattern.row_idx());
        for c in 0..n {
            for k in ptr[c]..ptr[c + 1] {
                let (r, v) = (idx[k], sys.values[k]);
                y[r] += v * x[c];
                rows[r] += v.abs();
                if r != c {
                    y[c] += v * x[r];
                    rows[c] += v.abs();
                }
            }
        }
        (y, rows.iter().fold(0.0, |m: f64, v| m.max(*v)))
    }

    /// On a 20 x 20 grid of blocks (2,400 unknowns, elimination-tree paths much shorter
    /// than the factor), low-rank solves after stiff springs are added, removed and tied
    /// to fixed blocks, with right-hand side terms, satisfy the changed system: residual
    /// within the bound of a Woodbury solve, and the sweeps of the new columns cover
    /// only part of the factor.
    #[test]
    fn low_rank_solve_on_a_grid_matches_the_changed_matrix() {
        let (w, nd) = (20u32, 6usize);
        let nb = (w * w) as usize;
        let mut pairs = Vec::new();
        for y in 0..w {
            for x in 0..w {
                let i = y * w + x;
                if x + 1 < w {
                    pairs.push((i, i + 1));
                }
                if y + 1 < w {
                    pairs.push((i, i + w));
                    if x + 1 < w {
                        pairs.push((i, i + w + 1));
                    }
                }
            }
        }
        pairs.sort_unstable();
        let mut rnd = rng(11);
        let (k_block, p) = (1e8, 1e10);
        let mut spring = |(i, j): (u32, u32), s: f64| RankOne {
            blocks: [Some(i), Some(j)],
            c: [
                std::array::from_fn(|_| rnd()),
                std::array::from_fn(|_| rnd()),
            ],
            s,
        };
        // Springs of the factorised matrix on the even pairs; new ones on the odd pairs.
        let base: Vec<RankOne> = pairs.iter().step_by(2).map(|&q| spring(q, p)).collect();
        let added: Vec<RankOne> = pairs
            .iter()
            .skip(1)
            .step_by(13)
            .map(|&q| spring(q, p))
            .collect();
        let removed: Vec<RankOne> = base
            .iter()
            .step_by(11)
            .map(|t| RankOne { s: -t.s, ..*t })
            .collect();
        let mut to_fixed: Vec<RankOne> = (0..5u32)
            .map(|k| RankOne {
                blocks: [Some(k * 37), None],
                ..spring((0, 1), p)
            })
            .collect();
        let loads: Vec<RankOne> = (0..4u32).map(|k| spring((k, k + w), 1e3)).collect();
        let f: Vec<f64> = (0..nb * nd).map(|k| (k % 7) as f64 - 3.0).collect();
        let assemble = |sys: &mut BlockSystem, springs: &[&RankOne], loads: &[RankOne]| {
            sys.clear();
            for i in 0..nb as u32 {
                let mut k = [[0.0; 6]; 6];
                for a in 0..nd {
                    k[a][a] = k_block;
                }
                sys.add_diagonal(i, &k);
                let fi: Vec6 = std::array::from_fn(|a| f[i as usize * nd + a]);
                sys.add_rhs(i, 1.0, &fi);
            }
            for t in springs {
                add_rank_one(sys, t);
            }
            for t in loads {
                for (b, c) in t.blocks.iter().zip(&t.c) {
                    if let Some(b) = b {
                        sys.add_rhs(*b, t.s, c);
                    }
                }
            }
        };
        let mut sys = BlockSystem::new();
        sys.set_pattern(nb, nd, &pairs).unwrap();
        assemble(&mut sys, &base.iter().collect::<Vec<_>>(), &[]);
        sys.solve().unwrap();

        to_fixed.truncate(3);
        let first: Vec<RankOne> = added.iter().chain(&removed).copied().collect();
        let second: Vec<RankOne> = first.iter().chain(&to_fixed).copied().collect();
        let rounds = [
            (false, &first, &loads[..2]),
            (false, &second, &loads[..]),
            // A new factorisation keeps the columns' buffer, and what lies outside a
            // column's path is never read: poisoned with NaN, the solves still match.
            (true, &first, &loads[..2]),
            (true, &second, &loads[..]),
        ];
        for (refactorise, terms, rhs_terms) in rounds {
            if refactorise && !sys.z.iter().any(|v| v.is_nan()) {
                assemble(&mut sys, &base.iter().collect::<Vec<_>>(), &[]);
                sys.solve().unwrap();
                sys.z.fill(f64::NAN);
            }
            assert!(sys.solve_low_rank(terms, rhs_terms));
            let x = sys.rhs.clone();
            // The changed system, assembled and checked directly.
            let mut direct = BlockSystem::new();
            direct.set_pattern(nb, nd, &pairs).unwrap();
            let kept = base
                .iter()
                .enumerate()
                .filter(|(k, _)| k % 11 != 0)
                .map(|(_, t)| t);
            let springs: Vec<&RankOne> = kept.chain(terms.iter().filter(|t| t.s > 0.0)).collect();
            assemble(&mut direct, &springs, rhs_terms);
            let (kx, norm) = matvec(&direct, &x);
            let x_max = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let res = kx
                .iter()
                .zip(&direct.rhs)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            // A backward-stable solve leaves a residual of order sqrt(n) eps |K| |x|; the
            // Woodbury form loses up to p / k_block more to cancellation in C (a removed
            // spring's S^-1 + u^T K^-1 u), and we allow a factor 10 of slack:
            // sqrt(2400) * 2.2e-16 * 100 * 10 = 1.1e-11.
            let bound = (nb as f64 * nd as f64).sqrt() * f64::EPSILON * (p / k_block) * 10.0;
            assert!(
                res <= bound * norm * x_max,
                "residual {res:e} against {:e}",
                bound * norm * x_max
            );
        }
        // The columns were swept along paths, not over the whole factor.
        let factor = factor_of(&sys.symbolic, &sys.l_values).unwrap();
        let n = nb * nd;
        let shortest = (0..sys.z_rows.len())
            .map(|c| {
                factor
                    .path_rows(path(&sys.paths, &sys.path_start, c))
                    .map(|r| r.len())
                    .sum::<usize>()
            })
            .min()
            .unwrap();
        assert!(
            shortest < n / 4,
            "shortest path covers {shortest} of {n} rows"
        );
    }
}
