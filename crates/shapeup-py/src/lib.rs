//! `shapeup._shapeup`: the Rust half of the `shapeup` Python package. The Python half
//! (`python/shapeup/`) checks shapes and dtypes, builds group entries and documents the API;
//! this module moves arrays in and out of `shapeup-core` and runs it without the GIL.
//!
//! One file per concept, as the Python modules: [`mesh`], [`types`], [`groups`] and
//! [`contact`] (the calls `_Solver` and `_Simulation` share), [`solver`], [`simulation`],
//! [`scene`]; [`convert`] and [`errors`] hold the array conversions and exception mapping they
//! all use, [`signals`] the Ctrl+C check of long runs.

mod contact;
mod convert;
mod errors;
mod groups;
mod mesh;
mod scene;
mod signals;
mod simulation;
mod solver;
mod types;

use pyo3::prelude::*;

/// Sets the worker threads of the parallel local step (once, before the first solve).
#[pyfunction]
fn set_threads(n: usize) -> PyResult<()> {
    rayon::ThreadPoolBuilder::new().num_threads(n).build_global().map_err(|e| {
        errors::value_error(format!("cannot set the threads: {e} (set them once, before the first solve)"))
    })
}

#[pymodule]
fn _shapeup(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(mesh::read_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::write_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(mesh::mesh_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(types::constraint_types, m)?)?;
    m.add_function(wrap_pyfunction!(types::catalogue_markdown, m)?)?;
    m.add_function(wrap_pyfunction!(set_threads, m)?)?;
    // Above it a static solve stopped at its iteration cap short of its minimum.
    m.add("STATIC_RESIDUAL_LIMIT", shapeup_core::solver::STATIC_RESIDUAL_LIMIT)?;
    m.add("DYNAMIC_RESIDUAL_LIMIT", shapeup_core::dynamics::DYNAMIC_RESIDUAL_LIMIT)?;
    m.add_class::<mesh::PyMesh>()?;
    m.add_class::<types::TypeInfo>()?;
    m.add_class::<solver::PySolver>()?;
    m.add_class::<simulation::PySimulation>()?;
    m.add_class::<scene::PyScene>()?;
    m.add("SolveFailed", m.py().get_type::<errors::SolveFailed>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
