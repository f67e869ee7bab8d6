//! 3×3 SVD (one-sided Jacobi) and the nearest rotation (scaled Newton polar iteration with an
//! SVD fallback).

use super::jacobi_rotation;
use glam::{DMat3, DVec3};

/// Singular value decomposition `A = U diag(σ) Vᵀ` of a 3×3 matrix, from [`svd3`] or
/// [`svd3_rotations`] (their docs give the sign conventions).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Svd3 {
    /// Left singular vectors (columns of U).
    pub u: DMat3,
    /// Singular values, sorted by decreasing magnitude.
    pub sigma: DVec3,
    /// Right singular vectors (columns of V); always a rotation (det +1).
    pub v: DMat3,
}

impl Svd3 {
    /// `U diag(σ) Vᵀ`.
    #[inline]
    pub fn reconstruct(&self) -> DMat3 {
        self.u * DMat3::from_diagonal(self.sigma) * self.v.transpose()
    }
}

/// Squared Frobenius norm `Σ a_ij²`.
#[inline]
pub fn frobenius2(a: &DMat3) -> f64 {
    a.x_axis.length_squared() + a.y_axis.length_squared() + a.z_axis.length_squared()
}

/// Cofactor matrix `cof A = det(A) A⁻ᵀ`, columns `(a₁ × a₂, a₂ × a₀, a₀ × a₁)` for the columns
/// `a₀, a₁, a₂` of A; defined (polynomial) for singular A too. `det A = a₀ · (a₁ × a₂)`.
#[inline]
pub fn cofactor(a: &DMat3) -> DMat3 {
    DMat3::from_cols(a.y_axis.cross(a.z_axis), a.z_axis.cross(a.x_axis), a.x_axis.cross(a.y_axis))
}

/// Jacobi sweeps after which [`svd3_rotations`] stops even if not converged (3–6 are typical).
const MAX_SWEEPS: usize = 16;
/// A column pair counts as orthogonal when `|bᵢ·bⱼ| ≤ ORTHO_TOL · ‖bᵢ‖‖bⱼ‖`.
const ORTHO_TOL: f64 = 1e-15;
/// Below this (relative to σ₁ = 1 after scaling), a singular vector is taken as arbitrary.
const RANK_TOL: f64 = 1e-150;

/// SVD `A = U diag(σ₁, σ₂, σ₃) Vᵀ` with **U and V both rotations** (det +1): `σ₁ ≥ σ₂ ≥ |σ₃|`,
/// `σ₁, σ₂ ≥ 0`, and σ₃ carries the sign of det A (the "rotation-variant" SVD used for
/// inversion-aware elasticity).
///
/// Method: one-sided (Hestenes) Jacobi. Plane rotations `G` applied on the right make the
/// columns of `B = A V` mutually orthogonal to working precision *relative to their lengths*
/// (rotation on pair (i, j): `ζ = (‖bⱼ‖² − ‖bᵢ‖²)/(2 bᵢ·bⱼ)`, `t = sign ζ/(|ζ| + √(1 + ζ²))`,
/// `c = 1/√(1 + t²)`, `s = c t` (evaluated without ζ, below), `bᵢ ← c bᵢ − s bⱼ`,
/// `bⱼ ← s bᵢ + c bⱼ`, same on V), which keeps
/// small singular values accurate and reconstruction at ~1e-15 ‖A‖ even for rank-deficient or
/// graded matrices. Columns are then sorted by length (a swap also negates one column so that V
/// stays a rotation), `u₁ = b₁/σ₁`, `u₂ = b₂/σ₂` (re-orthogonalized; any unit vector ⊥ u₁ when
/// `σ₂ ≈ 0`), `u₃ = u₁ × u₂` and `σ₃ = u₃ · b₃` (signed). A is scaled by its largest entry first
/// so that no square under- or overflows. The zero matrix gives U = V = I, σ = 0.
pub fn svd3_rotations(a: DMat3) -> Svd3 {
    let scale = a.abs().to_cols_array().into_iter().fold(0.0, f64::max);
    if !(scale > 0.0 && scale.is_finite()) {
        // Zero (or non-finite, which has no meaningful SVD): identity factors.
        let sigma = if scale == 0.0 { DVec3::ZERO } else { DVec3::splat(f64::NAN) };
        return Svd3 { u: DMat3::IDENTITY, sigma, v: DMat3::IDENTITY };
    }
    let inv_scale = 1.0 / scale;
    let mut b = [a.x_axis * inv_scale, a.y_axis * inv_scale, a.z_axis * inv_scale];
    let mut v = [DVec3::X, DVec3::Y, DVec3::Z];
    let mut n = [b[0].length_squared(), b[1].length_squared(), b[2].length_squared()];
    for _ in 0..MAX_SWEEPS {
        let mut rotated = false;
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            let g = b[i].dot(b[j]);
            if g * g <= ORTHO_TOL * ORTHO_TOL * n[i] * n[j] {
                continue;
            }
            rotated = true;
            let (c, s) = jacobi_rotation(n[i], n[j], g);
            let (bi, bj) = (b[i], b[j]);
            b[i] = c * bi - s * bj;
            b[j] = s * bi + c * bj;
            let (vi, vj) = (v[i], v[j]);
            v[i] = c * vi - s * vj;
            v[j] = s * vi + c * vj;
            n[i] = b[i].length_squared();
            n[j] = b[j].length_squared();
        }
        if !rotated {
            break;
        }
    }
    // Sort by decreasing column length; each swap negates one column to keep det V = +1.
    for (i, j) in [(0, 1), (1, 2), (0, 1)] {
        if n[i] < n[j] {
            n.swap(i, j);
            b.swap(i, j);
            v.swap(i, j);
            b[j] = -b[j];
            v[j] = -v[j];
        }
    }
    let s1 = n[0].sqrt();
    let u1 = b[0] / s1;
    let s2 = n[1].sqrt();
    let u2 = if s2 > RANK_TOL {
        // Re-orthogonalize against u₁ (b₂ ⊥ b₁ holds to ~1e-15 relative; this makes it exact).
        let w = b[1] / s2;
        (w - u1.dot(w) * u1).normalize_or(u1.any_orthonormal_vector())
    } else {
        u1.any_orthonormal_vector()
    };
    let u3 = u1.cross(u2);
    // |u₃·b₃| ≤ ‖b₃‖ ≤ σ₂ up to rounding; keep the order exact.
    let s3 = u3.dot(b[2]).max(-s2).min(s2);
    Svd3 {
        u: DMat3::from_cols(u1, u2, u3),
        sigma: DVec3::new(s1, s2, s3) * scale,
        v: DMat3::from_cols(v[0], v[1], v[2]),
    }
}

/// SVD `A = U diag(σ) Vᵀ` in the standard convention: `σ₁ ≥ σ₂ ≥ σ₃ ≥ 0`, U and V orthogonal.
/// V is a rotation; `det U = −1` exactly when the signed σ₃ of [`svd3_rotations`] is negative
/// (det A < 0), so `det U · det V < 0` ⇔ `det A < 0` (for A of full rank).
///
/// Formula: [`svd3_rotations`], then if `σ₃ < 0`: `σ₃ ← −σ₃`, `u₃ ← −u₃`.
#[inline]
pub fn svd3(a: DMat3) -> Svd3 {
    let mut svd = svd3_rotations(a);
    if svd.sigma.z < 0.0 {
        svd.sigma.z = -svd.sigma.z;
        svd.u.z_axis = -svd.u.z_axis;
    }
    svd
}

/// The rotation nearest to `a` in Frobenius norm, from the SVD: `R = U diag(1, 1, det(UVᵀ)) Vᵀ`
/// (the maximizer of `tr(RᵀA)` over rotations). With the rotation-variant SVD of
/// [`svd3_rotations`] this is simply `R = U Vᵀ`. Robust for every input (rank-deficient:
/// one of the equally near rotations; zero: the identity). ~5× slower than
/// [`nearest_rotation3`], which falls back to it.
#[inline]
pub fn nearest_rotation3_svd(a: DMat3) -> DMat3 {
    let svd = svd3_rotations(a);
    svd.u * svd.v.transpose()
}

/// Iterations (Newton and Newton–Schulz together) after which [`nearest_rotation3_newton`]
/// gives up.
const MAX_ITERATIONS: usize = 24;
/// Newton gives way to Newton–Schulz once its step `‖X_{k+1} − X_k‖_F` is below this (the
/// singular values are then within ~1e-4 of 1, where Newton–Schulz converges as fast and is
/// cheaper: no inverse, no square root).
const NEWTON_SWITCH: f64 = 1e-2;
/// Newton steps after a step with `‖X_{k+1} − X_k‖_F²` above this are scaled (the first always).
const NEWTON_SCALED: f64 = 1.0;
/// The iteration stops after a Newton–Schulz step `‖X_{k+1} − X_k‖_F` below this: the error
/// left is then about `1.5 · step² ≈ 1e-15` (quadratic convergence).
const SCHULZ_STOP: f64 = 3e-8;
/// Largest accepted Frobenius condition number ‖X‖‖X⁻¹‖ of the lifted matrix (an identity has
/// 3); beyond it the SVD is more accurate.
const NEWTON_MAX_COND: f64 = 1e6;
/// Smallest accepted `det X / ‖X‖_F³` of the lifted matrix.
const NEWTON_MIN_DET: f64 = 1e-9;

/// The rotation nearest to `a` (`U diag(1, 1, det(UVᵀ)) Vᵀ` for `A = UΣVᵀ`), fast: the scaled
/// Newton polar iteration ([`nearest_rotation3_newton`]), falling back to
/// [`nearest_rotation3_svd`] when that declines (zero, rank ≤ 1, inverted with
/// σ₂ ≈ σ₃, ill-conditioned or non-finite input). The result is always a rotation (det +1).
#[inline]
pub fn nearest_rotation3(a: DMat3) -> DMat3 {
    match nearest_rotation3_newton(a) {
        Some(r) => r,
        None => nearest_rotation3_svd(a),
    }
}

/// The scaled Newton part of [`nearest_rotation3`]; `None` when it declines (then use the SVD).
///
/// Formula. Scale `Â = A/‖A‖_F` and lift it to `X₀ = Â + cof Â` ([`cofactor`]). With
/// `Â = UΣVᵀ` (U, V orthogonal, σ ≥ 0, s = det U det V), `cof Â = s U diag(σ₂σ₃, σ₁σ₃, σ₁σ₂) Vᵀ`,
/// so `X₀ = U diag(σ₁ + sσ₂σ₃, σ₂ + sσ₁σ₃, σ₃ + sσ₁σ₂) Vᵀ` has Â's singular vectors, and as
/// `σ₁ ≤ 1`: when `det X₀ > 0` its orthogonal polar factor is exactly
/// `U diag(1, 1, s) Vᵀ` = the rotation sought (for s = +1 all entries are positive; for s = −1
/// the first two are, so det X₀ > 0 forces the third negative). The lift also makes rank-2
/// inputs (flat one-rings) well conditioned: σ₃ + σ₁σ₂ > 0. Then Higham's scaled Newton
/// iteration `X ← ½(γX + (γX)⁻ᵀ)`, `(X)⁻ᵀ = cof X / det X`, converges quadratically to the
/// polar factor (2–3 steps for κ ≤ 10); γ = (‖X⁻¹‖_F/‖X‖_F)^½ (Frobenius-norm scaling) on the
/// first step and after steps longer than 1, else γ = 1 (it is ≈ 1 near convergence). Once a
/// Newton step is below 1e-2 the cheaper Newton–Schulz iteration `X ← ½X(3I − XᵀX)` (also
/// quadratic there) finishes, until its step is below 3e-8 (error ≈ 1e-15; 1–2 steps).
/// Declines when `det X₀ ≤ 1e-9 ‖X₀‖³` (inverted with σ₂ ≈ σ₃, or rank ≤ 1), when
/// `‖X₀‖‖X₀⁻¹‖ > 1e6`, or after 24 steps.
#[inline]
pub fn nearest_rotation3_newton(a: DMat3) -> Option<DMat3> {
    let mut a = a;
    let mut n2 = frobenius2(&a);
    if !(n2 > 1e-280 && n2 < 1e280) {
        // Tiny or huge entries: rescale by the largest one first (rare path).
        let scale = a.abs().to_cols_array().into_iter().fold(0.0, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        a *= 1.0 / scale;
        n2 = frobenius2(&a);
    }
    let a = a * (1.0 / n2.sqrt());
    let mut x = a + cofactor(&a);
    let mut cof = cofactor(&x);
    let mut det = x.x_axis.dot(cof.x_axis);
    let mut xn2 = frobenius2(&x);
    let mut cn2 = frobenius2(&cof);
    // det X₀ ≥ 1e-9 ‖X₀‖³ keeps det far above its rounding noise (~1e-16 ‖X₀‖³, which can
    // pass for a positive det when Â has rank 1); κ_F² = ‖X‖²‖cof X‖²/det². Rejects NaN too.
    if !(det > NEWTON_MIN_DET * xn2 * xn2.sqrt() && xn2 * cn2 < NEWTON_MAX_COND * NEWTON_MAX_COND * det * det) {
        return None;
    }
    let mut newton = true;
    let mut scaled = true;
    for _ in 0..MAX_ITERATIONS {
        let next = if scaled {
            // X ← ½(γX + cof X/(γ det X)), γ = (‖cof X‖/(det X ‖X‖))^½.
            let gamma = (cn2 / (det * det * xn2)).sqrt().sqrt();
            (x * gamma + cof * (1.0 / (gamma * det))) * 0.5
        } else if newton {
            // Near convergence γ ≈ 1: plain Newton, X ← ½(X + cof X/det X).
            (x + cof * (1.0 / det)) * 0.5
        } else {
            // Newton–Schulz: X ← ½ X (3I − XᵀX).
            x * (DMat3::from_diagonal(DVec3::splat(1.5)) - 0.5 * (x.transpose() * x))
        };
        let step2 = frobenius2(&(next - x));
        x = next;
        if newton {
            if step2 < NEWTON_SWITCH * NEWTON_SWITCH {
                newton = false;
                scaled = false;
            } else {
                scaled = step2 > NEWTON_SCALED;
                cof = cofactor(&x);
                det = x.x_axis.dot(cof.x_axis);
                if scaled {
                    xn2 = frobenius2(&x);
                    cn2 = frobenius2(&cof);
                }
            }
        } else if step2 < SCHULZ_STOP * SCHULZ_STOP {
            return Some(x);
        }
    }
    None
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::linalg::test_rng::Rng;
    use glam::DQuat;
    use nalgebra::Matrix3;

    fn frob(m: DMat3) -> f64 {
        frobenius2(&m).sqrt()
    }

    /// `tr(AᵀB)`.
    fn inner(a: DMat3, b: DMat3) -> f64 {
        a.x_axis.dot(b.x_axis) + a.y_axis.dot(b.y_axis) + a.z_axis.dot(b.z_axis)
    }

    fn to_na(m: DMat3) -> Matrix3<f64> {
        Matrix3::from_column_slice(&m.to_cols_array())
    }

    fn from_na(m: &Matrix3<f64>) -> DMat3 {
        let mut cols = [0.0; 9];
        cols.copy_from_slice(m.as_slice());
        DMat3::from_cols_array(&cols)
    }

    fn rotation(rng: &mut Rng) -> DMat3 {
        let q = DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform());
        DMat3::from_quat(q.normalize())
    }

    fn with_sigma(rng: &mut Rng, s: DVec3) -> DMat3 {
        rotation(rng) * DMat3::from_diagonal(s) * rotation(rng)
    }

    /// Random 3×3 matrices of every kind the tests need, with a label.
    fn samples(rng: &mut Rng, count: usize) -> Vec<(&'static str, DMat3)> {
        let mut out = vec![
            ("zero", DMat3::ZERO),
            ("identity", DMat3::IDENTITY),
            ("mirror", DMat3::from_diagonal(DVec3::new(1.0, 1.0, -1.0))),
            ("minus identity", -DMat3::IDENTITY),
            ("diag", DMat3::from_diagonal(DVec3::new(3.0, -2.0, 1.0))),
        ];
        for _ in 0..count {
            let g = DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3());
            out.push(("uniform", g));
            out.push(("near rotation", rotation(rng) * (DMat3::IDENTITY + 0.3 * g)));
            let mut inv = DMat3::IDENTITY + 0.3 * g;
            inv.z_axis = -inv.z_axis;
            out.push(("inverted", rotation(rng) * inv));
            out.push((
                "rank 1",
                DMat3::from_cols(rng.vec3() * rng.uniform(), DVec3::ZERO, DVec3::ZERO) * rotation(rng),
            ));
            let (x, y) = (rng.vec3(), rng.vec3());
            out.push(("outer", DMat3::from_cols(x * y.x, x * y.y, x * y.z)));
            let (z, w) = (rng.vec3(), rng.vec3());
            out.push(("rank 2", DMat3::from_cols(x * y.x + z * w.x, x * y.y + z * w.y, x * y.z + z * w.z)));
            let s = 1.0 + 0.5 * rng.uniform();
            out.push(("equal", with_sigma(rng, DVec3::splat(s))));
            out.push(("nearly equal", with_sigma(rng, DVec3::new(s, s * (1.0 + 1e-10), s * (1.0 - 1e-10)))));
            out.push(("nearly equal inverted", with_sigma(rng, DVec3::new(s, s * (1.0 - 1e-9), -s))));
            out.push(("graded", with_sigma(rng, DVec3::new(1.0, 1e-6, 1e-12))));
            let (s2, s3) = (0.3 + rng.uniform().abs(), 1e-4 * rng.uniform());
            out.push(("flat", with_sigma(rng, DVec3::new(1.0, s2, 0.0))));
            out.push(("flat-ish", with_sigma(rng, DVec3::new(1.0, 0.8, s3))));
            let s2 = 1e-4 * (1.5 + rng.uniform());
            out.push(("anisotropic", with_sigma(rng, DVec3::new(1.0, s2, 1e-3 * s3))));
            out.push(("tiny", g * 1e-200));
            out.push(("huge", g * 1e200));
        }
        out
    }

    fn check_orthogonal(u: DMat3, what: &str) {
        assert!(frob(u.transpose() * u - DMat3::IDENTITY) < 1e-14, "{what}: not orthogonal {u:?}");
    }

    #[test]
    fn svd3_reconstructs_sorts_and_matches_nalgebra() {
        let mut rng = Rng(0x5eed);
        let mut worst = 0.0f64;
        for (label, a) in samples(&mut rng, 1000) {
            let scale = frob(a);
            for svd in [svd3(a), svd3_rotations(a)] {
                let err = frob(svd.reconstruct() - a);
                worst = worst.max(err / scale.max(f64::MIN_POSITIVE));
                assert!(err <= 1e-12 * scale, "{label}: reconstruction {err:e} of {a:?}");
                check_orthogonal(svd.u, label);
                check_orthogonal(svd.v, label);
                assert!((svd.v.determinant() - 1.0).abs() < 1e-14, "{label}: det V");
                assert!(svd.sigma.x >= svd.sigma.y && svd.sigma.y >= svd.sigma.z.abs(), "{label}: order {svd:?}");
            }
            let std = svd3(a);
            assert!(std.sigma.z >= 0.0);
            let rot = svd3_rotations(a);
            assert!((rot.u.determinant() - 1.0).abs() < 1e-14, "{label}: det U");
            let det = a.determinant();
            if det.abs() > 1e-9 * scale * scale * scale {
                assert_eq!(rot.sigma.z < 0.0, det < 0.0, "{label}: σ₃ sign");
                assert_eq!(std.u.determinant() < 0.0, det < 0.0, "{label}: det U sign");
            }
            if !(1e-100..1e100).contains(&scale) {
                continue; // nalgebra's SVD under/overflows there
            }
            let na = to_na(a).svd(false, false).singular_values;
            for k in 0..3 {
                assert!((std.sigma[k] - na[k]).abs() <= 1e-12 * scale, "{label}: σ {std:?} vs {na}");
            }
        }
        assert!(worst < 1e-14, "worst relative reconstruction error {worst:e}");
    }

    /// The reference rotation `U diag(1, 1, det(UVᵀ)) Vᵀ` from nalgebra's SVD, and the conditioning
    /// `(σ₂ + sσ₃)/σ₁` of the problem (the rotation is unique when it is > 0).
    fn reference_rotation(a: DMat3) -> (DMat3, f64) {
        let svd = to_na(a).svd(true, true);
        let (Some(u), Some(vt)) = (svd.u, svd.v_t) else { panic!("nalgebra SVD without vectors") };
        let (u, vt) = (from_na(&u), from_na(&vt));
        let s = (u * vt).determinant().signum();
        let r = u * DMat3::from_diagonal(DVec3::new(1.0, 1.0, s)) * vt;
        let sv = svd.singular_values;
        (r, if sv[0] > 0.0 { (sv[1] + s * sv[2]) / sv[0] } else { 0.0 })
    }

    #[test]
    fn nearest_rotation3_is_a_rotation_matching_nalgebra_and_optimal() {
        let mut rng = Rng(77);
        let mut fallbacks = std::collections::BTreeMap::new();
        let mut worst = 0.0f64;
        for (label, a) in samples(&mut rng, 1000) {
            if nearest_rotation3_newton(a).is_none() {
                *fallbacks.entry(label).or_insert(0) += 1;
            }
            let scale = frob(a);
            for r in [nearest_rotation3(a), nearest_rotation3_svd(a)] {
                check_orthogonal(r, label);
                assert!((r.determinant() - 1.0).abs() < 1e-14, "{label}: det R");
                if !(1e-100..1e100).contains(&scale) {
                    continue; // nalgebra's SVD under/overflows there
                }
                let (reference, gap) = reference_rotation(a);
                // The objective tr(RᵀA) is never worse than the reference's.
                let obj = inner(r, a);
                let ref_obj = inner(reference, a);
                assert!(obj >= ref_obj - 1e-13 * scale, "{label}: objective {obj} < {ref_obj}");
                // Where the rotation is unique and well conditioned it is the same matrix, up to
                // the accuracy of nalgebra's SVD (eigenvectors of AᵀA: error ~ ε/gap²).
                if gap > 1e-3 {
                    let err = frob(r - reference);
                    assert!(err < 1e-14 / (gap * gap), "{label}: {err:e} from nalgebra (gap {gap:e})");
                }
            }
            // The Newton path agrees with the (more accurate) one-sided Jacobi SVD to ~ε/gap.
            if let Some(r) = nearest_rotation3_newton(a) {
                let gap = reference_rotation(a).1;
                let err = frob(r - nearest_rotation3_svd(a));
                assert!(err < 4e-15 / gap.clamp(1e-6, 1.0), "{label}: Newton {err:e} from SVD (gap {gap:e})");
                worst = worst.max(err * gap);
            }
        }
        assert!(worst < 4e-15, "worst Newton error × gap {worst:e}");
        // The fast path takes the common cases: only degenerate or inverted inputs fall back.
        for label in
            ["identity", "diag", "near rotation", "rank 2", "equal", "nearly equal", "flat", "flat-ish", "anisotropic"]
        {
            assert!(!fallbacks.contains_key(label), "{label} fell back to the SVD: {fallbacks:?}");
        }
        for label in ["uniform", "tiny", "huge"] {
            assert!(fallbacks.get(label).copied().unwrap_or(0) < 50, "{fallbacks:?}");
        }
    }

    #[test]
    fn nearest_rotation3_beats_sampled_rotations() {
        let mut rng = Rng(99);
        for (label, a) in samples(&mut rng, 40) {
            let r = nearest_rotation3(a);
            let d = frob(r - a);
            let tol = 1e-13 * (1.0 + frob(a));
            for _ in 0..200 {
                let sample = rotation(&mut rng);
                assert!(d <= frob(sample - a) + tol, "{label}: random rotation closer");
                // Small perturbations of the answer probe optimality locally.
                let axis = rng.vec3();
                let near = r * DMat3::from_axis_angle(axis.normalize_or(DVec3::X), 1e-3 * rng.uniform());
                assert!(d <= frob(near - a) + tol, "{label}: nearby rotation closer");
            }
        }
    }

    #[test]
    fn newton_path_is_taken_for_near_rotations_and_flat_one_rings() {
        let mut rng = Rng(4);
        for _ in 0..1000 {
            let g = DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3());
            let a = rotation(&mut rng) * (DMat3::IDENTITY + 0.3 * g);
            assert!(nearest_rotation3_newton(a).is_some() || a.determinant() <= 0.0);
            // S = Σ e eᵀ of a planar one-ring, rotated: rank 2.
            let flat = rotation(&mut rng) * DMat3::from_diagonal(DVec3::new(1.0, 0.5 + rng.uniform().abs(), 0.0));
            assert!(nearest_rotation3_newton(flat).is_some());
        }
    }
}
