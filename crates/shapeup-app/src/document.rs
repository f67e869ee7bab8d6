//! The editor's model: a mesh, its constraint groups, the selection, the current shape and the
//! undo history, with no GUI.
//!
//! - [`EditState`] is what undo snapshots: the rest shape (shared, cheap to clone), the groups
//!   (shape model, handles with their targets, smoothing, others from a scene) and the
//!   iteration count. It is also what the [`worker`](crate::worker) receives to solve.
//! - [`Solver`] turns an `EditState` into a `shapeup-core` [`System`] and keeps the working
//!   positions: a structural change rebuilds the system, a handle move only sets targets
//!   ([`System::set_targets`], no refactorization), a weight change only refactors.
//! - [`Document`] ties them together with the selection and the current positions, and applies
//!   [`Command`]s.
//!
//! Handle targets and positions are in the mesh's input frame; the solver works in the
//! normalized working frame, as `shapeup deform` does, so a saved scene reproduces the
//! editor's solve.

use crate::command::{Command, SelectMode};
use glam::{DQuat, DVec3};
use shapeup_core::constraints::{
    ConstraintType, GroupDescription, Params, Selection, build_group as build_described, constraint_type, registry,
    selects_any,
};
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::io::{Attributes, read_mesh};
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{GroupSpec, MeshSettings, Scene, SelectionSpec, SolverSettings, Targets};
use shapeup_core::solver::{Acceleration, ConstraintGroup, GroupId, SolveError, SolveReport, SolverParams, System};
use std::fmt;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The range of group weights (the weight sliders are logarithmic over it).
pub const WEIGHT_RANGE: (f64, f64) = (1e-4, 1e4);

/// Undo steps kept; older ones are dropped.
pub const UNDO_LIMIT: usize = 200;

/// The editor's default convergence tolerance on the relative energy change of an iteration,
/// used when a scene sets none (`tolerance = 0`).
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// The editor's default cap on the iterations of one convergence, used when a scene sets no
/// tolerance (its `iterations` were then a fixed count, not a cap).
pub const DEFAULT_MAX_ITERATIONS: usize = 10_000;

/// The multiplier of the soft handle [`Command::PinFreePieces`] makes: enough to make the
/// system non-singular, small enough not to fight the shape model.
pub const FREE_PIECE_WEIGHT: f64 = 1e-2;

/// A group's identity in a [`Document`]: stable while the group exists, never reused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GroupKey(pub u32);

impl fmt::Display for GroupKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "#{}", self.0)
    }
}

/// The constraints that keep the shape, over the whole mesh (math reference, "Notes": the
/// editor's default multipliers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, serde::Serialize, serde::Deserialize)]
pub enum ShapeModel {
    /// Edge springs, g = 10.
    EdgeSprings,
    /// Triangle strain (g = 10) and bending (g = 10).
    #[default]
    StrainBending,
    /// Isometric one-rings, g = 100.
    IsoOneRing,
}

impl ShapeModel {
    /// Every model, in menu order.
    pub const ALL: [ShapeModel; 3] = [ShapeModel::EdgeSprings, ShapeModel::StrainBending, ShapeModel::IsoOneRing];

    /// Its groups: (constraint type, default multiplier g).
    pub fn groups(self) -> &'static [(&'static str, f64)] {
        match self {
            ShapeModel::EdgeSprings => &[("edge_spring", 10.0)],
            ShapeModel::StrainBending => &[("triangle_strain", 10.0), ("bending", 10.0)],
            ShapeModel::IsoOneRing => &[("iso_one_ring", 100.0)],
        }
    }

    /// Name for menus.
    pub fn label(self) -> &'static str {
        match self {
            ShapeModel::EdgeSprings => "Edge springs",
            ShapeModel::StrainBending => "Strain + bending",
            ShapeModel::IsoOneRing => "Iso 1-ring",
        }
    }

    /// The model whose groups have exactly these types (in any order), if any.
    fn from_kinds(kinds: &[&str]) -> Option<ShapeModel> {
        let mut kinds = kinds.to_vec();
        kinds.sort_unstable();
        ShapeModel::ALL.into_iter().find(|m| {
            let mut own: Vec<&str> = m.groups().iter().map(|(k, _)| *k).collect();
            own.sort_unstable();
            own == kinds
        })
    }
}

/// What a group is for in the editor.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GroupRole {
    /// Part of the shape model (over all vertices).
    Shape,
    /// A handle: a position group with targets the user drags.
    Handle,
    /// Smoothing on a selection.
    Smoothing,
    /// Any other group read from a scene (floor, strain on a part, options…), kept as is.
    Other,
}

/// A constraint group as the editor lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct Group {
    /// Stable identity.
    pub key: GroupKey,
    /// Display name.
    pub name: String,
    /// What it is for.
    pub role: GroupRole,
    /// Constraint type name (`"position"`, `"bending"`, …).
    pub kind: String,
    /// Multiplier g.
    pub weight: f64,
    /// The vertices it applies to (ascending); `None` = all (or the faces', when `faces` is
    /// set).
    pub vertices: Option<Vec<u32>>,
    /// The polygon faces it applies to (ascending), for a group made on a face selection.
    pub faces: Option<Vec<u32>>,
    /// Handles: one target per vertex of `vertices`, in its order (input frame); empty
    /// otherwise.
    pub targets: Vec<DVec3>,
    /// Type options (as a scene writes them, `hard` included), shared between undo steps.
    pub options: Arc<serde_json::Map<String, serde_json::Value>>,
}

impl Group {
    /// Whether it applies to vertex `v` (for hover highlighting).
    pub fn covers(&self, v: u32) -> bool {
        self.vertices.as_ref().is_none_or(|list| list.contains(&v))
    }

    /// Its vertices, `None` meaning every vertex.
    pub fn vertices(&self) -> Option<&[u32]> {
        self.vertices.as_deref()
    }

    /// Centroid of a handle's targets (input frame); `None` for other groups.
    pub fn target_centroid(&self) -> Option<DVec3> {
        (!self.targets.is_empty()).then(|| self.targets.iter().copied().sum::<DVec3>() / self.targets.len() as f64)
    }

    /// What the system needs to rebuild when this changes (everything but name, weight and
    /// targets).
    fn structure(&self) -> Structure {
        (self.key, self.kind.clone(), self.vertices.clone(), self.faces.clone(), Arc::clone(&self.options))
    }
}

/// What a rebuild of a group depends on: (key, kind, vertices, faces, options).
type Structure =
    (GroupKey, String, Option<Vec<u32>>, Option<Vec<u32>>, Arc<serde_json::Map<String, serde_json::Value>>);

/// The rest shape: the mesh in its input frame and its rest geometry in the working frame.
#[derive(Debug)]
pub struct Rest {
    /// Rest mesh, input frame.
    pub mesh: Mesh,
    /// Input ↔ working frame.
    pub frame: WorkingFrame,
    /// Whether the frame was fitted (`[mesh] normalize`).
    pub normalize: bool,
    /// Rest geometry (working frame).
    pub geometry: RestGeometry,
}

impl Rest {
    /// The rest state of a mesh, in the normalized frame when `normalize` (as a scene loads it).
    pub fn new(mesh: Mesh, normalize: bool) -> Self {
        let frame = if normalize { WorkingFrame::fit(&mesh.positions) } else { WorkingFrame::IDENTITY };
        let working = mesh.positions.iter().map(|&p| frame.to_working(p)).collect();
        let geometry = RestGeometry::of_mesh(working, &mesh);
        Rest { mesh, frame, normalize, geometry }
    }
}

/// The editable state that undo snapshots and the worker solves: cheap to clone (the rest shape
/// is shared).
#[derive(Debug, Clone)]
pub struct EditState {
    /// The rest shape.
    pub rest: Arc<Rest>,
    /// The shape model, `None` when the shape groups came from a scene that matches no model.
    pub shape_model: Option<ShapeModel>,
    /// Every group, in system (and scene) order.
    pub groups: Vec<Group>,
    /// The most local-global iterations one convergence runs after a change (the scene's
    /// `[solver] iterations`).
    pub iterations: usize,
    /// Convergence stops when the relative energy change of an iteration is at most this
    /// (the scene's `[solver] tolerance`).
    pub tolerance: f64,
    /// How iterates are combined (the scene's `[solver] acceleration`).
    pub acceleration: Acceleration,
    /// Iterations Anderson acceleration mixes (the scene's `[solver] anderson_window`).
    pub anderson_window: usize,
    /// Pairs L-BFGS keeps (the scene's `[solver] lbfgs_memory`).
    pub lbfgs_memory: usize,
}

impl PartialEq for EditState {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.rest, &other.rest)
            && self.shape_model == other.shape_model
            && self.groups == other.groups
            && self.iterations == other.iterations
            && self.tolerance.to_bits() == other.tolerance.to_bits()
            && self.acceleration == other.acceleration
            && self.anderson_window == other.anderson_window
            && self.lbfgs_memory == other.lbfgs_memory
    }
}

impl EditState {
    /// The group with this key.
    pub fn group(&self, key: GroupKey) -> Option<&Group> {
        self.groups.iter().find(|g| g.key == key)
    }

    fn group_mut(&mut self, key: GroupKey) -> Result<&mut Group, EditorError> {
        self.groups.iter_mut().find(|g| g.key == key).ok_or(EditorError::UnknownGroup(key))
    }

    fn handle_mut(&mut self, key: GroupKey) -> Result<&mut Group, EditorError> {
        let group = self.group_mut(key)?;
        if group.role == GroupRole::Handle { Ok(group) } else { Err(EditorError::NotAHandle(key)) }
    }

    /// Whether some handle exists (without one a solve has nothing to do).
    pub fn has_handles(&self) -> bool {
        self.groups.iter().any(|g| g.role == GroupRole::Handle)
    }
}

/// What [`Document::save_scene_with_mesh`] wrote besides the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedScene {
    /// The rest mesh written beside the scene, if the rest shape had to be saved.
    pub rest_mesh: Option<PathBuf>,
    /// What the rest mesh's format could not keep, said once each.
    pub warnings: Vec<String>,
}

/// An editor error: one line, meant for the status bar.
#[derive(Debug, Clone, PartialEq)]
pub enum EditorError {
    /// Solving needs at least one handle.
    NoHandles,
    /// The command works on the selection, which is empty.
    EmptySelection,
    /// No group has this key.
    UnknownGroup(GroupKey),
    /// The group is not a handle.
    NotAHandle(GroupKey),
    /// Shape-model groups are replaced with [`Command::SetShapeModel`], not removed.
    ShapeGroup(GroupKey),
    /// A NaN weight.
    BadWeight(f64),
    /// A non-finite or degenerate value (translation, axis, angle, iteration count).
    BadValue(String),
    /// A mesh or scene that cannot be read or used.
    Load(String),
    /// A file that cannot be written.
    Save(String),
    /// A group cannot be built (e.g. smoothing on a selection with no interior vertex).
    Constraint(String),
    /// The solver failed.
    Solve(SolveError),
    /// Dynamic mode could not start or failed.
    Simulation(String),
}

impl fmt::Display for EditorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EditorError::NoHandles => write!(f, "nothing to solve: select vertices and fix them as a handle first"),
            EditorError::EmptySelection => write!(f, "the selection is empty: select vertices first"),
            EditorError::UnknownGroup(k) => write!(f, "no group {k} (it was removed)"),
            EditorError::NotAHandle(k) => write!(f, "group {k} is not a handle"),
            EditorError::ShapeGroup(k) => {
                write!(f, "group {k} belongs to the shape model; choose another model instead of removing it")
            }
            EditorError::BadWeight(w) => write!(f, "weight must be a number, found {w}"),
            EditorError::BadValue(m) | EditorError::Load(m) | EditorError::Save(m) | EditorError::Constraint(m) => {
                write!(f, "{m}")
            }
            EditorError::Solve(e) => write!(f, "{e}"),
            EditorError::Simulation(e) => write!(f, "simulation: {e}"),
        }
    }
}

impl std::error::Error for EditorError {}

impl From<SolveError> for EditorError {
    fn from(e: SolveError) -> Self {
        EditorError::Solve(e)
    }
}

/// Builds a group's constraints on the rest shape, through the library's one route.
fn build_group(rest: &Rest, group: &Group) -> Result<ConstraintGroup, EditorError> {
    let n = rest.mesh.num_vertices();
    let selection = match (&group.faces, &group.vertices) {
        (Some(faces), _) => {
            Selection::from_faces(n, &rest.geometry.faces, &faces.iter().map(|&f| f as usize).collect::<Vec<_>>())
        }
        (None, None) => Selection::All,
        (None, Some(list)) => Selection::from_indices(n, &list.iter().map(|&v| v as usize).collect::<Vec<_>>()),
    };
    let targets = (group.role == GroupRole::Handle).then(|| {
        let vertices = group.vertices.clone().unwrap_or_else(|| (0..n as u32).collect());
        vertices.into_iter().zip(&group.targets).map(|(v, &t)| (v, rest.frame.to_working(t))).collect()
    });
    let description = GroupDescription {
        kind: group.kind.clone(),
        name: group.name.clone(),
        weight: Some(group.weight),
        selection,
        options: Params::new((*group.options).clone()),
        targets,
    };
    build_described(&description, &rest.geometry, &rest.frame)
        .map_err(|e| EditorError::Constraint(format!("group \"{}\": {e}", group.name)))
}

/// The solve state of an [`EditState`]: its [`System`] and the working positions.
#[derive(Debug, Default)]
pub struct Solver {
    rest: Option<Arc<Rest>>,
    /// What each group the system was built from depends on.
    structure: Vec<Structure>,
    system: Option<System>,
    ids: Vec<GroupId>,
    /// Current positions, working frame.
    q: Vec<DVec3>,
}

impl Solver {
    /// A solver with nothing built; the first [`Solver::sync`] builds the system and starts
    /// from the rest shape.
    pub fn new() -> Self {
        Solver::default()
    }

    /// Brings the system up to date with `state`: rebuilds it when the rest shape or the set of
    /// groups changed (the positions are carried over through the frames), else only sets the
    /// handles' targets and the weights. On error nothing changes.
    ///
    /// # Errors
    /// [`EditorError::Constraint`] when a group cannot be built.
    pub fn sync(&mut self, state: &EditState) -> Result<(), EditorError> {
        let same_rest = self.rest.as_ref().is_some_and(|r| Arc::ptr_eq(r, &state.rest));
        let same_groups = self.structure.len() == state.groups.len()
            && self.structure.iter().zip(&state.groups).all(|(s, g)| *s == g.structure());
        let params = SolverParams {
            iterations: state.iterations,
            acceleration: state.acceleration,
            anderson_window: state.anderson_window,
            lbfgs_memory: state.lbfgs_memory,
            ..SolverParams::default()
        };
        match self.system.as_mut() {
            Some(system) if same_rest && same_groups => {
                if *system.params() != params {
                    system.set_params(params);
                }
                for (group, &id) in state.groups.iter().zip(&self.ids) {
                    if group.role == GroupRole::Handle {
                        let working: Vec<DVec3> =
                            group.targets.iter().map(|&t| state.rest.frame.to_working(t)).collect();
                        system.set_targets(id, &working)?;
                    }
                    system.set_multiplier(id, group.weight)?;
                }
            }
            _ => {
                let rest = &state.rest;
                let mut system = System::new(rest.mesh.num_vertices(), params);
                let mut ids = Vec::with_capacity(state.groups.len());
                for group in &state.groups {
                    ids.push(system.add_group(build_group(rest, group)?)?);
                }
                // Vertices that only zero-area triangles use follow their edge, as in a scene.
                let (group, _, _) = shapeup_core::constraints::attach_degenerate_vertices(
                    &rest.geometry,
                    system.groups().map(|(_, g)| g),
                );
                if let Some(group) = group {
                    system.add_group(group)?;
                }
                self.q = match &self.rest {
                    // Same positions in the input frame, seen in the new working frame.
                    Some(old) if !same_rest && self.q.len() == rest.mesh.num_vertices() => {
                        self.q.iter().map(|&p| rest.frame.to_working(old.frame.to_input(p))).collect()
                    }
                    Some(_) if same_rest => std::mem::take(&mut self.q),
                    _ => rest.geometry.positions.clone(),
                };
                self.structure = state.groups.iter().map(Group::structure).collect();
                self.system = Some(system);
                self.ids = ids;
                self.rest = Some(Arc::clone(rest));
            }
        }
        Ok(())
    }

    /// Sets the current positions (input frame), e.g. back to the rest shape. Ignored before
    /// the first [`Solver::sync`] or with the wrong length.
    pub fn set_positions(&mut self, positions: &[DVec3]) {
        if let Some(rest) = &self.rest
            && positions.len() == rest.mesh.num_vertices()
        {
            self.q = positions.iter().map(|&p| rest.frame.to_working(p)).collect();
        }
    }

    /// Runs `iterations` local-global iterations from the current positions.
    ///
    /// # Errors
    /// [`EditorError::NoHandles`] before any sync, [`EditorError::Solve`] for a singular system.
    pub fn solve(&mut self, iterations: usize) -> Result<SolveReport, EditorError> {
        self.solve_to(iterations, 0.0)
    }

    /// Runs at most `iterations` local-global iterations from the current positions, stopping
    /// after the first whose relative energy change is at most `tolerance` (> 0).
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_to(&mut self, iterations: usize, tolerance: f64) -> Result<SolveReport, EditorError> {
        self.solve_until(iterations, tolerance, || false)
    }

    /// [`Solver::solve_to`] that also stops after any iteration for which `interrupted()` is
    /// true (a newer request in the background worker); at least one iteration runs.
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn solve_until(
        &mut self,
        iterations: usize,
        tolerance: f64,
        interrupted: impl Fn() -> bool,
    ) -> Result<SolveReport, EditorError> {
        let system = self.system.as_mut().ok_or(EditorError::NoHandles)?;
        Ok(system.solve_with(&mut self.q, iterations, tolerance, |_, _| {
            if interrupted() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        })?)
    }

    /// The current positions in the input frame; vertices no constraint touches keep their rest
    /// positions bit for bit (as `shapeup deform` writes them).
    pub fn positions(&self) -> Vec<DVec3> {
        let (Some(rest), Some(system)) = (&self.rest, &self.system) else { return Vec::new() };
        self.q
            .iter()
            .zip(&rest.mesh.positions)
            .enumerate()
            .map(|(v, (&p, &input))| if system.is_solved(v) { rest.frame.to_input(p) } else { input })
            .collect()
    }

    /// E of the current positions, per group (in the order of the synced state's groups).
    ///
    /// # Errors
    /// [`EditorError::Solve`] (e.g. no constraints).
    pub fn energy(&mut self) -> Result<Vec<f64>, EditorError> {
        let system = self.system.as_mut().ok_or(EditorError::NoHandles)?;
        let energy = system.energy(&self.q)?;
        Ok(self.ids.iter().map(|id| energy.per_group.iter().find(|(g, _)| g == id).map_or(0.0, |(_, e)| *e)).collect())
    }
}

/// One undo step: the edit state and the shape on screen before the change, so that undo
/// brings back what was seen (also after Reset shape, Make rest shape or a dynamics run).
#[derive(Debug, Clone)]
struct Snapshot {
    state: EditState,
    positions: Arc<Vec<DVec3>>,
}

/// The connected pieces of a mesh: vertices joined by triangle edges (a vertex no triangle
/// uses is a piece of its own, but is never solved and so never counted as free).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pieces {
    /// Piece of each vertex, numbered 0.. in order of each piece's first vertex.
    pub of_vertex: Vec<u32>,
    /// Number of pieces that have triangles.
    pub count: usize,
    /// Whether each piece has triangles.
    used: Vec<bool>,
}

impl Pieces {
    /// The pieces of `n` vertices joined by `triangles` (union–find over the triangles' edges;
    /// a few lines, not worth a graph crate).
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Pieces {
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        }
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut in_triangle = vec![false; n];
        for t in triangles {
            for &v in t {
                in_triangle[v as usize] = true;
            }
            for (a, b) in [(t[0], t[1]), (t[1], t[2])] {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        let mut label = vec![u32::MAX; n];
        let mut of_vertex = vec![0; n];
        let mut used = Vec::new();
        for v in 0..n {
            let r = root(&mut parent, v as u32) as usize;
            if label[r] == u32::MAX {
                label[r] = used.len() as u32;
                used.push(false);
            }
            of_vertex[v] = label[r];
            used[label[r] as usize] |= in_triangle[v];
        }
        let count = used.iter().filter(|u| **u).count();
        Pieces { of_vertex, count, used }
    }

    /// The vertices of the piece that holds vertex `v`, ascending (empty when out of range).
    pub fn piece_of(&self, v: u32) -> Vec<u32> {
        let Some(&piece) = self.of_vertex.get(v as usize) else { return Vec::new() };
        (0..self.of_vertex.len() as u32).filter(|&u| self.of_vertex[u as usize] == piece).collect()
    }

    /// Pieces with triangles none of whose vertices is in `pinned`.
    pub fn free(&self, pinned: &[bool]) -> Vec<u32> {
        let mut held = vec![false; self.used.len()];
        for (v, &p) in pinned.iter().enumerate() {
            if p && let Some(&piece) = self.of_vertex.get(v) {
                held[piece as usize] = true;
            }
        }
        (0..self.used.len() as u32).filter(|&p| self.used[p as usize] && !held[p as usize]).collect()
    }
}

/// The editor's document: the constraint state with its undo history, the selection and the
/// current shape.
#[derive(Debug)]
pub struct Document {
    state: EditState,
    solver: Solver,
    /// Current positions, input frame.
    positions: Vec<DVec3>,
    /// Bumped whenever the shape is set rather than solved (reset, make rest).
    epoch: u64,
    /// Where the current epoch started (input frame), for the worker.
    epoch_start: Arc<Vec<DVec3>>,
    selection: Vec<bool>,
    /// Selected polygon faces (of the rest mesh's faces), for face constraints.
    face_selection: Vec<bool>,
    undo: Vec<Snapshot>,
    redo: Vec<Snapshot>,
    /// Connected piece of each vertex (vertices no triangle uses: their own piece).
    pieces: Arc<Pieces>,
    /// Changed since opened or last saved.
    modified: bool,
    /// The rest shape as opened: when the state's differs (Make rest shape), saving a scene
    /// writes the rest mesh beside it.
    opened_rest: Arc<Rest>,
    /// The mesh file the document was read from (`None`: made in memory or generated).
    source: Option<PathBuf>,
    /// What that file carried besides positions and faces, written back with the mesh.
    attributes: Attributes,
    /// `Some(recorded)` during a drag: whether its undo step was recorded yet.
    drag: Option<bool>,
    next_key: u32,
    /// The `[solver]` table to save (iterations come from the state).
    solver_settings: SolverSettings,
}

impl Document {
    /// A document on a mesh (input frame, normalized working frame) with a shape model and no
    /// handles.
    ///
    /// # Errors
    /// [`EditorError::Load`] for a mesh without triangles, [`EditorError::Constraint`] if the
    /// model cannot be built on it.
    pub fn new(mesh: Mesh, model: ShapeModel) -> Result<Document, EditorError> {
        if mesh.triangles.is_empty() {
            return Err(EditorError::Load("the mesh has no triangles to deform".into()));
        }
        let rest = Arc::new(Rest::new(mesh, true));
        let mut document = Document::empty(rest, SolverSettings::default());
        document.state.shape_model = Some(model);
        document.state.groups = document.model_groups(model);
        document.solver.sync(&document.state)?;
        Ok(document)
    }

    /// Reads a mesh file and makes a document on it ([`Document::new`]).
    ///
    /// # Errors
    /// [`EditorError::Load`] naming the file, or as [`Document::new`].
    pub fn open(path: &Path, model: ShapeModel) -> Result<Document, EditorError> {
        let loaded = read_mesh(path).map_err(|e| EditorError::Load(e.to_string()))?;
        let mut document = Document::new(loaded.mesh, model)?;
        document.source = Some(path.to_path_buf());
        document.attributes = loaded.attributes;
        Ok(document)
    }

    fn empty(rest: Arc<Rest>, solver_settings: SolverSettings) -> Document {
        let n = rest.mesh.num_vertices();
        let positions = rest.mesh.positions.clone();
        Document {
            state: EditState {
                rest: Arc::clone(&rest),
                shape_model: None,
                groups: Vec::new(),
                // A scene without a tolerance ran a fixed count; the editor converges instead.
                iterations: if solver_settings.tolerance > 0.0 {
                    solver_settings.iterations.saturating_mul(solver_settings.steps).max(1)
                } else {
                    DEFAULT_MAX_ITERATIONS
                },
                tolerance: if solver_settings.tolerance > 0.0 { solver_settings.tolerance } else { DEFAULT_TOLERANCE },
                acceleration: solver_settings.acceleration,
                anderson_window: solver_settings.anderson_window,
                lbfgs_memory: solver_settings.lbfgs_memory,
            },
            solver: Solver::new(),
            epoch_start: Arc::new(positions.clone()),
            positions,
            epoch: 0,
            selection: vec![false; n],
            face_selection: vec![false; rest.geometry.faces.len()],
            undo: Vec::new(),
            redo: Vec::new(),
            pieces: Arc::new(Pieces::new(n, &rest.mesh.triangles)),
            modified: false,
            opened_rest: Arc::clone(&rest),
            source: None,
            attributes: Attributes::None,
            drag: None,
            next_key: 0,
            solver_settings,
        }
    }

    fn new_key(&mut self) -> GroupKey {
        self.next_key += 1;
        GroupKey(self.next_key - 1)
    }

    fn model_groups(&mut self, model: ShapeModel) -> Vec<Group> {
        model
            .groups()
            .iter()
            .map(|&(kind, weight)| Group {
                key: self.new_key(),
                name: kind.to_string(),
                role: GroupRole::Shape,
                kind: kind.to_string(),
                weight,
                vertices: None,
                targets: Vec::new(),
                faces: None,
                options: Arc::default(),
            })
            .collect()
    }

    /// A document from a scene: reads its mesh and takes its groups. Shape types over all
    /// vertices without options become the shape model (when they match one), position groups
    /// become handles (box and sphere selections resolved to vertices, targets made explicit),
    /// smoothing groups stay smoothing, anything else is kept as an "other" group.
    ///
    /// # Errors
    /// [`EditorError::Load`] for an unreadable mesh, a bad selection or target, or a
    /// tetrahedralized scene; [`EditorError::Constraint`] for a group that cannot be built.
    pub fn from_scene(scene: &Scene) -> Result<Document, EditorError> {
        let loaded = scene.read_mesh().map_err(|e| EditorError::Load(e.to_string()))?;
        let mut document = Document::from_scene_with_mesh(scene, loaded.mesh)?;
        document.source = scene.mesh.generate.is_none().then(|| scene.mesh_path());
        document.attributes = loaded.attributes;
        Ok(document)
    }

    /// [`Document::from_scene`] on an already loaded mesh.
    ///
    /// # Errors
    /// As [`Document::from_scene`].
    pub fn from_scene_with_mesh(scene: &Scene, mesh: Mesh) -> Result<Document, EditorError> {
        if scene.mesh.tetrahedralize {
            return Err(EditorError::Load("the editor does not support tetrahedralize = true".into()));
        }
        if mesh.triangles.is_empty() {
            return Err(EditorError::Load("the mesh has no triangles to deform".into()));
        }
        let rest = Arc::new(Rest::new(mesh, scene.mesh.normalize));
        let mut document = Document::empty(Arc::clone(&rest), scene.solver);
        let mut groups = Vec::with_capacity(scene.groups.len());
        for (i, spec) in scene.groups.iter().enumerate() {
            let entry = |m: String| EditorError::Load(format!("constraints[{i}] (\"{}\"): {m}", spec.name));
            let ty = shapeup_core::constraints::constraint_type(&spec.kind).map_err(|e| entry(e.to_string()))?;
            let (faces, picked) = match &spec.selection {
                SelectionSpec::Faces(list) => {
                    let m = rest.geometry.faces.len();
                    if let Some(&f) = list.iter().find(|&&f| f >= m) {
                        return Err(entry(format!("face {f} is out of range (the mesh has {m} faces)")));
                    }
                    let mut list: Vec<u32> = list.iter().map(|&f| f as u32).collect();
                    list.sort_unstable();
                    list.dedup();
                    (Some(list), None)
                }
                other => (None, resolve_selection(other, &rest.mesh).map_err(entry)?),
            };
            let shape_kind = ShapeModel::ALL.iter().any(|m| m.groups().iter().any(|(k, _)| *k == spec.kind));
            let plain = spec.options.is_empty();
            let (role, targets, picked) = if ty.has_targets() {
                let vertices = picked.unwrap_or_else(|| (0..rest.mesh.num_vertices() as u32).collect());
                let targets = position_targets(&vertices, &spec.targets, &rest.mesh).map_err(entry)?;
                // Ascending, as the editor keeps every selection (targets follow their vertex).
                let mut pairs: Vec<(u32, DVec3)> = vertices.into_iter().zip(targets).collect();
                pairs.sort_unstable_by_key(|&(v, _)| v);
                let (vertices, targets) = pairs.into_iter().unzip();
                (GroupRole::Handle, targets, Some(vertices))
            } else if shape_kind && plain && picked.is_none() && faces.is_none() {
                (GroupRole::Shape, Vec::new(), picked)
            } else if spec.kind == "smoothing" && plain {
                (GroupRole::Smoothing, Vec::new(), picked)
            } else {
                (GroupRole::Other, Vec::new(), picked)
            };
            let vertices = picked;
            groups.push(Group {
                key: document.new_key(),
                name: spec.name.clone(),
                role,
                kind: spec.kind.clone(),
                weight: spec.weight,
                vertices,
                targets,
                faces,
                options: Arc::new(spec.options.clone()),
            });
        }
        let kinds: Vec<&str> = groups.iter().filter(|g| g.role == GroupRole::Shape).map(|g| g.kind.as_str()).collect();
        document.state.shape_model = ShapeModel::from_kinds(&kinds);
        document.state.groups = groups;
        document.solver.sync(&document.state)?;
        Ok(document)
    }

    /// The document as a scene whose `[mesh] path` is `mesh_path` (as it should appear in the
    /// file: relative to the scene's directory, or absolute). Handles are written with explicit
    /// targets, editor groups with explicit vertex lists. After [`Command::MakeRest`], save
    /// [`Document::rest_mesh`] to that path too.
    pub fn to_scene(&self, mesh_path: impl Into<PathBuf>) -> Scene {
        let groups = self
            .state
            .groups
            .iter()
            .map(|g| GroupSpec {
                kind: g.kind.clone(),
                name: g.name.clone(),
                weight: g.weight,
                selection: match (&g.faces, &g.vertices) {
                    (Some(faces), _) => SelectionSpec::Faces(faces.iter().map(|&f| f as usize).collect()),
                    (None, None) => SelectionSpec::All,
                    (None, Some(list)) => SelectionSpec::Vertices(list.iter().map(|&v| v as usize).collect()),
                },
                targets: if g.role == GroupRole::Handle {
                    Targets { explicit: Some(g.targets.iter().map(|t| t.to_array()).collect()), ..Targets::default() }
                } else {
                    Targets::default()
                },
                options: (*g.options).clone(),
            })
            .collect();
        Scene {
            mesh: MeshSettings {
                path: mesh_path.into(),
                generate: None,
                normalize: self.state.rest.normalize,
                tetrahedralize: false,
            },
            // One run of up to `iterations` to the tolerance: what the editor converges with.
            solver: SolverSettings {
                iterations: self.state.iterations,
                steps: 1,
                tolerance: self.state.tolerance,
                acceleration: self.state.acceleration,
                anderson_window: self.state.anderson_window,
                lbfgs_memory: self.state.lbfgs_memory,
                ..self.solver_settings
            },
            groups,
            output: Default::default(),
            base_dir: PathBuf::new(),
            file: PathBuf::new(),
        }
    }

    /// Writes [`Document::to_scene`] as TOML to `scene_path` (atomically).
    ///
    /// # Errors
    /// [`EditorError::Save`] naming the file.
    pub fn save_scene(&self, scene_path: &Path, mesh_path: impl Into<PathBuf>) -> Result<(), EditorError> {
        let text = self.to_scene(mesh_path).to_toml_string();
        shapeup_core::io::write_atomic(scene_path, |w| w.write_all(text.as_bytes()))
            .map_err(|e| EditorError::Save(e.to_string()))
    }

    /// Saves what replays the shape on screen: a scene at `scene_path` whose mesh is the file
    /// the document was opened from (absolute path) or, when the rest shape changed (Make rest
    /// shape) or the mesh has no file, the rest mesh written beside the scene as
    /// `STEM.rest.EXT` (the opened format when it is OBJ, PLY or OFF, else OBJ). Clears
    /// [`Document::is_modified`].
    ///
    /// # Errors
    /// [`EditorError::Save`] naming the file that cannot be written.
    pub fn save_scene_with_mesh(&mut self, scene_path: &Path) -> Result<SavedScene, EditorError> {
        let save_error = |e: String| EditorError::Save(e);
        let source = self.source.as_ref().filter(|_| Arc::ptr_eq(&self.state.rest, &self.opened_rest));
        let (mesh_path, rest_mesh, warnings) = match source {
            Some(source) => (std::fs::canonicalize(source).unwrap_or_else(|_| source.clone()), None, Vec::new()),
            None => {
                let ext = self
                    .source
                    .as_ref()
                    .and_then(|p| p.extension())
                    .and_then(|e| e.to_str())
                    .map(str::to_ascii_lowercase)
                    .filter(|e| matches!(e.as_str(), "obj" | "ply" | "off"))
                    .unwrap_or_else(|| "obj".into());
                let stem = scene_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                let name = format!("{stem}.rest.{ext}");
                let rest_path = scene_path.with_file_name(&name);
                let warnings = shapeup_core::io::write_mesh(&rest_path, &self.state.rest.mesh, &self.attributes)
                    .map_err(|e| save_error(e.to_string()))?;
                (PathBuf::from(name), Some(rest_path), warnings.iter().map(ToString::to_string).collect())
            }
        };
        self.save_scene(scene_path, mesh_path)?;
        self.modified = false;
        Ok(SavedScene { rest_mesh, warnings })
    }

    // ---- Reading the document ----

    /// The editable state (groups, shape model, rest shape, iterations).
    pub fn state(&self) -> &EditState {
        &self.state
    }

    /// Every group, in system order, for the constraints panel.
    pub fn groups(&self) -> &[Group] {
        &self.state.groups
    }

    /// The group with this key.
    pub fn group(&self, key: GroupKey) -> Option<&Group> {
        self.state.group(key)
    }

    /// The handles, in order.
    pub fn handles(&self) -> impl Iterator<Item = &Group> {
        self.state.groups.iter().filter(|g| g.role == GroupRole::Handle)
    }

    /// The shape model (`None`: custom shape groups from a scene).
    pub fn shape_model(&self) -> Option<ShapeModel> {
        self.state.shape_model
    }

    /// The most iterations one convergence runs ([`EditState::iterations`]).
    pub fn iterations(&self) -> usize {
        self.state.iterations
    }

    /// How the solver combines iterates ([`EditState::acceleration`]).
    pub fn acceleration(&self) -> Acceleration {
        self.state.acceleration
    }

    /// The convergence tolerance on the relative energy change ([`EditState::tolerance`]).
    pub fn tolerance(&self) -> f64 {
        self.state.tolerance
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Triangles of the mesh.
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.state.rest.mesh.triangles
    }

    /// Current positions, input frame (n of them).
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// The rest positions, input frame.
    pub fn rest_positions(&self) -> &[DVec3] {
        &self.state.rest.mesh.positions
    }

    /// The rest mesh (input frame), e.g. to save after [`Command::MakeRest`].
    pub fn rest_mesh(&self) -> &Mesh {
        &self.state.rest.mesh
    }

    /// The current shape as a mesh (input frame), e.g. to export with [`Document::attributes`]:
    /// the opened file's every vertex in order and its polygons, at the current positions.
    pub fn current_mesh(&self) -> Mesh {
        self.state.rest.mesh.with_positions(self.positions.clone())
    }

    /// Boundary flags of the vertices (an edge with one triangle).
    pub fn boundary(&self) -> &[bool] {
        &self.state.rest.geometry.topology.boundary
    }

    /// Per-vertex selection flags.
    pub fn selection(&self) -> &[bool] {
        &self.selection
    }

    /// The selected vertices, ascending.
    pub fn selected_vertices(&self) -> Vec<u32> {
        self.selection.iter().enumerate().filter(|(_, s)| **s).map(|(v, _)| v as u32).collect()
    }

    /// Number of selected vertices.
    pub fn num_selected(&self) -> usize {
        self.selection.iter().filter(|s| **s).count()
    }

    /// Increases whenever the shape is set rather than solved ([`Command::ResetShape`],
    /// [`Command::MakeRest`]); worker results of an older epoch are stale.
    pub fn epoch(&self) -> u64 {
        self.epoch
    }

    /// The positions the current epoch started from (input frame).
    pub fn epoch_start(&self) -> &Arc<Vec<DVec3>> {
        &self.epoch_start
    }

    // ---- Selection ----

    /// Combines vertices with the selection; indices out of range are ignored.
    pub fn select(&mut self, vertices: &[u32], mode: SelectMode) {
        if mode == SelectMode::Replace {
            self.clear_selection();
        }
        for &v in vertices {
            if let Some(s) = self.selection.get_mut(v as usize) {
                *s = mode != SelectMode::Remove;
            }
        }
    }

    /// Empties the selection (vertices and faces).
    pub fn clear_selection(&mut self) {
        self.selection.iter_mut().for_each(|s| *s = false);
        self.face_selection.iter_mut().for_each(|s| *s = false);
    }

    /// Combines faces with the face selection (out-of-range indices are ignored).
    pub fn select_faces(&mut self, faces: &[u32], mode: SelectMode) {
        if mode == SelectMode::Replace {
            self.clear_selection();
        }
        for &f in faces {
            if let Some(s) = self.face_selection.get_mut(f as usize) {
                *s = mode != SelectMode::Remove;
            }
        }
    }

    /// Which polygon faces are selected (one flag per face of the rest mesh).
    pub fn face_selection(&self) -> &[bool] {
        &self.face_selection
    }

    /// The selected faces, ascending.
    pub fn selected_faces(&self) -> Vec<u32> {
        self.face_selection.iter().enumerate().filter(|(_, s)| **s).map(|(f, _)| f as u32).collect()
    }

    /// The selection as the library's builders take it: the selected faces when there are
    /// any, else the selected vertices.
    pub fn library_selection(&self) -> Selection {
        let faces = self.selected_faces();
        if faces.is_empty() {
            Selection::Vertices(self.selection.clone())
        } else {
            let list: Vec<usize> = faces.iter().map(|&f| f as usize).collect();
            Selection::from_faces(self.selection.len(), &self.state.rest.geometry.faces, &list)
        }
    }

    /// Every registered constraint type that fits the selection (it picks at least one of
    /// the type's elements), in registry order: what "Add constraint to selection" offers.
    pub fn fitting_types(&self) -> Vec<&'static dyn ConstraintType> {
        let selection = self.library_selection();
        let rest = &self.state.rest.geometry;
        registry().iter().copied().filter(|t| selects_any(t.element(), rest, &selection)).collect()
    }

    /// Combines the boundary vertices (of edges with one triangle) with the selection.
    pub fn select_boundary(&mut self, mode: SelectMode) {
        let rim: Vec<u32> = self.boundary().iter().enumerate().filter(|(_, b)| **b).map(|(v, _)| v as u32).collect();
        self.select(&rim, mode);
    }

    // ---- Commands and undo ----

    /// Applies a command. Undoable ones record one undo step (one per drag between
    /// [`Document::begin_drag`] and [`Document::end_drag`]) and clear the redo history; a
    /// command that fails changes nothing.
    ///
    /// Returns whether the edit state or the shape changed, i.e. whether there is something
    /// new to solve: `false` for selections, for undo with nothing to undo and for edits that
    /// set what is already there.
    ///
    /// # Errors
    /// [`EditorError`] saying why the command cannot apply (unknown group, empty selection,
    /// NaN weight, a group that cannot be built…).
    pub fn apply(&mut self, command: Command) -> Result<bool, EditorError> {
        match command {
            Command::Select { vertices, mode } => self.select(&vertices, mode),
            Command::SelectFaces { faces, mode } => self.select_faces(&faces, mode),
            Command::ClearSelection => self.clear_selection(),
            Command::SelectBoundary(mode) => self.select_boundary(mode),
            Command::SelectPiece { vertex, mode } => {
                let piece = self.pieces.piece_of(vertex);
                self.select(&piece, mode);
            }
            Command::ResetShape => {
                let rest = self.state.rest.mesh.positions.clone();
                if rest == self.positions {
                    return Ok(false);
                }
                self.record(self.state.clone());
                self.set_shape(rest);
                return Ok(true);
            }
            Command::Undo => return Ok(self.undo()),
            Command::Redo => return Ok(self.redo()),
            command => {
                let mut next = self.state.clone();
                let make_rest = command == Command::MakeRest;
                let fixes = command == Command::FixSelection;
                self.edit(&mut next, command)?;
                if next == self.state {
                    return Ok(false);
                }
                self.solver.sync(&next)?;
                let previous = std::mem::replace(&mut self.state, next);
                self.record(previous);
                if make_rest {
                    let positions = self.state.rest.mesh.positions.clone();
                    self.set_shape(positions);
                }
                if fixes {
                    // Fixed vertices show as a handle, not as a selection.
                    self.clear_selection();
                }
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Records an undo step for the current state and shape, e.g. before a dynamics run moves
    /// the shape: undo then brings the shape back.
    pub fn checkpoint(&mut self) {
        self.end_drag();
        self.record(self.state.clone());
    }

    /// Sets the current shape (input frame) and starts a new epoch.
    fn set_shape(&mut self, positions: Vec<DVec3>) {
        self.solver.set_positions(&positions);
        self.epoch += 1;
        self.epoch_start = Arc::new(positions.clone());
        self.positions = positions;
    }

    /// Records the state before an undoable change, with the shape on screen now.
    fn record(&mut self, previous: EditState) {
        self.redo.clear();
        self.modified = true;
        match self.drag {
            Some(true) => return,
            Some(false) => self.drag = Some(true),
            None => {}
        }
        self.undo.push(Snapshot { state: previous, positions: Arc::new(self.positions.clone()) });
        // Each step holds a copy of the shape: keep at most about 512 MiB of them.
        let per_step = (self.positions.len() * std::mem::size_of::<DVec3>()).max(1);
        let limit = UNDO_LIMIT.min((512 << 20) / per_step).max(10);
        if self.undo.len() > limit {
            let excess = self.undo.len() - limit;
            self.undo.drain(..excess);
        }
    }

    /// The edit a command makes to the state (no side effects on the document).
    fn edit(&mut self, state: &mut EditState, command: Command) -> Result<(), EditorError> {
        match command {
            Command::FixSelection => {
                let vertices = self.selected_vertices();
                if vertices.is_empty() {
                    return Err(EditorError::EmptySelection);
                }
                let name = unique_name(state, "handle");
                let targets = vertices.iter().map(|&v| self.positions[v as usize]).collect();
                state.groups.push(Group {
                    key: self.new_key(),
                    name,
                    role: GroupRole::Handle,
                    kind: "position".into(),
                    weight: 1.0,
                    vertices: Some(vertices),
                    targets,
                    faces: None,
                    options: Arc::default(),
                });
            }
            Command::MoveHandle { handle, delta } => {
                if !delta.is_finite() {
                    return Err(EditorError::BadValue(format!("translation must be finite, found {delta}")));
                }
                state.handle_mut(handle)?.targets.iter_mut().for_each(|t| *t += delta);
            }
            Command::RotateHandle { handle, axis, angle } => {
                let axis = axis.try_normalize().filter(|_| angle.is_finite()).ok_or_else(|| {
                    EditorError::BadValue(format!(
                        "rotation needs a non-zero axis and a finite angle ({axis}, {angle})"
                    ))
                })?;
                let group = state.handle_mut(handle)?;
                let center = group.target_centroid().unwrap_or_default();
                let rotation = DQuat::from_axis_angle(axis, angle);
                group.targets.iter_mut().for_each(|t| *t = center + rotation * (*t - center));
            }
            Command::RenameHandle { handle, name } => state.group_mut(handle)?.name = name,
            Command::DeleteHandle(handle) => {
                state.handle_mut(handle)?;
                state.groups.retain(|g| g.key != handle);
            }
            Command::ClearHandles => state.groups.retain(|g| g.role != GroupRole::Handle),
            Command::SetShapeModel(model) => {
                // The model's groups take the place of the first shape group (first if none).
                let at = state.groups.iter().position(|g| g.role == GroupRole::Shape).unwrap_or(0);
                state.groups.retain(|g| g.role != GroupRole::Shape);
                let groups = self.model_groups(model);
                state.groups.splice(at.min(state.groups.len())..at.min(state.groups.len()), groups);
                state.shape_model = Some(model);
            }
            Command::AddConstraint { kind, options } => {
                let ty = constraint_type(&kind).map_err(|e| EditorError::Constraint(e.to_string()))?;
                let faces = self.selected_faces();
                let vertices = self.selected_vertices();
                let on_faces = ty.element().is_face() && !faces.is_empty();
                if !on_faces && vertices.is_empty() {
                    return Err(EditorError::EmptySelection);
                }
                let name = unique_name(state, ty.name());
                let handle = ty.has_targets();
                state.groups.push(Group {
                    key: self.new_key(),
                    name,
                    role: if handle { GroupRole::Handle } else { GroupRole::Other },
                    kind: ty.name().into(),
                    weight: ty.default_multiplier(),
                    targets: if handle {
                        vertices.iter().map(|&v| self.positions[v as usize]).collect()
                    } else {
                        Vec::new()
                    },
                    vertices: (!on_faces).then_some(vertices),
                    faces: on_faces.then_some(faces),
                    options: Arc::new(options),
                });
            }
            Command::AddSmoothing => {
                let vertices = self.selected_vertices();
                if vertices.is_empty() {
                    return Err(EditorError::EmptySelection);
                }
                let name = unique_name(state, "smoothing");
                state.groups.push(Group {
                    key: self.new_key(),
                    name,
                    role: GroupRole::Smoothing,
                    kind: "smoothing".into(),
                    weight: 1.0,
                    vertices: Some(vertices),
                    targets: Vec::new(),
                    faces: None,
                    options: Arc::default(),
                });
            }
            Command::SetWeight { group, weight } => {
                if weight.is_nan() {
                    return Err(EditorError::BadWeight(weight));
                }
                state.group_mut(group)?.weight = weight.clamp(WEIGHT_RANGE.0, WEIGHT_RANGE.1);
            }
            Command::RemoveGroup(key) => {
                if state.group_mut(key)?.role == GroupRole::Shape {
                    return Err(EditorError::ShapeGroup(key));
                }
                state.groups.retain(|g| g.key != key);
            }
            Command::MakeRest => {
                let old = &state.rest;
                let mesh = old.mesh.with_positions(self.positions.clone());
                state.rest = Arc::new(Rest::new(mesh, old.normalize));
            }
            Command::SetIterations(n) => {
                if n == 0 {
                    return Err(EditorError::BadValue("iterations must be at least 1".into()));
                }
                state.iterations = n;
            }
            Command::SetTolerance(tolerance) => {
                if !(tolerance.is_finite() && tolerance > 0.0) {
                    return Err(EditorError::BadValue(format!(
                        "tolerance must be a positive number, found {tolerance}"
                    )));
                }
                state.tolerance = tolerance;
            }
            Command::SetAcceleration(acceleration) => state.acceleration = acceleration,
            Command::PinFreePieces => {
                let mut pinned = vec![false; self.positions.len()];
                for group in state.groups.iter().filter(|g| g.role == GroupRole::Handle) {
                    for &v in group.vertices().unwrap_or(&[]) {
                        pinned[v as usize] = true;
                    }
                }
                let mut free = vec![false; self.pieces.of_vertex.len()];
                for piece in self.pieces.free(&pinned) {
                    free[piece as usize] = true;
                }
                let vertices: Vec<u32> = (0..self.positions.len() as u32)
                    .filter(|&v| free[self.pieces.of_vertex[v as usize] as usize])
                    .collect();
                if vertices.is_empty() {
                    return Ok(());
                }
                let name = unique_name(state, "free pieces");
                let targets = vertices.iter().map(|&v| state.rest.mesh.positions[v as usize]).collect();
                state.groups.push(Group {
                    key: self.new_key(),
                    name,
                    role: GroupRole::Handle,
                    kind: "position".into(),
                    weight: FREE_PIECE_WEIGHT,
                    vertices: Some(vertices),
                    targets,
                    faces: None,
                    options: Arc::default(),
                });
            }
            Command::Select { .. }
            | Command::SelectFaces { .. }
            | Command::SelectPiece { .. }
            | Command::ClearSelection
            | Command::SelectBoundary(_)
            | Command::ResetShape
            | Command::Undo
            | Command::Redo => {}
        }
        Ok(())
    }

    /// Starts a drag: every undoable command until [`Document::end_drag`] forms one undo step.
    pub fn begin_drag(&mut self) {
        self.drag = Some(false);
    }

    /// Ends a drag (see [`Document::begin_drag`]).
    pub fn end_drag(&mut self) {
        self.drag = None;
    }

    /// Whether a drag is under way (between [`Document::begin_drag`] and
    /// [`Document::end_drag`]): more changes are expected within a frame.
    pub fn is_dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Whether there is a step to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is a step to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Undoes the last step; `false` if there was none. The shape goes back to what was on
    /// screen before the step (the next solve converges from there).
    ///
    /// While a drag is under way this does nothing and returns `false`: the drag is one step
    /// whatever the keyboard does meanwhile, and is undone as one once it ends.
    pub fn undo(&mut self) -> bool {
        !self.is_dragging() && self.step_history(true)
    }

    /// Redoes the last undone step; `false` if there was none or a drag is under way (see
    /// [`Document::undo`]).
    pub fn redo(&mut self) -> bool {
        !self.is_dragging() && self.step_history(false)
    }

    fn step_history(&mut self, back: bool) -> bool {
        let (from, to) = if back { (&mut self.undo, &mut self.redo) } else { (&mut self.redo, &mut self.undo) };
        let Some(snapshot) = from.pop() else { return false };
        if self.solver.sync(&snapshot.state).is_err() {
            // Every recorded state was built once, so this does not happen; keep the history.
            from.push(snapshot);
            return false;
        }
        let current = Arc::new(self.positions.clone());
        to.push(Snapshot { state: std::mem::replace(&mut self.state, snapshot.state), positions: current });
        // Back to the shape that was on screen (a new epoch: the next solve starts there).
        self.set_shape(Arc::unwrap_or_clone(snapshot.positions));
        self.modified = true;
        true
    }

    // ---- Solving ----

    /// Converges synchronously from the current positions: iterates until the relative energy
    /// change of an iteration is at most [`Document::tolerance`], at most
    /// [`Document::iterations`] times (what the editor's worker does in the background, and
    /// what `shapeup deform` does from the rest shape with a saved scene). On error the shape
    /// stays as it was.
    ///
    /// # Errors
    /// As [`Document::solve`].
    pub fn converge(&mut self) -> Result<SolveReport, EditorError> {
        self.solve_to(self.state.iterations, self.state.tolerance)
    }

    /// Runs `iterations` local-global iterations synchronously from the current positions
    /// (tests and simple front ends; the app uses the [`worker`](crate::worker)).
    ///
    /// # Errors
    /// [`EditorError::NoHandles`] without a handle (nothing changes), [`EditorError::Solve`]
    /// for a singular system.
    pub fn solve(&mut self, iterations: usize) -> Result<SolveReport, EditorError> {
        self.solve_to(iterations, 0.0)
    }

    fn solve_to(&mut self, iterations: usize, tolerance: f64) -> Result<SolveReport, EditorError> {
        if !self.state.has_handles() {
            return Err(EditorError::NoHandles);
        }
        self.solver.sync(&self.state)?;
        match self.solver.solve_to(iterations, tolerance) {
            Ok(report) => {
                self.positions = self.solver.positions();
                Ok(report)
            }
            Err(e) => {
                // A failed solve leaves the last good shape, not a half-solved one.
                self.solver.set_positions(&self.positions);
                Err(e)
            }
        }
    }

    /// The connected pieces of the mesh.
    pub fn pieces(&self) -> &Pieces {
        &self.pieces
    }

    /// How many pieces (with triangles) have no handle vertex: each makes the system singular.
    pub fn num_free_pieces(&self) -> usize {
        let mut pinned = vec![false; self.positions.len()];
        for handle in self.handles() {
            for &v in handle.vertices().unwrap_or(&[]) {
                pinned[v as usize] = true;
            }
        }
        self.pieces.free(&pinned).len()
    }

    /// Whether the document changed since it was opened or last saved as a scene.
    pub fn is_modified(&self) -> bool {
        self.modified
    }

    /// The mesh file the document was read from, if any.
    pub fn source(&self) -> Option<&Path> {
        self.source.as_deref()
    }

    /// What the opened mesh file carried besides positions and faces ([`Attributes::None`] for a
    /// mesh made in memory), to write with [`Document::current_mesh`].
    pub fn attributes(&self) -> &Attributes {
        &self.attributes
    }

    /// E of the current shape per group, in the order of [`Document::groups`].
    ///
    /// # Errors
    /// [`EditorError::Solve`].
    pub fn group_energies(&mut self) -> Result<Vec<(GroupKey, f64)>, EditorError> {
        let energies = self.solver.energy()?;
        Ok(self.state.groups.iter().map(|g| g.key).zip(energies).collect())
    }

    /// Takes the positions of a worker's result when they belong to the current epoch;
    /// returns whether they were taken.
    pub fn accept_positions(&mut self, epoch: u64, positions: &[DVec3]) -> bool {
        if epoch != self.epoch || positions.len() != self.positions.len() {
            return false;
        }
        self.positions.copy_from_slice(positions);
        self.solver.set_positions(positions);
        true
    }
}

/// "prefix N" with the smallest N ≥ 1 no group uses.
fn unique_name(state: &EditState, prefix: &str) -> String {
    (1..).map(|k| format!("{prefix} {k}")).find(|name| state.groups.iter().all(|g| &g.name != name)).unwrap_or_default()
}

/// The vertices a scene selection picks (input frame): `None` for all, else in listed order or
/// ascending (as the scene loader does).
fn resolve_selection(spec: &SelectionSpec, mesh: &Mesh) -> Result<Option<Vec<u32>>, String> {
    match spec {
        SelectionSpec::All => Ok(None),
        _ => Ok(Some(spec.resolve(&mesh.positions)?.into_iter().map(|v| v as u32).collect())),
    }
}

/// A position group's targets (input frame), as the scene loader computes them: explicit, or
/// rest rotated about its centre (default the centroid), then translated.
fn position_targets(vertices: &[u32], targets: &Targets, mesh: &Mesh) -> Result<Vec<DVec3>, String> {
    let rest: Vec<DVec3> = vertices.iter().map(|&v| mesh.positions[v as usize]).collect();
    targets.resolve(&rest).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    /// A flat (n+1)×(n+1) grid in the XY plane: an open mesh whose rim is its border.
    pub(crate) fn grid(n: u32) -> Mesh {
        let mut positions = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(DVec3::new(x as f64 / n as f64, y as f64 / n as f64, 0.0));
            }
        }
        let mut triangles = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let v = y * (n + 1) + x;
                triangles.push([v, v + 1, v + n + 2]);
                triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
        Mesh::new(positions, triangles).unwrap()
    }

    #[test]
    fn boundary_of_a_grid_is_its_rim() {
        let n = 6;
        let mut doc = Document::new(grid(n), ShapeModel::EdgeSprings).unwrap();
        doc.apply(Command::SelectBoundary(SelectMode::Replace)).unwrap();
        let expected: Vec<u32> = (0..(n + 1) * (n + 1))
            .filter(|&v| {
                let (x, y) = (v % (n + 1), v / (n + 1));
                x == 0 || y == 0 || x == n || y == n
            })
            .collect();
        assert_eq!(doc.selected_vertices(), expected);
        assert_eq!(doc.num_selected(), 4 * n as usize);
    }

    #[test]
    fn selection_modes() {
        let mut doc = Document::new(grid(3), ShapeModel::EdgeSprings).unwrap();
        doc.select(&[1, 2, 3], SelectMode::Replace);
        doc.select(&[5, 999], SelectMode::Add);
        doc.select(&[2], SelectMode::Remove);
        assert_eq!(doc.selected_vertices(), [1, 3, 5]);
        doc.select(&[7], SelectMode::Replace);
        assert_eq!(doc.selected_vertices(), [7]);
        doc.apply(Command::ClearSelection).unwrap();
        assert_eq!(doc.num_selected(), 0);
    }

    #[test]
    fn no_handles_is_an_error_not_a_panic() {
        let mut doc = Document::new(grid(3), ShapeModel::StrainBending).unwrap();
        assert_eq!(doc.solve(5).unwrap_err(), EditorError::NoHandles);
        assert_eq!(doc.apply(Command::FixSelection).unwrap_err(), EditorError::EmptySelection);
        assert_eq!(doc.positions(), doc.rest_positions());
        assert!(!doc.can_undo());
    }
}
