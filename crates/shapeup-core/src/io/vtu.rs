//! VTK XML unstructured grids (`.vtu`) and ParaView collections (`.pvd`). Write only.
//!
//! A `.vtu` file is written with the `vtkio` crate as a VTK XML `UnstructuredGrid` (file format
//! version 1.0, little endian, `UInt64` headers) whose arrays are inline base64 binary
//! (`format="binary"`, no compression): ParaView and every VTK reader open it, and unlike ASCII
//! it keeps each `Float64` coordinate bit for bit, in about half the size of shortest decimals.
//!
//! Cells are the mesh's tetrahedra (`VTK_TETRA`) when it has any, else its polygons as read
//! (`VTK_TRIANGLE`, `VTK_QUAD` or `VTK_POLYGON` by corner count; a degenerate face of one or
//! two corners as `VTK_VERTEX` or `VTK_LINE`); a mesh with neither is written as one
//! `VTK_VERTEX` per point. Point data: the caller's [`PointVectors`] (e.g. `velocity`), then
//! what the mesh's attributes hold per vertex — `normals` (recomputed from the written
//! geometry), `color` (r, g, b in [0, 1]), per-vertex texture coordinates `texcoords` (when
//! every corner of a vertex has the same pair) and each per-vertex scalar property under its
//! own name. Anything else is reported as dropped.
//!
//! The `.pvd` collection is a dozen lines of XML and is written by hand.

use std::io::{self, Write};

use glam::DVec3;
use vtkio::model::{
    Attribute, Attributes as VtkAttributes, ByteOrder, CellType, Cells, DataArray, DataSet, ElementType, IOBuffer,
    UnstructuredGridPiece, Version, VertexNumbers, Vtk,
};

use super::Attributes;
use super::attributes::{AttributeKind, NO_INDEX};
use crate::geometry::indexed_normals;
use crate::mesh::Mesh;
use crate::warnings::Warnings;

use super::report_dropped;

/// Per-point data written beside the positions (e.g. `velocity`), one 3-vector per vertex.
#[derive(Debug, Clone, Copy)]
pub struct PointVectors<'a> {
    /// Its name in the file.
    pub name: &'a str,
    /// One value per vertex.
    pub values: &'a [glam::DVec3],
}

/// Writes `mesh` as a VTK XML unstructured grid (see the [module docs](self)): its tetrahedra
/// if it has any, else its polygons; `point_vectors` as point data, then the attributes a
/// point array can hold. What it cannot keep is counted in `warnings`.
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] if a [`PointVectors`] does not have one
/// value per vertex, if two of them share a name, or for more than `u32::MAX` points or cells
/// (the format's counts). An attribute named like a [`PointVectors`] is dropped with a warning.
pub fn write_vtu(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    point_vectors: &[PointVectors<'_>],
    warnings: &mut Warnings,
) -> io::Result<()> {
    write_vtu_with_scalars(w, mesh, attributes, point_vectors, &[], warnings)
}

/// Per-point scalars written beside the positions (e.g. `contact`), one value per vertex.
#[derive(Debug, Clone, Copy)]
pub struct PointScalars<'a> {
    /// Its name in the file.
    pub name: &'a str,
    /// One value per vertex.
    pub values: &'a [f64],
}

/// [`write_vtu`] with per-point scalars after the vectors.
///
/// # Errors
/// As [`write_vtu`], for the scalars too.
pub fn write_vtu_with_scalars(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    point_vectors: &[PointVectors<'_>],
    point_scalars: &[PointScalars<'_>],
    warnings: &mut Warnings,
) -> io::Result<()> {
    let invalid = |message: String| io::Error::new(io::ErrorKind::InvalidInput, message);
    let n = mesh.positions.len();
    if let Some(v) = point_vectors.iter().find(|v| v.values.len() != n) {
        return Err(invalid(format!("point data '{}' has {} values for {n} points", v.name, v.values.len())));
    }
    let cells = cells(&super::in_file_order(mesh, attributes));
    // vtkio stores both counts as u32 (and panics past it).
    if u32::try_from(n).is_err() || u32::try_from(cells.types.len()).is_err() {
        return Err(invalid(format!("{n} points and {} cells: VTU counts are 32-bit", cells.types.len())));
    }

    let mut point = PointData::default();
    for v in point_vectors {
        if point.has(v.name) {
            return Err(invalid(format!("two point data arrays are named '{}'", v.name)));
        }
        point.push(v.name, ElementType::Vectors, flatten(v.values));
    }
    for s in point_scalars {
        if s.values.len() != n {
            return Err(invalid(format!("point data '{}' has {} values for {n} points", s.name, s.values.len())));
        }
        if point.has(s.name) {
            return Err(invalid(format!("two point data arrays are named '{}'", s.name)));
        }
        point.push(s.name, ElementType::Scalars { num_comp: 1, lookup_table: None }, s.values.to_vec().into());
    }
    // The mesh's own arrays come after the caller's, which keep their names on a clash.
    let mut add = |name: &str, elem: ElementType, data: IOBuffer| {
        if point.has(name) {
            warnings.add(
                "point_data_dropped",
                "per-vertex attributes named like another point array of the VTU file, dropped",
                || format!("'{name}'"),
            );
        } else {
            point.push(name, elem, data);
        }
    };
    let mut kept = Vec::new();
    if attributes.has_normals() {
        // Smooth per-vertex normals of the geometry as written; zero for a vertex in no face.
        let normals: Vec<DVec3> = indexed_normals(&mesh.positions, &mesh.polygons, mesh.polygons.indices(), n)
            .into_iter()
            .map(|normal| normal.unwrap_or(DVec3::ZERO))
            .collect();
        add("normals", ElementType::Normals, flatten(&normals));
        kept.push(AttributeKind::Normals);
    }
    if let Some(colors) = attributes.vertex_colors().filter(|c| c.len() == n) {
        let data: Vec<f64> = colors.iter().flatten().copied().collect();
        add("color", ElementType::Generic(3), data.into());
        kept.push(AttributeKind::VertexColors);
    }
    if let Some(uv) = per_vertex_texcoords(mesh, attributes) {
        add("texcoords", ElementType::TCoords(2), uv.into());
        kept.push(AttributeKind::TexCoords);
    }
    let scalars = attributes.vertex_scalars();
    if !scalars.is_empty() && scalars.iter().all(|s| s.values.len() == n) {
        for s in scalars {
            add(&s.name, ElementType::Scalars { num_comp: 1, lookup_table: None }, s.values.into());
        }
        kept.push(AttributeKind::VertexScalars);
    }
    report_dropped(attributes, &kept, "VTU", warnings);

    let vtk = Vtk {
        version: Version::new_xml(1, 0),
        title: String::new(),
        byte_order: ByteOrder::LittleEndian,
        file_path: None,
        data: DataSet::inline(UnstructuredGridPiece {
            points: flatten(&mesh.positions),
            cells,
            data: VtkAttributes { point: point.arrays, cell: Vec::new() },
        }),
    };
    // Encoded in memory first: vtkio's writer wraps `w` in a buffer whose final flush happens
    // on drop, where an I/O error would be lost.
    let mut bytes = Vec::new();
    vtk.write_xml(&mut bytes).map_err(|e| io::Error::other(format!("VTU encoding failed: {e}")))?;
    w.write_all(&bytes)?;
    w.write_all(b"\n")
}

/// The point data arrays, in order.
#[derive(Default)]
struct PointData {
    arrays: Vec<Attribute>,
}

impl PointData {
    fn has(&self, name: &str) -> bool {
        self.arrays.iter().any(|a| matches!(a, Attribute::DataArray(d) if d.name == name))
    }

    fn push(&mut self, name: &str, elem: ElementType, data: IOBuffer) {
        self.arrays.push(Attribute::DataArray(DataArray { name: name.to_owned(), elem, data }));
    }
}

/// The cells of the grid: tetrahedra, else polygons, else one vertex cell per point.
fn cells(mesh: &Mesh) -> Cells {
    let (connectivity, offsets, types): (Vec<u64>, Vec<u64>, Vec<CellType>) = if !mesh.tetrahedra.is_empty() {
        (
            mesh.tetrahedra.iter().flatten().map(|&v| u64::from(v)).collect(),
            (1..=mesh.tetrahedra.len() as u64).map(|i| 4 * i).collect(),
            vec![CellType::Tetra; mesh.tetrahedra.len()],
        )
    } else if !mesh.polygons.is_empty() {
        let types = mesh
            .polygons
            .iter()
            .map(|p| match p.len() {
                1 => CellType::Vertex,
                2 => CellType::Line,
                3 => CellType::Triangle,
                4 => CellType::Quad,
                _ => CellType::Polygon,
            })
            .collect();
        (
            mesh.polygons.indices().iter().map(|&v| u64::from(v)).collect(),
            mesh.polygons.offsets().iter().skip(1).map(|&o| o as u64).collect(),
            types,
        )
    } else {
        let n = mesh.positions.len() as u64;
        ((0..n).collect(), (1..=n).collect(), vec![CellType::Vertex; mesh.positions.len()])
    };
    Cells { cell_verts: VertexNumbers::XML { connectivity, offsets }, types }
}

/// x, y, z of each vector, one after the other, as a `Float64` array.
fn flatten(values: &[DVec3]) -> IOBuffer {
    values.iter().flat_map(|p| p.to_array()).collect::<Vec<f64>>().into()
}

/// The mesh's texture coordinates as (u, v) per vertex, when they are per vertex: every corner
/// of a vertex names the same pair (vertices in no face get (0, 0)). `None` when there are
/// none, or when some vertex has corners with different pairs (or without one), which a point
/// array cannot hold.
fn per_vertex_texcoords(mesh: &Mesh, attributes: &Attributes) -> Option<Vec<f64>> {
    let tex = attributes.texcoords(&mesh.polygons)?;
    if tex.corners.len() != mesh.polygons.num_corners() {
        return None;
    }
    let mut of_vertex = vec![NO_INDEX; mesh.positions.len()];
    for (&v, &t) in mesh.polygons.indices().iter().zip(&tex.corners) {
        let value = |i: u32| tex.values.get(i as usize).copied();
        let slot = of_vertex.get_mut(v as usize)?;
        value(t)?;
        if *slot == NO_INDEX {
            *slot = t;
        } else if *slot != t && value(*slot) != value(t) {
            return None;
        }
    }
    Some(of_vertex.iter().flat_map(|&t| tex.values.get(t as usize).copied().unwrap_or([0.0, 0.0])).collect())
}

/// Writes a ParaView data collection (`.pvd`): a time series of `entries`, each a time in
/// seconds and the path of its file relative to the `.pvd`. ParaView opens it as one dataset
/// whose time steps are those times.
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] for a time that is not finite.
pub fn write_pvd(w: &mut dyn Write, entries: &[(f64, &str)]) -> io::Result<()> {
    if let Some((t, file)) = entries.iter().find(|(t, _)| !t.is_finite()) {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, format!("{file}: time {t} is not finite")));
    }
    w.write_all(b"<?xml version=\"1.0\"?>\n")?;
    w.write_all(b"<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n")?;
    w.write_all(b"  <Collection>\n")?;
    for (t, file) in entries {
        // `{t:?}` is the shortest decimal that reads back to the same f64.
        writeln!(w, "    <DataSet timestep=\"{t:?}\" group=\"\" part=\"0\" file=\"{}\"/>", escape_attribute(file))?;
    }
    w.write_all(b"  </Collection>\n</VTKFile>\n")
}

/// `s` as the value of a double-quoted XML attribute.
fn escape_attribute(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn pvd_escapes_file_names_and_refuses_non_finite_times() {
        let mut out = Vec::new();
        write_pvd(&mut out, &[(0.5, "a&b\"<c>.vtu")]).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("timestep=\"0.5\"") && text.contains("file=\"a&amp;b&quot;&lt;c&gt;.vtu\""), "{text}");
        let err = write_pvd(&mut Vec::new(), &[(f64::NAN, "x.vtu")]).unwrap_err();
        assert_eq!(err.kind(), io::ErrorKind::InvalidInput);
    }
}
