//! VTK XML unstructured grids (`.vtu`) and ParaView collections (`.pvd`). Write only.

use std::io::{self, Write};

use crate::mesh::Mesh;
use crate::warnings::Warnings;

/// Per-point data written beside the positions (e.g. `velocity`), one 3-vector per vertex.
#[derive(Debug, Clone, Copy)]
pub struct PointVectors<'a> {
    /// Its name in the file.
    pub name: &'a str,
    /// One value per vertex.
    pub values: &'a [glam::DVec3],
}

/// Writes `mesh` as a VTK XML unstructured grid: its tetrahedra if it has any, else its
/// polygons; `point_vectors` as point data.
///
/// # Errors
/// Any error of `w`.
pub fn write_vtu(
    _w: &mut dyn Write,
    _mesh: &Mesh,
    _point_vectors: &[PointVectors<'_>],
    _warnings: &mut Warnings,
) -> io::Result<()> {
    Err(io::Error::other("VTU output is not implemented yet"))
}
