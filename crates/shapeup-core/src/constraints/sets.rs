//! Membership of constraint sets, shared by several types' [`Constraint::set_residual`]
//! (super::Constraint::set_residual): each is a direct test of the set's definition, not a
//! second projection, so that the shared tests can check projections against it.

use crate::linalg::svd3;
use glam::{DMat3, DVec3};

/// Distance of x from the interval [lo, hi].
pub(crate) fn interval_distance(x: f64, lo: f64, hi: f64) -> f64 {
    (lo - x).max(x - hi).max(0.0)
}

/// Singular values of the 3×2 matrix with columns `a`, `b` (descending): square roots of the
/// eigenvalues of its 2×2 Gram matrix.
pub(crate) fn singular_values_3x2(a: DVec3, b: DVec3) -> [f64; 2] {
    let (p, q, r) = (a.length_squared(), a.dot(b), b.length_squared());
    let mean = 0.5 * (p + r);
    let d = (0.25 * (p - r) * (p - r) + q * q).sqrt();
    [(mean + d).max(0.0).sqrt(), (mean - d).max(0.0).sqrt()]
}

/// How far the 3×3 matrix `m` is from having every singular value in [lo, hi] and det ≥ 0
/// (for `lo > 0`: a rotation times a stretch within the band).
pub(crate) fn strain_band_residual(m: DMat3, lo: f64, hi: f64) -> f64 {
    let s = svd3(m).sigma;
    let band = [s.x, s.y, s.z].iter().map(|&x| interval_distance(x, lo, hi)).fold(0.0, f64::max);
    band.max((-m.determinant()).max(0.0))
}

/// max_ij |pᵢ·pⱼ − rᵢ·rⱼ|: zero exactly when the vectors `p` are an orthogonal transform of
/// `r` (same lengths and angles), i.e. an isometric copy.
pub(crate) fn gram_residual(p: &[DVec3], r: &[DVec3]) -> f64 {
    let mut worst: f64 = 0.0;
    for i in 0..p.len() {
        for j in i..p.len() {
            worst = worst.max((p[i].dot(p[j]) - r[i].dot(r[j])).abs());
        }
    }
    worst
}

/// The largest row of `a − b`.
pub(crate) fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f64::max)
}

/// A root of `f` in `[lo, hi]`, given a sign change (`f(lo)` and `f(hi)` of opposite signs or
/// one of them zero; otherwise the end with the smaller |f| is returned): regula falsi with the
/// Illinois modification, falling back to bisection whenever a step is not inside the bracket or
/// three steps have not halved it, until the bracket is a few ulps wide. For the 1-D equations
/// of exact projections (a multiplier, a singular value), where a plain Newton step could leave
/// the branch it started on.
pub(crate) fn bracketed_root(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    let (mut a, mut b) = (lo.min(hi), lo.max(hi));
    let (mut fa, mut fb) = (f(a), f(b));
    if fa == 0.0 {
        return a;
    }
    if fb == 0.0 {
        return b;
    }
    if fa.is_nan() || fb.is_nan() || (fa > 0.0) == (fb > 0.0) {
        return if fa.abs() <= fb.abs() { a } else { b };
    }
    // Which end was kept by the last step (Illinois: an end kept twice has its f halved).
    let mut kept = 0i8;
    let mut checkpoint = b - a;
    for k in 0..400 {
        let mid = a + 0.5 * (b - a);
        if !(mid > a && mid < b) || b - a <= 2.0 * f64::EPSILON * a.abs().max(b.abs()) {
            break;
        }
        let mut x = b - fb * ((b - a) / (fb - fa));
        if k % 3 == 2 {
            if b - a > 0.5 * checkpoint {
                x = mid;
            }
            checkpoint = b - a;
        }
        if !(x > a && x < b) {
            x = mid;
        }
        let fx = f(x);
        if fx == 0.0 {
            return x;
        }
        if fx.is_nan() {
            break;
        }
        if (fx > 0.0) == (fb > 0.0) {
            b = x;
            fb = fx;
            if kept == -1 {
                fa *= 0.5;
            }
            kept = -1;
        } else {
            a = x;
            fa = fx;
            if kept == 1 {
                fb *= 0.5;
            }
            kept = 1;
        }
    }
    if fa.abs() <= fb.abs() { a } else { b }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn bracketed_root_finds_roots_to_full_precision() {
        let r = bracketed_root(|x| x * x - 2.0, 0.0, 2.0);
        assert!((r - std::f64::consts::SQRT_2).abs() <= 4.0 * f64::EPSILON, "{r}");
        // Steep, flat and decreasing functions.
        let r = bracketed_root(|x| (x - 1e-9).powi(3), 0.0, 10.0);
        assert!((r - 1e-9).abs() < 1e-12, "{r}");
        let r = bracketed_root(|x| 1.0 / x - 3.0, 1e-300, 1.0);
        assert!((r - 1.0 / 3.0).abs() <= 4.0 * f64::EPSILON, "{r}");
        let r = bracketed_root(|x| (-x).exp() - 0.5, 0.0, 50.0);
        assert!((r - std::f64::consts::LN_2).abs() <= 4.0 * f64::EPSILON, "{r}");
        // No sign change: the end nearer a root.
        assert_eq!(bracketed_root(|x| x + 1.0, 0.0, 1.0), 0.0);
    }
}
