//! L-BFGS with the global matrix as initial Hessian (Liu, Bouaziz, Kavan, "Quasi-Newton Methods
//! for Real-Time Simulation of Hyperelastic Materials", ACM TOG 36(3), 2017, Algorithm 1).
//!
//! E(x) = Σ_i w_i ‖C_i x − p_i(x)‖² (plus Σ μ ‖x − s‖² in dynamic mode) has the gradient
//! ∇E = 2 (A x − b(x)), A = Σ w_i C_iᵀC_i (+ diag μ), b(x) = Σ w_i C_iᵀ p_i(x) (+ μ s): the
//! projections' own variation drops out because each p_i is a closest point. The plain
//! local-global step x ↦ A⁻¹ b(x) = x − A⁻¹ (A x − b) is therefore a gradient step
//! preconditioned by A; L-BFGS replaces A⁻¹ by the inverse-Hessian estimate H_k that the two-loop
//! recursion (Nocedal & Wright, Algorithm 7.4) builds from the last m pairs
//! s_j = x_{j+1} − x_j, y_j = g_{j+1} − g_j, with H_0 = A⁻¹ (one prefactored solve):
//!
//!   d_k = −H_k g_k,   g = A x − b (half the gradient).
//!
//! Without history d_k is the plain step exactly. The caller keeps the energy guarantee: it
//! accepts x_k + d_k when it meets the Armijo condition E(x_k + d) ≤ E(x_k) + 2 c₁ gᵀd, and
//! otherwise takes the plain step and [`Lbfgs::reset`]s.
//!
//! Vectors live in the factor's permuted order, a vertex's x, y, z side by side (the fourth lane
//! stays 0 throughout, and is summed with the others so that loops vectorize), so H_0 is one
//! in-place solve and nothing is permuted per iteration.

/// Pairs whose curvature yᵀs is below this fraction of ‖y‖ ‖s‖ are not kept: H_k stays positive
/// definite only with yᵀs > 0, and E is not convex.
const CURVATURE_CUTOFF: f64 = 1e-10;

use rayon::prelude::*;

/// The last m pairs (s_j, y_j) and the previous x and g. Buffers are allocated once per problem
/// size and reused.
#[derive(Debug, Default)]
pub(crate) struct Lbfgs {
    memory: usize,
    prev_x: Vec<[f64; 4]>,
    prev_g: Vec<[f64; 4]>,
    has_prev: bool,
    /// Ring buffers of s and y with 1 / yᵀs, `len` of them valid, the oldest at `start`.
    s: Vec<Vec<[f64; 4]>>,
    y: Vec<Vec<[f64; 4]>>,
    rho: Vec<f64>,
    alpha: Vec<f64>,
    len: usize,
    start: usize,
}

impl Lbfgs {
    /// Sizes the buffers for `n` solved vertices and m = `memory` pairs (≥ 1); keeps them when
    /// nothing changed, and forgets the history otherwise.
    pub(crate) fn resize(&mut self, n: usize, memory: usize) {
        if self.memory == memory && self.prev_x.len() == n {
            return;
        }
        self.memory = memory;
        self.prev_x = vec![[0.0; 4]; n];
        self.prev_g = vec![[0.0; 4]; n];
        self.s = vec![vec![[0.0; 4]; n]; memory];
        self.y = vec![vec![[0.0; 4]; n]; memory];
        self.rho = vec![0.0; memory];
        self.alpha = vec![0.0; memory];
        self.reset();
    }

    /// Forgets every previous iterate (after a rejected step, or when the map changed).
    pub(crate) fn reset(&mut self) {
        self.has_prev = false;
        self.len = 0;
        self.start = 0;
    }

    /// Whether the next direction uses history (otherwise it is the plain step).
    #[cfg(test)]
    pub(crate) fn has_history(&self) -> bool {
        self.len > 0
    }

    /// Records the iterate x with half-gradient g (keeping the pair with the previous one when
    /// its curvature is positive) and sets `r` = g. Unless `plain`, it then runs the first loop
    /// of the two-loop recursion on r and returns whether the history was used; the caller then
    /// applies H_0 (solves with A) and, when it was, calls [`Lbfgs::second_loop`]. The
    /// direction is −r. A `plain` step (r = H_0 g, the local-global step) keeps the history.
    pub(crate) fn first_loop(&mut self, x: &[[f64; 4]], g: &[[f64; 4]], r: &mut [[f64; 4]], plain: bool) -> bool {
        debug_assert!(x.len() == self.prev_x.len() && g.len() == x.len() && r.len() == x.len());
        if self.has_prev && self.memory > 0 {
            let slot = (self.start + self.len) % self.memory;
            let (s, y) = (&mut self.s[slot], &mut self.y[slot]);
            // s, y and their products yᵀs, yᵀy, sᵀs in one pass.
            let [mut ys, mut yy, mut ss] = [0.0; 3];
            for i in 0..x.len() {
                for k in 0..4 {
                    let (si, yi) = (x[i][k] - self.prev_x[i][k], g[i][k] - self.prev_g[i][k]);
                    s[i][k] = si;
                    y[i][k] = yi;
                    ys += yi * si;
                    yy += yi * yi;
                    ss += si * si;
                }
            }
            let full = self.len == self.memory;
            if ys.is_finite() && ys > CURVATURE_CUTOFF * (yy * ss).sqrt() {
                self.rho[slot] = 1.0 / ys;
                if full {
                    self.start = (self.start + 1) % self.memory;
                } else {
                    self.len += 1;
                }
            } else if full {
                // The slot held the oldest pair, now overwritten: drop it.
                self.start = (self.start + 1) % self.memory;
                self.len -= 1;
            }
        }
        self.prev_x.copy_from_slice(x);
        self.prev_g.copy_from_slice(g);
        self.has_prev = true;
        r.copy_from_slice(g);
        if plain || self.len == 0 {
            return false;
        }
        // Newest to oldest: α_j = ρ_j s_jᵀr, r −= α_j y_j; each update also forms the next
        // pair's s·r, so r is read once per pair.
        let slot = |j: usize| (self.start + j) % self.memory.max(1);
        let mut sr = match self.len {
            0 => 0.0,
            len => dot(&self.s[slot(len - 1)], r),
        };
        for j in (0..self.len).rev() {
            let a = self.rho[slot(j)] * sr;
            self.alpha[slot(j)] = a;
            let next = (j > 0).then(|| self.s[slot(j - 1)].as_slice());
            sr = axpy_dot(-a, &self.y[slot(j)], r, next);
        }
        true
    }

    /// The second loop, on r = H_0 (first loop's output): r becomes H_k g. Oldest to newest:
    /// β_j = ρ_j y_jᵀr, r += (α_j − β_j) s_j, fused like the first loop.
    pub(crate) fn second_loop(&self, r: &mut [[f64; 4]]) {
        let slot = |j: usize| (self.start + j) % self.memory.max(1);
        let mut yr = match self.len {
            0 => 0.0,
            _ => dot(&self.y[slot(0)], r),
        };
        for j in 0..self.len {
            let b = self.rho[slot(j)] * yr;
            let next = (j + 1 < self.len).then(|| self.y[slot(j + 1)].as_slice());
            yr = axpy_dot(self.alpha[slot(j)] - b, &self.s[slot(j)], r, next);
        }
    }
}

/// Points per parallel task in the vector operations, which also fixes their summation order
/// whatever the thread count (1 and 2 threads give the same bits).
const CHUNK: usize = 1 << 14;

/// Σ_i a_i · b_i. All four lanes are summed (the fourth is 0 in every vector here) with two
/// independent accumulators, so that the loop vectorizes and is not one chain of additions.
pub(crate) fn dot(a: &[[f64; 4]], b: &[[f64; 4]]) -> f64 {
    let chunk_dot = |(a, b): (&[[f64; 4]], &[[f64; 4]])| {
        let mut acc = [[0.0; 4]; 2];
        for (x, y) in a.chunks(2).zip(b.chunks(2)) {
            for (i, (x, y)) in x.iter().zip(y).enumerate() {
                for k in 0..4 {
                    acc[i][k] += x[k] * y[k];
                }
            }
        }
        (0..4).map(|k| acc[0][k] + acc[1][k]).sum::<f64>()
    };
    if a.len() <= CHUNK {
        return chunk_dot((a, b));
    }
    let partial: Vec<f64> = a.par_chunks(CHUNK).zip(b.par_chunks(CHUNK)).map(chunk_dot).collect();
    partial.iter().sum()
}

/// y += a x, returning zᵀy (the updated y) when z is given, else 0: one pass over y for both.
fn axpy_dot(a: f64, x: &[[f64; 4]], y: &mut [[f64; 4]], z: Option<&[[f64; 4]]>) -> f64 {
    if y.len() <= CHUNK {
        return axpy_dot_serial(a, x, y, z);
    }
    let partial: Vec<f64> = y
        .par_chunks_mut(CHUNK)
        .zip(x.par_chunks(CHUNK))
        .enumerate()
        .map(|(c, (y, x))| {
            let len = y.len();
            axpy_dot_serial(a, x, y, z.map(|z| &z[c * CHUNK..c * CHUNK + len]))
        })
        .collect();
    partial.iter().sum()
}

/// [`axpy_dot`] on one chunk.
fn axpy_dot_serial(a: f64, x: &[[f64; 4]], y: &mut [[f64; 4]], z: Option<&[[f64; 4]]>) -> f64 {
    for (yi, xi) in y.iter_mut().zip(x) {
        for k in 0..4 {
            yi[k] += a * xi[k];
        }
    }
    z.map_or(0.0, |z| dot(y, z))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a convex quadratic ½ xᵀ Q x − cᵀx with exact line searches, L-BFGS with a memory at
    /// least the dimension finds the minimum in at most dimension + 1 steps (it is conjugate
    /// gradients there), while gradient steps with the same H_0 crawl.
    #[test]
    fn minimizes_a_quadratic_far_faster_than_gradient_steps() {
        // Two "vertices" = 6 unknowns; Q diagonal with condition number 100.
        let q = [[1.0, 3.0, 10.0, 0.0], [30.0, 60.0, 100.0, 0.0]];
        let c = [[1.0, -2.0, 0.5, 0.0], [2.0, 1.0, -1.0, 0.0]];
        let grad = |x: &[[f64; 4]]| -> Vec<[f64; 4]> {
            (0..2)
                .map(|i| [q[i][0] * x[i][0] - c[i][0], q[i][1] * x[i][1] - c[i][1], q[i][2] * x[i][2] - c[i][2], 0.0])
                .collect()
        };
        let mut lbfgs = Lbfgs::default();
        lbfgs.resize(2, 6);
        let mut x = vec![[0.0; 4]; 2];
        let mut r = vec![[0.0; 4]; 2];
        for _ in 0..40 {
            let g = grad(&x);
            if dot(&g, &g).sqrt() < 1e-12 {
                break;
            }
            lbfgs.first_loop(&x, &g, &mut r, false);
            // H_0 = 1/100 I, the plain step's scale.
            r.iter_mut().for_each(|v| v.iter_mut().for_each(|c| *c /= 100.0));
            lbfgs.second_loop(&mut r);
            // Exact line search along d = −r on the quadratic: t = gᵀr / rᵀQr.
            let qr: Vec<[f64; 4]> =
                (0..2).map(|i| [q[i][0] * r[i][0], q[i][1] * r[i][1], q[i][2] * r[i][2], 0.0]).collect();
            let t = dot(&g, &r) / dot(&r, &qr);
            axpy_dot(-t, &r, &mut x, None);
        }
        let g = grad(&x);
        assert!(dot(&g, &g).sqrt() < 1e-10, "L-BFGS gradient {}", dot(&g, &g).sqrt());
        let mut plain = vec![[0.0; 4]; 2];
        for _ in 0..40 {
            let g = grad(&plain);
            axpy_dot(-1.0 / 100.0, &g, &mut plain, None);
        }
        let g = grad(&plain);
        assert!(dot(&g, &g).sqrt() > 1e-2, "gradient steps {}", dot(&g, &g).sqrt());
    }

    #[test]
    fn without_history_the_direction_is_h0_g_and_reset_forgets() {
        let mut lbfgs = Lbfgs::default();
        lbfgs.resize(1, 3);
        let g = [[1.0, 2.0, 3.0, 0.0]];
        let mut r = [[0.0; 4]];
        lbfgs.first_loop(&[[0.0; 4]], &g, &mut r, false);
        assert!(!lbfgs.has_history());
        lbfgs.second_loop(&mut r);
        assert_eq!(r, g);
        lbfgs.first_loop(&[[1.0, 0.0, 0.0, 0.0]], &[[2.0, 2.0, 3.0, 0.0]], &mut r, false);
        assert!(lbfgs.has_history());
        lbfgs.reset();
        lbfgs.first_loop(&[[0.0; 4]], &g, &mut r, false);
        assert!(!lbfgs.has_history());
    }
}
