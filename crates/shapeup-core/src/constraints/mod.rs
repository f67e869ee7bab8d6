//! Constraints: the `w‖C q − p(q)‖²` terms of the ShapeUp / Projective Dynamics energy.
//!
//! A constraint type is one file: a struct implementing [`Constraint`] (its rows of C, its
//! projection p and its element weight ω) and a unit struct implementing [`ConstraintType`]
//! (how a scene or the editor builds it on a selection), listed once in [`registry`]. Assembly,
//! factorization, the parallel local step, energies and the editor's list are generic over them.
//!
//! Rows are numbered from 0 inside a constraint: a constraint never learns where its rows land
//! in the global system (the assembler adds the offset and the weight).

use crate::geometry::{RestGeometry, WorkingFrame};
use glam::DVec3;
use std::any::Any;
use std::fmt::Debug;

mod angle;
mod area;
mod attachment;
mod bending;
mod circle;
mod edge_spring;
mod edge_strain;
mod floor;
mod force;
mod gravity;
mod group;
mod hinge_bending;
mod iso_one_ring;
mod laplacian;
mod laplacian_displacement;
mod line;
mod parallelogram;
mod plane;
mod position;
mod rectangle;
mod rigid;
mod sets;
mod similarity;
mod smoothing;
mod sphere;
mod surface_closeness;
mod tet_strain;
mod triangle_strain;
mod volume;

pub use angle::{Angle, AngleType};
pub use area::{Area, AreaType};
pub use attachment::{
    DEGENERATE_FACES_GROUP, DegenerateAttachments, EdgeAttachment, attach_degenerate_vertices, degenerate_attachments,
};
pub use bending::{Bending, BendingType};
pub use circle::{Circle, CircleType};
pub use edge_spring::{EdgeSpring, EdgeSpringType};
pub use edge_strain::{EdgeStrain, EdgeStrainType};
pub use floor::{Floor, FloorType};
pub use force::{Force, ForceType};
pub use gravity::GravityType;
pub use group::{ConstraintGroup, GroupDescription, GroupId, WeightError, build_group, check_weight, held_vertices};
pub use hinge_bending::{HingeBending, HingeBendingType};
pub use iso_one_ring::{IsoOneRing, IsoOneRingType};
pub use laplacian::{Laplacian, LaplacianType};
pub use laplacian_displacement::{LaplacianDisplacement, LaplacianDisplacementType};
pub use line::{Line, LineType};
pub use parallelogram::{Parallelogram, ParallelogramType};
pub use plane::{Plane, PlaneType};
pub use position::{Position, PositionType};
pub use rectangle::{Rectangle, RectangleType};
pub use rigid::{Rigid, RigidType};
pub use similarity::{Similarity, SimilarityType};
pub use smoothing::{Smoothing, SmoothingType};
pub use sphere::{Sphere, SphereType};
pub use surface_closeness::{SurfaceCloseness, SurfaceClosenessType};
pub use tet_strain::{TetStrain, TetStrainType};
pub use triangle_strain::{TriangleStrain, TriangleStrainType};
pub use volume::{Volume, VolumeType};

/// One entry of a constraint's selection matrix C_i: `C[row, vertex] = coeff`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RowEntry {
    /// Row within the constraint, `0..num_rows()`.
    pub row: u32,
    /// Vertex index (column of C).
    pub vertex: u32,
    /// Coefficient.
    pub coeff: f64,
}

/// Collects the rows of C a constraint emits ([`Constraint::rows`]).
#[derive(Debug, Default, Clone)]
pub struct RowSink {
    /// Entries in emission order.
    pub entries: Vec<RowEntry>,
}

impl RowSink {
    /// Adds `C[row, vertex] += coeff`.
    pub fn push(&mut self, row: usize, vertex: u32, coeff: f64) {
        self.entries.push(RowEntry { row: row as u32, vertex, coeff });
    }
}

/// A constant load ([`Constraint::load`]): forces on vertices and the rest points their
/// potential is measured from (all working frame).
#[derive(Debug, Clone, Copy)]
pub struct Load<'a> {
    /// The vertices loaded.
    pub vertices: &'a [u32],
    /// The force on each (working frame).
    pub forces: &'a [DVec3],
    /// Each vertex's rest position x⁰_v.
    pub rest: &'a [DVec3],
}

impl Load<'_> {
    /// −2 Σ_v f_v · (q_v − x⁰_v): the load's share of E without the multiplier.
    pub fn energy(&self, q: &[DVec3]) -> f64 {
        let work: f64 =
            self.vertices.iter().zip(self.forces).zip(self.rest).map(|((&v, f), x0)| f.dot(q[v as usize] - *x0)).sum();
        -2.0 * work
    }
}

/// The elements a constraint type builds one constraint on: what its selection picks, what
/// the editor offers it for, and which meshes the shared tests run it on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Element {
    /// One constraint per selected vertex.
    Vertex,
    /// One constraint over all the selected vertices together (at least `min` of them).
    VertexSet {
        /// Fewest vertices the set needs.
        min: usize,
    },
    /// One per edge whose two vertices are selected.
    Edge,
    /// One per polygon face of the input (as read, not its triangles) with between `min` and
    /// `max` corners.
    Face {
        /// Fewest corners.
        min: usize,
        /// Most corners.
        max: usize,
    },
    /// One per triangle of the triangulation.
    Triangle,
    /// One per tetrahedron.
    Tetrahedron,
}

impl Element {
    /// Whether the element is a polygon face (selections may name faces).
    pub fn is_face(self) -> bool {
        matches!(self, Element::Face { .. })
    }

    /// Plural noun for messages ("quad faces", "vertices").
    pub fn plural(self) -> String {
        match self {
            Element::Vertex | Element::VertexSet { .. } => "vertices".into(),
            Element::Edge => "edges".into(),
            Element::Face { min: 4, max: 4 } => "quad faces".into(),
            Element::Face { min, max } if max == usize::MAX => format!("faces of {min} or more corners"),
            Element::Face { min, max } => format!("faces of {min} to {max} corners"),
            Element::Triangle => "triangles".into(),
            Element::Tetrahedron => "tetrahedra".into(),
        }
    }
}

/// What an option of a constraint type takes, and its default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OptionKind {
    /// A finite number in [`min`, `max`]; `default` `None` means the value comes from the rest
    /// shape (the option's doc says how).
    Number {
        /// Default, or `None` for "from the rest shape".
        default: Option<f64>,
        /// Smallest value allowed.
        min: f64,
        /// Largest value allowed.
        max: f64,
    },
    /// `true` or `false`.
    Bool {
        /// Default.
        default: bool,
    },
    /// Three finite numbers `[x, y, z]`.
    Vector {
        /// Default.
        default: [f64; 3],
    },
}

/// One option of a constraint type: its scene key, what it means, what it takes. Scenes,
/// the editor's widgets and the shared tests all read it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionSpec {
    /// Scene key.
    pub key: &'static str,
    /// One line: meaning, units, default.
    pub doc: &'static str,
    /// Value type, range and default.
    pub kind: OptionKind,
}

/// A constraint term `ω ‖C q − p(q)‖²_F` (the group multiplier g is applied by its group).
///
/// - `C q` is `num_rows()×3`: each row is a linear combination of vertex positions, given by
///   [`Constraint::rows`].
/// - `p(q)` is the closest point to `C q` on the constraint set, written by
///   [`Constraint::project`].
///
/// Implementations are immutable during a solve (`&self`): the local step projects all
/// constraints in parallel into disjoint slices of one buffer.
pub trait Constraint: Any + Send + Sync + Debug {
    /// The type's name, as in scene files (`"edge_spring"`, …).
    fn kind(&self) -> &'static str;
    /// The vertices the constraint reads (every column of its rows).
    fn vertices(&self) -> &[u32];
    /// The vertices this constraint pulls to points and those points, when it can hold them
    /// there exactly instead (a position handle): what a hard group fixes
    /// ([`ConstraintGroup::hard`](crate::solver::ConstraintGroup::hard)). `None` (the default):
    /// the constraint cannot be hard.
    fn held_points(&self) -> Option<(&[u32], &[DVec3])> {
        None
    }
    /// Moves the points [`Constraint::held_points`] gives (a handle's targets, working frame),
    /// one per held vertex; returns `false` (and changes nothing) for a constraint without
    /// targets or the wrong count. Only the projection may change, so the factorization stays
    /// valid.
    fn set_targets(&mut self, _targets: &[DVec3]) -> bool {
        false
    }
    /// A constant load instead of (or besides) a projective term: forces f_v on vertices v at
    /// rest points x⁰_v, adding −2 Σ_v f_v · (q_v − x⁰_v) to E (times the group multiplier),
    /// so that the global step's right-hand side gains Σ g f_v as in ShapeOp (math reference,
    /// "Forces"). `None` (the default): no load.
    fn load(&self) -> Option<Load<'_>> {
        None
    }
    /// The element weight ω_i (rest length, area, volume, … as in the math reference).
    fn element_weight(&self) -> f64;
    /// Number of rows k_i of C_i; fixed after construction.
    fn num_rows(&self) -> usize;
    /// Emits the rows of C_i, numbered `0..num_rows()`.
    fn rows(&self, sink: &mut RowSink);
    /// Writes the projection p_i(q) (`num_rows()` rows) into `out`.
    fn project(&self, q: &[DVec3], out: &mut [DVec3]);
    /// How far `p` (`num_rows()` rows, as [`Constraint::project`] writes them) is from the
    /// constraint set, in the rows' units: 0 on the set. The shared test suite checks every
    /// projection with it (`tests/catalogue.rs`).
    fn set_residual(&self, p: &[DVec3]) -> f64;
    /// The error a report gives for `C q` (`num_rows()` rows), in the rows' units: by default
    /// [`Constraint::set_residual`]; a type whose field measures its error otherwise (plane:
    /// the largest distance of a corner from the best-fit plane) says so here.
    fn violation(&self, cq: &[DVec3]) -> f64 {
        self.set_residual(cq)
    }

    /// `C_i q`, computed from [`Constraint::rows`] (for tests and diagnostics, not the solver's
    /// hot path, which uses the assembled matrix).
    fn apply(&self, q: &[DVec3]) -> Vec<DVec3> {
        let mut sink = RowSink::default();
        self.rows(&mut sink);
        let mut cq = vec![DVec3::ZERO; self.num_rows()];
        for e in &sink.entries {
            cq[e.row as usize] += e.coeff * q[e.vertex as usize];
        }
        cq
    }

    /// The term's energy without the group multiplier: ω ‖C q − p(q)‖².
    fn energy(&self, q: &[DVec3]) -> f64 {
        let cq = self.apply(q);
        let mut p = vec![DVec3::ZERO; self.num_rows()];
        self.project(q, &mut p);
        self.element_weight() * cq.iter().zip(&p).map(|(a, b)| (*a - *b).length_squared()).sum::<f64>()
    }
}

/// Which vertices (or polygon faces) a constraint group applies to.
///
/// Per-vertex and vertex-set constraints take the chosen vertices; edge, face, triangle and
/// tetrahedron constraints take the elements all of whose vertices are chosen, and face
/// constraints the chosen faces of a face selection ([`Element`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Selection {
    /// Every vertex and face.
    All,
    /// `chosen[i]` for each vertex i.
    Vertices(Vec<bool>),
    /// Polygon faces by index (into the input's faces), and the vertices they use.
    Faces {
        /// `faces[f]`: face f is chosen.
        faces: Vec<bool>,
        /// `vertices[i]`: vertex i is a corner of a chosen face.
        vertices: Vec<bool>,
    },
}

impl Selection {
    /// A selection of the listed vertex indices out of `n` (indices must be `< n`).
    pub fn from_indices(n: usize, indices: &[usize]) -> Self {
        let mut chosen = vec![false; n];
        for &i in indices {
            if let Some(c) = chosen.get_mut(i) {
                *c = true;
            }
        }
        Selection::Vertices(chosen)
    }

    /// A selection of the listed faces of `faces` and their corners (indices must be
    /// `< faces.len()`; others are ignored), over `n` vertices.
    pub fn from_faces(n: usize, faces: &crate::mesh::Polygons, indices: &[usize]) -> Self {
        let mut chosen = vec![false; faces.len()];
        let mut vertices = vec![false; n];
        for &f in indices {
            if let (Some(c), Some(corners)) = (chosen.get_mut(f), faces.get(f)) {
                *c = true;
                for &v in corners {
                    if let Some(x) = vertices.get_mut(v as usize) {
                        *x = true;
                    }
                }
            }
        }
        Selection::Faces { faces: chosen, vertices }
    }

    /// Whether vertex `v` is chosen (a corner of a chosen face, for a face selection).
    pub fn contains(&self, v: u32) -> bool {
        match self {
            Selection::All => true,
            Selection::Vertices(chosen) | Selection::Faces { vertices: chosen, .. } => {
                chosen.get(v as usize).copied().unwrap_or(false)
            }
        }
    }

    /// Whether polygon face `f` with these corners is chosen: every face for
    /// [`Selection::All`], a face whose corners are all chosen for a vertex selection, a listed
    /// face for a face selection.
    pub fn contains_face(&self, f: usize, corners: &[u32]) -> bool {
        match self {
            Selection::Faces { faces, .. } => faces.get(f).copied().unwrap_or(false),
            _ => self.contains_all(corners),
        }
    }

    /// The chosen vertices in ascending order, out of `n`.
    pub fn vertex_list(&self, n: usize) -> Vec<u32> {
        (0..n as u32).filter(|&v| self.contains(v)).collect()
    }

    /// Whether every vertex of an element is chosen.
    pub fn contains_all(&self, element: &[u32]) -> bool {
        element.iter().all(|&v| self.contains(v))
    }
}

/// What a [`ConstraintType`] needs to build constraints.
#[derive(Debug, Clone, Copy)]
pub struct BuildContext<'a> {
    /// Rest shape (working frame) with its topology and rest quantities.
    pub rest: &'a RestGeometry,
    /// The vertices the group applies to.
    pub selection: &'a Selection,
    /// The working frame, to convert options given in input units (e.g. a floor height).
    pub frame: &'a WorkingFrame,
}

/// "an" before a vowel ("an edge_spring", "an iso_one_ring"), else "a".
fn indefinite_article(word: &str) -> &'static str {
    if word.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" }
}

/// An error building constraints from a scene entry or the editor.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstraintError {
    /// No constraint type has this name.
    #[error("unknown constraint type \"{}\" (known: {known})", crate::io::one_line(.0), known = type_names().join(", "))]
    UnknownType(String),
    /// An option that this constraint type does not take.
    #[error("unknown key \"{}\" for {article} {kind} constraint{hint}", crate::io::one_line(key), article = indefinite_article(kind), hint = hint_for(&allowed_hint(allowed)))]
    UnknownOption {
        /// Constraint type.
        kind: &'static str,
        /// The key as written.
        key: String,
        /// The keys it does take.
        allowed: &'static [OptionSpec],
    },
    /// An option with a value of the wrong type or out of range.
    #[error("{kind} option \"{}\": {}", crate::io::one_line(key), crate::io::one_line(problem))]
    BadOption {
        /// Constraint type.
        kind: &'static str,
        /// The key.
        key: String,
        /// What is wrong, and what is expected.
        problem: String,
    },
    /// The selection contains no element this type can constrain.
    #[error("the {kind} group selects no {element} (check its vertices, box or sphere)")]
    NothingSelected {
        /// Constraint type.
        kind: &'static str,
        /// "vertices", "edges", "triangles", …
        element: &'static str,
    },
    /// A group that cannot be built as described (too few vertices, no face of the needed
    /// size, targets that do not match…).
    #[error("{kind}: {problem}")]
    Invalid {
        /// Constraint type.
        kind: &'static str,
        /// What is wrong.
        problem: String,
    },
}

fn allowed_hint(allowed: &[OptionSpec]) -> String {
    allowed.iter().map(|o| o.key).collect::<Vec<_>>().join(", ")
}

/// A range bound for messages: π for 3.14159…, else the number.
fn fmt_bound(x: f64) -> String {
    if x == std::f64::consts::PI {
        "π".into()
    } else if x == f64::MAX {
        "∞".into()
    } else {
        format!("{x}")
    }
}

fn hint_for(list: &str) -> String {
    if list.is_empty() { " (it takes no options)".into() } else { format!(" (allowed: {list})") }
}

/// Type-specific options of a constraint group (e.g. `strain_freedom`), taken one by one by the
/// builder; whatever is left is reported as an unknown key.
#[derive(Debug, Clone, Default)]
pub struct Params {
    map: serde_json::Map<String, serde_json::Value>,
}

impl Params {
    /// Options from a JSON object (scene entries are converted to JSON values first).
    pub fn new(map: serde_json::Map<String, serde_json::Value>) -> Self {
        Params { map }
    }

    /// Sets an option (used by the editor and tests).
    pub fn with(mut self, key: &str, value: impl Into<serde_json::Value>) -> Self {
        self.map.insert(key.to_string(), value.into());
        self
    }

    /// Takes a boolean option, or `default` when absent.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] if the value is not a boolean.
    pub fn take_bool(&mut self, kind: &'static str, key: &str, default: bool) -> Result<bool, ConstraintError> {
        match self.map.remove(key) {
            None => Ok(default),
            Some(v) => v.as_bool().ok_or_else(|| ConstraintError::BadOption {
                kind,
                key: key.into(),
                problem: format!("expected true or false, found {v}"),
            }),
        }
    }

    /// Takes a number option as `spec` describes it: its default when absent (`None` for a
    /// default from the rest shape), else a finite number within its range.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key, for a value that is not a number or is
    /// out of range.
    pub fn number(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<Option<f64>, ConstraintError> {
        let OptionKind::Number { default, min, max } = spec.kind else {
            return Err(ConstraintError::BadOption {
                kind,
                key: spec.key.into(),
                problem: "is not a number option".into(),
            });
        };
        let bad = |problem: String| ConstraintError::BadOption { kind, key: spec.key.into(), problem };
        match self.map.remove(spec.key) {
            None => Ok(default),
            Some(v) => {
                let x =
                    v.as_f64().filter(|x| x.is_finite()).ok_or_else(|| bad(format!("expected a number, found {v}")))?;
                if (min..=max).contains(&x) {
                    Ok(Some(x))
                } else {
                    Err(bad(format!("must be in [{}, {}], found {x}", fmt_bound(min), fmt_bound(max))))
                }
            }
        }
    }

    /// Takes a boolean option as `spec` describes it.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key.
    pub fn flag(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<bool, ConstraintError> {
        let default = match spec.kind {
            OptionKind::Bool { default } => default,
            _ => false,
        };
        self.take_bool(kind, spec.key, default)
    }

    /// Takes a vector option `[x, y, z]` as `spec` describes it.
    ///
    /// # Errors
    /// [`ConstraintError::BadOption`] naming the key, for anything but three finite numbers.
    pub fn vector(&mut self, kind: &'static str, spec: &OptionSpec) -> Result<DVec3, ConstraintError> {
        let default = match spec.kind {
            OptionKind::Vector { default } => default,
            _ => [0.0; 3],
        };
        match self.map.remove(spec.key) {
            None => Ok(DVec3::from(default)),
            Some(v) => serde_json::from_value::<[f64; 3]>(v.clone())
                .ok()
                .filter(|a| a.iter().all(|x| x.is_finite()))
                .map(DVec3::from)
                .ok_or_else(|| ConstraintError::BadOption {
                    kind,
                    key: spec.key.into(),
                    problem: format!("expected three finite numbers [x, y, z], found {v}"),
                }),
        }
    }

    /// Fails on the first option nobody took.
    ///
    /// # Errors
    /// [`ConstraintError::UnknownOption`] naming the key.
    pub fn finish(self, kind: &'static str, allowed: &'static [OptionSpec]) -> Result<(), ConstraintError> {
        match self.map.into_iter().next() {
            None => Ok(()),
            Some((key, _)) => Err(ConstraintError::UnknownOption { kind, key, allowed }),
        }
    }

    /// Whether no option is left.
    pub fn is_empty(&self) -> bool {
        self.map.is_empty()
    }
}

/// A kind of constraint as users see it: a name, a default multiplier, and how to build its
/// constraints on a selection.
pub trait ConstraintType: Sync {
    /// Name used in scene files and the editor (`"edge_spring"`).
    fn name(&self) -> &'static str;
    /// One line for menus and `--help`.
    fn summary(&self) -> &'static str;
    /// The options [`ConstraintType::build`] takes (besides the common ones: selection,
    /// weight, name, hard, targets), with their ranges and defaults.
    fn options(&self) -> &'static [OptionSpec];
    /// The elements it builds constraints on.
    fn element(&self) -> Element;
    /// Whether its constraints have targets a scene or the editor moves
    /// ([`Constraint::set_targets`]): the group takes `translate`, `rotate`, `targets` and
    /// `spin`, and the editor treats it as a handle. Default `false`.
    fn has_targets(&self) -> bool {
        false
    }
    /// Whether moving the input rigidly (and turning its vector options with it) moves the
    /// result the same way; `false` only for types tied to the world frame (a floor at y = h).
    /// The shared tests check it. Default `true`.
    fn is_rigidly_invariant(&self) -> bool {
        true
    }
    /// The editor's default group multiplier g (math reference, "Notes").
    fn default_multiplier(&self) -> f64;
    /// Builds this type's constraints on `ctx.selection`, taking its options from `params`.
    ///
    /// # Errors
    /// [`ConstraintError`] for a bad option or a selection with nothing to constrain.
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError>;
}

/// Every constraint type, in the order menus list them.
pub fn registry() -> &'static [&'static dyn ConstraintType] {
    &[
        // Shape models (keep lengths, strains, curvature, details).
        &EdgeSpringType,
        &EdgeStrainType,
        &TriangleStrainType,
        &AreaType,
        &TetStrainType,
        &VolumeType,
        &BendingType,
        &HingeBendingType,
        &IsoOneRingType,
        &LaplacianDisplacementType,
        &SmoothingType,
        &LaplacianType,
        // Geometric sets of ShapeUp / ShapeOp (faces, parts).
        &PlaneType,
        &CircleType,
        &SphereType,
        &LineType,
        &RectangleType,
        &ParallelogramType,
        &AngleType,
        &RigidType,
        &SimilarityType,
        // Handles, contact and loads.
        &PositionType,
        &SurfaceClosenessType,
        &FloorType,
        &ForceType,
        &GravityType,
    ]
}

/// Whether `selection` picks at least one element of this kind on `rest` (for menus: the
/// editor offers a type only when it fits the selection).
pub fn selects_any(element: Element, rest: &RestGeometry, selection: &Selection) -> bool {
    let n = rest.num_vertices() as u32;
    match element {
        Element::Vertex => (0..n).any(|v| selection.contains(v)),
        Element::VertexSet { min } => (0..n).filter(|&v| selection.contains(v)).take(min).count() >= min.max(1),
        Element::Edge => rest.topology.edges.iter().any(|e| selection.contains_all(&e[..])),
        Element::Face { min, max } => rest
            .faces
            .iter()
            .enumerate()
            .any(|(f, corners)| (min..=max).contains(&corners.len()) && selection.contains_face(f, corners)),
        Element::Triangle => rest.triangles.iter().any(|t| selection.contains_all(&t[..])),
        Element::Tetrahedron => rest.tetrahedra.iter().any(|t| selection.contains_all(&t[..])),
    }
}

/// The registry as a Markdown table (type, elements, default weight, options, summary): what
/// `shapeup types` prints and the README and the scene contract show (a test keeps them equal).
pub fn catalogue_markdown() -> String {
    let mut out = String::from(
        "| type | acts on | default weight | options (default, range) | what it does |\n|---|---|---:|---|---|\n",
    );
    for ty in registry() {
        let options: Vec<String> = ty.options().iter().map(option_markdown).collect();
        let mut options = if options.is_empty() { "—".to_string() } else { options.join("; ") };
        if ty.has_targets() {
            options.push_str("; targets: translate, rotate, targets, spin, hard");
        }
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            ty.name(),
            ty.element().plural(),
            ty.default_multiplier(),
            options,
            ty.summary().replace('|', "\\|")
        ));
    }
    out
}

/// One option as [`catalogue_markdown`] lists it: `key = default` and its range.
pub fn option_markdown(o: &OptionSpec) -> String {
    match o.kind {
        OptionKind::Number { default, min, max } => {
            let d = default.map_or("rest".to_string(), |d| format!("{d}"));
            let range = match (min > -f64::MAX, max < f64::MAX) {
                (true, true) => format!(" in [{}, {}]", fmt_bound(min), fmt_bound(max)),
                (true, false) => format!(" ≥ {}", fmt_bound(min)),
                (false, true) => format!(" ≤ {}", fmt_bound(max)),
                (false, false) => String::new(),
            };
            format!("`{}` = {d}{range}", o.key)
        }
        OptionKind::Bool { default } => format!("`{}` = {default}", o.key),
        OptionKind::Vector { default } => format!("`{}` = [{}, {}, {}]", o.key, default[0], default[1], default[2]),
    }
}

/// The names of every constraint type.
pub fn type_names() -> Vec<&'static str> {
    registry().iter().map(|t| t.name()).collect()
}

/// Looks a constraint type up by name.
///
/// # Errors
/// [`ConstraintError::UnknownType`] listing the known names.
pub fn constraint_type(name: &str) -> Result<&'static dyn ConstraintType, ConstraintError> {
    registry().iter().copied().find(|t| t.name() == name).ok_or_else(|| ConstraintError::UnknownType(name.to_string()))
}

/// Builds the constraints of a type on a selection: looks up `kind`, passes `params` and rejects
/// options it did not take.
///
/// # Errors
/// As [`constraint_type`] and [`ConstraintType::build`], and an unknown option.
pub fn build_constraints(
    kind: &str,
    ctx: &BuildContext,
    mut params: Params,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let ty = constraint_type(kind)?;
    let built = ty.build(ctx, &mut params)?;
    params.finish(ty.name(), ty.options())?;
    Ok(built)
}

/// Fails with [`ConstraintError::NothingSelected`] when a builder produced nothing.
/// One constraint per selected vertex, in index order, as `make(i)` builds it (`None`: vertex i
/// gets none), or [`ConstraintError::NothingSelected`] naming `element` when none is built: the
/// build of every per-vertex type.
pub(crate) fn per_selected_vertex<C: Constraint>(
    ctx: &BuildContext,
    kind: &'static str,
    element: &'static str,
    make: impl FnMut(usize) -> Option<C>,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let built = (0..ctx.rest.num_vertices())
        .filter(|&i| ctx.selection.contains(i as u32))
        .filter_map(make)
        .map(|c| Box::new(c) as Box<dyn Constraint>)
        .collect();
    non_empty(built, kind, element)
}

pub(crate) fn non_empty(
    built: Vec<Box<dyn Constraint>>,
    kind: &'static str,
    element: &'static str,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    if built.is_empty() { Err(ConstraintError::NothingSelected { kind, element }) } else { Ok(built) }
}

#[cfg(test)]
pub(crate) mod test_util {
    //! Shared helpers for projection tests.
    use super::*;

    /// `‖a − b‖_F²` of two row lists.
    pub fn dist2(a: &[DVec3], b: &[DVec3]) -> f64 {
        a.iter().zip(b).map(|(x, y)| (*x - *y).length_squared()).sum()
    }

    /// A small deterministic pseudo-random generator (xorshift), so tests need no extra crate.
    pub struct Rng(pub u64);
    impl Rng {
        /// Uniform in [-1, 1).
        pub fn uniform(&mut self) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        }
        /// A vector with entries uniform in [-1, 1).
        pub fn vec3(&mut self) -> DVec3 {
            DVec3::new(self.uniform(), self.uniform(), self.uniform())
        }
    }
}
