//! The solver's tests, one binary: invariants of a static solve, property tests on random small
//! meshes, and Projective Dynamics.
#![allow(clippy::unwrap_used, clippy::expect_used)]

#[path = "../common/mod.rs"]
mod common;

mod contact;
mod convergence;
mod dynamics;
mod invariants;
mod properties;
