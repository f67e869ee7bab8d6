//! Closed-form 2×2 kernels: nearest rotation, SVD and singular-value clamping.
//!
//! No trigonometry and no iteration: a handful of products, square roots and one division.

use glam::{DMat2, DVec2};

/// Singular value decomposition `M = U diag(σ) Vᵀ` of a 2×2 matrix, from [`svd2`].
///
/// Convention: `σ₁ ≥ σ₂ ≥ 0`; `V` is a rotation (det +1); `U` is orthogonal with
/// `det U = +1` when `det M ≥ 0` and `det U = −1` when `det M < 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Svd2 {
    /// Left singular vectors (columns of U).
    pub u: DMat2,
    /// Singular values (σ₁, σ₂), σ₁ ≥ σ₂ ≥ 0.
    pub sigma: DVec2,
    /// Right singular vectors (columns of V); always a rotation.
    pub v: DMat2,
}

impl Svd2 {
    /// `U diag(σ) Vᵀ`.
    #[inline]
    pub fn reconstruct(&self) -> DMat2 {
        self.u * DMat2::from_diagonal(self.sigma) * self.v.transpose()
    }
}

/// The rotation `R(θ) = [[cos θ, −sin θ], [sin θ, cos θ]]` nearest to `m` in Frobenius norm.
///
/// Formula: `argmin_R ‖R − M‖² = argmax_θ tr(R(θ)ᵀM) = argmax_θ e cos θ + h sin θ` with
/// `e = m₀₀ + m₁₁`, `h = m₁₀ − m₀₁`, so `(cos θ, sin θ) = (e, h) / √(e² + h²)`. Exact for every
/// `m`, including `det m ≤ 0` (the result is always a rotation, never a reflection). When
/// `e = h = 0` every rotation is equally near and the identity is returned.
#[inline]
pub fn nearest_rotation2(m: DMat2) -> DMat2 {
    let e = m.x_axis.x + m.y_axis.y;
    let h = m.x_axis.y - m.y_axis.x;
    let (c, s) = unit_direction(e, h);
    DMat2::from_cols(DVec2::new(c, s), DVec2::new(-s, c))
}

/// `(e, h) / ‖(e, h)‖`, or `(1, 0)` for the zero vector; safe against under/overflow.
#[inline]
fn unit_direction(e: f64, h: f64) -> (f64, f64) {
    let r2 = e * e + h * h;
    if r2 > f64::MIN_POSITIVE && r2 < f64::MAX {
        let inv = 1.0 / r2.sqrt();
        (e * inv, h * inv)
    } else if e == 0.0 && h == 0.0 || !(e.is_finite() && h.is_finite()) {
        (1.0, 0.0)
    } else {
        // Tiny or huge entries: rescale before squaring (rare path).
        let scale = e.abs().max(h.abs());
        let (e, h) = (e / scale, h / scale);
        let inv = 1.0 / (e * e + h * h).sqrt();
        (e * inv, h * inv)
    }
}

/// SVD of a 2×2 matrix in closed form (convention in [`Svd2`]).
///
/// Formula: polar decomposition first, then the eigen-decomposition of the symmetric factor.
/// `R` = [`nearest_rotation2`]`(M)` and `S = RᵀM` is symmetric with `tr S ≥ 0`. Writing
/// `S = [[p, w], [w, q]]`, `d = (p − q)/2`, `h = √(d² + w²)`: the larger eigenvalue is
/// `λ₁ = (p + q)/2 + h` with eigenvector `(d + h, w)` (or `(w, h − d)` when `d < 0`, the
/// cancellation-free choice), `V = [v₁, v₁^⊥]`, `λ₂ = det M / λ₁` (accurate even when tiny), and
/// `U = R V`. Then `σ = (λ₁, |λ₂|)`, and when `λ₂ < 0` (that is `det M < 0`) U's second column
/// is negated.
#[inline]
pub fn svd2(m: DMat2) -> Svd2 {
    let r = nearest_rotation2(m);
    let s = r.transpose() * m;
    let (p, q, w) = (s.x_axis.x, s.y_axis.y, 0.5 * (s.x_axis.y + s.y_axis.x));
    let d = 0.5 * (p - q);
    let h = (d * d + w * w).sqrt();
    let l1 = 0.5 * (p + q) + h;
    let raw = if d >= 0.0 { DVec2::new(d + h, w) } else { DVec2::new(w, h - d) };
    let n2 = raw.length_squared();
    // S = λ I (h = 0): every basis diagonalizes it.
    let v1 = if n2 > f64::MIN_POSITIVE { raw / n2.sqrt() } else { DVec2::X };
    let v = DMat2::from_cols(v1, v1.perp());
    let l2 = if l1 > 0.0 { m.determinant() / l1 } else { 0.0 };
    let mut u = r * v;
    if l2 < 0.0 {
        u.y_axis = -u.y_axis;
    }
    Svd2 { u, sigma: DVec2::new(l1, l2.abs()), v }
}

/// `U clamp(Σ, lo, hi) Vᵀ` for the SVD `M = UΣVᵀ` of [`svd2`]: the matrix nearest to `m`
/// whose singular values lie in `[lo, hi]` (each σ is clamped; with `lo = hi = 1` it is the
/// nearest orthogonal matrix, a reflection when `det M < 0`). `lo ≤ hi` expected.
#[inline]
pub fn clamp_singular_values2(m: DMat2, lo: f64, hi: f64) -> DMat2 {
    let svd = svd2(m);
    let clamped = DVec2::new(svd.sigma.x.max(lo).min(hi), svd.sigma.y.max(lo).min(hi));
    svd.u * DMat2::from_diagonal(clamped) * svd.v.transpose()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::linalg::test_rng::Rng;
    use nalgebra::Matrix2;

    fn frob(m: DMat2) -> f64 {
        (m.x_axis.length_squared() + m.y_axis.length_squared()).sqrt()
    }

    fn rot(t: f64) -> DMat2 {
        DMat2::from_angle(t)
    }

    /// Random 2×2 matrices of every kind the tests need.
    fn samples(rng: &mut Rng) -> Vec<DMat2> {
        let mut out = vec![DMat2::ZERO, DMat2::IDENTITY, DMat2::from_diagonal(DVec2::new(1.0, -1.0))];
        for _ in 0..2000 {
            let a = DMat2::from_cols(rng.vec2(), rng.vec2());
            out.push(a);
            out.push(DMat2::IDENTITY + 0.3 * a);
            let (u, v) = (rng.vec2(), rng.vec2());
            out.push(DMat2::from_cols(u * v.x, u * v.y)); // rank 1
            let t1 = rng.uniform() * 3.2;
            let t2 = rng.uniform() * 3.2;
            let s = 1.0 + rng.uniform();
            out.push(rot(t1) * DMat2::from_diagonal(DVec2::new(s, s * (1.0 + 1e-9 * rng.uniform()))) * rot(t2));
            out.push(rot(t1) * DMat2::from_diagonal(DVec2::new(s, -s * 0.5)) * rot(t2)); // reflection
            out.push(rot(t1) * DMat2::from_diagonal(DVec2::new(1.0, 1e-13)) * rot(t2));
            out.push(a * 1e-150);
            out.push(a * 1e150);
        }
        out
    }

    #[test]
    fn svd2_reconstructs_and_matches_nalgebra() {
        let mut rng = Rng(11);
        for m in samples(&mut rng) {
            let svd = svd2(m);
            let scale = frob(m);
            assert!(frob(svd.reconstruct() - m) <= 1e-13 * scale, "{m:?} {svd:?}");
            assert!(frob(svd.u.transpose() * svd.u - DMat2::IDENTITY) < 1e-14);
            assert!(frob(svd.v.transpose() * svd.v - DMat2::IDENTITY) < 1e-14);
            assert!((svd.v.determinant() - 1.0).abs() < 1e-14);
            let want_det_u = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
            assert!((svd.u.determinant() - want_det_u).abs() < 1e-14, "{m:?} {svd:?}");
            assert!(svd.sigma.x >= svd.sigma.y && svd.sigma.y >= 0.0);
            let na = Matrix2::new(m.x_axis.x, m.y_axis.x, m.x_axis.y, m.y_axis.y).singular_values();
            let (n1, n2) = (na[0].max(na[1]), na[0].min(na[1]));
            assert!((svd.sigma.x - n1).abs() <= 1e-13 * scale && (svd.sigma.y - n2).abs() <= 1e-13 * scale);
        }
    }

    #[test]
    fn nearest_rotation2_is_a_rotation_and_beats_every_sampled_angle() {
        let mut rng = Rng(5);
        for m in samples(&mut rng).into_iter().step_by(7) {
            let r = nearest_rotation2(m);
            assert!(frob(r.transpose() * r - DMat2::IDENTITY) < 1e-14);
            assert!((r.determinant() - 1.0).abs() < 1e-14);
            let d = frob(r - m);
            let r_angle = r.x_axis.y.atan2(r.x_axis.x);
            for k in 0..64 {
                let t = k as f64 / 64.0 * std::f64::consts::TAU;
                assert!(d <= frob(rot(t) - m) + 1e-13 * (1.0 + frob(m)));
                let near = rot(r_angle + 1e-4 * rng.uniform());
                assert!(d <= frob(near - m) + 1e-13 * (1.0 + frob(m)));
            }
        }
    }

    #[test]
    fn nearest_rotation2_of_rotation_is_itself_and_of_zero_is_identity() {
        for k in 0..20 {
            let r = rot(k as f64 * 0.4 - 4.0);
            assert!(frob(nearest_rotation2(r * 3.0) - r) < 1e-15);
        }
        assert_eq!(nearest_rotation2(DMat2::ZERO), DMat2::IDENTITY);
    }

    #[test]
    fn clamp2_keeps_matrices_within_bounds_and_clamps_others() {
        let mut rng = Rng(3);
        for _ in 0..500 {
            let (t1, t2) = (rng.uniform() * 3.0, rng.uniform() * 3.0);
            let s = DVec2::new(1.0 + 0.2 * rng.uniform().abs(), 1.0 - 0.2 * rng.uniform().abs());
            let m = rot(t1) * DMat2::from_diagonal(s) * rot(t2);
            assert!(frob(clamp_singular_values2(m, 0.75, 1.25) - m) < 1e-14);
            let c = clamp_singular_values2(m * 2.0, 0.75, 1.25);
            let svd = svd2(c);
            assert!((svd.sigma.x - 1.25).abs() < 1e-14);
            assert!((svd.sigma.y - (2.0 * s.y).min(1.25)).abs() < 1e-14);
        }
    }
}
