//! Native file dialogs (open, export, save scene, a mesh collider) on their own thread, so the editor keeps
//! drawing and solving while one is open. rfd talks to the XDG desktop portal and falls back to
//! zenity; where neither exists the dialog returns nothing and the typed-path fields remain.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};

/// What a dialog is for; decides its title, filters and what happens with the chosen path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DialogPurpose {
    /// Open a mesh or a scene.
    Open,
    /// Export the current mesh.
    ExportMesh,
    /// Save the session as a scene file.
    SaveScene,
    /// Add a mesh collider from a mesh file.
    ColliderMesh,
}

const MESH_EXTENSIONS: [&str; 4] = ["obj", "ply", "stl", "off"];
const SCENE_EXTENSIONS: [&str; 2] = ["toml", "json"];

/// At most one dialog open at a time; its answer arrives through [`FileDialogs::poll`].
#[derive(Debug)]
pub struct FileDialogs {
    sender: Sender<(DialogPurpose, Option<PathBuf>)>,
    receiver: Receiver<(DialogPurpose, Option<PathBuf>)>,
    open: bool,
}

impl Default for FileDialogs {
    fn default() -> Self {
        let (sender, receiver) = channel();
        FileDialogs { sender, receiver, open: false }
    }
}

impl FileDialogs {
    /// Whether a dialog is open (its button is disabled meanwhile).
    pub fn is_open(&self) -> bool {
        self.open
    }

    /// Shows a dialog starting in `directory` with `file_name` proposed (save dialogs);
    /// `wake` is called when it closes, so the UI polls the answer.
    pub fn show(
        &mut self,
        purpose: DialogPurpose,
        directory: Option<PathBuf>,
        file_name: &str,
        wake: impl Fn() + Send + 'static,
    ) {
        if self.open {
            return;
        }
        let mut dialog = rfd::FileDialog::new();
        if let Some(dir) = directory.filter(|d| d.is_dir()) {
            dialog = dialog.set_directory(dir);
        }
        dialog = match purpose {
            DialogPurpose::Open => dialog
                .set_title("Open a mesh or a scene")
                .add_filter("Meshes and scenes", &[&MESH_EXTENSIONS[..], &SCENE_EXTENSIONS[..]].concat())
                .add_filter("Meshes", &MESH_EXTENSIONS)
                .add_filter("Scenes", &SCENE_EXTENSIONS),
            DialogPurpose::ExportMesh => dialog
                .set_title("Export the current mesh")
                .add_filter("Meshes", &MESH_EXTENSIONS[..3])
                .set_file_name(file_name),
            DialogPurpose::SaveScene => dialog
                .set_title("Save the session as a scene")
                .add_filter("Scenes", &SCENE_EXTENSIONS)
                .set_file_name(file_name),
            DialogPurpose::ColliderMesh => {
                dialog.set_title("Add a mesh collider").add_filter("Meshes", &MESH_EXTENSIONS)
            }
        };
        let sender = self.sender.clone();
        let spawned = std::thread::Builder::new().name("shapeup-file-dialog".into()).spawn(move || {
            let path = match purpose {
                DialogPurpose::Open | DialogPurpose::ColliderMesh => dialog.pick_file(),
                DialogPurpose::ExportMesh | DialogPurpose::SaveScene => dialog.save_file(),
            };
            // The editor may have closed meanwhile; then nobody needs the answer.
            let _ = sender.send((purpose, path));
            wake();
        });
        self.open = spawned.is_ok();
    }

    /// The answer of the dialog that closed since the last poll (`None` path: cancelled, or no
    /// dialog service), without blocking.
    pub fn poll(&mut self) -> Option<(DialogPurpose, Option<PathBuf>)> {
        match self.receiver.try_recv() {
            Ok(answer) => {
                self.open = false;
                Some(answer)
            }
            Err(TryRecvError::Empty | TryRecvError::Disconnected) => None,
        }
    }
}
