//! The crate's top-level error, wrapping each module's own: what a program that uses several
//! parts of the library (read a mesh, build a scene, solve, step) propagates with `?`.

use crate::constraints::ConstraintError;
use crate::dynamics::DynamicsError;
use crate::io::IoError;
use crate::mesh::MeshError;
use crate::scene::SceneError;
use crate::solver::SolveError;

/// Any error shapeup-core reports. Each variant's message is one line, meant for users, and
/// is the wrapped error's own.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Reading or writing a file.
    #[error(transparent)]
    Io(#[from] IoError),
    /// Bad mesh elements.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Building constraints.
    #[error(transparent)]
    Constraint(#[from] ConstraintError),
    /// Solving (a singular system, non-finite positions…).
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// Reading, checking or building a scene.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// Setting up or stepping a simulation.
    #[error(transparent)]
    Dynamics(#[from] DynamicsError),
}
