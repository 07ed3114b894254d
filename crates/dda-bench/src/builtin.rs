//! Built-in scenes: runnable without a file (`dda run NAME`, `dda scenes`).

use crate::paper::PAPER_COLUMNS;
use dda_core::Scene;

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
pub const DEFAULT_BUILTIN: &str = "paper-5.1b-column-93";

/// All built-in scenes.
pub const BUILTINS: [Builtin; 4] = [
    Builtin {
        name: "paper-5.1a-column-20",
        description: "paper 5.1a: 10 m x 20 m column, one joint set at 60 deg, 20 blocks, \
                      frictionless, collapsing under gravity for 1 s (Table 3)",
        build: || PAPER_COLUMNS[0].scene(),
    },
    Builtin {
        name: "paper-5.1b-column-93",
        description: "paper 5.1b: 10 m x 20 m column, one joint set at 60 deg, 93 blocks, \
                      frictionless, 1 s (Table 3)",
        build: || PAPER_COLUMNS[1].scene(),
    },
    Builtin {
        name: "paper-5.2a-column-229",
        description: "paper 5.2a: 10 m x 20 m column, joint sets at 60 and 15 deg, \
                      229 blocks, frictionless, 1 s (Table 3)",
        build: || PAPER_COLUMNS[2].scene(),
    },
    Builtin {
        name: "paper-5.2b-column-826",
        description: "paper 5.2b: 10 m x 20 m column, joint sets at 60 and 15 deg, \
                      826 blocks, frictionless, 1 s (Table 3)",
        build: || PAPER_COLUMNS[3].scene(),
    },
];

/// The built-in scene called `name`.
pub fn builtin(name: &str) -> Option<Scene> {
    BUILTINS
        .iter()
        .find(|b| b.name == name)
        .map(|b| (b.build)())
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
        for (b, c) in BUILTINS.iter().zip(PAPER_COLUMNS) {
            assert_eq!(b.name, c.name());
        }
        assert!(builtin("nope").is_none());
    }
}
