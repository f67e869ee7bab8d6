//! Stable Neo-Hookean: a Neo-Hookean solid that stays finite and resists through inversion.
//!
//! Ψ(F) = (μ/2) (I_C − 3) + (λ'/2) (J − α)² − μ²/(2λ')
//!      = (μ/2) (I_C − 3) − μ (J − 1) + (λ'/2) (J − 1)²,  I_C = ‖F‖²_F, J = det F,
//! P(F) = μ F + (λ' (J − 1) − μ) cof F,
//! with λ' = λ + μ and α = 1 + μ/λ', so that Ψ(I) = 0, P(I) = 0 (the rest shape is stress-free)
//! and the linearization at rest is linear elasticity's with Lamé μ and λ (its Hessian there is
//! μ(δ_ik δ_jl + δ_il δ_jk) + (λ' − μ) δ_ij δ_kl). The constant μ²/(2λ') only puts the rest
//! energy at 0.
//!
//! Source: Smith, de Goes and Kim, "Stable Neo-Hookean Flesh Simulation", ACM TOG 37(2), 2018,
//! §3.3–3.4 (the energy without its optional −(μ/2) log(I_C + 1) term, which only matters for
//! elements collapsed to a point, and with its Lamé reparametrization worked out for that
//! form). Unlike the classic −μ log J form it has no log J: no NaN and no infinite energy at
//! J ≤ 0, so an inverted element is pushed back.

use super::{Hyperelastic, Lame, ModelInfo};
use crate::linalg::{cofactor, frobenius2};
use glam::DMat3;

/// Stable Neo-Hookean ([module docs](self)).
#[derive(Debug, Clone, Copy)]
pub struct NeoHookean;

const INFO: ModelInfo = ModelInfo {
    name: "neo_hookean",
    summary: "stable Neo-Hookean (Smith et al. 2018): μ/2 (‖F‖² − 3) + λ'/2 (det F − α)², finite through inversion",
};

/// λ' = λ + μ for Lamé (μ, λ): > 0 for every Poisson ratio in (−1, ½).
fn reparametrized(lame: Lame) -> f64 {
    lame.lambda + lame.mu
}

impl Hyperelastic for NeoHookean {
    fn info(&self) -> &'static ModelInfo {
        &INFO
    }
    fn energy_density(&self, f: DMat3, lame: Lame) -> f64 {
        let lambda = reparametrized(lame);
        let j = f.determinant();
        0.5 * lame.mu * (frobenius2(&f) - 3.0) - lame.mu * (j - 1.0) + 0.5 * lambda * (j - 1.0) * (j - 1.0)
    }
    fn first_piola(&self, f: DMat3, lame: Lame) -> DMat3 {
        let lambda = reparametrized(lame);
        f * lame.mu + cofactor(&f) * (lambda * (f.determinant() - 1.0) - lame.mu)
    }
    /// With F = diag(σ₁, σ₂, λ₃): ∂Ψ/∂λ₃ = μλ₃ + (λ'(J₂λ₃ − 1) − μ)J₂ = 0, J₂ = σ₁σ₂, so
    /// λ₃ = (λ' + μ)J₂ / (μ + λ'J₂²).
    fn plane_stress_stretch(&self, [s1, s2]: [f64; 2], lame: Lame) -> f64 {
        let (lambda, j) = (reparametrized(lame), s1 * s2);
        (lambda + lame.mu) * j / (lame.mu + lambda * j * j)
    }
}
