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

/// The largest distance between corresponding points of `a` and `b` (of one length).
fn max_distance(a: &[glam::DVec3], b: &[glam::DVec3]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max)
}
