//! Saint Venant–Kirchhoff: linear elasticity's energy on the Green strain.
//!
//! Ψ(F) = μ E:E + (λ/2) (tr E)²,  E = ½ (FᵀF − I),
//! P(F) = ∂Ψ/∂F = F (2μ E + λ tr(E) I).
//!
//! Source: Sifakis and Barbič, "FEM Simulation of 3D Deformable Solids", SIGGRAPH 2012 course
//! notes, §3.4. Exact for large rotations; softens under strong compression (it collapses
//! rather than resisting an inversion), which is why the stable Neo-Hookean model is the one to
//! take for large compressions.

use super::{Hyperelastic, Lame, ModelInfo};
use glam::DMat3;

/// Saint Venant–Kirchhoff ([module docs](self)).
#[derive(Debug, Clone, Copy)]
pub struct StVenantKirchhoff;

const INFO: ModelInfo =
    ModelInfo { name: "stvk", summary: "Saint Venant–Kirchhoff: μ E:E + λ/2 (tr E)², E the Green strain" };

/// E = ½ (FᵀF − I).
fn green_strain(f: DMat3) -> DMat3 {
    (f.transpose() * f - DMat3::IDENTITY) * 0.5
}

impl Hyperelastic for StVenantKirchhoff {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }
    fn energy_density(&self, f: DMat3, lame: Lame) -> f64 {
        let e = green_strain(f);
        let trace = e.x_axis.x + e.y_axis.y + e.z_axis.z;
        lame.mu * crate::linalg::frobenius2(&e) + 0.5 * lame.lambda * trace * trace
    }
    fn first_piola(&self, f: DMat3, lame: Lame) -> DMat3 {
        let e = green_strain(f);
        let trace = e.x_axis.x + e.y_axis.y + e.z_axis.z;
        f * (e * (2.0 * lame.mu) + DMat3::IDENTITY * (lame.lambda * trace))
    }
    /// ∂Ψ/∂λ₃ = λ₃ [μ(λ₃² − 1) + (λ/2)(σ₁² + σ₂² + λ₃² − 3)] = 0 gives
    /// λ₃² = (2μ + λ(3 − σ₁² − σ₂²)) / (2μ + λ), or λ₃ = 0 when that is negative (stretched
    /// far enough, the model prefers no thickness).
    fn plane_stress_stretch(&self, [s1, s2]: [f64; 2], lame: Lame) -> f64 {
        let square = (2.0 * lame.mu + lame.lambda * (3.0 - s1 * s1 - s2 * s2)) / (2.0 * lame.mu + lame.lambda);
        square.max(0.0).sqrt()
    }
}
