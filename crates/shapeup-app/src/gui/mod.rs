//! The windowed editor and headless rendering (feature `gui`).

pub mod app;
pub mod dialogs;
pub mod dynamics_panel;
pub mod files;
mod files_ui;
pub mod gizmo;
pub mod headless;
mod metrics;
mod panels;
pub mod renderer;
mod screenshot;
pub mod viewport;
mod viewport_ui;

/// The first view of a mesh: a three-quarter view from the +z side, slightly from above.
pub const INITIAL_YAW: f32 = 0.5;
/// See [`INITIAL_YAW`].
pub const INITIAL_PITCH: f32 = 0.25;
