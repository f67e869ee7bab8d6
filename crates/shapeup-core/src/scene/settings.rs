//! The `[solver]`, `[mesh]` and `[output]` tables of a scene.

use super::GeneratedMesh;
use crate::dynamics::DynamicsParams;
use crate::solver::{Acceleration, Factorization, SolverParams};
use glam::DVec3;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Static (ShapeUp) or dynamic (Projective Dynamics) solving.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// Quasi-static shape deformation: minimize the constraint energy.
    #[default]
    Static,
    /// Time stepping with inertia, gravity and damping.
    Dynamic,
}

/// The `[solver]` table. Defaults as in the scene contract.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// "static" (default) or "dynamic".
    pub mode: Mode,
    /// Local-global iterations per step (default 10).
    pub iterations: usize,
    /// Static: total iterations = steps × iterations; dynamic: time steps (default 1).
    pub steps: usize,
    /// > 0: stop early when the relative energy change of an iteration is below it (default 0).
    pub tolerance: f64,
    /// Dynamic: time step h in seconds (default 1/60).
    pub time_step: f64,
    /// Dynamic: gravity in input units per s² (default (0, −9.81, 0)).
    pub gravity: [f64; 3],
    /// Dynamic: stiffness k (default 100).
    pub stiffness: f64,
    /// Dynamic: velocity damping d ∈ [0, 1) (default 0).
    pub damping: f64,
    /// Dynamic: density ρ (default 1).
    pub density: f64,
    /// Sparse Cholesky layout: "auto" (default), "simplicial" or "supernodal".
    pub factorization: Factorization,
    /// "lbfgs" (default), "anderson" or "none": see [`Acceleration`].
    pub acceleration: Acceleration,
    /// Anderson acceleration: iterations mixed, m ≥ 1 (default 5).
    pub anderson_window: usize,
    /// L-BFGS: pairs kept, m ≥ 1 (default 5).
    pub lbfgs_memory: usize,
}

impl Default for SolverSettings {
    /// Each default is the core's: the solver's from [`SolverParams::default`], time stepping's
    /// from [`DynamicsParams::default`].
    fn default() -> Self {
        let solver = SolverParams::default();
        let dynamics = DynamicsParams::default();
        SolverSettings {
            mode: Mode::Static,
            iterations: solver.iterations,
            steps: 1,
            tolerance: solver.tolerance,
            time_step: dynamics.time_step,
            gravity: dynamics.gravity.to_array(),
            stiffness: dynamics.stiffness,
            damping: dynamics.damping,
            density: 1.0,
            factorization: solver.factorization,
            acceleration: solver.acceleration,
            anderson_window: solver.anderson_window,
            lbfgs_memory: solver.lbfgs_memory,
        }
    }
}

impl SolverSettings {
    /// The solver's settings: iterations, tolerance, factorization and acceleration.
    pub fn solver_params(&self) -> SolverParams {
        SolverParams {
            iterations: self.iterations,
            tolerance: self.tolerance,
            factorization: self.factorization,
            acceleration: self.acceleration,
            anderson_window: self.anderson_window,
            lbfgs_memory: self.lbfgs_memory,
        }
    }

    /// The time-stepping settings in a working frame `scale` times the input's (gravity, an
    /// acceleration in input units per s², scales with lengths; time is not scaled).
    pub fn dynamics_params(&self, scale: f64) -> DynamicsParams {
        DynamicsParams {
            time_step: self.time_step,
            stiffness: self.stiffness,
            damping: self.damping,
            gravity: DVec3::from_array(self.gravity) * scale,
        }
    }
}

/// The `[mesh]` table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSettings {
    /// Mesh file, relative to the scene file (as written); empty when `generate` is used.
    #[serde(default)]
    pub path: PathBuf,
    /// A generated mesh instead of a file (an extension of the contract).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub generate: Option<GeneratedMesh>,
    /// Work in the normalized frame (default true).
    #[serde(default = "yes")]
    pub normalize: bool,
    /// Fill a closed surface with tetrahedra (default false).
    #[serde(default)]
    pub tetrahedralize: bool,
    /// A mesh file (relative to the scene file) of the same vertices in the same order whose
    /// positions the solve starts from instead of the rest shape (default none: from rest). The
    /// editor saves the shape on screen here, so that a replay converges to the same minimum
    /// of energies that have several.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start: Option<PathBuf>,
}

fn yes() -> bool {
    true
}

/// The `[output]` table: where a run's results go when the command line does not say
/// (`shapeup deform` without `-o`, `shapeup.batch.run_scenes`). Paths are relative to the scene
/// file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputSettings {
    /// Static mode: the deformed mesh (its extension picks the format); dynamic mode: the
    /// folder of the frames.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub path: Option<PathBuf>,
    /// The JSON report.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub report: Option<PathBuf>,
}
