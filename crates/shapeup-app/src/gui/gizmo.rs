//! The handle gizmo in the viewport: egui input in, [`GizmoController`] (crate::gizmo) in the
//! middle, an [`egui::Mesh`] out.
//!
//! Why the `transform-gizmo` core crate with this thin adapter rather than
//! `transform-gizmo-egui`: its 0.9 release needs egui 0.34 and 0.11 needs egui 0.36 and Rust
//! 1.96, while this editor pins egui 0.37 and Rust 1.95. The core crate (MIT OR Apache-2.0,
//! Rust ≥ 1.92) depends on no egui, only on epaint/emath/ecolor 0.34 for tessellation; its draw
//! data (positions, linear premultiplied colours, indices) converts to an egui 0.37 mesh here.
//! Its egui adapter also claims every drag under the cursor with a 1-pixel widget; here the
//! pointer is read without a widget and [`GizmoOutput::hovered`] tells the viewport to hold
//! back its own gestures instead.

use crate::camera::OrbitCamera;
use crate::document::GroupKey;
use crate::gizmo::{GizmoController, GizmoDrawData, GizmoTarget, PointerState};
pub use crate::gizmo::{GizmoOutput, GizmoTool};
use eframe::egui;
use glam::{DVec3, Vec2};

/// The gizmo on the selected handle, kept across frames (keep one in the app's view state).
#[derive(Debug, Clone, Default)]
pub struct HandleGizmo {
    controller: GizmoController,
}

impl HandleGizmo {
    /// A gizmo showing arrows, squares and rings.
    pub fn new() -> Self {
        Self::default()
    }

    /// The model, for tests and for code that drives the gizmo without egui input.
    pub fn controller(&self) -> &GizmoController {
        &self.controller
    }

    /// The parts shown.
    pub fn tool(&self) -> GizmoTool {
        self.controller.tool()
    }

    /// Shows other parts from the next frame.
    pub fn set_tool(&mut self, tool: GizmoTool) {
        self.controller.set_tool(tool);
    }

    /// A row of toggles for [`GizmoTool`] (e.g. for the side panel).
    pub fn tool_selector(&mut self, ui: &mut egui::Ui) {
        let mut tool = self.tool();
        ui.horizontal(|ui| {
            ui.label("gizmo:");
            for t in GizmoTool::ALL {
                ui.selectable_value(&mut tool, t, t.label());
            }
        });
        self.set_tool(tool);
    }

    /// Whether a gizmo drag is in progress.
    pub fn is_dragging(&self) -> bool {
        self.controller.is_dragging()
    }

    /// Whether the gizmo wanted the pointer at the last [`HandleGizmo::show`] (a part hovered or
    /// a drag in progress): for viewport code that runs before this frame's `show`.
    pub fn claims_pointer(&self) -> bool {
        self.controller.claims_pointer()
    }

    /// Forgets a drag in progress (see [`GizmoController::cancel`]); returns whether there was
    /// one, in which case the caller ends the document's drag itself.
    pub fn cancel(&mut self) -> bool {
        self.controller.cancel()
    }

    /// Draws the gizmo at `center` (the handle's target centroid, input frame) in the viewport
    /// `rect` seen by `camera`, and turns a drag on one of its parts into this frame's
    /// `MoveHandle`/`RotateHandle` commands for `handle`. A primary press without modifiers on a
    /// part starts a drag, also with shift held (alt-drags and ctrl box selection keep working on
    /// top of the gizmo); holding shift during the drag snaps. `scale_hint` is a length typical of the
    /// scene (the mesh's bounding-box diagonal), for the snapping step.
    ///
    /// Call it every frame a handle is selected, after the mesh image is painted.
    pub fn show(
        &mut self,
        ui: &egui::Ui,
        rect: egui::Rect,
        camera: &OrbitCamera,
        handle: GroupKey,
        center: DVec3,
        scale_hint: f64,
    ) -> GizmoOutput {
        let pointer = pointer_state(ui, rect, self.is_dragging());
        let viewport = Vec2::new(rect.width(), rect.height());
        let target = GizmoTarget { handle, center, scale_hint };
        let output = self.controller.update(camera, viewport, ui.ctx().pixels_per_point(), target, pointer);
        let mesh = to_egui_mesh(self.controller.draw_data(), rect.min.to_vec2());
        if !mesh.is_empty() {
            ui.painter_at(rect).add(egui::Shape::mesh(mesh));
        }
        output
    }
}

/// The primary button and pointer position relative to `rect`'s top-left corner. The position
/// is `None` when the pointer is not over `rect` in this `ui`'s layer (a window covers it),
/// except during a drag, which follows the pointer anywhere.
pub fn pointer_state(ui: &egui::Ui, rect: egui::Rect, dragging: bool) -> PointerState {
    let (pos, pressed, down, modifiers) =
        ui.input(|i| (i.pointer.interact_pos(), i.pointer.primary_pressed(), i.pointer.primary_down(), i.modifiers));
    let over = dragging || ui.rect_contains_pointer(rect);
    PointerState {
        pos: pos.filter(|_| over).map(|p| Vec2::new(p.x - rect.left(), p.y - rect.top())),
        pressed,
        down,
        // Shift on a gizmo part is a snapped gizmo drag (elsewhere, shift+drag pans).
        modifiers: modifiers.alt || modifiers.command || modifiers.ctrl || modifiers.mac_cmd,
        snap: modifiers.shift,
    }
}

/// The gizmo's draw data as an egui mesh, moved by `offset` (the viewport's top-left corner).
pub fn to_egui_mesh(data: GizmoDrawData, offset: egui::Vec2) -> egui::Mesh {
    let vertices = data
        .vertices
        .iter()
        .zip(&data.colors)
        .map(|(&[x, y], &[r, g, b, a])| egui::epaint::Vertex {
            pos: egui::pos2(x, y) + offset,
            uv: egui::epaint::WHITE_UV,
            color: egui::Rgba::from_rgba_premultiplied(r, g, b, a).into(),
        })
        .collect::<Vec<_>>();
    // Indices past the vertices would make egui panic when painting: drop such triangles.
    let n = vertices.len();
    let indices =
        data.indices.chunks_exact(3).filter(|t| t.iter().all(|&i| (i as usize) < n)).flatten().copied().collect();
    egui::Mesh { indices, vertices, ..Default::default() }
}
