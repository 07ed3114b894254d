//! The paper's section 5 scenes (Zhuang, Zheng et al. 2021): a 10 m x 20 m column on a
//! fixed frictionless base, cut by one joint set at 60 deg (5.1a: 20 blocks, 5.1b: 93) or
//! by two sets at 60 and 15 deg (5.2a: 229, 5.2b: 826), collapsing under gravity for 1 s
//! with the parameters of Table 3.
//!
//! The paper shows the columns only as figures. Ours have exactly the paper's block counts
//! and a smallest edge within 10% of Table 3's; the joint spacings and first-joint
//! positions below were found by `examples/fit_columns.rs` (joint layout rules in
//! [`crate::layout`]), and `tests::columns_match_table_3` re-measures both.

use crate::column::{column_scene, paper_analysis};
use crate::layout::{JointLayout, SetLayout, place_joints};
use dda_core::Scene;
use dda_core::scene::Analysis;
use dda_geom::{ConvexPolygon, DVec2, cut_by_lines, shapes};

/// One of the paper's section 5 columns: Table 3's figures and our joint layout.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperColumn {
    /// The paper's case, e.g. "5.2b".
    pub case: &'static str,
    /// Number of blocks (Table 3).
    pub blocks: usize,
    /// Smallest block edge, m (Table 3).
    pub min_edge: f64,
    /// Max displacement per step, m (Table 3: 0.1 x the smallest edge).
    pub max_displacement: f64,
    /// Contact tolerance d_tol, m (Table 3: twice the max displacement).
    pub contact_tolerance: f64,
    /// Initial time step, s (Table 3).
    pub time_step: f64,
    /// Normal penalty, N/m (Table 3).
    pub penalty: f64,
    /// Joint sets: (dip in degrees, spacing in m, first joint as a fraction of spacing).
    sets: &'static [(f64, f64, f64)],
    /// The least edge the joint layout may make, m.
    layout_min_edge: f64,
}

/// The four columns of section 5, in the paper's order.
pub const PAPER_COLUMNS: [PaperColumn; 4] = [
    PaperColumn {
        case: "5.1a",
        blocks: 20,
        min_edge: 0.243,
        max_displacement: 0.0243,
        contact_tolerance: 0.0487,
        time_step: 0.05,
        penalty: 3e10,
        sets: &[(60.0, 0.9591, 0.5)],
        layout_min_edge: 0.2236,
    },
    PaperColumn {
        case: "5.1b",
        blocks: 93,
        min_edge: 0.2,
        max_displacement: 0.02,
        contact_tolerance: 0.04,
        time_step: 0.02,
        penalty: 3e10,
        sets: &[(60.0, 0.19984, 0.5)],
        layout_min_edge: 0.2,
    },
    PaperColumn {
        case: "5.2a",
        blocks: 229,
        min_edge: 0.135,
        max_displacement: 0.0135,
        contact_tolerance: 0.027,
        time_step: 0.02,
        penalty: 3e9,
        sets: &[(60.0, 0.96471, 0.7), (15.0, 0.79728, 0.3)],
        layout_min_edge: 0.1242,
    },
    PaperColumn {
        case: "5.2b",
        blocks: 826,
        min_edge: 0.13,
        max_displacement: 0.013,
        contact_tolerance: 0.026,
        time_step: 0.005,
        penalty: 3e9,
        sets: &[(60.0, 0.4506, 0.1), (15.0, 0.3724, 0.9)],
        layout_min_edge: 0.1248,
    },
];

impl PaperColumn {
    /// The built-in scene name, e.g. `paper-5.2b-column-826`.
    pub fn name(&self) -> String {
        format!("paper-{}-column-{}", self.case, self.blocks)
    }

    /// The joint layout that cuts this column.
    pub fn layout(&self) -> JointLayout {
        JointLayout {
            sets: self
                .sets
                .iter()
                .map(|&(dip_deg, spacing, start)| SetLayout {
                    dip_deg,
                    spacing,
                    start,
                })
                .collect(),
            min_edge: self.layout_min_edge,
        }
    }

    /// The column's blocks, lower-left corner at the origin.
    pub fn blocks(&self) -> Vec<ConvexPolygon> {
        self.scaled_blocks(1.0)
    }

    /// The blocks of a column `scale` times as wide and as tall, cut by the same joint
    /// layout (about scale^2 times as many blocks of the same sizes): for scaling studies.
    pub fn scaled_blocks(&self, scale: f64) -> Vec<ConvexPolygon> {
        let (w, h) = (10.0 * scale, 20.0 * scale);
        let lines = place_joints(w, h, &self.layout());
        // The rectangle and the lines are fixed and valid; an error here is a bug.
        shapes::rectangle(DVec2::ZERO, DVec2::new(w, h))
            .ok()
            .and_then(|region| cut_by_lines(&region, &lines, 0.0).ok())
            .map(|c| c.blocks)
            .unwrap_or_default()
    }

    /// Table 3's analysis: dynamic, 1.0 s, max rotation 2 deg, g = 9.8 m/s^2.
    pub fn analysis(&self) -> Analysis {
        paper_analysis(
            1.0,
            self.time_step,
            self.max_displacement,
            self.contact_tolerance,
            self.penalty,
            Some([0.0, -9.8]),
        )
    }

    /// The scene: the column on a fixed frictionless base, rock of section 5 (density
    /// 2600 kg/m^3, E = 1 GPa, nu = 0.3), frictionless joints.
    pub fn scene(&self) -> Scene {
        column_scene(&self.name(), &self.blocks(), self.analysis())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Block counts exact and smallest edge within 10% of Table 3, measured on the cut.
    #[test]
    fn columns_match_table_3() {
        for c in PAPER_COLUMNS {
            let blocks = c.blocks();
            assert_eq!(blocks.len(), c.blocks, "{}", c.case);
            let shortest = blocks
                .iter()
                .map(|b| b.shortest_edge().1)
                .fold(f64::INFINITY, f64::min);
            assert!(
                (shortest - c.min_edge).abs() <= 0.1 * c.min_edge,
                "{}: smallest edge {shortest}",
                c.case
            );
            let area: f64 = blocks.iter().map(ConvexPolygon::area).sum();
            assert!((area - 200.0).abs() < 1e-9, "{}: area {area}", c.case);
        }
    }
}
