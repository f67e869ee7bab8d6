//! The crate's top-level error, wrapping each module's own.

use crate::constraints::ConstraintError;
use crate::io::IoError;
use crate::mesh::MeshError;

/// Any error shapeup-core reports. Each variant's message is one line, meant for users.
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
}
