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
//! 5. [`dynamics`] steps the same system in time (Projective Dynamics): inertia, gravity,
//!    damping, external forces and grabs.
//!
//! Every formula follows the math reference (`docs/math.md`).
//!
//! # Example
//! Pull one corner of a square of two triangles while the opposite corner stays put; edge
//! springs keep the edge lengths.
//! ```
//! use glam::DVec3;
//! use shapeup_core::prelude::*;
//!
//! let rest = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
//! let geometry = RestGeometry::new(rest.clone(), vec![[0, 1, 2], [0, 2, 3]], vec![]);
//! let ctx = BuildContext { rest: &geometry, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
//!
//! let mut system = System::new(4, SolverParams::default());
//! let springs = build_constraints("edge_spring", &ctx, Params::default())?;
//! system.add_group(ConstraintGroup::new("shape", 10.0, springs))?;
//! let fixed = Position::new(vec![0], vec![DVec3::ZERO]).unwrap();
//! system.add_group(ConstraintGroup::new("fixed", 1.0, vec![Box::new(fixed)]))?;
//! let pulled = Position::new(vec![2], vec![DVec3::new(2.0, 2.0, 0.0)]).unwrap();
//! let handle = system.add_group(ConstraintGroup::new("handle", 1.0, vec![Box::new(pulled)]))?;
//!
//! let mut q = rest.clone();
//! let report = system.solve(&mut q, 20, 0.0)?;
//! // E never increases (up to round-off once converged).
//! assert!(report.energies.windows(2).all(|e| e[1] <= e[0] * (1.0 + 1e-12)));
//! assert!(q[2].x > 1.2, "the pulled corner moved towards its target");
//!
//! // Dragging a handle only changes its targets: no refactorization.
//! system.set_targets(handle, &[DVec3::new(1.5, 0.5, 0.0)])?;
//! system.solve(&mut q, 20, 0.0)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![warn(missing_docs)]

pub mod bench;
pub mod constraints;
pub mod contact;
pub mod dynamics;
pub mod error;
pub mod generate;
pub mod geometry;
pub mod inspect;
pub mod io;
pub mod linalg;
pub mod materials;
pub mod mesh;
pub mod motion;
pub mod nearest;
pub mod scene;
pub mod solver;
#[cfg(feature = "tetgen")]
pub mod tetrahedralize;
pub mod text;
pub mod topology;
pub mod warnings;

pub use error::Error;

/// The attributes a mesh file carries, under their former path: they live in [`io`] now, beside
/// the readers that return them ([`io::LoadedMesh::attributes`]).
pub mod attributes {
    pub use crate::io::Attributes;
    pub use crate::io::attributes::{AttributeKind, NO_INDEX, TexCoords, VertexScalar};
}
pub use mesh::Mesh;

/// The types most programs need.
pub mod prelude {
    pub use crate::constraints::{
        BuildContext, Constraint, ConstraintType, Params, Position, RowSink, Selection, build_constraints,
    };
    pub use crate::dynamics::{DynamicsParams, Simulation};
    pub use crate::geometry::{RestGeometry, WorkingFrame};
    pub use crate::io::{read_mesh, write_mesh};
    pub use crate::mesh::Mesh;
    pub use crate::scene::{LoadedScene, Scene};
    pub use crate::solver::{ConstraintGroup, GroupId, SolveReport, SolverParams, System};
}
