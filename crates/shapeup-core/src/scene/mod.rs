//! Scene files: a mesh, solver settings and constraint groups, in TOML or JSON (same schema;
//! see `docs/scenes-and-cli.md`). Paths are relative to the scene file; unknown keys are errors that
//! name the key.
//!
//! [`Scene`] is the parsed file (what the CLI and the editor edit and save); [`Scene::load`]
//! reads its mesh and builds a ready-to-solve [`LoadedScene`].

mod build;
pub mod frames;
mod run;
mod write;

pub use build::{LoadedScene, SpinningHandle, lumped_masses, resolve_selection};
pub use run::{SceneSimulation, StepError, StepTotals, relative_changes};

use crate::mesh::Mesh;
use crate::solver::{Acceleration, Factorization, MAX_ANDERSON_WINDOW, MAX_LBFGS_MEMORY, SolverParams};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};

use crate::text::one_line;
use std::path::{Path, PathBuf};

/// Static (ShapeUp) or dynamic (Projective Dynamics) solving.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Quasi-static shape deformation: minimize the constraint energy.
    #[default]
    Static,
    /// Time stepping with inertia, gravity and damping.
    Dynamic,
}

/// The `[solver]` table. Defaults as in the scene contract.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// "static" (default) or "dynamic".
    pub mode: Mode,
    /// Local-global iterations per step (default 10).
    pub iterations: usize,
    /// Static: total iterations = steps × iterations; dynamic: time steps (default 1).
    pub steps: usize,
    /// > 0: stop early when the relative energy change of an iteration is below it (default 0).
    pub tolerance: f64,
    /// Dynamic: time step h in seconds (default 1/60).
    pub time_step: f64,
    /// Dynamic: gravity in input units per s² (default (0, −9.81, 0)).
    pub gravity: [f64; 3],
    /// Dynamic: stiffness k (default 100).
    pub stiffness: f64,
    /// Dynamic: velocity damping d ∈ [0, 1) (default 0).
    pub damping: f64,
    /// Dynamic: density ρ (default 1).
    pub density: f64,
    /// Sparse Cholesky layout: "auto" (default), "simplicial" or "supernodal".
    pub factorization: Factorization,
    /// "lbfgs" (default), "anderson" or "none": see [`Acceleration`].
    pub acceleration: Acceleration,
    /// Anderson acceleration: iterations mixed, m ≥ 1 (default 5).
    pub anderson_window: usize,
    /// L-BFGS: pairs kept, m ≥ 1 (default 5).
    pub lbfgs_memory: usize,
}

impl Default for SolverSettings {
    fn default() -> Self {
        SolverSettings {
            mode: Mode::Static,
            iterations: 10,
            steps: 1,
            tolerance: 0.0,
            time_step: 1.0 / 60.0,
            gravity: [0.0, -9.81, 0.0],
            stiffness: 100.0,
            damping: 0.0,
            density: 1.0,
            factorization: Factorization::Auto,
            acceleration: SolverParams::default().acceleration,
            anderson_window: SolverParams::default().anderson_window,
            lbfgs_memory: SolverParams::default().lbfgs_memory,
        }
    }
}

/// The `[mesh]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSettings {
    /// Mesh file, relative to the scene file (as written); empty when `generate` is used.
    #[serde(default)]
    pub path: PathBuf,
    /// A generated mesh instead of a file (an extension of the contract).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GeneratedMesh>,
    /// Work in the normalized frame (default true).
    #[serde(default = "yes")]
    pub normalize: bool,
    /// Fill a closed surface with tetrahedra (default false).
    #[serde(default)]
    pub tetrahedralize: bool,
}

fn yes() -> bool {
    true
}

/// The `[output]` table: where a run's results go when the command line does not say
/// (`shapeup deform` without `-o`, `shapeup.batch.run_scenes`). Paths are relative to the scene
/// file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSettings {
    /// Static mode: the deformed mesh (its extension picks the format); dynamic mode: the
    /// folder of the frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// The JSON report.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<PathBuf>,
}

/// A mesh the scene generates instead of reading a file (`[mesh] generate = { kind = … }`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum GeneratedMesh {
    /// A flat cloth in the plane y = 0 ([`crate::generate::cloth_grid`]): `vertices = [nx, nz]`,
    /// `size = [width, depth]`.
    Cloth {
        /// Vertices along x and z (each ≥ 2).
        vertices: [usize; 2],
        /// Extent along x and z.
        size: [f64; 2],
    },
    /// A box of tetrahedra ([`crate::generate::tet_box`]): `cells = [nx, ny, nz]`,
    /// `size = [x, y, z]`.
    TetBox {
        /// Cubes along x, y and z (each ≥ 1).
        cells: [usize; 3],
        /// Extent along x, y and z.
        size: [f64; 3],
    },
}

/// The most memory, in bytes, that loading a scene's generated mesh may take: 1 GB, a tet_box
/// of about 138 × 138 × 138 cells (16 million tetrahedra) or a cloth of about 1,400 × 1,400
/// vertices, each loaded in 1–3 s; a typo in `cells` or `vertices` must not ask for terabytes.
/// Checked against [`GeneratedMesh::estimated_bytes`] when the scene is parsed and again when
/// it loads. Constraint groups come on top (`tet_strain` about 120 bytes per tetrahedron).
pub const MAX_GENERATED_BYTES: u64 = 1_000_000_000;

// Peak bytes that loading a generated mesh takes per element (the mesh, its polygons and
// boundary, the rest geometry with its topology, the solver's set-up; constraint groups come on
// top), measured with a counting allocator (tests/hostile_scene.rs checks them) and rounded up.
const BYTES_PER_VERTEX: f64 = 176.0;
const BYTES_PER_TRIANGLE: f64 = 160.0;
const BYTES_PER_TETRAHEDRON: f64 = 32.0;
// The cap keeps vertex indices far inside u32.
const _: () = assert!(MAX_GENERATED_BYTES as f64 / BYTES_PER_VERTEX < u32::MAX as f64);

impl GeneratedMesh {
    /// Checks the counts and sizes, and the memory the mesh needs against
    /// [`MAX_GENERATED_BYTES`].
    ///
    /// # Errors
    /// A one-line message naming the bad value; for too large a mesh, the estimate, the cap and
    /// the largest counts of the same proportions that fit.
    pub fn validate(&self) -> Result<(), String> {
        let (counts, minimum, sizes): (&[usize], usize, &[f64]) = match self {
            GeneratedMesh::Cloth { vertices, size } => (vertices, 2, size),
            GeneratedMesh::TetBox { cells, size } => (cells, 1, size),
        };
        if let Some(n) = counts.iter().find(|&&n| n < minimum) {
            return Err(format!("generate: every count must be at least {minimum}, found {n}"));
        }
        if let Some(x) = sizes.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
            return Err(format!("generate: every size must be a finite number > 0, found {x}"));
        }
        let bytes = self.estimated_bytes();
        if bytes <= MAX_GENERATED_BYTES as f64 {
            return Ok(());
        }
        let (what, unit, elements) = match self {
            GeneratedMesh::Cloth { .. } => {
                ("cloth", "vertices", format!("{} triangles", count(self.element_counts()[1])))
            }
            GeneratedMesh::TetBox { .. } => {
                ("tet_box", "cells", format!("{} tetrahedra", count(self.element_counts()[2])))
            }
        };
        let shown = |c: &[usize]| c.iter().map(|&n| grouped(n as u64)).collect::<Vec<_>>().join(" × ");
        let advice = match self.largest_that_fits() {
            Some(fits) => format!(": use at most about {} {unit}", shown(&fits)),
            None => String::new(),
        };
        Err(format!(
            "generate: a {what} of {} {unit} ({elements}) needs about {} to load; the cap is {}{advice}",
            shown(counts_of(self)),
            gigabytes(bytes),
            gigabytes(MAX_GENERATED_BYTES as f64),
        ))
    }

    /// Its vertices, triangles and tetrahedra, as floating-point numbers (exact up to 2⁵³,
    /// finite for any counts: no overflow).
    pub fn element_counts(&self) -> [f64; 3] {
        match *self {
            GeneratedMesh::Cloth { vertices, .. } => {
                let [x, z] = vertices.map(|n| n.max(2) as f64);
                [x * z, 2.0 * (x - 1.0) * (z - 1.0), 0.0]
            }
            GeneratedMesh::TetBox { cells, .. } => {
                let [x, y, z] = cells.map(|n| n.max(1) as f64);
                [(x + 1.0) * (y + 1.0) * (z + 1.0), 4.0 * (x * y + y * z + z * x), 6.0 * x * y * z]
            }
        }
    }

    /// The bytes that loading a scene with this mesh takes at its peak, estimated from its
    /// element counts (constraint groups come on top).
    pub fn estimated_bytes(&self) -> f64 {
        let [v, t, k] = self.element_counts();
        BYTES_PER_VERTEX * v + BYTES_PER_TRIANGLE * t + BYTES_PER_TETRAHEDRON * k
    }

    /// The largest counts in the same proportions whose estimate fits the cap (bisection on
    /// the scale), or `None` if not even the smallest does.
    fn largest_that_fits(&self) -> Option<Vec<usize>> {
        let scaled = |s: f64| -> GeneratedMesh {
            let f = |n: usize, minimum: usize| ((n as f64 * s).floor() as usize).max(minimum);
            match *self {
                GeneratedMesh::Cloth { vertices, size } => {
                    GeneratedMesh::Cloth { vertices: vertices.map(|n| f(n, 2)), size }
                }
                GeneratedMesh::TetBox { cells, size } => GeneratedMesh::TetBox { cells: cells.map(|n| f(n, 1)), size },
            }
        };
        let fits = |s: f64| scaled(s).estimated_bytes() <= MAX_GENERATED_BYTES as f64;
        if !fits(0.0) {
            return None;
        }
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..80 {
            let mid = 0.5 * (lo + hi);
            if fits(mid) { lo = mid } else { hi = mid }
        }
        Some(counts_of(&scaled(lo)).to_vec())
    }

    /// The mesh.
    pub fn mesh(&self) -> Mesh {
        match *self {
            GeneratedMesh::Cloth { vertices: [nx, nz], size: [w, d] } => crate::generate::cloth_grid(nx, nz, w, d),
            GeneratedMesh::TetBox { cells, size } => crate::generate::tet_box(cells, DVec3::from_array(size)),
        }
    }
}

fn counts_of(generated: &GeneratedMesh) -> &[usize] {
    match generated {
        GeneratedMesh::Cloth { vertices, .. } => vertices,
        GeneratedMesh::TetBox { cells, .. } => cells,
    }
}

/// A count with thousands separators (`14,762,250`), in scientific notation past 10¹⁵.
fn count(n: f64) -> String {
    if n >= 1e15 { format!("{n:.2e}") } else { grouped(n as u64) }
}

/// `n` with thousands separators.
fn grouped(n: u64) -> String {
    let digits = n.to_string();
    let mut out = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, d) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(d);
    }
    out
}

/// Bytes in GB (10⁹ bytes), or MB below 0.1 GB.
fn gigabytes(bytes: f64) -> String {
    match bytes {
        b if b < 1e8 => format!("{:.0} MB", b / 1e6),
        b if b < 1e15 => format!("{:.1} GB", b / 1e9),
        b => format!("{:.1e} GB", b / 1e9),
    }
}

/// Which vertices a group applies to (coordinates in the input frame).
#[derive(Debug, Clone, PartialEq)]
pub enum SelectionSpec {
    /// Every vertex.
    All,
    /// Listed vertex indices (0-based, file order).
    Vertices(Vec<usize>),
    /// Listed polygon faces (0-based, file order): face constraints act on them, vertex
    /// constraints on their corners.
    Faces(Vec<usize>),
    /// Vertices inside an axis-aligned box (bounds included).
    Box {
        /// Lower corner.
        min: [f64; 3],
        /// Upper corner.
        max: [f64; 3],
    },
    /// Vertices inside a ball (boundary included).
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
}

impl SelectionSpec {
    /// The vertex indices it picks among `positions` (input frame): every vertex for
    /// [`SelectionSpec::All`], the listed order for a list, ascending for a box or sphere.
    ///
    /// # Errors
    /// A listed index out of range, as a one-line message naming it.
    pub fn resolve(&self, positions: &[glam::DVec3]) -> Result<Vec<usize>, String> {
        let n = positions.len();
        let inside = |f: &dyn Fn(glam::DVec3) -> bool| (0..n).filter(|&i| f(positions[i])).collect();
        Ok(match self {
            SelectionSpec::All => (0..n).collect(),
            SelectionSpec::Vertices(list) => {
                if let Some(&v) = list.iter().find(|&&v| v >= n) {
                    return Err(format!(
                        "vertex {v} is out of range (the mesh has {n} vertices: 0..{})",
                        n.saturating_sub(1)
                    ));
                }
                list.clone()
            }
            SelectionSpec::Faces(_) => {
                return Err("a face selection needs the mesh's faces: use scene::resolve_selection".into());
            }
            SelectionSpec::Box { min, max } => {
                let (lo, hi) = (glam::DVec3::from(*min), glam::DVec3::from(*max));
                inside(&|p| p.cmpge(lo).all() && p.cmple(hi).all())
            }
            SelectionSpec::Sphere { center, radius } => {
                let c = glam::DVec3::from(*center);
                inside(&|p| (p - c).length() <= *radius)
            }
        })
    }
}

/// A rotation of a handle's targets about an axis, applied before its translation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotate {
    /// Rotation axis (normalized on use; must be non-zero).
    pub axis: [f64; 3],
    /// Angle in degrees, right-handed about the axis.
    pub angle_deg: f64,
    /// Centre; default the centroid of the selected vertices.
    #[serde(default)]
    pub center: Option<[f64; 3]>,
}

/// A handle turning at a constant rate in dynamic mode (an extension of the contract): at time
/// t its targets are the static ones turned by `deg_per_s` · t about the axis through `center`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spin {
    /// Rotation axis (normalized on use; must be non-zero).
    pub axis: [f64; 3],
    /// Turning rate in degrees per second, right-handed about the axis.
    pub deg_per_s: f64,
    /// Centre; default the centroid of the static targets.
    #[serde(default)]
    pub center: Option<[f64; 3]>,
}

impl Spin {
    /// The unit axis and the centre it turns about (default: the centroid of `targets`).
    ///
    /// # Errors
    /// A zero axis.
    pub fn pivot(&self, targets: &[glam::DVec3]) -> Result<(glam::DVec3, glam::DVec3), String> {
        use glam::DVec3;
        let axis = DVec3::from(self.axis).try_normalize().ok_or("spin axis must be non-zero")?;
        let center = self
            .center
            .map(DVec3::from)
            .unwrap_or_else(|| targets.iter().copied().sum::<DVec3>() / targets.len().max(1) as f64);
        Ok((axis, center))
    }
}

/// Where a position group's vertices should go (input frame).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Targets {
    /// Targets = rest (rotated) + translate.
    pub translate: [f64; 3],
    /// Optional rotation of the rest positions, applied first.
    pub rotate: Option<Rotate>,
    /// Explicit targets, one per selected vertex (overrides translate and rotate).
    pub explicit: Option<Vec<[f64; 3]>>,
    /// Dynamic mode: the targets turn at a constant rate (see [`Spin`]); static mode ignores it.
    pub spin: Option<Spin>,
}

impl Targets {
    /// The targets (input frame) of vertices at `rest` (input frame): the explicit ones, or
    /// `rest` rotated about the centre (default: their centroid) and then translated.
    ///
    /// # Errors
    /// An explicit list of the wrong length, or a zero rotation axis.
    pub fn resolve(&self, rest: &[glam::DVec3]) -> Result<Vec<glam::DVec3>, String> {
        use glam::{DQuat, DVec3};
        if let Some(explicit) = &self.explicit {
            if explicit.len() != rest.len() {
                return Err(format!(
                    "{} targets given for {} selected vertices (one per vertex)",
                    explicit.len(),
                    rest.len()
                ));
            }
            return Ok(explicit.iter().map(|&t| DVec3::from(t)).collect());
        }
        let translate = DVec3::from(self.translate);
        let rotation = match &self.rotate {
            None => None,
            Some(r) => {
                let center = r
                    .center
                    .map(DVec3::from)
                    .unwrap_or_else(|| rest.iter().copied().sum::<DVec3>() / rest.len().max(1) as f64);
                let axis = DVec3::from(r.axis).try_normalize().ok_or("rotation axis must be non-zero")?;
                Some((center, DQuat::from_axis_angle(axis, r.angle_deg.to_radians())))
            }
        };
        Ok(rest
            .iter()
            .map(|&p| match rotation {
                Some((center, q)) => center + q * (p - center) + translate,
                None => p + translate,
            })
            .collect())
    }
}

/// One `[[constraints]]` entry: a group.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupSpec {
    /// Constraint type name.
    pub kind: String,
    /// Group name (default: the type).
    pub name: String,
    /// Group multiplier g (default: the type's default).
    pub weight: f64,
    /// The vertices it applies to.
    pub selection: SelectionSpec,
    /// Position groups: their targets.
    pub targets: Targets,
    /// Type-specific options (`strain_freedom`, `prevent_flips`, `height`, `push`).
    pub options: Map<String, Value>,
}

/// A parsed scene file.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The `[mesh]` table.
    pub mesh: MeshSettings,
    /// The `[solver]` table.
    pub solver: SolverSettings,
    /// The constraint groups, in file order.
    pub groups: Vec<GroupSpec>,
    /// The `[output]` table.
    pub output: OutputSettings,
    /// Directory that relative paths start from.
    pub base_dir: PathBuf,
    /// The scene file, for messages.
    pub file: PathBuf,
}

/// A scene that cannot be read, parsed or built. Messages are one line naming the file and,
/// where known, the line or the `constraints[i]` entry.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file cannot be read.
    #[error("cannot read scene {}: {source}", one_line(path.display()))]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Syntax or schema error (unknown key, wrong type…).
    #[error("{}: {}", one_line(path.display()), one_line(message))]
    Parse {
        /// The file.
        path: PathBuf,
        /// What and where (line, column).
        message: String,
    },
    /// A semantically invalid entry.
    #[error("{}: {}: {}", one_line(path.display()), one_line(entry), one_line(message))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// `constraints[2] ("handle")`, `[solver]`, `[mesh]`…
        entry: String,
        /// What is wrong.
        message: String,
    },
    /// The mesh cannot be loaded.
    #[error("{}: {source}", one_line(path.display()))]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// The mesh error (names the mesh file).
        source: crate::io::IoError,
    },
    /// The constraints make an unsolvable system.
    #[error("{}: {source}", one_line(path.display()))]
    Solve {
        /// The scene file.
        path: PathBuf,
        /// Why.
        source: crate::solver::SolveError,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawScene {
    mesh: MeshSettings,
    #[serde(default)]
    solver: SolverSettings,
    #[serde(default)]
    constraints: Vec<Entry>,
    #[serde(default)]
    output: OutputSettings,
}

/// How deep a constraint entry may nest (`box = { min = [..] }` is 3 levels).
const MAX_ENTRY_DEPTH: usize = 32;

/// A `[[constraints]]` entry as JSON values, read strictly: a key given twice is refused
/// (serde_json's own map keeps the last one silently) and so is nesting deeper than
/// [`MAX_ENTRY_DEPTH`] (building `serde_json::Value` recurses once per level, and TOML's dotted
/// keys nest without its parser's limit).
struct Entry(Map<String, Value>);

impl<'de> Deserialize<'de> for Entry {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        match deserializer.deserialize_map(StrictValue { depth: 0 })? {
            Value::Object(map) => Ok(Entry(map)),
            _ => Err(serde::de::Error::custom("a constraint entry must be a table")),
        }
    }
}

/// Builds a `serde_json::Value` refusing repeated keys and deep nesting.
#[derive(Clone, Copy)]
struct StrictValue {
    depth: usize,
}

impl StrictValue {
    fn deeper<E: serde::de::Error>(self) -> Result<StrictValue, E> {
        if self.depth >= MAX_ENTRY_DEPTH {
            return Err(E::custom(format!("nested deeper than {MAX_ENTRY_DEPTH} levels")));
        }
        Ok(StrictValue { depth: self.depth + 1 })
    }
}

impl<'de> serde::de::DeserializeSeed<'de> for StrictValue {
    type Value = Value;
    fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Value, D::Error> {
        deserializer.deserialize_any(self)
    }
}

impl<'de> serde::de::Visitor<'de> for StrictValue {
    type Value = Value;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a value")
    }
    fn visit_bool<E>(self, v: bool) -> Result<Value, E> {
        Ok(Value::Bool(v))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Value, E> {
        Ok(Value::from(v))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Value, E> {
        // inf and nan become null, as serde_json has them (the builders name the key).
        Ok(serde_json::Number::from_f64(v).map_or(Value::Null, Value::Number))
    }
    fn visit_str<E>(self, v: &str) -> Result<Value, E> {
        Ok(Value::String(v.to_owned()))
    }
    fn visit_string<E>(self, v: String) -> Result<Value, E> {
        Ok(Value::String(v))
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_some<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Value, D::Error> {
        deserializer.deserialize_any(self)
    }
    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let inner = self.deeper()?;
        // Not sized by the hint: it may claim more than the input holds.
        let mut list = Vec::new();
        while let Some(v) = seq.next_element_seed(inner)? {
            list.push(v);
        }
        Ok(Value::Array(list))
    }
    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let inner = self.deeper()?;
        let mut out = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if out.contains_key(&key) {
                return Err(serde::de::Error::custom(format!("duplicate key `{key}`")));
            }
            let value = map.next_value_seed(inner)?;
            out.insert(key, value);
        }
        Ok(Value::Object(out))
    }
}

/// Scene file syntax.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneFormat {
    /// TOML (`.toml`).
    Toml,
    /// JSON (`.json`).
    Json,
}

impl Scene {
    /// Reads and parses a scene file (`.toml` or `.json`).
    ///
    /// # Errors
    /// [`SceneError`] naming the file, and the line or entry.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let format = match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("toml") => SceneFormat::Toml,
            Some("json") => SceneFormat::Json,
            _ => {
                return Err(SceneError::Parse {
                    path: path.into(),
                    message: "a scene file must end in .toml or .json".into(),
                });
            }
        };
        // UTF-8 (a byte-order mark, which is not TOML or JSON, removed) or UTF-16 (Windows
        // editors' "Unicode"), decoded; text that is neither is a format error with its offset.
        let text = crate::io::read_text_file(path).map_err(|source| match crate::io::DecodeError::of(&source) {
            Some(e) => SceneError::Parse { path: path.into(), message: e.to_string() },
            None => SceneError::Read { path: path.into(), source },
        })?;
        let text = text.as_str();
        let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(text, format, path, base_dir)
    }

    /// Parses scene text; `path` is only used in messages, `base_dir` resolves the mesh path.
    ///
    /// # Errors
    /// [`SceneError::Parse`] or [`SceneError::Invalid`].
    pub fn parse(text: &str, format: SceneFormat, path: &Path, base_dir: PathBuf) -> Result<Scene, SceneError> {
        let parse_error = |message: String| SceneError::Parse { path: path.into(), message };
        let raw: RawScene = match format {
            SceneFormat::Toml => toml::from_str(text).map_err(|e| parse_error(toml_message(text, &e)))?,
            SceneFormat::Json => serde_json::from_str(text).map_err(|e| parse_error(e.to_string()))?,
        };
        let mesh_error = |message: String| SceneError::Invalid { path: path.into(), entry: "[mesh]".into(), message };
        match (&raw.mesh.generate, raw.mesh.path.as_os_str().is_empty()) {
            (Some(g), true) => g.validate().map_err(mesh_error)?,
            (Some(_), false) => return Err(mesh_error("give either path or generate, not both".into())),
            (None, true) => return Err(mesh_error("missing path (a mesh file), or generate".into())),
            (None, false) => {}
        }
        validate_solver(&raw.solver).map_err(|message| SceneError::Invalid {
            path: path.into(),
            entry: "[solver]".into(),
            message,
        })?;
        let groups = raw
            .constraints
            .into_iter()
            .enumerate()
            .map(|(i, Entry(entry))| {
                let name = entry.get("name").and_then(Value::as_str).map(|n| format!(" (\"{n}\")")).unwrap_or_default();
                GroupSpec::from_entry(entry).map_err(|message| SceneError::Invalid {
                    path: path.into(),
                    entry: format!("constraints[{i}]{name}"),
                    message,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Scene { mesh: raw.mesh, solver: raw.solver, groups, output: raw.output, base_dir, file: path.into() })
    }

    /// The mesh file's path, resolved against the scene's directory.
    pub fn mesh_path(&self) -> PathBuf {
        self.base_dir.join(&self.mesh.path)
    }

    /// `[output] path`, resolved against the scene's directory.
    pub fn output_path(&self) -> Option<PathBuf> {
        self.output.path.as_ref().map(|p| self.base_dir.join(p))
    }

    /// `[output] report`, resolved against the scene's directory.
    pub fn report_path(&self) -> Option<PathBuf> {
        self.output.report.as_ref().map(|p| self.base_dir.join(p))
    }
}

/// One line from a TOML error: its message with the line and column of its span.
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim().replace('\n', " ");
    match e.span() {
        Some(span) => {
            let mut start = span.start.min(text.len());
            while !text.is_char_boundary(start) {
                start -= 1;
            }
            let before = &text[..start];
            let line = before.matches('\n').count() + 1;
            let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
            // Quote the line: a type error's message names the value but not the key.
            let quoted = text.lines().nth(line - 1).map(str::trim).filter(|l| !l.is_empty() && l.len() <= 80);
            match quoted {
                Some(l) => format!("line {line}, column {column}: {message} (in `{l}`)"),
                None => format!("line {line}, column {column}: {message}"),
            }
        }
        // toml's deserializer stops past 128 levels without a span: point at the line whose
        // keys and brackets nest deepest.
        None if message.contains("recursion limit") => {
            let depth =
                |l: &str| l.split('=').next().map_or(0, |key| key.matches('.').count()) + l.matches(['[', '{']).count();
            match text.lines().enumerate().max_by_key(|&(i, l)| (depth(l), std::cmp::Reverse(i))) {
                Some((i, _)) => format!("line {}: nested too deep ({message})", i + 1),
                None => message,
            }
        }
        None => message,
    }
}

fn validate_solver(s: &SolverSettings) -> Result<(), String> {
    let positive = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 { Ok(()) } else { Err(format!("{name} must be a number > 0, found {v}")) }
    };
    if !(s.tolerance.is_finite() && s.tolerance >= 0.0) {
        return Err(format!("tolerance must be ≥ 0, found {}", s.tolerance));
    }
    positive("time_step", s.time_step)?;
    positive("stiffness", s.stiffness)?;
    positive("density", s.density)?;
    if !(0.0..1.0).contains(&s.damping) {
        return Err(format!("damping must be in [0, 1), found {}", s.damping));
    }
    if !s.gravity.iter().all(|g| g.is_finite()) {
        return Err("gravity must be three finite numbers".into());
    }
    if !(1..=MAX_ANDERSON_WINDOW).contains(&s.anderson_window) {
        return Err(format!("anderson_window must be in 1..={MAX_ANDERSON_WINDOW}, found {}", s.anderson_window));
    }
    if !(1..=MAX_LBFGS_MEMORY).contains(&s.lbfgs_memory) {
        return Err(format!("lbfgs_memory must be in 1..={MAX_LBFGS_MEMORY}, found {}", s.lbfgs_memory));
    }
    Ok(())
}

/// Keys every group takes; the rest go to the type's builder (which rejects unknown ones).
const SELECTION_KEYS: [&str; 4] = ["vertices", "faces", "box", "sphere"];

impl GroupSpec {
    /// A group from one `[[constraints]]` entry as JSON values (the keys of the scene
    /// contract: `type`, `name`, `weight`, one selection key, targets for types with targets,
    /// and the type's options, which [`GroupSpec::build`] checks). The scene parser and the
    /// Python package both come through here.
    ///
    /// # Errors
    /// A one-line message naming the bad key.
    pub fn from_entry(entry: Map<String, Value>) -> Result<GroupSpec, String> {
        parse_group(entry)
    }
}

fn parse_group(mut entry: Map<String, Value>) -> Result<GroupSpec, String> {
    let kind = match entry.remove("type") {
        Some(Value::String(s)) => s,
        Some(other) => return Err(format!("\"type\" must be a string, found {other}")),
        None => return Err(format!("missing \"type\" (one of: {})", crate::constraints::type_names().join(", "))),
    };
    let ty = crate::constraints::constraint_type(&kind).map_err(|e| e.to_string())?;
    let name = match entry.remove("name") {
        Some(Value::String(s)) => s,
        Some(other) => return Err(format!("\"name\" must be a string, found {other}")),
        None => kind.clone(),
    };
    let weight = match entry.remove("weight") {
        None => ty.default_multiplier(),
        Some(v) => match v.as_f64() {
            Some(w) if w.is_finite() && w >= 0.0 => w,
            // TOML's inf and nan arrive as null (the entry went through JSON values).
            _ if v.is_null() => return Err("\"weight\" must be a finite number ≥ 0, found inf, nan or null".into()),
            _ => return Err(format!("\"weight\" must be a finite number ≥ 0, found {v}")),
        },
    };
    let given: Vec<&str> = SELECTION_KEYS.iter().copied().filter(|k| entry.contains_key(*k)).collect();
    if given.len() > 1 {
        return Err(format!("give at most one of vertices, faces, box, sphere (found {})", given.join(" and ")));
    }
    let selection = if let Some(v) = entry.remove("vertices") {
        let list: Vec<usize> =
            serde_json::from_value(v).map_err(|_| "\"vertices\" must be a list of vertex indices ≥ 0")?;
        SelectionSpec::Vertices(list)
    } else if let Some(v) = entry.remove("faces") {
        let list: Vec<usize> = serde_json::from_value(v).map_err(|_| "\"faces\" must be a list of face indices ≥ 0")?;
        SelectionSpec::Faces(list)
    } else if let Some(v) = entry.remove("box") {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct B {
            min: [f64; 3],
            max: [f64; 3],
        }
        let b: B = serde_json::from_value(v)
            .map_err(|e| format!("\"box\": {e} (expected {{ min = [x,y,z], max = [x,y,z] }})"))?;
        SelectionSpec::Box { min: b.min, max: b.max }
    } else if let Some(v) = entry.remove("sphere") {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct S {
            center: [f64; 3],
            radius: f64,
        }
        let s: S = serde_json::from_value(v)
            .map_err(|e| format!("\"sphere\": {e} (expected {{ center = [x,y,z], radius = r }})"))?;
        if !(s.radius.is_finite() && s.radius >= 0.0) {
            return Err(format!("sphere radius must be ≥ 0, found {}", s.radius));
        }
        SelectionSpec::Sphere { center: s.center, radius: s.radius }
    } else {
        SelectionSpec::All
    };
    let targets = if ty.has_targets() { parse_targets(&mut entry)? } else { Targets::default() };
    Ok(GroupSpec { kind, name, weight, selection, targets, options: entry })
}

fn parse_targets(entry: &mut Map<String, Value>) -> Result<Targets, String> {
    let mut t = Targets::default();
    if let Some(v) = entry.remove("translate") {
        t.translate = serde_json::from_value(v).map_err(|_| "\"translate\" must be [x, y, z]")?;
    }
    if let Some(v) = entry.remove("rotate") {
        let r: Rotate = serde_json::from_value(v)
            .map_err(|e| format!("\"rotate\": {e} (expected {{ axis = [x,y,z], angle_deg = a, center = [x,y,z] }})"))?;
        if r.axis.iter().map(|a| a * a).sum::<f64>() <= 0.0 || !r.angle_deg.is_finite() {
            return Err("\"rotate\" needs a non-zero axis and a finite angle_deg".into());
        }
        t.rotate = Some(r);
    }
    if let Some(v) = entry.remove("spin") {
        let spin: Spin = serde_json::from_value(v)
            .map_err(|e| format!("\"spin\": {e} (expected {{ axis = [x,y,z], deg_per_s = w, center = [x,y,z] }})"))?;
        if spin.axis.iter().map(|a| a * a).sum::<f64>() <= 0.0 || !spin.deg_per_s.is_finite() {
            return Err("\"spin\" needs a non-zero axis and a finite deg_per_s".into());
        }
        t.spin = Some(spin);
    }
    if let Some(v) = entry.remove("targets") {
        if t.rotate.is_some() || t.translate != [0.0; 3] {
            return Err("give either \"targets\" or translate/rotate, not both".into());
        }
        t.explicit = Some(serde_json::from_value(v).map_err(|_| "\"targets\" must be a list of [x, y, z]")?);
    }
    if [t.translate.iter().all(|x| x.is_finite())].contains(&false)
        || t.explicit.as_ref().is_some_and(|e| e.iter().flatten().any(|x| !x.is_finite()))
    {
        return Err("targets must be finite numbers".into());
    }
    Ok(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, SceneFormat::Toml, Path::new("s.toml"), PathBuf::new())
    }

    #[test]
    fn defaults_and_groups() {
        let s = parse(
            r#"
            [mesh]
            path = "m.obj"
            [[constraints]]
            type = "edge_spring"
            [[constraints]]
            type = "position"
            name = "handle"
            box = { min = [0, 0, 0], max = [1, 1, 1] }
            translate = [0.1, 0, 0]
            "#,
        )
        .unwrap();
        assert!(s.mesh.normalize);
        assert_eq!(s.solver, SolverSettings::default());
        assert_eq!(s.groups[0].weight, 10.0, "default multiplier of edge springs");
        assert_eq!(s.groups[0].name, "edge_spring");
        assert_eq!(s.groups[1].targets.translate, [0.1, 0.0, 0.0]);
        assert!(matches!(s.groups[1].selection, SelectionSpec::Box { .. }));
    }

    #[test]
    fn unknown_keys_are_named() {
        let e = parse("[mesh]\npath = \"m.obj\"\nnormalise = true\n").unwrap_err().to_string();
        assert!(e.contains("normalise") && e.contains("line 3"), "{e}");
        let e = parse("[mesh]\npath = \"m.obj\"\n[solver]\niteratons = 3\n").unwrap_err().to_string();
        assert!(e.contains("iteratons"), "{e}");
        let e = parse("[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge_sprin\"\n").unwrap_err().to_string();
        assert!(e.contains("edge_sprin") && e.contains("constraints[0]"), "{e}");
    }

    #[test]
    fn bad_values_are_rejected() {
        for (body, needle) in [
            ("[[constraints]]\ntype = \"edge_spring\"\nweight = -1\n", "weight"),
            ("[[constraints]]\ntype = \"position\"\nvertices = [-1]\n", "vertices"),
            (
                "[[constraints]]\ntype = \"position\"\nvertices = [1]\nbox = { min = [0,0,0], max = [1,1,1] }\n",
                "at most one",
            ),
            ("[solver]\ndamping = 1.0\n", "damping"),
            ("[solver]\niterations = -3\n", "iterations"),
            ("[[constraints]]\ntype = \"position\"\nvertices = [1]\ntranslate = [1, 2]\n", "translate"),
        ] {
            let e = parse(&format!("[mesh]\npath = \"m.obj\"\n{body}")).unwrap_err().to_string();
            assert!(e.contains(needle), "{needle}: {e}");
        }
    }

    #[test]
    fn json_has_the_same_schema() {
        let s = Scene::parse(
            r#"{"mesh": {"path": "m.obj", "normalize": false}, "constraints": [{"type": "iso_one_ring", "weight": 5}]}"#,
            SceneFormat::Json,
            Path::new("s.json"),
            PathBuf::new(),
        );
        let s = s.unwrap();
        assert!(!s.mesh.normalize);
        assert_eq!(s.groups[0].weight, 5.0);
        let e = Scene::parse(
            r#"{"mesh": {"path": "m.obj"}, "extra": 1}"#,
            SceneFormat::Json,
            Path::new("s.json"),
            PathBuf::new(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("extra"), "{e}");
    }
}
