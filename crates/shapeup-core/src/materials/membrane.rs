//! Membranes: a model's energy on the triangles of a surface of thickness h, in plane stress.
//!
//! A triangle's deformation gradient F₂ = [t₀ t₁] (3×2, the rows of `triangle_strain`) says how
//! its plane stretches. The shell's material is the volumetric model in plane stress: the
//! thickness direction stretches freely, by the λ₃ that minimizes the energy,
//!
//!   Ψ_m(F₂) = min_{λ₃ ≥ 0} Ψ(F₃),  F₃ = [t₀ t₁ λ₃ n],  n = (t₀ × t₁)/‖t₀ × t₁‖,
//!
//! and the triangle's energy is A h Ψ_m(F₂) (A its rest area, h the thickness in metres). Its
//! stress is P₂ = ∂Ψ_m/∂F₂ = the first two columns of P(F₃): by the envelope theorem λ₃'s own
//! variation drops out (∂Ψ/∂λ₃ = 0 at the minimum), and for an isotropic model P(F₃) e₃ =
//! (∂Ψ/∂λ₃) n = 0 there, so n's variation with F₂ drops out too. λ₃ comes from the model
//! ([`Hyperelastic::plane_stress_stretch`]: closed forms for the three models, a bracketed
//! root of ∂Ψ/∂λ₃ for one that has none). At small strain this is plane-stress linear
//! elasticity, stiffness E/(1 − ν²) (Timoshenko and Goodier, "Theory of Elasticity", §98).
//!
//! How the term enters the solver is as for a tetrahedron ([module docs](super)): weight
//! ω = A h κ with κ = E/(1 − ν²) = 4μ(λ + μ)/(λ + 2μ), the plane-stress P-wave modulus, and
//! "projection" F₂ − P₂/κ, so that the solver's gradient is half that of 2 A h Ψ_m.
//!
//! This is the membrane (stretching) part of a thin shell only: bending resistance, which for
//! a plate is D = E h³ / (12 (1 − ν²)), is not modelled yet, so a membrane resists stretch but
//! folds freely (a balloon, a cushion or a sail under load keeps its shape by tension).

use super::{Hyperelastic, Lame, Material};
use crate::constraints::kit::gradient::TriangleGradient;
use crate::constraints::kit::sets::singular_values_3x2;
use crate::constraints::{Constraint, RowSink};
use glam::{DMat3, DVec3};

/// The plane-stress P-wave modulus E/(1 − ν²) = 4μ(λ + μ)/(λ + 2μ), in Pa.
pub fn plane_stress_modulus(lame: Lame) -> f64 {
    4.0 * lame.mu * (lame.lambda + lame.mu) / (lame.lambda + 2.0 * lame.mu)
}

/// The thickness stretch of plane stress found numerically: the root λ₃ ≥ 0 of ∂Ψ/∂λ₃ =
/// P(diag(σ₁, σ₂, λ₃))₃₃ with the smallest energy, bracketed by doubling and closed by
/// bisection with the secant (Illinois) step. 0 when ∂Ψ/∂λ₃ > 0 for every λ₃ > 0 (the material
/// prefers no thickness at all, as St. Venant–Kirchhoff does when stretched far enough).
/// What [`Hyperelastic::plane_stress_stretch`] does for a model without a closed form.
pub fn plane_stress_stretch_numeric(model: &(impl Hyperelastic + ?Sized), [s1, s2]: [f64; 2], lame: Lame) -> f64 {
    let slope = |l: f64| model.first_piola(DMat3::from_diagonal(DVec3::new(s1, s2, l)), lame).z_axis.z;
    // The energy rises from λ₃ = 0 already: nothing to find.
    let tiny = 1e-12;
    if slope(tiny) > 0.0 {
        return 0.0;
    }
    let (mut lo, mut hi) = (tiny, 1.0);
    let (mut f_lo, mut f_hi) = (slope(lo), slope(hi));
    let mut doublings = 0;
    while f_hi <= 0.0 {
        if doublings == 200 {
            return hi;
        }
        (lo, f_lo) = (hi, f_hi);
        hi *= 2.0;
        f_hi = slope(hi);
        doublings += 1;
    }
    // Illinois: regula falsi that halves the stale end's value, so both ends move.
    let mut side = 0;
    for _ in 0..200 {
        let mid = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        let mid = if mid > lo && mid < hi { mid } else { 0.5 * (lo + hi) };
        let f_mid = slope(mid);
        if f_mid == 0.0 || hi - lo <= 4.0 * f64::EPSILON * hi {
            return mid;
        }
        if f_mid < 0.0 {
            (lo, f_lo) = (mid, f_mid);
            if side == -1 {
                f_hi *= 0.5;
            }
            side = -1;
        } else {
            (hi, f_hi) = (mid, f_mid);
            if side == 1 {
                f_lo *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (lo + hi)
}

/// F₃ = [t₀ t₁ λ₃ n] of a triangle's gradient `t` in plane stress ([module docs](self)); n is
/// any unit vector ⊥ t₀ when the triangle has collapsed to a segment or a point.
pub fn plane_stress_gradient(model: &dyn Hyperelastic, t: [DVec3; 2], lame: Lame) -> DMat3 {
    let cross = t[0].cross(t[1]);
    let scale = t[0].length_squared() * t[1].length_squared();
    let n = if cross.length_squared() > 1e-28 * scale && cross.length_squared() > 0.0 {
        cross.normalize()
    } else {
        let long = if t[0].length_squared() >= t[1].length_squared() { t[0] } else { t[1] };
        long.try_normalize().map_or(DVec3::Z, |u| u.any_orthonormal_vector())
    };
    let stretch = model.plane_stress_stretch(singular_values_3x2(t[0], t[1]), lame);
    DMat3::from_cols(t[0], t[1], n * stretch)
}

/// The membrane term of one triangle ([module docs](self)): rows F₂, weight A h κ, energy
/// 2 A h Ψ_m(F₂), "projection" F₂ − P₂/κ.
#[derive(Debug, Clone)]
pub struct TriMembrane {
    gradient: TriangleGradient,
    model: &'static dyn Hyperelastic,
    lame: Lame,
    /// h, metres.
    thickness: f64,
    /// κ = E/(1 − ν²).
    kappa: f64,
}

impl TriMembrane {
    /// The term of triangle `vertices` of the rest shape `rest` (metres) for a shell of
    /// `thickness` metres; `None` when the rest triangle is degenerate (area ≤ 1e-12 ℓ², ℓ its
    /// longest edge, or [`TriangleGradient::new`]'s tests).
    pub fn new(vertices: [u32; 3], rest: &[DVec3], material: &Material, thickness: f64) -> Option<Self> {
        let p = vertices.map(|v| rest[v as usize]);
        let longest = super::longest_edge(&p);
        let gradient = TriangleGradient::new(vertices, rest)?;
        (gradient.rest_area > 1e-12 * longest * longest).then(|| TriMembrane {
            gradient,
            model: material.model,
            lame: material.lame,
            thickness,
            kappa: plane_stress_modulus(material.lame),
        })
    }

    /// A h, the rest volume of the triangle's piece of shell.
    pub fn rest_volume(&self) -> f64 {
        self.gradient.rest_area * self.thickness
    }
}

impl Constraint for TriMembrane {
    fn kind(&self) -> &'static str {
        super::MATERIAL_GROUP
    }
    fn vertices(&self) -> &[u32] {
        &self.gradient.vertices
    }
    fn element_weight(&self) -> f64 {
        self.rest_volume() * self.kappa
    }
    fn num_rows(&self) -> usize {
        2
    }
    fn rows(&self, sink: &mut RowSink) {
        self.gradient.rows(sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let t = self.gradient.at(q);
        let p = self.model.first_piola(plane_stress_gradient(self.model, t, self.lame), self.lame);
        out[0] = t[0] - p.x_axis / self.kappa;
        out[1] = t[1] - p.y_axis / self.kappa;
    }
    fn is_projective(&self) -> bool {
        false
    }
    fn energy_from_rows(&self, cq: &[DVec3]) -> Option<f64> {
        let f = plane_stress_gradient(self.model, [cq[0], cq[1]], self.lame);
        Some(2.0 * self.rest_volume() * self.model.energy_density(f, self.lame))
    }
    /// No set: a material has no shape it projects onto.
    fn set_residual(&self, _p: &[DVec3]) -> f64 {
        0.0
    }
    /// The in-plane Green strain's size ‖½(F₂ᵀF₂ − I)‖_F: 0 at rest or rotated.
    fn violation(&self, cq: &[DVec3]) -> f64 {
        let (a, b, c) = (cq[0].length_squared() - 1.0, cq[0].dot(cq[1]), cq[1].length_squared() - 1.0);
        0.5 * (a * a + 2.0 * b * b + c * c).sqrt()
    }
    fn length_power(&self) -> i32 {
        0
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::linalg::test_rng::Rng;
    use crate::materials::{Lame, MODELS, Material};
    use glam::DQuat;

    fn lame() -> Lame {
        Lame::from_youngs(1.0e6, 0.3).unwrap()
    }

    fn range(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * 0.5 * (rng.uniform() + 1.0)
    }

    fn random_t(rng: &mut Rng) -> [DVec3; 2] {
        [DVec3::X + rng.vec3() * 0.4, DVec3::Y + rng.vec3() * 0.4]
    }

    /// Ψ_m(F₂) through the module's plane-stress gradient.
    fn membrane_energy(model: &dyn Hyperelastic, t: [DVec3; 2]) -> f64 {
        model.energy_density(plane_stress_gradient(model, t, lame()), lame())
    }

    #[test]
    fn each_models_closed_form_thickness_stretch_is_the_numerical_minimizer() {
        let mut rng = Rng(11);
        for model in MODELS {
            for nu in [-0.5, 0.0, 0.3, 0.49] {
                let name = model.info().name;
                if Material::new(name, 1.0e6, nu, 1.0).is_err() {
                    assert!(name == "corotated" && nu < 0.0, "{name} refuses ν {nu}");
                    continue;
                }
                let lame = Lame::from_youngs(1.0e6, nu).unwrap();
                for _ in 0..50 {
                    let sigma = [range(&mut rng, 0.3, 1.8), range(&mut rng, 0.3, 1.8)];
                    let closed = model.plane_stress_stretch(sigma, lame);
                    let numeric = plane_stress_stretch_numeric(*model, sigma, lame);
                    assert!(
                        (closed - numeric).abs() <= 1e-9 * numeric.max(1.0),
                        "{}: ν {nu}, σ {sigma:?}: closed form {closed}, numerical {numeric}",
                        model.info().name
                    );
                    // A minimum: the energy is higher on either side.
                    let psi =
                        |l: f64| model.energy_density(DMat3::from_diagonal(DVec3::new(sigma[0], sigma[1], l)), lame);
                    let h = 1e-4 * closed.max(1e-3);
                    assert!(psi(closed) <= psi(closed + h) && (closed < h || psi(closed) <= psi(closed - h)));
                }
                assert!((model.plane_stress_stretch([1.0, 1.0], lame) - 1.0).abs() < 1e-12, "1 at rest");
            }
        }
    }

    #[test]
    fn the_membrane_stress_is_its_energys_gradient() {
        let mut rng = Rng(5);
        for model in MODELS {
            for _ in 0..20 {
                let t = random_t(&mut rng);
                let p = model.first_piola(plane_stress_gradient(*model, t, lame()), lame());
                let stress = [p.x_axis, p.y_axis];
                for col in 0..2 {
                    for row in 0..3 {
                        let h = 1e-6;
                        let (mut plus, mut minus) = (t, t);
                        plus[col][row] += h;
                        minus[col][row] -= h;
                        let fd = (membrane_energy(*model, plus) - membrane_energy(*model, minus)) / (2.0 * h);
                        let exact = stress[col][row];
                        assert!(
                            (fd - exact).abs() <= 1e-5 * lame().mu + 1e-6 * exact.abs(),
                            "{}: ∂Ψ_m/∂F[{row}][{col}] = {fd} by differences, {exact} from P",
                            model.info().name
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn rest_is_stress_free_and_rotations_change_nothing() {
        let mut rng = Rng(9);
        for model in MODELS {
            let at_rest = plane_stress_gradient(*model, [DVec3::X, DVec3::Y], lame());
            assert!(model.energy_density(at_rest, lame()).abs() < 1e-9);
            assert!(crate::linalg::frobenius2(&model.first_piola(at_rest, lame())) < 1e-12);
            for _ in 0..10 {
                let t = random_t(&mut rng);
                let r = DQuat::from_axis_angle(
                    DVec3::new(range(&mut rng, -1.0, 1.0), range(&mut rng, -1.0, 1.0), 0.3).normalize(),
                    range(&mut rng, -3.0, 3.0),
                );
                let turned = [r * t[0], r * t[1]];
                let (a, b) = (membrane_energy(*model, t), membrane_energy(*model, turned));
                assert!((a - b).abs() <= 1e-9 * a.abs().max(1.0), "{}: {a} turned {b}", model.info().name);
            }
        }
    }

    /// At small strain, plane-stress linear elasticity (Timoshenko and Goodier §98):
    /// Ψ = E / (2(1 − ν²)) (ε₁² + ε₂² + 2ν ε₁ε₂) for principal strains ε₁, ε₂.
    #[test]
    fn small_strains_are_plane_stress_linear_elasticity() {
        for nu in [0.0, 0.3, 0.45] {
            let (e, eps) = (2.0e6, 1e-5);
            let lame = Lame::from_youngs(e, nu).unwrap();
            assert!((plane_stress_modulus(lame) - e / (1.0 - nu * nu)).abs() < 1e-9 * e);
            for model in MODELS {
                for (e1, e2) in [(eps, 0.0), (eps, eps), (eps, -eps), (eps, 0.5 * eps)] {
                    let t = [DVec3::X * (1.0 + e1), DVec3::Y * (1.0 + e2)];
                    let psi = model.energy_density(plane_stress_gradient(*model, t, lame), lame);
                    let linear = e / (2.0 * (1.0 - nu * nu)) * (e1 * e1 + e2 * e2 + 2.0 * nu * e1 * e2);
                    assert!(
                        (psi - linear).abs() <= 1e-4 * linear,
                        "{}: ν {nu}, ε ({e1}, {e2}): Ψ_m {psi}, linear {linear}",
                        model.info().name
                    );
                }
            }
        }
    }

    #[test]
    fn a_triangles_term_has_the_solvers_gradient_and_a_shells_weight() {
        let rest = [DVec3::ZERO, DVec3::new(0.1, 0.0, 0.0), DVec3::new(0.02, 0.08, 0.0)];
        let material = Material::new("neo_hookean", 1.0e6, 0.3, 1000.0).unwrap();
        let term = TriMembrane::new([0, 1, 2], &rest, &material, 0.002).unwrap();
        let area = 0.5 * 0.1 * 0.08;
        assert!((term.rest_volume() - area * 0.002).abs() < 1e-18);
        assert!((term.element_weight() - area * 0.002 * 1.0e6 / (1.0 - 0.09)).abs() < 1e-9);
        let q = [DVec3::new(0.0, 0.0, 0.01), DVec3::new(0.13, 0.01, 0.0), DVec3::new(0.0, 0.07, 0.02)];
        // ω Cᵀ(C q − p) is half the gradient of the energy with respect to the positions.
        let mut p = [DVec3::ZERO; 2];
        term.project(&q, &mut p);
        let cq = term.apply(&q);
        let mut sink = RowSink::default();
        term.rows(&mut sink);
        let mut half_gradient = [DVec3::ZERO; 3];
        for entry in &sink.entries {
            half_gradient[entry.vertex as usize] +=
                term.element_weight() * entry.coeff * (cq[entry.row as usize] - p[entry.row as usize]);
        }
        for v in 0..3 {
            for axis in 0..3 {
                let h = 1e-7;
                let (mut plus, mut minus) = (q, q);
                plus[v][axis] += h;
                minus[v][axis] -= h;
                let fd = (term.energy(&plus) - term.energy(&minus)) / (2.0 * h);
                let exact = 2.0 * half_gradient[v][axis];
                assert!((fd - exact).abs() <= 1e-5 * exact.abs().max(1e-3), "vertex {v} axis {axis}: {fd} vs {exact}");
            }
        }
        let flat = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(TriMembrane::new([0, 1, 2], &flat, &material, 0.002).is_none(), "a degenerate triangle has no term");
    }
}
