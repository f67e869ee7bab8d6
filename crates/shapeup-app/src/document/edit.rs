//! What each command does to the edit state: [`Document::edit`] dispatches, one function per
//! [`Command`] arm does the work.

use super::Document;
use crate::command::Command;
use crate::edit_state::{EditState, Rest};
use crate::error::{EditorError, GroupError};
use crate::group::{
    ATTACHMENT_KIND, FREE_PIECE_WEIGHT, Group, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE, explicit_targets,
};
use glam::{DQuat, DVec3};
use serde_json::Map;
use shapeup_core::constraints::{AttachmentType, ConstraintType, constraint_type};
use shapeup_core::contact::ColliderSpec;
use shapeup_core::nearest::NearestTriangle;
use shapeup_core::scene::{GroupSpec, SelectionSpec, Targets, unique_group_name};
use shapeup_core::solver::Acceleration;
use std::sync::Arc;

impl Document {
    /// The edit a command makes to the state (no side effects on the document but new group
    /// keys). Selections, Reset shape, Undo and Redo edit nothing: [`Document::apply`] handles
    /// them.
    pub(super) fn edit(&mut self, state: &mut EditState, command: Command) -> Result<(), EditorError> {
        match command {
            Command::FixSelection => self.fix_selection(state),
            Command::MoveHandle { handle, delta } => move_handle(state, handle, delta),
            Command::RotateHandle { handle, axis, angle } => rotate_handle(state, handle, axis, angle),
            Command::RenameHandle { handle, name } => {
                // Unique names, as a scene file requires: a saved session must open again.
                if state.groups.iter().any(|g| g.key != handle && g.spec.name == name) {
                    return Err(EditorError::NameTaken(name));
                }
                state.group_mut(handle)?.spec.name = name;
                Ok(())
            }
            Command::DeleteHandle(handle) => delete_handle(state, handle),
            Command::ClearHandles => {
                state.groups.retain(|g| g.role != GroupRole::Handle);
                Ok(())
            }
            Command::SetShapeModel(model) => {
                self.set_shape_model(state, model);
                Ok(())
            }
            Command::AddConstraint { kind, options } => self.add_constraint(state, &kind, options),
            Command::AddSmoothing => self.add_smoothing(state),
            Command::SetWeight { group, weight } => set_weight(state, group, weight),
            Command::RemoveGroup(key) => remove_group(state, key),
            Command::MakeRest => {
                self.make_rest(state);
                Ok(())
            }
            Command::SetIterations(n) => set_iterations(state, n),
            Command::SetTolerance(tolerance) => set_tolerance(state, tolerance),
            Command::SetAcceleration(acceleration) => {
                set_acceleration(state, acceleration);
                Ok(())
            }
            Command::PinFreePieces => {
                self.pin_free_pieces(state);
                Ok(())
            }
            Command::AttachFreePieces => self.attach_free_pieces(state, None).map(|_| ()),
            Command::AddCollider(spec) => {
                checked(&spec)?;
                state.colliders.push(spec);
                Ok(())
            }
            Command::RemoveCollider(index) => {
                collider_mut(state, index)?;
                state.colliders.remove(index);
                Ok(())
            }
            Command::EditCollider { index, spec } => {
                checked(&spec)?;
                *collider_mut(state, index)? = spec;
                Ok(())
            }
            Command::MoveCollider { index, delta } => {
                let c = collider_mut(state, index)?;
                *c = crate::collider::translated(c, delta)?;
                Ok(())
            }
            Command::RotateCollider { index, axis, angle } => {
                let c = collider_mut(state, index)?;
                *c = crate::collider::turned(c, axis, angle)?;
                Ok(())
            }
            Command::SetContact(settings) => {
                settings.validate().map_err(|e| EditorError::BadValue(e.to_string()))?;
                state.contact = settings;
                Ok(())
            }
            Command::Select { .. }
            | Command::SelectFaces { .. }
            | Command::SelectPiece { .. }
            | Command::ClearSelection
            | Command::SelectBoundary(_)
            | Command::ResetShape
            | Command::Undo
            | Command::Redo => Ok(()),
        }
    }

    /// [`Command::FixSelection`]: a handle on the selected vertices at their current positions.
    fn fix_selection(&mut self, state: &mut EditState) -> Result<(), EditorError> {
        let vertices = self.selected_vertices();
        if vertices.is_empty() {
            return Err(EditorError::EmptySelection);
        }
        let spec = GroupSpec {
            kind: "position".into(),
            name: unique_name(state, "handle"),
            weight: 1.0,
            targets: explicit_targets(vertices.iter().map(|&v| self.positions[v as usize])),
            selection: vertex_list(&vertices),
            options: Map::new(),
        };
        state.groups.push(Group { key: self.new_key(), role: GroupRole::Handle, spec });
        Ok(())
    }

    /// [`Command::SetShapeModel`]: the model's groups take the place of the first shape group
    /// (first if none).
    fn set_shape_model(&mut self, state: &mut EditState, model: ShapeModel) {
        let at = state.groups.iter().position(|g| g.role == GroupRole::Shape).unwrap_or(0);
        state.groups.retain(|g| g.role != GroupRole::Shape);
        let groups = self.model_groups(model);
        state.groups.splice(at.min(state.groups.len())..at.min(state.groups.len()), groups);
        state.shape_model = Some(model);
    }

    /// [`Command::AddConstraint`]: a group of any registered type on the selected faces (face
    /// types) or vertices.
    fn add_constraint(
        &mut self,
        state: &mut EditState,
        kind: &str,
        options: serde_json::Map<String, serde_json::Value>,
    ) -> Result<(), EditorError> {
        let ty = constraint_type(kind).map_err(|e| EditorError::Constraint(GroupError::Type(e)))?;
        let faces = self.selected_faces();
        let vertices = self.selected_vertices();
        let on_faces = ty.element().is_face() && !faces.is_empty();
        if !on_faces && vertices.is_empty() {
            return Err(EditorError::EmptySelection);
        }
        let handle = ty.has_targets();
        let spec = GroupSpec {
            kind: ty.name().into(),
            name: unique_name(state, ty.name()),
            weight: ty.default_multiplier(),
            targets: if handle {
                explicit_targets(vertices.iter().map(|&v| self.positions[v as usize]))
            } else {
                Targets::default()
            },
            selection: if on_faces {
                SelectionSpec::Faces(faces.iter().map(|&f| f as usize).collect())
            } else {
                vertex_list(&vertices)
            },
            options,
        };
        let role = if handle { GroupRole::Handle } else { GroupRole::Other };
        state.groups.push(Group { key: self.new_key(), role, spec });
        Ok(())
    }

    /// [`Command::AddSmoothing`]: a smoothing group (g = 1) on the selected vertices.
    fn add_smoothing(&mut self, state: &mut EditState) -> Result<(), EditorError> {
        let vertices = self.selected_vertices();
        if vertices.is_empty() {
            return Err(EditorError::EmptySelection);
        }
        let spec = GroupSpec {
            kind: "smoothing".into(),
            name: unique_name(state, "smoothing"),
            weight: 1.0,
            selection: vertex_list(&vertices),
            targets: Targets::default(),
            options: Map::new(),
        };
        state.groups.push(Group { key: self.new_key(), role: GroupRole::Smoothing, spec });
        Ok(())
    }

    /// [`Command::MakeRest`]: the current shape becomes the rest shape.
    fn make_rest(&self, state: &mut EditState) {
        let old = &state.rest;
        let mesh = old.mesh.with_positions(self.positions.clone());
        state.rest = Arc::new(Rest::new(mesh, old.normalize));
    }

    /// [`Command::AttachFreePieces`] (every free piece, `gap` `None`) or opening a mesh (the
    /// pieces within `gap`, a fraction of the diagonal, of the largest): the number of pieces
    /// attached (an error when none is).
    pub(super) fn attach_free_pieces(&mut self, state: &mut EditState, gap: Option<f64>) -> Result<usize, EditorError> {
        let pieces = &self.pieces;
        let held = held_vertices(state);
        let free = pieces.free(&held);
        let mut hosts = vec![false; pieces.of_vertex.len()];
        for (v, &h) in held.iter().enumerate() {
            hosts[pieces.of_vertex[v] as usize] |= h;
        }
        if !hosts.contains(&true) {
            // Nothing held yet (a mesh just opened): the pieces sit on the largest one.
            if let Some(largest) = pieces.largest(&state.rest.mesh.triangles) {
                hosts[largest as usize] = true;
            }
        }
        let mesh = &state.rest.mesh;
        let surface: Vec<[u32; 3]> =
            mesh.triangles.iter().filter(|t| hosts[pieces.of_vertex[t[0] as usize] as usize]).copied().collect();
        let (lo, hi) = mesh.bounding_box();
        let gap = gap.map_or(f64::INFINITY, |g| g * (hi - lo).length());
        // One pass over the vertices: a free piece is near when any of its vertices is.
        let mut near = vec![false; hosts.len()];
        if let Some(surface) = NearestTriangle::new(&mesh.positions, surface) {
            let mut candidate = vec![false; hosts.len()];
            for p in free.into_iter().filter(|&p| !hosts[p as usize]) {
                candidate[p as usize] = true;
            }
            for (v, &p) in pieces.of_vertex.iter().enumerate() {
                let p = p as usize;
                if candidate[p] && !near[p] && surface.nearest(mesh.positions[v]).1 <= gap {
                    near[p] = true;
                }
            }
        }
        let near: Vec<u32> = (0..near.len() as u32).filter(|&p| near[p as usize]).collect();
        if near.is_empty() {
            return Err(EditorError::BadValue(
                "no free piece to attach: every piece has a handle or is attached".into(),
            ));
        }
        let vertices = pieces.vertices_of(&near);
        let spec = GroupSpec {
            kind: ATTACHMENT_KIND.into(),
            name: unique_name(state, "attached pieces"),
            weight: AttachmentType.default_multiplier(),
            targets: Targets::default(),
            selection: vertex_list(&vertices),
            options: Map::new(),
        };
        state.groups.push(Group { key: self.new_key(), role: GroupRole::Other, spec });
        Ok(near.len())
    }

    /// [`Command::PinFreePieces`]: one soft handle at rest on every vertex of the pieces no
    /// handle holds (nothing when there are none).
    fn pin_free_pieces(&mut self, state: &mut EditState) {
        let vertices = self.pieces.vertices_of(&self.pieces.free(&held_vertices(state)));
        if vertices.is_empty() {
            return;
        }
        let spec = GroupSpec {
            kind: "position".into(),
            name: unique_name(state, "free pieces"),
            weight: FREE_PIECE_WEIGHT,
            targets: explicit_targets(vertices.iter().map(|&v| state.rest.mesh.positions[v as usize])),
            selection: vertex_list(&vertices),
            options: Map::new(),
        };
        state.groups.push(Group { key: self.new_key(), role: GroupRole::Handle, spec });
    }
}

/// Per vertex, whether a handle or an attachment holds it: a piece with such a vertex is not
/// free.
pub(super) fn held_vertices(state: &EditState) -> Vec<bool> {
    let mut held = vec![false; state.rest.mesh.num_vertices()];
    for group in state.groups.iter().filter(|g| g.role == GroupRole::Handle || g.spec.kind == ATTACHMENT_KIND) {
        for &v in group.vertices().unwrap_or(&[]) {
            if let Some(h) = held.get_mut(v) {
                *h = true;
            }
        }
    }
    held
}

/// [`Command::MoveHandle`]: translates a handle's targets.
fn move_handle(state: &mut EditState, handle: GroupKey, delta: DVec3) -> Result<(), EditorError> {
    if !delta.is_finite() {
        return Err(EditorError::BadValue(format!("translation must be finite, found {delta}")));
    }
    state.handle_mut(handle)?.map_targets(|t| t + delta);
    Ok(())
}

/// [`Command::RotateHandle`]: rotates a handle's targets about their centroid.
fn rotate_handle(state: &mut EditState, handle: GroupKey, axis: DVec3, angle: f64) -> Result<(), EditorError> {
    let axis = axis.try_normalize().filter(|_| angle.is_finite()).ok_or_else(|| {
        EditorError::BadValue(format!("rotation needs a non-zero axis and a finite angle ({axis}, {angle})"))
    })?;
    let group = state.handle_mut(handle)?;
    let center = group.target_centroid().unwrap_or_default();
    let rotation = DQuat::from_axis_angle(axis, angle);
    group.map_targets(|t| center + rotation * (t - center));
    Ok(())
}

/// [`Command::DeleteHandle`]: removes a handle (and only a handle).
fn delete_handle(state: &mut EditState, handle: GroupKey) -> Result<(), EditorError> {
    state.handle_mut(handle)?;
    state.groups.retain(|g| g.key != handle);
    Ok(())
}

/// [`Command::SetWeight`]: clamped to [`WEIGHT_RANGE`]; NaN is refused.
fn set_weight(state: &mut EditState, group: GroupKey, weight: f64) -> Result<(), EditorError> {
    if weight.is_nan() {
        return Err(EditorError::BadWeight(weight));
    }
    state.group_mut(group)?.spec.weight = weight.clamp(WEIGHT_RANGE.0, WEIGHT_RANGE.1);
    Ok(())
}

/// [`Command::RemoveGroup`]: any group but a shape-model one.
fn remove_group(state: &mut EditState, key: GroupKey) -> Result<(), EditorError> {
    if state.group_mut(key)?.role == GroupRole::Shape {
        return Err(EditorError::ShapeGroup(key));
    }
    state.groups.retain(|g| g.key != key);
    Ok(())
}

/// [`Command::SetIterations`]: at least 1.
fn set_iterations(state: &mut EditState, n: usize) -> Result<(), EditorError> {
    if n == 0 {
        return Err(EditorError::BadValue("iterations must be at least 1".into()));
    }
    state.iterations = n;
    Ok(())
}

/// [`Command::SetTolerance`]: a positive number.
fn set_tolerance(state: &mut EditState, tolerance: f64) -> Result<(), EditorError> {
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(EditorError::BadValue(format!("tolerance must be a positive number, found {tolerance}")));
    }
    state.tolerance = tolerance;
    Ok(())
}

/// [`Command::SetAcceleration`].
fn set_acceleration(state: &mut EditState, acceleration: Acceleration) {
    state.acceleration = acceleration;
}

/// A collider's values checked (its mesh file is read when the solver builds it).
fn checked(spec: &ColliderSpec) -> Result<(), EditorError> {
    spec.validate().map_err(|e| EditorError::BadValue(format!("{} collider: {e}", spec.kind())))
}

/// The collider at `index`.
fn collider_mut(state: &mut EditState, index: usize) -> Result<&mut ColliderSpec, EditorError> {
    let n = state.colliders.len();
    state.colliders.get_mut(index).ok_or(EditorError::UnknownCollider(index, n))
}

/// A name for a new group no group uses, by the core's one rule for unnamed groups
/// ([`unique_group_name`]: `base`, else `base_2`, `base_3`, …).
fn unique_name(state: &EditState, base: &str) -> String {
    let existing: Vec<&str> = state.groups.iter().map(|g| g.spec.name.as_str()).collect();
    unique_group_name(base, &existing)
}

/// An editor selection (ascending vertex indices) as a group's selection.
fn vertex_list(vertices: &[u32]) -> SelectionSpec {
    SelectionSpec::Vertices(vertices.iter().map(|&v| v as usize).collect())
}
