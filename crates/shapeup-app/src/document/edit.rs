//! What each command does to the edit state: [`Document::edit`] dispatches, one function per
//! [`Command`] arm does the work.

use super::Document;
use crate::command::Command;
use crate::edit_state::{EditState, Rest};
use crate::error::{EditorError, GroupError};
use crate::group::{FREE_PIECE_WEIGHT, Group, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE};
use glam::{DQuat, DVec3};
use shapeup_core::constraints::constraint_type;
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
                state.group_mut(handle)?.name = name;
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
        let name = unique_name(state, ty.name());
        let handle = ty.has_targets();
        state.groups.push(Group {
            key: self.new_key(),
            name,
            role: if handle { GroupRole::Handle } else { GroupRole::Other },
            kind: ty.name().into(),
            weight: ty.default_multiplier(),
            targets: if handle { vertices.iter().map(|&v| self.positions[v as usize]).collect() } else { Vec::new() },
            vertices: (!on_faces).then_some(vertices),
            faces: on_faces.then_some(faces),
            options: Arc::new(options),
        });
        Ok(())
    }

    /// [`Command::AddSmoothing`]: a smoothing group (g = 1) on the selected vertices.
    fn add_smoothing(&mut self, state: &mut EditState) -> Result<(), EditorError> {
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
        Ok(())
    }

    /// [`Command::MakeRest`]: the current shape becomes the rest shape.
    fn make_rest(&self, state: &mut EditState) {
        let old = &state.rest;
        let mesh = old.mesh.with_positions(self.positions.clone());
        state.rest = Arc::new(Rest::new(mesh, old.normalize));
    }

    /// [`Command::PinFreePieces`]: one soft handle at rest on every vertex of the pieces no
    /// handle holds (nothing when there are none).
    fn pin_free_pieces(&mut self, state: &mut EditState) {
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
        let vertices: Vec<u32> =
            (0..self.positions.len() as u32).filter(|&v| free[self.pieces.of_vertex[v as usize] as usize]).collect();
        if vertices.is_empty() {
            return;
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
}

/// [`Command::MoveHandle`]: translates a handle's targets.
fn move_handle(state: &mut EditState, handle: GroupKey, delta: DVec3) -> Result<(), EditorError> {
    if !delta.is_finite() {
        return Err(EditorError::BadValue(format!("translation must be finite, found {delta}")));
    }
    state.handle_mut(handle)?.targets.iter_mut().for_each(|t| *t += delta);
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
    group.targets.iter_mut().for_each(|t| *t = center + rotation * (*t - center));
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
    state.group_mut(group)?.weight = weight.clamp(WEIGHT_RANGE.0, WEIGHT_RANGE.1);
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

/// "prefix N" with the smallest N ≥ 1 no group uses.
fn unique_name(state: &EditState, prefix: &str) -> String {
    (1..).map(|k| format!("{prefix} {k}")).find(|name| state.groups.iter().all(|g| &g.name != name)).unwrap_or_default()
}
