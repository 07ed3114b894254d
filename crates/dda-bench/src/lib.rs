//! Scene generators for dda-rs: jointed columns cut with `dda-geom`, and the built-in
//! scenes the `dda` command runs without a file.

pub mod builtin;
pub mod column;

pub use self::builtin::{BUILTINS, Builtin, DEFAULT_BUILTIN, builtin};
pub use self::column::{ColumnError, ColumnSpec, column_analysis, column_scene, jointed_column};
