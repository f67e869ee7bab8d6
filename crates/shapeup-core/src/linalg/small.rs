//! Small dense solves on fixed-size arrays: a Cholesky solve ([`solve_spd`]) and linear least
//! squares by the normal equations ([`linear_least_squares`]).

/// Solves `a x = b` for a symmetric positive definite P×P `a` (Cholesky); `None` when a pivot
/// is not positive (singular or indefinite) or the result is not finite.
#[allow(clippy::needless_range_loop)] // triangular index patterns read best as indices
pub(crate) fn solve_spd<const P: usize>(mut a: [[f64; P]; P], mut b: [f64; P]) -> Option<[f64; P]> {
    for j in 0..P {
        let mut pivot = a[j][j];
        for k in 0..j {
            pivot -= a[j][k] * a[j][k];
        }
        if pivot.is_nan() || pivot <= 0.0 {
            return None;
        }
        let pivot = pivot.sqrt();
        a[j][j] = pivot;
        for i in j + 1..P {
            let mut x = a[i][j];
            for k in 0..j {
                x -= a[i][k] * a[j][k];
            }
            a[i][j] = x / pivot;
        }
    }
    for i in 0..P {
        let mut x = b[i];
        for k in 0..i {
            x -= a[i][k] * b[k];
        }
        b[i] = x / a[i][i];
    }
    for i in (0..P).rev() {
        let mut x = b[i];
        for k in i + 1..P {
            x -= a[k][i] * b[k];
        }
        b[i] = x / a[i][i];
    }
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// The least-squares solution of Σ_rows (row·x − rhs)² by the normal equations (for the
/// algebraic starts, where an approximate solution is enough); `None` when singular.
pub(crate) fn linear_least_squares<const P: usize>(rows: impl Iterator<Item = ([f64; P], f64)>) -> Option<[f64; P]> {
    let mut a = [[0.0; P]; P];
    let mut b = [0.0; P];
    for (row, rhs) in rows {
        for i in 0..P {
            b[i] += row[i] * rhs;
            for j in 0..P {
                a[i][j] += row[i] * row[j];
            }
        }
    }
    solve_spd(a, b)
}
