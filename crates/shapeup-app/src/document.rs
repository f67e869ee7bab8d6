//! The editor's model: a mesh, its constraint groups, the selection, the current shape and the
//! undo history, with no GUI.
//!
//! - [`EditState`] is what undo snapshots: the rest shape (shared, cheap to clone), the groups
//!   (shape model, handles with their targets, smoothing, others from a scene), the colliders
//!   and contact settings, and the iteration count. It is also what the
//!   [`worker`](crate::worker) receives to solve.
//! - [`EditSolver`] turns an `EditState` into a `shapeup-core` system and keeps the working
//!   positions ([`edit_state`](crate::edit_state)).
//! - [`Document`] ties them together with the selection and the current positions, and applies
//!   [`Command`]s: [`apply`](Document::apply) here, what each command edits in `edit.rs`, the
//!   undo history in `history.rs`, scene round trips in `scene_io.rs`.
//!
//! Handle targets and positions are in the mesh's input frame; the solver works in the
//! normalized working frame, as `shapeup deform` does, so a saved scene reproduces the
//! editor's solve.

mod edit;
mod history;
mod scene_io;

use crate::command::{Command, SelectMode};
use crate::error::{Cause, LoadError};
use glam::DVec3;
use history::Snapshot;
use shapeup_core::constraints::{ConstraintType, Selection, registry, selects_any};
use shapeup_core::contact::{ColliderSpec, ContactSettings};
use shapeup_core::io::{Attributes, read_mesh};
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{GroupSpec, SelectionSpec, SolverSettings, Targets};
use shapeup_core::solver::{Acceleration, SolveReport};
use std::path::{Path, PathBuf};
use std::sync::Arc;

// The document's vocabulary, re-exported where it was first defined.
pub use crate::edit_state::{DEFAULT_MAX_ITERATIONS, DEFAULT_TOLERANCE, EditSolver, EditState, Rest};
pub use crate::error::EditorError;
pub use crate::group::{FREE_PIECE_WEIGHT, Group, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE};
pub use crate::pieces::Pieces;
pub use history::UNDO_LIMIT;
pub use scene_io::SavedScene;

/// The editor's document: the constraint state with its undo history, the selection and the
/// current shape.
#[derive(Debug)]
pub struct Document {
    state: EditState,
    solver: EditSolver,
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
    /// handles; pieces within [`ATTACH_GAP`](crate::group::ATTACH_GAP) of the largest piece
    /// are attached to it ([`Command::AttachFreePieces`]).
    ///
    /// # Errors
    /// [`EditorError::Load`] for a mesh without triangles, [`EditorError::Constraint`] if the
    /// model cannot be built on it.
    pub fn new(mesh: Mesh, model: ShapeModel) -> Result<Document, EditorError> {
        if mesh.triangles.is_empty() {
            return Err(EditorError::Load(LoadError::NoTriangles));
        }
        let rest = Arc::new(Rest::new(mesh, true));
        let mut document = Document::empty(rest, SolverSettings::default());
        document.state.shape_model = Some(model);
        document.state.groups = document.model_groups(model);
        // Pieces that sit on the body (an eye, nails, a belt) follow it from the start.
        if document.pieces.count > 1 {
            let mut state = document.state.clone();
            if document.attach_free_pieces(&mut state, Some(crate::group::ATTACH_GAP)).is_ok() {
                document.state = state;
            }
        }
        document.solver.sync(&document.state)?;
        Ok(document)
    }

    /// Reads a mesh file and makes a document on it ([`Document::new`]).
    ///
    /// # Errors
    /// [`EditorError::Load`] naming the file, or as [`Document::new`].
    pub fn open(path: &Path, model: ShapeModel) -> Result<Document, EditorError> {
        let loaded = read_mesh(path).map_err(|e| EditorError::Load(LoadError::Mesh(Cause::new(e))))?;
        let mut document = Document::new(loaded.mesh, model)?;
        document.source = Some(path.to_path_buf());
        document.attributes = loaded.attributes;
        Ok(document)
    }

    /// A document on a bundled sample mesh ([`crate::samples`]), read from memory: it has no
    /// source file, so saving a scene writes its mesh beside the scene.
    ///
    /// # Errors
    /// As [`Document::open`].
    pub fn open_sample(sample: &crate::samples::Sample, model: ShapeModel) -> Result<Document, EditorError> {
        let loaded = sample.read().map_err(|e| EditorError::Load(LoadError::Mesh(Cause::new(e))))?;
        let mut document = Document::new(loaded.mesh, model)?;
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
                colliders: Vec::new(),
                contact: Default::default(),
            },
            solver: EditSolver::new(),
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
                role: GroupRole::Shape,
                spec: GroupSpec {
                    kind: kind.to_string(),
                    name: kind.to_string(),
                    weight,
                    selection: SelectionSpec::All,
                    targets: Targets::default(),
                    options: serde_json::Map::new(),
                },
            })
            .collect()
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

    /// The colliders, in order ([`EditState::colliders`]).
    pub fn colliders(&self) -> &[ColliderSpec] {
        &self.state.colliders
    }

    /// The `[contact]` settings ([`EditState::contact`]).
    pub fn contact_settings(&self) -> ContactSettings {
        self.state.contact
    }

    /// A collider of type `kind` (sphere, box, plane, capsule) placed just below the current
    /// shape ([`crate::collider::default_collider`]), for [`Command::AddCollider`]; `None` for
    /// another type.
    pub fn default_collider(&self, kind: &str) -> Option<ColliderSpec> {
        let lo = self.positions.iter().copied().reduce(DVec3::min)?;
        let hi = self.positions.iter().copied().reduce(DVec3::max)?;
        crate::collider::default_collider(kind, lo, hi)
    }

    /// Per vertex, whether it touched a collider or the surface itself at the end of the last
    /// synchronous solve ([`Document::converge`]); `None` without colliders and self-collision.
    pub fn touching(&self) -> Option<&[bool]> {
        self.solver.touching()
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
        if !command.effect().undoable {
            return Ok(self.navigate(command));
        }
        if command == Command::ResetShape {
            return Ok(self.reset_shape());
        }
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
        Ok(true)
    }

    /// Applies a command that records no undo step: a selection (nothing new to solve) or a
    /// step through the history. Returns whether the state or the shape changed.
    fn navigate(&mut self, command: Command) -> bool {
        match command {
            Command::Select { vertices, mode } => self.select(&vertices, mode),
            Command::SelectFaces { faces, mode } => self.select_faces(&faces, mode),
            Command::ClearSelection => self.clear_selection(),
            Command::SelectBoundary(mode) => self.select_boundary(mode),
            Command::SelectPiece { vertex, mode } => {
                let piece = self.pieces.piece_of(vertex);
                self.select(&piece, mode);
            }
            Command::Undo => return self.undo(),
            Command::Redo => return self.redo(),
            // Undoable commands go through `edit`.
            _ => {}
        }
        false
    }

    /// [`Command::ResetShape`]: back to the rest shape, one undo step; `false` when already
    /// there.
    fn reset_shape(&mut self) -> bool {
        let rest = self.state.rest.mesh.positions.clone();
        if rest == self.positions {
            return false;
        }
        self.record(self.state.clone());
        self.set_shape(rest);
        true
    }

    /// Sets the current shape (input frame) and starts a new epoch.
    fn set_shape(&mut self, positions: Vec<DVec3>) {
        self.solver.set_positions(&positions);
        self.epoch += 1;
        self.epoch_start = Arc::new(positions.clone());
        self.positions = positions;
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

    /// How many pieces (with triangles) have no handle vertex and are not attached: each makes
    /// the system singular.
    pub fn num_free_pieces(&self) -> usize {
        self.pieces.free(&edit::held_vertices(&self.state)).len()
    }

    /// How many pieces (with triangles) `attachment` groups hold: they follow the pieces
    /// around them.
    pub fn num_attached_pieces(&self) -> usize {
        let mut attached = vec![false; self.pieces.of_vertex.len()];
        let groups = self.state.groups.iter().filter(|g| g.spec.kind == crate::group::ATTACHMENT_KIND);
        for &v in groups.flat_map(|g| g.vertices().unwrap_or(&[])) {
            if let Some(&p) = self.pieces.of_vertex.get(v) {
                attached[p as usize] = true;
            }
        }
        attached.iter().filter(|a| **a).count()
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
