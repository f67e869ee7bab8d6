//! The editor's errors: one line each, meant for the status bar, keeping what caused them.

use crate::group::GroupKey;
use shapeup_core::constraints::ConstraintError;
use shapeup_core::dynamics::{DynamicsError, ParamError};
use shapeup_core::solver::SolveError;
use std::error::Error;
use std::fmt;
use std::sync::Arc;

/// An error from below kept as the source of an [`EditorError`]: shared so that the editor's
/// errors stay `Clone` (the worker hands them between threads), equal when they say the same.
#[derive(Debug, Clone)]
pub struct Cause(Arc<dyn Error + Send + Sync>);

impl Cause {
    /// Keeps `error` as a cause.
    pub fn new(error: impl Error + Send + Sync + 'static) -> Cause {
        Cause(Arc::new(error))
    }

    /// A cause the library reports as text only (e.g. a scene selection that cannot be
    /// resolved).
    pub fn text(message: impl Into<String>) -> Cause {
        Cause(Arc::new(Text(message.into())))
    }
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

// Transparent: the cause's own chain follows.
impl Error for Cause {
    fn source(&self) -> Option<&(dyn Error + 'static)> {
        self.0.source()
    }
}

impl PartialEq for Cause {
    fn eq(&self, other: &Cause) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || self.to_string() == other.to_string()
    }
}

/// A message with no further source.
#[derive(Debug)]
struct Text(String);

impl fmt::Display for Text {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl Error for Text {}

/// An editor error: one line, meant for the status bar.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EditorError {
    /// Solving needs at least one handle.
    #[error("nothing to solve: select vertices and fix them as a handle first")]
    NoHandles,
    /// The command works on the selection, which is empty.
    #[error("the selection is empty: select vertices first")]
    EmptySelection,
    /// No group has this key.
    #[error("no group {0} (it was removed)")]
    UnknownGroup(GroupKey),
    /// The group is not a handle.
    #[error("group {0} is not a handle")]
    NotAHandle(GroupKey),
    /// Another group has this name (group names are unique, as in scene files).
    #[error("a group named \"{0}\" exists already")]
    NameTaken(String),
    /// Shape-model groups are replaced with
    /// [`Command::SetShapeModel`](crate::command::Command::SetShapeModel), not removed.
    #[error("group {0} belongs to the shape model; choose another model instead of removing it")]
    ShapeGroup(GroupKey),
    /// A NaN weight.
    #[error("weight must be a number, found {0}")]
    BadWeight(f64),
    /// A non-finite or degenerate value (translation, axis, angle, iteration count).
    #[error("{0}")]
    BadValue(String),
    /// A mesh or scene that cannot be read or used.
    #[error(transparent)]
    Load(LoadError),
    /// A file that cannot be written.
    #[error(transparent)]
    Save(Cause),
    /// A group cannot be built (e.g. smoothing on a selection with no interior vertex).
    #[error(transparent)]
    Constraint(GroupError),
    /// The solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Dynamic mode could not start or failed.
    #[error("simulation: {0}")]
    Simulation(#[source] SimulationError),
    /// A collider cannot be used (a mesh file that cannot be read, a bad value), naming it
    /// as a scene does (`colliders[1]: …`).
    #[error("{0}")]
    Collider(String),
    /// No collider has this index.
    #[error("no collider {0} (there are {1})")]
    UnknownCollider(usize, usize),
}

/// Why a mesh or scene cannot be opened in the editor.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LoadError {
    /// The mesh file cannot be read.
    #[error(transparent)]
    Mesh(Cause),
    /// The scene's mesh cannot be read or generated.
    #[error(transparent)]
    Scene(Cause),
    /// A mesh without triangles.
    #[error("the mesh has no triangles to deform")]
    NoTriangles,
    /// A scene that asks for tetrahedra.
    #[error("the editor does not support tetrahedralize = true")]
    Tetrahedralize,
    /// A scene with a `[material]`, which the editor cannot keep yet.
    #[error(
        "the editor does not support [material] yet (it would drop it on saving): run the scene with `shapeup deform` or `shapeup simulate`, or from Python"
    )]
    Material,
    /// A scene with `[loads]` (a pressure), which the editor cannot keep yet.
    #[error(
        "the editor does not support [loads] yet (it would drop them on saving): run the scene with `shapeup deform` or `shapeup simulate`, or from Python"
    )]
    Loads,
    /// A scene entry that cannot become an editor group.
    #[error("constraints[{index}] (\"{name}\"): {cause}")]
    Entry {
        /// Index in the scene's `constraints`.
        index: usize,
        /// The entry's name.
        name: String,
        /// Why.
        #[source]
        cause: Cause,
    },
}

/// Why a group cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GroupError {
    /// An unknown constraint type.
    #[error(transparent)]
    Type(ConstraintError),
    /// The library cannot build the group (a bad option, nothing to constrain, a selection
    /// out of range).
    #[error("group \"{group}\": {source}")]
    Build {
        /// The group's name.
        group: String,
        /// Why: the library's [`SpecError`](shapeup_core::scene::SpecError).
        source: Cause,
    },
}

/// Why dynamic mode cannot start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimulationError {
    /// A setting is out of range (the message names it).
    #[error(transparent)]
    Settings(#[from] SettingsError),
    /// The mesh cannot be filled with tetrahedra.
    #[error("TetGen could not tetrahedralize {mesh}: {why}")]
    Tetrahedralize {
        /// The mesh's file, or "the mesh".
        mesh: String,
        /// Why.
        #[source]
        why: TetrahedraError,
    },
    /// The tet strain model on a mesh without tetrahedra.
    #[error("the tet strain model needs tetrahedra: tick Tetrahedralize")]
    NeedsTetrahedra,
    /// Tetrahedralize asked of a simulation that starts from a shape on screen other than the
    /// rest shape: TetGen fills the rest shape, and its inner points cannot follow a deformed surface (a collapsed one
    /// turns them inside out and the body explodes).
    #[error("Tetrahedralize fills the rest shape: start the solid with Run from rest")]
    TetrahedraFromRestOnly,
    /// A constraint type the dynamic scene needs is unknown.
    #[error(transparent)]
    Constraint(ConstraintError),
    /// A group of the simulation cannot be built on the simulated mesh.
    #[error(transparent)]
    Group(#[from] GroupError),
    /// The simulation refuses its start state.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
    /// A collider cannot be built on the simulated mesh.
    #[error("{0}")]
    Collider(String),
    /// The simulation thread cannot be started.
    #[error("cannot start the simulation thread: {0}")]
    Thread(#[source] Cause),
}

/// A dynamic-mode setting out of range
/// ([`SimulationSettings::validate`](crate::simulation::SimulationSettings::validate)).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// A time-stepping setting (stiffness, time step, damping, gravity).
    #[error(transparent)]
    Dynamics(#[from] ParamError),
    /// The grab strength is outside (0, 1].
    #[error("grab strength must be in (0, 1], found {0}")]
    GrabStrength(f64),
}

/// What went wrong in a running simulation, shown in the Dynamics panel
/// ([`SimulationStats::error`](crate::simulation::SimulationStats::error)).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunnerError {
    /// New settings were refused (they stay as they were).
    #[error(transparent)]
    Settings(DynamicsError),
    /// A grab was refused.
    #[error(transparent)]
    Grab(DynamicsError),
    /// A time step failed (stepping pauses).
    #[error(transparent)]
    Step(SolveError),
    /// Putting the vertices below the floor back on it failed (stepping pauses).
    #[error(transparent)]
    Floor(DynamicsError),
    /// New colliders or contact settings were refused (the old ones stay).
    #[error("{0}")]
    Contact(String),
}

/// Why a mesh cannot be filled with tetrahedra.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TetrahedraError {
    /// This build has no TetGen, said where the checkbox is.
    #[error("this build has no TetGen (cargo feature `tetgen`, AGPL-3.0)")]
    NoTetGen,
    /// This build has no TetGen, said when tetrahedralizing.
    #[error("this build has no TetGen (cargo feature `tetgen`)")]
    NotBuilt,
    /// The mesh has tetrahedra already.
    #[error("the mesh already has tetrahedra")]
    AlreadyTetrahedra,
    /// The mesh has no triangles.
    #[error("the mesh has no triangles")]
    NoTriangles,
    /// Some edges belong to one triangle only (and none to more than two).
    #[error("the surface is open: {border} edges belong to one triangle only (e.g. vertices {a}–{b})")]
    Open {
        /// Edges with one triangle.
        border: usize,
        /// First vertex of the first such edge.
        a: u32,
        /// Its second vertex.
        b: u32,
    },
    /// Some edges are not shared by exactly two triangles.
    #[error("the surface is not closed: {count} edges are not shared by exactly two triangles (e.g. vertices {a}–{b})")]
    NotClosed {
        /// Edges not shared by exactly two triangles.
        count: usize,
        /// First vertex of the first such edge.
        a: u32,
        /// Its second vertex.
        b: u32,
    },
    /// TetGen failed on a closed surface: mostly one crossing itself.
    #[error("the surface may intersect itself or repeat faces (TetGen: {0})")]
    TetGen(String),
    /// TetGen's input check refused the mesh.
    #[error("{0}")]
    BadInput(String),
}
