//! Materials in physical units: hyperelastic energies Σ_T |V_T| Ψ(F_T) over tetrahedra,
//! minimized by the solver's L-BFGS with a line search (Liu, Bouaziz and Kavan, "Quasi-Newton
//! Methods for Real-Time Simulation of Hyperelastic Materials", ACM TOG 36(3), 2017).
//!
//! A model is one file: its energy density Ψ(F) (J/m³) and first Piola–Kirchhoff stress
//! P(F) = ∂Ψ/∂F (Pa) as functions of the deformation gradient F and the Lamé parameters, and a
//! line in [`MODELS`]. Everything else is generic: [`TetMaterial`] turns a model into a term of
//! the solver's energy, [`material_group`] builds it on every tetrahedron.
//!
//! How a material enters a solver made for projections (math reference, "Materials"): each
//! tetrahedron keeps the rows of `tet_strain` (C q = F) with the weight ω = |V_T| κ, κ the
//! model's stiffness at rest (here the P-wave modulus λ + 2μ), so the prefactored global matrix
//! is the Projective Dynamics matrix Liu et al. take as L-BFGS's initial Hessian. Its
//! "projection" is p = F − P(F)/κ: then ω (F − p) = |V_T| P(F), and the solver's gradient
//! A q − b(q) is exactly half the gradient of 2 Σ |V_T| Ψ. The energy the solver sees is
//! 2 |V_T| Ψ(F) per tetrahedron (the factor 2 is the solver's convention: a load adds −2 f·u,
//! so the solver's objective is twice the physical one, in joules). Since p is not a closest
//! point, the plain local-global step no longer lowers the energy by itself: with a material
//! every iteration is an L-BFGS step with a backtracking (Armijo) line search.

mod corotated;
mod membrane;
mod neo_hookean;
mod pressure;
mod stvk;
mod wind;

pub use corotated::Corotated;
pub use membrane::{TriMembrane, plane_stress_gradient, plane_stress_modulus, plane_stress_stretch_numeric};
pub use neo_hookean::NeoHookean;
pub use pressure::{PRESSURE_GROUP, PressureTerm, pressure_group};
pub use stvk::StVenantKirchhoff;
pub use wind::{Wind, add_wind_forces};

use crate::constraints::kit::gradient::TetGradient;
use crate::constraints::{Constraint, ConstraintGroup, RowSink};
use crate::geometry::RestGeometry;
use glam::{DMat3, DVec3};
use std::fmt::Debug;

/// Every model, by name: the one list scenes, the command line and Python read.
pub const MODELS: &[&dyn Hyperelastic] = &[&StVenantKirchhoff, &Corotated, &NeoHookean];

/// The model named `name` (`"stvk"`, `"corotated"`, `"neo_hookean"`).
pub fn model(name: &str) -> Option<&'static dyn Hyperelastic> {
    MODELS.iter().copied().find(|m| m.info().name == name)
}

/// Every model's name, in [`MODELS`] order.
pub fn model_names() -> Vec<&'static str> {
    MODELS.iter().map(|m| m.info().name).collect()
}

/// Lamé parameters μ (shear modulus) and λ, in pascals.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lame {
    /// μ = E / (2 (1 + ν)).
    pub mu: f64,
    /// λ = E ν / ((1 + ν)(1 − 2ν)).
    pub lambda: f64,
}

impl Lame {
    /// From Young's modulus E (Pa, > 0) and Poisson's ratio ν ∈ (−1, ½).
    ///
    /// # Errors
    /// [`MaterialError`] naming the value out of range.
    pub fn from_youngs(youngs_modulus: f64, poisson_ratio: f64) -> Result<Lame, MaterialError> {
        if !(youngs_modulus.is_finite() && youngs_modulus > 0.0) {
            return Err(MaterialError::YoungsModulus(youngs_modulus));
        }
        if !(poisson_ratio > -1.0 && poisson_ratio < 0.5) {
            return Err(MaterialError::PoissonRatio(poisson_ratio));
        }
        let (e, nu) = (youngs_modulus, poisson_ratio);
        Ok(Lame { mu: e / (2.0 * (1.0 + nu)), lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)) })
    }

    /// The P-wave modulus λ + 2μ: the stress per unit strain of a stretch with no lateral
    /// motion, and the weight κ each tetrahedron's rows get in the global matrix.
    pub fn p_wave_modulus(&self) -> f64 {
        self.lambda + 2.0 * self.mu
    }
}

/// A model's static description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelInfo {
    /// Name in scene files (`"neo_hookean"`).
    pub name: &'static str,
    /// One line for `--help`, menus and the docs.
    pub summary: &'static str,
}

/// An isotropic hyperelastic model: its energy density and stress as functions of the
/// deformation gradient F (3 × 3, dimensionless) and the Lamé parameters.
pub trait Hyperelastic: Sync + Debug {
    /// Name and summary.
    fn info(&self) -> &'static ModelInfo;
    /// Ψ(F), energy per rest volume (J/m³ for Lamé parameters in Pa); 0 at F = I.
    fn energy_density(&self, f: DMat3, lame: Lame) -> f64;
    /// The first Piola–Kirchhoff stress P(F) = ∂Ψ/∂F (Pa); 0 at F = I.
    fn first_piola(&self, f: DMat3, lame: Lame) -> DMat3;
    /// Plane stress (a membrane, [`TriMembrane`]): the stretch λ₃ ≥ 0 of the thickness that
    /// minimizes Ψ(diag(σ₁, σ₂, λ₃)) for in-plane singular values `sigma` = (σ₁, σ₂) ≥ 0; 1 at
    /// rest. Default: [`plane_stress_stretch_numeric`]; a model overrides it with its closed
    /// form (the tests check each against the numerical one).
    fn plane_stress_stretch(&self, sigma: [f64; 2], lame: Lame) -> f64 {
        plane_stress_stretch_numeric(self, sigma, lame)
    }
}

/// A material setting out of range.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialError {
    /// E not a finite number > 0.
    #[error("youngs_modulus must be a finite number > 0 (pascals), found {0}")]
    YoungsModulus(f64),
    /// ν outside (−1, ½).
    #[error("poisson_ratio must be greater than -1 and less than 0.5, found {0}")]
    PoissonRatio(f64),
    /// Fixed corotated with ν < 0: λ < 0 makes λ/2 (J − 1)² unbounded below as J grows, so
    /// a stretched part has no equilibrium.
    #[error(
        "the corotated model needs poisson_ratio ≥ 0 (with {0} its λ is negative and a stretched part has no equilibrium): take neo_hookean or stvk for an auxetic material"
    )]
    CorotatedAuxetic(f64),
    /// ρ not a finite number > 0.
    #[error("density must be a finite number > 0 (kg/m³), found {0}")]
    Density(f64),
    /// An unknown model name.
    #[error("unknown material model \"{0}\" (one of: {names})", names = model_names().join(", "))]
    UnknownModel(String),
    /// No tetrahedron to carry the material, and no thickness to make the surface a shell.
    #[error(
        "a solid material needs tetrahedra, and the mesh has none (or only flat ones): give a tetrahedral mesh (.msh, .node/.ele), generate = {{ kind = \"tet_box\", … }} or [mesh] tetrahedralize = true; or, for a surface (cloth, a balloon, a membrane), give [material] thickness in metres"
    )]
    NoTetrahedra,
    /// h not a finite number > 0.
    #[error("thickness must be a finite number > 0 (metres), found {0}")]
    Thickness(f64),
    /// A thickness on a tetrahedral mesh.
    #[error(
        "thickness is for a surface (a shell of that thickness), and the mesh has tetrahedra: leave thickness out for a solid"
    )]
    ThicknessOnSolid,
    /// A shell without a triangle of positive area.
    #[error("a shell needs triangles, and the surface has none of positive area")]
    NoTriangles,
}

/// A material: a model with its Young's modulus, Poisson's ratio and density.
#[derive(Debug, Clone, Copy)]
pub struct Material {
    /// The model.
    pub model: &'static dyn Hyperelastic,
    /// Lamé parameters from E and ν.
    pub lame: Lame,
    /// Mass density ρ, kg/m³.
    pub density: f64,
    /// A shell's thickness h in metres (a surface mesh: [`TriMembrane`]); `None` for a solid.
    pub thickness: Option<f64>,
}

impl Material {
    /// A checked material.
    ///
    /// # Errors
    /// [`MaterialError`] for an unknown model or a value out of range.
    pub fn new(model: &str, youngs_modulus: f64, poisson_ratio: f64, density: f64) -> Result<Material, MaterialError> {
        let model = self::model(model).ok_or_else(|| MaterialError::UnknownModel(model.into()))?;
        let lame = Lame::from_youngs(youngs_modulus, poisson_ratio)?;
        if model.info().name == "corotated" && lame.lambda < 0.0 {
            return Err(MaterialError::CorotatedAuxetic(poisson_ratio));
        }
        if !(density.is_finite() && density > 0.0) {
            return Err(MaterialError::Density(density));
        }
        Ok(Material { model, lame, density, thickness: None })
    }

    /// The material of a shell of `thickness` metres.
    ///
    /// # Errors
    /// [`MaterialError::Thickness`] unless h is a finite number > 0.
    pub fn with_thickness(self, thickness: f64) -> Result<Material, MaterialError> {
        if !(thickness.is_finite() && thickness > 0.0) {
            return Err(MaterialError::Thickness(thickness));
        }
        Ok(Material { thickness: Some(thickness), ..self })
    }
}

/// Name of the group a material builds, and the kind of its terms.
pub const MATERIAL_GROUP: &str = "material";

/// The hyperelastic term of one tetrahedron ([module docs](self)): rows F, weight |V_T| κ,
/// energy 2 |V_T| Ψ(F), "projection" F − P(F)/κ.
#[derive(Debug, Clone)]
pub struct TetMaterial {
    gradient: TetGradient,
    model: &'static dyn Hyperelastic,
    lame: Lame,
    /// κ = λ + 2μ.
    kappa: f64,
}

impl TetMaterial {
    /// The term of tetrahedron `vertices` of the rest shape `rest` (metres); `None` when it is
    /// flat: its rest volume at most 1e-12 ℓ³, ℓ its longest edge (relative, since a part in
    /// millimetres has tetrahedra of 1e-12 m³).
    pub fn new(vertices: [u32; 4], rest: &[DVec3], material: &Material) -> Option<Self> {
        let p = vertices.map(|v| rest[v as usize]);
        let longest = longest_edge(&p);
        TetGradient::with_min_volume(vertices, rest, 1e-12 * longest.powi(3)).map(|gradient| TetMaterial {
            gradient,
            model: material.model,
            lame: material.lame,
            kappa: material.lame.p_wave_modulus(),
        })
    }

    /// |V_T|, the rest volume.
    pub fn rest_volume(&self) -> f64 {
        self.gradient.rest_volume
    }
}

/// An element's longest edge: the largest distance between two of its corners `p` (what the
/// materials and the pressure measure their elements' size by).
fn longest_edge(p: &[DVec3]) -> f64 {
    let mut longest: f64 = 0.0;
    for (i, a) in p.iter().enumerate() {
        for b in &p[i + 1..] {
            longest = longest.max((*a - *b).length());
        }
    }
    longest
}

fn from_rows(rows: &[DVec3]) -> DMat3 {
    DMat3::from_cols(rows[0], rows[1], rows[2])
}

impl Constraint for TetMaterial {
    fn kind(&self) -> &'static str {
        MATERIAL_GROUP
    }
    fn vertices(&self) -> &[u32] {
        &self.gradient.vertices
    }
    fn element_weight(&self) -> f64 {
        self.gradient.rest_volume * self.kappa
    }
    fn num_rows(&self) -> usize {
        3
    }
    fn rows(&self, sink: &mut RowSink) {
        self.gradient.rows(sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let f = self.gradient.at(q);
        let p = f - self.model.first_piola(f, self.lame) * (1.0 / self.kappa);
        out[0] = p.x_axis;
        out[1] = p.y_axis;
        out[2] = p.z_axis;
    }
    fn is_projective(&self) -> bool {
        false
    }
    fn energy_from_rows(&self, cq: &[DVec3]) -> Option<f64> {
        Some(2.0 * self.gradient.rest_volume * self.model.energy_density(from_rows(cq), self.lame))
    }
    /// No set: a material has no shape it projects onto.
    fn set_residual(&self, _p: &[DVec3]) -> f64 {
        0.0
    }
    /// The Green strain's size ‖½(FᵀF − I)‖_F: 0 at rest or rotated, dimensionless.
    fn violation(&self, cq: &[DVec3]) -> f64 {
        let f = from_rows(cq);
        crate::linalg::frobenius2(&((f.transpose() * f - DMat3::IDENTITY) * 0.5)).sqrt()
    }
    fn length_power(&self) -> i32 {
        0
    }
}

/// The material's group on `rest` (working frame in metres), with multiplier `multiplier` (1
/// in static mode; 1/k in dynamic mode, where the solver divides every term by the stiffness
/// k): a solid's on every tetrahedron ([`TetMaterial`]), a shell's (a `thickness`) on every
/// triangle of a surface ([`TriMembrane`]). Also the indices of the flat elements (tetrahedra,
/// or triangles for a shell) that carry none, for the caller to say.
///
/// # Errors
/// [`MaterialError::NoTetrahedra`] for a solid without a tetrahedron of positive volume,
/// [`MaterialError::ThicknessOnSolid`] for a thickness on a tetrahedral mesh,
/// [`MaterialError::NoTriangles`] for a shell without a triangle of positive area.
pub fn material_group(
    rest: &RestGeometry,
    material: &Material,
    multiplier: f64,
) -> Result<(ConstraintGroup, Vec<usize>), MaterialError> {
    let mut flat = Vec::new();
    let mut terms: Vec<Box<dyn Constraint>> = Vec::new();
    match material.thickness {
        Some(_) if !rest.tetrahedra.is_empty() => return Err(MaterialError::ThicknessOnSolid),
        Some(h) => {
            for (i, t) in rest.triangles.iter().enumerate() {
                match TriMembrane::new(*t, &rest.positions, material, h) {
                    Some(c) => terms.push(Box::new(c)),
                    None => flat.push(i),
                }
            }
            if terms.is_empty() {
                return Err(MaterialError::NoTriangles);
            }
        }
        None => {
            for (i, t) in rest.tetrahedra.iter().enumerate() {
                match TetMaterial::new(*t, &rest.positions, material) {
                    Some(c) => terms.push(Box::new(c)),
                    None => flat.push(i),
                }
            }
            if terms.is_empty() {
                return Err(MaterialError::NoTetrahedra);
            }
        }
    }
    Ok((ConstraintGroup::new(MATERIAL_GROUP, multiplier, terms), flat))
}

#[cfg(test)]
mod tests;
