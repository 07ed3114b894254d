//! The paper's two-set columns (section 5.2: 229 and 826 blocks, joint sets at 60 and 15
//! degrees, frictionless) collapse under gravity permissibly with every detector at
//! r_tol 1, as the paper ran TB-CD-2 through them: each run completes, no contact
//! penetrates d_tol, and at every step the collapse verdict holds (kinetic energy within
//! the potential energy released plus 0.2% of m g H, no block faster than 3 g t;
//! `dda_bench::collapse`).

// A panic is how a test reports failure.
#![allow(clippy::unwrap_used)]

use dda::bench::{PAPER_COLUMNS, run_watched};
use dda::core::{RunOptions, Simulation};

#[test]
fn two_set_columns_collapse_permissibly_with_every_detector() {
    for blocks in [229, 826] {
        let column = PAPER_COLUMNS.iter().find(|c| c.blocks == blocks).unwrap();
        for detector in ["cover", "type-1", "type-2"] {
            let mut scene = column.scene();
            scene.analysis.detector = detector.into();
            let model = scene.validate().unwrap();
            let d_tol = model.params.d_tol;
            let mut sim = Simulation::new(model, RunOptions::default());
            let (watch, stop) = run_watched(&mut sim, u64::MAX);
            assert_eq!(stop, None, "{blocks} blocks, {detector}");
            let deepest = sim.totals().max_penetration;
            assert!(
                deepest < d_tol,
                "{blocks} blocks, {detector}: penetration {deepest} m, d_tol {d_tol} m"
            );
            assert!(
                watch.permissible(),
                "{blocks} blocks, {detector}: {:?}",
                watch.failures()
            );
        }
    }
}

/// One step of the paper's 20-block column (elastic blocks stacked on a fixed base, from
/// rest) solved iteratively moves every vertex to within the iterative solve's stated
/// bound of the direct solve's motion, 1e-8 d_tol (`ITERATIVE_TOLERANCE`,
/// docs/method.md section 14: stated in each block's own terms of K, inertia, elasticity
/// and fixed points, a lower bound of K), plus the rounding of the coordinates; the
/// open-close iteration takes the same decisions both ways.
#[test]
fn one_step_solved_iteratively_lies_within_its_bound_of_the_direct_step() {
    use dda::core::iterative::ITERATIVE_TOLERANCE;
    use dda::core::scene::SolverChoice;
    let step = |solver| {
        let mut scene = dda::bench::builtin("paper-5.1a-column-20").unwrap();
        scene.analysis.solver = Some(solver);
        let model = scene.validate().unwrap();
        let d_tol = model.params.d_tol;
        let mut sim = Simulation::new(model, RunOptions::default());
        let record = sim.step().unwrap();
        assert_eq!(sim.solves_iteratively(), solver == SolverChoice::Iterative);
        let vertices: Vec<_> = sim
            .blocks()
            .iter()
            .flat_map(|b| b.polygon.vertices().to_vec())
            .collect();
        (record, vertices, d_tol)
    };
    let (direct, at_direct, d_tol) = step(SolverChoice::Direct);
    let (iterative, at_iterative, _) = step(SolverChoice::Iterative);
    assert_eq!((direct.oci, direct.cuts), (iterative.oci, iterative.cuts));
    let bound = ITERATIVE_TOLERANCE * d_tol;
    let mut worst = 0.0f64;
    for (a, b) in at_direct.iter().zip(&at_iterative) {
        // The rounding of a coordinate of the size of the column's (metres).
        let rounding = 8.0 * f64::EPSILON * a.length().max(1.0);
        let off = (*a - *b).length();
        assert!(
            off <= bound + rounding,
            "a vertex {off:e} m apart, bound {bound:e} m"
        );
        worst = worst.max(off);
    }
    // The solves differ at all: the comparison is not of one solve with itself.
    assert!(worst > 0.0);
}
