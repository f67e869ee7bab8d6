//! The eframe application: panels on the left, the 3D viewport in the centre. Panels and
//! gestures produce [`Command`]s that are applied to the [`Document`] after the UI pass; solves
//! run on a [`SolverWorker`] thread, so the window keeps redrawing while the solver works.

use super::dialogs::{DialogPurpose, FileDialogs};
use super::renderer::{BASE_COLOR, FrameParams, MeshRenderer};
use crate::camera::OrbitCamera;
use crate::command::{Command, SelectMode};
use crate::document::{Document, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE};
use crate::picking::{box_select, pick_vertex, visible_vertices};
use crate::simulation::{SimulationRunner, SimulationSettings};
use crate::worker::{SolveRequest, SolverWorker};
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Stroke};
use glam::{DVec3, Vec2, Vec3};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::Instant;

const SELECTED_COLOR: [f32; 3] = [0.15, 0.35, 0.95];
/// Colour of handle vertices (green, as in the seed editor).
pub const HANDLE_COLOR: [f32; 3] = [0.10, 0.70, 0.25];
const HOVER_COLOR: [f32; 3] = [0.95, 0.55, 0.10];

/// The bundled sample meshes (name, path relative to the repository root).
pub const SAMPLES: [(&str, &str); 4] = [
    ("Stanford bunny", "data/stanford-bunny.obj"),
    ("Spot", "data/spot.obj"),
    ("Cow", "data/cow.obj"),
    ("Suzanne (quads)", "data/suzanne.obj"),
];

/// A bundled sample's path: relative to the working directory when it exists there, else to
/// the source tree.
pub fn sample_path(relative: &str) -> PathBuf {
    let local = PathBuf::from(relative);
    if local.exists() { local } else { PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(relative) }
}

/// Viewport interaction in progress.
#[derive(Debug, Clone, Copy)]
enum Gesture {
    Orbit,
    Pan,
    BoxSelect {
        start: Pos2,
        mode: SelectMode,
    },
    DragHandle {
        handle: GroupKey,
        anchor: Vec3,
    },
    /// Dynamic mode: pulling the vertices in `EditorApp::grabbed` by `offset` from where they
    /// were; `anchor` is the picked vertex's position then.
    Grab {
        anchor: Vec3,
        offset: Vec3,
    },
    RotateHandle {
        handle: GroupKey,
    },
}

/// UI-only state (nothing here changes the solve).
struct View {
    camera: OrbitCamera,
    wireframe: bool,
    gesture: Option<Gesture>,
    hovered_group: Option<GroupKey>,
    renaming: Option<(GroupKey, String)>,
    status: String,
    path_input: String,
    export_input: String,
    scene_input: String,
    energy_history: VecDeque<f64>,
    last_local_ms: f64,
    last_global_ms: f64,
    solves: VecDeque<Instant>,
    solves_applied: u64,
    frames: VecDeque<Instant>,
}

/// Options of the editor window.
#[derive(Debug, Clone, Copy, Default)]
pub struct WindowOptions {
    /// Print frames/s, solves/s and solve times to stderr once per second (for measuring).
    pub print_stats: bool,
}

/// What the last 3D frame was rendered with: when nothing of it changed, the previous frame is
/// shown again instead of rasterizing the mesh (software renderers share the CPU with the
/// solver).
#[derive(Debug, Clone, Copy, PartialEq)]
struct RenderKey {
    size: (u32, u32),
    view_proj: [f32; 16],
    light: [f32; 3],
    wireframe: bool,
}

/// The editor window.
pub struct EditorApp {
    document: Document,
    mesh_path: PathBuf,
    view: View,
    worker: Option<SolverWorker>,
    renderer: Option<MeshRenderer>,
    texture: Option<egui::TextureId>,
    uploaded_epoch: Option<(usize, usize)>,
    /// Positions or colours changed since the last upload (uploads cost a normal recomputation
    /// and a buffer write: skip them on frames that only move the camera).
    geometry_dirty: bool,
    last_render: Option<RenderKey>,
    options: WindowOptions,
    last_stats_print: Instant,
    dialogs: FileDialogs,
    /// Dynamic mode: what to simulate, the running simulation, and the grabbed vertices with
    /// their positions at grab time.
    dynamics: SimulationSettings,
    simulation: Option<SimulationRunner>,
    grabbed: Vec<(u32, DVec3)>,
}

impl EditorApp {
    /// The editor on a document (e.g. from `Document::open`), for eframe.
    pub fn new(cc: &eframe::CreationContext<'_>, document: Document, mesh_path: PathBuf) -> Self {
        Self::with_options(cc, document, mesh_path, WindowOptions::default())
    }

    /// The editor with options.
    pub fn with_options(
        cc: &eframe::CreationContext<'_>,
        document: Document,
        mesh_path: PathBuf,
        options: WindowOptions,
    ) -> Self {
        let renderer = cc.wgpu_render_state.as_ref().map(|rs| MeshRenderer::new(&rs.device));
        let mut camera = OrbitCamera::with_angles(super::INITIAL_YAW, super::INITIAL_PITCH);
        frame_camera(&mut camera, &document);
        EditorApp {
            view: View {
                camera,
                wireframe: false,
                gesture: None,
                hovered_group: None,
                renaming: None,
                status: if renderer.is_some() {
                    format!("opened {}", mesh_path.display())
                } else {
                    "no wgpu renderer: the 3D view is unavailable".into()
                },
                path_input: mesh_path.display().to_string(),
                export_input: "deformed.obj".into(),
                scene_input: "session.toml".into(),
                energy_history: VecDeque::new(),
                last_local_ms: 0.0,
                last_global_ms: 0.0,
                solves: VecDeque::new(),
                solves_applied: 0,
                frames: VecDeque::new(),
            },
            document,
            mesh_path,
            // Each result wakes the UI, so nothing needs to redraw continuously while waiting.
            worker: {
                let ctx = cc.egui_ctx.clone();
                SolverWorker::spawn_with_notify(move || ctx.request_repaint()).ok()
            },
            renderer,
            texture: None,
            uploaded_epoch: None,
            geometry_dirty: true,
            last_render: None,
            options,
            last_stats_print: Instant::now(),
            dialogs: FileDialogs::default(),
            dynamics: SimulationSettings::default(),
            simulation: None,
            grabbed: Vec::new(),
        }
    }

    /// The document being edited.
    pub fn document(&self) -> &Document {
        &self.document
    }

    /// How many solver results the document has taken since the editor started.
    pub fn solves_applied(&self) -> u64 {
        self.view.solves_applied
    }

    fn apply(&mut self, commands: Vec<Command>) {
        let mut changed = false;
        for command in commands {
            // Moving targets or changing weights changes nothing drawn until the solve returns.
            self.geometry_dirty |= !matches!(
                command,
                Command::MoveHandle { .. }
                    | Command::RotateHandle { .. }
                    | Command::SetWeight { .. }
                    | Command::SetIterations(_)
                    | Command::RenameHandle { .. }
            );
            let solve = !matches!(
                command,
                Command::Select { .. }
                    | Command::ClearSelection
                    | Command::SelectBoundary(_)
                    | Command::RenameHandle { .. }
            );
            match self.document.apply(command) {
                Ok(()) => changed |= solve,
                Err(e) => self.view.status = e.to_string(),
            }
        }
        if changed {
            // The simulation was built from the old constraints.
            if self.simulation.take().is_some() {
                self.view.status = "simulation stopped: the constraints changed".into();
            }
            self.request_solve();
        }
    }

    /// Whether dynamic mode is on (a simulation exists, running or paused).
    pub fn is_simulating(&self) -> bool {
        self.simulation.is_some()
    }

    /// Whether the simulation is stepping.
    pub fn is_running(&self) -> bool {
        self.simulation.as_ref().is_some_and(SimulationRunner::is_running)
    }

    fn dynamics_panel(&mut self, ui: &mut egui::Ui) {
        let running = self.simulation.as_ref().is_some_and(SimulationRunner::is_running);
        let mut settings = self.dynamics;
        ui.horizontal_wrapped(|ui| {
            ui.checkbox(&mut settings.gravity, "Gravity");
            ui.checkbox(&mut settings.floor, "Floor");
            let tetgen = cfg!(feature = "tetgen");
            ui.add_enabled(tetgen, egui::Checkbox::new(&mut settings.tetrahedralize, "Tetrahedralize"))
                .on_disabled_hover_text("this build has no TetGen (cargo feature `tetgen`)")
                .on_hover_text("fill the closed surface with tetrahedra (TetGen)");
        });
        ui.add(egui::Slider::new(&mut settings.damping, 0.0..=0.5).text("damping"));
        if settings != self.dynamics {
            self.dynamics = settings;
            // New settings, new simulation (from the current shape).
            self.simulation = None;
        }
        ui.horizontal_wrapped(|ui| {
            if ui.button(if running { "Pause" } else { "Run" }).clicked() {
                if self.simulation.is_none() {
                    let ctx = ui.ctx().clone();
                    match SimulationRunner::start(&self.document, self.dynamics, move || ctx.request_repaint()) {
                        Ok(runner) => self.simulation = Some(runner),
                        Err(e) => self.view.status = e.to_string(),
                    }
                }
                if let Some(runner) = &self.simulation {
                    runner.set_running(!running);
                }
            }
            if ui.add_enabled(self.simulation.is_some(), egui::Button::new("Restart")).clicked()
                && let Some(runner) = &self.simulation
            {
                runner.reset();
            }
            if ui
                .add_enabled(self.simulation.is_some(), egui::Button::new("Stop"))
                .on_hover_text("leave dynamic mode, keeping the current shape")
                .clicked()
            {
                self.simulation = None;
            }
        });
        if let Some(runner) = &self.simulation {
            let (steps, ms, error) = runner.stats();
            let tets = if runner.num_tetrahedra > 0 {
                format!(", {} tetrahedra", runner.num_tetrahedra)
            } else {
                String::new()
            };
            ui.label(format!("{steps} steps, {ms:.1} ms per step{tets}"));
            if let Some(e) = error {
                ui.colored_label(Color32::RED, e);
            }
            ui.label("alt+left drag: grab and pull the mesh");
        }
    }

    fn poll_simulation(&mut self) {
        if let Some(positions) = self.simulation.as_ref().and_then(SimulationRunner::poll)
            && self.document.accept_positions(self.document.epoch(), &positions)
        {
            self.geometry_dirty = true;
        }
    }

    fn request_solve(&mut self) {
        if !self.document.state().has_handles() {
            return;
        }
        // One round per change: measured on 2 cores with software rendering, iterating on
        // between mouse moves took frames from the renderer without adding updates per second.
        match &mut self.worker {
            Some(worker) => {
                worker.request(SolveRequest::from_document(&self.document));
            }
            None => {
                if let Err(e) = self.document.solve(self.document.iterations()) {
                    self.view.status = e.to_string();
                }
            }
        }
    }

    fn poll_worker(&mut self) {
        let Some(worker) = &mut self.worker else { return };
        while let Some(result) = worker.poll() {
            if let Some(e) = &result.error {
                self.view.status = e.to_string();
            }
            if result.apply_to(&mut self.document) {
                self.geometry_dirty = true;
                self.view.last_local_ms = result.local_ms;
                self.view.last_global_ms = result.global_ms;
                self.view.energy_history.extend(result.energy.iter().copied());
                while self.view.energy_history.len() > 300 {
                    self.view.energy_history.pop_front();
                }
                self.view.solves.push_back(Instant::now());
                self.view.solves_applied += 1;
            }
        }
    }

    fn open(&mut self, path: PathBuf) {
        let is_scene = path.extension().and_then(|e| e.to_str()).is_some_and(|e| matches!(e, "toml" | "json"));
        let opened = if is_scene {
            shapeup_core::scene::Scene::from_file(&path)
                .map_err(|e| e.to_string())
                .and_then(|s| Document::from_scene(&s).map_err(|e| e.to_string()))
        } else {
            Document::open(&path, ShapeModel::EdgeSprings).map_err(|e| e.to_string())
        };
        match opened {
            Ok(document) => {
                self.document = document;
                self.mesh_path = path.clone();
                self.uploaded_epoch = None;
                self.geometry_dirty = true;
                frame_camera(&mut self.view.camera, &self.document);
                self.view.energy_history.clear();
                self.view.status = format!("opened {}", path.display());
            }
            Err(e) => self.view.status = e,
        }
    }

    fn export_mesh(&mut self, path: PathBuf) {
        self.view.status = match shapeup_core::io::write_mesh(&path, &self.document.current_mesh()) {
            Ok(warnings) if warnings.is_empty() => format!("wrote {}", path.display()),
            // What the format could not keep (or recomputed), said once each.
            Ok(warnings) => {
                let said: Vec<String> = warnings.iter().map(ToString::to_string).collect();
                format!("wrote {}; {}", path.display(), said.join("; "))
            }
            Err(e) => e.to_string(),
        };
        self.view.export_input = path.display().to_string();
    }

    fn save_scene(&mut self, path: PathBuf) {
        let mesh = std::fs::canonicalize(&self.mesh_path).unwrap_or_else(|_| self.mesh_path.clone());
        self.view.status = match self.document.save_scene(&path, mesh) {
            Ok(()) => format!("saved {}", path.display()),
            Err(e) => e.to_string(),
        };
        self.view.scene_input = path.display().to_string();
    }

    /// Opens a native dialog (on its own thread) starting next to the current mesh.
    fn show_dialog(&mut self, ctx: &egui::Context, purpose: DialogPurpose) {
        let directory = std::fs::canonicalize(&self.mesh_path).ok().and_then(|p| p.parent().map(PathBuf::from));
        let proposed = match purpose {
            DialogPurpose::Open => String::new(),
            DialogPurpose::ExportMesh => file_name_of(&self.view.export_input),
            DialogPurpose::SaveScene => file_name_of(&self.view.scene_input),
        };
        let ctx = ctx.clone();
        self.dialogs.show(purpose, directory, &proposed, move || ctx.request_repaint());
    }

    /// Opens, exports or saves to `path`, whether it came from a dialog or was typed.
    fn act_on_path(&mut self, purpose: DialogPurpose, path: PathBuf) {
        match purpose {
            DialogPurpose::Open => self.open(path),
            DialogPurpose::ExportMesh => self.export_mesh(path),
            DialogPurpose::SaveScene => self.save_scene(path),
        }
    }

    /// One file row: the dialog button, the typed path, and the button acting on the typed path.
    fn path_row(&mut self, ui: &mut egui::Ui, purpose: DialogPurpose) {
        let (browse_label, act_label, hint) = match purpose {
            DialogPurpose::Open => ("Open…", "Open", "open the typed path"),
            DialogPurpose::ExportMesh => ("Export…", "Export mesh", "write OBJ, PLY or STL to the typed path"),
            DialogPurpose::SaveScene => ("Save…", "Save scene", "a scene file that shapeup deform replays"),
        };
        ui.horizontal(|ui| {
            let browse = ui.add_enabled(!self.dialogs.is_open(), egui::Button::new(browse_label));
            if browse.clicked() {
                self.show_dialog(ui.ctx(), purpose);
            }
            let typed = match purpose {
                DialogPurpose::Open => &mut self.view.path_input,
                DialogPurpose::ExportMesh => &mut self.view.export_input,
                DialogPurpose::SaveScene => &mut self.view.scene_input,
            };
            ui.text_edit_singleline(typed).labelled_by(browse.id);
            if ui.button(act_label).on_hover_text(hint).clicked() {
                let path = PathBuf::from(typed.trim());
                self.act_on_path(purpose, path);
            }
        });
    }

    fn poll_dialogs(&mut self) {
        match self.dialogs.poll() {
            Some((purpose, Some(path))) => self.act_on_path(purpose, path),
            Some((_, None)) => {
                self.view.status = "no file chosen (without a file dialog service, type the path instead)".into();
            }
            None => {}
        }
    }

    fn colors(&self) -> Vec<[f32; 3]> {
        let selection = self.document.selection();
        let mut colors = vec![BASE_COLOR; self.document.num_vertices()];
        for handle in self.document.handles() {
            for &v in handle.vertices().unwrap_or(&[]) {
                colors[v as usize] = HANDLE_COLOR;
            }
        }
        for (v, c) in colors.iter_mut().enumerate() {
            if selection.get(v).copied().unwrap_or(false) {
                *c = SELECTED_COLOR;
            }
        }
        if let Some(group) = self.view.hovered_group.and_then(|k| self.document.group(k)) {
            match group.vertices() {
                Some(list) => list.iter().for_each(|&v| colors[v as usize] = HOVER_COLOR),
                None => colors.iter_mut().for_each(|c| *c = HOVER_COLOR),
            }
        }
        colors
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) -> Vec<Command> {
        let mut commands = Vec::new();
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("shapeup");
            egui::CollapsingHeader::new("Mesh").default_open(true).show(ui, |ui| {
                self.path_row(ui, DialogPurpose::Open);
                ui.label("or drop a mesh or scene file on the window");
                ui.menu_button("Sample meshes", |ui| {
                    for (name, relative) in SAMPLES {
                        if ui.button(name).clicked() {
                            self.open(sample_path(relative));
                            ui.close();
                        }
                    }
                });
            });
            ui.separator();
            ui.collapsing("Mouse", |ui| {
                ui.label(
                    "left drag: orbit · right or shift+left drag: pan · wheel: zoom\n\
                     ctrl+left drag: select visible vertices in a box (ctrl+alt adds, ctrl+shift removes)\n\
                     alt+left drag on a handle: move it · alt+right drag: rotate it\n\
                     dynamics running: alt+left drag grabs and pulls the mesh\n\
                     ctrl+z / ctrl+shift+z: undo / redo",
                );
            });
            ui.label(format!("{} vertices selected", self.document.num_selected()));
            ui.horizontal_wrapped(|ui| {
                if ui.button("Fix selection").clicked() {
                    commands.push(Command::FixSelection);
                }
                if ui.button("Clear selection").clicked() {
                    commands.push(Command::ClearSelection);
                }
                if ui.button("Select boundary").clicked() {
                    commands.push(Command::SelectBoundary(SelectMode::Replace));
                }
                if ui.button("Add smoothing to selection").clicked() {
                    commands.push(Command::AddSmoothing);
                }
            });
            ui.separator();
            ui.label("Shape constraints");
            let current = self.document.shape_model();
            for model in [ShapeModel::EdgeSprings, ShapeModel::StrainBending, ShapeModel::IsoOneRing] {
                if ui.radio(current == Some(model), model.label()).clicked() && current != Some(model) {
                    commands.push(Command::SetShapeModel(model));
                }
            }
            ui.separator();
            ui.label("Groups (hover to highlight)");
            let previously_hovered = self.view.hovered_group.take();
            let groups: Vec<_> = self.document.groups().to_vec();
            for group in &groups {
                let row = ui.horizontal(|ui| {
                    ui.label(format!("{} ({})", group.name, group.kind));
                    let mut weight = group.weight;
                    let slider = egui::Slider::new(&mut weight, WEIGHT_RANGE.0..=WEIGHT_RANGE.1)
                        .logarithmic(true)
                        .text("weight");
                    if ui.add(slider).changed() {
                        commands.push(Command::SetWeight { group: group.key, weight });
                    }
                    if group.role == GroupRole::Handle && ui.small_button("rename").clicked() {
                        self.view.renaming = Some((group.key, group.name.clone()));
                    }
                    if group.role != GroupRole::Shape && ui.small_button("remove").clicked() {
                        commands.push(Command::RemoveGroup(group.key));
                    }
                });
                if row.response.hovered() {
                    self.view.hovered_group = Some(group.key);
                }
            }
            if let Some((key, name)) = &mut self.view.renaming {
                let key = *key;
                let done = ui
                    .horizontal(|ui| {
                        let label = ui.label("new name");
                        let edit = ui.text_edit_singleline(name).labelled_by(label.id);
                        edit.lost_focus() || ui.button("OK").clicked()
                    })
                    .inner;
                if done {
                    commands.push(Command::RenameHandle { handle: key, name: name.clone() });
                    self.view.renaming = None;
                }
            }
            if self.view.hovered_group != previously_hovered {
                self.geometry_dirty = true;
            }
            if ui.button("Clear handles").clicked() {
                commands.push(Command::ClearHandles);
            }
            ui.separator();
            let mut iterations = self.document.iterations();
            if ui.add(egui::Slider::new(&mut iterations, 1..=100).text("iterations per update")).changed() {
                commands.push(Command::SetIterations(iterations));
            }
            ui.horizontal_wrapped(|ui| {
                if ui.button("Reset shape").clicked() {
                    commands.push(Command::ResetShape);
                }
                if ui.button("Make rest shape").clicked() {
                    commands.push(Command::MakeRest);
                }
                if ui.add_enabled(self.document.can_undo(), egui::Button::new("Undo")).clicked() {
                    commands.push(Command::Undo);
                }
                if ui.add_enabled(self.document.can_redo(), egui::Button::new("Redo")).clicked() {
                    commands.push(Command::Redo);
                }
            });
            self.path_row(ui, DialogPurpose::ExportMesh);
            self.path_row(ui, DialogPurpose::SaveScene);
            ui.separator();
            egui::CollapsingHeader::new("Dynamics").default_open(true).show(ui, |ui| self.dynamics_panel(ui));
            ui.separator();
            ui.checkbox(&mut self.view.wireframe, "Wireframe");
            if ui.button("Reset view").clicked() {
                frame_camera(&mut self.view.camera, &self.document);
            }
            ui.separator();
            self.stats(ui);
            ui.separator();
            ui.label(&self.view.status);
        });
        commands
    }

    fn stats(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        for q in [&mut self.view.solves, &mut self.view.frames] {
            while q.front().is_some_and(|t| now.duration_since(*t).as_secs_f64() > 1.0) {
                q.pop_front();
            }
        }
        ui.label(format!(
            "{} vertices, {} triangles\nlocal {:.1} ms, global {:.1} ms per solve\n{} solves/s, {} frames/s",
            self.document.num_vertices(),
            self.document.triangles().len(),
            self.view.last_local_ms,
            self.view.last_global_ms,
            self.view.solves.len(),
            self.view.frames.len(),
        ));
        // Energy over recent iterations, log scale.
        let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), Sense::hover());
        let painter = ui.painter_at(rect);
        painter.rect_stroke(rect, 2.0, Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Inside);
        let logs: Vec<f64> = self.view.energy_history.iter().filter(|e| **e > 0.0).map(|e| e.log10()).collect();
        if logs.len() >= 2 {
            let (lo, hi) = logs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
            let span = (hi - lo).max(1e-9);
            let points: Vec<Pos2> = logs
                .iter()
                .enumerate()
                .map(|(i, &e)| {
                    let x = rect.left() + rect.width() * i as f32 / (logs.len() - 1) as f32;
                    let y = rect.bottom() - rect.height() * ((e - lo) / span) as f32;
                    Pos2::new(x, y)
                })
                .collect();
            painter.add(egui::Shape::line(points, Stroke::new(1.5, Color32::LIGHT_BLUE)));
        }
        ui.label("energy (log) over recent iterations");
    }

    fn viewport(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame) -> Vec<Command> {
        let mut commands = Vec::new();
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let to_local = |p: Pos2| Vec2::new(p.x - rect.left(), p.y - rect.top());
        let modifiers = ui.input(|i| i.modifiers);
        let positions: Vec<Vec3> = self.document.positions().iter().map(|p| p.as_vec3()).collect();

        if response.drag_started() {
            let start = response.interact_pointer_pos().unwrap_or(rect.center());
            let primary = response.drag_started_by(egui::PointerButton::Primary);
            self.view.gesture = if primary && modifiers.command {
                // Ctrl+Shift removes (as the editor issue asks); Shift+Left alone already pans,
                // so adding to the selection is Ctrl+Alt.
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
                    Gesture::DragHandle { handle, anchor: positions[v as usize] }
                })
            } else if response.drag_started_by(egui::PointerButton::Secondary) && modifiers.alt {
                self.handle_under(to_local(start), viewport).map(|(handle, _)| {
                    self.document.begin_drag();
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
        let delta = response.drag_delta();
        let delta = Vec2::new(delta.x, delta.y);
        match self.view.gesture {
            Some(Gesture::Orbit) => self.view.camera.orbit(delta, viewport),
            Some(Gesture::Pan) => self.view.camera.pan(delta, viewport),
            Some(Gesture::DragHandle { handle, anchor }) if delta != Vec2::ZERO => {
                let moved = self.view.camera.drag_in_view_plane(delta, anchor, viewport);
                self.view.gesture = Some(Gesture::DragHandle { handle, anchor: anchor + moved });
                commands.push(Command::MoveHandle { handle, delta: moved.as_dvec3() });
            }
            Some(Gesture::Grab { anchor, offset }) if delta != Vec2::ZERO => {
                let moved = self.view.camera.drag_in_view_plane(delta, anchor + offset, viewport);
                let offset = offset + moved;
                self.view.gesture = Some(Gesture::Grab { anchor, offset });
                if let Some(runner) = &self.simulation {
                    let d = offset.as_dvec3();
                    runner.grab(
                        self.grabbed.iter().map(|(v, _)| *v).collect(),
                        self.grabbed.iter().map(|(_, p)| *p + d).collect(),
                    );
                }
            }
            Some(Gesture::RotateHandle { handle }) if delta.x != 0.0 => {
                // Turn about the view direction through the handle's centroid: horizontal mouse
                // motion, 0.01 rad per pixel.
                let (_, _, forward) = self.view.camera.basis();
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
                (self.view.gesture, response.interact_pointer_pos())
            {
                let vertices = box_select(
                    self.document.positions(),
                    self.document.triangles(),
                    &self.view.camera,
                    viewport,
                    to_local(start),
                    to_local(end),
                );
                commands.push(Command::Select { vertices, mode });
            }
            if matches!(self.view.gesture, Some(Gesture::Grab { .. }))
                && let Some(runner) = &self.simulation
            {
                runner.release();
                self.grabbed.clear();
            }
            let released = matches!(self.view.gesture, Some(Gesture::DragHandle { .. } | Gesture::RotateHandle { .. }));
            self.view.gesture = None;
            if released {
                self.document.end_drag();
                // One more round on the final targets.
                self.request_solve();
            }
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.view.camera.zoom(scroll / 50.0);
            }
        }

        self.paint(ui, frame, rect, &positions, viewport);
        if let (Some(Gesture::BoxSelect { start, .. }), Some(now)) =
            (self.view.gesture, response.interact_pointer_pos())
        {
            ui.painter().rect_stroke(
                Rect::from_two_pos(start, now),
                0.0,
                Stroke::new(1.0, Color32::from_rgb(40, 90, 240)),
                egui::StrokeKind::Inside,
            );
        }
        commands
    }

    /// Dynamic mode: grabs the visible vertex nearest to `pixel` and those within 3 % of the
    /// mesh's diagonal of it.
    fn start_grab(&mut self, pixel: Vec2, viewport: Vec2) -> Option<Gesture> {
        let positions = self.document.positions();
        let visible = visible_vertices(positions, self.document.triangles(), &self.view.camera, viewport);
        let v = pick_vertex(positions, &visible, &self.view.camera, viewport, pixel, 12.0)?;
        let (lo, hi) = self.document.rest_mesh().bounding_box();
        let radius = 0.03 * (hi - lo).length();
        let centre = positions[v as usize];
        self.grabbed = positions
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
        let visible = visible_vertices(positions, self.document.triangles(), &self.view.camera, viewport);
        let v = pick_vertex(positions, &visible, &self.view.camera, viewport, pixel, 12.0)?;
        self.document.handles().find(|h| h.covers(v)).map(|h| (h.key, v))
    }

    fn paint(&mut self, ui: &mut egui::Ui, frame: &eframe::Frame, rect: Rect, positions: &[Vec3], viewport: Vec2) {
        let key = (self.document.num_vertices(), self.document.triangles().len());
        let upload = self.geometry_dirty || self.uploaded_epoch != Some(key);
        let colors = if upload { self.colors() } else { Vec::new() };
        let (Some(render_state), Some(renderer)) = (frame.wgpu_render_state(), self.renderer.as_mut()) else {
            ui.painter().text(
                rect.center(),
                egui::Align2::CENTER_CENTER,
                "no 3D renderer",
                Default::default(),
                Color32::RED,
            );
            return;
        };
        let pixels_per_point = ui.ctx().pixels_per_point();
        let size = ((viewport.x * pixels_per_point) as u32, (viewport.y * pixels_per_point) as u32);
        if self.uploaded_epoch != Some(key) {
            renderer.set_mesh(&render_state.device, positions, self.document.triangles(), &colors);
            self.uploaded_epoch = Some(key);
        } else if upload {
            renderer.update(&render_state.queue, positions, &colors);
        }
        self.geometry_dirty = false;
        let camera = &self.view.camera;
        let params = FrameParams {
            view_proj: camera.view_projection(viewport),
            light_dir: camera.eye() - camera.target + Vec3::Y * camera.distance * 0.5,
            wireframe: self.view.wireframe,
            background: [0.97, 0.97, 0.98],
        };
        let key = RenderKey {
            size,
            view_proj: params.view_proj.to_cols_array(),
            light: params.light_dir.to_array(),
            wireframe: params.wireframe,
        };
        if let Some(id) = self.texture
            && !upload
            && self.last_render == Some(key)
        {
            ui.painter().image(id, rect, Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)), Color32::WHITE);
            return;
        }
        let Some(view) = renderer.render(&render_state.device, &render_state.queue, size, &params) else { return };
        self.last_render = Some(key);
        let mut egui_renderer = render_state.renderer.write();
        let id = match self.texture {
            Some(id) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(
                    &render_state.device,
                    view,
                    wgpu::FilterMode::Linear,
                    id,
                );
                id
            }
            None => {
                let id = egui_renderer.register_native_texture(&render_state.device, view, wgpu::FilterMode::Linear);
                self.texture = Some(id);
                id
            }
        };
        drop(egui_renderer);
        ui.painter().image(id, rect, Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)), Color32::WHITE);
    }
}

/// The file name part of a typed path, proposed by save dialogs.
fn file_name_of(typed: &str) -> String {
    std::path::Path::new(typed.trim()).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

fn frame_camera(camera: &mut OrbitCamera, document: &Document) {
    let (lo, hi) = document
        .positions()
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    camera.frame(lo.as_vec3(), hi.as_vec3());
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.view.frames.push_back(Instant::now());
        self.poll_worker();
        self.poll_simulation();
        self.poll_dialogs();
        let dropped: Vec<PathBuf> = ui.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).collect());
        if let Some(path) = dropped.into_iter().next() {
            self.open(path);
        }
        let (undo, redo) = ui.input_mut(|i| {
            let redo = i.consume_key(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
            let undo = i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z);
            (undo, redo)
        });
        let mut commands = Vec::new();
        if redo {
            commands.push(Command::Redo);
        } else if undo {
            commands.push(Command::Undo);
        }
        let panel = egui::Panel::left("controls").default_size(300.0).show(ui, |ui| self.side_panel(ui));
        commands.extend(panel.inner);
        let viewport = egui::CentralPanel::no_frame().show(ui, |ui| self.viewport(ui, frame));
        commands.extend(viewport.inner);
        self.apply(commands);
        if self.options.print_stats {
            self.print_stats(ui.ctx());
        }
    }
}

impl EditorApp {
    /// One line per second on stderr: frames/s, solves/s, last solve times.
    fn print_stats(&mut self, ctx: &egui::Context) {
        use std::io::Write as _;
        let now = Instant::now();
        if now.duration_since(self.last_stats_print).as_secs_f64() >= 1.0 {
            self.last_stats_print = now;
            let count =
                |q: &VecDeque<Instant>| q.iter().filter(|t| now.duration_since(**t).as_secs_f64() <= 1.0).count();
            // Best effort: a closed stderr must not stop the editor.
            let _ = writeln!(
                std::io::stderr().lock(),
                "stats: {} frames/s, {} solves/s, local {:.1} ms, global {:.1} ms",
                count(&self.view.frames),
                count(&self.view.solves),
                self.view.last_local_ms,
                self.view.last_global_ms,
            );
        }
        // Keep printing when idle.
        ctx.request_repaint_after(std::time::Duration::from_millis(250));
    }
}

/// Opens the editor window on a document and runs until it is closed.
///
/// # Errors
/// The windowing or graphics error, as text (no display, no adapter…).
pub fn run_window(document: Document, mesh_path: PathBuf, window: WindowOptions) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_title("shapeup").with_inner_size([1280.0, 800.0]),
        ..Default::default()
    };
    eframe::run_native(
        "shapeup",
        options,
        Box::new(move |cc| {
            Ok(Box::new(EditorApp::with_options(cc, document, mesh_path, window)) as Box<dyn eframe::App>)
        }),
    )
    .map_err(|e| e.to_string())
}
