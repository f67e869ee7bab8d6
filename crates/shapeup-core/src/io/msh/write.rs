//! Writing MSH 4.1 ASCII.

use std::io::{self, Write};

use super::{TETRAHEDRON, TRIANGLE};
use crate::io::write_point;
use crate::mesh::Mesh;

/// Writes `mesh` as MSH 4.1 ASCII: node tags are vertex indices + 1; element tags number the
/// tetrahedra, then the triangles, from 1. Coordinates read back exactly.
///
/// # Errors
/// Any error of `w`.
pub fn write_msh(w: &mut dyn Write, mesh: &Mesh) -> io::Result<()> {
    let (n, t, m) = (mesh.num_vertices(), mesh.num_tetrahedra(), mesh.num_triangles());
    let dim = if t > 0 { 3 } else { 2 };
    writeln!(w, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 {n} 1 {n}\n{dim} 1 0 {n}")?;
    for tag in 1..=n {
        writeln!(w, "{tag}")?;
    }
    for p in &mesh.positions {
        write_point(w, *p)?;
    }
    let blocks = usize::from(t > 0) + usize::from(m > 0);
    let min_tag = usize::from(t + m > 0);
    writeln!(w, "$EndNodes\n$Elements\n{blocks} {} {min_tag} {}", t + m, t + m)?;
    if t > 0 {
        writeln!(w, "3 1 {TETRAHEDRON} {t}")?;
        for (k, [a, b, c, d]) in mesh.tetrahedra.iter().enumerate() {
            writeln!(w, "{} {} {} {} {}", k + 1, a + 1, b + 1, c + 1, d + 1)?;
        }
    }
    if m > 0 {
        writeln!(w, "2 1 {TRIANGLE} {m}")?;
        for (k, [a, b, c]) in mesh.triangles.iter().enumerate() {
            writeln!(w, "{} {} {} {}", t + k + 1, a + 1, b + 1, c + 1)?;
        }
    }
    writeln!(w, "$EndElements")
}
