//! The editor model's integration tests in one binary (one link instead of seven), a module per
//! area; `editor_ui` drives the real UI and needs the `gui` feature.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod camera;
mod catalogue;
mod contact;
mod document;
#[cfg(feature = "gui")]
mod editor_ui;
mod gizmo;
mod simulation;
mod worker;
