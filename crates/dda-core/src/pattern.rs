//! The sparsity pattern of the global matrix: which blocks couple. It must hold every
//! pair with candidate contacts; it is set wider (every free pair within a margin) and
//! kept while it holds, so that the symbolic factorisation is reused.

use crate::diagnosis::SimError;
use crate::simulation::Simulation;
use dda_geom::separation;

/// How near (in d_tol, by separating-axis gap) two free blocks must be for a new matrix
/// pattern to couple them before they have contacts. Measured on paper 5.2b (826 blocks,
/// one run each): coupling every pair whose boxes are within d_tol gave 58 symbolic
/// analyses and 530-580k nonzeros in L, 3.2 ms per factorisation; coupling only the
/// needed pairs, 340 analyses and 335k nonzeros (2.3 ms), but each analysis costs the
/// next step its predicted states; margins of 2, 3, 4 and 6 d_tol gave 34, 21, 14 and
/// 9 analyses with 374k, 384k, 408k and 443k nonzeros (2.71, 2.76, 2.82 and 2.80 ms).
pub(crate) const PATTERN_MARGIN: f64 = 2.0;

impl Simulation {
    /// Fixes the pattern of the global matrix from the candidate pairs between free
    /// blocks, reusing the symbolic factorisation when the pattern is unchanged.
    pub(crate) fn set_pattern(&mut self) -> Result<(), SimError> {
        self.scratch.block_pairs.clear();
        for pc in &self.state.contacts.pairs {
            if let (Some(a), Some(b)) =
                (self.free[pc.pair.a as usize], self.free[pc.pair.b as usize])
            {
                self.scratch.block_pairs.push((a.min(b), a.max(b)));
            }
        }
        let mut bolts = std::mem::take(&mut self.scratch.block_pairs);
        self.bolt_pairs(&mut bolts);
        self.scratch.block_pairs = bolts;
        self.scratch.block_pairs.sort_unstable();
        self.scratch.block_pairs.dedup();
        if !is_subset(&self.scratch.block_pairs, &self.state.pattern) {
            // A new pattern: the needed pairs and every free pair whose polygons are
            // within PATTERN_MARGIN d_tol (separating-axis gap), contacts or not, so that
            // it holds while blocks shift among their neighbours. It is kept until a
            // needed pair is missing.
            self.state.pattern.clone_from(&self.scratch.block_pairs);
            let margin = PATTERN_MARGIN * self.detection.d_tol;
            self.scratch.neighbours.find(
                &self.scratch.aabbs,
                margin,
                &mut self.scratch.pattern_pairs,
            );
            for q in &self.scratch.pattern_pairs {
                let (pa, pb) = (
                    &self.state.blocks[q.a as usize],
                    &self.state.blocks[q.b as usize],
                );
                if let (Some(a), Some(b)) = (self.free[q.a as usize], self.free[q.b as usize])
                    && separation(&pa.polygon, &pb.polygon).0 < margin
                {
                    self.state.pattern.push((a.min(b), a.max(b)));
                }
            }
            self.state.pattern.sort_unstable();
            self.state.pattern.dedup();
        }
        self.scratch
            .system
            .set_pattern(self.n_free, self.nd, &self.state.pattern)
            .map_err(|source| SimError::Solve {
                t: self.state.t,
                source,
            })?;
        self.scratch.pair_entry.clear();
        for pc in &self.state.contacts.pairs {
            let e = match (self.free[pc.pair.a as usize], self.free[pc.pair.b as usize]) {
                (Some(a), Some(b)) => self.scratch.system.entry(a, b),
                _ => None,
            };
            self.scratch.pair_entry.push(e);
        }
        Ok(())
    }
}

/// Whether sorted `a` is contained in sorted `b`.
pub(crate) fn is_subset(a: &[(u32, u32)], b: &[(u32, u32)]) -> bool {
    let mut j = 0;
    for x in a {
        while j < b.len() && b[j] < *x {
            j += 1;
        }
        if j == b.len() || b[j] != *x {
            return false;
        }
    }
    true
}
