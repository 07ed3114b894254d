//! The model a scene is validated into: every value checked against its admissible
//! range (`limits`), names resolved to indices, polygons built, the start checked
//! (no overlaps; in a static analysis, every free block supported).

use crate::detection::glue_reach;
use crate::limits::{self, Range};
use crate::scene::{
    Analysis, BlockSpec, Integration, Invalid, Joint, Material, Mode, Plane, Scene, SolverChoice,
    invalid,
};
use crate::seismic::{GroundMotion, check_samples};
use dda_contact::BoxTrees;
use dda_geom::{ConvexPolygon, DVec2, Groups, PolygonError, PolygonOptions, separation};
use std::borrow::Cow;
use std::collections::BTreeMap;

impl Scene {
    /// Checks every value and builds the model the engine runs; regions are cut into
    /// their blocks first (`regions::expand`), and the pieces their `min_area` dropped
    /// are reported as warnings.
    pub fn validate(&self) -> Result<Model, Invalid> {
        self.build().map(|(_, model)| model)
    }

    /// [`Scene::validate`], with the scene as run: this one (borrowed) when every block
    /// is explicit, else its regions cut into blocks (what `dda build` writes and a run
    /// records), so that the cutting is done once.
    pub fn build(&self) -> Result<(Cow<'_, Scene>, Model), Invalid> {
        if self.regions.is_empty() && self.joint_sets.is_empty() && self.excavations.is_empty() {
            let mut model = self.validate_blocks()?;
            model.warnings.extend(self.stress_of_rigid_blocks(&model));
            model.warnings.extend(self.slivers_written(&model));
            model.warnings.extend(self.parts_unjoined(&model));
            model.warnings.extend(self.points_outside());
            return Ok((Cow::Borrowed(self), model));
        }
        let (scene, dropped) = crate::regions::expand(self)?;
        let mut model = scene.validate_blocks()?;
        for (i, n, area, min_area) in dropped.slivers {
            let given = if self.regions[i].min_area.is_some() {
                ""
            } else {
                "; min_area not given: the larger of 1e-9 of the region's area and d_tol^2"
            };
            model.warnings.push(invalid(
                format!("regions[{i}].min_area"),
                format!(
                    "{n} pieces smaller than {min_area:.3e} m^2 dropped ({area:.3e} m^2 in \
                     all){given}"
                ),
            ));
        }
        for (x, n, area, small) in dropped.excavated {
            let (parts, are, its) = if n == 1 {
                ("part", "is", "its")
            } else {
                ("parts", "are", "their")
            };
            model.warnings.push(invalid(
                format!("excavations[{x}].vertices"),
                format!(
                    "{n} {parts} of the blocks it cuts, outside the outline, {are} smaller \
                     than d_tol^2 ({small:.3e} m^2) and than a tenth of {its} block \
                     ({area:.3e} m^2 in all): slivers below what contact detection \
                     resolves, dropped"
                ),
            ));
        }
        model.warnings.extend(self.stress_of_rigid_blocks(&model));
        model.warnings.extend(self.slivers_written(&model));
        model.warnings.extend(self.parts_unjoined(&model));
        model.warnings.extend(self.points_outside());
        Ok((Cow::Owned(scene), model))
    }

    /// A warning for each part of a body the scene writes that shares no seam with
    /// another part of its body ([`Model::seams`]): nothing joins it, and it moves as a
    /// block of its own (a glued edge that misses its neighbour's, or a `body` given to a
    /// block apart from the others, most likely). The parts regions and excavations cut
    /// are not written, and are not warned of (an excavation can leave one part of a
    /// block, its others inside the outline or dropped as slivers).
    fn parts_unjoined(&self, model: &Model) -> Vec<Invalid> {
        let mut seamed = vec![false; model.blocks.len()];
        for &[i, j] in &model.seams {
            seamed[i as usize] = true;
            seamed[j as usize] = true;
        }
        let index = model.index_by_id();
        self.blocks
            .iter()
            .enumerate()
            .filter_map(|(i, b)| {
                let body = b.body.as_deref()?;
                let k = *index.get(b.id.as_str())?;
                (!seamed[k]).then(|| {
                    invalid(
                        format!("blocks[{i}].body"),
                        format!(
                            "`{}` shares no seam with another part of body `{body}` (no glued \
                             edge runs along another part's edge): nothing joins it, and it \
                             moves as a block on its own",
                            b.id
                        ),
                    )
                })
            })
            .collect()
    }

    /// A warning for each load or fixed point the scene writes outside its block, beyond
    /// what a point written to 6 decimals on a face misses it by (`limits::START_OVERLAP`,
    /// or 1e-9 of the block's size if that is more): it acts as a point of the block all
    /// the same, carried with its turn and strain, but a point off the rock is most
    /// likely a slip (a coordinate of another block, or of the wrong sign), and an
    /// excavation that cuts the block gives it to no piece.
    fn points_outside(&self) -> Vec<Invalid> {
        let mut warnings = Vec::new();
        for (i, b) in self.blocks.iter().enumerate() {
            if b.loads.is_empty() && b.fixed_points.is_empty() {
                continue;
            }
            let Ok(poly) = ConvexPolygon::from_coords(&b.vertices) else {
                continue;
            };
            let reach = point_reach(&poly);
            let points =
                (b.loads.iter().enumerate())
                    .map(|(k, l)| (format!("blocks[{i}].loads[{k}].at"), "load", l.at))
                    .chain((b.fixed_points.iter().enumerate()).map(|(k, &q)| {
                        (format!("blocks[{i}].fixed_points[{k}]"), "fixed point", q)
                    }));
            for (key, what, at) in points {
                if !poly.contains_within(DVec2::from(at), reach) {
                    warnings.push(invalid(
                        key,
                        format!(
                            "the {what} at ({}, {}) lies outside block `{}`: it acts as a \
                             point of the block all the same, moving with it, and an \
                             excavation that cuts the block drops it",
                            at[0], at[1], b.id
                        ),
                    ));
                }
            }
        }
        warnings
    }

    /// A warning where the scene writes a free block smaller than d_tol^2 wedged among
    /// others (touching another as written, within `glue_reach`; not a part of a body,
    /// whose seams glue it): contact detection at d_tol does not resolve it, and such a sliver
    /// between stiffer blocks can spin up numerically and hold every step under Shi's rule
    /// (docs/method.md section 10, where a region drops such pieces by default). A small
    /// block thrown at others (the paper's hard cases) is not warned of. Names the
    /// first, with how many more there are.
    fn slivers_written(&self, model: &Model) -> Option<Invalid> {
        let d_tol = model.params.d_tol;
        let touch = glue_reach(d_tol);
        let index = model.index_by_id();
        // (scene index, model index, area) of the small free blocks the scene writes (an
        // excavation's pieces of one carry ids of their own, and are not written).
        let small: Vec<(usize, usize, f64)> = self
            .blocks
            .iter()
            .enumerate()
            .filter(|(_, b)| !b.fixed && b.body.is_none())
            .filter_map(|(i, b)| {
                let k = *index.get(b.id.as_str())?;
                let area = model.blocks[k].polygon.area();
                (area < d_tol * d_tol).then_some((i, k, area))
            })
            .collect();
        if small.is_empty() {
            return None;
        }
        // Those that touch another, from the broad phase's pairs (a scene without small
        // blocks pays none of it).
        let boxes: Vec<_> = model.blocks.iter().map(|b| b.polygon.aabb()).collect();
        let mut pairs = Vec::new();
        dda_contact::neighbour_pairs(&boxes, touch, &mut pairs);
        let mut touching = vec![false; model.blocks.len()];
        for q in &pairs {
            let (a, b) = (q.a as usize, q.b as usize);
            if separation(&model.blocks[a].polygon, &model.blocks[b].polygon).0 <= touch {
                touching[a] = true;
                touching[b] = true;
            }
        }
        let small: Vec<(usize, f64)> = small
            .into_iter()
            .filter(|&(_, k, _)| touching[k])
            .map(|(i, _, area)| (i, area))
            .collect();
        let &(i, area) = small.first()?;
        let more = match small.len() - 1 {
            0 => String::new(),
            n => format!(" ({n} more blocks are)"),
        };
        // The damped rule keeps at most a third of such a sliver's spin a step.
        let spin = if model.params.integration == Integration::DampedConstantAcceleration {
            "; leave it out, or make it part of a neighbour"
        } else {
            ", and a sliver between stiffer blocks can spin up numerically and hold every \
             step of the run; leave it out, make it part of a neighbour, or take \
             `analysis.integration = \"damped-constant-acceleration\"`, which damps that spin"
        };
        Some(invalid(
            format!("blocks[{i}].vertices"),
            format!(
                "block `{}` is {area:.3e} m^2, smaller than d_tol^2 ({:.3e} m^2){more}: contact \
                 detection does not resolve it{spin}",
                self.blocks[i].id,
                d_tol * d_tol
            ),
        ))
    }

    /// A warning where a rigid analysis is given an initial stress, which its blocks
    /// cannot carry (they have no strain): the first block's or region's key that gives
    /// one, with how many more do.
    fn stress_of_rigid_blocks(&self, model: &Model) -> Option<Invalid> {
        if model.params.deformable {
            return None;
        }
        let stressed = |s: &Option<[f64; 3]>| s.is_some_and(|s| s.iter().any(|&x| x != 0.0));
        let keys: Vec<String> = self
            .blocks
            .iter()
            .enumerate()
            .filter(|(_, b)| stressed(&b.stress))
            .map(|(i, _)| format!("blocks[{i}].stress"))
            .chain(self.regions.iter().enumerate().filter_map(|(i, r)| {
                if stressed(&r.stress) {
                    Some(format!("regions[{i}].stress"))
                } else if stressed(&r.stress_gradient) {
                    Some(format!("regions[{i}].stress_gradient"))
                } else {
                    None
                }
            }))
            .collect();
        let first = keys.first()?;
        let more = match keys.len() - 1 {
            0 => String::new(),
            n => format!(" (and {n} more)"),
        };
        Some(invalid(
            first.clone(),
            format!(
                "a rigid analysis (analysis.deformable = false) ignores initial stress{more}: \
                 rigid blocks have no strain to carry it"
            ),
        ))
    }

    /// The scene with its regions cut into blocks: what `dda build` writes.
    pub fn expanded(&self) -> Result<Scene, Invalid> {
        crate::regions::expand(self).map(|(scene, _)| scene)
    }

    /// [`Scene::validate`] of a scene whose blocks are all explicit.
    fn validate_blocks(&self) -> Result<Model, Invalid> {
        if self.name.trim().is_empty() {
            return Err(invalid("name", "must not be empty"));
        }
        let params = self.analysis.validate()?;
        let mut names: Vec<&String> = self.materials.keys().collect();
        names.sort();
        let mut materials = Vec::new();
        for name in &names {
            let m = &self.materials[*name];
            let key = format!("materials.{name}");
            materials.push(m.validate(&key, &params)?);
        }
        let mat_index =
            |name: &str| -> Option<usize> { names.iter().position(|n| n.as_str() == name) };

        // Joint table: `default` everywhere, then `between` joints on their pairs; joints
        // without `between` apply only where an edge names them.
        let named: std::collections::BTreeSet<&str> = self
            .blocks
            .iter()
            .flat_map(|b| b.edge_joints.iter().map(String::as_str))
            .collect();
        let mut by_name: BTreeMap<&str, u16> = BTreeMap::new();
        let mut unused = Vec::new();
        by_name.insert("default", 0);
        let nm = names.len();
        let mut joints = vec![JointProps::default()];
        let mut joint_of = vec![0u16; nm * nm];
        if let Some(j) = self.joints.get("default") {
            if j.between.is_some() {
                return Err(invalid(
                    "joints.default.between",
                    "the default joint applies to every pair; name another joint to restrict it",
                ));
            }
            joints[0] = j.validate("joints.default")?;
        }
        for (name, j) in &self.joints {
            if name == "default" {
                continue;
            }
            let key = format!("joints.{name}");
            let Some([m1, m2]) = &j.between else {
                // A joint that applies only where named: by blocks' `edge_joints`.
                if !named.contains(name.as_str()) {
                    unused.push(invalid(
                        format!("{key}.between"),
                        "this joint applies nowhere: a joint other than `default` applies \
                         between the materials of its `between = [material, material]`, or \
                         where a joint set's `joint` or a block's `edge_joints` names it",
                    ));
                }
                joints.push(j.validate(&key)?);
                by_name.insert(name.as_str(), (joints.len() - 1) as u16);
                continue;
            };
            let find = |m: &str| {
                mat_index(m).ok_or_else(|| no_material(&format!("{key}.between"), m, self))
            };
            let (a, b) = (find(m1)?, find(m2)?);
            joints.push(j.validate(&key)?);
            let k = (joints.len() - 1) as u16;
            by_name.insert(name.as_str(), k);
            joint_of[a * nm + b] = k;
            joint_of[b * nm + a] = k;
        }

        if self.blocks.is_empty() {
            return Err(invalid("blocks", "a scene needs at least one block"));
        }
        let mut blocks = Vec::with_capacity(self.blocks.len());
        let mut seen: BTreeMap<&str, usize> = BTreeMap::new();
        let mut bodies: BTreeMap<&str, (u32, usize)> = BTreeMap::new();
        for (i, b) in self.blocks.iter().enumerate() {
            let key = format!("blocks[{i}]");
            if b.id.trim().is_empty() {
                return Err(invalid(format!("{key}.id"), "must not be empty"));
            }
            if let Some(first) = seen.insert(&b.id, i) {
                return Err(invalid(
                    format!("{key}.id"),
                    format!("duplicate block id `{}` (also blocks[{first}])", b.id),
                ));
            }
            let material = mat_index(&b.material)
                .ok_or_else(|| no_material(&format!("{key}.material"), &b.material, self))?;
            let mut block = b.validate(&key, material)?;
            if !b.edge_joints.is_empty() {
                if b.edge_joints.len() != b.vertices.len() {
                    return Err(invalid(
                        format!("{key}.edge_joints"),
                        format!(
                            "names the joints of {} edges, but the block has {} (one name \
                             per edge, \"\" for the materials' joint)",
                            b.edge_joints.len(),
                            b.vertices.len()
                        ),
                    ));
                }
                for (e, name) in b.edge_joints.iter().enumerate() {
                    if name.is_empty() {
                        block.edge_joints.push(None);
                        continue;
                    }
                    let k = by_name.get(name.as_str()).ok_or_else(|| {
                        invalid(
                            format!("{key}.edge_joints[{e}]"),
                            format!(
                                "no joint named `{name}` (defined: {})",
                                self.joints.keys().cloned().collect::<Vec<_>>().join(", ")
                            ),
                        )
                    })?;
                    block.edge_joints.push(Some(*k));
                }
            }
            if let Some(body) = &b.body {
                if body.trim().is_empty() {
                    return Err(invalid(format!("{key}.body"), "must not be empty"));
                }
                let next = bodies.len() as u32;
                let (index, first) = *bodies.entry(body.as_str()).or_insert((next, i));
                if self.blocks[first].fixed != b.fixed {
                    return Err(invalid(
                        format!("{key}.fixed"),
                        format!(
                            "the parts of body `{body}` must all be fixed or all free \
                             (blocks[{first}] is {})",
                            if self.blocks[first].fixed {
                                "fixed"
                            } else {
                                "free"
                            }
                        ),
                    ));
                }
                block.body = Some(index);
                if let Some(edges) = &b.glued_edges {
                    block.glued = vec![false; block.polygon.len()];
                    for (e, &k) in edges.iter().enumerate() {
                        let slot = block.glued.get_mut(k).ok_or_else(|| {
                            invalid(
                                format!("{key}.glued_edges[{e}]"),
                                format!(
                                    "edge {k} does not exist: the block has {} edges (0 to {})",
                                    b.vertices.len(),
                                    b.vertices.len().saturating_sub(1)
                                ),
                            )
                        })?;
                        *slot = true;
                    }
                }
            } else if b.glued_edges.is_some() {
                return Err(invalid(
                    format!("{key}.glued_edges"),
                    "only a part of a body (`body = \"NAME\"`) has glued edges",
                ));
            }
            blocks.push(block);
        }
        glue_seams(&mut blocks, self, params.d_tol);
        let seams = body_seams(&blocks, params.d_tol);
        let ground = self.ground_motion(&params, &mut blocks)?;
        let drift = ground.as_ref().and_then(|g| {
            let (end, peak) = g.end_and_peak_velocity();
            (end.length() > GROUND_DRIFT * peak).then(|| {
                invalid(
                    "seismic",
                    format!(
                        "the record ends with the ground moving at ({:.3e}, {:.3e}) m/s, {:.0}% \
                         of its peak speed, and it keeps that velocity to the end of the run: \
                         a record that is not baseline-corrected",
                        end.x,
                        end.y,
                        100.0 * end.length() / peak
                    ),
                )
            })
        });
        if blocks.iter().all(|b| b.fixed || b.removed_at.is_some())
            && let Some(i) = blocks.iter().position(|b| !b.fixed)
        {
            return Err(invalid(
                format!("blocks[{i}].removed_at"),
                "every free block is removed (excavated) during the run, which leaves \
                 nothing to move: excavate less, or add the rock around the excavation",
            ));
        }
        if blocks.iter().all(|b| b.fixed) {
            return Err(invalid(
                "blocks",
                "every block is fixed, so nothing can move: mark at least one block \
                 `fixed = false` (the default)",
            ));
        }
        check_start_overlaps(&blocks)?;
        let mut warnings = unit_slips(self);
        warnings.append(&mut unused);
        warnings.extend(drift);
        if params.integration == Integration::AverageAcceleration && params.impact_steps.is_none() {
            warnings.push(invalid(
                "analysis.integration",
                "the average-acceleration rule without impact_steps: it damps no vibration \
                 (blocks near their toppling limit rock, and walls sliding on a slope part), \
                 and impacts that span a step or two lose a quarter to a half of their speed \
                 under it as under the default rule; give impact_steps (10 is a good start; \
                 it holds the step to a tenth of each impact's duration, so rock that \
                 tumbles takes many more steps), whose default rule takes it only in \
                 impacts",
            ));
        }
        if params.integration == Integration::AverageInImpacts && params.impact_steps.is_none() {
            warnings.push(invalid(
                "analysis.integration",
                "average-in-impacts without impact_steps: no step is held down for an \
                 impact, so every step is taken by the constant-acceleration rule; give \
                 impact_steps (10 is a good start; it holds the step to a tenth of each \
                 impact's duration, so rock that tumbles takes many more steps)",
            ));
        }
        if params.d_tol < 2.0 * params.d_max {
            warnings.push(invalid(
                "analysis.contact_tolerance",
                format!(
                    "{} m is below twice the max displacement ({} m): contacts may be \
                     missed within a step (paper section 2.6)",
                    params.d_tol,
                    2.0 * params.d_max
                ),
            ));
        }
        let joints_by_edge = blocks
            .iter()
            .any(|b| b.body.is_some() || !b.edge_joints.is_empty());
        let mut locator = Locator::default();
        let measures = self
            .measure
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let key = format!("measure[{i}]");
                if m.id.trim().is_empty() {
                    return Err(invalid(format!("{key}.id"), "must not be empty"));
                }
                let at = locator.point_in(&format!("{key}.at"), m.at, &blocks)?;
                Ok(ModelMeasure {
                    id: m.id.clone(),
                    block: at.0,
                    at: at.1,
                })
            })
            .collect::<Result<Vec<_>, Invalid>>()?;
        for (i, m) in measures.iter().enumerate() {
            warnings.extend(excavated_end(
                &format!("measure[{i}].at"),
                &blocks[m.block],
                "its rows in measurements.csv end then",
            ));
        }
        let mut ids = BTreeMap::new();
        for (i, m) in measures.iter().enumerate() {
            if let Some(j) = ids.insert(m.id.as_str(), i) {
                return Err(invalid(
                    format!("measure[{i}].id"),
                    format!("duplicate id `{}` (also measure[{j}])", m.id),
                ));
            }
        }
        let mut bolts = Vec::with_capacity(self.bolts.len());
        for (i, b) in self.bolts.iter().enumerate() {
            let key = format!("bolts[{i}]");
            let from = locator.point_in(&format!("{key}.from"), b.from, &blocks)?;
            let to = locator.point_in(&format!("{key}.to"), b.to, &blocks)?;
            if from.0 == to.0 {
                return Err(invalid(
                    format!("{key}.to"),
                    format!(
                        "both ends are in block `{}`: a bolt joins two blocks",
                        blocks[from.0].id
                    ),
                ));
            }
            if blocks[from.0].fixed && blocks[to.0].fixed {
                return Err(invalid(
                    format!("{key}.to"),
                    format!(
                        "both ends are in fixed blocks (`{}`, `{}`): the bolt holds nothing",
                        blocks[from.0].id, blocks[to.0].id
                    ),
                ));
            }
            if from.1.distance(to.1) <= 1e-9 * blocks[from.0].polygon.diameter() {
                return Err(invalid(
                    format!("{key}.to"),
                    "the two ends coincide: a bolt needs a length",
                ));
            }
            for (end, at) in [("from", from.0), ("to", to.0)] {
                warnings.extend(excavated_end(
                    &format!("{key}.{end}"),
                    &blocks[at],
                    "the bolt goes with it",
                ));
            }
            let stiffness = within(&format!("{key}.stiffness"), b.stiffness, &limits::PENALTY)?;
            let pretension = match b.pretension {
                Some(t) => within(&format!("{key}.pretension"), t, &limits::BOLT_FORCE)?,
                None => 0.0,
            };
            let strength = match b.strength {
                Some(t) if t > 0.0 => {
                    Some(within(&format!("{key}.strength"), t, &limits::BOLT_FORCE)?)
                }
                Some(t) => {
                    return Err(invalid(
                        format!("{key}.strength"),
                        format!("must be a positive force in N, got {t}"),
                    ));
                }
                None => None,
            };
            bolts.push(ModelBolt {
                from_block: from.0,
                from: from.1,
                to_block: to.0,
                to: to.1,
                stiffness,
                pretension,
                strength,
            });
        }
        if params.mode == Mode::Static {
            let tied: Vec<(usize, usize)> =
                bolts.iter().map(|b| (b.from_block, b.to_block)).collect();
            check_static_support(&blocks, params.d_tol, &tied)?;
        }
        Ok(Model {
            bolts,
            measures,
            ground,
            name: self.name.clone(),
            params,
            materials,
            joints,
            joint_of,
            joints_by_edge,
            blocks,
            seams,
            warnings,
        })
    }
}

/// The share of its peak speed a record may leave the ground moving at, at its end,
/// before a warning says it is not baseline-corrected (the ground then moves on at that
/// velocity).
const GROUND_DRIFT: f64 = 0.01;

impl Scene {
    /// The validated `[seismic]` table: its ground motion, with the blocks that follow it
    /// marked `driven` and fixed (they move as the record says, not by the equations).
    fn ground_motion(
        &self,
        params: &Params,
        blocks: &mut [ModelBlock],
    ) -> Result<Option<GroundMotion>, Invalid> {
        let Some(spec) = &self.seismic else {
            return Ok(None);
        };
        if params.mode == Mode::Static {
            return Err(invalid(
                "seismic",
                "ground motion needs a dynamic analysis: set analysis.mode = \"dynamic\"",
            ));
        }
        if spec.samples.is_empty() {
            return Err(invalid(
                "seismic",
                "no record: give `record` (a CSV file of t, ax, ay) or `samples`",
            ));
        }
        if let Err((i, m)) = check_samples(&spec.samples) {
            return Err(invalid(format!("seismic.samples[{i}]"), m));
        }
        let scale = match spec.scale {
            Some(s) => within("seismic.scale", s, &limits::RECORD_SCALE)?,
            None => 1.0,
        };
        let mut driven = vec![false; blocks.len()];
        match &spec.blocks {
            None => {
                for (d, b) in driven.iter_mut().zip(blocks.iter()) {
                    *d = b.fixed;
                }
            }
            Some(names) => {
                for (k, name) in names.iter().enumerate() {
                    // A block by its id, or every block cut from the region of that id.
                    let prefix = format!("{name}.");
                    let mut found = false;
                    for (d, b) in driven.iter_mut().zip(blocks.iter()) {
                        if b.id == *name || b.id.starts_with(&prefix) {
                            *d = true;
                            found = true;
                        }
                    }
                    if !found {
                        return Err(invalid(
                            format!("seismic.blocks[{k}]"),
                            format!("no block or region has the id `{name}`"),
                        ));
                    }
                }
            }
        }
        if !driven.contains(&true) {
            return Err(invalid(
                "seismic.blocks",
                "no block follows the ground motion: fix the ground blocks or name them here",
            ));
        }
        let mut list = Vec::new();
        for (i, (b, &d)) in blocks.iter_mut().zip(&driven).enumerate() {
            if d {
                b.fixed = true;
                b.driven = true;
                b.velocity = [0.0; 6];
                list.push(i);
            }
        }
        // The parts of a body move together: all driven or none (each part against the
        // body's first).
        let mut first: BTreeMap<u32, usize> = BTreeMap::new();
        for (i, b) in blocks.iter().enumerate() {
            let Some(body) = b.body else {
                continue;
            };
            let f = *first.entry(body).or_insert(i);
            if blocks[f].driven != b.driven {
                let (on, off) = if b.driven { (i, f) } else { (f, i) };
                return Err(invalid(
                    "seismic.blocks",
                    format!(
                        "`{}` follows the ground and `{}`, a part of the same body, does not",
                        blocks[on].id, blocks[off].id
                    ),
                ));
            }
        }
        if blocks.iter().all(|b| b.fixed) {
            return Err(invalid(
                "seismic.blocks",
                "every block follows the ground or is fixed, so nothing responds to it",
            ));
        }
        Ok(Some(GroundMotion::new(&spec.samples, scale, list)))
    }
}

/// A warning for the point of `key` where it lies in `block` and an excavation removes
/// that block: what the point carries (`then`) ends with it. A point meant to stay, a
/// bolt's anchor or a point on a tunnel's wall, placed a little inside the outline
/// excavated, most likely.
fn excavated_end(key: &str, block: &ModelBlock, then: &str) -> Option<Invalid> {
    let t = block.removed_at?;
    Some(invalid(
        key,
        format!(
            "lies in block `{}`, which an excavation removes at {t} s: {then}",
            block.id
        ),
    ))
}

/// The error of key `key` naming material `name`, which `scene` does not define: the
/// materials it does define, so that a misspelt name is seen at once.
pub(crate) fn no_material(key: &str, name: &str, scene: &Scene) -> Invalid {
    let defined: Vec<&str> = scene.materials.keys().map(String::as_str).collect();
    invalid(
        key,
        format!(
            "no material named `{name}` (defined: {})",
            if defined.is_empty() {
                "none".to_string()
            } else {
                defined.join(", ")
            }
        ),
    )
}

/// Finds the blocks that hold measured points and bolts' ends ([`Locator::point_in`]).
/// The blocks' boxes that the tests of [`Locator::point_in`] can accept a point in
/// (`ConvexPolygon::reach_bounds`) are put in trees once, at the first point: the blocks
/// whose boxes hold the point are then tested, in scene order, instead of every block
/// (4,000 points in a mass of 40,000 blocks took 3.6 s so).
#[derive(Default)]
struct Locator {
    boxes: Vec<dda_geom::Aabb>,
    trees: Option<BoxTrees>,
    found: Vec<u32>,
}

impl Locator {
    /// The block holding `at` (key `key`): the first, in scene order, whose outline
    /// contains it (its boundary included, to 1e-9 of its size), else the first it lies
    /// within [`point_reach`] of (2e-6 m: a point written to 6 decimals on a face that is
    /// not level or upright lies up to 7e-7 m off it, outside the rock as often as in
    /// it), and the point.
    fn point_in(
        &mut self,
        key: &str,
        at: [f64; 2],
        blocks: &[ModelBlock],
    ) -> Result<(usize, DVec2), Invalid> {
        each_within(key, &at, &limits::COORDINATE)?;
        let p = DVec2::from(at);
        let boxes = &mut self.boxes;
        let trees = self.trees.get_or_insert_with(|| {
            // Each box holds what `near` accepts, and so what `holds` does (its reach
            // is the smaller, 1e-9 of the size against at least that).
            boxes.extend((blocks.iter()).map(|b| b.polygon.reach_bounds(point_reach(&b.polygon))));
            let mut trees = BoxTrees::new();
            trees.build(boxes, |_| true);
            trees
        });
        trees.containing(boxes, p, &mut self.found);
        let candidates = self
            .found
            .iter()
            .map(|&i| (i as usize, &blocks[i as usize]));
        let holds = |b: &ModelBlock| b.polygon.contains_within(p, 1e-9 * b.polygon.diameter());
        let near = |b: &ModelBlock| b.polygon.contains_within(p, point_reach(&b.polygon));
        (candidates.clone().find(|(_, b)| holds(b)))
            .or_else(|| candidates.clone().find(|(_, b)| near(b)))
            .map(|(i, _)| (i, p))
            .ok_or_else(|| {
                invalid(
                    key,
                    format!(
                        "({}, {}) lies in no block: a point must be in the rock",
                        at[0], at[1]
                    ),
                )
            })
    }
}

/// How far from one line two parts' edges may lie and still make a seam, m: the glue's
/// reach (`glue_reach`: 1e-3 d_tol, or 2e-6 m, what faces written by hand to 6 decimals
/// may differ by, where that is more), or as far as the two may overlap at the start
/// (`start_overlap`) if that is more.
fn seam_reach(a: &ConvexPolygon, b: &ConvexPolygon, d_tol: f64) -> f64 {
    start_overlap(a, b).max(glue_reach(d_tol))
}

/// The seams of the parts of bodies whose scene gives no `glued_edges`: every edge that
/// runs along an edge of another part of its body (anti-parallel, on one line within
/// [`seam_reach`], overlapping by more than that). Before 2026-11-27 the line was 1e-9
/// of the part's size, and an L-shaped body written by hand as two parts to 6 decimals,
/// turned 30 degrees, had no seam: its parts came apart.
fn glue_seams(blocks: &mut [ModelBlock], scene: &Scene, d_tol: f64) {
    let n = blocks.len();
    for i in 0..n {
        if blocks[i].body.is_none() || scene.blocks[i].glued_edges.is_some() {
            continue;
        }
        let p = &blocks[i].polygon;
        let glued: Vec<bool> = (0..p.len())
            .map(|k| {
                (0..n).any(|j| {
                    let q = &blocks[j].polygon;
                    j != i
                        && blocks[j].body == blocks[i].body
                        && !p.edge_contacts(k, q, seam_reach(p, q, d_tol)).is_empty()
                })
            })
            .collect();
        blocks[i].glued = glued;
    }
}

/// The seams that join the parts of bodies: the pairs `[i, j]`, `i < j`, of parts of one
/// body where a glued edge of one runs along an edge of the other at the start (on one
/// line and overlapping within [`seam_reach`]), in order. Parts that touch only at a
/// corner share no seam: no intact rock joins them.
fn body_seams(blocks: &[ModelBlock], d_tol: f64) -> Vec<[u32; 2]> {
    let mut parts: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (i, b) in blocks.iter().enumerate() {
        if let Some(body) = b.body {
            parts.entry(body).or_default().push(i);
        }
    }
    let joined = |i: usize, j: usize| {
        let (p, q) = (&blocks[i].polygon, &blocks[j].polygon);
        let eps = seam_reach(p, q, d_tol);
        (0..p.len()).any(|k| {
            blocks[i].glued.get(k) == Some(&true) && !p.edge_contacts(k, q, eps).is_empty()
        })
    };
    let mut seams = Vec::new();
    for list in parts.values() {
        for (x, &i) in list.iter().enumerate() {
            for &j in &list[x + 1..] {
                if joined(i, j) || joined(j, i) {
                    seams.push([i as u32, j as u32]);
                }
            }
        }
    }
    seams.sort_unstable();
    seams
}

/// Rejects blocks that overlap at the start by more than coordinates written by hand
/// round to (`limits::START_OVERLAP`, or 1e-9 of their size if larger); two fixed blocks
/// may overlap, as they never interact.
fn check_start_overlaps(blocks: &[ModelBlock]) -> Result<(), Invalid> {
    let boxes: Vec<_> = blocks.iter().map(|b| b.polygon.aabb()).collect();
    let mut pairs = Vec::new();
    dda_contact::neighbour_pairs(&boxes, 0.0, &mut pairs);
    for q in &pairs {
        let (a, b) = (&blocks[q.a as usize], &blocks[q.b as usize]);
        if a.fixed && b.fixed {
            continue;
        }
        let (gap, _) = separation(&a.polygon, &b.polygon);
        let allowed = start_overlap(&a.polygon, &b.polygon);
        if gap < -allowed {
            return Err(invalid(
                format!("blocks[{}].vertices", q.b),
                format!(
                    "block `{}` overlaps block `{}` by {:.3e} m at the start (more than \
                     {allowed:.1e} m): move it clear, or, where the two share a face, write \
                     the shared vertices with the same numbers in both",
                    b.id, a.id, -gap
                ),
            ));
        }
    }
    Ok(())
}

/// How far outside block `p` a point written by hand may lie and still be of it, m: as
/// far as two blocks may overlap at the start ([`start_overlap`]), what a point written
/// to 6 decimals on a face that is neither level nor upright misses it by.
pub(crate) fn point_reach(p: &ConvexPolygon) -> f64 {
    start_overlap(p, p)
}

/// How far two outlines may overlap at the start, m: `limits::START_OVERLAP`, or 1e-9 of
/// the larger one's size if that is more.
pub(crate) fn start_overlap(a: &ConvexPolygon, b: &ConvexPolygon) -> f64 {
    limits::START_OVERLAP.max(1e-9 * a.diameter().max(b.diameter()))
}

/// In a static analysis every free block must rest, through blocks within d_tol of each
/// other or tied by bolts, on a fixed block or a fixed point: a free-floating block has
/// no equilibrium (the classic static DDA matrix is singular for it).
fn check_static_support(
    blocks: &[ModelBlock],
    d_tol: f64,
    tied: &[(usize, usize)],
) -> Result<(), Invalid> {
    let supported = supported_blocks(blocks, d_tol, tied);
    match supported.iter().position(|s| !s) {
        Some(i) => Err(invalid(
            format!("blocks[{i}]"),
            format!(
                "static analysis: block `{}` rests on no fixed block or fixed point \
                 (directly or through touching blocks), so it has no equilibrium; fix it, \
                 give it fixed points, or use mode = \"dynamic\"",
                blocks[i].id
            ),
        )),
        None => Ok(()),
    }
}

/// Which blocks rest, through blocks within `d_tol` of each other or tied by bolts
/// (`tied`), on a fixed block or a fixed point.
pub(crate) fn supported_blocks(
    blocks: &[ModelBlock],
    d_tol: f64,
    tied: &[(usize, usize)],
) -> Vec<bool> {
    let boxes: Vec<_> = blocks.iter().map(|b| b.polygon.aabb()).collect();
    let mut pairs = Vec::new();
    dda_contact::neighbour_pairs(&boxes, d_tol, &mut pairs);
    let mut supported: Vec<bool> = blocks
        .iter()
        .map(|b| b.fixed || !b.fixed_points.is_empty())
        .collect();
    // Blocks within d_tol of each other, as adjacency lists.
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); blocks.len()];
    for q in &pairs {
        let (a, b) = (q.a as usize, q.b as usize);
        if separation(&blocks[a].polygon, &blocks[b].polygon).0 <= d_tol {
            adjacent[a].push(b);
            adjacent[b].push(a);
        }
    }
    // Blocks tied by bolts support each other too.
    for &(a, b) in tied {
        adjacent[a].push(b);
        adjacent[b].push(a);
    }
    // Breadth-first from every supported block.
    let mut queue: std::collections::VecDeque<usize> =
        (0..blocks.len()).filter(|&i| supported[i]).collect();
    while let Some(i) = queue.pop_front() {
        for &j in &adjacent[i] {
            if !supported[j] {
                supported[j] = true;
                queue.push_back(j);
            }
        }
    }
    supported
}

/// `v` if it lies in `range` (see [`crate::limits`]), else the error naming `key`.
fn within(key: &str, v: f64, range: &Range) -> Result<f64, Invalid> {
    if range.contains(v) {
        Ok(v)
    } else {
        Err(invalid(key, range.message(v)))
    }
}

/// Checks every component of `v` against `range`, naming `key[i]` in the error.
fn each_within(key: &str, v: &[f64], range: &Range) -> Result<(), Invalid> {
    for (i, &x) in v.iter().enumerate() {
        within(&format!("{key}[{i}]"), x, range)?;
    }
    Ok(())
}

/// The damping ratio of the contact springs' dashpots when `analysis.contact_damping` is
/// not given (docs/method.md section 12). Our choice: walls and stacks at their friction
/// limit on penalty springs, resolved in fine steps, fluttered undamped (up to 18% off
/// the closed form) and needed 0.1 to 0.2 to slide as one body; 0.3 holds every one
/// measured to its floor.
pub const DEFAULT_CONTACT_DAMPING: f64 = 0.3;

/// The validated analysis settings, in SI units and radians.
#[derive(Clone, Debug, PartialEq)]
pub struct Params {
    /// Dynamic or static.
    pub mode: Mode,
    /// Simulated time, s.
    pub duration: f64,
    /// Initial and largest time step, s.
    pub dt0: f64,
    /// d_max, m.
    pub d_max: f64,
    /// theta_max, rad.
    pub theta_max: f64,
    /// d_tol, m.
    pub d_tol: f64,
    /// Normal penalty, N/m.
    pub normal_penalty: f64,
    /// Shear penalty, N/m.
    pub shear_penalty: f64,
    /// Fixed-point penalty, N/m.
    pub fixed_penalty: f64,
    /// Detector name.
    pub detector: String,
    /// Gravity, if the scene asks for it.
    pub gravity: Option<DVec2>,
    /// 6 DOF per block (true) or 3.
    pub deformable: bool,
    /// Plane stress or strain.
    pub plane: Plane,
    /// OCI iteration bound.
    pub max_oci: u32,
    /// SVG frames over the run.
    pub frames: u32,
    /// Fewest steps an impact spans (`analysis.impact_steps`), if given.
    pub impact_steps: Option<u32>,
    /// The time-integration rule of a dynamic step.
    pub integration: Integration,
    /// Whether a dynamic analysis settles before it starts (`analysis.settle`).
    pub settle: bool,
    /// How the global system is solved (`analysis.solver`).
    pub solver: SolverChoice,
    /// Damping ratio of the contact springs at their own frequencies
    /// (`analysis.contact_damping`; 0: none).
    pub contact_damping: f64,
}

impl Params {
    /// The rule a dynamic analysis steps by (`analysis.integration`, named or the
    /// default); none for a static analysis, whose steps carry no motion.
    pub fn stepping_rule(&self) -> Option<Integration> {
        (self.mode == Mode::Dynamic).then_some(self.integration)
    }
}

impl Analysis {
    fn validate(&self) -> Result<Params, Invalid> {
        let k = |s: &str| format!("analysis.{s}");
        let duration = within(&k("duration"), self.duration, &limits::DURATION)?;
        let dt0 = within(&k("time_step"), self.time_step, &limits::TIME_STEP)?;
        if duration / dt0 > limits::MAX_NOMINAL_STEPS {
            return Err(invalid(
                k("duration"),
                format!(
                    "{duration:e} s is more than {:e} steps of the time step {dt0:e} s; \
                     shorten the run or lengthen analysis.time_step",
                    limits::MAX_NOMINAL_STEPS
                ),
            ));
        }
        let d_max = within(
            &k("max_displacement"),
            self.max_displacement,
            &limits::TOLERANCE,
        )?;
        let theta_deg = within(
            &k("max_rotation_deg"),
            self.max_rotation_deg,
            &limits::ROTATION_DEG,
        )?;
        let d_tol = match self.contact_tolerance {
            Some(v) => within(&k("contact_tolerance"), v, &limits::TOLERANCE)?,
            None => 2.0 * d_max,
        };
        let normal_penalty = within(&k("normal_penalty"), self.normal_penalty, &limits::PENALTY)?;
        let shear_penalty = match self.shear_penalty {
            Some(v) => within(&k("shear_penalty"), v, &limits::PENALTY)?,
            None => normal_penalty,
        };
        let fixed_penalty = match self.fixed_penalty {
            Some(v) => within(&k("fixed_penalty"), v, &limits::FIXED_PENALTY)?,
            None => 100.0 * normal_penalty,
        };
        if dda_contact::detector_by_name(&self.detector).is_err() {
            return Err(invalid(
                k("detector"),
                format!(
                    "unknown detector `{}` (expected one of: {})",
                    self.detector,
                    dda_contact::DETECTOR_NAMES.join(", ")
                ),
            ));
        }
        if let Some(g) = &self.gravity {
            each_within(&k("gravity"), g, &limits::GRAVITY)?;
        }
        if self.max_oci == 0 || self.max_oci > 100 {
            return Err(invalid(
                k("max_oci"),
                format!("must be between 1 and 100, got {}", self.max_oci),
            ));
        }
        if self.frames > 100_000 {
            return Err(invalid(k("frames"), "must be at most 100000"));
        }
        if let Some(n) = self.impact_steps
            && !(1..=1000).contains(&n)
        {
            return Err(invalid(
                k("impact_steps"),
                format!("must be between 1 and 1000, got {n}"),
            ));
        }
        let contact_damping = match self.contact_damping {
            Some(z) => within(&k("contact_damping"), z, &limits::CONTACT_DAMPING)?,
            None => DEFAULT_CONTACT_DAMPING,
        };
        let integration = self.integration.unwrap_or(if self.impact_steps.is_some() {
            Integration::AverageInImpacts
        } else {
            Integration::DampedConstantAcceleration
        });
        Ok(Params {
            mode: self.mode,
            duration,
            dt0,
            d_max,
            theta_max: theta_deg.to_radians(),
            d_tol,
            normal_penalty,
            shear_penalty,
            fixed_penalty,
            detector: self.detector.clone(),
            gravity: self.gravity.map(DVec2::from),
            deformable: self.deformable,
            plane: self.plane,
            max_oci: self.max_oci,
            frames: self.frames,
            impact_steps: self.impact_steps,
            integration,
            settle: self.mode == Mode::Dynamic && self.settle.unwrap_or(true),
            solver: self.solver.unwrap_or_default(),
            contact_damping,
        })
    }
}

/// Validated material constants; the elastic ones already converted for plane strain.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialProps {
    /// Density, kg/m^3.
    pub density: f64,
    /// Effective Young's modulus (E, or E/(1-nu^2) in plane strain), Pa.
    pub young: f64,
    /// Effective Poisson's ratio (nu, or nu/(1-nu) in plane strain).
    pub poisson: f64,
    /// Stiffness-proportional damping time of the strain, s (0: none); None: each
    /// block's own ([`crate::kinematics::own_damping`]).
    pub damping: Option<f64>,
}

impl Material {
    fn validate(&self, key: &str, params: &Params) -> Result<MaterialProps, Invalid> {
        let density = within(&format!("{key}.density"), self.density, &limits::DENSITY)?;
        let damping = match self.damping {
            Some(b) => Some(within(&format!("{key}.damping"), b, &limits::DAMPING)?),
            None => None,
        };
        if !params.deformable {
            return Ok(MaterialProps {
                density,
                young: 0.0,
                poisson: 0.0,
                damping: Some(0.0),
            });
        }
        let young = match self.young {
            Some(e) => within(&format!("{key}.young"), e, &limits::YOUNG)?,
            None => {
                return Err(invalid(
                    format!("{key}.young"),
                    "deformable blocks need Young's modulus (or set analysis.deformable = false)",
                ));
            }
        };
        let nu = match self.poisson {
            Some(nu) if nu.is_finite() && nu > -1.0 && nu < 0.5 => nu,
            Some(nu) => {
                return Err(invalid(
                    format!("{key}.poisson"),
                    format!("must be in (-1, 0.5), got {nu}"),
                ));
            }
            None => {
                return Err(invalid(
                    format!("{key}.poisson"),
                    "deformable blocks need Poisson's ratio (or set analysis.deformable = false)",
                ));
            }
        };
        let (young, poisson) = match params.plane {
            Plane::Stress => (young, nu),
            Plane::Strain => (young / (1.0 - nu * nu), nu / (1.0 - nu)),
        };
        Ok(MaterialProps {
            density,
            young,
            poisson,
            damping,
        })
    }
}

/// Validated contact properties.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JointProps {
    /// tan(friction angle).
    pub tan_phi: f64,
    /// Cohesion, Pa.
    pub cohesion: f64,
    /// Tensile strength, Pa.
    pub tensile_strength: f64,
    /// The artificial joint between the convex parts of one body: its contacts are
    /// locked and bonded whenever active, and never open or slide.
    pub glued: bool,
}

impl JointProps {
    /// The joint between parts of one body.
    pub const GLUED: JointProps = JointProps {
        tan_phi: 0.0,
        cohesion: 0.0,
        tensile_strength: 0.0,
        glued: true,
    };

    /// Whether contacts of this joint need shear springs (friction, cohesion or glue).
    pub fn has_shear(&self) -> bool {
        self.tan_phi > 0.0 || self.cohesion > 0.0 || self.glued
    }

    /// Whether contacts of this joint start bonded (cohesion, tensile strength or glue).
    pub fn bonds(&self) -> bool {
        self.cohesion > 0.0 || self.tensile_strength > 0.0 || self.glued
    }
}

impl Joint {
    fn validate(&self, key: &str) -> Result<JointProps, Invalid> {
        let phi = self.friction_deg;
        if !(phi.is_finite() && (0.0..90.0).contains(&phi)) {
            return Err(invalid(
                format!("{key}.friction_deg"),
                format!("must be in [0, 90) degrees, got {phi}"),
            ));
        }
        Ok(JointProps {
            tan_phi: phi.to_radians().tan(),
            cohesion: within(&format!("{key}.cohesion"), self.cohesion, &limits::STRENGTH)?,
            tensile_strength: within(
                &format!("{key}.tensile_strength"),
                self.tensile_strength,
                &limits::STRENGTH,
            )?,
            glued: false,
        })
    }
}

/// A validated block.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelBlock {
    /// Block id.
    pub id: String,
    /// Index into [`Model::materials`].
    pub material: usize,
    /// Its polygon (counter-clockwise, convex).
    pub polygon: ConvexPolygon,
    /// DOFs eliminated.
    pub fixed: bool,
    /// Initial velocity (u0, v0, r0, ex, ey, gxy) rates.
    pub velocity: [f64; 6],
    /// Initial stress (sx, sy, txy), Pa.
    pub stress: [f64; 3],
    /// Point loads: point, force.
    pub loads: Vec<(DVec2, DVec2)>,
    /// Fixed points.
    pub fixed_points: Vec<DVec2>,
    /// The joint of each edge (index into [`Model::joints`]), or `None` for the
    /// materials'; empty when every edge takes the materials' joint.
    pub edge_joints: Vec<Option<u16>>,
    /// The body this block is a part of (glued to the other parts), by index.
    pub body: Option<u32>,
    /// For a part of a body, whether each edge is glued to the other parts (a seam of
    /// intact rock); empty otherwise.
    pub glued: Vec<bool>,
    /// When the block is removed (excavated), s.
    pub removed_at: Option<f64>,
    /// Whether it follows the ground motion (it is then also fixed).
    pub driven: bool,
}

impl BlockSpec {
    fn validate(&self, key: &str, material: usize) -> Result<ModelBlock, Invalid> {
        let polygon = outline(key, &self.vertices, |e| match e {
            // A block must be convex, but the rock need not be: say how to write it.
            PolygonError::NotConvex { .. } => format!(
                "block `{}`: {e} (a block must be convex: write a non-convex piece of rock \
                 as a [[regions]] outline, which is cut into glued convex parts, or as \
                 convex blocks sharing a `body`)",
                self.id
            ),
            _ => format!("block `{}`: {e}", self.id),
        })?;
        let mut velocity = [0.0; 6];
        if let Some(v) = &self.velocity {
            each_within(&format!("{key}.velocity"), v, &limits::SPEED)?;
            velocity[0] = v[0];
            velocity[1] = v[1];
        }
        if let Some(w) = self.angular_velocity {
            within(&format!("{key}.angular_velocity"), w, &limits::SPIN)?;
            velocity[2] = w;
        }
        let mut stress = [0.0; 3];
        if let Some(s) = &self.stress {
            each_within(&format!("{key}.stress"), s, &limits::STRESS)?;
            stress = *s;
        }
        let mut loads = Vec::new();
        for (i, l) in self.loads.iter().enumerate() {
            each_within(&format!("{key}.loads[{i}].at"), &l.at, &limits::COORDINATE)?;
            each_within(&format!("{key}.loads[{i}].force"), &l.force, &limits::FORCE)?;
            loads.push((DVec2::from(l.at), DVec2::from(l.force)));
        }
        let mut fixed_points = Vec::new();
        for (i, p) in self.fixed_points.iter().enumerate() {
            each_within(&format!("{key}.fixed_points[{i}]"), p, &limits::COORDINATE)?;
            fixed_points.push(DVec2::from(*p));
        }
        Ok(ModelBlock {
            id: self.id.clone(),
            material,
            polygon,
            fixed: self.fixed,
            velocity,
            stress,
            loads,
            fixed_points,
            edge_joints: Vec::new(),
            body: None,
            glued: Vec::new(),
            driven: false,
            removed_at: match self.removed_at {
                Some(t) => Some(within(&format!("{key}.removed_at"), t, &limits::REMOVAL)?),
                None => None,
            },
        })
    }
}

/// A validated rock bolt: an axial spring between two material points.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelBolt {
    /// The block holding the first end.
    pub from_block: usize,
    /// The first end at the start, m.
    pub from: DVec2,
    /// The block holding the other end.
    pub to_block: usize,
    /// The other end at the start, m.
    pub to: DVec2,
    /// Axial stiffness, N/m.
    pub stiffness: f64,
    /// Tension at the start, N.
    pub pretension: f64,
    /// Tension at which it breaks, N.
    pub strength: Option<f64>,
}

/// A validated measured point.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelMeasure {
    /// Its name.
    pub id: String,
    /// The block it belongs to.
    pub block: usize,
    /// Where it is at the start, m.
    pub at: DVec2,
}

/// A validated scene, ready to run.
#[derive(Clone, Debug, PartialEq)]
pub struct Model {
    /// Scene name.
    pub name: String,
    /// Analysis settings.
    pub params: Params,
    /// Materials, in name order.
    pub materials: Vec<MaterialProps>,
    /// Joints; index 0 is the default.
    pub joints: Vec<JointProps>,
    /// Joint index for each ordered pair of materials (row-major, materials^2).
    pub joint_of: Vec<u16>,
    /// Blocks in scene order.
    pub blocks: Vec<ModelBlock>,
    /// The seams of intact rock that join the parts of bodies, pairs of block indices
    /// `[i, j]` with `i < j` (see [`Model::bodies`]).
    pub seams: Vec<[u32; 2]>,
    /// Whether some block names its edges' joints or is part of a body, so that a
    /// contact's joint depends on more than its blocks' materials.
    pub joints_by_edge: bool,
    /// Rock bolts.
    pub bolts: Vec<ModelBolt>,
    /// Measured points.
    pub measures: Vec<ModelMeasure>,
    /// The ground motion, when the scene has a `[seismic]` record.
    pub ground: Option<GroundMotion>,
    /// What is allowed but suspect (key and message), for the user to see.
    pub warnings: Vec<Invalid>,
}

impl Model {
    /// The joint acting between blocks `a` and `b` by their materials (edges may name
    /// another: [`Model::joint_of_contact`]).
    pub fn joint_between(&self, a: usize, b: usize) -> &JointProps {
        self.joint_of_materials(self.blocks[a].material, self.blocks[b].material)
    }

    /// Each block's index by its id.
    pub(crate) fn index_by_id(&self) -> BTreeMap<&str, usize> {
        (self.blocks.iter().enumerate())
            .map(|(k, m)| (m.id.as_str(), k))
            .collect()
    }

    /// The bodies as the blocks not `removed` (a flag for each block, in scene order) hold
    /// together: each block's body, the smallest index of the parts joined to it by seams
    /// of intact rock ([`Model::seams`]) through parts that remain, or `None` for a block
    /// no seam joins to another that remains. Before any removal these are the scene's
    /// bodies (their parts are joined by their seams); an excavation that takes away the
    /// parts joining others splits a body into the pieces left, and a part it leaves
    /// joined to none is a block on its own.
    pub fn bodies(&self, removed: &[bool]) -> Vec<Option<u32>> {
        let mut groups = Groups::new(self.blocks.len());
        let mut joined = vec![false; self.blocks.len()];
        for &[i, j] in &self.seams {
            let (i, j) = (i as usize, j as usize);
            if removed[i] || removed[j] {
                continue;
            }
            groups.join(i, j);
            joined[i] = true;
            joined[j] = true;
        }
        (0..self.blocks.len())
            .map(|i| joined[i].then(|| groups.of(i) as u32))
            .collect()
    }

    /// The joint of a contact of a vertex of block `a` against edge `edge` of block `b`,
    /// `bodies` the blocks' bodies as they hold together ([`Model::bodies`]): the glue, if
    /// the two are parts of one body and the edge is one of its seams; else the joint the
    /// edge names; else that of the two materials.
    pub fn joint_of_contact(
        &self,
        bodies: &[Option<u32>],
        a: usize,
        b: usize,
        edge: usize,
    ) -> &JointProps {
        let bb = &self.blocks[b];
        if bodies[a].is_some() && bodies[a] == bodies[b] && bb.glued.get(edge) == Some(&true) {
            return &JointProps::GLUED;
        }
        match bb.edge_joints.get(edge) {
            Some(Some(k)) => &self.joints[*k as usize],
            _ => self.joint_of_materials(self.blocks[a].material, bb.material),
        }
    }

    /// The joint acting between blocks of materials `ma` and `mb`.
    pub fn joint_of_materials(&self, ma: usize, mb: usize) -> &JointProps {
        &self.joints[self.joint_of[ma * self.materials.len() + mb] as usize]
    }
}

/// The convex polygon of the outline `vertices` at `key` (each coordinate within
/// `limits::COORDINATE`); strict: clockwise order and collinear vertices are reported,
/// not repaired. An error names the vertex where it can, with `message` of the polygon
/// error.
pub(crate) fn outline(
    key: &str,
    vertices: &[[f64; 2]],
    message: impl Fn(&PolygonError) -> String,
) -> Result<ConvexPolygon, Invalid> {
    for (i, v) in vertices.iter().enumerate() {
        each_within(&format!("{key}.vertices[{i}]"), v, &limits::COORDINATE)?;
    }
    let coords: Vec<DVec2> = vertices.iter().map(|&c| DVec2::from(c)).collect();
    ConvexPolygon::with_options(coords, &PolygonOptions::strict())
        .map(|(p, _)| p)
        .map_err(|e| {
            let at = match e {
                PolygonError::DuplicateVertex { vertex, .. }
                | PolygonError::CollinearVertex { vertex }
                | PolygonError::NotConvex { vertex } => format!("{key}.vertices[{vertex}]"),
                _ => format!("{key}.vertices"),
            };
            invalid(at, message(&e))
        })
}

/// Warnings for values that are admissible but look like a slip of units: a Young's
/// modulus below 1e5 Pa (written in MPa or GPa), a density below 100 or above 20,000
/// kg/m^3 (t/m^3, or g/cm^3 x 1000 twice), a friction angle between 0 and 1 degree (a
/// ratio tan(phi) written as the angle).
fn unit_slips(scene: &Scene) -> Vec<Invalid> {
    let mut out = Vec::new();
    for (name, m) in &scene.materials {
        let key = format!("materials.{name}");
        if let Some(e) = m.young
            && e < 1e5
        {
            out.push(invalid(
                format!("{key}.young"),
                format!(
                    "{e} Pa is softer than any rock or soil: is it in MPa or GPa? (Pa expected)"
                ),
            ));
        }
        if !(100.0..=20_000.0).contains(&m.density) {
            out.push(invalid(
                format!("{key}.density"),
                format!("{} kg/m^3 is unlike any rock (about 1,500 to 3,500): is it in t/m^3 or g/cm^3? (kg/m^3 expected)", m.density),
            ));
        }
    }
    for (name, j) in &scene.joints {
        if j.friction_deg > 0.0 && j.friction_deg <= 1.0 {
            out.push(invalid(
                format!("joints.{name}.friction_deg"),
                format!(
                    "{} degrees is almost frictionless: is it tan(phi)? (the angle in degrees expected; tan(phi) = {} is {:.1} degrees)",
                    j.friction_deg,
                    j.friction_deg,
                    j.friction_deg.atan().to_degrees()
                ),
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::{Locator, ModelBlock, point_reach};
    use dda_geom::{ConvexPolygon, DVec2};

    /// The block a scan of every block in scene order gives: the first that holds the
    /// point, else the first within its reach, as `Locator::point_in` had it before the
    /// trees.
    fn scan(p: DVec2, blocks: &[ModelBlock]) -> Option<usize> {
        let holds = |b: &ModelBlock| b.polygon.contains_within(p, 1e-9 * b.polygon.diameter());
        let near = |b: &ModelBlock| b.polygon.contains_within(p, point_reach(&b.polygon));
        blocks
            .iter()
            .position(holds)
            .or_else(|| blocks.iter().position(near))
    }

    fn block(id: usize, vertices: Vec<DVec2>) -> ModelBlock {
        ModelBlock {
            id: format!("b{id}"),
            material: 0,
            polygon: ConvexPolygon::new(vertices).expect("convex"),
            fixed: false,
            velocity: [0.0; 6],
            stress: [0.0; 3],
            loads: Vec::new(),
            fixed_points: Vec::new(),
            edge_joints: Vec::new(),
            body: None,
            glued: Vec::new(),
            removed_at: None,
            driven: false,
        }
    }

    /// A grid of unit squares turned 58.7 degrees and written to 6 decimals (faces that
    /// shared a line no longer quite do), a sliver triangle and a block ten times larger
    /// beside them: every corner and edge midpoint, and points 1e-6, 1.5e-6 and 3e-6 m
    /// off each along its normal either way (inside another block's reach, or no
    /// block's), are found in the same block as the scan finds them, or in none.
    #[test]
    fn the_locator_finds_the_block_the_scan_finds() {
        let (s, c) = 58.7f64.to_radians().sin_cos();
        let six = |v: f64| (v * 1e6).round() / 1e6;
        let turn = |x: f64, y: f64| DVec2::new(six(c * x - s * y), six(s * x + c * y));
        let mut blocks = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                let (x, y) = (f64::from(i), f64::from(j));
                blocks.push(block(
                    blocks.len(),
                    vec![
                        turn(x, y),
                        turn(x + 1.0, y),
                        turn(x + 1.0, y + 1.0),
                        turn(x, y + 1.0),
                    ],
                ));
            }
        }
        blocks.push(block(
            blocks.len(),
            vec![turn(6.0, 0.0), turn(7.0, 0.0), turn(6.0, 0.001)],
        ));
        blocks.push(block(
            blocks.len(),
            vec![
                turn(-10.0, 0.0),
                turn(0.0, 0.0),
                turn(0.0, 10.0),
                turn(-10.0, 10.0),
            ],
        ));
        let mut points = Vec::new();
        for b in &blocks {
            let p = &b.polygon;
            for k in 0..p.len() {
                let (a, e) = p.edge(k);
                let n = p.normal(k);
                for q in [a, 0.5 * (a + e)] {
                    for off in [0.0, 1e-6, -1e-6, 1.5e-6, -1.5e-6, 3e-6, -3e-6] {
                        points.push(q + n * off);
                    }
                }
            }
        }
        let mut locator = Locator::default();
        let mut found = 0;
        for (k, &p) in points.iter().enumerate() {
            let got = locator
                .point_in("at", [p.x, p.y], &blocks)
                .ok()
                .map(|r| r.0);
            assert_eq!(got, scan(p, &blocks), "point {k} at {p:?}");
            found += usize::from(got.is_some());
        }
        // Both kinds of answer were asked for.
        assert!(
            found > 0 && found < points.len(),
            "{found} of {}",
            points.len()
        );
    }
}
