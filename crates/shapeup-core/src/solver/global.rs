//! Global step: the right-hand side Σ w_i C_iᵀ P_i and the prefactored solve for x, y, z.

use super::assemble::Assembly;
use glam::DVec3;
use rayon::prelude::*;

/// Solved vertices per parallel task when forming the right-hand side.
const MIN_LEN: usize = 2048;

/// Where each entry of C goes in the right-hand side, and with what weight: the global step's
/// per-iteration view of the assembly, in the factor's permuted order.
#[derive(Debug, Default)]
pub(crate) struct RhsMap {
    /// Per entry of C (CSR order): the permuted position of its column's solved vertex in the
    /// factor, or `u32::MAX` when that vertex is not solved (held by a hard group).
    pub slot: Vec<u32>,
    /// Per entry of C: g · w_r · c_rk (multiplier, element weight, coefficient).
    pub weighted: Vec<f64>,
}

/// Entries of C per part of the right-hand side, and the most parts. The number of parts is a
/// function of the problem alone, not of the thread count, so that every thread count sums in
/// the same order and gets the same bits (Anderson acceleration's accept/reject decisions
/// amplify a last-bit difference to 1e-8 over 50 iterations). A part costs a pass to clear its
/// buffer and one to add it: on the bunny at 2 threads the split paid for strain + bending's
/// 634 k entries (1.06 → 0.72 ms) but not for springs' 210 k (0.26 → 0.36 ms).
const ENTRIES_PER_PART: usize = 1 << 18;
const MAX_PARTS: usize = 4;

/// b = Σ_r w_r c_rᵀ P_r added into `out` (permuted order, a vertex's x, y, z side by side; the
/// caller starts it from the constant part). Rows are walked in order and their entries added
/// into b: P and C stream through memory, and b, a few hundred kilobytes, stays in cache; the
/// gather by vertex it replaces (b_v = Σ over Cᵀ's column v) read P at random and took 3–4 ns
/// an entry on the bunny. Large problems are split into blocks of rows, each added into its
/// own `partials` buffer (kept between calls) in parallel, then summed into `out` in order.
pub(crate) fn right_hand_side(
    a: &Assembly,
    map: &RhsMap,
    p: &[DVec3],
    out: &mut [[f64; 4]],
    partials: &mut Vec<Vec<[f64; 4]>>,
) {
    let entries = a.c_ptr.last().copied().unwrap_or(0);
    let parts = (entries / ENTRIES_PER_PART).clamp(1, MAX_PARTS);
    if parts == 1 {
        add_rows(a, map, p, 0..a.num_rows(), out);
        return;
    }
    partials.resize_with(parts - 1, Vec::new);
    let size = out.len();
    // Row blocks of about equal numbers of entries.
    let bounds: Vec<usize> =
        (0..=parts).map(|t| a.c_ptr.partition_point(|&k| k < entries * t / parts).min(a.num_rows())).collect();
    rayon::scope(|scope| {
        for (t, partial) in partials.iter_mut().enumerate() {
            let rows = bounds[t + 1]..bounds[t + 2];
            scope.spawn(move |_| {
                partial.clear();
                partial.resize(size, [0.0; 4]);
                add_rows(a, map, p, rows, partial);
            });
        }
        add_rows(a, map, p, bounds[0]..bounds[1], out);
    });
    out.par_chunks_mut(MIN_LEN).enumerate().for_each(|(c, chunk)| {
        for partial in partials.iter() {
            for (o, x) in chunk.iter_mut().zip(&partial[c * MIN_LEN..]) {
                for k in 0..3 {
                    o[k] += x[k];
                }
            }
        }
    });
}

/// `out[slot] += weighted · P_r` for the entries of `rows`.
#[inline]
fn add_rows(a: &Assembly, map: &RhsMap, p: &[DVec3], rows: std::ops::Range<usize>, out: &mut [[f64; 4]]) {
    for r in rows {
        let pr = p[r];
        for k in a.c_ptr[r]..a.c_ptr[r + 1] {
            if let Some(b) = out.get_mut(map.slot[k] as usize) {
                let w = map.weighted[k];
                b[0] += w * pr.x;
                b[1] += w * pr.y;
                b[2] += w * pr.z;
            }
        }
    }
}

/// The solution, in the factor's order (position i solves for solved vertex `forward[i]`),
/// back into the full position array; `false`, writing nothing, if it holds a NaN or an
/// infinity.
pub(crate) fn scatter(a: &Assembly, forward: &[u32], solution: &[[f64; 4]], q: &mut [DVec3]) -> bool {
    if !solution.iter().all(|x| x[..3].iter().all(|c| c.is_finite())) {
        return false;
    }
    for (x, &s) in solution.iter().zip(forward) {
        q[a.solved[s as usize] as usize] = DVec3::new(x[0], x[1], x[2]);
    }
    true
}

/// C q, one row per constraint row (for energies).
pub(crate) fn apply_c(a: &Assembly, q: &[DVec3], out: &mut [DVec3]) {
    out.par_iter_mut().enumerate().with_min_len(MIN_LEN).for_each(|(r, o)| {
        *o = (a.c_ptr[r]..a.c_ptr[r + 1]).map(|k| a.c_val[k] * q[a.c_col[k] as usize]).sum();
    });
}

/// The solved vertices of q in the factor's order (the inverse of [`scatter`]), fourth lane 0.
pub(crate) fn gather(a: &Assembly, forward: &[u32], q: &[DVec3], out: &mut [[f64; 4]]) {
    for (o, &s) in out.iter_mut().zip(forward) {
        let p = q[a.solved[s as usize] as usize];
        *o = [p.x, p.y, p.z, 0.0];
    }
}
