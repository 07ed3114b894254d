//! The iterative solve of large systems: conjugate gradients preconditioned by the
//! inverses of the blocks' diagonal terms (block Jacobi), started from a guess of the
//! motion, and stopped by a bound on the motion's error rather than on the force.
//!
//! The bound: K = K_o + S, with K_o block-diagonal, each block's own terms (its inertia
//! c/dt^2 M, elasticity and fixed-point springs; symmetric positive definite), and S
//! the springs and bolts between blocks, positive semi-definite; so K >= K_o. For the
//! error e = K^-1 r of the current iterate, with residual r,
//! e^T K_o e <= e^T K e = r^T K^-1 r <= r^T K_o^-1 r =: B. Each block's share of the left
//! side is at most B, so a point of block b moves in error by at most sqrt(reach_b B),
//! with reach_b the largest eigenvalue of T K_o,b^-1 T^T over the block's vertices (T
//! the displacement rows of a point). The solve stops when the largest reach times B is
//! within the tolerance squared: a stated bound on every vertex's motion, whatever the
//! conditioning. Since the diagonal blocks D of K exceed K_o too, r . D^-1 r <= B, so B
//! is computed only once the iteration's own r . D^-1 r allows it. (Until 2026-11-27 K_o
//! was the inertia alone: 2% to 4% more iterations, `docs/scaling.md`.)
//!
//! Every pass over the blocks (the products with K, the preconditioner, the updates of
//! the iterate) is taken in two halves of the blocks ([`Phase`]), on two threads when
//! [`BlockSystem::threads`] is set (`team`): each half writes its own rows, in the same
//! order either way, and the halves' sums are added in a fixed order, so the bits are
//! the same on one thread or two. A product's rows of one half read the other half's x
//! or p where a coupling crosses between them.
//!
//! Measured on matrices of the 826-, 3,472- and 10,131-block columns (cold starts, to a
//! relative error of 1e-9): 91, 95 and 97 iterations, about the same at every size: the
//! inertia keeps the system's condition bounded. A two-level correction by aggregates
//! of blocks cut the iterations to a half but not the matrix products (`docs/scaling.md`).

use super::BlockSystem;
use super::team::{Phase, with_team};
use crate::kinematics::{Mat6, Vec6};
use std::sync::{PoisonError, RwLock, RwLockReadGuard, RwLockWriteGuard};

/// The outcome of an iterative solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Iterated {
    /// Conjugate-gradient iterations taken.
    pub iterations: u32,
    /// Whether the bound on the motion's error was met.
    pub converged: bool,
    /// The bound reached: the largest error of a vertex's motion, in metres.
    pub bound: f64,
}

impl BlockSystem {
    /// Sets block `i`'s part of the start of the next iterative solve.
    pub fn set_start(&mut self, i: u32, d: &[f64]) {
        let nd = self.nd;
        let p = self.pos[i as usize] as usize;
        self.x[p * nd..(p + 1) * nd].copy_from_slice(&d[..nd]);
    }

    /// Sets each block's own terms of K (in block order, its leading `nd` x `nd` part
    /// read: symmetric positive definite, and K minus them positive semi-definite), the
    /// lower bound of K that the iterative solve's stop is stated in; kept until set
    /// again (it changes with dt and the blocks' shapes, once an attempt).
    pub fn set_lower_bound(&mut self, own: &[Mat6]) {
        let nd = self.nd;
        self.metric.resize(self.nb, [0.0; 21]);
        for (b, m) in own.iter().enumerate().take(self.nb) {
            let p = self.pos[b] as usize;
            self.metric[p] = inverse_of(m, nd);
        }
    }

    /// Solves K x = F by preconditioned conjugate gradients from the start in place (see
    /// [`BlockSystem::set_start`]; else the last solution), until every vertex's motion is
    /// within `tol` of the exact solution's by the bound of this module, or `max_iter`
    /// iterations. `reach` is the largest of the blocks' reaches, for the terms of
    /// [`BlockSystem::set_lower_bound`]. The solution is read with
    /// [`BlockSystem::solution`] either way.
    pub fn solve_iterative(&mut self, reach: f64, tol: f64, max_iter: u32) -> Iterated {
        let (nb, nd) = (self.nb, self.nd);
        let n = nb * nd;
        self.factored = false;
        let mut it = Iterated {
            iterations: 0,
            converged: true,
            bound: 0.0,
        };
        if n == 0 {
            return it;
        }
        self.seal();
        // The inverses of the diagonal blocks: the preconditioner D^-1, made again only
        // for the blocks whose diagonal changed since.
        let mut diag = std::mem::take(&mut self.diag_inverse);
        if diag.len() != nb {
            diag.resize(nb, [0.0; 21]);
            self.stale.fill(true);
        }
        let mut work = std::mem::take(&mut self.work);
        work.resize(5 * n, 0.0);
        let mut x = std::mem::take(&mut self.x);
        let view = self.product_view();
        let (half, split) = (view.half, view.half * nd);
        // Each half's own vectors, and x and p, which a product reads across the halves,
        // behind a lock per half (each phase only reads or only writes them: the locks
        // are never contended).
        let [r, z, p, q, w] = split5(&mut work, n);
        let (x0, x1) = x.split_at_mut(split);
        let (p0, p1) = p.split_at_mut(split);
        let shared = Shared {
            view,
            x: [RwLock::new(x0), RwLock::new(x1)],
            p: [RwLock::new(p0), RwLock::new(p1)],
        };
        let (d0, d1) = diag.split_at_mut(half);
        let halves = |v| halves(v, split);
        let ([r0, r1], [z0, z1], [q0, q1], [w0, w1]) = (halves(r), halves(z), halves(q), halves(w));
        let (rhs0, rhs1) = self.rhs.split_at(split);
        let (m0, m1) = self.metric.split_at(half.min(self.metric.len()));
        let (st0, st1) = self.stale.split_at(half);
        let mut first = Half {
            h: 0,
            diag: d0,
            stale: st0,
            metric: m0,
            rhs: rhs0,
            r: r0,
            z: z0,
            q: q0,
            w: w0,
        };
        let mut second = Half {
            h: 1,
            diag: d1,
            stale: st1,
            metric: m1,
            rhs: rhs1,
            r: r1,
            z: z1,
            q: q1,
            w: w1,
        };
        let shared = &shared;
        with_team(
            self.threads,
            |phase| second.run(phase, shared),
            |team| {
                let mut run = |phase: Phase| team.run(phase, |phase| first.run(phase, shared));
                // The bound on the motion's error of the current residual.
                let bound =
                    |run: &mut dyn FnMut(Phase) -> f64| (reach * run(Phase::Bound)).max(0.0).sqrt();
                run(Phase::Invert);
                let mut rz = run(Phase::Residual);
                let (mut rz_old, mut restart) = (rz, true);
                loop {
                    // D >= I (K >= I, block by block on the diagonal), so B = r^T I^-1 r >= r . z:
                    // B is worth computing only once reach r . z is within the tolerance.
                    if reach * rz <= tol * tol {
                        it.bound = bound(&mut run);
                        if it.bound <= tol {
                            // The recurrence's residual drifts from the true one: the stop is
                            // confirmed on the true residual, and the directions start again
                            // from it if it fails.
                            rz = run(Phase::Residual);
                            it.bound = bound(&mut run);
                            if it.bound <= tol {
                                break;
                            }
                            restart = true;
                        }
                    }
                    if it.iterations == max_iter || !rz.is_finite() {
                        it.converged = false;
                        it.bound = bound(&mut run);
                        break;
                    }
                    run(Phase::Turn((!restart).then(|| rz / rz_old)));
                    restart = false;
                    let pq = run(Phase::Product);
                    if pq.is_nan() || pq <= 0.0 {
                        it.converged = false;
                        it.bound = f64::INFINITY;
                        break;
                    }
                    let alpha = rz / pq;
                    rz_old = rz;
                    rz = run(Phase::Descend(alpha));
                    it.iterations += 1;
                }
            },
        );
        self.stale.fill(false);
        self.diag_inverse = diag;
        self.work = work;
        self.x = x;
        self.counters.iterative += 1;
        self.counters.cg_iterations += it.iterations as u64;
        it
    }

    /// Seals the couplings added since the matrix was cleared (see [`Couplings`]): a
    /// product reads them sealed.
    pub(super) fn seal(&mut self) {
        self.couplings
            .seal(self.nd, &self.col_start, &self.col_rows);
    }

    /// What a product with K reads.
    fn product_view(&self) -> ProductView<'_> {
        ProductView {
            nd: self.nd,
            nb: self.nb,
            half: self.nb / 2,
            values: &self.values,
            couplings: &self.couplings,
            col_start: &self.col_start,
            entry_col: &self.entry_col,
        }
    }

    /// y = K x (both halves, one after the other); returns x . y, the first half's sum
    /// plus the second's.
    #[cfg(test)]
    pub(super) fn multiply(&self, x: &[f64], y: &mut [f64]) -> f64 {
        let view = self.product_view();
        let split = view.half * self.nd;
        let x = x.split_at(split);
        let (y0, y1) = y.split_at_mut(split);
        let s0 = view.product(0, [x.0, x.1], y0);
        s0 + view.product(1, [x.0, x.1], y1)
    }
}

/// The five work vectors of an iterative solve, `n` values each.
fn split5(work: &mut [f64], n: usize) -> [&mut [f64]; 5] {
    let (r, rest) = work.split_at_mut(n);
    let (z, rest) = rest.split_at_mut(n);
    let (p, rest) = rest.split_at_mut(n);
    let (q, w) = rest.split_at_mut(n);
    [r, z, p, q, w]
}

/// `v` split after its first `split` values.
fn halves(v: &mut [f64], split: usize) -> [&mut [f64]; 2] {
    let (a, b) = v.split_at_mut(split);
    [a, b]
}

/// A vector's halves behind their locks.
type Locked<'a> = [RwLock<&'a mut [f64]>; 2];

/// Both halves of `v`, to read.
fn read_both<'s, 'a>(v: &'s Locked<'a>) -> [RwLockReadGuard<'s, &'a mut [f64]>; 2] {
    v.each_ref()
        .map(|h| h.read().unwrap_or_else(PoisonError::into_inner))
}

/// Half `h` of `v`, to write (each phase that writes a vector writes its own half
/// alone).
fn write_own<'s, 'a>(v: &'s Locked<'a>, h: usize) -> RwLockWriteGuard<'s, &'a mut [f64]> {
    v[h].write().unwrap_or_else(PoisonError::into_inner)
}

/// What both halves of a solve read: the matrix, and the halves of x and p.
struct Shared<'a> {
    view: ProductView<'a>,
    x: Locked<'a>,
    p: Locked<'a>,
}

/// One half of the blocks' own part of a solve: its preconditioner, which of its
/// diagonal blocks changed, its inertia inverses, right-hand side and work vectors.
struct Half<'a> {
    h: usize,
    diag: &'a mut [Packed],
    stale: &'a [bool],
    metric: &'a [Packed],
    rhs: &'a [f64],
    r: &'a mut [f64],
    z: &'a mut [f64],
    q: &'a mut [f64],
    w: &'a mut [f64],
}

impl Half<'_> {
    /// Runs `phase` over this half (see [`Phase`]); returns its sum.
    fn run(&mut self, phase: Phase, shared: &Shared) -> f64 {
        let view = &shared.view;
        let nd = view.nd;
        match phase {
            Phase::Invert => {
                let first = self.h * view.half;
                for (j, (d, &stale)) in self.diag.iter_mut().zip(self.stale).enumerate() {
                    if stale {
                        *d = inverse_of(&view.diagonal_block(first + j), nd);
                    }
                }
                0.0
            }
            Phase::Residual => {
                let x = read_both(&shared.x);
                view.product(self.h, [&x[0], &x[1]], self.q);
                for ((ri, fi), qi) in self.r.iter_mut().zip(self.rhs).zip(self.q.iter()) {
                    *ri = fi - qi;
                }
                apply_nd(self.diag, nd, self.r, self.z)
            }
            Phase::Bound => apply_nd(self.metric, nd, self.r, self.w),
            Phase::Turn(beta) => {
                let mut p = write_own(&shared.p, self.h);
                match beta {
                    None => p.copy_from_slice(self.z),
                    Some(beta) => {
                        for (pi, zi) in p.iter_mut().zip(self.z.iter()) {
                            *pi = zi + beta * *pi;
                        }
                    }
                }
                0.0
            }
            Phase::Product => {
                let p = read_both(&shared.p);
                view.product(self.h, [&p[0], &p[1]], self.q)
            }
            Phase::Descend(alpha) => {
                let mut x = write_own(&shared.x, self.h);
                let p = shared.p[self.h]
                    .read()
                    .unwrap_or_else(PoisonError::into_inner);
                for (xi, pi) in x.iter_mut().zip(p.iter()) {
                    *xi += alpha * pi;
                }
                for (ri, qi) in self.r.iter_mut().zip(self.q.iter()) {
                    *ri -= alpha * qi;
                }
                apply_nd(self.diag, nd, self.r, self.z)
            }
        }
    }
}

/// What a product with K reads: the diagonal blocks (`values`, each one's columns
/// together, in block order) and the couplings between blocks.
struct ProductView<'a> {
    nd: usize,
    nb: usize,
    /// The first block of the second half.
    half: usize,
    values: &'a [f64],
    couplings: &'a Couplings,
    col_start: &'a [usize],
    entry_col: &'a [usize],
}

impl ProductView<'_> {
    /// Block `j`'s diagonal block of K, in full.
    fn diagonal_block(&self, j: usize) -> Mat6 {
        let (nd, e) = (self.nd, self.col_start[j]);
        let mut k = [[0.0; 6]; 6];
        for q in 0..nd {
            let base = self.entry_col[e * nd + q];
            for (a, v) in self.values[base..base + nd - q].iter().enumerate() {
                k[q + a][q] = *v;
                k[q][q + a] = *v;
            }
        }
        k
    }

    /// Half `h`'s rows of y = K x into `y` (those rows alone), `x` given by halves;
    /// returns x . y over the rows.
    fn product(&self, h: usize, x: [&[f64]; 2], y: &mut [f64]) -> f64 {
        let rows = if h == 0 {
            0..self.half
        } else {
            self.half..self.nb
        };
        match self.nd {
            6 => self.product_rows::<6>(x, y, rows),
            3 => self.product_rows::<3>(x, y, rows),
            nd => unreachable!("blocks of {nd} unknowns"),
        }
    }

    /// Block `b` of `x`, given by halves.
    fn at<'x, const ND: usize>(&self, x: [&'x [f64]; 2], b: usize) -> &'x [f64; ND] {
        if b < self.half {
            block(x[0], b)
        } else {
            block(x[1], b - self.half)
        }
    }

    /// The block rows `rows` (the first or the second half of the blocks) of y = K x into
    /// `y` (those rows alone), for blocks of `ND` unknowns: the rank-one couplings first
    /// (both their rows where both blocks lie in `rows`, else the one that does), then the
    /// dense couplings from columns before `rows`, then the block columns `rows`, each
    /// dense coupling below the diagonal serving both its block rows (both lie in `rows`,
    /// unless a row of the second half below a column of the first: there only its
    /// transpose's share is taken). Returns x . y over the rows, each row's share taken
    /// once its column is done (the row is complete then).
    fn product_rows<const ND: usize>(
        &self,
        x: [&[f64]; 2],
        y: &mut [f64],
        rows: std::ops::Range<usize>,
    ) -> f64 {
        let first = rows.start;
        let second = first > 0;
        let cp = self.couplings;
        y.fill(0.0);
        // A rank-one term's products with the x of its two blocks.
        let dots = |c: &Coupling, xa: &[f64; ND], xb: &[f64; ND]| {
            let (mut da, mut db) = (0.0, 0.0);
            for k in 0..ND {
                da += c.su[k] * xa[k];
                db += c.v[k] * xb[k];
            }
            (da, db)
        };
        let scaled = |w: &Vec6, s: f64| std::array::from_fn::<f64, ND, _>(|k| w[k] * s);
        // The terms within this half: both rows ours, both blocks in this half's x.
        let own = x[usize::from(second)];
        for c in &cp.within[usize::from(second)] {
            let [a, b] = c.blocks.map(|b| b as usize - first);
            let (da, db) = dots(c, block(own, a), block(own, b));
            add_to(y, a, scaled(&c.su, db));
            add_to(y, b, scaled(&c.v, da));
        }
        // The terms across the halves: one row ours.
        for c in &cp.across {
            let [a, b] = c.blocks.map(|b| b as usize);
            let (da, db) = dots(c, self.at(x, a), self.at(x, b));
            if rows.contains(&a) {
                add_to(y, a - first, scaled(&c.su, db));
            } else {
                add_to(y, b - first, scaled(&c.v, da));
            }
        }
        // The dense couplings from the other half, so that each row is complete once its
        // own column is done, and its share of x . y is taken then.
        if second {
            for &(d, jb) in &cp.dense_across {
                let xj: &[f64; ND] = self.at(x, jb as usize);
                let values = cp.dense_block::<ND>(d as usize);
                let mut yi = [0.0f64; ND];
                for q in 0..ND {
                    let col: &[f64; ND] = block(values, q);
                    for a in 0..ND {
                        yi[a] += col[a] * xj[q];
                    }
                }
                add_to(y, cp.dense_rows[d as usize] as usize - first, yi);
            }
        }
        let mut xy = 0.0;
        // The diagonal blocks are stored in block order, each one's columns together: they
        // are read in one pass, with no offsets looked up.
        let tri = ND * (ND + 1) / 2;
        let mut off = first * tri;
        for jb in rows.clone() {
            let xj: [f64; ND] = *self.at(x, jb);
            let mut yj = [0.0f64; ND];
            // The diagonal block: column q's rows q.. of the block.
            for q in 0..ND {
                let col = &self.values[off..off + ND - q];
                off += ND - q;
                yj[q] += col[0] * xj[q];
                for a in 1..ND - q {
                    yj[q + a] += col[a] * xj[q];
                    yj[q] += col[a] * xj[q + a];
                }
            }
            for d in cp.dense_start[jb] as usize..cp.dense_start[jb + 1] as usize {
                let ib = cp.dense_rows[d] as usize;
                let xi: &[f64; ND] = self.at(x, ib);
                let values = cp.dense_block::<ND>(d);
                if ib >= rows.end {
                    // A row of the other half: only its transpose's share is ours.
                    for q in 0..ND {
                        let col: &[f64; ND] = block(values, q);
                        let mut acc = 0.0;
                        for a in 0..ND {
                            acc += col[a] * xi[a];
                        }
                        yj[q] += acc;
                    }
                    continue;
                }
                let mut yi = [0.0f64; ND];
                for q in 0..ND {
                    let col: &[f64; ND] = block(values, q);
                    let mut acc = 0.0;
                    for a in 0..ND {
                        yi[a] += col[a] * xj[q];
                        acc += col[a] * xi[a];
                    }
                    yj[q] += acc;
                }
                add_to(y, ib - first, yi);
            }
            add_to(y, jb - first, yj);
            let row: &[f64; ND] = block(y, jb - first);
            xy += (0..ND).map(|q| xj[q] * row[q]).sum::<f64>();
        }
        xy
    }
}

/// One term s u v^T of the couplings between two blocks (and its transpose): `s u`
/// over the unknowns of the first block, `v` over those of the second (positions in the
/// pattern's order).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Coupling {
    blocks: [u32; 2],
    su: Vec6,
    v: Vec6,
}

/// The couplings between blocks of a system solved iteratively: every term s u v^T
/// added off the diagonal (a contact's spring, a bolt), kept as it came until the solve
/// seals them. Sealed, the terms of a pair of blocks with at least nd / 2 of them (as many
/// values as a dense nd x nd block, or more) are summed into a dense block; the others
/// stay rank-one terms. A product with a rank-one term reads its 2 nd values and takes
/// 4 nd multiply-adds, with a dense block nd^2 values and 2 nd^2: between blocks of
/// frictionless contacts, which carry two springs (one at each vertex of their shared
/// edge) or none (a pair of the pattern not in contact), a product reads half the
/// values a dense block for every pair of the pattern took. Terms added after the seal
/// (the open-close iteration's changed springs) stay rank-one terms.
#[derive(Clone, Debug, Default)]
pub(crate) struct Couplings {
    /// The first block of the second half.
    half: u32,
    /// Terms added since the last reset, with their entries of the pattern, until sealed.
    pending: Vec<(u32, Coupling)>,
    sealed: bool,
    /// Per entry of the pattern: its terms, then its dense block (`u32::MAX`: none).
    count: Vec<u32>,
    /// The rank-one terms with both blocks in the first half, both in the second; and
    /// those with one in each.
    within: [Vec<Coupling>; 2],
    across: Vec<Coupling>,
    /// The dense blocks: per block (the earlier of the pair) the range of `dense_rows`
    /// of its dense blocks, and each one's later block; values `nd x nd` a block, its
    /// columns (over the earlier block's unknowns) together.
    dense_start: Vec<u32>,
    dense_rows: Vec<u32>,
    dense_values: Vec<f64>,
    /// The dense blocks whose earlier block lies in the first half and later in the
    /// second, with their earlier blocks: the second half's rows of a product read them.
    dense_across: Vec<(u32, u32)>,
}

impl Couplings {
    /// Empties the couplings of a pattern of `entries` entries, whose second half of the
    /// blocks starts at `half`.
    pub(crate) fn reset(&mut self, entries: usize, half: usize) {
        self.half = half as u32;
        self.pending.clear();
        self.sealed = false;
        self.count.clear();
        self.count.resize(entries, 0);
        self.within.iter_mut().for_each(Vec::clear);
        self.across.clear();
        self.dense_start.clear();
        self.dense_rows.clear();
        self.dense_values.clear();
        self.dense_across.clear();
    }

    /// Adds `s u v^T` between blocks `blocks` (positions: `u` over the first's unknowns,
    /// `v` over the second's), of entry `entry` of the pattern.
    pub(crate) fn add(&mut self, entry: usize, blocks: [u32; 2], s: f64, u: &Vec6, v: &Vec6) {
        let c = Coupling {
            blocks,
            su: u.map(|x| s * x),
            v: *v,
        };
        if self.sealed {
            self.keep(c);
        } else {
            self.pending.push((entry as u32, c));
        }
    }

    /// Keeps `c` as a rank-one term.
    fn keep(&mut self, c: Coupling) {
        let [a, b] = c.blocks.map(|b| b >= self.half);
        match (a, b) {
            (false, false) => self.within[0].push(c),
            (true, true) => self.within[1].push(c),
            _ => self.across.push(c),
        }
    }

    /// Dense block `d`'s values.
    fn dense_block<const ND: usize>(&self, d: usize) -> &[f64] {
        &self.dense_values[d * ND * ND..(d + 1) * ND * ND]
    }

    /// Seals the terms added since the last reset (see [`Couplings`]), in the order they
    /// were added, for blocks of `nd` unknowns and the pattern's block columns
    /// (`col_start`, `col_rows`: each column's diagonal entry, then its later blocks).
    pub(crate) fn seal(&mut self, nd: usize, col_start: &[usize], col_rows: &[u32]) {
        if self.sealed {
            return;
        }
        self.sealed = true;
        for &(e, _) in &self.pending {
            self.count[e as usize] += 1;
        }
        let dense_from = nd.div_ceil(2) as u32;
        let nb = col_start.len() - 1;
        self.dense_start.push(0);
        for jb in 0..nb {
            for e in col_start[jb] + 1..col_start[jb + 1] {
                if self.count[e] < dense_from {
                    self.count[e] = u32::MAX;
                    continue;
                }
                let (d, ib) = (self.dense_rows.len() as u32, col_rows[e]);
                self.count[e] = d;
                self.dense_rows.push(ib);
                if (jb as u32) < self.half && ib >= self.half {
                    self.dense_across.push((d, jb as u32));
                }
            }
            self.dense_start.push(self.dense_rows.len() as u32);
        }
        self.dense_values
            .resize(self.dense_rows.len() * nd * nd, 0.0);
        let pending = std::mem::take(&mut self.pending);
        for &(e, c) in &pending {
            let d = self.count[e as usize];
            if d == u32::MAX {
                self.keep(c);
                continue;
            }
            // Stored: rows of the later block, columns of the earlier.
            let [a, b] = c.blocks;
            let (rows, cols) = if a > b { (&c.su, &c.v) } else { (&c.v, &c.su) };
            let values = &mut self.dense_values[d as usize * nd * nd..(d as usize + 1) * nd * nd];
            for q in 0..nd {
                for r in 0..nd {
                    values[q * nd + r] += rows[r] * cols[q];
                }
            }
        }
        self.pending = pending;
        self.pending.clear();
    }
}

/// Adds `v` to block `b` of `y`.
fn add_to<const ND: usize>(y: &mut [f64], b: usize, v: [f64; ND]) {
    for (t, v) in y[b * ND..(b + 1) * ND].iter_mut().zip(v) {
        *t += v;
    }
}

/// Block `b` of `ND` values of `v`, as an array.
fn block<const ND: usize>(v: &[f64], b: usize) -> &[f64; ND] {
    v[b * ND..(b + 1) * ND]
        .try_into()
        .expect("a block of ND values")
}

/// A symmetric 6 x 6 block by its lower triangle, row by row: entry (i, k), k <= i, at
/// i (i + 1) / 2 + k, so that the leading 3 x 3 part comes first. 21 values instead of
/// 36: the preconditioner and the bound are read at every iteration, from memory.
pub(crate) type Packed = [f64; 21];

/// Where entry (i, k) of a symmetric block lies in its [`Packed`] form.
const fn packed(i: usize, k: usize) -> usize {
    if k <= i {
        i * (i + 1) / 2 + k
    } else {
        k * (k + 1) / 2 + i
    }
}

/// The inverse of the leading `nd` x `nd` part of a symmetric positive definite block
/// (the identity for a block that is not numerically positive definite), made
/// symmetric (the mean of its two triangles, which differ by rounding) and packed.
fn inverse_of(a: &Mat6, nd: usize) -> Packed {
    let l = chol(a, nd).unwrap_or_else(|| identity_chol(nd));
    let mut inv = [[0.0; 6]; 6];
    for j in 0..nd {
        let mut e = [0.0f64; 6];
        e[j] = 1.0;
        chol_solve(&l, nd, &mut e);
        for i in 0..nd {
            inv[i][j] = e[i];
        }
    }
    let mut out = [0.0; 21];
    for i in 0..nd {
        for k in 0..=i {
            out[packed(i, k)] = 0.5 * (inv[i][k] + inv[k][i]);
        }
    }
    out
}

/// z = A_b r_b block by block, for symmetric blocks `a` of `ND` unknowns; returns r . z.
fn apply_blocks<const ND: usize>(a: &[Packed], r: &[f64], z: &mut [f64]) -> f64 {
    let mut sum = 0.0;
    for ((m, rb), zb) in a.iter().zip(r.chunks_exact(ND)).zip(z.chunks_exact_mut(ND)) {
        let rb: &[f64; ND] = rb.try_into().expect("a block");
        for i in 0..ND {
            let mut acc = 0.0;
            for k in 0..ND {
                acc += m[packed(i, k)] * rb[k];
            }
            zb[i] = acc;
            sum += acc * rb[i];
        }
    }
    sum
}

/// [`apply_blocks`] for blocks of `nd` unknowns.
fn apply_nd(a: &[Packed], nd: usize, r: &[f64], z: &mut [f64]) -> f64 {
    match nd {
        6 => apply_blocks::<6>(a, r, z),
        3 => apply_blocks::<3>(a, r, z),
        nd => unreachable!("blocks of {nd} unknowns"),
    }
}

/// The Cholesky factor (lower, in place of a full matrix) of the leading `nd` x `nd` part
/// of symmetric `a`; None if it is not numerically positive definite.
pub(crate) fn chol(a: &Mat6, nd: usize) -> Option<Mat6> {
    let mut l = [[0.0; 6]; 6];
    for j in 0..nd {
        let d = a[j][j] - (0..j).map(|k| l[j][k] * l[j][k]).sum::<f64>();
        if d.is_nan() || d <= 0.0 {
            return None;
        }
        let ljj = d.sqrt();
        l[j][j] = ljj;
        for i in j + 1..nd {
            l[i][j] = (a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>()) / ljj;
        }
    }
    Some(l)
}

/// The identity's factor: the stand-in for a block whose term is not positive definite.
fn identity_chol(nd: usize) -> Mat6 {
    std::array::from_fn(|i| std::array::from_fn(|j| if i == j && i < nd { 1.0 } else { 0.0 }))
}

/// x <- L^-1 x for the `nd` unknowns of one block.
pub(crate) fn forward_solve(l: &Mat6, nd: usize, x: &mut [f64]) {
    for i in 0..nd {
        let s = x[i] - (0..i).map(|k| l[i][k] * x[k]).sum::<f64>();
        x[i] = s / l[i][i];
    }
}

/// x <- (L L^T)^-1 x for the `nd` unknowns of one block.
pub(crate) fn chol_solve(l: &Mat6, nd: usize, x: &mut [f64]) {
    forward_solve(l, nd, x);
    for i in (0..nd).rev() {
        let s = x[i] - (i + 1..nd).map(|k| l[k][i] * x[k]).sum::<f64>();
        x[i] = s / l[i][i];
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::{in_pool_of_two, rng};
    use super::*;
    use crate::kinematics::Vec6;

    /// An iterative system of `nb` blocks of `nd` unknowns coupled on `pairs`, cleared,
    /// and the zero dense matrix of its size.
    fn empty(nb: usize, nd: usize, pairs: &[(u32, u32)]) -> (BlockSystem, Vec<Vec<f64>>) {
        let mut sys = BlockSystem::iterative();
        sys.set_pattern(nb, nd, pairs).unwrap();
        sys.clear();
        let n = nb * nd;
        (sys, vec![vec![0.0; n]; n])
    }

    /// A chain of 12 blocks whose inertia terms (B B^T + I / 2, random B) are tied by stiff
    /// springs p c c^T (p = 1e3, random rows): K = I + springs >= I, as in the engine.
    /// Returns the system (assembled, inertia set), its inertia terms and the exact
    /// solution by dense elimination.
    fn chain(nd: usize) -> (BlockSystem, Vec<Mat6>, Vec<f64>) {
        let nb = 12;
        let mut pairs: Vec<(u32, u32)> = (0..nb as u32 - 1)
            .map(|i| (i, i + 1))
            .chain((0..nb as u32 - 3).map(|i| (i, i + 3)))
            .collect();
        pairs.sort_unstable();
        let (mut sys, mut dense) = empty(nb, nd, &pairs);
        let n = nb * nd;
        let mut rnd = rng(7);
        let mut inertia = Vec::new();
        for i in 0..nb {
            let b: Mat6 = std::array::from_fn(|_| std::array::from_fn(|_| rnd()));
            let mut m = [[0.0; 6]; 6];
            for a in 0..nd {
                for c in 0..nd {
                    m[a][c] = (0..nd).map(|k| b[a][k] * b[c][k]).sum::<f64>()
                        + if a == c { 0.5 } else { 0.0 };
                    dense[i * nd + a][i * nd + c] += m[a][c];
                }
            }
            sys.add_diagonal(i as u32, &m);
            inertia.push(m);
        }
        for &(i, j) in &pairs {
            let u: Vec6 = std::array::from_fn(|_| rnd());
            let v: Vec6 = std::array::from_fn(|_| rnd());
            let p = 1e3;
            let (iu, ju) = (i as usize, j as usize);
            sys.add_outer(sys.diagonal(i), i, i, p, &u, &u);
            sys.add_outer(sys.diagonal(j), j, j, p, &v, &v);
            sys.add_outer(sys.entry(i, j).unwrap(), i, j, p, &u, &v);
            for a in 0..nd {
                for c in 0..nd {
                    dense[iu * nd + a][iu * nd + c] += p * u[a] * u[c];
                    dense[ju * nd + a][ju * nd + c] += p * v[a] * v[c];
                    dense[iu * nd + a][ju * nd + c] += p * u[a] * v[c];
                    dense[ju * nd + c][iu * nd + a] += p * u[a] * v[c];
                }
            }
        }
        let f: Vec<f64> = (0..n).map(|_| rnd()).collect();
        for i in 0..nb {
            let fi: Vec6 = std::array::from_fn(|a| if a < nd { f[i * nd + a] } else { 0.0 });
            sys.add_rhs(i as u32, 1.0, &fi);
        }
        sys.set_lower_bound(&inertia);
        (sys, inertia, dense_solve(dense, f))
    }

    /// The iterative solve stops with the inertia-weighted error of the exact solution
    /// within the bound it reports and the bound within its tolerance, after more than a
    /// few iterations.
    #[test]
    fn iterative_solve_meets_its_bound_on_the_motion() {
        for nd in [3usize, 6] {
            let (mut sys, inertia, exact) = chain(nd);
            let tol = 1e-9 * exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let out = sys.solve_iterative(1.0, tol, 10_000);
            assert!(out.converged && out.iterations > 5, "nd {nd}: {out:?}");
            let mut err_i = 0.0;
            for (i, m) in inertia.iter().enumerate() {
                let e: Vec<f64> = (0..nd)
                    .map(|a| sys.solution(i as u32)[a] - exact[i * nd + a])
                    .collect();
                for a in 0..nd {
                    for c in 0..nd {
                        err_i += e[a] * m[a][c] * e[c];
                    }
                }
            }
            assert!(
                err_i.sqrt() <= out.bound && out.bound <= tol,
                "nd {nd}: error {} against bound {} and tolerance {tol}",
                err_i.sqrt(),
                out.bound
            );
        }
    }

    /// On two threads the iterative solve gives the same bits as on one.
    #[test]
    fn iterative_solve_is_the_same_on_two_threads() {
        let solve = |threads: bool| {
            let (mut sys, _, exact) = chain(6);
            sys.threads = threads;
            let tol = 1e-9 * exact.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let out = sys.solve_iterative(1.0, tol, 10_000);
            let x: Vec<u64> = (0..12u32)
                .flat_map(|i| sys.solution(i).to_vec())
                .map(f64::to_bits)
                .collect();
            (out.iterations, x)
        };
        assert_eq!(in_pool_of_two(|| solve(true)), solve(false));
    }

    /// A spring added to the assembled matrix (`BlockSystem::add_rank_one`) changes its
    /// product with any x by s u (u . x), u the spring's row over both blocks, computed
    /// here densely; both orders of the blocks, blocks of 3 and 6 unknowns, and a
    /// spring against a fixed block.
    #[test]
    fn a_spring_added_to_the_matrix_changes_its_product_by_its_own() {
        use crate::solver::RankOne;
        for nd in [3usize, 6] {
            for blocks in [[Some(2), Some(5)], [Some(5), Some(2)], [None, Some(7)]] {
                let (mut sys, _, _) = chain(nd);
                let n = 12 * nd;
                let mut rnd = rng(11);
                let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
                let c: [Vec6; 2] = std::array::from_fn(|_| std::array::from_fn(|_| rnd()));
                let t = RankOne { blocks, c, s: 3e2 };
                // u over all unknowns (sys.x's order is the pattern's: block order).
                let mut u = vec![0.0; n];
                for (b, cb) in blocks.iter().zip(&c) {
                    if let Some(b) = b {
                        let p = sys.pos[*b as usize] as usize;
                        u[p * nd..(p + 1) * nd].copy_from_slice(&cb[..nd]);
                    }
                }
                let ux: f64 = u.iter().zip(&x).map(|(a, b)| a * b).sum();
                let mut before = vec![0.0; n];
                sys.seal();
                sys.multiply(&x, &mut before);
                sys.add_rank_one(&t);
                let mut after = vec![0.0; n];
                sys.multiply(&x, &mut after);
                let scale = before.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for i in 0..n {
                    let want = before[i] + t.s * u[i] * ux;
                    assert!(
                        (after[i] - want).abs() <= 1e-12 * scale,
                        "nd {nd}, blocks {blocks:?}, row {i}: {} against {want}",
                        after[i]
                    );
                }
            }
        }
    }

    /// A product with K equals the dense matrix's, whatever the couplings' form: pairs of
    /// blocks with one to four terms (kept rank-one below nd / 2 terms, summed into a
    /// dense block from there), pairs within either half of the blocks and across them,
    /// and terms added after the seal; the same bits on one thread and two. Fails when a
    /// dense block's orientation, a half's share of a term across the halves, or the
    /// count that decides the form is wrong.
    #[test]
    fn a_product_with_the_couplings_is_the_dense_matrix_s() {
        for nd in [3usize, 6] {
            let nb = 10;
            let pairs: Vec<(u32, u32)> = vec![
                (0, 1),
                (0, 7),
                (1, 2),
                (2, 6),
                (3, 4),
                (4, 9),
                (5, 6),
                (6, 8),
                (7, 8),
            ];
            let (mut sys, mut dense) = empty(nb, nd, &pairs);
            let n = nb * nd;
            let mut rnd = rng(5);
            let mut term = |sys: &mut BlockSystem, dense: &mut Vec<Vec<f64>>, i: u32, j: u32| {
                let u: Vec6 = std::array::from_fn(|k| if k < nd { rnd() } else { 0.0 });
                let v: Vec6 = std::array::from_fn(|k| if k < nd { rnd() } else { 0.0 });
                let s = 1.0 + rnd();
                sys.add_outer(sys.entry(i, j).unwrap(), i, j, s, &u, &v);
                let (i, j) = (i as usize, j as usize);
                for a in 0..nd {
                    for c in 0..nd {
                        dense[i * nd + a][j * nd + c] += s * u[a] * v[c];
                        dense[j * nd + c][i * nd + a] += s * u[a] * v[c];
                    }
                }
            };
            for i in 0..nb as u32 {
                let k: Mat6 = std::array::from_fn(|a| {
                    std::array::from_fn(|c| if a == c { 5.0 } else { 0.1 })
                });
                sys.add_diagonal(i, &k);
                for a in 0..nd {
                    for c in 0..nd {
                        dense[i as usize * nd + a][i as usize * nd + c] += k[a][c];
                    }
                }
            }
            // Pair k gets k % 4 + 1 terms, in either order of its blocks.
            for (k, &(i, j)) in pairs.iter().enumerate() {
                for t in 0..=k % 4 {
                    let (a, b) = if t % 2 == 0 { (i, j) } else { (j, i) };
                    term(&mut sys, &mut dense, a, b);
                }
            }
            sys.seal();
            let dense_pairs = sys.couplings.dense_rows.len();
            let expect = (0..pairs.len())
                .filter(|k| k % 4 + 1 >= nd.div_ceil(2))
                .count();
            assert_eq!(dense_pairs, expect, "nd {nd}: dense blocks");
            term(&mut sys, &mut dense, 7, 0);
            term(&mut sys, &mut dense, 4, 9);
            let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let mut y1 = vec![0.0; n];
            sys.threads = false;
            let xy1 = sys.multiply(&x, &mut y1);
            let mut y2 = vec![0.0; n];
            sys.threads = true;
            let xy2 = sys.multiply(&x, &mut y2);
            assert_eq!(
                (y1.clone(), xy1.to_bits()),
                (y2, xy2.to_bits()),
                "nd {nd}: threads"
            );
            for r in 0..n {
                let want: f64 = (0..n).map(|c| dense[r][c] * x[c]).sum();
                assert!(
                    (y1[r] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "nd {nd}, row {r}: {} against {want}",
                    y1[r]
                );
            }
            let want: f64 = (0..n).map(|r| x[r] * y1[r]).sum();
            assert!((xy1 - want).abs() <= 1e-12 * (1.0 + want.abs()));
        }
    }

    /// Gaussian elimination with partial pivoting.
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for c in 0..n {
            let p = (c..n)
                .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
                .unwrap();
            a.swap(c, p);
            b.swap(c, p);
            for r in c + 1..n {
                let f = a[r][c] / a[c][c];
                for k in c..n {
                    a[r][k] -= f * a[c][k];
                }
                b[r] -= f * b[c];
            }
        }
        let mut x = vec![0.0; n];
        for r in (0..n).rev() {
            x[r] = (b[r] - (r + 1..n).map(|k| a[r][k] * x[k]).sum::<f64>()) / a[r][r];
        }
        x
    }
}
