//! `_Mesh` and the mesh functions: read, write, build from arrays.

use crate::convert::{index_array, points, rows, to_array, warnings_list};
use crate::errors::{io_error, value_error};
use numpy::{PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use shapeup_core::io::Attributes;
use shapeup_core::mesh::{Mesh as CoreMesh, Polygons};
use shapeup_core::warnings::Warnings;
use std::path::{Path, PathBuf};

/// A mesh as the library holds it: positions, polygons (kept as they are), their
/// triangulation, tetrahedra and attributes (texture coordinates, normals, colours, scalars).
#[pyclass(name = "_Mesh", module = "shapeup._shapeup", frozen)]
pub(crate) struct PyMesh {
    pub(crate) mesh: CoreMesh,
    /// What the file carried besides the mesh (kept for writing it back).
    pub(crate) attributes: Attributes,
    pub(crate) warnings: Warnings,
}

#[pymethods]
impl PyMesh {
    /// Vertex positions, float64 (n, 3).
    #[getter]
    fn vertices<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        to_array(py, &self.mesh.positions)
    }

    /// The triangulation of the polygons, int64 (m, 3).
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        index_array(py, &self.mesh.triangles)
    }

    /// Tetrahedra, int64 (t, 4).
    #[getter]
    fn tetrahedra<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<i64>> {
        index_array(py, &self.mesh.tetrahedra)
    }

    /// The polygons as (corner indices, offsets): polygon i is `indices[offsets[i]:offsets[i+1]]`.
    #[getter]
    fn polygon_arrays(&self) -> (Vec<i64>, Vec<i64>) {
        let indices = self.mesh.polygons.indices().iter().map(|&v| i64::from(v)).collect();
        let offsets = self.mesh.polygons.offsets().iter().map(|&o| o as i64).collect();
        (indices, offsets)
    }

    /// Texture coordinates as (values float64 (k, 2), corner → value index int64 per polygon
    /// corner, -1 where a corner has none), or None.
    #[getter]
    fn texcoords(&self) -> Option<(Vec<[f64; 2]>, Vec<i64>)> {
        let t = self.attributes.texcoords(&self.mesh.polygons)?;
        let corners =
            t.corners.iter().map(|&c| if c == shapeup_core::io::NO_INDEX { -1 } else { i64::from(c) }).collect();
        Some((t.values, corners))
    }

    /// Per-vertex colours (r, g, b in [0, 1]), or None.
    #[getter]
    fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        self.attributes.vertex_colors()
    }

    /// Per-vertex scalar properties as {name: values}.
    #[getter]
    fn vertex_scalars(&self) -> Vec<(String, Vec<f64>)> {
        self.attributes.vertex_scalars().into_iter().map(|s| (s.name, s.values)).collect()
    }

    /// What the file carries besides positions and faces, one description each.
    #[getter]
    fn attributes(&self) -> Vec<String> {
        self.attributes.kinds().iter().map(|k| k.describe()).collect()
    }

    /// What reading or building the mesh changed or left out, one line each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        warnings_list(&self.warnings)
    }

    /// The kind of each of [`PyMesh::warnings`] (`duplicate_faces`, …), in the same order.
    #[getter]
    fn warning_kinds(&self) -> Vec<String> {
        self.warnings.iter().map(|w| w.kind.clone()).collect()
    }

    /// The same mesh (faces, attributes) with other positions, float64 (n, 3).
    fn with_vertices(&self, vertices: PyReadonlyArray2<'_, f64>) -> PyResult<PyMesh> {
        let positions = points(&vertices, "V")?;
        if positions.len() != self.mesh.num_vertices() {
            return Err(value_error(format!(
                "V has {} rows but the mesh has {} vertices",
                positions.len(),
                self.mesh.num_vertices()
            )));
        }
        Ok(PyMesh {
            mesh: self.mesh.with_positions(positions),
            attributes: self.attributes.clone(),
            warnings: Warnings::new(),
        })
    }

    fn __len__(&self) -> usize {
        self.mesh.num_vertices()
    }
}

/// Reads a mesh file (.obj .ply .off .stl .msh .vtu .node/.ele), as the command line does.
#[pyfunction]
pub(crate) fn read_mesh(py: Python<'_>, path: PathBuf) -> PyResult<PyMesh> {
    let loaded = py.detach(|| shapeup_core::io::read_mesh(&path)).map_err(io_error)?;
    Ok(PyMesh { mesh: loaded.mesh, attributes: loaded.attributes, warnings: loaded.warnings })
}

/// Writes a mesh (format from the extension), atomically; returns what writing it said.
#[pyfunction]
pub(crate) fn write_mesh(py: Python<'_>, path: PathBuf, mesh: &PyMesh) -> PyResult<Vec<String>> {
    let warnings = py.detach(|| shapeup_core::io::write_mesh(&path, &mesh.mesh, &mesh.attributes)).map_err(io_error)?;
    Ok(warnings_list(&warnings))
}

/// A mesh from arrays: V (n, 3); polygons as (indices, offsets) or None; T (t, 4) or None.
#[pyfunction]
#[pyo3(signature = (vertices, polygons=None, tetrahedra=None))]
pub(crate) fn mesh_from_arrays(
    vertices: PyReadonlyArray2<'_, f64>,
    polygons: Option<(PyReadonlyArray1<'_, i64>, PyReadonlyArray1<'_, i64>)>,
    tetrahedra: Option<PyReadonlyArray2<'_, i64>>,
) -> PyResult<PyMesh> {
    let positions = points(&vertices, "V")?;
    let mut faces = Polygons::new();
    if let Some((indices, offsets)) = &polygons {
        let indices = indices.as_slice().map_err(|_| value_error("polygon indices must be contiguous"))?;
        let offsets = offsets.as_slice().map_err(|_| value_error("polygon offsets must be contiguous"))?;
        let mut corners = Vec::new();
        for (i, w) in offsets.windows(2).enumerate() {
            let (a, b) = (usize::try_from(w[0]).unwrap_or(0), usize::try_from(w[1]).unwrap_or(0));
            let slice = indices.get(a..b).ok_or_else(|| value_error(format!("F: polygon {i} has bad offsets")))?;
            corners.clear();
            for &v in slice {
                corners.push(u32::try_from(v).map_err(|_| value_error(format!("F: face {i} has index {v}")))?);
            }
            faces.push(&corners);
        }
    }
    let (mut mesh, mut warnings) = CoreMesh::from_polygons(positions, faces).map_err(value_error)?;
    if let Some(t) = &tetrahedra {
        mesh.tetrahedra = rows::<4>(t, "T")?;
        mesh.validate().map_err(value_error)?;
    }
    if mesh.triangles.is_empty() && mesh.tetrahedra.is_empty() {
        let why = mesh.why_no_triangles();
        return Err(value_error(if why.is_empty() {
            "the mesh has no faces and no tetrahedra: give F or T".to_owned()
        } else {
            format!("F has no face that can be triangulated{why}")
        }));
    }
    warnings = warnings.for_file(Path::new("<arrays>"));
    Ok(PyMesh { mesh, attributes: Attributes::None, warnings })
}
