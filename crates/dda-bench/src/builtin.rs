//! Built-in scenes: runnable without a file (`dda run NAME`, `dda scenes`).

use crate::column::undamped;
use crate::hard_cases::HARD_CASES;
use crate::masonry::Masonry;
use crate::paper::PAPER_COLUMNS;
use dda_core::Scene;
use dda_core::scene::Integration;

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

/// All built-in scenes: the paper's section 4 hard cases and section 5 columns, then
/// structures on flush joints (running-bond walls and a grid of equal blocks).
pub const BUILTINS: [Builtin; 15] = [
    Builtin {
        name: "paper-4.1-sharp-corners",
        description: "paper 4.1: triangles with 11.4 deg tips, A at 1 m/s onto fixed B \
                      (Table 1)",
        build: || HARD_CASES[0].scene(),
    },
    Builtin {
        name: "paper-4.2-short-edges",
        description: "paper 4.2: 18-gons with 0.35 m edges, A at 5 m/s onto fixed B (Table 1)",
        build: || HARD_CASES[1].scene(),
    },
    Builtin {
        name: "paper-4.3a-flat-polygons",
        description: "paper 4.3a: flat plates with 0.02 m edges, A at 1 m/s onto fixed B, \
                      d_tol 0.2 m (Table 1)",
        build: || HARD_CASES[2].scene(),
    },
    Builtin {
        name: "paper-4.3b-flat-polygons",
        description: "paper 4.3b: flat plates with 0.02 m edges, A at 1 m/s onto fixed B, \
                      d_tol 0.01 m (Table 1)",
        build: || HARD_CASES[3].scene(),
    },
    Builtin {
        name: "paper-4.4a-corner-small-edge",
        description: "paper 4.4a: a 0.02 m edge at 5 m/s onto a fixed corner, d_tol 0.2 m, \
                      penalty 3e10 (Table 2)",
        build: || HARD_CASES[4].scene(),
    },
    Builtin {
        name: "paper-4.4b-corner-small-edge",
        description: "paper 4.4b: a 0.02 m edge at 5 m/s onto a fixed corner, d_tol 0.01 m, \
                      penalty 3e10 (Table 2)",
        build: || HARD_CASES[5].scene(),
    },
    Builtin {
        name: "paper-4.4c-corner-small-edge",
        description: "paper 4.4c: a 0.02 m edge at 5 m/s onto a fixed corner, d_tol 0.01 m, \
                      penalty 3e6 (Table 2)",
        build: || HARD_CASES[6].scene(),
    },
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
    Builtin {
        name: "wall-106",
        description: "running-bond brick wall, 10 courses of 10 bricks of 1 x 0.5 m (106 \
                      blocks) on a fixed base, friction 35 deg, shear penalty p/2.5, 1 s",
        build: || unloaded(Masonry::wall(10, 10, 2.5).scene("wall-106")),
    },
    Builtin {
        name: "wall-411",
        description: "running-bond brick wall, 20 courses of 20 bricks (411 blocks), shear \
                      penalty p/2.5, 1 s",
        build: || unloaded(Masonry::wall(20, 20, 2.5).scene("wall-411")),
    },
    Builtin {
        name: "wall-411-stiff-shear",
        description: "the 411-block wall with shear penalty p, 1 s",
        build: || unloaded(Masonry::wall(20, 20, 1.0).scene("wall-411-stiff-shear")),
    },
    Builtin {
        name: "grid-201",
        description: "a 10 x 20 grid of 0.5 m blocks (X-junctions at every corner) on a \
                      fixed base, friction 35 deg, 1 s",
        build: || unloaded(Masonry::grid(10, 20, 0.5).scene("grid-201")),
    },
];

/// `scene` starting from its unloaded contacts (`settle = false`), its blocks' strain
/// and its contacts undamped (`damping = 0`, `contact_damping = 0`), stepped by Shi's
/// rule (`integration = "constant-acceleration"`): the built-in walls and grid, run
/// beside ntdda, which starts so, has no damping and steps so (docs/performance.md),
/// and whose standing on flush joints the open-close iteration is tested on from that
/// start.
fn unloaded(mut scene: Scene) -> Scene {
    scene.analysis.settle = Some(false);
    scene.analysis.contact_damping = Some(0.0);
    scene.analysis.integration = Some(Integration::ConstantAcceleration);
    scene.materials = undamped(scene.materials);
    scene
}

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
            assert!(model.blocks.len() >= 2, "{} has no blocks", b.name);
        }
        assert!(builtin(DEFAULT_BUILTIN).is_some());
        let names: Vec<String> = HARD_CASES
            .iter()
            .map(|c| c.name())
            .chain(PAPER_COLUMNS.iter().map(|c| c.name()))
            .chain(["wall-106", "wall-411", "wall-411-stiff-shear", "grid-201"].map(String::from))
            .collect();
        assert_eq!(BUILTINS.map(|b| b.name.to_string()).to_vec(), names);
        assert!(builtin("nope").is_none());
    }
}
