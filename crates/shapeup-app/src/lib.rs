//! The shapeup editor: open a mesh, select vertices, fix them as handles, drag them and watch
//! the shape follow. It talks to the solver only through `shapeup-core`'s public API.
//!
//! This crate is the editor's model, with no GUI dependency, so that all of it is tested
//! without a window:
//! - [`camera`]: the orbit camera (view, projection, pixel ↔ ray, drags in the view plane);
//! - [`picking`]: occlusion-aware vertex picking and box selection on a CPU depth buffer;
//! - [`group`]: what a constraint group is in the editor: the scene's description of it
//!   (`GroupSpec`) with a key and a role; the shape models;
//! - [`edit_state`]: the rest shape, the edit state undo snapshots, and the solver behind it;
//! - [`pieces`]: the mesh's connected pieces;
//! - [`collider`]: colliders in the editor (defaults around the mesh, moves and turns, their
//!   outlines) and the core's contact model of them;
//! - [`document`]: the mesh, its constraint groups (shape model, handles, smoothing), the
//!   selection, the current shape, undo/redo and scene round trips;
//! - [`command`]: the [`command::Command`]s a panel or a drag emits, applied by
//!   [`document::Document::apply`], and what each can change ([`command::Effect`]);
//! - [`error`]: [`EditorError`], one line for the status bar, keeping its source;
//! - [`gizmo`]: the handle gizmo's picking, drag math and tessellation, framework-agnostic;
//! - [`worker`]: a background solver thread, so the UI never waits for a solve;
//! - [`simulation`]: dynamic mode, a Projective Dynamics simulation built from the document's
//!   groups, on its own thread (run/pause, gravity, floor, tetrahedra, grab, colliders);
//! - `gui` (feature `gui`): the window (the app shell, one file per panel, the viewport, files
//!   and dialogs, metrics) and headless rendering.
#![warn(missing_docs)]

pub mod camera;
pub mod collider;
pub mod command;
pub mod document;
pub mod edit_state;
pub mod error;
pub mod gizmo;
pub mod group;
pub mod picking;
pub mod pieces;
pub mod samples;
pub mod simulation;
pub mod worker;

pub use camera::OrbitCamera;
pub use command::{Command, Effect, SelectMode};
pub use document::Document;
pub use error::EditorError;
pub use group::{GroupKey, ShapeModel};
pub use worker::{SolveResult, SolverWorker};

/// The windowed editor and headless rendering.
#[cfg(feature = "gui")]
pub mod gui;
