//! What the user asks the editor to do. Panels and viewport gestures return [`Command`]s; the
//! app applies them after the UI pass with [`Document::apply`](crate::document::Document::apply),
//! which also records undo steps.

use crate::group::{GroupKey, ShapeModel};
use glam::DVec3;
use shapeup_core::contact::{ColliderSpec, ContactSettings};

/// How a selection combines with the current one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum SelectMode {
    /// The new vertices become the selection.
    #[default]
    Replace,
    /// The new vertices are added to it.
    Add,
    /// The new vertices are removed from it.
    Remove,
}

/// One editor action.
///
/// Commands that change the constraints (handles, groups, weights, shape model, rest shape,
/// iterations, tolerance, colliders, contact settings) or the shape ([`Command::ResetShape`])
/// are undoable; selection
/// changes, [`Command::Undo`] and [`Command::Redo`] are not ([`Command::effect`]).
#[derive(Debug, Clone, PartialEq)]
#[must_use]
pub enum Command {
    /// Combines `vertices` with the selection (e.g. from a box selection or a click).
    Select {
        /// Vertex indices.
        vertices: Vec<u32>,
        /// How they combine with the current selection.
        mode: SelectMode,
    },
    /// Combines polygon faces (indices into the rest mesh's faces) with the face selection
    /// (face mode).
    SelectFaces {
        /// Face indices.
        faces: Vec<u32>,
        /// How they combine with the current face selection.
        mode: SelectMode,
    },
    /// Empties the selection (vertices and faces).
    ClearSelection,
    /// Combines the mesh's boundary vertices with the selection.
    SelectBoundary(SelectMode),
    /// Combines the connected piece holding `vertex` with the selection.
    SelectPiece {
        /// A vertex of the piece (out of range: nothing).
        vertex: u32,
        /// How it combines with the current selection.
        mode: SelectMode,
    },
    /// A new handle (position group, g = 1) on the selected vertices, at their current
    /// positions; the selection is emptied.
    FixSelection,
    /// One soft handle (g = [`FREE_PIECE_WEIGHT`](crate::group::FREE_PIECE_WEIGHT)) on
    /// every vertex of the pieces no handle holds, at rest, listed as one group "free pieces".
    PinFreePieces,
    /// One `attachment` group on every piece that no handle holds and no attachment holds:
    /// each of its vertices follows the nearest triangle of the held pieces (of the largest
    /// piece when nothing is held), listed as one group "attached pieces". Opening a mesh does
    /// the same for the pieces within [`ATTACH_GAP`](crate::group::ATTACH_GAP) of the largest.
    /// Nothing free is an error.
    AttachFreePieces,
    /// Translates a handle's targets by `delta` (input frame).
    MoveHandle {
        /// The handle.
        handle: GroupKey,
        /// Translation, input frame.
        delta: DVec3,
    },
    /// Rotates a handle's targets about their centroid.
    RotateHandle {
        /// The handle.
        handle: GroupKey,
        /// Rotation axis (input frame, any non-zero length).
        axis: DVec3,
        /// Angle in radians, right-handed about the axis.
        angle: f64,
    },
    /// Renames a group (any group, not only handles).
    RenameHandle {
        /// The group.
        handle: GroupKey,
        /// Its new name.
        name: String,
    },
    /// Removes a handle.
    DeleteHandle(GroupKey),
    /// Removes every handle.
    ClearHandles,
    /// Replaces the shape groups by those of another model, with its default weights; handles
    /// and smoothing groups stay.
    SetShapeModel(ShapeModel),
    /// A smoothing group (g = 1) on the selected vertices.
    AddSmoothing,
    /// A group of any registered constraint type on the selection (the selected faces for a
    /// face type when faces are selected, else the selected vertices), with the type's
    /// default weight and these options (scene keys); a type with targets becomes a handle at
    /// the current positions.
    AddConstraint {
        /// Constraint type name.
        kind: String,
        /// Its options, as a scene would give them.
        options: serde_json::Map<String, serde_json::Value>,
    },
    /// Sets a group's weight (multiplier g), clamped to [`WEIGHT_RANGE`](crate::group::WEIGHT_RANGE).
    SetWeight {
        /// The group.
        group: GroupKey,
        /// The weight; NaN is rejected.
        weight: f64,
    },
    /// Removes a handle, smoothing or other group (not a shape-model group: pick another model
    /// instead).
    RemoveGroup(GroupKey),
    /// The current shape goes back to the rest shape.
    ResetShape,
    /// The current shape becomes the rest shape: every group is rebuilt on it.
    MakeRest,
    /// The most local-global iterations one convergence runs (≥ 1).
    SetIterations(usize),
    /// The convergence tolerance on the relative energy change (> 0).
    SetTolerance(f64),
    /// How the solver combines iterates (Anderson acceleration or plain).
    SetAcceleration(shapeup_core::solver::Acceleration),
    /// A collider, appended to the document's (a scene's `[[colliders]]` entry, input frame;
    /// [`Document::default_collider`](crate::document::Document::default_collider) places a
    /// primitive around the mesh, [`mesh_collider`](crate::collider::mesh_collider) reads a
    /// file). Refused when a value is out of range or its mesh file cannot be used.
    AddCollider(ColliderSpec),
    /// Removes the collider at this index.
    RemoveCollider(usize),
    /// Replaces the collider at `index` (e.g. a number edited in the Contact panel).
    EditCollider {
        /// Which collider.
        index: usize,
        /// Its new description.
        spec: ColliderSpec,
    },
    /// Translates a collider by `delta` (input frame; the gizmo on a collider). A mesh
    /// collider cannot move (its file places it).
    MoveCollider {
        /// Which collider.
        index: usize,
        /// Translation, input frame.
        delta: DVec3,
    },
    /// Turns a collider about its centre ([`crate::collider::center`]).
    RotateCollider {
        /// Which collider.
        index: usize,
        /// Rotation axis (input frame, any non-zero length).
        axis: DVec3,
        /// Angle in radians, right-handed about the axis.
        angle: f64,
    },
    /// The `[contact]` settings: self-collision, thickness, self friction.
    SetContact(ContactSettings),
    /// Undoes the last undoable command (or drag).
    Undo,
    /// Redoes the last undone step.
    Redo,
}

/// What applying a command can change: the one classification the document and the app read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Effect {
    /// It records an undo step when it changes something (not selections, undo or redo).
    pub undoable: bool,
    /// It can change what the solver computes (constraints, targets, weights, rest shape, the
    /// shape itself, convergence settings): the editor converges again after it.
    pub changes_solve: bool,
    /// It changes what is drawn before any solve returns (selection, groups, shape), so the
    /// mesh's geometry and colours are uploaded again; moving targets or changing weights
    /// changes nothing drawn until the solve returns.
    pub redraws: bool,
}

impl Command {
    /// Whether it changes only the colliders or the contact settings: a running simulation
    /// takes these over live instead of starting again.
    pub fn is_contact_edit(&self) -> bool {
        matches!(
            self,
            Command::AddCollider(_)
                | Command::RemoveCollider(_)
                | Command::EditCollider { .. }
                | Command::MoveCollider { .. }
                | Command::RotateCollider { .. }
                | Command::SetContact(_)
        )
    }

    /// What applying it can change.
    pub fn effect(&self) -> Effect {
        let effect = |undoable, changes_solve, redraws| Effect { undoable, changes_solve, redraws };
        match self {
            Command::Select { .. }
            | Command::SelectFaces { .. }
            | Command::ClearSelection
            | Command::SelectBoundary(_)
            | Command::SelectPiece { .. } => effect(false, false, true),
            Command::Undo | Command::Redo => effect(false, true, true),
            Command::RenameHandle { .. } => effect(true, false, false),
            Command::MoveHandle { .. }
            | Command::RotateHandle { .. }
            | Command::SetWeight { .. }
            | Command::SetIterations(_)
            | Command::SetTolerance(_)
            | Command::SetAcceleration(_)
            | Command::MoveCollider { .. }
            | Command::RotateCollider { .. } => effect(true, true, false),
            Command::FixSelection
            | Command::PinFreePieces
            | Command::AttachFreePieces
            | Command::DeleteHandle(_)
            | Command::ClearHandles
            | Command::SetShapeModel(_)
            | Command::AddSmoothing
            | Command::AddConstraint { .. }
            | Command::RemoveGroup(_)
            | Command::ResetShape
            | Command::MakeRest
            | Command::AddCollider(_)
            | Command::RemoveCollider(_)
            | Command::EditCollider { .. }
            | Command::SetContact(_) => effect(true, true, true),
        }
    }
}
