//! Membership of constraint sets, shared by several types' [`Constraint::set_residual`]
//! (crate::constraints::Constraint::set_residual): each is a direct test of the set's definition, not a
//! second projection, so that the shared tests can check projections against it.

use crate::linalg::{jacobi_rotation, svd3};
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

/// How far the vectors `p` are from the rotations {R rᵢ : R ∈ SO(3)} of the vectors `r`, in
/// length units: (max_ij |pᵢ·pⱼ − rᵢ·rⱼ|) / L + |det[p_a, p_b, p_c] − det[r_a, r_b, r_c]| / L²,
/// L = max(max_i ‖pᵢ‖, max_i ‖rᵢ‖) (0 when L = 0; ∞ for a non-finite p), with (a, b, c) three
/// vectors spanning `r` as well as a greedy search finds (the longest r_a, the r_b farthest
/// from its line, the r_c farthest from their plane). The first term is zero exactly for an
/// orthogonal transform of `r` (same lengths and angles); the second then tells a rotation
/// from a reflection (they differ only when `r` spans space). The powers of L make it a
/// length at every scale (the Gram entries are squared lengths, the determinants cubed).
pub(crate) fn isometry_residual(p: &[DVec3], r: &[DVec3]) -> f64 {
    if !p.iter().all(|x| x.is_finite()) {
        return f64::INFINITY;
    }
    let longest = |rows: &[DVec3]| rows.iter().map(|x| x.length()).fold(0.0, f64::max);
    let scale = longest(p).max(longest(r));
    if scale == 0.0 || p.is_empty() {
        return 0.0;
    }
    let mut gram: f64 = 0.0;
    for i in 0..p.len() {
        for j in i..p.len() {
            gram = gram.max((p[i].dot(p[j]) - r[i].dot(r[j])).abs());
        }
    }
    let argmax = |f: &dyn Fn(DVec3) -> f64| {
        r.iter().enumerate().fold((0, f64::NEG_INFINITY), |best, (i, d)| {
            let x = f(*d);
            if x > best.1 { (i, x) } else { best }
        })
    };
    let a = argmax(&|d| d.length_squared()).0;
    let b = argmax(&|d| r[a].cross(d).length_squared()).0;
    let normal = r[a].cross(r[b]);
    let c = argmax(&|d| normal.dot(d).abs()).0;
    let det = p[a].cross(p[b]).dot(p[c]);
    gram / scale + (det - normal.dot(r[c])).abs() / (scale * scale)
}

/// The largest row of `a − b`.
pub(crate) fn max_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).length()).fold(0.0, f64::max)
}

/// Jacobi sweeps after which [`singular_values`] stops even if not converged.
const JACOBI_SWEEPS: usize = 40;
/// Columns count as orthogonal when `|bᵢ·bⱼ| ≤ JACOBI_TOL · ‖bᵢ‖‖bⱼ‖`.
const JACOBI_TOL: f64 = 1e-15;

/// Singular values `σ₁ ≥ … ≥ σ_M ≥ 0` of the k×M matrix with rows `rows`, and its right
/// singular vectors (`v[j]` belongs to `σ_j`), by one-sided (Hestenes) Jacobi on the columns,
/// as [`svd3_rotations`](crate::linalg::svd3_rotations) does for 3×3: plane rotations on the
/// right make the columns mutually orthogonal to working precision relative to their lengths,
/// so that the small singular values (what rank tests read) are accurate to about 1e-15 of the
/// largest. With k < M the last M − k values are 0. The matrix is scaled by its largest entry
/// first; the zero matrix gives σ = 0, V = I.
pub(crate) fn singular_values<const M: usize>(rows: &[[f64; M]]) -> ([f64; M], [[f64; M]; M]) {
    let mut v = [[0.0; M]; M];
    for (j, column) in v.iter_mut().enumerate() {
        column[j] = 1.0;
    }
    let scale = rows.iter().flatten().fold(0.0, |a: f64, x| a.max(x.abs()));
    if !(scale > 0.0 && scale.is_finite()) {
        let sigma = if scale == 0.0 { 0.0 } else { f64::NAN };
        return ([sigma; M], v);
    }
    // Columns b_j (and v_j, stored as columns too).
    let mut b: Vec<[f64; M]> = rows.iter().map(|r| r.map(|x| x / scale)).collect();
    let column_norm2 = |b: &[[f64; M]], j: usize| b.iter().map(|r| r[j] * r[j]).sum::<f64>();
    let mut n: [f64; M] = std::array::from_fn(|j| column_norm2(&b, j));
    for _ in 0..JACOBI_SWEEPS {
        let mut rotated = false;
        for i in 0..M {
            for j in i + 1..M {
                let g: f64 = b.iter().map(|r| r[i] * r[j]).sum();
                if g * g <= JACOBI_TOL * JACOBI_TOL * n[i] * n[j] {
                    continue;
                }
                rotated = true;
                let (c, s) = jacobi_rotation(n[i], n[j], g);
                for row in b.iter_mut() {
                    let (bi, bj) = (row[i], row[j]);
                    row[i] = c * bi - s * bj;
                    row[j] = s * bi + c * bj;
                }
                for column in v.iter_mut() {
                    let (vi, vj) = (column[i], column[j]);
                    column[i] = c * vi - s * vj;
                    column[j] = s * vi + c * vj;
                }
                n[i] = column_norm2(&b, i);
                n[j] = column_norm2(&b, j);
            }
        }
        if !rotated {
            break;
        }
    }
    // `v` holds V by rows (v[row][column]); sort the columns by decreasing norm.
    let mut order: [usize; M] = std::array::from_fn(|j| j);
    order.sort_by(|&a, &b| n[b].total_cmp(&n[a]));
    let sigma = order.map(|j| n[j].sqrt() * scale);
    let vectors = order.map(|j| std::array::from_fn(|row| v[row][j]));
    (sigma, vectors)
}

/// The centroid of `points`, the singular values σ₁ ≥ σ₂ ≥ σ₃ of the points about it (rows
/// `x_i − x̄`) and the principal axes (unit, in the same order): σ₃ = 0 exactly when the points
/// are coplanar, σ₂ = σ₃ = 0 when collinear. Empty input: zero centroid, σ = 0, the unit axes.
pub(crate) fn principal_axes(points: &[DVec3]) -> (DVec3, [f64; 3], [DVec3; 3]) {
    let centroid =
        if points.is_empty() { DVec3::ZERO } else { points.iter().copied().sum::<DVec3>() / points.len() as f64 };
    let rows: Vec<[f64; 3]> = points.iter().map(|&x| (x - centroid).to_array()).collect();
    let (sigma, v) = singular_values(&rows);
    (centroid, sigma, v.map(DVec3::from_array))
}

/// ‖Σ_i p_i‖ / √k: the distance (Frobenius, over the k rows) of `p` from the centred
/// configurations (Σ p_i = 0), where the mean-centred rows of line, plane, circle and sphere live.
pub(crate) fn centroid_offset(p: &[DVec3]) -> f64 {
    if p.is_empty() { 0.0 } else { p.iter().copied().sum::<DVec3>().length() / (p.len() as f64).sqrt() }
}

/// Singular values σ₁ ≥ … ≥ σ₅ of the k×5 "lifted" matrix with rows (‖y_i‖²/L, y_i, L),
/// y_i = p_i − p̄ and L = max_i ‖y_i‖ (so that every column is in length units and of the
/// points' size). A row is orthogonal to (a, b, e) exactly when y_i lies on the generalized
/// sphere a‖y‖²/L + b·y + eL = 0 (a sphere, or a plane when a = 0), so:
/// - σ₅ = 0 ⇔ the points lie on one sphere or plane (cospherical, or coplanar: the closure of
///   the cospherical configurations);
/// - σ₄ = 0 ⇔ a two-dimensional null space ⇔ one plane and one more sphere or plane contain
///   them ⇔ the points lie on one circle or line (concyclic, or collinear: the closure of the
///   concyclic configurations).
///
/// Coincident points (L = 0) give σ = 0.
pub(crate) fn lifted_singular_values(p: &[DVec3]) -> [f64; 5] {
    if p.is_empty() {
        return [0.0; 5];
    }
    let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
    let length = p.iter().map(|&x| (x - mean).length()).fold(0.0, f64::max);
    if length == 0.0 {
        return [0.0; 5];
    }
    if !length.is_finite() {
        return [f64::NAN; 5];
    }
    let rows: Vec<[f64; 5]> = p
        .iter()
        .map(|&x| {
            let y = x - mean;
            [y.length_squared() / length, y.x, y.y, y.z, length]
        })
        .collect();
    singular_values(&rows).0
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
