//! The mesh and what is computed from it: polygon triangulation and `shapeup info`'s inspection.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../common/mod.rs"]
mod common;

mod inspect;
mod polygons;
