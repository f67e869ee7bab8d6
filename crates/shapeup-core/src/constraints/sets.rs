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
