//! Mesh I/O, one test program with a module per format (as `src/io/` is laid out) plus what all
//! formats share: encodings, safe writes and one-line errors.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../common/file_mesh.rs"]
mod file_mesh;

mod encodings;
mod formats;
mod msh_binary;
mod obj;
mod one_line_errors;
mod ply;
mod roundtrip;
mod safe_write;
mod tetgen_msh;
mod vtu;
