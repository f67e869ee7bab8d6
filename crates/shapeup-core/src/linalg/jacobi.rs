//! The one-sided Jacobi plane rotation shared by the 3×3 SVD ([`svd3_rotations`](super::svd3_rotations))
//! and the k×M singular values of the constraint sets.

/// The rotation (c, s) that makes two columns bᵢ, bⱼ orthogonal, from ‖bᵢ‖² = `ni`,
/// ‖bⱼ‖² = `nj` and g = bᵢ·bⱼ (g ≠ 0): the new columns are c bᵢ − s bⱼ and s bᵢ + c bⱼ.
/// Without ζ: with d = ‖bⱼ‖² − ‖bᵢ‖², r = √(d² + 4g²), w = r + |d|: t = 2g sgn(d)/w,
/// c = 1/√(1 + t²) = w/√(2rw), s = tc (one division, no overflow).
#[inline]
pub fn jacobi_rotation(ni: f64, nj: f64, g: f64) -> (f64, f64) {
    let d = nj - ni;
    let r = (d * d + 4.0 * g * g).sqrt();
    let w = r + d.abs();
    let h = 1.0 / (2.0 * r * w).sqrt();
    let c = w * h;
    let s = if d < 0.0 { -2.0 * g * h } else { 2.0 * g * h };
    (c, s)
}
