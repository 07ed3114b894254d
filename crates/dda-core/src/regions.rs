//! Rock masses from a scene file (docs/scene-format.md, "Regions and joint sets"): each
//! `[[regions]]` entry is an outline (convex or not) cut by the scene's `[joint_sets]`
//! (persistent or not, regular or statistical) into pieces of rock, named `ID.1`,
//! `ID.2`, ... in the order the cutting makes them. A piece that is not convex is written
//! as its convex parts `ID.k.1`, `ID.k.2`, ... with `body = "ID.k"`: glued where they
//! touch. [`expand`] turns a scene with regions into the explicit scene, every block
//! listed, that `dda build` writes and a run records; the engine only ever sees explicit
//! blocks.

use crate::limits;
use crate::model::{point_reach, start_overlap};
use crate::scene::{BlockSpec, ExcavationSpec, Invalid, JointSetSpec, RegionSpec, Scene, invalid};
use dda_geom::{
    Aabb, ConvexPolygon, DVec2, Joint, JointFamily, JointSet, JointSetError, Line, Outline,
    PolygonError, cut_mass, separation,
};
use std::collections::BTreeMap;

/// What expanding the regions dropped: per region, the pieces below its `min_area`; per
/// excavation, the slivers its cutting left outside its outline.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Dropped {
    /// (region index, pieces dropped, their total area in m^2, the `min_area` applied),
    /// for regions that dropped any.
    pub slivers: Vec<(usize, usize, f64, f64)>,
    /// (excavation index, slivers dropped, their total area in m^2, the area below
    /// which a part is a sliver: d_tol^2), for excavations that dropped any.
    pub excavated: Vec<(usize, usize, f64, f64)>,
}

/// The statistical family of a `[joint_sets.NAME]` entry, its values checked.
fn family(
    name: &str,
    s: &JointSetSpec,
    joints: &BTreeMap<String, crate::scene::Joint>,
) -> Result<JointFamily, Invalid> {
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
    let mut set = JointSet {
        dip_deg: s.dip_deg,
        spacing: s.spacing,
        offset: 0.0,
    };
    set.offset = match (s.offset, s.through) {
        (Some(_), Some(_)) => {
            return Err(invalid(
                format!("{key}.through"),
                "give one of offset and through: both place the set's joints",
            ));
        }
        (_, Some(p)) => {
            if let Some(&c) = p.iter().find(|&&c| !limits::COORDINATE.contains(c)) {
                return Err(invalid(
                    format!("{key}.through"),
                    limits::COORDINATE.message(c),
                ));
            }
            set.normal().dot(DVec2::from(p))
        }
        (offset, None) => {
            let offset = offset.unwrap_or(0.0);
            if !limits::COORDINATE.contains(offset) {
                return Err(invalid(
                    format!("{key}.offset"),
                    limits::COORDINATE.message(offset),
                ));
            }
            offset
        }
    };
    if let Some(j) = &s.joint
        && !joints.contains_key(j)
    {
        return Err(invalid(
            format!("{key}.joint"),
            format!(
                "no joint named `{j}` (defined: {})",
                names_or_none(joints.keys().map(String::as_str))
            ),
        ));
    }
    let spacing_cv = s.spacing_cv.unwrap_or(0.0);
    if !(spacing_cv.is_finite() && (0.0..=0.5).contains(&spacing_cv)) {
        return Err(invalid(
            format!("{key}.spacing_cv"),
            format!("must be between 0 and 0.5, got {spacing_cv}"),
        ));
    }
    let dip_spread_deg = s.dip_spread_deg.unwrap_or(0.0);
    if !(dip_spread_deg.is_finite() && (0.0..=45.0).contains(&dip_spread_deg)) {
        return Err(invalid(
            format!("{key}.dip_spread_deg"),
            format!("must be between 0 and 45 degrees, got {dip_spread_deg}"),
        ));
    }
    let positive = |k: &str, v: f64| {
        if v.is_finite() && v > 0.0 && v <= limits::COORDINATE.max {
            Ok(v)
        } else {
            Err(invalid(
                format!("{key}.{k}"),
                format!("must be a positive length in m, got {v}"),
            ))
        }
    };
    let trace = match (s.trace_length, s.bridge) {
        (None, None) => None,
        (Some(t), Some(b)) => Some((positive("trace_length", t)?, positive("bridge", b)?)),
        (Some(_), None) => {
            return Err(invalid(
                format!("{key}.bridge"),
                "a set with trace_length needs bridge, the length of intact rock between \
                 traces along a joint (m)",
            ));
        }
        (None, Some(_)) => {
            return Err(invalid(
                format!("{key}.trace_length"),
                "a set with bridge needs trace_length, the length of each joint trace (m)",
            ));
        }
    };
    // Each set draws from its own stream: the seed mixed with the set's name (FNV-1a).
    let name_hash = name.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    });
    Ok(JointFamily {
        set,
        spacing_cv,
        dip_spread_deg,
        trace,
        trace_origin: s.through.map_or(DVec2::ZERO, DVec2::from),
        seed: s.seed.unwrap_or(0) ^ name_hash,
    })
}

fn names_or_none<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let v: Vec<&str> = names.collect();
    if v.is_empty() {
        "none".to_string()
    } else {
        v.join(", ")
    }
}

/// The outline of region (or excavation) `key` (a simple polygon, counter-clockwise),
/// its errors naming the vertex.
fn region_outline(key: &str, id: &str, vertices: &[[f64; 2]]) -> Result<Outline, Invalid> {
    for (i, v) in vertices.iter().enumerate() {
        for (k, &c) in v.iter().enumerate() {
            if !limits::COORDINATE.contains(c) {
                return Err(invalid(
                    format!("{key}.vertices[{i}][{k}]"),
                    limits::COORDINATE.message(c),
                ));
            }
        }
    }
    Outline::new(vertices.iter().map(|&c| DVec2::from(c)).collect()).map_err(|e| {
        let at = match e {
            PolygonError::DuplicateVertex { vertex, .. }
            | PolygonError::CollinearVertex { vertex }
            | PolygonError::NotConvex { vertex } => format!("{key}.vertices[{vertex}]"),
            PolygonError::SelfIntersecting { edge_a, .. } => format!("{key}.vertices[{edge_a}]"),
            _ => format!("{key}.vertices"),
        };
        let hint = match e {
            PolygonError::Clockwise => " (list the outline's vertices counter-clockwise)",
            PolygonError::SelfIntersecting { .. } => {
                " (an outline is one loop that never touches itself; edge k runs from vertex \
                 k to vertex k + 1)"
            }
            _ => "",
        };
        let what = if key.starts_with("excavations") {
            "excavation"
        } else {
            "region"
        };
        invalid(at, format!("{what} `{id}`: {e}{hint}"))
    })
}

/// The scene with every region replaced by the blocks it is cut into (after the
/// explicit blocks, region by region) and no joint sets left, and what was dropped.
/// Errors name the key: `regions[i].vertices[k]`, `regions[i].joint_sets[k]`,
/// `joint_sets.NAME.spacing`, ...
pub fn expand(scene: &Scene) -> Result<(Scene, Dropped), Invalid> {
    let mut families = BTreeMap::new();
    for (name, s) in &scene.joint_sets {
        families.insert(name.as_str(), family(name, s, &scene.joints)?);
    }
    let set_names: Vec<&str> = families.keys().copied().collect();
    let mut outlines = Vec::with_capacity(scene.regions.len());
    let mut parts: Vec<Vec<ConvexPolygon>> = Vec::with_capacity(scene.regions.len());
    for (i, r) in scene.regions.iter().enumerate() {
        let key = format!("regions[{i}]");
        if r.id.trim().is_empty() {
            return Err(invalid(format!("{key}.id"), "must not be empty"));
        }
        // A region's id names its blocks, and selects them (`seismic.blocks`).
        let clash = scene.regions[..i]
            .iter()
            .position(|o| o.id == r.id)
            .map(|j| format!("regions[{j}]"))
            .or_else(|| {
                let k = scene.blocks.iter().position(|b| b.id == r.id)?;
                Some(format!("blocks[{k}]"))
            });
        if let Some(other) = clash {
            return Err(invalid(
                format!("{key}.id"),
                format!(
                    "`{}` is also the id of {other}: a region's id names its blocks (`{}.1`, \
                     `{}.2`, ...) and selects them, so it must be unique",
                    r.id, r.id, r.id
                ),
            ));
        }
        if !scene.materials.contains_key(&r.material) {
            return Err(crate::model::no_material(
                &format!("{key}.material"),
                &r.material,
                scene,
            ));
        }
        let shape = region_outline(&key, &r.id, &r.vertices)?;
        let own: Vec<ConvexPolygon> = shape
            .convex_parts()
            .iter()
            .filter_map(|p| {
                ConvexPolygon::new(p.iter().map(|&k| shape.vertices()[k]).collect::<Vec<_>>()).ok()
            })
            .collect();
        for (j, other) in parts.iter().enumerate() {
            for a in &own {
                for b in other {
                    let depth = -separation(a, b).0;
                    if depth > start_overlap(a, b) {
                        return Err(invalid(
                            format!("{key}.vertices"),
                            format!(
                                "region `{}` overlaps region `{}` (regions[{j}]) by {depth:e} m",
                                r.id, scene.regions[j].id
                            ),
                        ));
                    }
                }
            }
        }
        for (k, name) in r.joint_sets.iter().enumerate() {
            if !families.contains_key(name.as_str()) {
                return Err(invalid(
                    format!("{key}.joint_sets[{k}]"),
                    format!(
                        "no joint set named `{name}` (defined: {})",
                        names_or_none(set_names.iter().copied())
                    ),
                ));
            }
        }
        outlines.push(shape);
        parts.push(own);
    }
    // Each set's joints over the box of every region it cuts, so that a joint runs on
    // from one region into the next.
    let mut joints_of = BTreeMap::new();
    for (s, name) in set_names.iter().enumerate() {
        let users: Vec<usize> = (0..scene.regions.len())
            .filter(|&i| scene.regions[i].joint_sets.iter().any(|n| n == name))
            .collect();
        if users.is_empty() {
            continue;
        }
        let bounds = users
            .iter()
            .map(|&i| outlines[i].aabb())
            .reduce(|a, b| Aabb::from_points(&[a.min, a.max, b.min, b.max]))
            .unwrap_or(Aabb::from_points(&[DVec2::ZERO]));
        let joints = families[name]
            .joints(s, &bounds, limits::MAX_REGION_BLOCKS as usize)
            .map_err(|e| match e {
                JointSetError::TooMany { .. } => invalid(
                    format!("joint_sets.{name}.spacing"),
                    format!(
                        "the set would cut its regions by more than {:e} joints or traces: is \
                         the spacing, trace_length or bridge in the wrong unit?",
                        limits::MAX_REGION_BLOCKS
                    ),
                ),
                e => invalid(format!("joint_sets.{name}"), e.to_string()),
            })?;
        joints_of.insert(*name, joints);
    }
    let mut out = scene.clone();
    out.joint_sets.clear();
    out.regions.clear();
    let mut dropped = Dropped::default();
    let mut total = 0.0;
    // Every block id so far, and what wrote it: a block of the scene's, or a region's.
    let mut ids: BTreeMap<String, String> = scene
        .blocks
        .iter()
        .enumerate()
        .map(|(k, b)| (b.id.clone(), format!("blocks[{k}]")))
        .collect();
    for (i, r) in scene.regions.iter().enumerate() {
        let key = format!("regions[{i}]");
        let shape = &outlines[i];
        let mut joints = Vec::new();
        // Lines cut a region into about 1 + L + I pieces, L of them crossing it and I
        // crossing points inside it. Two sets of spacings s and s' at an angle t cross
        // A |sin t| / (s s') times over an area A; one set's joints cross each other only
        // where they spread in dip (by up to d either way: at most A sin 2d / (2 s^2),
        // 2d at most 90 degrees). For two sets at right angles over a rectangle along
        // them, (1 + n)(1 + m), the grid's cells. Before 2026-11-28 the estimate was the
        // product of every set's count, which held a 100 m square cut by sets of 0.6,
        // 0.7 and 1.5 m to 3.3e6 blocks where they make 54,807.
        let area = shape.area();
        let (mut lines, mut crossings) = (0.0, 0.0);
        let mut seen: Vec<&dda_geom::JointFamily> = Vec::new();
        for name in &r.joint_sets {
            let family = &families[name.as_str()];
            let set = &family.set;
            let n = set.normal();
            let (lo, hi) = shape
                .vertices()
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(n.dot(*v)), hi.max(n.dot(*v)))
                });
            lines += (hi - lo) / set.spacing;
            let spread = (2.0 * family.dip_spread_deg).min(90.0).to_radians();
            crossings += area * spread.sin() / (2.0 * set.spacing * set.spacing);
            for other in &seen {
                let sin = n.perp_dot(other.set.normal()).abs();
                crossings += area * sin / (set.spacing * other.set.spacing);
            }
            seen.push(family);
            joints.extend(joints_of[name.as_str()].iter().cloned());
        }
        total += 1.0 + lines + crossings;
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
        let min_area = r
            .min_area
            .unwrap_or_else(|| default_min_area(&scene.analysis, shape.area()));
        if !(min_area.is_finite() && min_area >= 0.0) {
            return Err(invalid(
                format!("{key}.min_area"),
                format!("must be an area in m^2, 0 or more, got {min_area}"),
            ));
        }
        let cut = cut_mass(shape, &joints, min_area).map_err(|e| {
            invalid(
                format!("{key}.joint_sets"),
                format!("region `{}`: {e}", r.id),
            )
        })?;
        if cut.pieces.is_empty() {
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
            dropped
                .slivers
                .push((i, cut.dropped, cut.dropped_area, min_area));
        }
        let in_situ = in_situ_stress(&key, r)?;
        for (k, piece) in cut.pieces.iter().enumerate() {
            let id = format!("{}.{}", r.id, k + 1);
            let glued = piece.parts.len() > 1;
            for (m, (part, sets)) in piece.parts.iter().zip(&piece.edge_sets).enumerate() {
                let edge_joints: Vec<String> = sets
                    .iter()
                    .map(|s| {
                        s.and_then(|s| scene.joint_sets[set_names[s]].joint.clone())
                            .unwrap_or_default()
                    })
                    .collect();
                let block = if glued {
                    format!("{id}.{}", m + 1)
                } else {
                    id.clone()
                };
                if let Some(other) = ids.insert(block.clone(), format!("a block of {key}")) {
                    return Err(invalid(
                        format!("{key}.id"),
                        format!(
                            "region `{}` names a block `{block}`, the id of {other}: rename \
                             the region or that block",
                            r.id
                        ),
                    ));
                }
                out.blocks.push(BlockSpec {
                    id: block,
                    material: r.material.clone(),
                    vertices: part.vertices().iter().map(|v| [v.x, v.y]).collect(),
                    fixed: r.fixed,
                    edge_joints: if edge_joints.iter().any(|j| !j.is_empty()) {
                        edge_joints
                    } else {
                        Vec::new()
                    },
                    body: glued.then(|| id.clone()),
                    // Seams: intact rock between parts, never a trace (the faces of a
                    // joint that ends inside the piece are a joint, not a seam).
                    glued_edges: glued.then(|| seams(&piece.parts, m, |k| sets[k].is_none())),
                    stress: in_situ(part.centroid().y)?,
                    ..Default::default()
                });
            }
        }
    }
    let excavations = std::mem::take(&mut out.excavations);
    let small = written_d_tol(&scene.analysis).map_or(0.0, |d| d * d);
    for (x, e) in excavations.iter().enumerate() {
        let (n, area) = excavate(&mut out, x, e, small)?;
        if n > 0 {
            dropped.excavated.push((x, n, area, small));
        }
    }
    let free = |b: &&BlockSpec| !b.fixed;
    if !excavations.is_empty()
        && out.blocks.iter().any(|b| free(&b))
        && out
            .blocks
            .iter()
            .filter(free)
            .all(|b| b.removed_at.is_some())
    {
        return Err(invalid(
            format!("excavations[{}].vertices", excavations.len() - 1),
            "the excavations remove every free block during the run, which leaves nothing \
             to move: excavate less, or add the rock around the excavation",
        ));
    }
    Ok((out, dropped))
}

/// A region's `min_area` when the scene gives none: 1e-9 of its area (slivers of
/// rounding), or d_tol^2 if that is more. A piece smaller than the contact tolerance
/// squared is below what contact detection at d_tol resolves (every vertex of it lies
/// within d_tol of every other), and such a sliver, its inertia some 1e-13 of its
/// springs' stiffness, spins up numerically where the mass around it moves: a sliver of
/// 1e-6 m^2 (2 mm x 1 mm, d_tol 4 mm) at the foot of a stressed mass, disturbed by an
/// excavation 8 m away, turned ever faster and held every step of the run to 5e-7 s
/// (docs/method.md section 10). The analysis here is as written, not yet validated: a
/// d_tol that is no length leaves the rounding default.
fn default_min_area(analysis: &crate::scene::Analysis, area: f64) -> f64 {
    let rounding = 1e-9 * area;
    written_d_tol(analysis).map_or(rounding, |d_tol| rounding.max(d_tol * d_tol))
}

/// d_tol as the scene writes it (`contact_tolerance`, else 2 `max_displacement`), not yet
/// validated: None where it is no length.
fn written_d_tol(analysis: &crate::scene::Analysis) -> Option<f64> {
    let d_tol = analysis
        .contact_tolerance
        .unwrap_or(2.0 * analysis.max_displacement);
    (d_tol.is_finite() && d_tol > 0.0).then_some(d_tol)
}

/// The initial stress of region `r`'s blocks (`key` its entry) as a function of a
/// block's centroid height y: `stress` + `stress_gradient` y, None where the region
/// gives neither. Errors name the key of a component out of its range, or the gradient
/// where it takes a block's stress out of the range a block's may have.
fn in_situ_stress(
    key: &str,
    r: &RegionSpec,
) -> Result<impl Fn(f64) -> Result<Option<[f64; 3]>, Invalid>, Invalid> {
    let check = |name: &str, v: &Option<[f64; 3]>, range: &limits::Range| {
        for (i, &x) in v.iter().flatten().enumerate() {
            if !range.contains(x) {
                return Err(invalid(format!("{key}.{name}[{i}]"), range.message(x)));
            }
        }
        Ok(())
    };
    check("stress", &r.stress, &limits::STRESS)?;
    check(
        "stress_gradient",
        &r.stress_gradient,
        &limits::STRESS_GRADIENT,
    )?;
    let (at_zero, gradient) = (r.stress, r.stress_gradient);
    let key = key.to_string();
    Ok(move |y: f64| {
        if at_zero.is_none() && gradient.is_none() {
            return Ok(None);
        }
        let (s0, g) = (at_zero.unwrap_or_default(), gradient.unwrap_or_default());
        let mut s = [0.0; 3];
        for i in 0..3 {
            s[i] = s0[i] + g[i] * y;
            if !limits::STRESS.contains(s[i]) {
                return Err(invalid(
                    format!("{key}.stress_gradient[{i}]"),
                    format!(
                        "gives a block at y = {y} m a stress of {:e} Pa, beyond the {:e} \
                         to {:e} Pa a block's stress may have",
                        s[i],
                        limits::STRESS.min,
                        limits::STRESS.max
                    ),
                ));
            }
        }
        Ok(Some(s))
    })
}

/// Cuts every block of `scene` that excavation `x` crosses along its outline, and marks
/// the pieces inside it `removed_at = at`. The pieces of one block stay one body, glued
/// (the rock is intact across the outline until the excavation), and take the block's
/// velocity, stress and edge joints; its loads and fixed points go to the piece that
/// holds them. A part of the cutting outside the outline smaller than `small` (d_tol^2)
/// and than a tenth of its block, a sliver between the outline and a face or corner of
/// the block close to it, is below what contact detection at d_tol resolves, and is
/// dropped as a region drops its slivers (docs/method.md section 10). Returns how many
/// it dropped, and their area.
fn excavate(
    scene: &mut Scene,
    x: usize,
    e: &ExcavationSpec,
    small: f64,
) -> Result<(usize, f64), Invalid> {
    let key = format!("excavations[{x}]");
    if e.id.trim().is_empty() {
        return Err(invalid(format!("{key}.id"), "must not be empty"));
    }
    let duration = scene.analysis.duration;
    if !(e.at.is_finite() && e.at >= 0.0 && e.at <= duration) {
        return Err(invalid(
            format!("{key}.at"),
            format!(
                "must be a time in s from 0 to the run's duration ({duration} s), got {}",
                e.at
            ),
        ));
    }
    let outline = region_outline(&key, &e.id, &e.vertices)?;
    let v = outline.vertices();
    let n = v.len();
    // Each edge of the outline is a joint whose one trace is that edge.
    let joints: Vec<Joint> = (0..n)
        .map(|k| {
            let (a, b) = (v[k], v[(k + 1) % n]);
            let line = Line::through(a, b - a);
            let d = line.direction();
            let (ta, tb) = (d.dot(a), d.dot(b));
            Joint {
                line,
                set: 0,
                traces: Some(vec![[ta.min(tb), ta.max(tb)]]),
            }
        })
        .collect();
    let bounds = outline.aabb();
    let mut removes = false;
    let mut slivers = (0, 0.0);
    // The points a sliver holding one is kept for: bolts' ends and measured points.
    let anchors: Vec<[f64; 2]> = (scene.bolts.iter())
        .flat_map(|b| [b.from, b.to])
        .chain(scene.measure.iter().map(|m| m.at))
        .collect();
    let blocks = std::mem::take(&mut scene.blocks);
    for b in blocks {
        let Ok(poly) = ConvexPolygon::from_coords(&b.vertices) else {
            // Validation names what is wrong with it.
            scene.blocks.push(b);
            continue;
        };
        let apart = !poly.aabb().overlaps(&bounds);
        let Ok(shape) = Outline::new(poly.vertices().to_vec()) else {
            scene.blocks.push(b);
            continue;
        };
        if apart {
            scene.blocks.push(b);
            continue;
        }
        let cut = cut_mass(&shape, &joints, 0.0).map_err(|err| {
            invalid(
                format!("{key}.vertices"),
                format!("excavation `{}` cutting block `{}`: {err}", e.id, b.id),
            )
        })?;
        let removal = |inside: bool| {
            if inside {
                Some(b.removed_at.map_or(e.at, |t| t.min(e.at)))
            } else {
                b.removed_at
            }
        };
        let inside = |p: &dda_geom::Piece| outline.contains(p.parts[0].centroid());
        if cut.pieces.len() == 1 && cut.pieces[0].parts.len() == 1 {
            removes |= inside(&cut.pieces[0]);
            scene.blocks.push(BlockSpec {
                removed_at: removal(inside(&cut.pieces[0])),
                ..b
            });
            continue;
        }
        let body = b.body.clone().unwrap_or_else(|| b.id.clone());
        let eps = 1e-9 * poly.diameter();
        // A piece holds a load, a fixed point, a bolt's end or a measured point within
        // what a point written to 6 decimals on a face misses it by, as a block does.
        let reach = point_reach(&poly);
        // A part outside the outline smaller than d_tol^2, and than a tenth of the
        // block, is a sliver between the outline and a face or corner of the block close
        // to it: dropped, unless it holds one of the block's loads or fixed points, a
        // bolt's end or a measured point. (A block that is itself below d_tol^2 is
        // warned of as such, and its pieces kept.)
        let sliver_area = small.min(0.1 * poly.area());
        // Each part in the cut's order: whether it is such a sliver.
        let sliver: Vec<bool> = (cut.pieces.iter())
            .flat_map(|piece| piece.parts.iter().map(move |part| (piece, part)))
            .map(|(piece, part)| {
                let holds = |q: [f64; 2]| part.contains_within(DVec2::from(q), reach);
                part.area() < sliver_area
                    && !inside(piece)
                    && !b.loads.iter().any(|l| holds(l.at))
                    && !b.fixed_points.iter().chain(&anchors).any(|&q| holds(q))
            })
            .collect();
        let all: Vec<ConvexPolygon> = (cut.pieces.iter())
            .flat_map(|p| &p.parts)
            .zip(&sliver)
            .filter(|(_, s)| !**s)
            .map(|(part, _)| part.clone())
            .collect();
        // The block's own seams, if it was a part of a body already.
        let was_glued = |k: usize| match &b.glued_edges {
            Some(g) => g.contains(&k),
            None => b.body.is_some(),
        };
        let (mut m, mut k) = (0, 0);
        for piece in &cut.pieces {
            let gone = inside(piece);
            removes |= gone;
            for part in &piece.parts {
                k += 1;
                if sliver[k - 1] {
                    slivers.0 += 1;
                    slivers.1 += part.area();
                    continue;
                }
                m += 1;
                let pv = part.vertices();
                let holds = |q: DVec2| part.contains_within(q, reach);
                let mut loads = Vec::new();
                for l in &b.loads {
                    if holds(DVec2::from(l.at)) && !claimed(&scene.blocks, &b.id, l.at) {
                        loads.push(l.clone());
                    }
                }
                let fixed_points: Vec<[f64; 2]> = b
                    .fixed_points
                    .iter()
                    .filter(|&&q| holds(DVec2::from(q)))
                    .copied()
                    .collect();
                let edge_joints = if b.edge_joints.is_empty() {
                    Vec::new()
                } else {
                    (0..pv.len())
                        .map(|k| {
                            original_edge(&poly, pv[k], pv[(k + 1) % pv.len()], eps)
                                .and_then(|o| b.edge_joints.get(o).cloned())
                                .unwrap_or_default()
                        })
                        .collect()
                };
                // Glued along the new cuts (the rock is intact until the excavation),
                // and where the block was glued before.
                let mut glued = seams(&all, m - 1, |_| true);
                for k in 0..pv.len() {
                    if original_edge(&poly, pv[k], pv[(k + 1) % pv.len()], eps)
                        .is_some_and(was_glued)
                        && !glued.contains(&k)
                    {
                        glued.push(k);
                    }
                }
                glued.sort_unstable();
                scene.blocks.push(BlockSpec {
                    id: format!("{}.{m}", b.id),
                    // A part of a body whose seams were left to be found keeps them so.
                    glued_edges: (b.body.is_none() || b.glued_edges.is_some()).then_some(glued),
                    vertices: pv.iter().map(|p| [p.x, p.y]).collect(),
                    loads,
                    fixed_points,
                    edge_joints,
                    body: Some(body.clone()),
                    removed_at: removal(gone),
                    ..b.clone()
                });
            }
        }
    }
    if !removes {
        return Err(invalid(
            format!("{key}.vertices"),
            format!(
                "excavation `{}` removes no rock: its outline lies outside every block",
                e.id
            ),
        ));
    }
    Ok(slivers)
}

/// Whether a load at `at` of block `id` went to an earlier piece of it already (a load
/// on the line between two pieces goes to the first).
fn claimed(blocks: &[BlockSpec], id: &str, at: [f64; 2]) -> bool {
    let prefix = format!("{id}.");
    blocks
        .iter()
        .rev()
        .take_while(|b| b.id.starts_with(&prefix))
        .any(|b| b.loads.iter().any(|l| l.at == at))
}

/// The edges of `parts[i]` that run along another of the `parts` (anti-parallel, on one
/// line within 1e-9 of the part's size, overlapping by more than that) and that `may`
/// be seams.
fn seams(parts: &[ConvexPolygon], i: usize, may: impl Fn(usize) -> bool) -> Vec<usize> {
    let p = &parts[i];
    let eps = 1e-9 * p.diameter();
    (0..p.len())
        .filter(|&k| {
            may(k)
                && parts
                    .iter()
                    .enumerate()
                    .any(|(j, q)| j != i && !p.edge_contacts(k, q, eps).is_empty())
        })
        .collect()
}

/// The edge of `poly` that the segment a-b lies along, if any.
fn original_edge(poly: &ConvexPolygon, a: DVec2, b: DVec2, eps: f64) -> Option<usize> {
    (0..poly.len()).find(|&k| {
        let (p, q) = poly.edge(k);
        let d = (q - p).normalize();
        d.perp_dot(a - p).abs() <= eps && d.perp_dot(b - p).abs() <= eps && d.dot(b - a) > 0.0
    })
}
