//! # shapeup-core
//!
//! Constraint-based shape deformation (ShapeUp, Bouaziz et al. 2012) and physics simulation
//! (Projective Dynamics, Bouaziz et al. 2014) of triangle and tetrahedral meshes.
//!
//! The pipeline, module by module:
//! 1. [`io`] reads a mesh ([`mesh::Mesh`]); [`scene`] reads a scene file that names the mesh and
//!    its constraint groups.
//! 2. [`geometry`] maps it to the working frame and computes rest quantities
//!    ([`geometry::RestGeometry`]: areas, cotan weights) over its [`topology`].
//! 3. [`constraints`] builds the terms `w_i ‖C_i q − p_i(q)‖²` on selections.
//! 4. [`solver`] assembles `Σ w_i C_iᵀ C_i`, factors it once (sparse Cholesky), and iterates the
//!    local step (all projections, in parallel) and the global step (three triangular solves).
//!
//! Every formula follows the math reference (`shapeup-math.md`).
#![warn(missing_docs)]

pub mod bench;
pub mod constraints;
pub mod error;
pub mod geometry;
pub mod io;
pub mod linalg;
pub mod mesh;
pub mod scene;
pub mod solver;
pub mod topology;

pub use error::Error;
pub use mesh::Mesh;
