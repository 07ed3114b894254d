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
