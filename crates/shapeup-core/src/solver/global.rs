//! Global step: the right-hand side Σ w_i C_iᵀ P_i and the prefactored solve for x, y, z.

use super::assemble::Assembly;
use glam::DVec3;
use rayon::prelude::*;

/// Solved vertices per parallel task when forming the right-hand side.
const MIN_LEN: usize = 2048;

/// b = Σ_r w_r c_rᵀ P_r (+ `extra` per solved vertex, e.g. M s / h²), written column-major
/// into `rhs` (x column, then y, then z), one solved vertex per row; `ct_weighted` holds
/// w_r · coeff for each entry of Cᵀ.
pub(crate) fn right_hand_side(
    a: &Assembly,
    ct_weighted: &[f64],
    p: &[DVec3],
    extra: Option<&[DVec3]>,
    rhs: &mut [f64],
) {
    let ns = a.num_solved();
    let (xs, rest) = rhs.split_at_mut(ns);
    let (ys, zs) = rest.split_at_mut(ns);
    xs.par_iter_mut().zip(ys.par_iter_mut()).zip(zs.par_iter_mut()).enumerate().with_min_len(MIN_LEN).for_each(
        |(v, ((x, y), z))| {
            let mut b = extra.map_or(DVec3::ZERO, |e| e[v]);
            for k in a.ct_ptr[v]..a.ct_ptr[v + 1] {
                b += ct_weighted[k] * p[a.ct_row[k] as usize];
            }
            (*x, *y, *z) = (b.x, b.y, b.z);
        },
    );
}

/// Writes the solved coordinates back into the full position array.
pub(crate) fn scatter(a: &Assembly, solution: &[f64], q: &mut [DVec3]) {
    let ns = a.num_solved();
    for (s, &v) in a.solved.iter().enumerate() {
        q[v as usize] = DVec3::new(solution[s], solution[ns + s], solution[2 * ns + s]);
    }
}

/// C q, one row per constraint row (for energies).
pub(crate) fn apply_c(a: &Assembly, q: &[DVec3], out: &mut [DVec3]) {
    out.par_iter_mut().enumerate().with_min_len(MIN_LEN).for_each(|(r, o)| {
        *o = (a.c_ptr[r]..a.c_ptr[r + 1]).map(|k| a.c_val[k] * q[a.c_col[k] as usize]).sum();
    });
}
