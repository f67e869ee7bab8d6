//! Files in the frame: the Open, Export and Save rows (a native dialog or a typed path), the
//! bundled samples, opening, exporting and saving, and the modals that ask before unsaved
//! changes are dropped. The rows' state ([`FilesState`]) and opening a file as a document live
//! in [`super::files`], beneath the app shell.

use super::app::{EditorApp, spawn_worker};
use super::dialogs::DialogPurpose;
use super::files::{SAMPLES, file_name_of, is_scene_path, open_document, sample_path, scene_name_for};
use super::metrics::SolveProgress;
use super::panels::count;
use crate::command::Command;
use crate::simulation::tetrahedralize_available;
use eframe::egui;
use std::path::PathBuf;

impl EditorApp {
    /// Opens `path` now, or asks first when the session has unsaved changes.
    pub(super) fn request_open(&mut self, path: PathBuf) {
        // A path that cannot be opened fails at once, without asking first.
        if self.document.is_modified() && path.is_file() {
            self.files.confirm_open = Some(path);
        } else {
            self.open(path);
        }
    }

    /// Opens a mesh or scene file in place of the document, or says why not.
    fn open(&mut self, path: PathBuf) {
        self.files.path_input = path.display().to_string();
        match open_document(&path) {
            Ok(document) => {
                self.document = document;
                self.mesh_path = path.clone();
                // A fresh worker: the old one holds the old mesh's system.
                self.worker = spawn_worker(&self.ctx);
                self.simulation = None;
                self.viewport.show_new_mesh(self.document.positions(), self.document.triangles());
                self.groups.hovered = None;
                self.groups.active_handle = None;
                self.contact.selected = None;
                self.view.touching.clear();
                self.view.banner = None;
                self.view.progress = SolveProgress::default();
                self.view.tetrahedralize = tetrahedralize_available(&self.document);
                self.view.energy_history.clear();
                self.files.scene_input = scene_name_for(&path);
                self.view.status = match crate::samples::resolve(&path) {
                    Some(sample) => format!("opened the bundled sample {}", sample.name),
                    None => format!("opened {}", path.display()),
                };
                let attached = self.document.num_attached_pieces();
                if attached > 0 && !is_scene_path(&path) {
                    self.view.status += &format!(
                        "; {} that sit on the body follow it (group \"attached pieces\"; remove it to let them go)",
                        count(attached, "piece", "pieces")
                    );
                }
                self.request_solve();
            }
            Err(e) => self.view.status = e.to_string(),
        }
    }

    /// Writes the current shape to `path`; says what was written (and what the format could
    /// not keep) or why not in the status line.
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
        self.files.export_input = path.display().to_string();
    }

    /// Saves the session as a scene at `path` (with its rest mesh when needed); says so in the
    /// status line.
    fn save_scene(&mut self, path: PathBuf) {
        self.view.status = match self.document.save_scene_with_mesh(&path) {
            Ok(saved) => {
                let mut line = format!("saved {}", path.display());
                if let Some(rest) = &saved.rest_mesh {
                    line.push_str(&format!(" and its rest mesh {}", rest.display()));
                }
                if let Some(start) = &saved.start_mesh {
                    line.push_str(&format!(" with the shape on screen as its start, {}", start.display()));
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
        self.files.scene_input = path.display().to_string();
    }

    /// Opens a native dialog (on its own thread) starting next to the current file.
    pub(super) fn show_dialog(&mut self, ctx: &egui::Context, purpose: DialogPurpose) {
        let directory = std::fs::canonicalize(&self.mesh_path).ok().and_then(|p| p.parent().map(PathBuf::from));
        let proposed = match purpose {
            DialogPurpose::Open | DialogPurpose::ColliderMesh => String::new(),
            DialogPurpose::ExportMesh => file_name_of(&self.files.export_input),
            DialogPurpose::SaveScene => file_name_of(&self.files.scene_input),
        };
        let ctx = ctx.clone();
        self.files.dialogs.show(purpose, directory, &proposed, move || ctx.request_repaint());
    }

    /// Opens, exports or saves to `path`, whether it came from a dialog or was typed.
    pub(super) fn act_on_path(&mut self, purpose: DialogPurpose, path: PathBuf) {
        match purpose {
            DialogPurpose::Open => self.request_open(path),
            DialogPurpose::ExportMesh => self.export_mesh(path),
            DialogPurpose::SaveScene => self.save_scene(path),
            DialogPurpose::ColliderMesh => {
                self.files.collider_input = path.display().to_string();
                if path.as_os_str().is_empty() {
                    self.view.status = "type the path of a mesh file first".into();
                    return;
                }
                let index = self.document.colliders().len();
                self.apply(vec![Command::AddCollider(crate::collider::mesh_collider(&path))]);
                if self.document.colliders().len() > index {
                    self.contact.selected = Some(index);
                    self.view.status = format!("added the mesh collider {}", path.display());
                }
            }
        }
    }

    /// Acts on a dialog's answer, if one came.
    pub(super) fn poll_dialogs(&mut self) {
        match self.files.dialogs.poll() {
            Some((purpose, Some(path))) => self.act_on_path(purpose, path),
            Some((_, None)) => {
                self.view.status = "no file chosen (without a file dialog service, type the path instead)".into();
            }
            None => {}
        }
    }

    /// One file row: the dialog button, the typed path (Enter acts on it), and the button acting
    /// on the typed path.
    pub(super) fn path_row(&mut self, ui: &mut egui::Ui, purpose: DialogPurpose) {
        let (browse_label, act_label, hint) = match purpose {
            DialogPurpose::Open => ("Open…", "Open", "open the typed mesh or scene file"),
            DialogPurpose::ExportMesh => ("Export…", "Export mesh", "write OBJ, PLY, STL or OFF to the typed path"),
            DialogPurpose::SaveScene => {
                ("Save…", "Save scene", "a scene file that `shapeup deform` replays to the converged shape")
            }
            DialogPurpose::ColliderMesh => {
                ("Mesh…", "Add mesh", "a collider from the typed mesh file (OBJ, PLY, STL, OFF)")
            }
        };
        ui.horizontal(|ui| {
            let browse = ui.add_enabled(!self.files.dialogs.is_open(), egui::Button::new(browse_label));
            if browse.clicked() {
                self.show_dialog(ui.ctx(), purpose);
            }
            let typed = match purpose {
                DialogPurpose::Open => &mut self.files.path_input,
                DialogPurpose::ExportMesh => &mut self.files.export_input,
                DialogPurpose::SaveScene => &mut self.files.scene_input,
                DialogPurpose::ColliderMesh => &mut self.files.collider_input,
            };
            let edit = ui.add(egui::TextEdit::singleline(typed).desired_width(140.0)).labelled_by(browse.id);
            let entered = edit.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
            let path = PathBuf::from(typed.trim());
            if ui.button(act_label).on_hover_text(hint).clicked() || entered {
                self.act_on_path(purpose, path);
            }
        });
    }

    /// The Open row, the drop hint and the Samples menu.
    pub(super) fn mesh_section(&mut self, ui: &mut egui::Ui) {
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

    /// Asks before dropping unsaved changes.
    pub(super) fn confirm_open_modal(&mut self, ctx: &egui::Context) {
        let Some(path) = self.files.confirm_open.clone() else { return };
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
                self.files.confirm_open = None;
                self.open(path);
            }
            Some(false) => {
                self.files.confirm_open = None;
                self.files.path_input = self.mesh_path.display().to_string();
            }
            None => {}
        }
    }

    /// Closing the window with unsaved changes asks first (as opening another mesh does).
    pub(super) fn confirm_close(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested()) && self.document.is_modified() && !self.files.close_confirmed {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.files.confirm_close = true;
        }
        if !self.files.confirm_close {
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
                self.files.confirm_close = false;
                self.files.close_confirmed = true;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            Some(false) => self.files.confirm_close = false,
            None => {}
        }
    }

    /// Whether the window is asking to confirm quitting with unsaved changes.
    pub fn is_confirming_close(&self) -> bool {
        self.files.confirm_close
    }
}
