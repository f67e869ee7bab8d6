//! Errors of the core as Python exceptions: `SolveFailed`, and which `OSError`, `FileNotFoundError`,
//! `KeyError` (a scene override naming no entry) or `ValueError` each core error becomes.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyValueError};
use pyo3::prelude::*;
use shapeup_core::io::{IoError, OutputError, check_output_extension, check_output_folder};
use shapeup_core::scene::SceneError;
use shapeup_core::solver::SolveError;
use std::path::Path;

create_exception!(
    _shapeup,
    SolveFailed,
    PyException,
    "The solver refused: an unsolvable system (nothing anchors it), non-finite positions or energy."
);

pub(crate) fn value_error(message: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(message.to_string().replace('\n', " "))
}

pub(crate) fn solve_error(e: SolveError) -> PyErr {
    SolveFailed::new_err(e.to_string())
}

/// A missing or unreadable file is an `OSError` (`FileNotFoundError` when it is not there);
/// a file that is there but wrong is a `ValueError`.
pub(crate) fn io_error(e: IoError) -> PyErr {
    let message = e.to_string();
    match &e {
        IoError::Open { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            pyo3::exceptions::PyFileNotFoundError::new_err(message)
        }
        IoError::Open { .. } | IoError::Read { .. } | IoError::Write { .. } => PyOSError::new_err(message),
        _ => value_error(message),
    }
}

pub(crate) fn scene_error(e: SceneError) -> PyErr {
    match e {
        SceneError::Read { ref source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string())
        }
        SceneError::Read { .. } => PyOSError::new_err(e.to_string()),
        SceneError::Mesh { source: IoError::Open { ref source, .. }, .. }
        | SceneError::Start { source: IoError::Open { ref source, .. }, .. }
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string())
        }
        SceneError::Solve { .. } => SolveFailed::new_err(e.to_string()),
        // A dotted override that names no entry: a missing key, as a dict lookup would say.
        SceneError::Override { .. } => pyo3::exceptions::PyKeyError::new_err(e.to_string()),
        _ => value_error(e),
    }
}

/// The library's before-any-work output checks as Python exceptions: a missing folder is a
/// `FileNotFoundError`, a file where a folder should be a `NotADirectoryError`, an unwritable
/// folder an `OSError`, a folder where a file is wanted an `IsADirectoryError`, an extension a
/// `ValueError`.
pub(crate) fn output_error(e: OutputError) -> PyErr {
    match e {
        OutputError::MissingFolder { .. } => pyo3::exceptions::PyFileNotFoundError::new_err(e.to_string()),
        OutputError::NotAFolder { .. } => pyo3::exceptions::PyNotADirectoryError::new_err(e.to_string()),
        OutputError::Unwritable { .. } => PyOSError::new_err(e.to_string()),
        OutputError::IsAFolder { .. } => pyo3::exceptions::PyIsADirectoryError::new_err(e.to_string()),
        OutputError::Extension { .. } => value_error(e),
    }
}

pub(crate) fn check_folder(path: &Path) -> PyResult<()> {
    check_output_folder(path).map_err(output_error)
}

pub(crate) fn check_extension(path: &Path, allowed: &'static [&'static str]) -> PyResult<()> {
    check_output_extension(path, allowed).map_err(output_error)
}
