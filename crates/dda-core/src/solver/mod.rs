//! The global block-sparse system K D = F (paper eq. 14) and its solution.
//!
//! The pattern (which blocks couple) is set once per step from the candidate contacts and
//! stays fixed through the open-close iteration, so only values change between solves.
//! The lower triangle is stored as a scalar CSC matrix with, for every block entry, the
//! offset of each of its columns, so a 6x6 (or 3x3) term is added without searching.
//! faer's sparse (supernodal) Cholesky factorises it: the symbolic analysis (ordering and
//! elimination tree) is redone only when the pattern changes, the numeric factorisation
//! goes into a preallocated buffer. The triangular sweeps are ours (`sweeps`), so that
//! a low-rank update of the factor needs only forward sweeps along short paths.
//!
//! This file holds the layout (the block pattern, its ordering, where each block term
//! goes); `factor` the numeric factorisation and its solves; `low_rank` the Woodbury
//! solves of an iteration that changed few springs; `sweeps` the triangular sweeps.

pub use self::iterative::Iterated;
pub(crate) use self::iterative::{chol, chol_solve, forward_solve};
pub use self::low_rank::RankOne;
use self::sweeps::{Factor, Scratch, Tree};
use crate::kinematics::{Mat6, Vec6};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Par, Side};

mod factor;
mod iterative;
mod low_rank;
mod sweeps;
mod team;

/// Columns of the low-rank path's buffer counted in the memory estimate: the engine
/// keeps at most about this many rank-one terms (its bound on springs changed since a
/// factorisation) and their right-hand side terms.
pub const MAX_RANK_COLUMNS: usize = 96;

/// Parallelism of the factorisation and solve: sequential. Measured on the 830-block
/// column (4,980 unknowns, 2 cores): `Par::rayon(2)` took 11.8 s over 5,617
/// factorisations against 11.5 s sequential, so threads do not pay at this size. Nor at
/// 10,131 blocks (60,786 unknowns, 25 steps, 2026-11-25): 16.8 s of solve against
/// 10.4 s, the results the same to the bit.
const PAR: Par = Par::Seq;

/// Why the system could not be solved.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The matrix is not numerically positive definite.
    #[error("the global matrix is not positive definite (a block without mass or support?)")]
    NotPositiveDefinite,
    /// faer could not build the symbolic factorisation.
    #[error("symbolic factorisation failed: {0}")]
    Symbolic(String),
    /// The factor of the global matrix would not fit in the memory allowed.
    #[error(
        "the factor of the global matrix ({unknowns} unknowns) needs about {}, more than \
         the {} allowed (the memory available, or --max-memory); `analysis.solver = \
         \"iterative\"` solves it without a factor, in memory linear in the blocks",
        bytes(*needed),
        bytes(*allowed)
    )]
    OutOfMemory {
        /// Unknowns of the system.
        unknowns: usize,
        /// Estimated bytes of the factor and its workspace.
        needed: u64,
        /// Bytes allowed.
        allowed: u64,
    },
}

/// A byte count in words: bytes, KiB, MiB or GiB.
fn bytes(n: u64) -> String {
    match n {
        0..1024 => format!("{n} bytes"),
        1024..1_048_576 => format!("{:.1} KiB", n as f64 / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.1} MiB", n as f64 / 1_048_576.0),
        _ => format!("{:.2} GiB", n as f64 / 1_073_741_824.0),
    }
}

/// The solver's work: factorisations and low-rank solves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct SolverCounters {
    /// Symbolic factorisations (new matrix patterns).
    pub symbolic: u64,
    /// Numeric factorisations.
    pub numeric: u64,
    /// Solves through a low-rank update of the factor.
    pub low_rank: u64,
    /// Iterative solves (conjugate gradients, no factor).
    pub iterative: u64,
    /// Their conjugate-gradient iterations.
    pub cg_iterations: u64,
}

/// Where the block pair (i, j) lives in the storage: an index into the block entries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Entry(u32);

/// The block-sparse symmetric system over the free blocks.
///
/// Blocks are renumbered by an approximate-minimum-degree ordering of the block graph
/// (6x smaller than the scalar graph, so cheap to order), and the lower triangle is
/// stored in that order: faer then factorises it as given, with no permutation or
/// transposition of the matrix at each numeric factorisation.
pub struct BlockSystem {
    pub(super) nd: usize,
    pub(super) nb: usize,
    /// Off-diagonal block pairs (I < J, scene free-block numbering), sorted: the pattern.
    pub(super) pairs: Vec<(u32, u32)>,
    /// Position of each block in the elimination order.
    pub(super) pos: Vec<u32>,
    /// Per permuted block column J': range into `col_rows` of its block rows I' >= J'
    /// (J' first).
    pub(super) col_start: Vec<usize>,
    pub(super) col_rows: Vec<u32>,
    /// Per block entry and local column q: offset of its first value.
    pub(super) entry_col: Vec<usize>,
    /// Per block entry: whether it is a diagonal block.
    pub(super) entry_diag: Vec<bool>,
    /// The scalar lower-triangle pattern (checked once when set, not at each solve).
    pub(super) pattern: SymbolicSparseColMat<usize>,
    pub(super) values: Vec<f64>,
    /// Right-hand side, then the solution, in permuted block order.
    pub(super) rhs: Vec<f64>,
    pub(super) symbolic: Option<SymbolicCholesky<usize>>,
    pub(super) l_values: Vec<f64>,
    pub(super) mem: MemBuffer,
    /// Whether `l_values` holds the factor of `values`.
    pub(super) factored: bool,
    /// The supernodal elimination tree of the factor.
    pub(super) tree: Tree,
    /// Scratch of the triangular solves: one supernode's rows.
    pub(super) gather: Vec<f64>,
    /// Scratch of the batched sweeps of new low-rank columns.
    pub(super) sweep: Scratch,
    /// Low-rank solves: L^-1 u for every u solved since the factorisation (column-major,
    /// n per column; only the rows of its path are its own, the rest are left from
    /// earlier columns and never read), and each column's u.
    pub(super) z: Vec<f64>,
    pub(super) z_rows: Vec<([Option<u32>; 2], [Vec6; 2])>,
    /// Per column of `z`: the supernodes it may be nonzero on (`paths[path_start[c]..
    /// path_start[c + 1]]`, ascending).
    pub(super) paths: Vec<u32>,
    pub(super) path_start: Vec<usize>,
    /// The Gram matrix of the columns of `z` (column j's products with columns 0..=j at
    /// j (j + 1) / 2): U^T K^-1 U = (L^-1 U)^T (L^-1 U), kept as columns arrive.
    pub(super) gram: Vec<f64>,
    /// The forward half of the factorised system's solution, L^-1 F.
    pub(super) h0: Vec<f64>,
    /// Per term of the current low-rank solve: its column in `z`.
    pub(super) term_col: Vec<usize>,
    /// The right-hand side's changes of a low-rank solve, then L^-1 of them.
    pub(super) delta: Vec<f64>,
    /// The capacitance matrix (row-major) and its right-hand side, then solution.
    pub(super) cap: Vec<f64>,
    pub(super) cap_rhs: Vec<f64>,
    /// The work done so far.
    counters: SolverCounters,
    /// Most bytes the factor and its workspace may take (None: no bound but the
    /// allocator's).
    pub memory_limit: Option<u64>,
    /// Whether the system is solved iteratively ([`BlockSystem::solve_iterative`]):
    /// then it keeps no factor, and its blocks stay in their own order.
    iterative: bool,
    /// Whether a pattern is set.
    has_pattern: bool,
    /// Whether the iterative solve's products run on two threads (the same result
    /// either way).
    pub threads: bool,
    /// The iterative solve's start, then its solution (block order of the pattern).
    pub(super) x: Vec<f64>,
    /// The iterative solve's factors of the diagonal blocks (the scaling of its system)
    /// and inverses of the blocks' own terms (its bound), and its work vectors.
    pub(super) factors: Vec<iterative::Packed>,
    pub(super) metric: Vec<iterative::Packed>,
    pub(super) work: Vec<f64>,
    /// The iterative layout's couplings between blocks (`iterative::Couplings`): the
    /// off-diagonal terms, kept as rank-one terms or dense blocks, pair by pair.
    pub(super) couplings: iterative::Couplings,
    /// The couplings' terms in the scaled system the iterative solve iterates on.
    pub(super) scaled: iterative::Terms,
    /// Per block (in the pattern's order): whether its diagonal block changed since the
    /// iterative solve last factorised it (cleared and refilled, or a term added).
    pub(super) stale: Vec<bool>,
}

impl std::fmt::Debug for BlockSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("BlockSystem")
            .field("nd", &self.nd)
            .field("nb", &self.nb)
            .field("pairs", &self.pairs.len())
            .field("nnz", &self.values.len())
            .finish()
    }
}

impl Default for BlockSystem {
    fn default() -> Self {
        BlockSystem {
            nd: 0,
            nb: 0,
            pairs: Vec::new(),
            pos: Vec::new(),
            col_start: vec![0],
            col_rows: Vec::new(),
            entry_col: Vec::new(),
            entry_diag: Vec::new(),
            pattern: SymbolicSparseColMat::new_checked(0, 0, vec![0], None, Vec::new()),
            values: Vec::new(),
            rhs: Vec::new(),
            symbolic: None,
            l_values: Vec::new(),
            mem: MemBuffer::new(StackReq::EMPTY),
            factored: false,
            tree: Tree::default(),
            gather: Vec::new(),
            sweep: Scratch::default(),
            z: Vec::new(),
            z_rows: Vec::new(),
            paths: Vec::new(),
            path_start: vec![0],
            gram: Vec::new(),
            h0: Vec::new(),
            term_col: Vec::new(),
            delta: Vec::new(),
            cap: Vec::new(),
            cap_rhs: Vec::new(),
            counters: SolverCounters::default(),
            memory_limit: None,
            iterative: false,
            has_pattern: false,
            threads: false,
            x: Vec::new(),
            factors: Vec::new(),
            metric: Vec::new(),
            work: Vec::new(),
            couplings: iterative::Couplings::default(),
            scaled: iterative::Terms::default(),
            stale: Vec::new(),
        }
    }
}

impl BlockSystem {
    /// An empty system.
    pub fn new() -> Self {
        Self::default()
    }

    /// A system solved iteratively ([`BlockSystem::solve_iterative`]): no ordering, no
    /// symbolic analysis, no factor.
    pub fn iterative() -> Self {
        BlockSystem {
            iterative: true,
            ..Self::default()
        }
    }

    /// Whether the system is solved iteratively.
    pub fn is_iterative(&self) -> bool {
        self.iterative
    }

    /// Unknowns per block.
    pub fn dofs_per_block(&self) -> usize {
        self.nd
    }

    /// Sets the pattern: `nb` blocks of `nd` unknowns coupled by `pairs` (I < J, sorted,
    /// unique). Returns whether the symbolic factorisation had to be redone.
    pub fn set_pattern(
        &mut self,
        nb: usize,
        nd: usize,
        pairs: &[(u32, u32)],
    ) -> Result<bool, SolveError> {
        if self.has_pattern && self.nb == nb && self.nd == nd && self.pairs == pairs {
            return Ok(false);
        }
        self.has_pattern = false;
        self.factored = false;
        self.nb = nb;
        self.nd = nd;
        self.pairs.clear();
        self.pairs.extend_from_slice(pairs);
        self.order_blocks()?;

        // Block rows of each permuted block column: J' itself, then the I' > J'.
        let mut count = vec![1usize; nb];
        for &(i, j) in pairs {
            let (pi, pj) = (self.pos[i as usize], self.pos[j as usize]);
            count[pi.min(pj) as usize] += 1;
        }
        self.col_start.clear();
        self.col_start.push(0);
        for c in &count {
            let s = self.col_start[self.col_start.len() - 1] + c;
            self.col_start.push(s);
        }
        self.col_rows.clear();
        self.col_rows.resize(self.col_start[nb], 0);
        let mut fill: Vec<usize> = self.col_start[..nb].to_vec();
        for (j, f) in fill.iter_mut().enumerate() {
            self.col_rows[*f] = j as u32;
            *f += 1;
        }
        for &(i, j) in pairs {
            let (pi, pj) = (self.pos[i as usize], self.pos[j as usize]);
            let (lo, hi) = (pi.min(pj) as usize, pi.max(pj));
            self.col_rows[fill[lo]] = hi;
            fill[lo] += 1;
        }
        for j in 0..nb {
            self.col_rows[self.col_start[j] + 1..self.col_start[j + 1]].sort_unstable();
        }

        let n = nb * nd;
        self.rhs.clear();
        self.rhs.resize(n, 0.0);
        self.x.clear();
        self.x.resize(n, 0.0);
        self.stale.clear();
        self.stale.resize(nb, true);
        self.entry_diag.clear();
        self.entry_diag.resize(self.col_rows.len(), false);
        for jb in 0..nb {
            self.entry_diag[self.col_start[jb]] = true;
        }
        self.entry_col.clear();
        self.entry_col.resize(self.col_rows.len() * nd, 0);
        if self.iterative {
            // No factorisation reads the values: they hold the diagonal blocks alone (each
            // one's lower triangle, its columns together, in block order, so that they
            // stream from memory in one pass); the couplings between blocks are kept
            // apart (`iterative::Couplings`).
            let mut off = 0;
            for e in 0..self.col_rows.len() {
                for q in 0..nd {
                    self.entry_col[e * nd + q] = off;
                    if self.entry_diag[e] {
                        off += nd - q;
                    }
                }
            }
            self.couplings.reset(self.col_rows.len(), nb / 2);
            self.values.clear();
            self.values.resize(off, 0.0);
            self.has_pattern = true;
            return Ok(true);
        }

        // Scalar lower-triangle CSC.
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for jb in 0..nb {
            for q in 0..nd {
                for e in self.col_start[jb]..self.col_start[jb + 1] {
                    let ib = self.col_rows[e] as usize;
                    self.entry_col[e * nd + q] = row_idx.len();
                    let first = if ib == jb { q } else { 0 };
                    row_idx.extend((first..nd).map(|a| ib * nd + a));
                }
                col_ptr.push(row_idx.len());
            }
        }
        self.values.clear();
        self.values.resize(row_idx.len(), 0.0);

        // With the identity ordering faer's symbolic analysis reads the upper triangle,
        // so it gets the transpose of our lower pattern.
        let (up_ptr, up_rows) = transpose_pattern(n, &col_ptr, &row_idx);
        self.pattern = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let a = SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_rows);
        // Always supernodal: the low-rank path's solves walk its supernodes.
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(a, Side::Upper, SymmetricOrdering::Identity, params)
                .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return Err(SolveError::Symbolic(
                "faer chose a simplicial factor".into(),
            ));
        };
        self.tree = Tree::new(sn);
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(PAR, Default::default());
        // The factor, its workspace and the low-rank path's kept columns, checked
        // against the bound before any of it is allocated; then allocated fallibly, so
        // that a system too large is an error, not an abort.
        let needed = (symbolic.len_val() as u64 + (2 * MAX_RANK_COLUMNS * n) as u64) * 8
            + req.size_bytes() as u64;
        let limit = self.memory_limit;
        let out_of_memory = |allowed: u64| SolveError::OutOfMemory {
            unknowns: n,
            needed,
            allowed,
        };
        if let Some(allowed) = limit
            && needed > allowed
        {
            return Err(out_of_memory(allowed));
        }
        let fail = || out_of_memory(limit.unwrap_or(needed));
        self.l_values.clear();
        self.l_values
            .try_reserve_exact(symbolic.len_val())
            .map_err(|_| fail())?;
        self.l_values.resize(symbolic.len_val(), 0.0);
        self.gather = Vec::with_capacity(Factor::new(sn, &self.l_values).max_rows());
        self.mem = MemBuffer::try_new(req).map_err(|_| fail())?;
        self.symbolic = Some(symbolic);
        self.counters.symbolic += 1;
        self.has_pattern = true;
        Ok(true)
    }

    /// Orders the blocks by approximate minimum degree of the block graph into `pos`.
    ///
    /// Tried and dropped: nested dissection by breadth-first level sets (George and Liu)
    /// down to parts of 24 blocks. On paper 5.2b it gave 2.5 times the factorisation flops
    /// of minimum degree (7.5e7 against 2.7e7 on the first pattern): with the blocks'
    /// corner contacts and the pattern margin the level sets are thick separators.
    fn order_blocks(&mut self) -> Result<(), SolveError> {
        let nb = self.nb;
        if self.iterative {
            self.pos.clear();
            self.pos.extend(0..nb as u32);
            return Ok(());
        }
        // Upper pattern of the block graph, column by column (faer reads A + A^T).
        let mut count = vec![0usize; nb];
        for &(_, j) in &self.pairs {
            count[j as usize] += 1;
        }
        let mut ptr = Vec::with_capacity(nb + 1);
        ptr.push(0usize);
        for j in 0..nb {
            ptr.push(ptr[j] + count[j] + 1);
        }
        let mut rows = vec![0usize; ptr[nb]];
        let mut fill: Vec<usize> = ptr[..nb].to_vec();
        for &(i, j) in &self.pairs {
            rows[fill[j as usize]] = i as usize;
            fill[j as usize] += 1;
        }
        for (j, f) in fill.iter().enumerate() {
            rows[*f] = j;
        }
        let mut perm = vec![0usize; nb];
        let mut perm_inv = vec![0usize; nb];
        let a = SymbolicSparseColMatRef::new_checked(nb, nb, &ptr, None, &rows);
        let mut mem = MemBuffer::new(amd::order_scratch::<usize>(nb, rows.len()));
        amd::order(
            &mut perm,
            &mut perm_inv,
            a,
            amd::Control::default(),
            MemStack::new(&mut mem),
        )
        .map_err(|e| SolveError::Symbolic(format!("{e:?}")))?;
        self.pos.clear();
        self.pos.extend(perm_inv.iter().map(|&p| p as u32));
        Ok(())
    }

    /// Zeroes the matrix values and the right-hand side, keeping the pattern.
    pub fn clear(&mut self) {
        self.factored = false;
        self.stale.fill(true);
        self.values.fill(0.0);
        self.rhs.fill(0.0);
        if self.iterative {
            self.couplings.reset(self.col_rows.len(), self.nb / 2);
        }
    }

    /// The work done so far.
    pub fn counters(&self) -> SolverCounters {
        self.counters
    }

    /// Sets the counters (to resume a run's totals).
    pub fn set_counters(&mut self, counters: SolverCounters) {
        self.counters = counters;
    }

    /// The entry coupling blocks `i` and `j` (either order), if the pattern has it.
    pub fn entry(&self, i: u32, j: u32) -> Option<Entry> {
        let (pi, pj) = (self.pos[i as usize], self.pos[j as usize]);
        let (lo, hi) = (pi.min(pj) as usize, pi.max(pj));
        let (s, e) = (self.col_start[lo], self.col_start[lo + 1]);
        self.col_rows[s..e]
            .binary_search(&hi)
            .ok()
            .map(|k| Entry((s + k) as u32))
    }

    /// The diagonal entry of block `i`.
    pub fn diagonal(&self, i: u32) -> Entry {
        Entry(self.col_start[self.pos[i as usize] as usize] as u32)
    }

    /// Adds the symmetric block `k` (only its upper triangle is read) to the diagonal
    /// entry of block `i`.
    pub fn add_diagonal(&mut self, i: u32, k: &Mat6) {
        self.factored = false;
        let nd = self.nd;
        let e = self.diagonal(i).0 as usize;
        self.stale[self.pos[i as usize] as usize] = true;
        for q in 0..nd {
            let base = self.entry_col[e * nd + q];
            for (a, v) in self.values[base..base + nd - q].iter_mut().enumerate() {
                *v += k[q][q + a];
            }
        }
    }

    /// Adds `s * u v^T` to the coupling of block `i` (rows, `u`) and block `j` (columns,
    /// `v`) at `entry`, and its transpose to the coupling of `j` and `i`; on a diagonal
    /// entry (`i == j`) `u == v` is assumed and the term is added once.
    pub fn add_outer(&mut self, entry: Entry, i: u32, j: u32, s: f64, u: &Vec6, v: &Vec6) {
        self.factored = false;
        let nd = self.nd;
        let e = entry.0 as usize;
        if self.entry_diag[e] {
            self.stale[self.pos[i as usize] as usize] = true;
            for q in 0..nd {
                let base = self.entry_col[e * nd + q];
                let sv = s * v[q];
                for (a, val) in self.values[base..base + nd - q].iter_mut().enumerate() {
                    *val += u[q + a] * sv;
                }
            }
            return;
        }
        if self.iterative {
            let (a, b) = (self.pos[i as usize], self.pos[j as usize]);
            self.couplings.add(e, [a, b], s, u, v);
            return;
        }
        // Stored block: rows of the later block in the order, columns of the earlier.
        let (rows, cols) = if self.pos[i as usize] > self.pos[j as usize] {
            (u, v)
        } else {
            (v, u)
        };
        for q in 0..nd {
            let base = self.entry_col[e * nd + q];
            let sc = s * cols[q];
            for (a, val) in self.values[base..base + nd].iter_mut().enumerate() {
                *val += rows[a] * sc;
            }
        }
    }

    /// Adds `s * f` to the right-hand side of block `i`.
    pub fn add_rhs(&mut self, i: u32, s: f64, f: &Vec6) {
        let nd = self.nd;
        let p = self.pos[i as usize] as usize;
        for (r, fa) in self.rhs[p * nd..(p + 1) * nd].iter_mut().zip(f) {
            *r += s * fa;
        }
    }

    /// The solution for block `i` after [`BlockSystem::solve`].
    pub fn solution(&self, i: u32) -> &[f64] {
        let p = self.pos[i as usize] as usize;
        // Solved iteratively, the right-hand side is kept (the next solve changes it).
        let x = if self.iterative { &self.x } else { &self.rhs };
        &x[p * self.nd..(p + 1) * self.nd]
    }
}

/// The transpose of a CSC pattern (row indices sorted in each column).
fn transpose_pattern(n: usize, col_ptr: &[usize], row_idx: &[usize]) -> (Vec<usize>, Vec<usize>) {
    let mut ptr = vec![0usize; n + 1];
    for &r in row_idx {
        ptr[r + 1] += 1;
    }
    for i in 0..n {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr[..n].to_vec();
    let mut rows = vec![0usize; row_idx.len()];
    for c in 0..n {
        for &r in &row_idx[col_ptr[c]..col_ptr[c + 1]] {
            rows[fill[r]] = c;
            fill[r] += 1;
        }
    }
    (ptr, rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `f` in a pool of two threads, so that an iterative solve's second half runs
    /// on a helper thread whatever the machine's cores (without the `rayon` feature,
    /// here: a solve then works both halves itself).
    pub(super) fn in_pool_of_two<R: Send>(f: impl FnOnce() -> R + Send) -> R {
        #[cfg(feature = "rayon")]
        return rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool of two threads")
            .install(f);
        #[cfg(not(feature = "rayon"))]
        f()
    }

    /// A 4-block system (a star around block 0, which the ordering moves last) solved by
    /// the block system has a dense residual at rounding level.
    /// A pseudo-random generator for test values in [-0.5, 0.5).
    pub(super) fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
    }

    #[test]
    fn block_system_solves_like_dense() {
        for nd in [3usize, 6] {
            let nb = 4;
            let pairs = [(0u32, 1u32), (0, 2), (0, 3), (2, 3)];
            let mut sys = BlockSystem::new();
            assert!(sys.set_pattern(nb, nd, &pairs).unwrap());
            assert!(!sys.set_pattern(nb, nd, &pairs).unwrap());
            sys.clear();
            let n = nb * nd;
            let mut dense = vec![vec![0.0; n]; n];
            let mut rnd = rng(1);
            for i in 0..nb {
                let mut k = [[0.0; 6]; 6];
                for a in 0..nd {
                    for b in a..nd {
                        let v = if a == b { 20.0 } else { rnd() };
                        k[a][b] = v;
                        dense[i * nd + a][i * nd + b] = v;
                        dense[i * nd + b][i * nd + a] = v;
                    }
                }
                sys.add_diagonal(i as u32, &k);
            }
            for &(i, j) in &pairs {
                let u: Vec6 = std::array::from_fn(|_| rnd());
                let v: Vec6 = std::array::from_fn(|_| rnd());
                // Either argument order means the same coupling.
                let e = sys.entry(j, i).unwrap();
                sys.add_outer(e, i, j, 2.0, &u, &v);
                let (i, j) = (i as usize, j as usize);
                for a in 0..nd {
                    for b in 0..nd {
                        dense[i * nd + a][j * nd + b] += 2.0 * u[a] * v[b];
                        dense[j * nd + b][i * nd + a] += 2.0 * u[a] * v[b];
                    }
                }
            }
            assert!(sys.entry(1, 2).is_none());
            let f: Vec<f64> = (0..n).map(|k| k as f64 - 4.0).collect();
            for i in 0..nb {
                let fi: Vec6 = std::array::from_fn(|a| if a < nd { f[i * nd + a] } else { 0.0 });
                sys.add_rhs(i as u32, 1.0, &fi);
            }
            sys.solve().unwrap();
            let x: Vec<f64> = (0..nb as u32)
                .flat_map(|i| sys.solution(i).to_vec())
                .collect();
            for r in 0..n {
                let res: f64 = (0..n).map(|c| dense[r][c] * x[c]).sum::<f64>() - f[r];
                assert!(res.abs() < 1e-12, "nd {nd} row {r}: residual {res}");
            }
        }
    }
}
