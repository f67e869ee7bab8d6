//! The constraint suite in one binary: registry-wide checks of every type (`catalogue`),
//! property tests on random meshes (`properties`) and vertices of degenerate faces
//! (`degenerate`).
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../common/mod.rs"]
mod common;

mod catalogue;
mod degenerate;
mod properties;
