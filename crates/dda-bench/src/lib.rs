//! Scene generators for dda-rs: jointed columns cut with `dda-geom`, the paper's section 4
//! hard cases and section 5 columns, and the built-in scenes the `dda` command runs
//! without a file.

pub mod analytic;
pub mod builtin;
pub mod collapse;
pub mod column;
pub mod hard_cases;
pub mod layout;
pub mod masonry;
pub mod paper;
pub mod verdict;

pub use self::builtin::{BUILTINS, Builtin, DEFAULT_BUILTIN, builtin};
pub use self::collapse::{
    CollapseWatch, ENERGY_MARGIN, SPEED_FACTOR, Stop, Worst, potential_energy, run_watched,
};
pub use self::column::{
    ColumnError, ColumnSpec, column_scene, jointed_column, paper_analysis, undamped,
};
pub use self::hard_cases::{HARD_CASES, HardCase, collision_scene};
pub use self::masonry::{Layout, Masonry};
pub use self::paper::{PAPER_COLUMNS, PaperColumn};
pub use self::verdict::{Outcome, judge_collision, judge_collision_with, mechanical_energy};
