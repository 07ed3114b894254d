//! The numeric factorisation of the global matrix (faer's supernodal Cholesky into a
//! preallocated buffer) and the solves with it: a new factor, a new right-hand side
//! with the last factor (the state predictor), or a saved matrix refactorised on resume.

use super::sweeps::Factor;
use super::{BlockSystem, PAR, SolveError};
use faer::Side;
use faer::dyn_stack::MemStack;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

impl BlockSystem {
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
        let count = self.counters.numeric;
        self.solve()?;
        self.counters.numeric = count;
        Ok(())
    }

    /// Zeroes the right-hand side only, keeping the matrix and its factor.
    pub fn clear_rhs(&mut self) {
        self.rhs.fill(0.0);
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
        self.counters.numeric += 1;
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
}

/// The factor with symbolic structure `symbolic` and values `l`, once the symbolic
/// analysis is done.
pub(super) fn factor_of<'a>(
    symbolic: &'a Option<SymbolicCholesky<usize>>,
    l: &'a [f64],
) -> Option<Factor<'a>> {
    match symbolic.as_ref()?.raw() {
        SymbolicCholeskyRaw::Supernodal(sn) => Some(Factor::new(sn, l)),
        SymbolicCholeskyRaw::Simplicial(_) => None,
    }
}
