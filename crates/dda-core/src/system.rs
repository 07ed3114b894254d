//! The global block-sparse system K D = F (paper eq. 14) and its solution.
//!
//! The pattern (which blocks couple) is set once per step from the candidate contacts and
//! stays fixed through the open-close iteration, so only values change between solves.
//! The lower triangle is stored as a scalar CSC matrix with, for every block entry, the
//! offset of each of its columns, so a 6x6 (or 3x3) term is added without searching.
//! faer's sparse (supernodal) Cholesky factorises it: the symbolic analysis (ordering and
//! elimination tree) is redone only when the pattern changes, the numeric factorisation
//! goes into a preallocated buffer. The triangular sweeps are ours (`supernodal`), so that
//! a low-rank update of the factor needs only forward sweeps along short paths.

use crate::kinematics::{Mat6, Vec6};
use crate::supernodal::{Factor, Scratch, Tree, axpy_over, dot_over};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::amd;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Par, Side};

/// Columns of the low-rank path's buffer counted in the memory estimate: the engine
/// keeps at most about this many rank-one terms (its bound on springs changed since a
/// factorisation) and their right-hand side terms.
pub const MAX_RANK_COLUMNS: usize = 96;

/// Parallelism of the factorisation and solve: sequential. Measured on the 830-block
/// column (4,980 unknowns, 2 cores): `Par::rayon(2)` took 11.8 s over 5,617
/// factorisations against 11.5 s sequential, so threads do not pay at this size.
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
         the {} allowed (the memory available, or --max-memory)",
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
    nd: usize,
    nb: usize,
    /// Off-diagonal block pairs (I < J, scene free-block numbering), sorted: the pattern.
    pairs: Vec<(u32, u32)>,
    /// Position of each block in the elimination order.
    pos: Vec<u32>,
    /// Per permuted block column J': range into `col_rows` of its block rows I' >= J'
    /// (J' first).
    col_start: Vec<usize>,
    col_rows: Vec<u32>,
    /// Per block entry and local column q: offset of its first value.
    entry_col: Vec<usize>,
    /// Per block entry: whether it is a diagonal block.
    entry_diag: Vec<bool>,
    /// The scalar lower-triangle pattern (checked once when set, not at each solve).
    pattern: SymbolicSparseColMat<usize>,
    values: Vec<f64>,
    /// Right-hand side, then the solution, in permuted block order.
    rhs: Vec<f64>,
    symbolic: Option<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    mem: MemBuffer,
    /// Whether `l_values` holds the factor of `values`.
    factored: bool,
    /// The supernodal elimination tree of the factor.
    tree: Tree,
    /// Scratch of the triangular solves: one supernode's rows.
    gather: Vec<f64>,
    /// Scratch of the batched sweeps of new low-rank columns.
    sweep: Scratch,
    /// Low-rank solves: L^-1 u for every u solved since the factorisation (column-major,
    /// n per column; only the rows of its path are its own, the rest are left from
    /// earlier columns and never read), and each column's u.
    z: Vec<f64>,
    z_rows: Vec<([Option<u32>; 2], [Vec6; 2])>,
    /// Per column of `z`: the supernodes it may be nonzero on (`paths[path_start[c]..
    /// path_start[c + 1]]`, ascending).
    paths: Vec<u32>,
    path_start: Vec<usize>,
    /// The Gram matrix of the columns of `z` (column j's products with columns 0..=j at
    /// j (j + 1) / 2): U^T K^-1 U = (L^-1 U)^T (L^-1 U), kept as columns arrive.
    gram: Vec<f64>,
    /// The forward half of the factorised system's solution, L^-1 F.
    h0: Vec<f64>,
    /// Per term of the current low-rank solve: its column in `z`.
    term_col: Vec<usize>,
    /// The capacitance matrix (row-major) and its right-hand side, then solution.
    cap: Vec<f64>,
    cap_rhs: Vec<f64>,
    /// Number of symbolic factorisations done.
    pub symbolic_count: u64,
    /// Number of numeric factorisations done.
    pub numeric_count: u64,
    /// Number of solves through a low-rank update of the factor.
    pub low_rank_count: u64,
    /// Most bytes the factor and its workspace may take (None: no bound but the
    /// allocator's).
    pub memory_limit: Option<u64>,
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
            cap: Vec::new(),
            cap_rhs: Vec::new(),
            symbolic_count: 0,
            numeric_count: 0,
            low_rank_count: 0,
            memory_limit: None,
        }
    }
}

impl BlockSystem {
    /// An empty system.
    pub fn new() -> Self {
        Self::default()
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
        if self.symbolic.is_some() && self.nb == nb && self.nd == nd && self.pairs == pairs {
            return Ok(false);
        }
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

        // Scalar lower-triangle CSC.
        let n = nb * nd;
        let mut col_ptr = Vec::with_capacity(n + 1);
        let mut row_idx = Vec::new();
        self.entry_col.clear();
        self.entry_col.resize(self.col_rows.len() * nd, 0);
        self.entry_diag.clear();
        self.entry_diag.resize(self.col_rows.len(), false);
        col_ptr.push(0);
        for jb in 0..nb {
            self.entry_diag[self.col_start[jb]] = true;
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
        self.rhs.clear();
        self.rhs.resize(n, 0.0);

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
        self.symbolic_count += 1;
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
        self.values.fill(0.0);
        self.rhs.fill(0.0);
    }

    /// Whether the matrix is factorised as it stands (no entry added since the last
    /// [`BlockSystem::solve`]).
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// The values of the matrix the current factor was computed from (lower triangle in
    /// the pattern's order), if there is a factor; what a checkpoint saves to rebuild it.
    pub fn factored_values(&self) -> Option<&[f64]> {
        self.factored.then_some(&self.values[..])
    }

    /// Rebuilds the factor of a saved matrix (`values` from
    /// [`BlockSystem::factored_values`], pattern already set): the same numbers, so the
    /// same factor bit for bit. Leaves the counters as they were (a restore, not work of
    /// the run). Errors if the values do not fit the pattern or are not positive definite.
    pub fn restore_factor(&mut self, values: &[f64]) -> Result<(), SolveError> {
        if values.len() != self.values.len() {
            return Err(SolveError::Symbolic(format!(
                "saved matrix has {} values, the pattern {}",
                values.len(),
                self.values.len()
            )));
        }
        self.values.copy_from_slice(values);
        self.rhs.fill(0.0);
        let count = self.numeric_count;
        self.solve()?;
        self.numeric_count = count;
        Ok(())
    }

    /// Sets the symbolic, numeric and low-rank counters (to resume a run's totals).
    pub fn set_counters(&mut self, symbolic: u64, numeric: u64, low_rank: u64) {
        self.symbolic_count = symbolic;
        self.numeric_count = numeric;
        self.low_rank_count = low_rank;
    }

    /// Zeroes the right-hand side only, keeping the matrix and its factor.
    pub fn clear_rhs(&mut self) {
        self.rhs.fill(0.0);
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
            for q in 0..nd {
                let base = self.entry_col[e * nd + q];
                let sv = s * v[q];
                for (a, val) in self.values[base..base + nd - q].iter_mut().enumerate() {
                    *val += u[q + a] * sv;
                }
            }
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
        &self.rhs[p * self.nd..(p + 1) * self.nd]
    }

    /// Factorises the matrix (numeric only) and solves in place; read the result with
    /// [`BlockSystem::solution`].
    pub fn solve(&mut self) -> Result<(), SolveError> {
        let n = self.nb * self.nd;
        if n == 0 {
            return Ok(());
        }
        let Some(symbolic) = self.symbolic.as_ref() else {
            return Err(SolveError::Symbolic("no pattern set".into()));
        };
        let a = SparseColMatRef::new(self.pattern.as_ref(), &self.values);
        let stack = MemStack::new(&mut self.mem);
        symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                PAR,
                stack,
                Default::default(),
            )
            .map_err(|_| SolveError::NotPositiveDefinite)?;
        self.numeric_count += 1;
        self.factored = true;
        self.z_rows.clear();
        self.paths.clear();
        self.path_start.truncate(1);
        self.gram.clear();
        self.resolve();
        Ok(())
    }

    /// Solves the right-hand side assembled since [`BlockSystem::clear_rhs`] with the
    /// factor of the last [`BlockSystem::solve`] (which may be of an earlier matrix);
    /// false when there is no factor. Keeps the forward half, L^-1 F.
    pub fn resolve(&mut self) -> bool {
        if !self.factored {
            return false;
        }
        let Some(factor) = factor_of(&self.symbolic, &self.l_values) else {
            return false;
        };
        let mut g = std::mem::take(&mut self.gather);
        factor.forward(&mut self.rhs, &mut g);
        self.h0.clone_from(&self.rhs);
        factor.backward(&mut self.rhs, &mut g);
        self.gather = g;
        true
    }

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
    /// from one call to the next costs nothing more. One backward sweep ends the solve.
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
        for t in terms.iter().chain(rhs_terms) {
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
        // h = L^-1 F + sum g L^-1 v.
        self.rhs.copy_from_slice(&self.h0);
        let k = terms.len();
        for (t, &col) in rhs_terms.iter().zip(&self.term_col[k..]) {
            let rows = factor.path_rows(path(&self.paths, &self.path_start, col));
            axpy_over(rows, t.s, &self.z[col * n..(col + 1) * n], &mut self.rhs);
        }

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
        self.low_rank_count += 1;
        true
    }
}

/// The factor with symbolic structure `symbolic` and values `l`, once the symbolic
/// analysis is done.
fn factor_of<'a>(
    symbolic: &'a Option<SymbolicCholesky<usize>>,
    l: &'a [f64],
) -> Option<Factor<'a>> {
    match symbolic.as_ref()?.raw() {
        SymbolicCholeskyRaw::Supernodal(sn) => Some(Factor::new(sn, l)),
        SymbolicCholeskyRaw::Simplicial(_) => None,
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

    /// A 4-block system (a star around block 0, which the ordering moves last) solved by
    /// the block system has a dense residual at rounding level.
    /// A pseudo-random generator for test values in [-0.5, 0.5).
    fn rng(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        }
    }

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
        assert_eq!(sys.low_rank_count, 2);
        // A change of the matrix drops the factor: the low-rank path declines.
        sys.add_diagonal(0, &[[1.0; 6]; 6]);
        assert!(!sys.solve_low_rank(&[spring], &[]));
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
