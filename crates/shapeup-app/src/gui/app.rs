//! The eframe application: panels on the left, the 3D viewport in the centre, a status bar at
//! the bottom. Panels and gestures produce [`Command`]s that are applied to the [`Document`]
//! after the UI pass; after every change a [`SolverWorker`] converges the shape in the
//! background (see [`crate::worker`]), so the window keeps redrawing while the solver works and
//! what is on screen settles to the converged shape that a saved scene replays.
//!
//! This file is the shell: the app's state, the frame's order, applying commands and taking
//! solver results. The rooms: the side panel's sections in `panels/`, the 3D view's state in
//! [`super::viewport`] and its frame in `viewport_ui`, files in [`super::files`] and their rows
//! and dialogs in `files_ui`, measurements in `metrics`. The shell's fields come from the rooms
//! below it; `viewport_ui` and `files_ui` add methods to [`EditorApp`] from above it, so no
//! import runs back up.

use super::dialogs::DialogPurpose;
use super::dynamics_panel::{DynamicsAction, dynamics_panel};
use super::files::FilesState;
use super::metrics::{Metrics, SolveProgress, frame_busy, push_bounded};
use super::panels::PanelOutput;
use super::panels::contact::{ContactPanel, contact_panel};
use super::panels::groups::{GroupsPanel, groups_panel, shape_model_panel};
use super::panels::selection::{SelectionPanel, selection_panel};
use super::panels::solver::solver_panel;
use super::panels::stats::stats_panel;
use super::renderer::MeshRenderer;
use super::viewport::ViewportState;
use crate::command::Command;
use crate::document::{Document, GroupKey};
use crate::error::TetrahedraError;
use crate::simulation::{SimulationRunner, SimulationSettings, StartShape, tetrahedralize_available};
use crate::worker::{SolveRequest, SolveResult, SolverWorker};
use eframe::egui;
use std::collections::VecDeque;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The longest a frame waits for the solver's first answer to a change before drawing (about
/// two iterations on a 35k-vertex mesh with strain + bending on 2 cores): a wait pays off while
/// it is shorter than the frame it saves.
const FIRST_UPDATE_WAIT: Duration = Duration::from_millis(50);

/// Energies kept for the convergence plot.
const ENERGY_HISTORY: usize = 400;

/// The shell's own UI state: messages, convergence, and what the Dynamics panel needs.
pub(super) struct View {
    /// The last message (opened, saved, an error).
    pub(super) status: String,
    /// A solve or simulation error, shown over the 3D view until the next good solve.
    pub(super) banner: Option<String>,
    pub(super) progress: SolveProgress,
    /// Whether Tetrahedralize can be ticked for this mesh (computed once per mesh).
    pub(super) tetrahedralize: Result<(), TetrahedraError>,
    pub(super) energy_history: VecDeque<f64>,
    /// Per vertex, whether it touches a collider or the surface itself (from the last solve or
    /// simulation step; empty without contact).
    pub(super) touching: Vec<bool>,
}

/// Options of the editor window.
#[derive(Debug, Clone, Copy, Default)]
pub struct WindowOptions {
    /// Print frames/s, solves/s, solve times and the latency from a change to its first
    /// visible update to stderr once per second (for measuring).
    pub print_stats: bool,
}

/// The editor window.
pub struct EditorApp {
    pub(super) document: Document,
    /// The mesh or scene file the document came from.
    pub(super) mesh_path: PathBuf,
    pub(super) view: View,
    pub(super) viewport: ViewportState,
    pub(super) selection: SelectionPanel,
    pub(super) groups: GroupsPanel,
    pub(super) contact: ContactPanel,
    pub(super) files: FilesState,
    pub(super) worker: Option<SolverWorker>,
    options: WindowOptions,
    pub(super) metrics: Metrics,
    /// A drag (slider, gizmo) ended this frame: end the document's drag after this frame's
    /// commands, so that they still join its undo step.
    pub(super) end_drag: bool,
    /// Dynamic mode: what to simulate and the running simulation.
    dynamics: SimulationSettings,
    pub(super) simulation: Option<SimulationRunner>,
    pub(super) ctx: egui::Context,
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
        let viewport = ViewportState::new(renderer, document.positions(), document.triangles());
        let mut app = EditorApp {
            view: View {
                status: if viewport.has_renderer() {
                    format!("opened {}", path.display())
                } else {
                    "no wgpu renderer: the 3D view is unavailable".into()
                },
                banner: None,
                progress: SolveProgress::default(),
                tetrahedralize: tetrahedralize_available(&document),
                energy_history: VecDeque::new(),
                touching: Vec::new(),
            },
            viewport,
            selection: SelectionPanel::default(),
            groups: GroupsPanel::default(),
            contact: ContactPanel::default(),
            files: FilesState::new(&path),
            document,
            mesh_path: path,
            worker: spawn_worker(&cc.egui_ctx),
            options,
            metrics: Metrics::new(),
            end_drag: false,
            dynamics: SimulationSettings::default(),
            simulation: None,
            ctx: cc.egui_ctx.clone(),
        };
        // Scenes open solved: converge what was opened, like any other change.
        app.request_solve();
        app
    }

    /// The view.
    pub fn camera(&self) -> &crate::camera::OrbitCamera {
        &self.viewport.camera
    }

    /// The status line's message.
    pub fn status(&self) -> &str {
        &self.view.status
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

    /// The handle the gizmo is on, if any.
    pub fn active_handle(&self) -> Option<GroupKey> {
        self.groups.active_handle
    }

    /// The error shown over the 3D view, if any.
    pub fn banner(&self) -> Option<&str> {
        self.view.banner.as_deref()
    }

    /// The path typed in the Open row.
    pub fn path_input(&self) -> &str {
        &self.files.path_input
    }

    /// The group whose row the pointer is over.
    pub fn hovered_group(&self) -> Option<GroupKey> {
        self.groups.hovered
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

    /// Per vertex, whether it touches a collider or the surface itself as last shown (empty
    /// without contact).
    pub fn touching(&self) -> &[bool] {
        &self.view.touching
    }

    /// The collider the gizmo sits on (the Contact panel's selection), if any.
    pub fn selected_collider(&self) -> Option<usize> {
        self.contact.selected
    }

    /// Applies the frame's commands to the document, in order; a change of the solve starts
    /// a new convergence (and ends dynamic mode, built from the old constraints), but a
    /// change of the colliders or contact settings alone goes to the running simulation.
    pub(super) fn apply(&mut self, commands: Vec<Command>) {
        let mut changed = false;
        let mut contact_only = true;
        for command in commands {
            let effect = command.effect();
            let contact_edit = command.is_contact_edit();
            // Moving targets or changing weights changes nothing drawn until the solve returns.
            self.viewport.geometry_dirty |= effect.redraws;
            let solve = effect.changes_solve;
            // A new handle from the selection gets the gizmo; pinning or attaching free pieces
            // leaves it on the handle the user was working with.
            let fixes = matches!(command, Command::FixSelection);
            let attaches = matches!(command, Command::AttachFreePieces);
            match self.document.apply(command) {
                Ok(changed_state) => {
                    // Undo with nothing to undo, a weight set to what it was: nothing to solve.
                    let solve = solve && changed_state;
                    if solve {
                        // An earlier message (an error, "opened…") no longer describes the state.
                        self.view.status.clear();
                    }
                    changed |= solve;
                    contact_only &= !solve || contact_edit;
                    if attaches {
                        let n = self.document.num_attached_pieces();
                        self.view.status =
                            format!("{} follow the surface under them", super::panels::count(n, "piece", "pieces"));
                    }
                    if fixes {
                        // The new handle gets the gizmo.
                        self.groups.active_handle = self.document.handles().last().map(|h| h.key);
                        self.contact.selected = None;
                    }
                }
                Err(e) => self.view.status = e.to_string(),
            }
        }
        if std::mem::take(&mut self.end_drag) {
            self.document.end_drag();
        }
        if changed && contact_only {
            if let Some(runner) = &self.simulation {
                // Colliders move under the running simulation; no static solve meanwhile.
                runner.set_contact(self.document.colliders().to_vec(), self.document.contact_settings());
                return;
            }
            // The next solve says what touches the new colliders.
            self.view.touching.clear();
            self.viewport.geometry_dirty = true;
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
    pub(super) fn request_solve(&mut self) {
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
                    self.viewport.geometry_dirty = true;
                }
                Err(e) => self.view.banner = Some(e.to_string()),
            },
        }
    }

    /// Takes the worker's new results.
    fn poll_worker(&mut self) {
        let Some(worker) = &mut self.worker else { return };
        for result in worker.poll_all() {
            self.take_result(&result);
        }
    }

    /// Shows one solver result: its shape, progress and energies, or its error.
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
        self.view.touching.clone_from(&result.touching);
        self.view.banner = None;
        self.viewport.geometry_dirty = true;
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

    /// Shows the simulation's newest positions, if any.
    fn poll_simulation(&mut self) {
        let Some(runner) = &self.simulation else { return };
        if let Some(positions) = runner.poll()
            && self.document.accept_positions(self.document.epoch(), &positions)
        {
            self.view.touching = runner.touching();
            self.viewport.geometry_dirty = true;
        }
    }

    /// The side panel: each section in turn; the commands they ask for, in order.
    fn side_panel(&mut self, ui: &mut egui::Ui) -> Vec<Command> {
        let mut out = PanelOutput::default();
        egui::ScrollArea::vertical().show(ui, |ui| {
            ui.heading("shapeup");
            egui::CollapsingHeader::new("Mesh").default_open(true).show(ui, |ui| self.mesh_section(ui));
            ui.collapsing("Mouse", |ui| {
                ui.label(
                    "left drag: orbit · right or shift+left drag: pan · wheel: zoom\n\
                     ctrl+left drag: select visible vertices in a box (ctrl+alt adds, ctrl+shift removes)\n\
                     alt+left drag on a handle: move it · alt+right drag: rotate it\n\
                     gizmo on the active handle: drag an arrow, a square or a ring (shift snaps)\n\
                     gizmo on the collider picked in Contact: move or turn it (also while simulating)\n\
                     dynamics running: alt+left drag grabs and pulls the mesh\n\
                     ctrl+z / ctrl+shift+z: undo / redo",
                );
            });
            ui.separator();
            out.commands.extend(selection_panel(ui, &self.document, &mut self.selection));
            ui.separator();
            out.commands.extend(shape_model_panel(ui, &self.document));
            ui.separator();
            let hovered = self.groups.hovered;
            let active = self.groups.active_handle;
            out.extend(groups_panel(ui, &self.document, &mut self.groups));
            if self.groups.hovered != hovered {
                self.viewport.geometry_dirty = true;
            }
            if self.groups.active_handle != active {
                // A handle picked for the gizmo takes it from the collider.
                self.contact.selected = None;
            }

            ui.separator();
            out.extend(solver_panel(ui, &self.document, &self.view.progress));
            ui.separator();
            self.path_row(ui, DialogPurpose::ExportMesh);
            self.path_row(ui, DialogPurpose::SaveScene);
            ui.separator();
            egui::CollapsingHeader::new("Dynamics").default_open(true).show(ui, |ui| self.dynamics_section(ui));
            ui.separator();
            egui::CollapsingHeader::new("Contact").default_open(true).show(ui, |ui| {
                out.extend(contact_panel(ui, &self.document, &mut self.contact));
                self.path_row(ui, DialogPurpose::ColliderMesh);
            });
            ui.separator();
            ui.horizontal(|ui| {
                ui.checkbox(&mut self.viewport.wireframe, "Wireframe");
                if ui.button("Reset view").clicked() {
                    self.viewport.camera.reset();
                }
                if ui
                    .button("Screenshot")
                    .on_hover_text("save the 3D view as a PNG beside the Save row's scene (NAME-view-N.png)")
                    .clicked()
                {
                    self.request_screenshot(ui.ctx());
                }
            });
            self.viewport.gizmo.tool_selector(ui);
            ui.separator();
            stats_panel(ui, &self.document, &mut self.metrics, &self.view.progress, &self.view.energy_history);
        });
        // Slider drags form one undo step each.
        if out.drag_started {
            self.document.begin_drag();
        }
        self.end_drag |= out.drag_stopped;
        out.commands
    }

    /// The Dynamics panel, and what its action does to the simulation.
    fn dynamics_section(&mut self, ui: &mut egui::Ui) {
        let available = self.view.tetrahedralize.clone();
        let action = dynamics_panel(ui, &mut self.dynamics, self.simulation.as_ref(), available);
        match action {
            Some(DynamicsAction::RunFromRest) => {
                self.simulation = None;
                self.start_simulation(ui, StartShape::Rest);
            }
            Some(DynamicsAction::Continue) => {
                if self.simulation.is_none() {
                    self.start_simulation(ui, StartShape::OnScreen);
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
                    self.view.status =
                        "dynamics settings changed: Run from rest or Continue starts a new simulation".into();
                }
            }
            None => {}
        }
        if let Some(error) = self.simulation.as_ref().and_then(|r| r.stats().error) {
            self.view.banner = Some(format!("simulation: {error}"));
        }
    }

    /// Ctrl+S saves the scene to the Save row's path, Ctrl+O opens the Open dialog; outside a
    /// text field, F frames the selection (else the gizmo's handle, else the shape) and Esc
    /// clears the selection (returned as a command).
    fn shortcuts(&mut self, ctx: &egui::Context) -> Option<Command> {
        let typing = ctx.memory(|m| m.focused().is_some());
        let (save, open, frame, clear) = ctx.input_mut(|i| {
            let save = i.consume_key(egui::Modifiers::COMMAND, egui::Key::S);
            let open = i.consume_key(egui::Modifiers::COMMAND, egui::Key::O);
            let frame = !typing && i.consume_key(egui::Modifiers::NONE, egui::Key::F);
            let clear = !typing && i.consume_key(egui::Modifiers::NONE, egui::Key::Escape);
            (save, open, frame, clear)
        });
        if save {
            let path = PathBuf::from(self.files.scene_input.trim());
            self.act_on_path(DialogPurpose::SaveScene, path);
        }
        if open && !self.files.dialogs.is_open() {
            self.show_dialog(ctx, DialogPurpose::Open);
        }
        if frame {
            self.frame_selection();
        }
        (clear && self.document.num_selected() > 0).then_some(Command::ClearSelection)
    }

    /// Turns the view onto the selected vertices, else the gizmo's handle, else the whole
    /// shape (as it is now), keeping the view Reset view returns to.
    fn frame_selection(&mut self) {
        let selected = self.document.selected_vertices();
        let handle = self.groups.active_handle.and_then(|key| self.document.group(key)).and_then(|g| g.vertices());
        let vertices: Vec<usize> = match (selected.is_empty(), handle) {
            (false, _) => selected.iter().map(|&v| v as usize).collect(),
            (true, Some(list)) => list.to_vec(),
            (true, None) => (0..self.document.num_vertices()).collect(),
        };
        let positions = self.document.positions();
        let points: Vec<glam::DVec3> = vertices.iter().filter_map(|&v| positions.get(v).copied()).collect();
        if points.is_empty() {
            return;
        }
        let (lo, hi) = crate::picking::bounds(&points);
        self.viewport.camera.look_at(lo, hi);
    }

    /// A new simulation from `from`, running; undo brings back the shape from before it.
    fn start_simulation(&mut self, ui: &egui::Ui, from: StartShape) {
        let ctx = ui.ctx().clone();
        match SimulationRunner::start_from(&self.document, self.dynamics, from, move || ctx.request_repaint()) {
            Ok(runner) => {
                self.document.checkpoint();
                runner.set_running(true);
                self.simulation = Some(runner);
            }
            Err(e) => self.view.banner = Some(e.to_string()),
        }
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

    /// The bottom line: the convergence and the last message, always in view.
    fn status_bar(&mut self, ui: &mut egui::Ui) {
        // Wrapped, never cut at the window's edge.
        let stop = ui
            .horizontal_wrapped(|ui| {
                let p = &self.view.progress;
                let solving = self.worker.as_ref().is_some_and(SolverWorker::is_busy);
                let stop = solving
                    && ui
                        .button("Stop solving")
                        .on_hover_text("keep the shape reached; any change converges again")
                        .clicked();
                if !p.line.is_empty() {
                    ui.add(egui::Label::new(&p.line).wrap());
                    ui.separator();
                }
                ui.add(egui::Label::new(&self.view.status).wrap());
                stop
            })
            .inner;
        if stop && let Some(worker) = &mut self.worker {
            worker.stop();
        }
    }
}

/// A solver thread whose results wake the UI (so nothing redraws while waiting); `None` when the
/// thread cannot start (the editor then converges synchronously).
pub(super) fn spawn_worker(ctx: &egui::Context) -> Option<SolverWorker> {
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
        self.poll_screenshot();
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
        commands.extend(self.shortcuts(ui.ctx()));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        let panel = egui::Panel::left("controls").default_size(330.0).show(ui, |ui| self.side_panel(ui));
        commands.extend(panel.inner);
        let viewport = egui::CentralPanel::no_frame().show(ui, |ui| self.show_viewport(ui));
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
            self.metrics.print_stats(ui.ctx(), self.viewport.reduced_resolution, &self.view.progress);
        }
    }
}

/// Opens the editor window on a document and runs until it is closed; `path` is the mesh or
/// scene it came from.
///
/// # Errors
/// The windowing or graphics error (no display, no adapter…).
pub fn run_window(document: Document, path: PathBuf, window: WindowOptions) -> Result<(), eframe::Error> {
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
}
