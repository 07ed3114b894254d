//! Structures whose blocks meet along flush joints, on a fixed base: running-bond brick
//! walls (every face flush, T-junctions at every brick end), grids of equal blocks
//! (X-junctions at every corner) and stacks. They are what masonry and rock cut by
//! persistent joint sets look like, and what the open-close iteration must decide where
//! contacts sit at d_n = 0. The base may be tilted: the structure is then turned with it
//! about the base's top-left corner, gravity staying vertical.

use crate::column::{rock, rock_block};
use dda_core::Simulation;
use dda_core::scene::{Analysis, BlockSpec, Joint, Mode, Plane, Scene};
use dda_geom::DVec2;
use std::collections::BTreeMap;

/// The layout of a structure of rectangular blocks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Layout {
    /// A running-bond wall of `courses` courses of `bricks` bricks each; odd courses start
    /// and end with half bricks, so every face is flush.
    RunningBond {
        /// Bricks per course.
        bricks: usize,
        /// Courses.
        courses: usize,
    },
    /// A grid of `columns` x `rows` equal blocks: X-junctions at every inner corner.
    Grid {
        /// Blocks across.
        columns: usize,
        /// Blocks up.
        rows: usize,
    },
}

/// A structure on a fixed base, with the parameters of the open-close issue's walls:
/// density 2600, E 1 GPa, nu 0.25, dt 1 ms, d_max 0.01 m, d_tol 0.02 m, p 1e10. Its
/// scenes settle before the run, as a user's scene does (`analysis.settle` unset,
/// docs/method.md section 13); the built-in walls and grid, run beside ntdda, which
/// starts unloaded, state `settle = false`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Masonry {
    /// How the blocks are laid.
    pub layout: Layout,
    /// Block (brick) width, m.
    pub width: f64,
    /// Block (brick) height, m.
    pub height: f64,
    /// Friction angle of every joint, degrees.
    pub friction_deg: f64,
    /// Normal penalty, N/m.
    pub penalty: f64,
    /// Shear penalty over the normal penalty.
    pub shear_ratio: f64,
    /// Multiplies d_max (0.01 m) and d_tol (0.02 m) together.
    pub tolerance_scale: f64,
    /// Tilt of the base, degrees counter-clockwise.
    pub tilt_deg: f64,
    /// Simulated time, s.
    pub duration: f64,
}

impl Masonry {
    /// The wall: running bond, 1 x 0.5 m bricks, friction 35 deg, p 1e10, shear
    /// penalty p / `shear_ratio`, 1 s.
    pub fn wall(bricks: usize, courses: usize, shear_ratio: f64) -> Self {
        Masonry {
            layout: Layout::RunningBond { bricks, courses },
            width: 1.0,
            height: 0.5,
            friction_deg: 35.0,
            penalty: 1e10,
            shear_ratio,
            tolerance_scale: 1.0,
            tilt_deg: 0.0,
            duration: 1.0,
        }
    }

    /// A grid of equal square blocks of side `size`, otherwise as [`Masonry::wall`] with
    /// shear penalty p / 2.5.
    pub fn grid(columns: usize, rows: usize, size: f64) -> Self {
        Masonry {
            layout: Layout::Grid { columns, rows },
            width: size,
            height: size,
            ..Masonry::wall(1, 1, 2.5)
        }
    }

    /// The blocks' outlines, bottom course first, left to right, before the tilt.
    fn outlines(&self) -> Vec<[f64; 4]> {
        let (w, h) = (self.width, self.height);
        let mut out = Vec::new();
        match self.layout {
            Layout::RunningBond { bricks, courses } => {
                for c in 0..courses {
                    let (y0, y1) = (c as f64 * h, (c + 1) as f64 * h);
                    let mut xs = vec![0.0];
                    if c % 2 == 1 {
                        xs.extend((0..bricks).map(|i| (i as f64 + 0.5) * w));
                    } else {
                        xs.extend((1..bricks).map(|i| i as f64 * w));
                    }
                    xs.push(bricks as f64 * w);
                    for x in xs.windows(2) {
                        out.push([x[0], y0, x[1], y1]);
                    }
                }
            }
            Layout::Grid { columns, rows } => {
                for r in 0..rows {
                    for c in 0..columns {
                        let (x0, y0) = (c as f64 * w, r as f64 * h);
                        out.push([x0, y0, x0 + w, y0 + h]);
                    }
                }
            }
        }
        out
    }

    /// The structure's width, m.
    pub fn span(&self) -> f64 {
        self.outlines().iter().map(|o| o[2]).fold(0.0, f64::max)
    }

    /// Each block's slide down the tilted base since `start` (the blocks' centroids when
    /// the run began, base first) over g (sin a - cos a tan phi) t^2 / 2 at the time
    /// `sim` has reached: 1 for a block sliding as a rigid body slides at its friction
    /// limit. The base turns counter-clockwise, so down the slope is -(cos a, sin a).
    pub fn slide_ratios(&self, sim: &Simulation, start: &[DVec2]) -> Vec<f64> {
        let (sin, cos) = self.tilt_deg.to_radians().sin_cos();
        let down = DVec2::new(-cos, -sin);
        let t = sim.time();
        let exact = 0.5 * 9.81 * (sin - cos * self.friction_deg.to_radians().tan()) * t * t;
        sim.blocks()
            .iter()
            .zip(start)
            .skip(1)
            .map(|(b, s0)| (b.polygon.centroid() - *s0).dot(down) / exact)
            .collect()
    }

    /// The scene: the base (fixed, one block height deep, one width beyond each side),
    /// then the blocks, all turned by the tilt.
    pub fn scene(&self, name: &str) -> Scene {
        let (sin, cos) = self.tilt_deg.to_radians().sin_cos();
        let turn = |x: f64, y: f64| [x * cos - y * sin, x * sin + y * cos];
        let rect = |[x0, y0, x1, y1]: [f64; 4]| {
            vec![turn(x0, y0), turn(x1, y0), turn(x1, y1), turn(x0, y1)]
        };
        let span = self.span();
        let margin = self.width.max(self.height);
        let mut blocks: Vec<BlockSpec> = vec![rock_block(
            "base",
            rect([-margin, -margin, span + margin, 0.0]),
            true,
        )];
        for (k, o) in self.outlines().into_iter().enumerate() {
            blocks.push(rock_block(&format!("b{k}"), rect(o), false));
        }
        let r = self.tolerance_scale;
        Scene {
            name: name.into(),
            analysis: Analysis {
                mode: Mode::Dynamic,
                duration: self.duration,
                time_step: 0.001,
                max_displacement: 0.01 * r,
                max_rotation_deg: 2.0,
                contact_tolerance: Some(0.02 * r),
                normal_penalty: self.penalty,
                shear_penalty: Some(self.penalty / self.shear_ratio),
                fixed_penalty: None,
                detector: "cover".into(),
                gravity: Some([0.0, -9.81]),
                deformable: true,
                plane: Plane::Stress,
                max_oci: 6,
                frames: 2,
                impact_steps: None,
                integration: None,
                settle: None,
                solver: None,
                contact_damping: None,
            },
            materials: rock(2600.0, 1e9, 0.25),
            joints: BTreeMap::from([(
                "default".into(),
                Joint {
                    friction_deg: self.friction_deg,
                    ..Joint::default()
                },
            )]),
            blocks,
            joint_sets: BTreeMap::new(),
            regions: Vec::new(),
            excavations: Vec::new(),
            bolts: Vec::new(),
            measure: Vec::new(),
            seismic: None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every course of a running-bond wall spans the wall, and its joints are offset by
    /// half a brick from the course below: every face is flush and the wall validates.
    #[test]
    fn a_running_bond_wall_is_flush_and_valid() {
        let m = Masonry::wall(10, 10, 2.5);
        let outlines = m.outlines();
        // 10 courses: 5 of 10 bricks, 5 of 9 bricks and two halves.
        assert_eq!(outlines.len(), 5 * 10 + 5 * 11);
        for c in 0..10 {
            let course: Vec<_> = outlines.iter().filter(|o| o[1] == c as f64 * 0.5).collect();
            assert_eq!(course.first().map(|o| o[0]), Some(0.0));
            assert_eq!(course.last().map(|o| o[2]), Some(10.0));
        }
        let model = m.scene("wall").validate().expect("valid");
        assert_eq!(model.blocks.len(), 106);
        let tilted = Masonry {
            tilt_deg: 30.0,
            ..m
        };
        tilted
            .scene("tilted")
            .validate()
            .expect("valid when tilted");
    }
}
