//! Files: the bundled samples, the file rows' state ([`FilesState`]) and opening a file as a
//! document. The rows, dialogs and confirmations in a frame are in `files_ui`, above the app
//! shell.

use super::dialogs::FileDialogs;
use crate::document::Document;
use crate::error::EditorError;
use crate::group::DEFAULT_SHAPE_MODEL;
use shapeup_core::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};

/// The Samples menu: (label, entry): a bundled mesh's name ([`crate::samples`]) or the example
/// scene's path relative to the repository root.
pub const SAMPLES: [(&str, &str); 5] = [
    ("Stanford bunny", "stanford-bunny"),
    ("Spot", "spot"),
    ("Cow", "cow"),
    ("Suzanne (quads)", "suzanne"),
    ("Bunny ears (scene)", "examples/bunny-springs.toml"),
];

/// What a Samples entry opens: a bundled mesh by its name (read from memory, whatever the
/// working directory), or the example scene's file (relative to the working directory when
/// it exists there, else to the source tree).
pub fn sample_path(entry: &str) -> PathBuf {
    if crate::samples::Sample::find(entry).is_some() {
        return PathBuf::from(entry);
    }
    let local = PathBuf::from(entry);
    if local.exists() { local } else { PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join(entry) }
}

/// The file rows' typed paths, the dialogs, and the pending confirmations.
#[derive(Debug, Default)]
pub(super) struct FilesState {
    /// The Open row's path.
    pub(super) path_input: String,
    /// The Export row's path.
    pub(super) export_input: String,
    /// The Save row's path.
    pub(super) scene_input: String,
    /// The mesh collider row's path.
    pub(super) collider_input: String,
    /// A path to open once the user agrees to drop unsaved changes.
    pub(super) confirm_open: Option<PathBuf>,
    /// The window's close was asked for with unsaved changes: ask before closing.
    pub(super) confirm_close: bool,
    /// The user agreed to close without saving.
    pub(super) close_confirmed: bool,
    pub(super) dialogs: FileDialogs,
}

impl FilesState {
    /// The rows for a session opened from `path`.
    pub(super) fn new(path: &Path) -> Self {
        FilesState {
            path_input: path.display().to_string(),
            export_input: "deformed.obj".into(),
            scene_input: scene_name_for(path),
            ..FilesState::default()
        }
    }
}

/// Why a file cannot be opened in the editor.
#[derive(Debug, thiserror::Error)]
pub(super) enum OpenError {
    /// The scene file cannot be read or parsed.
    #[error(transparent)]
    SceneFile(#[from] SceneError),
    /// The scene cannot become a document.
    #[error("{}: {source}", path.display())]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// Why.
        #[source]
        source: EditorError,
    },
    /// The mesh cannot be read or used.
    #[error(transparent)]
    Mesh(EditorError),
}

/// A document from a scene file (`.toml`, `.json`) or a mesh file (with [`DEFAULT_SHAPE_MODEL`]).
///
/// A bare name with no file of that name is a bundled sample, as on the command line.
///
/// # Errors
/// [`OpenError`] naming the file.
pub(super) fn open_document(path: &Path) -> Result<Document, OpenError> {
    if let Some(sample) = crate::samples::resolve(path) {
        Document::open_sample(&sample, DEFAULT_SHAPE_MODEL).map_err(OpenError::Mesh)
    } else if is_scene_path(path) {
        let scene = Scene::from_file(path)?;
        Document::from_scene(&scene).map_err(|source| OpenError::Scene { path: path.to_path_buf(), source })
    } else {
        Document::open(path, DEFAULT_SHAPE_MODEL).map_err(OpenError::Mesh)
    }
}

/// Whether `path` names a scene file (.toml or .json).
pub(super) fn is_scene_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| matches!(e, "toml" | "json"))
}

/// The scene path proposed for saving: `STEM-session.toml` in the working directory.
pub(super) fn scene_name_for(path: &Path) -> String {
    // Never the opened scene itself: one click must not overwrite it (a bundled example, say).
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "session".into());
    format!("{stem}-session.toml")
}

/// The file name part of a typed path, proposed by save dialogs.
pub(super) fn file_name_of(typed: &str) -> String {
    Path::new(typed.trim()).file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}
