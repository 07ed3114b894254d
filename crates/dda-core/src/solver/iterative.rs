//! The iterative solve of large systems: conjugate gradients on the system scaled by
//! the factors of its diagonal blocks, started from a guess of the motion, and stopped
//! by a bound on the motion's error rather than on the force.
//!
//! The scaling: with each block's diagonal block D_b = L_b L_b^T (Cholesky), CG runs on
//! (L^-1 K L^-T) (L^T x) = L^-1 F, whose diagonal blocks are the identity. In exact
//! arithmetic its iterates are those of CG on K preconditioned by D^-1 (block Jacobi),
//! but an iteration reads neither the diagonal blocks nor their inverses, nor keeps
//! z = D^-1 r: the scaled couplings (each term s u v^T between blocks a and b becomes
//! s (L_a^-1 u) (L_b^-1 v)^T, made once a solve) are all a product reads. On the
//! 111,460-block column an iteration took 4.6 ms against 7.3 ms (`docs/scaling.md`).
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
//! conditioning. The scaled system's residual is r~ = L^-1 r, so r = L r~ for B; and
//! since the diagonal blocks D of K exceed K_o too, r~ . r~ = r^T D^-1 r <= B, so B is
//! computed only once the iteration's own r~ . r~ allows it. (Until 2026-11-27 K_o
//! was the inertia alone: 2% to 4% more iterations, `docs/scaling.md`.)
//!
//! Every pass over the blocks (the products with the scaled K, the updates of the
//! iterate) is taken in two halves of the blocks ([`Phase`]), on two threads when
//! [`BlockSystem::threads`] is set (`team`): each half writes its own rows, in the same
//! order either way, and the halves' sums are added in a fixed order, so the bits are
//! the same on one thread or two. A product's rows of one half read the other half's x
//! or p where a coupling crosses between them. The factors and the scaled terms are
//! made by halves too, each term the same bits whichever thread makes it.
//!
//! Measured on matrices of the 826-, 3,472- and 10,131-block columns (cold starts, to a
//! relative error of 1e-9): 91, 95 and 97 iterations, about the same at every size: the
//! inertia keeps the system's condition bounded. A two-level correction by aggregates
//! of blocks cut the iterations to a half but not the matrix products (`docs/scaling.md`).

use super::BlockSystem;
use super::team::{Phase, both, with_team};
use crate::kinematics::{Mat6, Vec6};
use std::sync::{PoisonError, RwLock, RwLockReadGuard, RwLockWriteGuard};

/// How far, in squares, the bound predicted from the last one's ratio to the scaled
/// residual's square may lie above the tolerance and still be computed: each bound is a
/// pass over the residual, the blocks' factors and their own terms' inverses, and
/// computed whenever r~ . r~ allowed it, it was 11.6 passes a solve of 61.7 iterations
/// on the 10,131-block column; 6.1 with this slack, the same iterations and bits
/// (`docs/scaling.md`). A prediction too high delays the stop by an iteration or so
/// (6.1 against 4.6 passes with a slack of 2, which took some solves an iteration
/// more); never does it let a solve stop early.
const BOUND_SLACK: f64 = 4.0;

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
        // The diagonal blocks' factors D_b = L_b L_b^T, made again only for the blocks
        // whose diagonal changed since.
        let mut factors = std::mem::take(&mut self.factors);
        if factors.len() != nb {
            factors.resize(nb, [0.0; 21]);
            self.stale.fill(true);
        }
        // Each half's blocks factorised (on two threads where set); true if all were
        // positive definite.
        let factorise = |factors: &mut [Packed], stale: &[bool], first: usize| {
            let mut definite = true;
            for (j, (l, &stale)) in factors.iter_mut().zip(stale).enumerate() {
                if stale {
                    match cholesky(&self.diagonal_block(first + j), nd) {
                        Some(f) => *l = f,
                        None => definite = false,
                    }
                }
            }
            definite
        };
        let half = nb / 2;
        let (l0, l1) = factors.split_at_mut(half);
        let (st0, st1) = self.stale.split_at(half);
        let mut definite = [true; 2];
        let [d0, d1] = &mut definite;
        both(
            self.threads,
            || *d1 = factorise(l1, st1, half),
            || *d0 = factorise(l0, st0, 0),
        );
        if definite != [true; 2] {
            // K is not numerically positive definite: no solve (the blocks whose factor
            // failed are factorised again at the next solve).
            self.factors = factors;
            self.counters.iterative += 1;
            it.converged = false;
            it.bound = f64::INFINITY;
            return it;
        }
        // The couplings of the scaled system L^-1 K L^-T, whose diagonal blocks are the
        // identity.
        let mut scaled = std::mem::take(&mut self.scaled);
        self.couplings
            .scale_into(&factors, nd, self.threads, &mut scaled);
        let mut work = std::mem::take(&mut self.work);
        work.resize(4 * n, 0.0);
        let mut x = std::mem::take(&mut self.x);
        let view = ProductView {
            values: None,
            terms: &scaled,
            ..self.product_view()
        };
        let (half, split) = (view.half, view.half * nd);
        // Each half's own vectors, and x and p, which a product reads across the halves,
        // behind a lock per half (each phase only reads or only writes them: the locks
        // are never contended).
        let [f, r, p, q] = split4(&mut work, n);
        let (x0, x1) = x.split_at_mut(split);
        let (p0, p1) = p.split_at_mut(split);
        let shared = Shared {
            view,
            x: [RwLock::new(x0), RwLock::new(x1)],
            p: [RwLock::new(p0), RwLock::new(p1)],
        };
        let (l0, l1) = factors.split_at(half);
        let halves = |v| halves(v, split);
        let ([f0, f1], [r0, r1], [q0, q1]) = (halves(f), halves(r), halves(q));
        let (rhs0, rhs1) = self.rhs.split_at(split);
        let (m0, m1) = self.metric.split_at(half.min(self.metric.len()));
        let mut first = Half {
            h: 0,
            factors: l0,
            metric: m0,
            rhs: rhs0,
            f: f0,
            r: r0,
            q: q0,
        };
        let mut second = Half {
            h: 1,
            factors: l1,
            metric: m1,
            rhs: rhs1,
            f: f1,
            r: r1,
            q: q1,
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
                run(Phase::Scale);
                let mut rr = run(Phase::Residual);
                let (mut rr_old, mut restart) = (rr, true);
                // B / (r~ . r~) at the last B computed (at least 1, below).
                let mut ratio = 1.0f64;
                loop {
                    // D >= K_o (block by block on the diagonal), so B = r^T K_o^-1 r >=
                    // r^T D^-1 r = r~ . r~ (r~ = L^-1 r, the scaled system's residual): B
                    // is worth computing only once reach r~ . r~ is within the tolerance,
                    // and, predicted by the last B's ratio, within BOUND_SLACK of it.
                    let predicted = rr * (ratio / BOUND_SLACK).max(1.0);
                    if reach * predicted <= tol * tol {
                        it.bound = bound(&mut run);
                        if rr > 0.0 {
                            ratio = it.bound * it.bound / (reach * rr);
                        }
                        if it.bound <= tol {
                            // The recurrence's residual drifts from the true one: the stop is
                            // confirmed on the true residual, and the directions start again
                            // from it if it fails.
                            rr = run(Phase::Residual);
                            it.bound = bound(&mut run);
                            if it.bound <= tol {
                                break;
                            }
                            restart = true;
                        }
                    }
                    if it.iterations == max_iter || !rr.is_finite() {
                        it.converged = false;
                        it.bound = bound(&mut run);
                        break;
                    }
                    run(Phase::Turn((!restart).then(|| rr / rr_old)));
                    restart = false;
                    let pq = run(Phase::Product);
                    if pq.is_nan() || pq <= 0.0 {
                        it.converged = false;
                        it.bound = f64::INFINITY;
                        break;
                    }
                    let alpha = rr / pq;
                    rr_old = rr;
                    rr = run(Phase::Descend(alpha));
                    it.iterations += 1;
                }
                run(Phase::Unscale);
            },
        );
        self.stale.fill(false);
        self.factors = factors;
        self.scaled = scaled;
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

    /// Block position `j`'s diagonal block of K, in full.
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

    /// What a product with K reads.
    fn product_view(&self) -> ProductView<'_> {
        ProductView {
            nd: self.nd,
            nb: self.nb,
            half: self.nb / 2,
            values: Some(&self.values),
            couplings: &self.couplings,
            terms: &self.couplings.terms,
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

/// The four work vectors of an iterative solve, `n` values each.
fn split4(work: &mut [f64], n: usize) -> [&mut [f64]; 4] {
    let (f, rest) = work.split_at_mut(n);
    let (r, rest) = rest.split_at_mut(n);
    let (p, q) = rest.split_at_mut(n);
    [f, r, p, q]
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

/// One half of the blocks' own part of a solve: the factors of its diagonal blocks,
/// the inverses of its blocks' own terms (the bound), its right-hand side and work
/// vectors (the scaled system's right-hand side, residual and product).
struct Half<'a> {
    h: usize,
    factors: &'a [Packed],
    metric: &'a [Packed],
    rhs: &'a [f64],
    f: &'a mut [f64],
    r: &'a mut [f64],
    q: &'a mut [f64],
}

impl Half<'_> {
    /// Runs `phase` over this half (see [`Phase`]); returns its sum.
    fn run(&mut self, phase: Phase, shared: &Shared) -> f64 {
        let view = &shared.view;
        match view.nd {
            6 => self.run_nd::<6>(phase, shared),
            3 => self.run_nd::<3>(phase, shared),
            nd => unreachable!("blocks of {nd} unknowns"),
        }
    }

    /// [`Half::run`] for blocks of `ND` unknowns.
    fn run_nd<const ND: usize>(&mut self, phase: Phase, shared: &Shared) -> f64 {
        let view = &shared.view;
        match phase {
            Phase::Scale => {
                // f~ = L^-1 F, x~ = L^T x.
                let mut x = write_own(&shared.x, self.h);
                for (b, l) in self.factors.iter().enumerate() {
                    let fb = block_mut::<ND>(self.f, b);
                    fb.copy_from_slice(block::<ND>(self.rhs, b));
                    lower_solve(l, fb);
                    upper_mul(l, block_mut::<ND>(&mut x, b));
                }
                0.0
            }
            Phase::Unscale => {
                // x = L^-T x~.
                let mut x = write_own(&shared.x, self.h);
                for (b, l) in self.factors.iter().enumerate() {
                    upper_solve(l, block_mut::<ND>(&mut x, b));
                }
                0.0
            }
            Phase::Residual => {
                let x = read_both(&shared.x);
                view.product(self.h, [&x[0], &x[1]], self.q);
                let mut rr = 0.0;
                for ((ri, fi), qi) in self.r.iter_mut().zip(self.f.iter()).zip(self.q.iter()) {
                    *ri = fi - qi;
                    rr += *ri * *ri;
                }
                rr
            }
            Phase::Bound => {
                // r = L r~, and r^T K_o^-1 r.
                let mut sum = 0.0;
                for ((l, m), rb) in self
                    .factors
                    .iter()
                    .zip(self.metric)
                    .zip(self.r.chunks_exact(ND))
                {
                    let mut t: [f64; ND] = *block::<ND>(rb, 0);
                    lower_mul(l, &mut t);
                    sum += quadratic(m, &t);
                }
                sum
            }
            Phase::Turn(beta) => {
                let mut p = write_own(&shared.p, self.h);
                match beta {
                    None => p.copy_from_slice(self.r),
                    Some(beta) => {
                        for (pi, ri) in p.iter_mut().zip(self.r.iter()) {
                            *pi = ri + beta * *pi;
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
                let mut rr = 0.0;
                for (ri, qi) in self.r.iter_mut().zip(self.q.iter()) {
                    *ri -= alpha * qi;
                    rr += *ri * *ri;
                }
                rr
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
    /// The diagonal blocks (None: the identity, as in the scaled system).
    values: Option<&'a [f64]>,
    /// The couplings' pattern, and the values of their terms (the couplings' own, or the
    /// scaled system's).
    couplings: &'a Couplings,
    terms: &'a Terms,
}

impl ProductView<'_> {
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
        for c in &self.terms.within[usize::from(second)] {
            let [a, b] = c.blocks.map(|b| b as usize - first);
            let (da, db) = dots(c, block(own, a), block(own, b));
            add_to(y, a, scaled(&c.su, db));
            add_to(y, b, scaled(&c.v, da));
        }
        // The terms across the halves: one row ours.
        for c in &self.terms.across {
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
                let values = self.terms.dense_block::<ND>(d as usize);
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
            match self.values {
                // The diagonal block: column q's rows q.. of the block.
                Some(values) => {
                    for q in 0..ND {
                        let col = &values[off..off + ND - q];
                        off += ND - q;
                        yj[q] += col[0] * xj[q];
                        for a in 1..ND - q {
                            yj[q + a] += col[a] * xj[q];
                            yj[q] += col[a] * xj[q + a];
                        }
                    }
                }
                None => yj = xj,
            }
            for d in cp.dense_start[jb] as usize..cp.dense_start[jb + 1] as usize {
                let ib = cp.dense_rows[d] as usize;
                let xi: &[f64; ND] = self.at(x, ib);
                let values = self.terms.dense_block::<ND>(d);
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
#[derive(Clone, Copy, Debug, Default)]
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
    /// The terms' values: the rank-one terms and the dense blocks' values.
    terms: Terms,
    /// The dense blocks: per block (the earlier of the pair) the range of `dense_rows`
    /// of its dense blocks, and each one's later block (their values in `terms`).
    dense_start: Vec<u32>,
    dense_rows: Vec<u32>,
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
        self.terms.within.iter_mut().for_each(Vec::clear);
        self.terms.across.clear();
        self.dense_start.clear();
        self.dense_rows.clear();
        self.terms.dense_values.clear();
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
            (false, false) => self.terms.within[0].push(c),
            (true, true) => self.terms.within[1].push(c),
            _ => self.terms.across.push(c),
        }
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
        self.terms
            .dense_values
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
            let values =
                &mut self.terms.dense_values[d as usize * nd * nd..(d as usize + 1) * nd * nd];
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

/// The values of the couplings' terms (their blocks and pattern in [`Couplings`]).
#[derive(Clone, Debug, Default)]
pub(crate) struct Terms {
    /// The rank-one terms with both blocks in the first half, both in the second; and
    /// those with one in each.
    within: [Vec<Coupling>; 2],
    across: Vec<Coupling>,
    /// The dense blocks' values, `nd x nd` a block, its columns (over the earlier block's
    /// unknowns) together.
    dense_values: Vec<f64>,
}

impl Terms {
    /// Dense block `d`'s values.
    fn dense_block<const ND: usize>(&self, d: usize) -> &[f64] {
        &self.dense_values[d * ND * ND..(d + 1) * ND * ND]
    }
}

impl Couplings {
    /// The terms of the scaled system L^-1 K L^-T into `out`, for the factors `l` of the
    /// diagonal blocks (in block order): a term s u v^T between blocks a and b becomes
    /// s (L_a^-1 u) (L_b^-1 v)^T, a dense block B of a later block i and an earlier j
    /// becomes L_i^-1 B L_j^-T. The first half's terms and the second's are scaled at
    /// once when `threads` is set (each term the same bits either way).
    pub(crate) fn scale_into(&self, l: &[Packed], nd: usize, threads: bool, out: &mut Terms) {
        match nd {
            6 => self.scale::<6>(l, threads, out),
            3 => self.scale::<3>(l, threads, out),
            nd => unreachable!("blocks of {nd} unknowns"),
        }
    }

    /// [`Couplings::scale_into`] for blocks of `ND` unknowns.
    fn scale<const ND: usize>(&self, l: &[Packed], threads: bool, out: &mut Terms) {
        let terms = &self.terms;
        // The rank-one terms are written scaled from the couplings' own (the lists only
        // fitted to their lengths here); the dense blocks are copied, then scaled.
        for h in 0..2 {
            out.within[h].resize(terms.within[h].len(), Coupling::default());
        }
        out.across.resize(terms.across.len(), Coupling::default());
        out.dense_values.clone_from(&terms.dense_values);
        let Terms {
            within: [w0, w1],
            across,
            dense_values,
        } = out;
        let mid = across.len() / 2;
        let (a0, a1) = across.split_at_mut(mid);
        let (s0, s1) = terms.across.split_at(mid);
        // The dense blocks of the first half's block columns, then the second's.
        let nb = self.dense_start.len().saturating_sub(1);
        let half = (self.half as usize).min(nb);
        let cut = self.dense_start.get(half).map_or(0, |&d| d as usize);
        let (v0, v1) = dense_values.split_at_mut(cut * ND * ND);
        let rank_one = |own: &[Coupling], scaled: &mut [Coupling]| {
            for (c, t) in own.iter().zip(scaled) {
                *t = *c;
                let [a, b] = c.blocks.map(|b| b as usize);
                lower_solve::<ND>(&l[a], block_mut::<ND>(&mut t.su, 0));
                lower_solve::<ND>(&l[b], block_mut::<ND>(&mut t.v, 0));
            }
        };
        let dense = |values: &mut [f64], columns: std::ops::Range<usize>| {
            let first = self
                .dense_start
                .get(columns.start)
                .map_or(0, |&d| d as usize);
            for jb in columns {
                for d in self.dense_start[jb] as usize..self.dense_start[jb + 1] as usize {
                    let ib = self.dense_rows[d] as usize;
                    let at = (d - first) * ND * ND;
                    let values = &mut values[at..at + ND * ND];
                    // Its columns (over block j's unknowns) by L_i^-1, then its rows by
                    // L_j^-1.
                    for q in 0..ND {
                        lower_solve::<ND>(&l[ib], block_mut::<ND>(values, q));
                    }
                    for r in 0..ND {
                        let mut row: [f64; ND] = std::array::from_fn(|q| values[q * ND + r]);
                        lower_solve::<ND>(&l[jb], &mut row);
                        for (q, v) in row.into_iter().enumerate() {
                            values[q * ND + r] = v;
                        }
                    }
                }
            }
        };
        both(
            threads,
            || {
                rank_one(&terms.within[1], w1);
                rank_one(s1, a1);
                dense(v1, half..nb);
            },
            || {
                rank_one(&terms.within[0], w0);
                rank_one(s0, a0);
                dense(v0, 0..half);
            },
        );
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

/// A symmetric 6 x 6 block, or a lower triangular one, by its lower triangle, row by
/// row: entry (i, k), k <= i, at i (i + 1) / 2 + k, so that the leading 3 x 3 part comes
/// first. 21 values instead of 36 (the diagonal blocks' factors, the bound's inverses).
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

/// The Cholesky factor L (lower, packed: entry (i, k), k <= i, where [`packed`] puts
/// it) of the leading `nd` x `nd` part of symmetric `a`; None if it is not numerically
/// positive definite.
fn cholesky(a: &Mat6, nd: usize) -> Option<Packed> {
    let l = chol(a, nd)?;
    let mut out = [0.0; 21];
    for i in 0..nd {
        for k in 0..=i {
            out[packed(i, k)] = l[i][k];
        }
    }
    Some(out)
}

/// x <- L^-1 x for a packed lower factor.
fn lower_solve<const ND: usize>(l: &Packed, x: &mut [f64; ND]) {
    for i in 0..ND {
        let mut s = x[i];
        for k in 0..i {
            s -= l[packed(i, k)] * x[k];
        }
        x[i] = s / l[packed(i, i)];
    }
}

/// x <- L^-T x for a packed lower factor.
fn upper_solve<const ND: usize>(l: &Packed, x: &mut [f64; ND]) {
    for i in (0..ND).rev() {
        let mut s = x[i];
        for k in i + 1..ND {
            s -= l[packed(k, i)] * x[k];
        }
        x[i] = s / l[packed(i, i)];
    }
}

/// x <- L^T x for a packed lower factor (row i reads x's entries from i on, not yet
/// overwritten).
fn upper_mul<const ND: usize>(l: &Packed, x: &mut [f64; ND]) {
    for i in 0..ND {
        let mut s = 0.0;
        for k in i..ND {
            s += l[packed(k, i)] * x[k];
        }
        x[i] = s;
    }
}

/// x <- L x for a packed lower factor (row i reads x's entries up to i, not yet
/// overwritten).
fn lower_mul<const ND: usize>(l: &Packed, x: &mut [f64; ND]) {
    for i in (0..ND).rev() {
        let mut s = 0.0;
        for k in 0..=i {
            s += l[packed(i, k)] * x[k];
        }
        x[i] = s;
    }
}

/// t^T M t for a packed symmetric M.
fn quadratic<const ND: usize>(m: &Packed, t: &[f64; ND]) -> f64 {
    let mut sum = 0.0;
    for i in 0..ND {
        let mut acc = 0.0;
        for k in 0..ND {
            acc += m[packed(i, k)] * t[k];
        }
        sum += acc * t[i];
    }
    sum
}

/// Block `b` of `ND` values of `v`, to write.
fn block_mut<const ND: usize>(v: &mut [f64], b: usize) -> &mut [f64; ND] {
    (&mut v[b * ND..(b + 1) * ND])
        .try_into()
        .expect("a block of ND values")
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

    /// Ten blocks of `nd` unknowns coupled in pairs with one to four terms each (kept
    /// rank-one below nd / 2 terms, summed into a dense block from there), within either
    /// half of the blocks and across them, sealed, then two terms more; with the dense
    /// matrix of the same terms.
    fn coupled(nd: usize) -> (BlockSystem, Vec<Vec<f64>>) {
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
                // Diagonally dominant, and another for each block.
                let i = f64::from(i);
                std::array::from_fn(|c| {
                    if a == c {
                        5.0 + a as f64 + 0.5 * i
                    } else {
                        0.1 * (a + c) as f64 + 0.01 * i
                    }
                })
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
        (sys, dense)
    }

    /// A product with K equals the dense matrix's, whatever the couplings' form (see
    /// [`coupled`]); the same bits on one thread and two. Fails when a dense block's
    /// orientation, a half's share of a term across the halves, or the count that decides
    /// the form is wrong.
    #[test]
    fn a_product_with_the_couplings_is_the_dense_matrix_s() {
        for nd in [3usize, 6] {
            let (mut sys, dense) = coupled(nd);
            let n = sys.nb * nd;
            let mut rnd = rng(9);
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

    /// The scaled system's product, the identity on the diagonal and the scaled terms off
    /// it, is L^-1 K L^-T x with L the blocks' factors, here computed densely: K's
    /// product with L^-T x, then L^-1 of it. The same bits scaled on one thread and two.
    /// Fails when a rank-one term's or a dense block's scaling takes the wrong factor or
    /// side.
    #[test]
    fn the_scaled_system_s_product_is_k_between_the_inverse_factors() {
        for nd in [3usize, 6] {
            let (sys, dense) = coupled(nd);
            let (nb, n) = (sys.nb, sys.nb * nd);
            let factors: Vec<Packed> = (0..nb)
                .map(|j| cholesky(&sys.diagonal_block(j), nd).unwrap())
                .collect();
            let scale = |threads: bool| {
                let mut terms = Terms::default();
                sys.couplings.scale_into(&factors, nd, threads, &mut terms);
                terms
            };
            let (one, two) = (scale(false), in_pool_of_two(|| scale(true)));
            let scaled = ProductView {
                values: None,
                terms: &one,
                ..sys.product_view()
            };
            let mut rnd = rng(3);
            let x: Vec<f64> = (0..n).map(|_| rnd()).collect();
            let mut y = vec![0.0; n];
            let split = scaled.half * nd;
            let halves = x.split_at(split);
            let (y0, y1) = y.split_at_mut(split);
            scaled.product(0, [halves.0, halves.1], y0);
            scaled.product(1, [halves.0, halves.1], y1);
            // Densely: w = L^-T x, v = K w, want = L^-1 v (block by block, the pattern's
            // order being the blocks' own here).
            let per_block = |v: &[f64], f: &dyn Fn(&Packed, &mut [f64; 6])| -> Vec<f64> {
                let mut out = Vec::with_capacity(n);
                for (b, l) in factors.iter().enumerate() {
                    let mut t = [0.0; 6];
                    t[..nd].copy_from_slice(&v[b * nd..(b + 1) * nd]);
                    f(l, &mut t);
                    out.extend_from_slice(&t[..nd]);
                }
                out
            };
            let w = per_block(&x, &|l, t| match nd {
                6 => upper_solve::<6>(l, t),
                _ => upper_solve::<3>(l, block_mut::<3>(t, 0)),
            });
            let v: Vec<f64> = (0..n)
                .map(|r| (0..n).map(|c| dense[r][c] * w[c]).sum())
                .collect();
            let want = per_block(&v, &|l, t| match nd {
                6 => lower_solve::<6>(l, t),
                _ => lower_solve::<3>(l, block_mut::<3>(t, 0)),
            });
            let scale_of = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for r in 0..n {
                assert!(
                    (y[r] - want[r]).abs() <= 1e-12 * scale_of,
                    "nd {nd}, row {r}: {} against {}",
                    y[r],
                    want[r]
                );
            }
            let bits = |t: &Terms| {
                let mut all: Vec<u64> = t.dense_values.iter().map(|v| v.to_bits()).collect();
                for c in t.within.iter().flatten().chain(&t.across) {
                    all.extend(c.su.iter().chain(&c.v).map(|v| v.to_bits()));
                }
                all
            };
            assert_eq!(bits(&one), bits(&two), "nd {nd}: threads");
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
