//! Built-in scenes: runnable without a file (`dda run NAME`, `dda scenes`).

use crate::column::{ColumnSpec, column_analysis, column_scene, jointed_column};
use dda_core::Scene;
use dda_geom::JointSet;

/// A built-in scene: its name, a line about it, and how to build it.
#[derive(Clone, Copy, Debug)]
pub struct Builtin {
    /// Name, as `dda run NAME` spells it.
    pub name: &'static str,
    /// One line for `dda scenes`.
    pub description: &'static str,
    /// Builds the scene.
    pub build: fn() -> Scene,
}

/// The scene `dda run` runs when given none.
pub const DEFAULT_BUILTIN: &str = "column";

/// All built-in scenes.
pub const BUILTINS: [Builtin; 2] = [
    Builtin {
        name: "column",
        description: "10 m x 20 m column cut by one joint set at 60 deg (1.2 m spacing), \
                      frictionless, collapsing under gravity for 1 s",
        build: column,
    },
    Builtin {
        name: "column-two-sets",
        description: "10 m x 20 m column cut by joint sets at 60 and 15 deg \
                      (0.48 m and 0.40 m spacing, about 830 blocks), 1 s",
        build: column_two_sets,
    },
];

/// The built-in scene called `name`.
pub fn builtin(name: &str) -> Option<Scene> {
    BUILTINS
        .iter()
        .find(|b| b.name == name)
        .map(|b| (b.build)())
}

fn cut(spec: &ColumnSpec) -> Vec<dda_geom::ConvexPolygon> {
    // The specs below are fixed and valid; an error here is a bug in this file.
    jointed_column(spec).unwrap_or_default()
}

fn column() -> Scene {
    let spec = ColumnSpec {
        width: 10.0,
        height: 20.0,
        sets: vec![JointSet {
            dip_deg: 60.0,
            spacing: 1.2,
            offset: 0.3,
        }],
        min_area: 1e-3,
    };
    column_scene("column", &cut(&spec), column_analysis(0.01, 0.02, 3e10))
}

fn column_two_sets() -> Scene {
    let spec = ColumnSpec {
        width: 10.0,
        height: 20.0,
        sets: vec![
            JointSet {
                dip_deg: 60.0,
                spacing: 0.48,
                offset: 0.13,
            },
            JointSet {
                dip_deg: 15.0,
                spacing: 0.4,
                offset: 0.07,
            },
        ],
        min_area: 1e-4,
    };
    column_scene(
        "column-two-sets",
        &cut(&spec),
        column_analysis(0.005, 0.013, 3e9),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_validates() {
        for b in BUILTINS {
            let scene = (b.build)();
            assert_eq!(scene.name, b.name);
            let model = scene.validate().expect("valid built-in");
            assert!(model.blocks.len() > 2, "{} has no blocks", b.name);
        }
        assert!(builtin(DEFAULT_BUILTIN).is_some());
        assert!(builtin("nope").is_none());
    }
}
