//! End-to-end tests of the `shapeup` binary, one test program (one link) with a module per
//! concern: real processes, real files, outcomes read back with `shapeup_core`.
#![allow(clippy::unwrap_used, clippy::expect_used, dead_code)]

mod common;

mod contract;
mod conventions;
mod frames;
mod materials;
mod obj_assets;
mod ply_assets;
#[cfg(feature = "gui")]
mod view;
