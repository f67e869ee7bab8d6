//! Arrays in and out: numpy arrays as points and index rows, and back.

use crate::errors::value_error;
use glam::DVec3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use shapeup_core::warnings::Warnings;

/// (n, 3) float64 rows as points, read in place from a C-contiguous array.
pub(crate) fn points(array: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<Vec<DVec3>> {
    let shape = array.shape();
    if shape[1] != 3 {
        return Err(value_error(format!("{what} must have shape (n, 3), found {shape:?}")));
    }
    let flat = array.as_slice().map_err(|_| value_error(format!("{what} must be C-contiguous")))?;
    Ok(flat.chunks_exact(3).map(|p| DVec3::new(p[0], p[1], p[2])).collect())
}

/// Points as a new (n, 3) float64 array.
pub(crate) fn to_array<'py>(py: Python<'py>, points: &[DVec3]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = points.iter().flat_map(|p| p.to_array()).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((points.len(), 3), flat).unwrap_or_else(|_| Array2::zeros((0, 3))).into_pyarray(py)
}

/// Index rows (triangles, tetrahedra) as a new (m, K) int64 array.
pub(crate) fn index_array<'py, const K: usize>(py: Python<'py>, rows: &[[u32; K]]) -> Bound<'py, PyArray2<i64>> {
    let flat: Vec<i64> = rows.iter().flatten().map(|&v| i64::from(v)).collect();
    // The shape matches the data by construction.
    Array2::from_shape_vec((rows.len(), K), flat).unwrap_or_else(|_| Array2::zeros((0, K))).into_pyarray(py)
}

/// Rows of an (m, k) int64 array as `[u32; K]` (the Python side checked range and sign).
pub(crate) fn rows<const K: usize>(array: &PyReadonlyArray2<'_, i64>, what: &str) -> PyResult<Vec<[u32; K]>> {
    let shape = array.shape();
    if shape[1] != K {
        return Err(value_error(format!("{what} must have shape (m, {K}), found {shape:?}")));
    }
    let flat = array.as_slice().map_err(|_| value_error(format!("{what} must be C-contiguous")))?;
    flat.chunks_exact(K)
        .map(|row| {
            let mut out = [0u32; K];
            for (o, &v) in out.iter_mut().zip(row) {
                *o = u32::try_from(v).map_err(|_| value_error(format!("{what}: index {v} is out of range")))?;
            }
            Ok(out)
        })
        .collect()
}

pub(crate) fn warnings_list(warnings: &Warnings) -> Vec<String> {
    warnings.iter().map(ToString::to_string).collect()
}
