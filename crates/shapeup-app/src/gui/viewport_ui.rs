//! The 3D view in the frame: camera gestures, picking and selection boxes, handle drags and
//! the gizmo (on the active handle, or on the collider picked in the Contact panel), grabs in
//! dynamic mode, the colliders' outlines and the simulation's floor, the error banner, and drawing the mesh (vertices
//! touching something in red). The view's state
//! ([`ViewportState`]) lives in [`super::viewport`], beneath the app shell, so that no import
//! runs back up from the shell's fields to the code that works on them.

use super::app::EditorApp;
use super::renderer::{BASE_COLOR, FrameParams};
use super::viewport::{
    COLLIDER_COLOR, CONTACT_COLOR, FLOOR_COLOR, Gesture, HANDLE_COLOR, HOVER_COLOR, RenderKey, SELECTED_COLLIDER_COLOR,
    SELECTED_COLOR, SELECTED_FACE_COLOR, ViewportSlot, render_scale,
};
use crate::command::{Command, SelectMode};
use crate::document::GroupKey;
use crate::gizmo::{COLLIDER_GIZMO, collider_command};
use crate::picking::{box_select, faces_within, pick_face, pick_vertex, visible_vertices};
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Stroke};
use glam::{Vec2, Vec3};

impl EditorApp {
    /// The 3D view's interaction and overlays; the mesh itself is drawn into the returned slot
    /// (beneath the overlays) once the frame's changes are applied, by [`EditorApp::paint`].
    pub(super) fn show_viewport(&mut self, ui: &mut egui::Ui) -> (Vec<Command>, ViewportSlot) {
        let mut commands = Vec::new();
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        self.viewport.rect = rect;
        let slot = ViewportSlot { painter: ui.painter().clone(), shape: ui.painter().add(egui::Shape::Noop), rect };
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let to_local = |p: Pos2| Vec2::new(p.x - rect.left(), p.y - rect.top());
        let modifiers = ui.input(|i| i.modifiers);
        let positions: Vec<Vec3> = self.document.positions().iter().map(|p| p.as_vec3()).collect();

        if response.drag_started() && !self.viewport.gizmo.claims_pointer() {
            // Where the button went down: egui reports the drag a few pixels later.
            let start = ui
                .input(|i| i.pointer.press_origin())
                .or_else(|| response.interact_pointer_pos())
                .unwrap_or(rect.center());
            let primary = response.drag_started_by(egui::PointerButton::Primary);
            self.viewport.gesture = if primary && modifiers.command {
                // Ctrl+Shift removes; Shift+Left alone already pans, so adding is Ctrl+Alt.
                let mode = if modifiers.shift {
                    SelectMode::Remove
                } else if modifiers.alt {
                    SelectMode::Add
                } else {
                    SelectMode::Replace
                };
                Some(Gesture::BoxSelect { start, mode })
            } else if primary && modifiers.alt && self.simulation.is_some() {
                self.start_grab(to_local(start), viewport)
            } else if primary && modifiers.alt {
                self.handle_under(to_local(start), viewport).map(|(handle, v)| {
                    self.document.begin_drag();
                    self.groups.active_handle = Some(handle);
                    self.contact.selected = None;
                    Gesture::DragHandle { handle, anchor: positions[v as usize] }
                })
            } else if response.drag_started_by(egui::PointerButton::Secondary) && modifiers.alt {
                self.handle_under(to_local(start), viewport).map(|(handle, _)| {
                    self.document.begin_drag();
                    self.groups.active_handle = Some(handle);
                    Gesture::RotateHandle { handle }
                })
            } else if response.drag_started_by(egui::PointerButton::Secondary) || (primary && modifiers.shift) {
                Some(Gesture::Pan)
            } else if primary {
                Some(Gesture::Orbit)
            } else {
                None
            };
        }
        if response.clicked()
            && self.selection.face_mode
            && !self.selection.pick_piece
            && let Some(pos) = response.interact_pointer_pos()
        {
            let mesh = self.document.rest_mesh();
            let picked = pick_face(
                self.document.positions(),
                &mesh.triangles,
                &mesh.triangle_polygon,
                &self.viewport.camera,
                viewport,
                to_local(pos),
            );
            match picked {
                Some(face) => {
                    let mode = if modifiers.shift { SelectMode::Add } else { SelectMode::Replace };
                    commands.push(Command::SelectFaces { faces: vec![face], mode });
                }
                None => self.view.status = "no face under the pointer: click on the mesh".into(),
            }
        }
        if response.clicked()
            && self.selection.pick_piece
            && let Some(pos) = response.interact_pointer_pos()
        {
            let visible =
                visible_vertices(self.document.positions(), self.document.triangles(), &self.viewport.camera, viewport);
            match pick_vertex(self.document.positions(), &visible, &self.viewport.camera, viewport, to_local(pos), 12.0)
            {
                Some(vertex) => {
                    let mode = if modifiers.shift { SelectMode::Add } else { SelectMode::Replace };
                    commands.push(Command::SelectPiece { vertex, mode });
                }
                None => self.view.status = "no vertex under the pointer: click on the mesh".into(),
            }
        }
        let delta = response.drag_delta();
        let delta = Vec2::new(delta.x, delta.y);
        match self.viewport.gesture {
            Some(Gesture::Orbit) => self.viewport.camera.orbit(delta, viewport),
            Some(Gesture::Pan) => self.viewport.camera.pan(delta, viewport),
            Some(Gesture::DragHandle { handle, anchor }) if delta != Vec2::ZERO => {
                let moved = self.viewport.camera.drag_in_view_plane(delta, anchor, viewport);
                self.viewport.gesture = Some(Gesture::DragHandle { handle, anchor: anchor + moved });
                commands.push(Command::MoveHandle { handle, delta: moved.as_dvec3() });
            }
            Some(Gesture::Grab { anchor, offset }) if delta != Vec2::ZERO => {
                let moved = self.viewport.camera.drag_in_view_plane(delta, anchor + offset, viewport);
                let offset = offset + moved;
                self.viewport.gesture = Some(Gesture::Grab { anchor, offset });
                if let Some(runner) = &self.simulation {
                    let d = offset.as_dvec3();
                    runner.grab(
                        self.viewport.grabbed.iter().map(|(v, _)| *v).collect(),
                        self.viewport.grabbed.iter().map(|(_, p)| *p + d).collect(),
                    );
                }
            }
            Some(Gesture::RotateHandle { handle }) if delta.x != 0.0 => {
                // Turn about the view direction through the handle's centroid: horizontal mouse
                // motion, 0.01 rad per pixel.
                let (_, _, forward) = self.viewport.camera.basis();
                commands.push(Command::RotateHandle {
                    handle,
                    axis: forward.as_dvec3(),
                    angle: f64::from(delta.x) * 0.01,
                });
            }
            _ => {}
        }
        if response.drag_stopped() {
            if let (Some(Gesture::BoxSelect { start, mode }), Some(end)) =
                (self.viewport.gesture, response.interact_pointer_pos())
            {
                let vertices = box_select(
                    self.document.positions(),
                    self.document.triangles(),
                    &self.viewport.camera,
                    viewport,
                    to_local(start),
                    to_local(end),
                );
                if self.selection.face_mode {
                    let mesh = self.document.rest_mesh();
                    let faces = faces_within(&mesh.polygons, &vertices, mesh.num_vertices());
                    commands.push(Command::SelectFaces { faces, mode });
                } else {
                    commands.push(Command::Select { vertices, mode });
                }
            }
            if matches!(self.viewport.gesture, Some(Gesture::Grab { .. }))
                && let Some(runner) = &self.simulation
            {
                runner.release();
                self.viewport.grabbed.clear();
            }
            if matches!(self.viewport.gesture, Some(Gesture::DragHandle { .. } | Gesture::RotateHandle { .. })) {
                self.end_drag = true;
            }
            self.viewport.gesture = None;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.viewport.camera.zoom(scroll / 50.0);
            }
        }

        if let (Some(Gesture::BoxSelect { start, .. }), Some(now)) =
            (self.viewport.gesture, response.interact_pointer_pos())
        {
            ui.painter().rect_stroke(
                Rect::from_two_pos(start, now),
                0.0,
                Stroke::new(1.0, Color32::from_rgb(40, 90, 240)),
                egui::StrokeKind::Inside,
            );
        }
        self.paint_colliders(ui, rect);
        commands.extend(self.gizmo(ui, rect));
        self.paint_banner(ui, rect);
        (commands, slot)
    }

    fn colors(&self) -> Vec<[f32; 3]> {
        let selection = self.document.selection();
        let mut colors = vec![BASE_COLOR; self.document.num_vertices()];
        for (c, _) in colors.iter_mut().zip(&self.view.touching).filter(|(_, t)| **t) {
            *c = CONTACT_COLOR;
        }
        for handle in self.document.handles() {
            for &v in handle.vertices().unwrap_or(&[]) {
                colors[v] = HANDLE_COLOR;
            }
        }
        for (v, c) in colors.iter_mut().enumerate() {
            if selection.get(v).copied().unwrap_or(false) {
                *c = SELECTED_COLOR;
            }
        }
        // A selected face shows as its corners (the renderer colours vertices).
        let mesh = self.document.rest_mesh();
        for (corners, _) in mesh.polygons.iter().zip(self.document.face_selection()).filter(|(_, s)| **s) {
            for &v in corners {
                if let Some(c) = colors.get_mut(v as usize) {
                    *c = SELECTED_FACE_COLOR;
                }
            }
        }
        if let Some(group) = self.groups.hovered.and_then(|k| self.document.group(k)) {
            match group.vertices() {
                Some(list) => list.iter().for_each(|&v| colors[v] = HOVER_COLOR),
                None => colors.iter_mut().for_each(|c| *c = HOVER_COLOR),
            }
        }
        colors
    }

    /// The colliders' outlines over the mesh (the selected one highlighted), and the
    /// simulation's floor while one runs with a floor.
    fn paint_colliders(&mut self, ui: &egui::Ui, rect: Rect) {
        let floor = self.simulation.as_ref().and_then(|r| r.floor_height);
        if self.document.colliders().is_empty() && floor.is_none() {
            return;
        }
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let (lo, hi) = self.document.rest_mesh().bounding_box();
        let extent = 3.0 * (hi - lo).length();
        let painter = ui.painter_at(rect);
        let camera = self.viewport.camera;
        let segments = |lines: &[[glam::DVec3; 2]], stroke: Stroke| {
            for [a, b] in lines {
                // Segments with an end behind the camera are left out.
                if let (Some((a, _)), Some((b, _))) =
                    (camera.project(a.as_vec3(), viewport), camera.project(b.as_vec3(), viewport))
                {
                    let at = |p: Vec2| Pos2::new(rect.left() + p.x, rect.top() + p.y);
                    painter.line_segment([at(a), at(b)], stroke);
                }
            }
        };
        if let Some(y) = floor {
            let centre = 0.5 * (lo + hi);
            let grid = crate::collider::plane_grid(glam::DVec3::new(centre.x, y, centre.z), glam::DVec3::Y, extent);
            segments(&grid, Stroke::new(1.0, FLOOR_COLOR));
        }
        let selected = self.contact.selected;
        let outlines = self.viewport.collider_outlines(self.document.colliders(), extent);
        for (i, (_, lines)) in outlines.iter().enumerate() {
            let stroke = if selected == Some(i) {
                Stroke::new(1.5, SELECTED_COLLIDER_COLOR)
            } else {
                Stroke::new(1.0, COLLIDER_COLOR)
            };
            segments(lines, stroke);
        }
    }

    /// The gizmo on the collider picked in the Contact panel (also while simulating), else on
    /// the active handle (static mode only).
    fn gizmo(&mut self, ui: &egui::Ui, rect: Rect) -> Vec<Command> {
        let box_select = matches!(self.viewport.gesture, Some(Gesture::BoxSelect { .. }));
        let collider = self
            .contact
            .selected
            .filter(|_| !box_select)
            .and_then(|i| Some((i, crate::collider::center(self.document.colliders().get(i)?))));
        if let Some((index, center)) = collider {
            let (lo, hi) = self.document.rest_mesh().bounding_box();
            let output =
                self.viewport.gizmo.show(ui, rect, &self.viewport.camera, COLLIDER_GIZMO, center, (hi - lo).length());
            if output.drag_started {
                self.document.begin_drag();
                self.viewport.gesture = None;
            }
            if output.drag_stopped {
                self.end_drag = true;
            }
            return output.commands.into_iter().map(|c| collider_command(index, c)).collect();
        }
        let handle = if self.simulation.is_none() && !matches!(self.viewport.gesture, Some(Gesture::BoxSelect { .. })) {
            let active = self.groups.active_handle.and_then(|k| self.document.handles().find(|h| h.key == k));
            active.or_else(|| self.document.handles().last()).and_then(|h| Some((h.key, h.target_centroid()?)))
        } else {
            None
        };
        let Some((handle, center)) = handle else {
            if self.viewport.gizmo.cancel() {
                self.end_drag = true;
            }
            return Vec::new();
        };
        let (lo, hi) = self.document.rest_mesh().bounding_box();
        let output = self.viewport.gizmo.show(ui, rect, &self.viewport.camera, handle, center, (hi - lo).length());
        if output.drag_started {
            self.document.begin_drag();
            self.viewport.gesture = None;
        }
        if output.drag_stopped {
            self.end_drag = true;
        }
        output.commands
    }

    /// The solve or simulation error over the top of the 3D view.
    fn paint_banner(&self, ui: &egui::Ui, rect: Rect) {
        let Some(text) = &self.view.banner else { return };
        let painter = ui.painter_at(rect);
        let galley = painter.layout(
            text.clone(),
            egui::FontId::proportional(15.0),
            Color32::WHITE,
            (rect.width() - 24.0).max(50.0),
        );
        let banner = Rect::from_min_size(rect.min + egui::vec2(8.0, 8.0), galley.size() + egui::vec2(16.0, 12.0));
        painter.rect_filled(banner, 4.0, Color32::from_rgb(180, 30, 30));
        painter.galley(banner.min + egui::vec2(8.0, 6.0), galley, Color32::WHITE);
    }

    /// Dynamic mode: grabs the visible vertex nearest to `pixel` and those within 3 % of the
    /// mesh's diagonal of it.
    fn start_grab(&mut self, pixel: Vec2, viewport: Vec2) -> Option<Gesture> {
        let positions = self.document.positions();
        let visible = visible_vertices(positions, self.document.triangles(), &self.viewport.camera, viewport);
        let v = pick_vertex(positions, &visible, &self.viewport.camera, viewport, pixel, 12.0)?;
        let (lo, hi) = self.document.rest_mesh().bounding_box();
        let radius = 0.03 * (hi - lo).length();
        let centre = positions[v as usize];
        self.viewport.grabbed = positions
            .iter()
            .enumerate()
            .filter(|(_, p)| (**p - centre).length() <= radius)
            .map(|(i, p)| (i as u32, *p))
            .collect();
        Some(Gesture::Grab { anchor: centre.as_vec3(), offset: Vec3::ZERO })
    }

    /// The handle owning the visible vertex nearest to `pixel` (within 12 px), and that vertex.
    fn handle_under(&self, pixel: Vec2, viewport: Vec2) -> Option<(GroupKey, u32)> {
        let positions = self.document.positions();
        let visible = visible_vertices(positions, self.document.triangles(), &self.viewport.camera, viewport);
        let v = pick_vertex(positions, &visible, &self.viewport.camera, viewport, pixel, 12.0)?;
        self.document.handles().find(|h| h.covers(v)).map(|h| (h.key, v))
    }

    /// Renders the mesh (re-uploaded when the shape or colours changed) and puts it in the
    /// viewport's slot.
    pub(super) fn paint(&mut self, frame: &eframe::Frame, slot: &ViewportSlot) {
        let rect = slot.rect;
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let key = (self.document.num_vertices(), self.document.triangles().len());
        let upload = self.viewport.geometry_dirty || self.viewport.uploaded_epoch != Some(key);
        let colors = if upload { self.colors() } else { Vec::new() };
        let (Some(render_state), Some(renderer)) = (frame.wgpu_render_state(), self.viewport.renderer.as_mut()) else {
            slot.painter.text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "no 3D renderer",
                Default::default(),
                Color32::RED,
            );
            return;
        };
        // Handle and gizmo drags, orbit and pan redraw the mesh every frame (box select does not).
        let interacting = self.document.is_dragging()
            || matches!(self.viewport.gesture, Some(Gesture::Orbit | Gesture::Pan | Gesture::Grab { .. }));
        let (scale, reduced) =
            render_scale(interacting, self.viewport.reduced_resolution, self.metrics.last_frame_busy);
        self.viewport.reduced_resolution = reduced;
        let pixels = slot.painter.ctx().pixels_per_point() * scale;
        let size = ((viewport.x * pixels) as u32, (viewport.y * pixels) as u32);
        let filter = if reduced { wgpu::FilterMode::Linear } else { wgpu::FilterMode::Nearest };
        let positions: Vec<Vec3> =
            if upload { self.document.positions().iter().map(|p| p.as_vec3()).collect() } else { Vec::new() };
        let positions = &positions[..];
        if self.viewport.uploaded_epoch != Some(key) {
            renderer.set_mesh(&render_state.device, positions, self.document.triangles(), &colors);
            self.viewport.uploaded_epoch = Some(key);
        } else if upload {
            renderer.update(&render_state.queue, positions, &colors);
        }
        self.viewport.geometry_dirty = false;
        let camera = &self.viewport.camera;
        let params = FrameParams {
            view_proj: camera.view_projection(viewport),
            light_dir: camera.eye() - camera.target + Vec3::Y * camera.distance * 0.5,
            wireframe: self.viewport.wireframe,
            background: [0.97, 0.97, 0.98],
        };
        let key = RenderKey {
            size,
            view_proj: params.view_proj.to_cols_array(),
            light: params.light_dir.to_array(),
            wireframe: params.wireframe,
        };
        if let Some(id) = self.viewport.texture
            && !upload
            && self.viewport.last_render == Some(key)
        {
            slot.show(id);
            return;
        }
        let Some(view) = renderer.render(&render_state.device, &render_state.queue, size, &params) else { return };
        self.viewport.last_render = Some(key);
        let mut egui_renderer = render_state.renderer.write();
        let id = match self.viewport.texture {
            Some(id) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(&render_state.device, view, filter, id);
                id
            }
            None => {
                let id = egui_renderer.register_native_texture(&render_state.device, view, filter);
                self.viewport.texture = Some(id);
                id
            }
        };
        drop(egui_renderer);
        slot.show(id);
    }
}
