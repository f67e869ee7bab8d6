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
    /// The length unit of the mesh's coordinates, with a `[material]` (default metres): the
    /// solver then works in metres, so moduli in pascals, densities in kg/m³ and gravity in
    /// m/s² mean what they say.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<Units>,
}

/// `[mesh] units`: the length unit of the mesh's coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Units {
    /// Metres (the default).
    #[default]
    M,
    /// Centimetres.
    Cm,
    /// Millimetres.
    Mm,
    /// Inches (25.4 mm).
    In,
}

impl Units {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            Units::M => 1.0,
            Units::Cm => 0.01,
            Units::Mm => 0.001,
            Units::In => 0.0254,
        }
    }

    /// The name in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Units::M => "m",
            Units::Cm => "cm",
            Units::Mm => "mm",
            Units::In => "in",
        }
    }
}

/// The `[material]` table: a hyperelastic model in physical units ([`crate::materials`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSettings {
    /// `"stvk"`, `"corotated"`, `"neo_hookean"`, or `"projective"` (no material: the scene's
    /// constraint groups alone, as without the table).
    pub model: String,
    /// Young's modulus E, Pa.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub youngs_modulus: Option<f64>,
    /// Poisson's ratio ν ∈ (−1, ½).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson_ratio: Option<f64>,
    /// Density ρ, kg/m³.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub density: Option<f64>,
    /// A shell's thickness h, metres (whatever `[mesh] units`): the material on a surface's
    /// triangles as a membrane ([`crate::materials::TriMembrane`]); absent for a solid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
}

/// The `[loads]` table: loads on the surface beside gravity (`[solver] gravity`) and the
/// constraint groups' forces.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSettings {
    /// A gas pressure p inside the surface ([`crate::materials::PressureTerm`]): pascals with a
    /// `[material]`, else a force per area in the scene's units (forces scaling like lengths);
    /// positive inflates. On every triangle of the surface (a tetrahedral mesh's boundary), which
    /// must be closed or held along its boundary.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pressure: Option<f64>,
    /// Wind on the surface's triangles, in a simulation ([`crate::materials::Wind`]); needs a
    /// `[material]` (its force is in newtons).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wind: Option<WindSettings>,
}

/// `[loads] wind = { velocity = [x, y, z], drag = 1.0, lift = 0.0, air_density = 1.225 }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WindSettings {
    /// The air's velocity, m/s.
    pub velocity: [f64; 3],
    /// C_D ≥ 0 (default 1).
    #[serde(default = "one")]
    pub drag: f64,
    /// C_L (default 0).
    #[serde(default)]
    pub lift: f64,
    /// ρ_air > 0, kg/m³ (default 1.225, sea level at 15 °C).
    #[serde(default = "sea_level_air")]
    pub air_density: f64,
}

fn one() -> f64 {
    1.0
}

fn sea_level_air() -> f64 {
    1.225
}

impl WindSettings {
    /// The wind, checked.
    ///
    /// # Errors
    /// One line naming the bad key.
    pub fn wind(&self) -> Result<crate::materials::Wind, String> {
        if let Some(x) = self.velocity.iter().find(|x| !x.is_finite()) {
            return Err(format!("wind velocity must be three finite numbers (m/s), found {x}"));
        }
        if !(self.drag.is_finite() && self.drag >= 0.0) {
            return Err(format!("wind drag must be a finite number ≥ 0, found {}", self.drag));
        }
        if !self.lift.is_finite() {
            return Err(format!("wind lift must be a finite number, found {}", self.lift));
        }
        if !(self.air_density.is_finite() && self.air_density > 0.0) {
            return Err(format!("wind air_density must be a finite number > 0 (kg/m³), found {}", self.air_density));
        }
        Ok(crate::materials::Wind {
            velocity: glam::DVec3::from_array(self.velocity),
            drag: self.drag,
            lift: self.lift,
            air_density: self.air_density,
        })
    }
}

/// Iterations a static solve or a time step with a material runs at most when `[solver]
/// iterations` is not given: a material runs to its tolerance, and this is only the guard.
pub const MATERIAL_ITERATIONS: usize = 1000;

/// `[solver] tolerance` with a material when the scene gives none: the relative change of the
/// objective at which a static solve or a time step stops.
pub const MATERIAL_TOLERANCE: f64 = 1e-10;

impl MaterialSettings {
    /// The material, checked; `None` for `model = "projective"`.
    ///
    /// # Errors
    /// One line naming the first bad key.
    pub fn material(&self) -> Result<Option<crate::materials::Material>, String> {
        let keys = [
            ("youngs_modulus", self.youngs_modulus),
            ("poisson_ratio", self.poisson_ratio),
            ("density", self.density),
            ("thickness", self.thickness),
        ];
        if self.model == "projective" {
            if let Some((key, _)) = keys.iter().find(|(_, v)| v.is_some()) {
                return Err(format!(
                    "model = \"projective\" (the constraint groups alone) takes no {key}: choose one of {} to give the material's moduli",
                    crate::materials::model_names().join(", ")
                ));
            }
            return Ok(None);
        }
        let mut values = [0.0; 3];
        for (value, (key, given)) in values.iter_mut().zip(&keys[..3]) {
            *value = given.ok_or_else(|| {
                format!("missing {key} (a material needs youngs_modulus in Pa, poisson_ratio and density in kg/m³)")
            })?;
        }
        let [e, nu, rho] = values;
        let material = crate::materials::Material::new(&self.model, e, nu, rho).map_err(|e| e.to_string())?;
        match self.thickness {
            Some(h) => material.with_thickness(h).map(Some).map_err(|e| e.to_string()),
            None => Ok(Some(material)),
        }
    }
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
