//! Triangular solves with faer's supernodal Cholesky factor K = L L^T: the whole forward
//! (L) and backward (L^T) sweeps of one right-hand side, and the forward sweeps of sparse
//! right-hand sides along their paths in the supernodal elimination tree, together.
//!
//! The open-close iteration changes a few dozen springs against the factorised matrix;
//! its low-rank solve (`BlockSystem::solve_low_rank`) needs L^-1 u for the row u of each
//! changed spring. Such a row touches the unknowns of two blocks, so L^-1 u is nonzero
//! only on the supernodes from theirs up to the root (about a fifth of the rows of the
//! 826-block column's factor, the large separators near the root included), where
//! a full solve reads all of it twice.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky;
use faer::{Accum, MatMut, MatRef, Par};

/// Buffers of the batched sweeps, kept between calls so that a sweep does not allocate
/// once they have grown.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    /// Per column: its next supernode, as an index into the paths.
    next: Vec<usize>,
    /// The supernodes of all the columns' paths, ascending.
    union: Vec<u32>,
    /// The columns whose paths pass the current supernode.
    members: Vec<usize>,
    /// Their rows of the current supernode, column-major.
    block: Vec<f64>,
}

/// A supernodal factor: faer's symbolic structure and the values of L, column-major per
/// supernode (the supernode's own columns on top, then the rows of its pattern).
#[derive(Clone, Copy)]
pub(crate) struct Factor<'a> {
    sym: &'a SymbolicSupernodalCholesky<usize>,
    l: &'a [f64],
}

/// One supernode of a factor: its first column, its columns' count, the rows below its
/// diagonal block, and its values (column-major, `ncols + pattern.len()` rows).
struct Node<'a> {
    start: usize,
    ncols: usize,
    pattern: &'a [usize],
    values: &'a [f64],
}

impl<'a> Factor<'a> {
    /// The factor with symbolic structure `sym` and values `l`.
    pub(crate) fn new(sym: &'a SymbolicSupernodalCholesky<usize>, l: &'a [f64]) -> Self {
        Factor { sym, l }
    }

    /// Supernode `s`.
    fn node(&self, s: usize) -> Node<'a> {
        let start = self.sym.supernode_begin()[s];
        let ptr = self.sym.col_ptr_for_val();
        Node {
            start,
            ncols: self.sym.supernode_end()[s] - start,
            pattern: self.sym.supernode(s).pattern(),
            values: &self.l[ptr[s]..ptr[s + 1]],
        }
    }

    /// x <- L^-1 x over supernode `s`; `g` is scratch.
    fn forward_node(&self, s: usize, x: &mut [f64], g: &mut Vec<f64>) {
        let node = self.node(s);
        let (c, rows) = (node.ncols, node.ncols + node.pattern.len());
        g.clear();
        g.extend_from_slice(&x[node.start..node.start + c]);
        g.extend(node.pattern.iter().map(|&r| x[r]));
        for j in 0..c {
            let col = &node.values[j * rows..(j + 1) * rows];
            let xj = g[j] / col[j];
            g[j] = xj;
            if xj != 0.0 {
                for (gi, li) in g[j + 1..].iter_mut().zip(&col[j + 1..]) {
                    *gi -= li * xj;
                }
            }
        }
        x[node.start..node.start + c].copy_from_slice(&g[..c]);
        for (&r, &v) in node.pattern.iter().zip(&g[c..]) {
            x[r] = v;
        }
    }

    /// x <- L^-1 x (the forward sweep over every supernode).
    pub(crate) fn forward(&self, x: &mut [f64], g: &mut Vec<f64>) {
        for s in 0..self.sym.n_supernodes() {
            self.forward_node(s, x, g);
        }
    }

    /// z_c <- L^-1 z_c for the columns c in `cols` of `z` (`n` rows each), each zero
    /// outside the columns of the supernodes of its path (`paths[start[c]..start[c + 1]]`,
    /// ascending, closed under parents: see [`Tree::path`]); the results are zero outside
    /// them too, so only they are swept. Supernode by supernode over all the columns, so
    /// that the large supernodes near the root, on every path, are read from cache.
    pub(crate) fn forward_paths(
        &self,
        z: &mut [f64],
        n: usize,
        paths: &[u32],
        start: &[usize],
        cols: std::ops::Range<usize>,
        scratch: &mut Scratch,
    ) {
        let (next, union, members) = (&mut scratch.next, &mut scratch.union, &mut scratch.members);
        next.clear();
        next.extend_from_slice(&start[cols.clone()]);
        union.clear();
        union.extend_from_slice(&paths[start[cols.start]..start[cols.end]]);
        union.sort_unstable();
        union.dedup();
        for &s in union.iter() {
            members.clear();
            for (c, at) in cols.clone().zip(next.iter_mut()) {
                if *at < start[c + 1] && paths[*at] == s {
                    *at += 1;
                    members.push(c);
                }
            }
            let node = self.node(s as usize);
            let (c, rows, m) = (node.ncols, node.ncols + node.pattern.len(), members.len());
            // The members' rows of this supernode, as a dense rows x m block.
            let g = &mut scratch.block;
            g.clear();
            for &col in members.iter() {
                let x = &z[col * n..(col + 1) * n];
                g.extend_from_slice(&x[node.start..node.start + c]);
                g.extend(node.pattern.iter().map(|&r| x[r]));
            }
            let l = MatRef::from_column_major_slice(node.values, rows, c);
            let (l_top, l_bot) = l.split_at_row(c);
            let gm = MatMut::from_column_major_slice_mut(g, rows, m);
            let (mut g_top, g_bot) = gm.split_at_row_mut(c);
            solve_lower_triangular_in_place(l_top, g_top.as_mut(), Par::Seq);
            matmul(g_bot, Accum::Add, l_bot, g_top.as_ref(), -1.0, Par::Seq);
            for (&col, gc) in members.iter().zip(g.chunks_exact(rows)) {
                let x = &mut z[col * n..(col + 1) * n];
                x[node.start..node.start + c].copy_from_slice(&gc[..c]);
                for (&r, &v) in node.pattern.iter().zip(&gc[c..]) {
                    x[r] = v;
                }
            }
        }
    }

    /// x <- L^-T x (the backward sweep over every supernode). In each supernode the
    /// products of its columns with the pattern rows come first: those rows are final
    /// values of ancestors, so the products are independent of each other and can
    /// overlap in the processor. The short triangular chain of the diagonal block comes
    /// after. Measured (`column_step/resolve`, both sweeps): 3,472 blocks 4.98-5.12 ms
    /// against 6.26-6.75 ms with each column's product over its whole height in the
    /// chain; 10,131 blocks 24.0-24.6 against 24.8-26.7 ms; 826 blocks no change.
    pub(crate) fn backward(&self, x: &mut [f64], g: &mut Vec<f64>) {
        for s in (0..self.sym.n_supernodes()).rev() {
            let node = self.node(s);
            let (c, rows) = (node.ncols, node.ncols + node.pattern.len());
            g.clear();
            g.extend(node.pattern.iter().map(|&r| x[r]));
            let top = &mut x[node.start..node.start + c];
            for (j, t) in top.iter_mut().enumerate() {
                *t -= dot(&node.values[j * rows + c..(j + 1) * rows], g);
            }
            for j in (0..c).rev() {
                let col = &node.values[j * rows..j * rows + c];
                top[j] = (top[j] - dot(&top[j + 1..], &col[j + 1..])) / col[j];
            }
        }
    }

    /// Rows a vector zero outside `path` may be nonzero on: the column ranges of its
    /// supernodes.
    pub(crate) fn path_rows(
        &self,
        path: &'a [u32],
    ) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
        self.node_rows(path.iter().copied())
    }

    /// The column ranges of supernodes `nodes`.
    pub(crate) fn node_rows(
        &self,
        nodes: impl Iterator<Item = u32> + 'a,
    ) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
        let (begin, end) = (self.sym.supernode_begin(), self.sym.supernode_end());
        nodes.map(move |s| begin[s as usize]..end[s as usize])
    }

    /// Most rows of a supernode (the size `g` grows to).
    pub(crate) fn max_rows(&self) -> usize {
        (0..self.sym.n_supernodes())
            .map(|s| {
                let node = self.node(s);
                node.ncols + node.pattern.len()
            })
            .max()
            .unwrap_or(0)
    }
}

/// The supernodal elimination tree: each column's supernode and each supernode's parent.
#[derive(Clone, Debug, Default)]
pub(crate) struct Tree {
    col_super: Vec<u32>,
    /// `u32::MAX` for a root.
    parent: Vec<u32>,
}

impl Tree {
    /// The tree of `sym`. A supernode's parent is the supernode of the first row below its
    /// diagonal block: the rows of its pattern all belong to ancestors, so that is where
    /// its column of L^-1 u spills into.
    pub(crate) fn new(sym: &SymbolicSupernodalCholesky<usize>) -> Self {
        let ns = sym.n_supernodes();
        let mut col_super = vec![0u32; sym.nrows()];
        for s in 0..ns {
            col_super[sym.supernode_begin()[s]..sym.supernode_end()[s]].fill(s as u32);
        }
        let parent = (0..ns)
            .map(|s| {
                let pattern = sym.supernode(s).pattern();
                pattern.iter().min().map_or(u32::MAX, |&r| col_super[r])
            })
            .collect();
        Tree { col_super, parent }
    }

    /// Appends to `out` the supernodes from those of the columns `cols` to the root,
    /// ascending and without repeats: where L^-1 u can be nonzero for a u nonzero only on
    /// `cols`. `out` is used from `from` on (the part before is left alone).
    pub(crate) fn path(&self, cols: impl IntoIterator<Item = usize>, out: &mut Vec<u32>) {
        let from = out.len();
        for c in cols {
            let mut s = self.col_super[c];
            // Ancestors have larger numbers: stop at one already listed.
            while s != u32::MAX && !out[from..].contains(&s) {
                out.push(s);
                s = self.parent[s as usize];
            }
        }
        out[from..].sort_unstable();
    }
}

/// u . v over the rows of `ranges`.
pub(crate) fn dot_over(
    ranges: impl Iterator<Item = std::ops::Range<usize>>,
    u: &[f64],
    v: &[f64],
) -> f64 {
    ranges.map(|r| dot(&u[r.clone()], &v[r])).sum()
}

/// y += a x over the rows of `ranges`.
pub(crate) fn axpy_over(
    ranges: impl Iterator<Item = std::ops::Range<usize>>,
    a: f64,
    x: &[f64],
    y: &mut [f64],
) {
    for r in ranges {
        for (yi, xi) in y[r.clone()].iter_mut().zip(&x[r]) {
            *yi += a * xi;
        }
    }
}

/// u . v, summed in eight interleaved lanes so that it vectorises (a plain sum of f64 does
/// not: its order is fixed). That order is fixed too, so results are reproducible.
pub(crate) fn dot(u: &[f64], v: &[f64]) -> f64 {
    let n = u.len().min(v.len());
    let (uc, vc) = (u[..n].chunks_exact(8), v[..n].chunks_exact(8));
    let (ur, vr) = (uc.remainder(), vc.remainder());
    let mut acc = [0.0f64; 8];
    for (a, b) in uc.zip(vc) {
        for l in 0..8 {
            acc[l] += a[l] * b[l];
        }
    }
    let tail: f64 = ur.iter().zip(vr).map(|(a, b)| a * b).sum();
    ((acc[0] + acc[4]) + (acc[1] + acc[5])) + ((acc[2] + acc[6]) + (acc[3] + acc[7])) + tail
}
