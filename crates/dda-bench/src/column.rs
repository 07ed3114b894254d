//! Jointed rock columns (paper section 5): a rectangle cut by joint sets, standing on a
//! fixed base, under gravity.

use dda_core::Scene;
use dda_core::scene::{Analysis, BlockSpec, Integration, Joint, Material, Mode, Plane};
use dda_geom::{
    ConvexPolygon, DVec2, JointSet, JointSetError, PolygonError, cut_by_joint_sets, shapes,
};
use std::collections::BTreeMap;

/// A column to cut: its size, the joint sets, and the sliver threshold.
#[derive(Clone, Debug, PartialEq)]
pub struct ColumnSpec {
    /// Width, m.
    pub width: f64,
    /// Height, m.
    pub height: f64,
    /// Joint sets cutting it.
    pub sets: Vec<JointSet>,
    /// Pieces smaller than this area (m^2) are dropped as slivers.
    pub min_area: f64,
}

/// Why a column could not be cut.
#[derive(Clone, Debug, PartialEq)]
pub enum ColumnError {
    /// The column's rectangle is invalid (size not finite and positive).
    Region(PolygonError),
    /// A joint set is invalid.
    Cut(JointSetError),
}

impl std::fmt::Display for ColumnError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ColumnError::Region(e) => write!(f, "column rectangle: {e}"),
            ColumnError::Cut(e) => write!(f, "joint sets: {e}"),
        }
    }
}

impl std::error::Error for ColumnError {}

/// The blocks of a column with its lower-left corner at the origin.
pub fn jointed_column(spec: &ColumnSpec) -> Result<Vec<ConvexPolygon>, ColumnError> {
    let region = shapes::rectangle(DVec2::ZERO, DVec2::new(spec.width, spec.height))
        .map_err(ColumnError::Region)?;
    let cut = cut_by_joint_sets(&region, &spec.sets, spec.min_area).map_err(ColumnError::Cut)?;
    Ok(cut.blocks)
}

/// A scene of `blocks` standing on a fixed, frictionless base 1 m thick that extends a
/// column height to each side, under gravity 9.8 m/s^2, with the rock of paper section 5
/// (density 2600 kg/m^3, E = 1 GPa, nu = 0.3) and frictionless joints.
pub fn column_scene(name: &str, blocks: &[ConvexPolygon], analysis: Analysis) -> Scene {
    let bb = blocks
        .iter()
        .map(|b| b.aabb())
        .reduce(|a, b| a.union(&b))
        .unwrap_or(dda_geom::Aabb {
            min: DVec2::ZERO,
            max: DVec2::ONE,
        });
    let reach = bb.size().y.max(bb.size().x);
    let (x0, x1, y) = (bb.min.x - reach, bb.max.x + reach, bb.min.y);
    let spec = |id: String, vertices, fixed| rock_block(&id, vertices, fixed);
    let mut specs = vec![spec(
        "base".into(),
        vec![[x0, y - 1.0], [x1, y - 1.0], [x1, y], [x0, y]],
        true,
    )];
    for (i, b) in blocks.iter().enumerate() {
        specs.push(spec(
            format!("b{i}"),
            b.vertices().iter().map(|v| [v.x, v.y]).collect(),
            false,
        ));
    }
    Scene {
        name: name.into(),
        analysis,
        materials: undamped(rock(2600.0, 1e9, 0.3)),
        joints: BTreeMap::from([("default".into(), Joint::default())]),
        blocks: specs,
        joint_sets: BTreeMap::new(),
        regions: Vec::new(),
        excavations: Vec::new(),
        bolts: Vec::new(),
        measure: Vec::new(),
        seismic: None,
    }
}

/// The paper's analysis settings (Tables 1-3): dynamic, max rotation 2 deg, the cover
/// detector, deformable blocks in plane stress, at most 6 OCI iterations, 10 frames,
/// Shi's constant-acceleration rule (the paper's DDA; not the default, which damps
/// stiff modes: docs/method.md section 12).
pub fn paper_analysis(
    duration: f64,
    time_step: f64,
    max_displacement: f64,
    contact_tolerance: f64,
    penalty: f64,
    gravity: Option<[f64; 2]>,
) -> Analysis {
    Analysis {
        mode: Mode::Dynamic,
        duration,
        time_step,
        max_displacement,
        max_rotation_deg: 2.0,
        contact_tolerance: Some(contact_tolerance),
        normal_penalty: penalty,
        shear_penalty: None,
        fixed_penalty: None,
        detector: "cover".into(),
        gravity,
        deformable: true,
        plane: Plane::Stress,
        max_oci: 6,
        frames: 10,
        impact_steps: None,
        integration: Some(Integration::ConstantAcceleration),
        settle: Some(false),
        solver: None,
        contact_damping: Some(0.0),
    }
}

/// A block of the material `rock`, at rest, without loads or fixed points.
pub(crate) fn rock_block(id: &str, vertices: Vec<[f64; 2]>, fixed: bool) -> BlockSpec {
    BlockSpec {
        id: id.into(),
        material: "rock".into(),
        vertices,
        fixed,
        velocity: None,
        angular_velocity: None,
        stress: None,
        loads: Vec::new(),
        fixed_points: Vec::new(),
        ..Default::default()
    }
}

/// `materials` with no damping of the blocks' strain (`damping = 0`): the paper's scenes,
/// which Shi's undamped blocks are for, and the scenes run beside ntdda.
pub fn undamped(mut materials: BTreeMap<String, Material>) -> BTreeMap<String, Material> {
    for m in materials.values_mut() {
        m.damping = Some(0.0);
    }
    materials
}

/// The materials of a one-rock scene: `rock` with this density, E and nu, its blocks'
/// strain damped as the scene format's default (`damping` unset).
pub(crate) fn rock(density: f64, young: f64, poisson: f64) -> BTreeMap<String, Material> {
    BTreeMap::from([(
        "rock".into(),
        Material {
            density,
            young: Some(young),
            poisson: Some(poisson),
            damping: None,
        },
    )])
}
