//! Sparse triangular solves with L in compressed columns, for the three coordinates at once.
//!
//! The global step solves L Lᵀ x = b for x, y and z. Here the coordinates of a vertex sit side by
//! side (`[f64; 4]`, the fourth lane padding), so each entry of L is read once for all three and
//! its update is one 4-wide multiply-add. faer's sparse triangular solves (column-major right
//! sides, one sum per column in the transposed solve, scalar code) spent 1.6 of the bunny's
//! 2.5 ms springs solve and 6 of its 8.3 ms strain + bending solve in the back substitution:
//! a chain of dependent additions per column, and a factor read against the prefetchers' grain.
//! These two loops fix both; no crate offers them.
//!
//! L is lower triangular, stored by columns with the diagonal entry first in each column and the
//! rows below it after (faer's simplicial layout, and that of `SolveColumns`). On x86-64 CPUs with
//! AVX2 and FMA (x86-64-v3) the loops are compiled for those, chosen at run time through pulp
//! (faer's own dispatch crate); elsewhere as plain code.
/// L in compressed sparse columns: column j holds rows `row_idx[col_ptr[j]..col_ptr[j+1]]` with
/// values at the same positions; the first entry of each column is its diagonal (positive).
#[derive(Clone, Copy)]
pub(crate) struct LowerColumns<'a> {
    pub col_ptr: &'a [u32],
    pub row_idx: &'a [u32],
    pub values: &'a [f64],
}

impl LowerColumns<'_> {
    /// Column j: its diagonal entry, then the rows below it and their values.
    #[inline(always)]
    fn column(&self, j: usize) -> (f64, &[u32], &[f64]) {
        let (start, end) = (self.col_ptr[j] as usize, self.col_ptr[j + 1] as usize);
        (self.values[start], &self.row_idx[start + 1..end], &self.values[start + 1..end])
    }
}

/// Solves L Lᵀ x = b in place (x holds b on entry): [`forward_substitute`] then
/// [`back_substitute`], with the widest instruction set the CPU has.
pub(crate) fn solve_llt(l: LowerColumns<'_>, x: &mut [[f64; 4]]) {
    #[cfg(target_arch = "x86_64")]
    if let Some(simd) = pulp::x86::V3::try_new() {
        return simd.vectorize(|| {
            forward_substitute::<true>(l, x);
            back_substitute::<true>(l, x);
        });
    }
    forward_substitute::<false>(l, x);
    back_substitute::<false>(l, x);
}

/// a·b + c, rounded once where the CPU has a fused multiply-add (`FUSED`), else twice.
#[inline(always)]
fn multiply_add<const FUSED: bool>(a: f64, b: f64, c: f64) -> f64 {
    if FUSED { a.mul_add(b, c) } else { a * b + c }
}

/// Forward substitution L y = b in place (x holds b on entry, y on return), column-oriented:
/// y_j = b_j / L_jj, then b_i −= L_ij y_j for the rows i below j.
#[inline(always)]
pub(crate) fn forward_substitute<const FUSED: bool>(l: LowerColumns<'_>, x: &mut [[f64; 4]]) {
    for j in 0..x.len() {
        let (diagonal, rows, values) = l.column(j);
        // The reciprocal does not wait for x: only a multiplication is on the critical path
        // (x_j is usually updated by column j − 1, its child in the elimination tree).
        let inverse = 1.0 / diagonal;
        let y = x[j].map(|b| b * inverse);
        x[j] = y;
        for (&i, &v) in rows.iter().zip(values) {
            let xi = &mut x[i as usize];
            for c in 0..4 {
                xi[c] = multiply_add::<FUSED>(-v, y[c], xi[c]);
            }
        }
    }
}

/// Independent partial sums in [`back_substitute`].
const SUMS: usize = 4;

/// Back substitution Lᵀ x = y in place, column-oriented (row j of Lᵀ is column j of L):
/// x_j = (y_j − Σ_{i>j} L_ij x_i) / L_jj, from the last row up.
#[inline(always)]
pub(crate) fn back_substitute<const FUSED: bool>(l: LowerColumns<'_>, x: &mut [[f64; 4]]) {
    for j in (0..x.len()).rev() {
        let (diagonal, rows, values) = l.column(j);
        // x_j is needed by the next column up, so the dot product is the critical path: it is
        // split over four partial sums. Entries go from the last up, so that the whole pass
        // reads L downward in memory, a stream the prefetchers follow (ascending entries in
        // descending columns made this pass 3× slower than the forward one once L outgrew
        // the cache).
        let mut sums = [[0.0; 4]; SUMS];
        for (r, v) in rows.rchunks_exact(SUMS).zip(values.rchunks_exact(SUMS)) {
            for k in 0..SUMS {
                let p = x[r[k] as usize];
                for c in 0..4 {
                    sums[k][c] = multiply_add::<FUSED>(v[k], p[c], sums[k][c]);
                }
            }
        }
        let head = rows.len() % SUMS;
        for (k, (&r, &v)) in rows[..head].iter().zip(&values[..head]).enumerate() {
            let p = x[r as usize];
            for c in 0..4 {
                sums[k][c] = multiply_add::<FUSED>(v, p[c], sums[k][c]);
            }
        }
        let inverse = 1.0 / diagonal;
        let xj = &mut x[j];
        for c in 0..4 {
            let sum = (sums[0][c] + sums[1][c]) + (sums[2][c] + sums[3][c]);
            xj[c] = (xj[c] - sum) * inverse;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dense lower-triangular L with a positive diagonal, as compressed columns.
    fn dense_lower(n: usize) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
        let (mut cp, mut ri, mut v) = (vec![0u32], vec![], vec![]);
        for j in 0..n {
            for i in j..n {
                ri.push(i as u32);
                v.push(if i == j { 2.0 + j as f64 * 0.1 } else { ((i * 7 + j * 3) % 5) as f64 * 0.1 - 0.2 });
            }
            cp.push(ri.len() as u32);
        }
        (cp, ri, v)
    }

    /// L as a dense matrix, entry (i, j).
    fn entry(l: LowerColumns<'_>, i: usize, j: usize) -> f64 {
        let range = l.col_ptr[j] as usize..l.col_ptr[j + 1] as usize;
        l.row_idx[range.clone()].iter().zip(&l.values[range]).find(|(r, _)| **r as usize == i).map_or(0.0, |(_, v)| *v)
    }

    #[test]
    fn forward_and_back_substitution_invert_l_and_its_transpose() {
        check_substitutions::<false>();
        check_substitutions::<true>();
    }

    /// M x = b to 1e-12 relative, each of the four lanes, M given entry by entry.
    fn assert_solves(n: usize, m: impl Fn(usize, usize) -> f64, x: &[[f64; 4]], b: &[[f64; 4]], what: &str) {
        for (i, bi) in b.iter().enumerate() {
            for c in 0..4 {
                let mx: f64 = (0..n).map(|j| m(i, j) * x[j][c]).sum();
                assert!((mx - bi[c]).abs() < 1e-12 * (1.0 + bi[c].abs()), "{what}, n={n} row {i}: {mx} vs {}", bi[c]);
            }
        }
    }

    fn check_substitutions<const FUSED: bool>() {
        for n in [1, 2, 3, 8, 17] {
            let (cp, ri, v) = dense_lower(n);
            let l = LowerColumns { col_ptr: &cp, row_idx: &ri, values: &v };
            let b: Vec<[f64; 4]> = (0..n).map(|i| [i as f64 + 1.0, (i as f64).sin(), -2.0 * i as f64, 0.5]).collect();
            // L y = b
            let mut y = b.clone();
            forward_substitute::<FUSED>(l, &mut y);
            assert_solves(n, |i, j| entry(l, i, j), &y, &b, "L");
            // Lᵀ x = b
            let mut x = b.clone();
            back_substitute::<FUSED>(l, &mut x);
            assert_solves(n, |i, j| entry(l, j, i), &x, &b, "Lᵀ");
        }
    }
}
