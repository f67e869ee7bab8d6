//! The 3D view's state ([`ViewportState`]: camera, gesture, gizmo, grab, what was last drawn)
//! and its colours and resolution rule. What the view does in a frame (gestures, picking,
//! drags, drawing: re-uploaded only when the mesh changed, at a reduced resolution during
//! interactions on a slow renderer) is in `viewport_ui`, above the app shell.

use super::gizmo::HandleGizmo;
use super::renderer::MeshRenderer;
use crate::camera::OrbitCamera;
use crate::collider::outline;
use crate::command::SelectMode;
use crate::document::GroupKey;
use eframe::egui;
use egui::{Color32, Pos2, Rect};
use glam::{DVec3, Vec3};
use shapeup_core::contact::{ColliderSpec, ShapeSpec};
use shapeup_core::mesh::Mesh;
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// A frame slower than this during an interaction (a software renderer: a GPU takes a few
/// milliseconds) switches the 3D view to [`INTERACTIVE_SCALE`] until the interaction ends.
const SLOW_FRAME: Duration = Duration::from_millis(33);

/// Resolution scale of the 3D view while dragging on a slow renderer: a quarter of the pixels
/// to shade (measured on lavapipe with the 35k-vertex bunny: a frame 69 → 56 ms); the full
/// resolution returns with the first frame after the drag.
const INTERACTIVE_SCALE: f32 = 0.5;

/// The 3D view's resolution scale for this frame: reduced from the first slow frame of an
/// interaction until it ends (not back and forth within one), full otherwise.
pub(super) fn render_scale(interacting: bool, reduced_so_far: bool, last_frame: Option<Duration>) -> (f32, bool) {
    let reduced = interacting && (reduced_so_far || last_frame.is_some_and(|t| t > SLOW_FRAME));
    (if reduced { INTERACTIVE_SCALE } else { 1.0 }, reduced)
}

/// Where the 3D view's image goes: a shape reserved beneath the view's overlays.
pub(super) struct ViewportSlot {
    pub(super) painter: egui::Painter,
    pub(super) shape: egui::layers::ShapeIdx,
    pub(super) rect: Rect,
}

impl ViewportSlot {
    /// Shows `texture` (the rendered mesh) in the slot.
    pub(super) fn show(&self, texture: egui::TextureId) {
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        self.painter.set(self.shape, egui::Shape::image(texture, self.rect, uv, Color32::WHITE));
    }
}

/// Colour of selected vertices.
pub(super) const SELECTED_COLOR: [f32; 3] = [0.15, 0.35, 0.95];
/// Corners of selected faces (face mode).
pub(super) const SELECTED_FACE_COLOR: [f32; 3] = [0.1, 0.75, 0.8];
/// Colour of handle vertices (green, as in the seed editor).
pub const HANDLE_COLOR: [f32; 3] = [0.10, 0.70, 0.25];
/// Colour of the vertices of the group whose row the pointer is over.
pub const HOVER_COLOR: [f32; 3] = [0.95, 0.55, 0.10];
/// Colour of vertices touching a collider or the surface itself.
pub const CONTACT_COLOR: [f32; 3] = [0.85, 0.15, 0.20];
/// Colour of colliders' outlines.
pub(super) const COLLIDER_COLOR: Color32 = Color32::from_rgb(70, 80, 95);
/// Colour of the simulation's floor grid.
pub(super) const FLOOR_COLOR: Color32 = Color32::from_rgb(110, 120, 100);
/// Colour of the selected collider's outline.
pub(super) const SELECTED_COLLIDER_COLOR: Color32 = Color32::from_rgb(235, 130, 20);

/// Viewport interaction in progress.
#[derive(Debug, Clone, Copy)]
pub(super) enum Gesture {
    Orbit,
    Pan,
    BoxSelect {
        /// Where the button went down (not where the first motion was seen).
        start: Pos2,
        mode: SelectMode,
    },
    DragHandle {
        handle: GroupKey,
        anchor: Vec3,
    },
    /// Dynamic mode: pulling the grabbed vertices (`ViewportState::grabbed`) by `offset` from where they
    /// were; `anchor` is the picked vertex's position then.
    Grab {
        anchor: Vec3,
        offset: Vec3,
    },
    RotateHandle {
        handle: GroupKey,
    },
}

/// Where a screenshot's answer waits for the next frame: the file written, or why not.
pub(super) type ScreenshotSlot = Arc<std::sync::Mutex<Option<Result<PathBuf, String>>>>;

/// The 3D view's state: camera, gesture, gizmo, grab, and what was last drawn.
pub(super) struct ViewportState {
    pub(super) camera: OrbitCamera,
    pub(super) wireframe: bool,
    pub(super) gesture: Option<Gesture>,
    pub(super) gizmo: HandleGizmo,
    /// The 3D view is drawn at [`INTERACTIVE_SCALE`] for the interaction under way.
    pub(super) reduced_resolution: bool,
    /// Dynamic mode: the grabbed vertices with their positions at grab time.
    pub(super) grabbed: Vec<(u32, DVec3)>,
    pub(super) renderer: Option<MeshRenderer>,
    pub(super) texture: Option<egui::TextureId>,
    pub(super) uploaded_epoch: Option<(usize, usize)>,
    /// Positions or colours changed since the last upload (uploads cost a normal recomputation
    /// and a buffer write: skip them on frames that only move the camera).
    pub(super) geometry_dirty: bool,
    pub(super) last_render: Option<RenderKey>,
    /// Each collider's outline (input frame) with the description it was made from.
    pub(super) outlines: Vec<(ColliderSpec, Vec<[DVec3; 2]>)>,
    /// Mesh colliders' files as read for drawing (`None`: unreadable).
    pub(super) collider_meshes: HashMap<PathBuf, Option<Arc<Mesh>>>,
    /// Where the 3D view was last laid out (points), for screenshots.
    pub(super) rect: egui::Rect,
    /// The answer of a screenshot under way.
    pub(super) screenshot: ScreenshotSlot,
}

impl ViewportState {
    /// A view of `positions` (input frame) and `triangles` from the front, drawn with
    /// `renderer` (`None`: no wgpu, the view says so).
    pub(super) fn new(renderer: Option<MeshRenderer>, positions: &[DVec3], triangles: &[[u32; 3]]) -> Self {
        let mut camera = OrbitCamera::default();
        camera.frame_front(positions, triangles);
        ViewportState {
            camera,
            wireframe: false,
            gesture: None,
            gizmo: HandleGizmo::new(),
            reduced_resolution: false,
            grabbed: Vec::new(),
            renderer,
            texture: None,
            uploaded_epoch: None,
            geometry_dirty: true,
            last_render: None,
            outlines: Vec::new(),
            collider_meshes: HashMap::new(),
            rect: egui::Rect::NOTHING,
            screenshot: Arc::default(),
        }
    }

    /// The outlines of `colliders` (input frame), made again for those that changed; a plane
    /// is drawn as a square `extent` across.
    pub(super) fn collider_outlines(
        &mut self,
        colliders: &[ColliderSpec],
        extent: f64,
    ) -> &[(ColliderSpec, Vec<[DVec3; 2]>)] {
        self.outlines.truncate(colliders.len());
        for (i, spec) in colliders.iter().enumerate() {
            if self.outlines.get(i).is_some_and(|(s, _)| s == spec) {
                continue;
            }
            let mesh = match &spec.shape {
                ShapeSpec::Mesh { path, .. } => self
                    .collider_meshes
                    .entry(path.clone())
                    .or_insert_with(|| shapeup_core::io::read_mesh(path).ok().map(|m| Arc::new(m.mesh)))
                    .clone(),
                _ => None,
            };
            let lines = outline(spec, mesh.as_deref(), extent);
            if i < self.outlines.len() {
                self.outlines[i] = (spec.clone(), lines);
            } else {
                self.outlines.push((spec.clone(), lines));
            }
        }
        &self.outlines
    }

    /// Whether a 3D renderer exists.
    pub(super) fn has_renderer(&self) -> bool {
        self.renderer.is_some()
    }

    /// A new mesh: framed from the front, uploaded on the next paint, no gesture or grab.
    pub(super) fn show_new_mesh(&mut self, positions: &[DVec3], triangles: &[[u32; 3]]) {
        self.grabbed.clear();
        self.outlines.clear();
        self.uploaded_epoch = None;
        self.geometry_dirty = true;
        self.gesture = None;
        self.camera.frame_front(positions, triangles);
    }
}

/// What the last 3D frame was rendered with: when nothing of it changed, the previous frame is
/// shown again instead of rasterizing the mesh (software renderers share the CPU with the
/// solver).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct RenderKey {
    pub(super) size: (u32, u32),
    pub(super) view_proj: [f32; 16],
    pub(super) light: [f32; 3],
    pub(super) wireframe: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_is_reduced_from_the_first_slow_frame_of_an_interaction_until_it_ends() {
        let slow = Some(SLOW_FRAME + Duration::from_millis(1));
        let fast = Some(Duration::from_millis(5));
        assert_eq!(render_scale(false, false, slow), (1.0, false), "no interaction: full");
        assert_eq!(render_scale(true, false, fast), (1.0, false), "a fast renderer: full");
        assert_eq!(render_scale(true, false, None), (1.0, false));
        assert_eq!(render_scale(true, false, slow), (INTERACTIVE_SCALE, true));
        assert_eq!(render_scale(true, true, fast), (INTERACTIVE_SCALE, true), "no flicker within a drag");
        assert_eq!(render_scale(false, true, slow), (1.0, false), "full again once it ends");
    }
}
