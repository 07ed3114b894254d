//! The engine's side of the iterative solve (`analysis.solver`, docs/method.md section
//! 14): which scenes take it, where each attempt starts, and the data of its stop.
//!
//! A system solved iteratively has no factor, so there are no low-rank solves. The
//! state predictor assembles the step's own matrix and solves it; each open-close
//! iteration after it adds the springs that changed since to the assembled matrix (or
//! assembles anew when more changed than a new assembly adds) and solves by conjugate
//! gradients, started from the last solve's motion (the first solve of an attempt from
//! the blocks' velocities times dt; `open_close.rs`).

use crate::kinematics::{Mat6, Vec6, dot, t_rows};
use crate::scene::SolverChoice;
use crate::simulation::Simulation;
use crate::solver::{Iterated, chol, forward_solve};

/// Free blocks from which `solver = "auto"` solves iteratively. Measured on the paper's
/// two-set column scaled up (docs/scaling.md, whole runs, 2026-11-26 after the couplings
/// were kept as springs and the second half of a solve got its own thread), iterative
/// against direct: 1,525 blocks for 0.5 s 7.38-7.51 s against 8.45-8.53 s (two
/// alternating runs), 2,085 blocks 11.1 s against 13.4 s, 3,472 blocks for 0.1 s 5.7 s
/// against 9.3-10.3 s; 826 blocks for 1 s 7.37 s against 7.42 s, for 0.1 s 1.06 s against
/// 0.83-0.88 s. A hand-written pit wall of 2,159 bolted, glued and frictional blocks,
/// 0.05 s with its settling: 46 s against 89 s. The crossing lies near 1,000 blocks;
/// this keeps the direct solve's exact answers to 1,500 (it was 3,000, and 6,000
/// before that).
pub const ITERATIVE_FROM_BLOCKS: usize = 1_500;

/// The largest error of a vertex's motion an iterative solve leaves, as a fraction of
/// d_tol. Our choice: a gap error of 1e-8 d_tol, times a normal penalty, is a force some
/// ten thousand times under a block's weight in the paper's columns, under the band
/// within which the open-close iteration keeps a contact's state (docs/method.md
/// section 6).
pub const ITERATIVE_TOLERANCE: f64 = 1e-8;

/// Most conjugate-gradient iterations of one solve; past them the attempt is treated as
/// an open-close iteration that did not converge (dt is cut, which also conditions the
/// system better).
pub const MAX_CG_ITERATIONS: u32 = 2000;

/// Free blocks from which `solver = "auto"` solves the settling's static steps
/// iteratively (docs/method.md section 13); below, they are solved directly whatever the
/// run takes. A static step is stiff by construction: its inertia is at most a hundredth
/// of the penalty for the heaviest block, far less for the others, so conjugate gradients
/// take hundreds of iterations a solve where the factor's cost does not depend on it.
/// Measured on a benched pit wall written by hand (bedding 0.35 m and cross joints 0.4 m
/// apart, glued parts, bolts, friction and cohesion; docs/scaling.md), one process at a
/// time, seconds a static step direct against iterative: 2,158 blocks 0.069 against 0.22
/// (3.2 times), 8,418 blocks 0.69 against 1.12 to 1.33 (1.6 to 1.9 times), 18,668 blocks
/// 1.9 against 1.05 (the iterative the faster): the crossing near 12,000 blocks.
pub const SETTLE_ITERATIVE_FROM_BLOCKS: usize = 10_000;

/// Whether a scene of `n_free` free blocks is solved iteratively under `choice`.
pub fn solves_iteratively(choice: SolverChoice, n_free: usize) -> bool {
    match choice {
        SolverChoice::Direct => false,
        SolverChoice::Iterative => true,
        SolverChoice::Auto => n_free >= ITERATIVE_FROM_BLOCKS,
    }
}

/// The solve of the settling's static steps for a scene of `n_free` free blocks under
/// `choice`: the scene's own where it names one, else by
/// [`SETTLE_ITERATIVE_FROM_BLOCKS`].
pub fn settling_solver(choice: SolverChoice, n_free: usize) -> SolverChoice {
    match choice {
        SolverChoice::Auto if n_free < SETTLE_ITERATIVE_FROM_BLOCKS => SolverChoice::Direct,
        SolverChoice::Auto => SolverChoice::Iterative,
        named => named,
    }
}

impl Simulation {
    /// Solves the assembled system iteratively. At the attempt's first solve the start
    /// is each block's velocity times dt and the stop's data are made: each block's own
    /// terms of K (its inertia c / dt^2 M, with c = 2 under Shi's rule, 16/9 under its
    /// damped form and 4 under the average acceleration, its elasticity and its fixed
    /// points: the lower bound of K
    /// the stop is stated in) and the largest reach of a vertex (see
    /// `solver::iterative`). Later solves of the attempt start from the last solution.
    pub(crate) fn solve_iteratively(&mut self) -> Iterated {
        let nd = self.nd;
        if !self.scratch.iteration_ready {
            self.scratch.iteration_ready = true;
            let dt = self.scratch.attempt_dt;
            let mut reach = 0.0f64;
            for (f, &i) in self.free_blocks.iter().enumerate() {
                let shape = &self.scratch.shapes[i as usize];
                if let Some(l) = chol(&self.scratch.base_k[f], nd) {
                    for &v in &shape.vertices {
                        reach = reach.max(vertex_reach(&l, nd, &t_rows(v, shape.centroid)));
                    }
                }
                let v = self.state.blocks[i as usize].velocity;
                let start: [f64; 6] = std::array::from_fn(|k| v[k] * dt);
                self.scratch.system.set_start(f as u32, &start);
            }
            self.scratch.reach = reach;
            self.scratch.system.set_lower_bound(&self.scratch.base_k);
        }
        let tol = ITERATIVE_TOLERANCE * self.model.params.d_tol;
        self.scratch
            .system
            .solve_iterative(self.scratch.reach, tol, MAX_CG_ITERATIONS)
    }
}

/// The largest eigenvalue of T K_o^-1 T^T for a vertex's two rows T and the Cholesky
/// factor `l` of a block's own terms K_o: how far the vertex can move per unit of the
/// block's error weighted by them.
fn vertex_reach(l: &Mat6, nd: usize, rows: &[Vec6; 2]) -> f64 {
    // y_k = L^-1 t_k; then the 2 x 2 Gram matrix of y_0 and y_1.
    let (mut y0, mut y1) = (rows[0], rows[1]);
    forward_solve(l, nd, &mut y0);
    forward_solve(l, nd, &mut y1);
    let (a, b, c) = (dot(&y0, &y0, nd), dot(&y0, &y1, nd), dot(&y1, &y1, nd));
    0.5 * (a + c) + (0.25 * (a - c) * (a - c) + b * b).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Under `auto` the settling is solved directly below its own threshold whatever the
    /// run takes, and iteratively from it; a solve the scene names is kept.
    #[test]
    fn the_settling_takes_the_named_solve_or_the_direct_one_below_its_threshold() {
        let below = SETTLE_ITERATIVE_FROM_BLOCKS - 1;
        assert!(solves_iteratively(SolverChoice::Auto, below));
        assert_eq!(
            settling_solver(SolverChoice::Auto, below),
            SolverChoice::Direct
        );
        assert_eq!(
            settling_solver(SolverChoice::Auto, SETTLE_ITERATIVE_FROM_BLOCKS),
            SolverChoice::Iterative
        );
        for n in [1, below, SETTLE_ITERATIVE_FROM_BLOCKS] {
            for named in [SolverChoice::Direct, SolverChoice::Iterative] {
                assert_eq!(settling_solver(named, n), named);
            }
        }
    }
}
