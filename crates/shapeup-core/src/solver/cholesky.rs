//! Sparse Cholesky factorization of the global matrix: the only file that names faer.
//!
//! The symbolic analysis (fill-reducing AMD ordering, elimination tree, supernodes) runs once
//! per sparsity pattern; the numeric factorization reuses it and writes into the same L buffer
//! when only the values change (weights, time step); solves are in place on an n×3 right side.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// Which factorization layout to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Factorization {
    /// Simplicial when the factor is sparse (≤ 64 entries per column), else supernodal.
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
    mem: MemBuffer,
    factored: bool,
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

/// `Auto` keeps the simplicial layout while nnz(L) ≤ this many entries per column.
const SIMPLICIAL_MAX_FILL: usize = 64;

/// The per-iteration solve is sequential: on small machines faer's parallel solve was measured
/// slower (stack-notes §1), and the local step already uses the cores.
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
            Factorization::Auto => {
                // A sparse factor (springs, strain, iso: 1-ring patterns) solves faster in the
                // simplicial layout; a denser one (2-ring patterns from bending/smoothing)
                // factors 10× faster supernodally. Measured on the bunny: see the README.
                let simplicial = analyze_with(SupernodalThreshold::FORCE_SIMPLICIAL, SymmetricOrdering::Amd)?;
                match simplicial.perm() {
                    Some(perm) if simplicial.len_val() > SIMPLICIAL_MAX_FILL * n.max(1) => {
                        // Reuse the AMD ordering: it is the costliest part of the analysis.
                        let (fwd, inv) = perm.arrays();
                        let perm = faer::perm::PermRef::new_checked(fwd, inv, n);
                        analyze_with(SupernodalThreshold::FORCE_SUPERNODAL, SymmetricOrdering::Custom(perm))?
                    }
                    _ => simplicial,
                }
            }
        };
        let scratch = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(3, SOLVE_PAR));
        let mem = MemBuffer::try_new(scratch).map_err(|e| FactorError::Other(format!("{e:?}")))?;
        Ok(SparseCholesky {
            n,
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            symbolic,
            mem,
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
        self.symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.mem),
                Default::default(),
            )
            .map_err(|e| match e {
                LltError::NonPositivePivot { index } => FactorError::NotPositiveDefinite(index),
            })?;
        self.factored = true;
        Ok(())
    }

    /// Solves A X = B in place for B given column-major as `rhs` (n×k, k = rhs.len() / n).
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) {
        debug_assert!(self.factored);
        let k = rhs.len() / self.n.max(1);
        let b = MatMut::from_column_major_slice_mut(rhs, self.n, k);
        LltRef::<u32, f64>::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            b,
            SOLVE_PAR,
            MemStack::new(&mut self.mem),
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
