//! The scene file (docs/scene-format.md): TOML, or JSON of the same structure, read with
//! serde into [`Scene`] and validated into a [`Model`] the engine runs. Unknown keys and
//! invalid values are errors naming the file, the key path and the line.

use crate::limits::{self};
use crate::locate::{LineIndex, line_at, nesting_beyond};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

pub use crate::model::{
    JointProps, MaterialProps, Model, ModelBlock, ModelBolt, ModelMeasure, Params,
};

/// A scene as written in a file: the analysis settings, materials, joints and blocks.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Scene name (names the output directory).
    pub name: String,
    /// Analysis settings.
    pub analysis: Analysis,
    /// Materials by name.
    #[serde(default)]
    pub materials: BTreeMap<String, Material>,
    /// Contact properties by name; `default` applies to every pair no other joint names.
    #[serde(default)]
    pub joints: BTreeMap<String, Joint>,
    /// The blocks.
    #[serde(default)]
    pub blocks: Vec<BlockSpec>,
    /// Joint sets by name, for regions to be cut by.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub joint_sets: BTreeMap<String, JointSetSpec>,
    /// Regions of rock cut by joint sets into blocks.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub regions: Vec<RegionSpec>,
    /// Outlines excavated during the run.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub excavations: Vec<ExcavationSpec>,
    /// Rock bolts: axial springs between two material points.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bolts: Vec<BoltSpec>,
    /// Material points followed through the run (`measurements.csv`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub measure: Vec<MeasureSpec>,
    /// Ground motion: blocks that follow an acceleration record.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seismic: Option<SeismicSpec>,
}

/// The `[seismic]` table: the ground's acceleration record and the blocks that follow it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeismicSpec {
    /// A CSV file of `t, ax, ay` (s, m/s^2) under a header line, relative to the scene
    /// file. Reading the scene reads it into `samples` and clears this key, so that the
    /// scene as run (`scene.json`, checkpoints, `dda build`) holds the record itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record: Option<String>,
    /// The record's samples `[t, ax, ay]`, written in the scene instead of a file.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "exact::list"
    )]
    pub samples: Vec<[f64; 3]>,
    /// Factor on the accelerations; 1 if absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// The blocks that follow the ground (a block id, or a region's id for every block
    /// cut from it); absent: every fixed block.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blocks: Option<Vec<String>>,
}

/// A `[[bolts]]` entry: an axial spring between two material points, each attached to
/// the block that holds it at the start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoltSpec {
    /// One end, m.
    #[serde(deserialize_with = "exact::array")]
    pub from: [f64; 2],
    /// The other end, m.
    #[serde(deserialize_with = "exact::array")]
    pub to: [f64; 2],
    /// Axial stiffness, N/m.
    pub stiffness: f64,
    /// Tension at the start, N.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pretension: Option<f64>,
    /// Tension at which it breaks, N; absent, it never does.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub strength: Option<f64>,
}

/// A `[[measure]]` entry: a material point followed through the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeasureSpec {
    /// Its name in `measurements.csv`.
    pub id: String,
    /// Where it is at the start, m; it belongs to the block that holds it.
    #[serde(deserialize_with = "exact::array")]
    pub at: [f64; 2],
}

/// An `[[excavations]]` entry: the blocks are cut along the outline before the run, and
/// the pieces inside it are removed at time `at`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExcavationSpec {
    /// Its name, for messages.
    pub id: String,
    /// Outline `[x, y]`, counter-clockwise, a simple polygon.
    #[serde(deserialize_with = "exact::list")]
    pub vertices: Vec<[f64; 2]>,
    /// When the rock inside is removed, s.
    pub at: f64,
}

/// A `[joint_sets.NAME]` entry: a family of joints, parallel and persistent unless its
/// statistics say otherwise.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSetSpec {
    /// Direction of the joint lines, degrees counter-clockwise from +x.
    pub dip_deg: f64,
    /// Normal distance between neighbouring joints, m (the mean, if it varies).
    pub spacing: f64,
    /// Position of one joint along the set's normal (-sin dip, cos dip), m; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<f64>,
    /// A point `[x, y]` one joint passes through, m: instead of `offset` (a joint
    /// mapped at a known place, in a survey grid's coordinates).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub through: Option<[f64; 2]>,
    /// Contact properties of these joints: a `[joints.NAME]`; absent, the materials'.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<String>,
    /// Coefficient of variation of the spacing (uniform draws), 0 to 0.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing_cv: Option<f64>,
    /// Largest deviation of a joint's dip from `dip_deg` (uniform draws), degrees.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dip_spread_deg: Option<f64>,
    /// Length of each joint's traces, m; absent, the joints are persistent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trace_length: Option<f64>,
    /// Length of intact rock between traces along a joint, m (with `trace_length`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bridge: Option<f64>,
    /// Seed of the statistical draws (default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
}

/// A `[[regions]]` entry: an outline filled with one material and cut by joint
/// sets into blocks named `ID.1`, `ID.2`, ...
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    /// Region id: its blocks are named after it.
    pub id: String,
    /// Material name.
    pub material: String,
    /// Outline `[x, y]`, counter-clockwise, a simple polygon (convex or not).
    #[serde(deserialize_with = "exact::list")]
    pub vertices: Vec<[f64; 2]>,
    /// Names of the joint sets cutting it (none: the region is one block).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joint_sets: Vec<String>,
    /// Whether its blocks are fixed.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed: bool,
    /// Pieces smaller than this, m^2, are dropped and reported (default 1e-9 of the
    /// region's area: slivers of rounding).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_area: Option<f64>,
    /// Initial stress (sx, sy, txy) of its blocks at y = 0, Pa (tension positive); with
    /// `stress_gradient`, a block's is taken at its centroid (the in-situ stress).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact::option"
    )]
    pub stress: Option<[f64; 3]>,
    /// Change of the initial stress per metre of height y, Pa/m (each component).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact::option"
    )]
    pub stress_gradient: Option<[f64; 3]>,
}

/// Dynamic (inertia carried from step to step) or static (velocities zeroed each step).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Velocities carried over (Shi's dynamic coefficient 1).
    #[default]
    Dynamic,
    /// Velocities zeroed at each step start (Shi's dynamic coefficient 0).
    Static,
}

/// Plane stress or plane strain elasticity.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Plane {
    /// Plane stress.
    #[default]
    Stress,
    /// Plane strain: E' = E/(1-nu^2), nu' = nu/(1-nu).
    Strain,
}

/// The `[analysis]` table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Analysis {
    /// Dynamic or static.
    #[serde(default)]
    pub mode: Mode,
    /// Simulated time, s.
    pub duration: f64,
    /// Initial (and largest) time step, s.
    pub time_step: f64,
    /// d_max: largest vertex displacement allowed in a step, m.
    pub max_displacement: f64,
    /// theta_max: largest rotation allowed in a step, degrees.
    #[serde(default = "default_max_rotation_deg")]
    pub max_rotation_deg: f64,
    /// d_tol, m; default 2 d_max (paper section 2.6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_tolerance: Option<f64>,
    /// Normal contact penalty p, N/m.
    pub normal_penalty: f64,
    /// Shear contact penalty, N/m; default the normal penalty.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_penalty: Option<f64>,
    /// Penalty of fixed points, N/m; default 100 times the normal penalty.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fixed_penalty: Option<f64>,
    /// Contact detector: "cover", "type-1" or "type-2".
    #[serde(default = "default_detector")]
    pub detector: String,
    /// Body acceleration (gx, gy), m/s^2; no key, no gravity effect.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact::option"
    )]
    pub gravity: Option<[f64; 2]>,
    /// Deformable blocks (6 DOF) or rigid (3 DOF).
    #[serde(default = "default_true")]
    pub deformable: bool,
    /// Plane stress or strain.
    #[serde(default)]
    pub plane: Plane,
    /// Largest number of open-close iterations before the step is cut.
    #[serde(default = "default_max_oci")]
    pub max_oci: u32,
    /// Number of SVG frames over the run (plus the initial one); 0 for none.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Fewest steps an impact spans: while blocks strike or rebound, the step is held to
    /// 1/N of the contact's duration pi sqrt(m / p); absent, impacts are not resolved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impact_steps: Option<u32>,
    /// The time-integration rule; default `constant-acceleration` (Shi's), or
    /// `average-in-impacts` when `impact_steps` is given.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub integration: Option<Integration>,
    /// Settle a dynamic analysis before it starts: the blocks resting on each other
    /// load their contacts under gravity and loads, under the scene's own joints, so
    /// that the run starts from the forces of its first instant rather than from
    /// unloaded contacts that ring; default true.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle: Option<bool>,
    /// Damping ratio of the normal spring of every contact at rest (not in impact) at its
    /// own frequency sqrt(p / m) (m the reduced mass of the contact's two blocks), in the
    /// dynamic steps taken by Shi's rule: a dashpot beside each such spring; default 0.3
    /// (`crate::model::DEFAULT_CONTACT_DAMPING`), 0 for none (docs/method.md section
    /// 12).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact_damping: Option<f64>,
    /// How the global system is solved: `direct` (a sparse Cholesky factor),
    /// `iterative` (conjugate gradients, for large scenes) or `auto` (the default:
    /// iterative from `crate::iterative::ITERATIVE_FROM_BLOCKS` free blocks).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub solver: Option<SolverChoice>,
}

/// How the global system is solved (docs/method.md section 14).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverChoice {
    /// By the number of free blocks: direct below
    /// `crate::iterative::ITERATIVE_FROM_BLOCKS`, iterative from it.
    #[default]
    Auto,
    /// A sparse Cholesky factor, updated by low-rank terms between factorisations.
    Direct,
    /// Conjugate gradients preconditioned by block Jacobi, stopped on a bound of the
    /// motion's error: no factor, memory linear in the blocks.
    Iterative,
}

impl SolverChoice {
    /// How a system solved this way is said to be solved: "directly", "iteratively"
    /// ("as `auto` chooses" before the choice is made).
    pub fn adverb(self) -> &'static str {
        match self {
            SolverChoice::Auto => "as `auto` chooses",
            SolverChoice::Direct => "directly",
            SolverChoice::Iterative => "iteratively",
        }
    }
}

impl Integration {
    /// The rule's name as a scene writes it (`analysis.integration`).
    pub fn name(self) -> &'static str {
        match self {
            Integration::ConstantAcceleration => "constant-acceleration",
            Integration::DampedConstantAcceleration => "damped-constant-acceleration",
            Integration::AverageAcceleration => "average-acceleration",
            Integration::AverageInImpacts => "average-in-impacts",
        }
    }
}

/// How a dynamic step integrates the motion (docs/method.md section 12).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Integration {
    /// Shi's: D = V dt + a dt^2 / 2 and V' = V + a dt with a from the forces at the
    /// step's end (Newmark's gamma = 1, beta = 1/2): unconditionally stable, and
    /// dissipative most at w dt = 4, less beyond (docs/method.md section 12). The
    /// paper's rule.
    ConstantAcceleration,
    /// Shi's rule with its stiff modes damped (Newmark's gamma = 1, beta = 9/16):
    /// D = V dt + (9 a - A) dt^2 / 16 and V' = V + a dt, A the last step's
    /// acceleration. As dissipative as Shi's where a motion is resolved in time, and a
    /// mode far stiffer than 1 / dt keeps at most a third of itself a step, where
    /// under Shi's rule its velocity flips sign from step to step, hardly damped. The
    /// default.
    #[default]
    DampedConstantAcceleration,
    /// Newmark's average acceleration (gamma = 1/2, beta = 1/4): D = V dt + (a + a')
    /// dt^2 / 4, V' = V + (a + a') dt / 2; conserves the energy of linear springs.
    AverageAcceleration,
    /// The average-acceleration rule in the steps `impact_steps` holds down (an impact
    /// under way), Shi's in the others: impacts keep their energy, and blocks resting
    /// or sliding on each other keep the damping of Shi's rule (docs/method.md section
    /// 12). The default with `impact_steps`.
    AverageInImpacts,
}

fn default_max_rotation_deg() -> f64 {
    2.0
}

fn default_detector() -> String {
    "cover".to_string()
}

fn default_true() -> bool {
    true
}

fn default_max_oci() -> u32 {
    6
}

fn default_frames() -> u32 {
    10
}

/// A `[materials.NAME]` table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Density, kg/m^3 (mass per unit area of the 2D block per unit thickness).
    pub density: f64,
    /// Young's modulus, Pa (needed when blocks are deformable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young: Option<f64>,
    /// Poisson's ratio (needed when blocks are deformable).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    /// Stiffness-proportional damping of the blocks' strain, s (docs/method.md section
    /// 12): a viscous stress of this time times the elastic stress rate. None: 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
}

/// A `[joints.NAME]` table: contact properties.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Joint {
    /// Friction angle, degrees.
    #[serde(default)]
    pub friction_deg: f64,
    /// Cohesion, Pa (force per unit contact length per unit thickness).
    #[serde(default)]
    pub cohesion: f64,
    /// Tensile strength, Pa.
    #[serde(default)]
    pub tensile_strength: f64,
    /// The two materials this joint applies between; absent for `default` and for joints
    /// that apply only where named (by a joint set or a block's `edge_joints`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub between: Option<[String; 2]>,
}

/// A point load, moving with its block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Load {
    /// Point of application, m.
    #[serde(deserialize_with = "exact::array")]
    pub at: [f64; 2],
    /// Force, N.
    #[serde(deserialize_with = "exact::array")]
    pub force: [f64; 2],
}

/// A `[[blocks]]` entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlockSpec {
    /// Block id, unique in the scene.
    pub id: String,
    /// Material name.
    pub material: String,
    /// Vertices `[x, y]`, counter-clockwise.
    #[serde(deserialize_with = "exact::list")]
    pub vertices: Vec<[f64; 2]>,
    /// Whether the block is fixed (its DOFs are eliminated).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub fixed: bool,
    /// Initial centroid velocity, m/s.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact::option"
    )]
    pub velocity: Option<[f64; 2]>,
    /// Initial angular velocity, rad/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angular_velocity: Option<f64>,
    /// Initial stress (sx, sy, txy), Pa.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact::option"
    )]
    pub stress: Option<[f64; 3]>,
    /// Point loads.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub loads: Vec<Load>,
    /// Points of the block held at their place by stiff springs.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "exact::list"
    )]
    pub fixed_points: Vec<[f64; 2]>,
    /// The joint of each edge (edge k from vertex k to k + 1), by `[joints.NAME]`; an
    /// empty name: the joint of the blocks' materials. Empty: every edge's joint is the
    /// materials'.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub edge_joints: Vec<String>,
    /// The non-convex block this one is a convex part of: blocks of one body are glued
    /// along their `glued_edges` (bonded contacts that never open or slide).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// The edges (by index, edge k from vertex k to k + 1) along which this part of a
    /// body is glued to the others; absent: every edge that runs along another part of
    /// its body at the start.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub glued_edges: Option<Vec<usize>>,
    /// When the block is removed (excavated), s; absent, never.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub removed_at: Option<f64>,
}

/// A scene that could not be read or is invalid: where, and what is wrong.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.render())]
pub struct SceneError {
    /// The file (or the built-in scene's name).
    pub file: String,
    /// Key path, e.g. `blocks[3].vertices[2]`; empty for the whole document.
    pub key: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// What is wrong.
    pub message: String,
}

impl SceneError {
    fn render(&self) -> String {
        let mut s = self.file.clone();
        if let Some(l) = self.line {
            s.push_str(&format!(":{l}"));
        }
        if !self.key.is_empty() {
            s.push_str(&format!(": key `{}`", self.key));
        }
        s.push_str(": ");
        s.push_str(&self.message);
        s
    }
}

/// A validation failure before the file and line are known: key path and message.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Invalid {
    /// Key path.
    pub key: String,
    /// What is wrong.
    pub message: String,
}

pub(crate) fn invalid(key: impl Into<String>, message: impl Into<String>) -> Invalid {
    Invalid {
        key: key.into(),
        message: message.into(),
    }
}

/// File formats of a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// TOML (`.toml`).
    Toml,
    /// JSON (`.json`).
    Json,
}

impl Scene {
    /// Reads and validates the scene file at `path` (format from its extension).
    pub fn load(path: &Path) -> Result<(Scene, Model), SceneError> {
        Scene::load_indexed(path).map(|(scene, model, _)| (scene, model))
    }

    /// [`Scene::load`], also returning where the file's keys are (to name the lines of
    /// errors and warnings found after overrides).
    pub fn load_indexed(path: &Path) -> Result<(Scene, Model, LineIndex), SceneError> {
        let file = path.display().to_string();
        let fail = |message: String| SceneError {
            file: file.clone(),
            key: String::new(),
            line: None,
            message,
        };
        let format = match path.extension().and_then(|e| e.to_str()) {
            Some("toml") => Format::Toml,
            Some("json") => Format::Json,
            _ => {
                return Err(fail(
                    "unknown scene format: the file name must end in .toml or .json".into(),
                ));
            }
        };
        // A regular file of bounded size: a pipe or a device named like a scene would
        // block the read, or never end it.
        let text = read_limited(path, limits::MAX_SCENE_BYTES)
            .map_err(|why| fail(format!("the scene file {why}")))?;
        Scene::parse_indexed(&text, format, &file, path.parent())
    }

    /// Parses and validates scene text; `file` names it in errors.
    pub fn parse(text: &str, format: Format, file: &str) -> Result<(Scene, Model), SceneError> {
        Scene::parse_indexed(text, format, file, None).map(|(scene, model, _)| (scene, model))
    }

    /// [`Scene::parse`], also returning where the text's keys are; a seismic record's
    /// file is found in `dir` (the scene file's directory; None: the current one).
    fn parse_indexed(
        text: &str,
        format: Format,
        file: &str,
        dir: Option<&Path>,
    ) -> Result<(Scene, Model, LineIndex), SceneError> {
        // A byte order mark, which editors on Windows write at the start of UTF-8 text,
        // is no part of the scene (the JSON parser took it for a value).
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        if let Some(line) = nesting_beyond(text, format == Format::Toml, limits::MAX_NESTING) {
            return Err(SceneError {
                file: file.to_string(),
                key: String::new(),
                line: Some(line),
                message: format!(
                    "arrays and tables nest deeper than {} levels (a scene needs 4)",
                    limits::MAX_NESTING
                ),
            });
        }
        let index = match format {
            Format::Toml => LineIndex::toml(text),
            Format::Json => LineIndex::json(text),
        };
        let error = |key: String, line: Option<usize>, message: String| SceneError {
            file: file.to_string(),
            line: index.line(&key).or(line),
            key,
            message,
        };
        let mut scene: Scene = match format {
            Format::Toml => {
                let de = toml::Deserializer::parse(text).map_err(|e| {
                    error(
                        String::new(),
                        e.span().map(|s| line_at(text, s.start)),
                        e.message().to_string(),
                    )
                })?;
                serde_path_to_error::deserialize(de).map_err(|e| {
                    let key = path_string(e.path());
                    let inner = e.into_inner();
                    let line = inner.span().map(|s| line_at(text, s.start));
                    // The error's own span is exact; the index only knows the key.
                    SceneError {
                        file: file.to_string(),
                        line: line.or_else(|| index.line(&key)),
                        key,
                        message: inner.message().to_string(),
                    }
                })?
            }
            Format::Json => {
                let mut de = serde_json::Deserializer::from_str(text);
                let scene = serde_path_to_error::deserialize(&mut de).map_err(|e| {
                    let key = path_string(e.path());
                    let inner = e.into_inner();
                    SceneError {
                        file: file.to_string(),
                        line: Some(inner.line()),
                        key,
                        message: strip_position(&inner.to_string()),
                    }
                })?;
                de.end().map_err(|e| {
                    error(
                        String::new(),
                        Some(e.line()),
                        strip_position(&e.to_string()),
                    )
                })?;
                scene
            }
        };
        scene.read_record(dir, |message| {
            error("seismic.record".to_string(), None, message)
        })?;
        let model = scene
            .validate()
            .map_err(|v| error(v.key, None, v.message))?;
        Ok((scene, model, index))
    }

    /// Reads the `[seismic]` record file into `samples` (and clears `record`), found in
    /// `dir` when its path is relative. An error in the file names the file and line; one
    /// in finding or opening it goes through `at_key` (the scene's key and line).
    fn read_record(
        &mut self,
        dir: Option<&Path>,
        at_key: impl Fn(String) -> SceneError,
    ) -> Result<(), SceneError> {
        let Some(spec) = self.seismic.as_mut() else {
            return Ok(());
        };
        let Some(record) = spec.record.take() else {
            return Ok(());
        };
        if !spec.samples.is_empty() {
            return Err(at_key(
                "give the record as a file (record) or in the scene (samples), not both".into(),
            ));
        }
        let path = match dir {
            Some(d) if Path::new(&record).is_relative() => d.join(&record),
            _ => Path::new(&record).to_path_buf(),
        };
        let shown = path.display().to_string();
        let text = read_limited(&path, limits::MAX_RECORD_BYTES)
            .map_err(|e| at_key(format!("the record `{shown}` {e}")))?;
        let in_file = |line: usize, message: String| SceneError {
            file: shown.clone(),
            key: String::new(),
            line: Some(line),
            message: format!("{message} (the seismic record)"),
        };
        let (samples, lines) =
            crate::seismic::read_record(&text).map_err(|(line, m)| in_file(line, m))?;
        if let Err((i, m)) = crate::seismic::check_samples(&samples) {
            return Err(match lines.get(i) {
                Some(&line) => in_file(line, m),
                None => at_key(format!("the record `{shown}`: {m}")),
            });
        }
        spec.samples = samples;
        Ok(())
    }

    /// Multiplies the contact tolerance and the largest step displacement by `r`
    /// (the paper's contact tolerance ratio r_tol, eq. 15).
    pub fn scale_tolerances(&mut self, r: f64) {
        let a = &mut self.analysis;
        a.contact_tolerance = Some(a.contact_tolerance.unwrap_or(2.0 * a.max_displacement) * r);
        a.max_displacement *= r;
    }
}

/// The text of the regular file at `path` if it holds at most `limit` bytes of UTF-8;
/// else why not, as the end of a sentence naming the file.
fn read_limited(path: &Path, limit: u64) -> Result<String, String> {
    use std::io::Read;
    let meta = std::fs::metadata(path).map_err(|e| format!("cannot be read: {e}"))?;
    if !meta.is_file() {
        return Err("is not a regular file".into());
    }
    let file = std::fs::File::open(path).map_err(|e| format!("cannot be read: {e}"))?;
    let mut bytes = Vec::new();
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| format!("cannot be read: {e}"))?;
    if bytes.len() as u64 > limit {
        return Err(format!("is larger than {limit} bytes"));
    }
    String::from_utf8(bytes).map_err(|_| "is not UTF-8 text".into())
}

/// `serde_path_to_error`'s path as `a.b[3].c`.
fn path_string(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut s = String::new();
    for seg in path.iter() {
        match seg {
            Segment::Seq { index } => s.push_str(&format!("[{index}]")),
            Segment::Map { key } | Segment::Enum { variant: key } => {
                if !s.is_empty() {
                    s.push('.');
                }
                s.push_str(key);
            }
            Segment::Unknown => {}
        }
    }
    s
}

/// serde_json's message without its " at line L column C" suffix (we print the line).
fn strip_position(msg: &str) -> String {
    match msg.rfind(" at line ") {
        Some(i) => msg[..i].to_string(),
        None => msg.to_string(),
    }
}

/// Deserialisers of fixed-length number arrays that refuse a wrong length in every
/// format (TOML's reader otherwise drops the extra components of `[1, 2, 3]` read as a
/// point), naming the array's position in the error path.
mod exact {
    use serde::de::{Deserialize, Deserializer, Error};

    /// `[f64; N]` read from an array of exactly N numbers.
    struct Exact<const N: usize>([f64; N]);

    impl<'de, const N: usize> Deserialize<'de> for Exact<N> {
        fn deserialize<D: Deserializer<'de>>(de: D) -> Result<Self, D::Error> {
            let v = Vec::<f64>::deserialize(de)?;
            let n = v.len();
            v.try_into().map(Exact).map_err(|_| {
                D::Error::invalid_length(n, &format!("an array of {N} numbers").as_str())
            })
        }
    }

    /// A `[f64; N]` field.
    pub fn array<'de, D: Deserializer<'de>, const N: usize>(de: D) -> Result<[f64; N], D::Error> {
        Exact::<N>::deserialize(de).map(|e| e.0)
    }

    /// An optional `[f64; N]` field (with `#[serde(default)]`).
    pub fn option<'de, D: Deserializer<'de>, const N: usize>(
        de: D,
    ) -> Result<Option<[f64; N]>, D::Error> {
        Option::<Exact<N>>::deserialize(de).map(|o| o.map(|e| e.0))
    }

    /// A list of `[f64; N]`.
    pub fn list<'de, D: Deserializer<'de>, const N: usize>(
        de: D,
    ) -> Result<Vec<[f64; N]>, D::Error> {
        Vec::<Exact<N>>::deserialize(de).map(|v| v.into_iter().map(|e| e.0).collect())
    }
}

#[cfg(test)]
mod tests {
    use super::Integration;

    /// Each rule's name is the one a scene writes, which serde reads.
    #[test]
    fn an_integration_rule_s_name_is_its_scene_key() {
        for rule in [
            Integration::ConstantAcceleration,
            Integration::DampedConstantAcceleration,
            Integration::AverageAcceleration,
            Integration::AverageInImpacts,
        ] {
            let written = serde_json::to_string(&rule).unwrap_or_default();
            assert_eq!(written, format!("\"{}\"", rule.name()));
            let read: Result<Integration, _> = serde_json::from_str(&written);
            assert_eq!(read.ok(), Some(rule));
        }
    }
}
