//! Sparse Cholesky factorization of the global matrix: the only file that names faer.
//!
//! The symbolic analysis (fill-reducing ordering: AMD, or nested dissection for dense patterns;
//! elimination tree, supernodes) runs once
//! per sparsity pattern; the numeric factorization reuses it and writes into the same L buffer
//! when only the values change (weights, time step); solves are in place on an n×3 right side.
//!
//! Solves walk L in compressed columns for the three coordinates at once (`triangular.rs`): a
//! simplicial factor is already stored so; a supernodal one is compacted in place, after each
//! numeric factorization, into compressed columns without its zero padding. The automatic layout is
//! supernodal: it factors faster (dense blocks; the bunny's springs 34 against 61 ms, strain +
//! bending 0.35 s faster), and with the solves on the compacted columns the layout no longer changes the
//! solve. The compaction costs one pass over L per factorization.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

use super::triangular::{LowerColumns, solve_llt};

/// Which factorization layout to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Factorization {
    /// Supernodal, ordered by nested dissection for dense patterns (two rings, tetrahedra) and
    /// by AMD otherwise.
    #[default]
    Auto,
    /// Column-by-column: slower to factor, often faster to solve on small, sparse systems.
    Simplicial,
    /// Dense supernodal blocks: fastest to factor.
    Supernodal,
}

/// Why a factorization failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FactorError {
    /// The matrix is not positive definite (a pivot ≤ 0 at this permuted column).
    #[error("the global matrix is not positive definite (pivot {0})")]
    NotPositiveDefinite(usize),
    /// faer could not allocate or the sizes overflow.
    #[error("the sparse factorization failed: {0}")]
    Other(String),
}

/// A symmetric positive definite sparse matrix's Cholesky factor L Lᵀ = P A Pᵀ.
pub(crate) struct SparseCholesky {
    n: usize,
    // u32 indices: the solve is memory-bound, and 4-byte indices cut its traffic by a quarter.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    symbolic: SymbolicCholesky<u32>,
    l_values: Vec<f64>,
    factored: bool,
    /// A supernodal L in compressed columns, for the solves (see the module doc); empty for a
    /// simplicial factor, which is stored so already.
    columns: SolveColumns,
    /// Row i of P b is b[forward[i]].
    forward: Vec<u32>,
}

/// A supernodal L (lower triangle, diagonal first in each column) in compressed sparse columns,
/// in the factor's permuted order. Entries that are exactly zero after a factorization (the
/// supernodes' padding: 13 % of the bunny's two-ring factor) are left out, so solves do not read
/// them. The values are compacted in place at the front of the supernodal buffer after each
/// factorization (an entry only ever moves forward), so the factor is stored once: a separate
/// copy took 12 more bytes per entry (and up to twice that while it grew), 0.3 GB of the 1.9 GB
/// a 556k-vertex springs setup peaked at. faer zeroes that buffer before each numeric
/// factorization, so the compaction leaves nothing behind for the next one.
#[derive(Default)]
struct SolveColumns {
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    /// How many values lead the supernodal buffer (= `row_idx.len()`).
    len: usize,
}

impl SolveColumns {
    /// Compacts a new supernodal factor's non-zero entries to the front of `l_values`, recording
    /// their rows: column j of supernode s holds the diagonal block's rows j.. and then the rows
    /// below the block (the diagonal always: it is positive).
    fn compact(
        &mut self,
        s: &faer::sparse::linalg::cholesky::supernodal::SymbolicSupernodalCholesky<u32>,
        l_values: &mut [f64],
    ) {
        self.col_ptr.clear();
        self.row_idx.clear();
        // The structural count, an upper bound, reserved once: growing by doubling held up to
        // twice the entries, and their copy during a reallocation.
        let structural: usize = (0..s.n_supernodes())
            .map(|k| {
                let width = (s.supernode_end()[k] - s.supernode_begin()[k]) as usize;
                let below = (s.col_ptr_for_row_idx()[k + 1] - s.col_ptr_for_row_idx()[k]) as usize;
                width * (width + 1) / 2 + width * below
            })
            .sum();
        self.row_idx.reserve_exact(structural);
        self.col_ptr.reserve_exact(s.nrows() + 1);
        self.col_ptr.push(0);
        let mut write = 0;
        for k in 0..s.n_supernodes() {
            let (first, end) = (s.supernode_begin()[k] as usize, s.supernode_end()[k] as usize);
            let width = end - first;
            let below = &s.row_idx()[s.col_ptr_for_row_idx()[k] as usize..s.col_ptr_for_row_idx()[k + 1] as usize];
            let ld = width + below.len();
            let base = s.col_ptr_for_val()[k] as usize;
            for j in 0..width {
                let rows = (first + j..first + width).map(|r| r as u32).chain(below.iter().copied());
                for (i, r) in rows.enumerate() {
                    // Reads move forward by at least one entry per kept entry: read ≥ write.
                    let v = l_values[base + j * ld + j + i];
                    if v != 0.0 || i == 0 {
                        l_values[write] = v;
                        self.row_idx.push(r);
                        write += 1;
                    }
                }
                self.col_ptr.push(self.row_idx.len() as u32);
            }
        }
        self.len = write;
    }
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.n)
            .field("nnz_a", &self.row_idx.len())
            .field("nnz_l", &self.l_values.len())
            .field("supernodal", &self.is_supernodal())
            .finish()
    }
}

/// `Auto` orders by nested dissection when the lower triangle of A has more than this many
/// entries per column (a triangle mesh's one ring has about 4, its two rings about 10, a tet
/// mesh's one ring about 8)...
const ND_MIN_ENTRIES_PER_COLUMN: usize = 6;

/// ...and the system has at least this many vertices (below, AMD is as good and cheaper).
const ND_MIN_VERTICES: usize = 1000;

/// faer's own solve (the tests' reference; the solver's is `triangular.rs`), sequential: on
/// small machines faer's parallel solve was measured slower (stack-notes §1).
#[cfg(test)]
const SOLVE_PAR: Par = Par::Seq;

impl SparseCholesky {
    /// Symbolic analysis of an n×n matrix given by its lower triangle in CSC form (sorted row
    /// indices per column, diagonal included).
    pub fn analyze(n: usize, col_ptr: Vec<u32>, row_idx: Vec<u32>, layout: Factorization) -> Result<Self, FactorError> {
        let analyze_with = |threshold: SupernodalThreshold, ordering: SymmetricOrdering<'_, u32>| {
            let pattern = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(
                pattern,
                Side::Lower,
                ordering,
                CholeskySymbolicParams { supernodal_flop_ratio_threshold: threshold, ..Default::default() },
            )
            .map_err(|e| FactorError::Other(format!("{e:?}")))
        };
        let symbolic = match layout {
            Factorization::Simplicial => analyze_with(SupernodalThreshold::FORCE_SIMPLICIAL, SymmetricOrdering::Amd)?,
            Factorization::Supernodal => analyze_with(SupernodalThreshold::FORCE_SUPERNODAL, SymmetricOrdering::Amd)?,
            Factorization::Auto if n >= ND_MIN_VERTICES && row_idx.len() > ND_MIN_ENTRIES_PER_COLUMN * n => {
                // A dense pattern (2-ring from bending/smoothing, tetrahedra): nested
                // dissection and supernodes (see `ordering.rs`); AMD if METIS fails.
                match super::ordering::nested_dissection(n, &col_ptr, &row_idx) {
                    Some((fwd, inv)) => {
                        let perm = faer::perm::PermRef::new_checked(&fwd, &inv, n);
                        analyze_with(SupernodalThreshold::FORCE_SUPERNODAL, SymmetricOrdering::Custom(perm))?
                    }
                    None => analyze_with(SupernodalThreshold::FORCE_SUPERNODAL, SymmetricOrdering::Amd)?,
                }
            }
            // A sparse pattern (springs, strain, one-rings): AMD. Supernodal in every case: it
            // factors faster (the bunny's springs: 34 against 61 ms), and the solves read the
            // compacted columns either way.
            Factorization::Auto => analyze_with(SupernodalThreshold::FORCE_SUPERNODAL, SymmetricOrdering::Amd)?,
        };
        let forward = match symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..n as u32).collect(),
        };
        Ok(SparseCholesky {
            // u32 positions suffice: faer's u32 symbolic factor already indexes its values so.
            columns: SolveColumns::default(),
            forward,
            n,
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            symbolic,
            factored: false,
        })
    }

    /// Number of stored values of the lower triangle of A (the pattern's nnz).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    /// Stored values of L (supernodal storage includes padding).
    pub fn nnz_l(&self) -> usize {
        self.l_values.len()
    }

    /// Whether faer chose (or was told) the supernodal layout.
    pub fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// Numeric factorization of the matrix with this pattern and `values` (one per stored
    /// entry, in CSC order), into the existing L buffer.
    pub fn factorize(&mut self, values: &[f64]) -> Result<(), FactorError> {
        self.factored = false;
        let pattern = SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::<u32, f64>::new(pattern, values);
        // faer's scratch lives for the factorization only (67 MB at 556k springs): it is gone
        // before the compacted columns' row indices are allocated.
        let mut mem =
            MemBuffer::try_new(self.symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()))
                .map_err(|e| FactorError::Other(format!("{e:?}")))?;
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| match e {
                LltError::NonPositivePivot { index } => FactorError::NotPositiveDefinite(index),
            })?;
        drop(mem);
        if let SymbolicCholeskyRaw::Supernodal(s) = self.symbolic.raw() {
            self.columns.compact(s, &mut self.l_values);
        }
        self.factored = true;
        Ok(())
    }

    /// The fill-reducing permutation: row i of P b is b[`permutation()[i]`].
    pub fn permutation(&self) -> &[u32] {
        &self.forward
    }

    /// Solves L Lᵀ y = x in place for a right-hand side already in the factor's permuted order
    /// (x = P b, y = P A⁻¹ b), a vertex's coordinates side by side (the fourth lane is solved
    /// too and may be ignored): one pass over L forward and one backward for all of them.
    pub fn solve_permuted_in_place(&mut self, x: &mut [[f64; 4]]) {
        debug_assert!(self.factored && x.len() == self.n);
        let l = match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                LowerColumns { col_ptr: s.col_ptr(), row_idx: s.row_idx(), values: &self.l_values }
            }
            SymbolicCholeskyRaw::Supernodal(_) => {
                let c = &self.columns;
                LowerColumns { col_ptr: &c.col_ptr, row_idx: &c.row_idx, values: &self.l_values[..c.len] }
            }
        };
        solve_llt(l, x);
    }

    /// Solves A X = B in place for B given column-major as `rhs` (n×k, k = rhs.len() / n,
    /// k ≤ 4): X = Pᵀ L⁻ᵀ L⁻¹ P B.
    #[cfg(test)]
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        let n = self.n;
        let k = rhs.len() / n.max(1);
        assert!(k <= 4 && k * n == rhs.len());
        let mut x: Vec<[f64; 4]> = self
            .forward
            .iter()
            .map(|&i| std::array::from_fn(|c| if c < k { rhs[c * n + i as usize] } else { 0.0 }))
            .collect();
        self.solve_permuted_in_place(&mut x);
        for (xi, &i) in x.iter().zip(&self.forward) {
            for c in 0..k {
                rhs[c * n + i as usize] = xi[c];
            }
        }
    }

    /// [`SparseCholesky::solve_in_place`] with faer's own factorization of `values` (into a
    /// fresh buffer: the solves' one is compacted) and its solve (the tests' reference).
    #[cfg(test)]
    fn solve_with_faer(&mut self, values: &[f64], rhs: &mut [f64]) {
        use faer::sparse::linalg::cholesky::LltRef;
        use faer::{Conj, MatMut};
        let mut l = vec![0.0; self.symbolic.len_val()];
        let mut mem = MemBuffer::new(
            self.symbolic
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
                .or(self.symbolic.solve_in_place_scratch::<f64>(3, SOLVE_PAR)),
        );
        let pattern = SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::<u32, f64>::new(pattern, values);
        let factored = self.symbolic.factorize_numeric_llt::<f64>(
            &mut l,
            a,
            Side::Lower,
            LltRegularization::default(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        );
        assert!(factored.is_ok(), "faer's reference factorization failed");
        let k = rhs.len() / self.n.max(1);
        let b = MatMut::from_column_major_slice_mut(rhs, self.n, k);
        LltRef::<u32, f64>::new(&self.symbolic, &l).solve_in_place_with_conj(
            Conj::No,
            b,
            SOLVE_PAR,
            MemStack::new(&mut mem),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tridiagonal [2 -1; -1 2 -1; …] plus a diagonal shift.
    fn tridiagonal(n: usize, shift: f64) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
        let (mut cp, mut ri, mut v) = (vec![0], vec![], vec![]);
        for j in 0..n as u32 {
            ri.push(j);
            v.push(2.0 + shift);
            if j + 1 < n as u32 {
                ri.push(j + 1);
                v.push(-1.0);
            }
            cp.push(ri.len() as u32);
        }
        (cp, ri, v)
    }

    #[test]
    fn solves_and_refactors_in_place() {
        for layout in [Factorization::Auto, Factorization::Simplicial, Factorization::Supernodal] {
            let n = 50;
            let (cp, ri, v) = tridiagonal(n, 0.0);
            let mut chol = SparseCholesky::analyze(n, cp, ri, layout).unwrap();
            chol.factorize(&v).unwrap();
            // A · 1 = [1, 0, …, 0, 1]
            let mut b = vec![0.0; 3 * n];
            for c in 0..3 {
                b[c * n] = 1.0;
                b[c * n + n - 1] = 1.0;
            }
            chol.solve_in_place(&mut b);
            assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-10), "{layout:?}");
            // Refactor with a shifted diagonal: A' · 1 = previous + shift.
            let (_, _, v2) = tridiagonal(n, 1.0);
            chol.factorize(&v2).unwrap();
            let mut b: Vec<f64> = (0..3 * n).map(|i| if i % n == 0 || i % n == n - 1 { 2.0 } else { 1.0 }).collect();
            chol.solve_in_place(&mut b);
            assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-10), "{layout:?} refactor");
        }
    }

    /// A random sparse SPD matrix coupling each node of a √n × √n grid to a two-ring-like
    /// neighbourhood (multi-column supernodes in both layouts); lower triangle in CSC.
    fn mesh_like(n: usize, seed: u64) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
        let mut state = seed;
        let mut random = move || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let side = (n as f64).sqrt().ceil() as usize;
        let (mut cp, mut ri, mut v) = (vec![0u32], vec![], vec![]);
        for j in 0..n {
            let (x, y) = (j % side, j / side);
            let mut rows = vec![j];
            for (dx, dy) in [(1, 0), (2, 0), (0, 1), (1, 1), (0, 2), (2, 1), (1, 2)] {
                let i = (y + dy) * side + x + dx;
                if x + dx < side && i < n {
                    rows.push(i);
                }
            }
            rows.sort_unstable();
            for i in rows {
                ri.push(i as u32);
                v.push(if i == j { 20.0 + random() } else { -random() });
            }
            cp.push(ri.len() as u32);
        }
        (cp, ri, v)
    }

    #[test]
    fn the_column_solves_equal_faers_on_every_layout() {
        for layout in [Factorization::Supernodal, Factorization::Auto, Factorization::Simplicial] {
            for n in [1, 2, 7, 300, 3000] {
                let (cp, ri, v) = mesh_like(n, n as u64);
                let mut chol = SparseCholesky::analyze(n, cp, ri, layout).unwrap();
                if n >= 300 {
                    assert_eq!(chol.is_supernodal(), layout != Factorization::Simplicial, "{layout:?} n={n}");
                }
                for round in 0..2 {
                    // The second round refactors with other values into the same buffers.
                    let values: Vec<f64> = v.iter().map(|x| x * (1.0 + round as f64)).collect();
                    chol.factorize(&values).unwrap();
                    let copied = if chol.is_supernodal() { n + 1 } else { 0 };
                    assert_eq!(chol.columns.col_ptr.len(), copied, "{layout:?} n={n}: the column copy");
                    for k in 1..=3 {
                        let b: Vec<f64> = (0..k * n).map(|i| (i as f64 * 0.37).sin() + (i % 5) as f64).collect();
                        let mut reference = b.clone();
                        chol.solve_with_faer(&values, &mut reference);
                        let mut x = b.clone();
                        chol.solve_in_place(&mut x);
                        for (i, (a, r)) in x.iter().zip(&reference).enumerate() {
                            assert!(
                                (a - r).abs() <= 1e-12 * (1.0 + r.abs()),
                                "{layout:?} n={n} k={k} entry {i}: {a} vs {r}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The global step solves x, y and z in one pass over the factor: the same numbers as three
    /// single-column solves, and A x = b (every layout; `Auto` orders this two-ring-like pattern
    /// by nested dissection).
    #[test]
    fn the_three_column_solve_equals_three_single_solves() {
        let n = 3000;
        let (cp, ri, v) = mesh_like(n, 7);
        assert!(ri.len() > ND_MIN_ENTRIES_PER_COLUMN * n, "the pattern takes the nested-dissection path");
        for layout in [Factorization::Auto, Factorization::Simplicial, Factorization::Supernodal] {
            let mut chol = SparseCholesky::analyze(n, cp.clone(), ri.clone(), layout).unwrap();
            chol.factorize(&v).unwrap();
            let b: Vec<f64> = (0..3 * n).map(|i| (i as f64 * 0.11).cos() * 3.0 + (i % 7) as f64).collect();
            let mut together = b.clone();
            chol.solve_in_place(&mut together);
            for c in 0..3 {
                let mut single = b[c * n..(c + 1) * n].to_vec();
                chol.solve_in_place(&mut single);
                for (a, r) in together[c * n..(c + 1) * n].iter().zip(&single) {
                    assert!((a - r).abs() <= 1e-12 * (1.0 + r.abs()), "{layout:?} column {c}: {a} vs {r}");
                }
                // A x = b, A given by its lower triangle.
                let x = &together[c * n..(c + 1) * n];
                let mut ax = vec![0.0; n];
                for j in 0..n {
                    for k in cp[j] as usize..cp[j + 1] as usize {
                        let i = ri[k] as usize;
                        ax[i] += v[k] * x[j];
                        if i != j {
                            ax[j] += v[k] * x[i];
                        }
                    }
                }
                for (lhs, rhs) in ax.iter().zip(&b[c * n..(c + 1) * n]) {
                    assert!((lhs - rhs).abs() <= 1e-10 * (1.0 + rhs.abs()), "{layout:?} residual {lhs} vs {rhs}");
                }
            }
        }
    }

    #[test]
    fn singular_matrix_is_an_error() {
        // The 1-D Laplacian without shift or boundary terms: constants are in its kernel.
        let n = 10;
        let (cp, ri, mut v) = tridiagonal(n, 0.0);
        v[0] = 1.0;
        let last = v.len() - 1;
        v[last] = 1.0;
        let mut chol = SparseCholesky::analyze(n, cp, ri, Factorization::Auto).unwrap();
        assert!(matches!(chol.factorize(&v), Err(FactorError::NotPositiveDefinite(_))));
    }
}
