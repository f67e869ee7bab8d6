//! Why a scene cannot be read, parsed or built.

use crate::text::one_line;
use std::path::PathBuf;

/// A scene that cannot be read, parsed or built. Messages are one line naming the file and,
/// where known, the line or the `constraints[i]` entry.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file cannot be read.
    #[error("cannot read scene {}: {source}", one_line(path.display()))]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// Syntax or schema error (unknown key, wrong type…).
    #[error("{}: {}", one_line(path.display()), one_line(message))]
    Parse {
        /// The file.
        path: PathBuf,
        /// What and where (line, column).
        message: String,
    },
    /// A semantically invalid entry.
    #[error("{}: {}: {}", one_line(path.display()), one_line(entry), one_line(message))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// `constraints[2] ("handle")`, `[solver]`, `[mesh]`…
        entry: String,
        /// What is wrong.
        message: String,
    },
    /// The `[mesh] start` file cannot be read.
    #[error("{}: [mesh] start: {source}", one_line(path.display()))]
    Start {
        /// The scene file.
        path: PathBuf,
        /// The mesh error (names the start file).
        source: crate::io::IoError,
    },
    /// The mesh cannot be loaded.
    #[error("{}: {source}", one_line(path.display()))]
    Mesh {
        /// The scene file.
        path: PathBuf,
        /// The mesh error (names the mesh file).
        source: crate::io::IoError,
    },
    /// A dotted override ([`super::Scene::with_overrides`]) names no entry of the scene.
    #[error("override '{}': {}", one_line(key), one_line(problem))]
    Override {
        /// The dotted key as given.
        key: String,
        /// Which part names nothing.
        problem: String,
    },
    /// The constraints make an unsolvable system.
    #[error("{}: {source}", one_line(path.display()))]
    Solve {
        /// The scene file.
        path: PathBuf,
        /// Why.
        source: crate::solver::SolveError,
    },
}
