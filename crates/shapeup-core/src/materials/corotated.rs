//! Fixed corotated elasticity: the distance of F from its rotation, and the volume change.
//!
//! Ψ(F) = μ ‖F − R‖²_F + (λ/2) (J − 1)²,  R the rotation nearest F (polar decomposition, det R =
//! +1), J = det F,
//! P(F) = 2μ (F − R) + λ (J − 1) cof F,  cof F = J F⁻ᵀ.
//!
//! Source: Stomakhin, Howes, Schroeder and Teran, "Energetically Consistent Invertible
//! Elasticity", SCA 2012, §4 ("fixed corotated"); the gradient is Sifakis and Barbič's course
//! notes (2012), §5.3. R varies with F, but ∂/∂F of ‖F − R‖² is 2(F − R) all the same, since R
//! is the closest rotation. Defined through inversion (R stays a rotation, J changes sign).

use super::{Hyperelastic, Lame, ModelInfo};
use crate::linalg::{cofactor, frobenius2, nearest_rotation3};
use glam::DMat3;

/// Fixed corotated ([module docs](self)).
#[derive(Debug, Clone, Copy)]
pub struct Corotated;

const INFO: ModelInfo = ModelInfo {
    name: "corotated",
    summary: "fixed corotated: μ ‖F − R‖² + λ/2 (det F − 1)², R the nearest rotation",
};

impl Hyperelastic for Corotated {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }
    fn energy_density(&self, f: DMat3, lame: Lame) -> f64 {
        let j = f.determinant();
        lame.mu * frobenius2(&(f - nearest_rotation3(f))) + 0.5 * lame.lambda * (j - 1.0) * (j - 1.0)
    }
    fn first_piola(&self, f: DMat3, lame: Lame) -> DMat3 {
        let j = f.determinant();
        (f - nearest_rotation3(f)) * (2.0 * lame.mu) + cofactor(&f) * (lame.lambda * (j - 1.0))
    }
    /// With F = diag(σ₁, σ₂, λ₃), R = I: ∂Ψ/∂λ₃ = 2μ(λ₃ − 1) + λ(J₂λ₃ − 1)J₂ = 0, J₂ = σ₁σ₂, so
    /// λ₃ = (2μ + λJ₂) / (2μ + λJ₂²).
    fn plane_stress_stretch(&self, [s1, s2]: [f64; 2], lame: Lame) -> f64 {
        let j = s1 * s2;
        (2.0 * lame.mu + lame.lambda * j) / (2.0 * lame.mu + lame.lambda * j * j)
    }
}
