//! Rock masses from a scene file (docs/scene-format.md, "Regions and joint sets"): each
//! `[[regions]]` entry is a convex outline cut by the scene's `[joint_sets]` into convex
//! blocks, named `ID.1`, `ID.2`, ... in the order the cutting makes them. [`expand`]
//! turns a scene with regions into the explicit scene, every block listed, that `dda
//! build` writes and a run records; the engine only ever sees explicit blocks.

use crate::limits;
use crate::model::{outline, start_overlap};
use crate::scene::{BlockSpec, Invalid, Scene, invalid};
use dda_geom::{ConvexPolygon, JointSet, PolygonError, cut_by_joint_sets, separation};

/// What expanding the regions dropped: per region, the pieces below its `min_area`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dropped {
    /// (region index, pieces dropped, their total area in m^2), for regions that dropped
    /// any.
    pub slivers: Vec<(usize, usize, f64)>,
}

/// The scene with every region replaced by the blocks it is cut into (after the
/// explicit blocks, region by region) and no joint sets left, and what was dropped.
/// Errors name the key: `regions[i].vertices[k]`, `regions[i].joint_sets[k]`,
/// `joint_sets.NAME.spacing`, ...
pub fn expand(scene: &Scene) -> Result<(Scene, Dropped), Invalid> {
    let mut sets = std::collections::BTreeMap::new();
    for (name, s) in &scene.joint_sets {
        let key = format!("joint_sets.{name}");
        if !(s.dip_deg.is_finite() && (-360.0..=360.0).contains(&s.dip_deg)) {
            return Err(invalid(
                format!("{key}.dip_deg"),
                format!(
                    "must be an angle in degrees between -360 and 360, got {}",
                    s.dip_deg
                ),
            ));
        }
        if !(s.spacing.is_finite() && s.spacing > 0.0 && s.spacing <= limits::COORDINATE.max) {
            return Err(invalid(
                format!("{key}.spacing"),
                format!("must be a positive distance in m, got {}", s.spacing),
            ));
        }
        if !limits::COORDINATE.contains(s.offset) {
            return Err(invalid(
                format!("{key}.offset"),
                limits::COORDINATE.message(s.offset),
            ));
        }
        sets.insert(
            name.as_str(),
            JointSet {
                dip_deg: s.dip_deg,
                spacing: s.spacing,
                offset: s.offset,
            },
        );
    }
    let mut out = scene.clone();
    out.joint_sets.clear();
    out.regions.clear();
    let mut dropped = Dropped::default();
    let mut outlines: Vec<ConvexPolygon> = Vec::new();
    let mut total = 0.0;
    for (i, r) in scene.regions.iter().enumerate() {
        let key = format!("regions[{i}]");
        if r.id.trim().is_empty() {
            return Err(invalid(format!("{key}.id"), "must not be empty"));
        }
        let shape = outline(&key, &r.vertices, |e| {
            let hint = if matches!(e, PolygonError::NotConvex { .. }) {
                " (a region's outline must be convex for now: split it into convex regions \
                 that share their edges)"
            } else {
                ""
            };
            format!("region `{}`: {e}{hint}", r.id)
        })?;
        for (j, other) in outlines.iter().enumerate() {
            let depth = -separation(&shape, other).0;
            if depth > start_overlap(&shape, other) {
                return Err(invalid(
                    format!("{key}.vertices"),
                    format!(
                        "region `{}` overlaps region `{}` (regions[{j}]) by {depth:e} m",
                        r.id, scene.regions[j].id
                    ),
                ));
            }
        }
        let mut cut_by = Vec::new();
        let mut estimate = 1.0;
        for (k, name) in r.joint_sets.iter().enumerate() {
            let set = sets.get(name.as_str()).ok_or_else(|| {
                invalid(
                    format!("{key}.joint_sets[{k}]"),
                    format!(
                        "no joint set named `{name}` (defined: {})",
                        if sets.is_empty() {
                            "none".to_string()
                        } else {
                            sets.keys().copied().collect::<Vec<_>>().join(", ")
                        }
                    ),
                )
            })?;
            let (lo, hi) = shape.extent(set.normal());
            estimate *= (hi - lo) / set.spacing + 1.0;
            cut_by.push(*set);
        }
        total += estimate;
        if total > limits::MAX_REGION_BLOCKS {
            return Err(invalid(
                format!("{key}.joint_sets"),
                format!(
                    "the joint sets would cut the regions into about {total:.3e} blocks, more \
                     than {:e}: is a spacing in the wrong unit?",
                    limits::MAX_REGION_BLOCKS
                ),
            ));
        }
        let min_area = r.min_area.unwrap_or(1e-9 * shape.area());
        if !(min_area.is_finite() && min_area >= 0.0) {
            return Err(invalid(
                format!("{key}.min_area"),
                format!("must be an area in m^2, 0 or more, got {min_area}"),
            ));
        }
        let cut = cut_by_joint_sets(&shape, &cut_by, min_area).map_err(|e| {
            invalid(
                format!("{key}.joint_sets"),
                format!("region `{}`: {e}", r.id),
            )
        })?;
        if cut.blocks.is_empty() {
            return Err(invalid(
                format!("{key}.min_area"),
                format!(
                    "all {} pieces of region `{}` are smaller than min_area ({min_area:e} \
                     m^2), so nothing is left of it: is a spacing in the wrong unit?",
                    cut.dropped, r.id
                ),
            ));
        }
        if cut.dropped > 0 {
            dropped.slivers.push((i, cut.dropped, cut.dropped_area));
        }
        for (k, b) in cut.blocks.iter().enumerate() {
            out.blocks.push(BlockSpec {
                id: format!("{}.{}", r.id, k + 1),
                material: r.material.clone(),
                vertices: b.vertices().iter().map(|v| [v.x, v.y]).collect(),
                fixed: r.fixed,
                velocity: None,
                angular_velocity: None,
                stress: None,
                loads: Vec::new(),
                fixed_points: Vec::new(),
            });
        }
        outlines.push(shape);
    }
    Ok((out, dropped))
}
