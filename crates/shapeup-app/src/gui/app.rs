//! The eframe application: panels on the left, the 3D viewport in the centre, a status bar at
//! the bottom. Panels and gestures produce [`Command`]s that are applied to the [`Document`]
//! after the UI pass; after every change a [`SolverWorker`] converges the shape in the
//! background (see [`crate::worker`]), so the window keeps redrawing while the solver works and
//! what is on screen settles to the converged shape that a saved scene replays.

use super::dialogs::{DialogPurpose, FileDialogs};
use super::dynamics_panel::{DynamicsAction, dynamics_panel};
use super::gizmo::HandleGizmo;
use super::metrics::{Metrics, SolveProgress, frame_busy, push_bounded};
use super::renderer::{BASE_COLOR, FrameParams, MeshRenderer};
use crate::camera::OrbitCamera;
use crate::command::{Command, SelectMode};
use crate::document::{Document, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE};
use crate::error::TetrahedraError;
use crate::picking::{box_select, faces_within, pick_face, pick_vertex, visible_vertices};
use crate::simulation::{SimulationRunner, SimulationSettings, tetrahedralize_available};
use crate::worker::{SolveRequest, SolveResult, SolverWorker};
use eframe::egui;
use egui::{Color32, Pos2, Rect, Sense, Stroke};
use glam::{DVec3, Vec2, Vec3};
use shapeup_core::solver::Acceleration;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The longest a frame waits for the solver's first answer to a change before drawing (about
/// two iterations on a 35k-vertex mesh with strain + bending on 2 cores): a wait pays off while
/// it is shorter than the frame it saves.
const FIRST_UPDATE_WAIT: Duration = Duration::from_millis(50);

/// A frame slower than this during an interaction (a software renderer: a GPU takes a few
/// milliseconds) switches the 3D view to [`INTERACTIVE_SCALE`] until the interaction ends.
const SLOW_FRAME: Duration = Duration::from_millis(33);

/// Resolution scale of the 3D view while dragging on a slow renderer: a quarter of the pixels
/// to shade (measured on lavapipe with the 35k-vertex bunny: a frame 69 → 56 ms); the full
/// resolution returns with the first frame after the drag.
const INTERACTIVE_SCALE: f32 = 0.5;

/// "1 vertex", "2 vertices".
fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// The 3D view's resolution scale for this frame: reduced from the first slow frame of an
/// interaction until it ends (not back and forth within one), full otherwise.
pub(super) fn render_scale(interacting: bool, reduced_so_far: bool, last_frame: Option<Duration>) -> (f32, bool) {
    let reduced = interacting && (reduced_so_far || last_frame.is_some_and(|t| t > SLOW_FRAME));
    (if reduced { INTERACTIVE_SCALE } else { 1.0 }, reduced)
}

/// Where the 3D view's image goes: a shape reserved beneath the view's overlays.
struct ViewportSlot {
    painter: egui::Painter,
    shape: egui::layers::ShapeIdx,
    rect: Rect,
}

impl ViewportSlot {
    fn show(&self, texture: egui::TextureId) {
        let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
        self.painter.set(self.shape, egui::Shape::image(texture, self.rect, uv, Color32::WHITE));
    }
}

const SELECTED_COLOR: [f32; 3] = [0.15, 0.35, 0.95];
/// Corners of selected faces (face mode).
const SELECTED_FACE_COLOR: [f32; 3] = [0.1, 0.75, 0.8];
/// Colour of handle vertices (green, as in the seed editor).
pub const HANDLE_COLOR: [f32; 3] = [0.10, 0.70, 0.25];
/// Colour of the vertices of the group whose row the pointer is over.
pub const HOVER_COLOR: [f32; 3] = [0.95, 0.55, 0.10];
/// Energies kept for the convergence plot.
const ENERGY_HISTORY: usize = 400;
/// Tolerance slider range, as powers of ten.
const TOLERANCE_EXPONENTS: std::ops::RangeInclusive<f64> = -12.0..=-2.0;

/// The bundled sample meshes (name, path relative to the repository root).
pub const SAMPLES: [(&str, &str); 5] = [
    ("Stanford bunny", "data/stanford-bunny.obj"),
    ("Spot", "data/spot.obj"),
    ("Cow", "data/cow.obj"),
    ("Suzanne (quads)", "data/suzanne.obj"),
    ("Bunny ears (scene)", "examples/bunny-springs.toml"),
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
        /// Where the button went down (not where the first motion was seen).
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
    /// The handle the gizmo sits on (the last one made until a row is clicked).
    active_handle: Option<GroupKey>,
    gizmo: HandleGizmo,
    renaming: Option<(GroupKey, String)>,
    /// The last message (opened, saved, an error).
    status: String,
    /// A solve or simulation error, shown over the 3D view until the next good solve.
    banner: Option<String>,
    progress: SolveProgress,
    path_input: String,
    export_input: String,
    scene_input: String,
    /// A path to open once the user agrees to drop unsaved changes.
    confirm_open: Option<PathBuf>,
    /// The window's close was asked for with unsaved changes: ask before closing.
    confirm_close: bool,
    /// The user agreed to close without saving.
    close_confirmed: bool,
    /// The next click on the mesh selects the connected piece under it.
    pick_piece: bool,
    /// Face mode: clicks and box selections pick polygon faces instead of vertices.
    face_mode: bool,
    /// The type "Add constraint to selection" will add, and the options set in its widgets.
    add_kind: Option<&'static str>,
    add_options: serde_json::Map<String, serde_json::Value>,
    /// Whether Tetrahedralize can be ticked for this mesh (computed once per mesh).
    tetrahedralize: Result<(), TetrahedraError>,
    energy_history: VecDeque<f64>,
    /// The 3D view is drawn at [`INTERACTIVE_SCALE`] for the interaction under way.
    reduced_resolution: bool,
}

/// Options of the editor window.
#[derive(Debug, Clone, Copy, Default)]
pub struct WindowOptions {
    /// Print frames/s, solves/s, solve times and the latency from a change to its first
    /// visible update to stderr once per second (for measuring).
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
    metrics: Metrics,
    dialogs: FileDialogs,
    /// A drag (slider, gizmo) ended this frame: end the document's drag after this frame's
    /// commands, so that they still join its undo step.
    end_drag: bool,
    /// Dynamic mode: what to simulate, the running simulation, and the grabbed vertices with
    /// their positions at grab time.
    dynamics: SimulationSettings,
    simulation: Option<SimulationRunner>,
    grabbed: Vec<(u32, DVec3)>,
    ctx: egui::Context,
}

impl EditorApp {
    /// The editor on a document (e.g. from `Document::open`), for eframe; `path` is the mesh or
    /// scene file it came from.
    pub fn new(cc: &eframe::CreationContext<'_>, document: Document, path: PathBuf) -> Self {
        Self::with_options(cc, document, path, WindowOptions::default())
    }

    /// The editor with options. The shape starts converging at once.
    pub fn with_options(
        cc: &eframe::CreationContext<'_>,
        document: Document,
        path: PathBuf,
        options: WindowOptions,
    ) -> Self {
        let renderer = cc.wgpu_render_state.as_ref().map(|rs| MeshRenderer::new(&rs.device));
        let mut camera = OrbitCamera::default();
        camera.frame_front(document.positions(), document.triangles());
        let mut app = EditorApp {
            view: View {
                camera,
                wireframe: false,
                gesture: None,
                hovered_group: None,
                active_handle: None,
                gizmo: HandleGizmo::new(),
                renaming: None,
                status: if renderer.is_some() {
                    format!("opened {}", path.display())
                } else {
                    "no wgpu renderer: the 3D view is unavailable".into()
                },
                banner: None,
                progress: SolveProgress::default(),
                path_input: path.display().to_string(),
                export_input: "deformed.obj".into(),
                scene_input: scene_name_for(&path),
                confirm_open: None,
                confirm_close: false,
                close_confirmed: false,
                pick_piece: false,
                face_mode: false,
                add_kind: None,
                add_options: serde_json::Map::new(),
                tetrahedralize: tetrahedralize_available(&document),
                energy_history: VecDeque::new(),
                reduced_resolution: false,
            },
            document,
            mesh_path: path,
            worker: spawn_worker(&cc.egui_ctx),
            renderer,
            texture: None,
            uploaded_epoch: None,
            geometry_dirty: true,
            last_render: None,
            options,
            metrics: Metrics::new(),
            dialogs: FileDialogs::default(),
            end_drag: false,
            dynamics: SimulationSettings::default(),
            simulation: None,
            grabbed: Vec::new(),
            ctx: cc.egui_ctx.clone(),
        };
        // Scenes open solved: converge what was opened, like any other change.
        app.request_solve();
        app
    }

    /// The document being edited.
    pub fn document(&self) -> &Document {
        &self.document
    }

    /// How many solver results the document has taken since the editor started.
    pub fn solves_applied(&self) -> u64 {
        self.metrics.solves_applied
    }

    /// The convergence line the panel shows ("converged: …", "solving… …"; empty before any
    /// solve).
    pub fn solve_status(&self) -> &str {
        &self.view.progress.line
    }

    /// Whether the shape on screen is converged (the last solve reached the tolerance).
    pub fn is_converged(&self) -> bool {
        self.view.progress.converged
    }

    /// The error shown over the 3D view, if any.
    pub fn banner(&self) -> Option<&str> {
        self.view.banner.as_deref()
    }

    /// The path typed in the Open row.
    pub fn path_input(&self) -> &str {
        &self.view.path_input
    }

    /// The group whose row the pointer is over.
    pub fn hovered_group(&self) -> Option<GroupKey> {
        self.view.hovered_group
    }

    /// Milliseconds from each change of the constraints (a drag event, a slider move) to the
    /// end of the UI pass of the first frame that shows a solve of it (its rendering and presentation
    /// come after), most recent last (at most 1000).
    pub fn latencies(&self) -> impl Iterator<Item = f64> + '_ {
        self.metrics.latencies.iter().copied()
    }

    /// Whether dynamic mode is on (a simulation exists, running or paused).
    pub fn is_simulating(&self) -> bool {
        self.simulation.is_some()
    }

    /// Whether the simulation is stepping.
    pub fn is_running(&self) -> bool {
        self.simulation.as_ref().is_some_and(SimulationRunner::is_running)
    }

    /// The dynamics settings the panel edits.
    pub fn dynamics_settings(&self) -> &SimulationSettings {
        &self.dynamics
    }

    // ---- Commands and solving ----

    /// Applies commands as if they came from the panels this frame (scripted sessions,
    /// measurements): the shape then converges in the background like after any change.
    pub fn apply_commands(&mut self, commands: Vec<Command>) {
        self.apply(commands);
    }

    /// Starts a drag as a pointer drag on a handle does (scripted sessions, measurements):
    /// until [`EditorApp::end_drag`], moves make one undo step and the solver answers each with
    /// one chunk, leaving the CPU to drawing it.
    pub fn begin_drag(&mut self) {
        self.document.begin_drag();
    }

    /// Ends a drag begun with [`EditorApp::begin_drag`].
    pub fn end_drag(&mut self) {
        self.end_drag = true;
    }

    fn apply(&mut self, commands: Vec<Command>) {
        let mut changed = false;
        for command in commands {
            let effect = command.effect();
            // Moving targets or changing weights changes nothing drawn until the solve returns.
            self.geometry_dirty |= effect.redraws;
            let solve = effect.changes_solve;
            let fixes = matches!(command, Command::FixSelection | Command::PinFreePieces);
            match self.document.apply(command) {
                Ok(changed_state) => {
                    // Undo with nothing to undo, a weight set to what it was: nothing to solve.
                    let solve = solve && changed_state;
                    if solve {
                        // An earlier message (an error, "opened…") no longer describes the state.
                        self.view.status.clear();
                    }
                    changed |= solve;
                    if fixes {
                        // The new handle gets the gizmo.
                        self.view.active_handle = self.document.handles().last().map(|h| h.key);
                    }
                }
                Err(e) => self.view.status = e.to_string(),
            }
        }
        if std::mem::take(&mut self.end_drag) {
            self.document.end_drag();
        }
        if changed {
            // The simulation was built from the old constraints.
            if self.simulation.take().is_some() {
                self.view.status = "simulation stopped: the constraints changed".into();
            }
            self.request_solve();
        }
    }

    /// Starts converging the document's current state in the background (synchronously when
    /// there is no worker thread); the newest request replaces any older one.
    fn request_solve(&mut self) {
        if !self.document.state().has_handles() {
            self.view.progress = SolveProgress { line: "no handle: nothing to solve".into(), ..Default::default() };
            self.view.banner = None;
            return;
        }
        match &mut self.worker {
            Some(worker) => {
                let seq = worker.request(SolveRequest::from_document(&self.document));
                self.metrics.change_since.get_or_insert((seq, Instant::now()));
                self.view.progress.converged = false;
            }
            None => match self.document.converge() {
                Ok(report) => {
                    let n = report.energies.len();
                    let e = report.energies.last().copied().unwrap_or(0.0);
                    self.view.progress = SolveProgress {
                        line: format!("converged: {n} iterations, E {e:.3e}"),
                        converged: n < self.document.iterations(),
                        ..Default::default()
                    };
                    self.view.banner = None;
                    self.geometry_dirty = true;
                }
                Err(e) => self.view.banner = Some(e.to_string()),
            },
        }
    }

    fn poll_worker(&mut self) {
        let Some(worker) = &mut self.worker else { return };
        for result in worker.poll_all() {
            self.take_result(&result);
        }
    }

    fn take_result(&mut self, result: &SolveResult) {
        if let Some(e) = &result.error {
            // The document keeps the last good shape; say why where the user looks.
            self.view.banner = Some(format!("solve failed: {e}"));
            self.view.progress = SolveProgress { line: result.status(), ..Default::default() };
            return;
        }
        if !result.apply_to(&mut self.document) {
            return;
        }
        self.view.banner = None;
        self.geometry_dirty = true;
        self.view.progress = SolveProgress {
            line: result.status(),
            converged: result.converged,
            local_ms: result.local_ms,
            global_ms: result.global_ms,
            ms_per_iteration: result.ms_per_iteration().unwrap_or(self.view.progress.ms_per_iteration),
        };
        self.view.energy_history.extend(result.energy.iter().copied());
        let excess = self.view.energy_history.len().saturating_sub(ENERGY_HISTORY);
        self.view.energy_history.drain(..excess);
        self.metrics.solves.push_back(Instant::now());
        self.metrics.solves_applied += 1;
        if let Some((seq, since)) = self.metrics.change_since
            && result.seq >= seq
        {
            self.metrics.change_since = None;
            self.metrics.shown_change = Some(since);
        }
    }

    fn poll_simulation(&mut self) {
        let Some(runner) = &self.simulation else { return };
        if let Some(positions) = runner.poll()
            && self.document.accept_positions(self.document.epoch(), &positions)
        {
            self.geometry_dirty = true;
        }
    }

    // ---- Files ----

    /// Opens `path` now, or asks first when the session has unsaved changes.
    fn request_open(&mut self, path: PathBuf) {
        // A path that cannot be opened fails at once, without asking first.
        if self.document.is_modified() && path.is_file() {
            self.view.confirm_open = Some(path);
        } else {
            self.open(path);
        }
    }

    fn open(&mut self, path: PathBuf) {
        self.view.path_input = path.display().to_string();
        let opened = if is_scene(&path) {
            shapeup_core::scene::Scene::from_file(&path)
                .map_err(|e| e.to_string())
                .and_then(|s| Document::from_scene(&s).map_err(|e| format!("{}: {e}", path.display())))
        } else {
            Document::open(&path, ShapeModel::EdgeSprings).map_err(|e| e.to_string())
        };
        match opened {
            Ok(document) => {
                self.document = document;
                self.mesh_path = path.clone();
                // A fresh worker: the old one holds the old mesh's system.
                self.worker = spawn_worker(&self.ctx);
                self.simulation = None;
                self.grabbed.clear();
                self.uploaded_epoch = None;
                self.geometry_dirty = true;
                self.view.gesture = None;
                self.view.hovered_group = None;
                self.view.active_handle = None;
                self.view.banner = None;
                self.view.progress = SolveProgress::default();
                self.view.tetrahedralize = tetrahedralize_available(&self.document);
                self.view.camera.frame_front(self.document.positions(), self.document.triangles());
                self.view.energy_history.clear();
                self.view.scene_input = scene_name_for(&path);
                self.view.status = format!("opened {}", path.display());
                self.request_solve();
            }
            Err(e) => self.view.status = e,
        }
    }

    fn export_mesh(&mut self, path: PathBuf) {
        self.view.status =
            match shapeup_core::io::write_mesh(&path, &self.document.current_mesh(), self.document.attributes()) {
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
        self.view.status = match self.document.save_scene_with_mesh(&path) {
            Ok(saved) => {
                let mut line = format!("saved {}", path.display());
                if let Some(rest) = &saved.rest_mesh {
                    line.push_str(&format!(" and its rest mesh {}", rest.display()));
                }
                for warning in &saved.warnings {
                    line.push_str(&format!("; {warning}"));
                }
                if !self.view.progress.converged {
                    line.push_str(" (the shape was still converging: the replay converges it)");
                }
                line
            }
            Err(e) => e.to_string(),
        };
        self.view.scene_input = path.display().to_string();
    }

    /// Opens a native dialog (on its own thread) starting next to the current file.
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
            DialogPurpose::Open => self.request_open(path),
            DialogPurpose::ExportMesh => self.export_mesh(path),
            DialogPurpose::SaveScene => self.save_scene(path),
        }
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

    // ---- Panels ----

    /// One file row: the dialog button, the typed path (Enter acts on it), and the button acting
    /// on the typed path.
    fn path_row(&mut self, ui: &mut egui::Ui, purpose: DialogPurpose) {
        let (browse_label, act_label, hint) = match purpose {
            DialogPurpose::Open => ("Open…", "Open", "open the typed mesh or scene file"),
            DialogPurpose::ExportMesh => ("Export…", "Export mesh", "write OBJ, PLY, STL or OFF to the typed path"),
            DialogPurpose::SaveScene => {
                ("Save…", "Save scene", "a scene file that `shapeup deform` replays to the converged shape")
            }
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
            let edit = ui.add(egui::TextEdit::singleline(typed).desired_width(140.0)).labelled_by(browse.id);
            let entered = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            let path = PathBuf::from(typed.trim());
            if ui.button(act_label).on_hover_text(hint).clicked() || entered {
                self.act_on_path(purpose, path);
            }
        });
    }

    fn colors(&self) -> Vec<[f32; 3]> {
        let selection = self.document.selection();
        let mut colors = vec![BASE_COLOR; self.document.num_vertices()];
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
        if let Some(group) = self.view.hovered_group.and_then(|k| self.document.group(k)) {
            match group.vertices() {
                Some(list) => list.iter().for_each(|&v| colors[v] = HOVER_COLOR),
                None => colors.iter_mut().for_each(|c| *c = HOVER_COLOR),
            }
        }
        colors
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) -> Vec<Command> {
        let mut commands = Vec::new();
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("shapeup");
            egui::CollapsingHeader::new("Mesh").default_open(true).show(ui, |ui| self.mesh_section(ui));
            ui.collapsing("Mouse", |ui| {
                ui.label(
                    "left drag: orbit · right or shift+left drag: pan · wheel: zoom\n\
                     ctrl+left drag: select visible vertices in a box (ctrl+alt adds, ctrl+shift removes)\n\
                     alt+left drag on a handle: move it · alt+right drag: rotate it\n\
                     gizmo on the active handle: drag an arrow, a square or a ring (shift snaps)\n\
                     dynamics running: alt+left drag grabs and pulls the mesh\n\
                     ctrl+z / ctrl+shift+z: undo / redo",
                );
            });
            ui.separator();
            self.selection_section(ui, &mut commands);
            ui.separator();
            ui.label("Shape constraints");
            let current = self.document.shape_model();
            for model in ShapeModel::ALL {
                if ui.radio(current == Some(model), model.label()).clicked() && current != Some(model) {
                    commands.push(Command::SetShapeModel(model));
                }
            }
            ui.separator();
            self.groups_section(ui, &mut commands);
            ui.separator();
            self.solver_section(ui, &mut commands);
            ui.separator();
            self.path_row(ui, DialogPurpose::ExportMesh);
            self.path_row(ui, DialogPurpose::SaveScene);
            ui.separator();
            egui::CollapsingHeader::new("Dynamics").default_open(true).show(ui, |ui| self.dynamics_section(ui));
            ui.separator();
            ui.horizontal(|ui| {
                ui.checkbox(&mut self.view.wireframe, "Wireframe");
                if ui.button("Reset view").clicked() {
                    self.view.camera.reset();
                }
            });
            self.view.gizmo.tool_selector(ui);
            ui.separator();
            self.stats(ui);
        });
        commands
    }

    fn mesh_section(&mut self, ui: &mut egui::Ui) {
        self.path_row(ui, DialogPurpose::Open);
        ui.label("or drop a mesh or scene file on the window");
        let mut chosen = None;
        ui.menu_button("Samples", |ui| {
            for (name, relative) in SAMPLES {
                if ui.button(name).clicked() {
                    chosen = Some(sample_path(relative));
                    ui.close();
                }
            }
        });
        if let Some(path) = chosen {
            self.request_open(path);
        }
    }

    fn selection_section(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let faces = self.document.face_selection().iter().filter(|s| **s).count();
        ui.horizontal(|ui| {
            let vertices = count(self.document.num_selected(), "vertex", "vertices");
            ui.label(match faces {
                0 => format!("{vertices} selected"),
                _ => format!("{vertices}, {} selected", count(faces, "face", "faces")),
            });
            ui.toggle_value(&mut self.view.face_mode, "Face mode")
                .on_hover_text("clicks and Ctrl+drag boxes select polygon faces (for plane, circle, rectangle…)");
        });
        ui.horizontal_wrapped(|ui| {
            if ui.button("Fix selection").on_hover_text("a handle holding the selected vertices").clicked() {
                commands.push(Command::FixSelection);
            }
            if ui.button("Clear selection").clicked() {
                commands.push(Command::ClearSelection);
            }
            if ui.button("Select boundary").clicked() {
                commands.push(Command::SelectBoundary(SelectMode::Replace));
            }
        });
        self.add_constraint_row(ui, commands);
        // Pieces: every connected piece needs a handle, or the system is singular.
        let pieces = self.document.pieces().count;
        let free = self.document.num_free_pieces();
        ui.horizontal_wrapped(|ui| {
            if pieces > 1 || free > 0 {
                let text = match (free, pieces) {
                    (1, 1) => "the mesh has no handle".to_owned(),
                    (1, _) => format!("1 of {pieces} pieces has no handle"),
                    _ => format!("{free} of {pieces} pieces have no handle"),
                };
                if free > 0 && self.document.state().has_handles() {
                    ui.colored_label(Color32::from_rgb(200, 90, 0), text)
                        .on_hover_text("a piece without a handle has no defined position: the solve fails");
                } else {
                    ui.label(text);
                }
            }
            if ui
                .add_enabled(free > 0, egui::Button::new("Pin free pieces"))
                .on_hover_text("one soft handle (weight 0.01) on every piece without one, at rest")
                .clicked()
            {
                commands.push(Command::PinFreePieces);
            }
            ui.toggle_value(&mut self.view.pick_piece, "Select connected piece")
                .on_hover_text("while on, a click on a vertex selects its piece (shift adds); click again to stop");
        });
    }

    /// "Add constraint to selection": every registered type that fits the selection, its
    /// options as widgets generated from its option descriptions, and the button.
    fn add_constraint_row(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        let fitting = self.document.fitting_types();
        if fitting.is_empty() {
            ui.label("select vertices or faces to add a constraint");
            return;
        }
        let chosen = self.view.add_kind.and_then(|k| fitting.iter().copied().find(|t| t.name() == k));
        let ty = chosen.unwrap_or(fitting[0]);
        if chosen.is_none() {
            self.view.add_kind = Some(ty.name());
            self.view.add_options.clear();
        }
        ui.horizontal(|ui| {
            egui::ComboBox::from_id_salt("add constraint type")
                .selected_text(ty.name())
                .show_ui(ui, |ui| {
                    for t in &fitting {
                        if ui.selectable_label(t.name() == ty.name(), t.name()).on_hover_text(t.summary()).clicked()
                            && t.name() != ty.name()
                        {
                            self.view.add_kind = Some(t.name());
                            self.view.add_options.clear();
                        }
                    }
                })
                .response
                .on_hover_text(ty.summary());
            if ui.button("Add constraint to selection").on_hover_text(ty.summary()).clicked() {
                commands
                    .push(Command::AddConstraint { kind: ty.name().into(), options: self.view.add_options.clone() });
            }
        });
        for option in ty.options() {
            option_widget(ui, option, &mut self.view.add_options);
        }
    }

    fn groups_section(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.label("Groups (hover to highlight, click a handle's name for the gizmo)");
        let previously_hovered = self.view.hovered_group.take();
        let groups: Vec<_> = self.document.groups().to_vec();
        for group in &groups {
            let row = ui.vertical(|ui| {
                ui.horizontal(|ui| {
                    let active = self.view.active_handle == Some(group.key);
                    let name = format!("{} ({})", group.spec.name, group.spec.kind);
                    if group.role == GroupRole::Handle {
                        if ui.selectable_label(active, name).on_hover_text("put the gizmo on this handle").clicked() {
                            self.view.active_handle = Some(group.key);
                        }
                        if ui.small_button("rename").clicked() {
                            self.view.renaming = Some((group.key, group.spec.name.clone()));
                        }
                    } else {
                        ui.label(name);
                    }
                    if group.role != GroupRole::Shape && ui.small_button("remove").clicked() {
                        commands.push(Command::RemoveGroup(group.key));
                    }
                });
                if let Some(weight) = self.weight_control(ui, group.spec.weight) {
                    commands.push(Command::SetWeight { group: group.key, weight });
                }
            });
            // The whole row, children included (they cover the row's own response).
            if ui.rect_contains_pointer(row.response.rect) {
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
    }

    /// A weight slider over log10(w) from [`WEIGHT_RANGE`], with text entry (the number field:
    /// type any weight) and fine steps while shift is held. Returns the new weight when it
    /// changed. One undo step per slider drag.
    fn weight_control(&mut self, ui: &mut egui::Ui, weight: f64) -> Option<f64> {
        let (lo, hi) = (WEIGHT_RANGE.0.log10(), WEIGHT_RANGE.1.log10());
        let before = weight.max(WEIGHT_RANGE.0).log10();
        let mut exponent = before;
        let slider = egui::Slider::new(&mut exponent, lo..=hi)
            .text("weight")
            .custom_formatter(|x, _| format_weight(10f64.powf(x)))
            .custom_parser(|text| text.trim().parse::<f64>().ok().filter(|w| *w > 0.0).map(f64::log10));
        let response = ui.add(slider);
        self.track_drag(&response);
        if response.dragged() && ui.input(|i| i.modifiers.shift) {
            // Fine: a tenth of the pointer's motion.
            let per_px = (hi - lo) / f64::from(ui.spacing().slider_width.max(1.0));
            exponent = (before + 0.1 * per_px * f64::from(response.drag_delta().x)).clamp(lo, hi);
        }
        let weight = 10f64.powf(exponent);
        (exponent != before && response.changed()).then_some(weight)
    }

    /// Slider drags form one undo step each.
    fn track_drag(&mut self, response: &egui::Response) {
        if response.drag_started() {
            self.document.begin_drag();
        }
        if response.drag_stopped() {
            self.end_drag = true;
        }
    }

    fn solver_section(&mut self, ui: &mut egui::Ui, commands: &mut Vec<Command>) {
        ui.label("Solver");
        let converged = self.view.progress.converged;
        let color = if converged { Color32::from_rgb(20, 140, 60) } else { ui.visuals().text_color() };
        ui.colored_label(color, if self.view.progress.line.is_empty() { "—" } else { &self.view.progress.line });
        let mut exponent = self.document.tolerance().log10();
        let response = ui
            .add(
                egui::Slider::new(&mut exponent, TOLERANCE_EXPONENTS)
                    .step_by(0.5)
                    .custom_formatter(|x, _| format!("{:.0e}", 10f64.powf(x)))
                    .custom_parser(|t| t.trim().parse::<f64>().ok().filter(|v| *v > 0.0).map(f64::log10))
                    .text("tolerance"),
            )
            .on_hover_text("converged when an iteration changes the energy by at most this fraction");
        self.track_drag(&response);
        if response.changed() {
            commands.push(Command::SetTolerance(10f64.powf(exponent)));
        }
        let mut cap = self.document.iterations();
        let response = ui
            .add(egui::DragValue::new(&mut cap).range(1..=10_000_000).prefix("iteration cap "))
            .on_hover_text("the most iterations one convergence runs");
        self.track_drag(&response);
        if response.changed() {
            commands.push(Command::SetIterations(cap));
        }
        let current = self.document.acceleration();
        let mut chosen = current;
        egui::ComboBox::from_label("acceleration")
            .selected_text(acceleration_label(current))
            .show_ui(ui, |ui| {
                for a in Acceleration::ALL {
                    ui.selectable_value(&mut chosen, a, acceleration_label(a)).on_hover_text(acceleration_hint(a));
                }
            })
            .response
            .on_hover_text(acceleration_hint(current));
        if chosen != current {
            commands.push(Command::SetAcceleration(chosen));
        }
        ui.horizontal_wrapped(|ui| {
            if ui.button("Reset shape").on_hover_text("back to the rest shape (undoable)").clicked() {
                commands.push(Command::ResetShape);
            }
            if ui.button("Make rest shape").on_hover_text("the current shape becomes the rest shape").clicked() {
                commands.push(Command::MakeRest);
            }
            if ui.add_enabled(self.document.can_undo(), egui::Button::new("Undo")).clicked() {
                commands.push(Command::Undo);
            }
            if ui.add_enabled(self.document.can_redo(), egui::Button::new("Redo")).clicked() {
                commands.push(Command::Redo);
            }
        });
    }

    fn dynamics_section(&mut self, ui: &mut egui::Ui) {
        let available = self.view.tetrahedralize.clone();
        let action = dynamics_panel(ui, &mut self.dynamics, self.simulation.as_ref(), available);
        match action {
            Some(DynamicsAction::Run) => {
                if self.simulation.is_none() {
                    let ctx = ui.ctx().clone();
                    match SimulationRunner::start(&self.document, self.dynamics, move || ctx.request_repaint()) {
                        Ok(runner) => {
                            // The run is undoable: undo brings back the shape it started from.
                            self.document.checkpoint();
                            self.simulation = Some(runner);
                        }
                        Err(e) => self.view.banner = Some(e.to_string()),
                    }
                }
                if let Some(runner) = &self.simulation {
                    runner.set_running(true);
                }
            }
            Some(DynamicsAction::Pause) => {
                if let Some(runner) = &self.simulation {
                    runner.set_running(false);
                }
            }
            Some(DynamicsAction::Restart) => {
                if let Some(runner) = &self.simulation {
                    runner.reset();
                }
            }
            Some(DynamicsAction::Stop) => self.simulation = None,
            Some(DynamicsAction::SettingsChanged) => {
                if let Some(runner) = &self.simulation
                    && !runner.update_settings(&self.dynamics)
                {
                    // A new model, floor or tetrahedralization: a new simulation on Run.
                    self.simulation = None;
                    self.view.status = "dynamics settings changed: Run starts a new simulation".into();
                }
            }
            None => {}
        }
        if let Some(error) = self.simulation.as_ref().and_then(|r| r.stats().error) {
            self.view.banner = Some(format!("simulation: {error}"));
        }
    }

    fn stats(&mut self, ui: &mut egui::Ui) {
        let now = Instant::now();
        for q in [&mut self.metrics.solves, &mut self.metrics.frames] {
            while q.front().is_some_and(|t| now.duration_since(*t).as_secs_f64() > 1.0) {
                q.pop_front();
            }
        }
        let p = &self.view.progress;
        ui.label(format!(
            "{}, {}, {}\n{:.1} ms per iteration (last update: local {:.1} ms, global {:.1} ms)\n{} updates/s, {} frames/s",
            count(self.document.num_vertices(), "vertex", "vertices"),
            count(self.document.triangles().len(), "triangle", "triangles"),
            count(self.document.pieces().count, "piece", "pieces"),
            p.ms_per_iteration,
            p.local_ms,
            p.global_ms,
            self.metrics.solves.len(),
            self.metrics.frames.len(),
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

    /// Asks before dropping unsaved changes.
    fn confirm_open_modal(&mut self, ctx: &egui::Context) {
        let Some(path) = self.view.confirm_open.clone() else { return };
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("confirm-open")).show(ctx, |ui| {
            ui.label(format!("Open {}?", path.display()));
            ui.label("This session has unsaved changes (save the scene to keep them); its undo history goes.");
            ui.horizontal(|ui| {
                if ui.button("Discard changes and open").clicked() {
                    choice = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    choice = Some(false);
                }
            });
        });
        match choice {
            Some(true) => {
                self.view.confirm_open = None;
                self.open(path);
            }
            Some(false) => {
                self.view.confirm_open = None;
                self.view.path_input = self.mesh_path.display().to_string();
            }
            None => {}
        }
    }

    /// Closing the window with unsaved changes asks first (as opening another mesh does).
    fn confirm_close(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested()) && self.document.is_modified() && !self.view.close_confirmed {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.view.confirm_close = true;
        }
        if !self.view.confirm_close {
            return;
        }
        let mut choice = None;
        egui::Modal::new(egui::Id::unique("confirm-close")).show(ctx, |ui| {
            ui.label("Quit without saving?");
            ui.label("This session has unsaved changes (save the scene to keep them).");
            ui.horizontal(|ui| {
                if ui.button("Discard changes and quit").clicked() {
                    choice = Some(true);
                }
                if ui.button("Cancel").clicked() {
                    choice = Some(false);
                }
            });
        });
        match choice {
            Some(true) => {
                self.view.confirm_close = false;
                self.view.close_confirmed = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Some(false) => self.view.confirm_close = false,
            None => {}
        }
    }

    /// Whether the window is asking to confirm quitting with unsaved changes.
    pub fn is_confirming_close(&self) -> bool {
        self.view.confirm_close
    }

    // ---- Viewport ----

    /// The 3D view's interaction and overlays; the mesh itself is drawn into the returned slot
    /// (beneath the overlays) once the frame's changes are applied, by [`EditorApp::paint`].
    fn viewport(&mut self, ui: &mut egui::Ui) -> (Vec<Command>, ViewportSlot) {
        let mut commands = Vec::new();
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), Sense::click_and_drag());
        let slot = ViewportSlot { painter: ui.painter().clone(), shape: ui.painter().add(egui::Shape::Noop), rect };
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let to_local = |p: Pos2| Vec2::new(p.x - rect.left(), p.y - rect.top());
        let modifiers = ui.input(|i| i.modifiers);
        let positions: Vec<Vec3> = self.document.positions().iter().map(|p| p.as_vec3()).collect();

        if response.drag_started() && !self.view.gizmo.claims_pointer() {
            // Where the button went down: egui reports the drag a few pixels later.
            let start = ui
                .input(|i| i.pointer.press_origin())
                .or_else(|| response.interact_pointer_pos())
                .unwrap_or(rect.center());
            let primary = response.drag_started_by(egui::PointerButton::Primary);
            self.view.gesture = if primary && modifiers.command {
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
                    self.view.active_handle = Some(handle);
                    Gesture::DragHandle { handle, anchor: positions[v as usize] }
                })
            } else if response.drag_started_by(egui::PointerButton::Secondary) && modifiers.alt {
                self.handle_under(to_local(start), viewport).map(|(handle, _)| {
                    self.document.begin_drag();
                    self.view.active_handle = Some(handle);
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
            && self.view.face_mode
            && !self.view.pick_piece
            && let Some(pos) = response.interact_pointer_pos()
        {
            let mesh = self.document.rest_mesh();
            let picked = pick_face(
                self.document.positions(),
                &mesh.triangles,
                &mesh.triangle_polygon,
                &self.view.camera,
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
            && self.view.pick_piece
            && let Some(pos) = response.interact_pointer_pos()
        {
            let visible =
                visible_vertices(self.document.positions(), self.document.triangles(), &self.view.camera, viewport);
            match pick_vertex(self.document.positions(), &visible, &self.view.camera, viewport, to_local(pos), 12.0) {
                Some(vertex) => {
                    let mode = if modifiers.shift { SelectMode::Add } else { SelectMode::Replace };
                    commands.push(Command::SelectPiece { vertex, mode });
                }
                None => self.view.status = "no vertex under the pointer: click on the mesh".into(),
            }
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
                if self.view.face_mode {
                    let mesh = self.document.rest_mesh();
                    let faces = faces_within(&mesh.polygons, &vertices, mesh.num_vertices());
                    commands.push(Command::SelectFaces { faces, mode });
                } else {
                    commands.push(Command::Select { vertices, mode });
                }
            }
            if matches!(self.view.gesture, Some(Gesture::Grab { .. }))
                && let Some(runner) = &self.simulation
            {
                runner.release();
                self.grabbed.clear();
            }
            if matches!(self.view.gesture, Some(Gesture::DragHandle { .. } | Gesture::RotateHandle { .. })) {
                self.end_drag = true;
            }
            self.view.gesture = None;
        }
        if response.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.view.camera.zoom(scroll / 50.0);
            }
        }

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
        commands.extend(self.gizmo(ui, rect));
        self.paint_banner(ui, rect);
        (commands, slot)
    }

    /// Blocks (at most [`FIRST_UPDATE_WAIT`] after the change) until the worker's first result
    /// for the newest change is there, so the frame about to be drawn shows it: without this the
    /// frame shows the shape before the change and the answer waits a whole frame more.
    fn await_first_update(&mut self) {
        let (Some(worker), Some((seq, since))) = (&self.worker, self.metrics.change_since) else { return };
        if let Some(left) = FIRST_UPDATE_WAIT.checked_sub(since.elapsed()) {
            let start = Instant::now();
            worker.wait_for(seq, left);
            self.metrics.waited += start.elapsed();
        }
    }

    /// The gizmo on the active handle (static mode only).
    fn gizmo(&mut self, ui: &egui::Ui, rect: Rect) -> Vec<Command> {
        let handle = if self.simulation.is_none() && !matches!(self.view.gesture, Some(Gesture::BoxSelect { .. })) {
            let active = self.view.active_handle.and_then(|k| self.document.handles().find(|h| h.key == k));
            active.or_else(|| self.document.handles().last()).and_then(|h| Some((h.key, h.target_centroid()?)))
        } else {
            None
        };
        let Some((handle, center)) = handle else {
            if self.view.gizmo.cancel() {
                self.end_drag = true;
            }
            return Vec::new();
        };
        let (lo, hi) = self.document.rest_mesh().bounding_box();
        let output = self.view.gizmo.show(ui, rect, &self.view.camera, handle, center, (hi - lo).length());
        if output.drag_started {
            self.document.begin_drag();
            self.view.gesture = None;
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

    /// Renders the mesh (re-uploaded when the shape or colours changed) and puts it in the
    /// viewport's slot.
    fn paint(&mut self, frame: &eframe::Frame, slot: &ViewportSlot) {
        let rect = slot.rect;
        let viewport = Vec2::new(rect.width().max(1.0), rect.height().max(1.0));
        let key = (self.document.num_vertices(), self.document.triangles().len());
        let upload = self.geometry_dirty || self.uploaded_epoch != Some(key);
        let colors = if upload { self.colors() } else { Vec::new() };
        let (Some(render_state), Some(renderer)) = (frame.wgpu_render_state(), self.renderer.as_mut()) else {
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
            || matches!(self.view.gesture, Some(Gesture::Orbit | Gesture::Pan | Gesture::Grab { .. }));
        let (scale, reduced) = render_scale(interacting, self.view.reduced_resolution, self.metrics.last_frame_busy);
        self.view.reduced_resolution = reduced;
        let pixels = slot.painter.ctx().pixels_per_point() * scale;
        let size = ((viewport.x * pixels) as u32, (viewport.y * pixels) as u32);
        let filter = if reduced { wgpu::FilterMode::Linear } else { wgpu::FilterMode::Nearest };
        let positions: Vec<Vec3> =
            if upload { self.document.positions().iter().map(|p| p.as_vec3()).collect() } else { Vec::new() };
        let positions = &positions[..];
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
            slot.show(id);
            return;
        }
        let Some(view) = renderer.render(&render_state.device, &render_state.queue, size, &params) else { return };
        self.last_render = Some(key);
        let mut egui_renderer = render_state.renderer.write();
        let id = match self.texture {
            Some(id) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(&render_state.device, view, filter, id);
                id
            }
            None => {
                let id = egui_renderer.register_native_texture(&render_state.device, view, filter);
                self.texture = Some(id);
                id
            }
        };
        drop(egui_renderer);
        slot.show(id);
    }

    /// The bottom line: the convergence and the last message, always in view.
    fn status_bar(&self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let p = &self.view.progress;
            if !p.line.is_empty() {
                ui.label(&p.line);
                ui.separator();
            }
            ui.label(&self.view.status);
        });
    }
}

/// Whether `path` names a scene file (.toml or .json).
fn is_scene(path: &std::path::Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| matches!(e, "toml" | "json"))
}

/// The scene path proposed for saving: `STEM-session.toml` in the working directory.
fn scene_name_for(path: &std::path::Path) -> String {
    // Never the opened scene itself: one click must not overwrite it (a bundled example, say).
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "session".into());
    format!("{stem}-session.toml")
}

/// A weight as the slider shows it: 3 significant digits, scientific outside [0.01, 1000).
fn format_weight(w: f64) -> String {
    if (0.01..1000.0).contains(&w) {
        format!("{:.3}", w).trim_end_matches('0').trim_end_matches('.').into()
    } else {
        format!("{w:.2e}")
    }
}

/// The file name part of a typed path, proposed by save dialogs.
fn file_name_of(typed: &str) -> String {
    std::path::Path::new(typed.trim()).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// A solver thread whose results wake the UI (so nothing redraws while waiting); `None` when the
/// thread cannot start (the editor then converges synchronously).
fn spawn_worker(ctx: &egui::Context) -> Option<SolverWorker> {
    let ctx = ctx.clone();
    SolverWorker::spawn_with_notify(move || ctx.request_repaint()).ok()
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        self.metrics.frames.push_back(Instant::now());
        let mut starts = self.metrics.frames.iter().rev();
        let gap = match (starts.next(), starts.next()) {
            (Some(now), Some(before)) => Some(now.duration_since(*before)),
            _ => None,
        };
        let waited = std::mem::take(&mut self.metrics.waited);
        self.metrics.last_frame_busy = frame_busy(gap, waited, ui.ctx().requested_repaint_last_pass());
        if let Some(since) = self.metrics.painted_change.take() {
            push_bounded(&mut self.metrics.on_screen, since.elapsed().as_secs_f64() * 1e3);
        }
        self.poll_worker();
        self.poll_simulation();
        self.poll_dialogs();
        let dropped: Vec<PathBuf> = ui.input(|i| i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).collect());
        if let Some(path) = dropped.into_iter().next() {
            self.request_open(path);
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
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        let panel = egui::Panel::left("controls").default_size(330.0).show(ui, |ui| self.side_panel(ui));
        commands.extend(panel.inner);
        let viewport = egui::CentralPanel::no_frame().show(ui, |ui| self.viewport(ui));
        let (viewport_commands, slot) = viewport.inner;
        commands.extend(viewport_commands);
        self.apply(commands);
        // Draw the answer to this frame's change rather than the shape before it.
        self.await_first_update();
        self.poll_worker();
        self.paint(frame, &slot);
        self.confirm_open_modal(ui.ctx());
        self.confirm_close(ui.ctx());
        self.metrics.record_latency();
        if self.options.print_stats {
            self.metrics.print_stats(ui.ctx(), self.view.reduced_resolution, &self.view.progress);
        }
    }
}

/// Opens the editor window on a document and runs until it is closed; `path` is the mesh or
/// scene it came from.
///
/// # Errors
/// The windowing or graphics error, as text (no display, no adapter…).
pub fn run_window(document: Document, path: PathBuf, window: WindowOptions) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_title("shapeup").with_inner_size([1280.0, 800.0]),
        // Dithering costs every pixel of every frame on software renderers; flat panels and a
        // shaded mesh show no banding without it.
        dithering: false,
        ..Default::default()
    };
    eframe::run_native(
        "shapeup",
        options,
        Box::new(move |cc| Ok(Box::new(EditorApp::with_options(cc, document, path, window)) as Box<dyn eframe::App>)),
    )
    .map_err(|e| e.to_string())
}

/// The editor's name for an acceleration.
/// The widget of one constraint option, generated from its description: a number field
/// within its range (with "rest" for a default taken from the rest shape), a checkbox, or
/// three number fields; the value lands in `options` under the option's key, and an option
/// left at its default is left out.
fn option_widget(
    ui: &mut egui::Ui,
    option: &shapeup_core::constraints::OptionSpec,
    options: &mut serde_json::Map<String, serde_json::Value>,
) {
    use shapeup_core::constraints::OptionKind;
    ui.horizontal(|ui| {
        ui.label(option.key).on_hover_text(option.doc);
        match option.kind {
            OptionKind::Number { default, min, max } => {
                let current = options.get(option.key).and_then(serde_json::Value::as_f64);
                if default.is_none() {
                    let mut from_rest = current.is_none();
                    if ui.checkbox(&mut from_rest, "rest").on_hover_text(option.doc).changed() {
                        if from_rest {
                            options.remove(option.key);
                        } else {
                            options.insert(option.key.into(), min.max(0.0).min(max).into());
                        }
                    }
                    if from_rest {
                        return;
                    }
                }
                let mut value = current.or(default).unwrap_or(0.0);
                let speed = if max - min < 10.0 { 0.01 } else { 0.1 };
                if ui
                    .add(egui::DragValue::new(&mut value).range(min..=max).speed(speed))
                    .on_hover_text(option.doc)
                    .changed()
                {
                    options.insert(option.key.into(), value.into());
                }
            }
            OptionKind::Bool { default } => {
                let mut value = options.get(option.key).and_then(serde_json::Value::as_bool).unwrap_or(default);
                if ui.checkbox(&mut value, "").on_hover_text(option.doc).changed() {
                    options.insert(option.key.into(), value.into());
                }
            }
            OptionKind::Vector { default } => {
                let mut value: [f64; 3] =
                    options.get(option.key).and_then(|v| serde_json::from_value(v.clone()).ok()).unwrap_or(default);
                let mut changed = false;
                for x in &mut value {
                    changed |= ui.add(egui::DragValue::new(x).speed(0.1)).on_hover_text(option.doc).changed();
                }
                if changed {
                    options.insert(option.key.into(), value.to_vec().into());
                }
            }
        }
    });
}

fn acceleration_label(a: Acceleration) -> &'static str {
    match a {
        Acceleration::Anderson => "Anderson",
        Acceleration::Lbfgs => "L-BFGS",
        Acceleration::None => "none (plain)",
    }
}

/// What an acceleration does, in one hover line.
fn acceleration_hint(a: Acceleration) -> &'static str {
    match a {
        Acceleration::Anderson => {
            "mix the last iterations (Peng et al. 2018); a mixed step that does not lower the energy is replaced by a plain one"
        }
        Acceleration::Lbfgs => {
            "quasi-Newton steps with the global matrix as first Hessian (Liu et al. 2017): the converged shape in the fewest iterations; a step that does not lower the energy enough is replaced by a plain one"
        }
        Acceleration::None => "plain local-global iterations: the energy decreases, slowly",
    }
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
