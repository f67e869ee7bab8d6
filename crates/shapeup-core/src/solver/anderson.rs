//! Anderson acceleration of the local-global iteration (Peng, Deng, Zhang, Pauly, "Anderson
//! Acceleration for Geometry Optimization and Physics Simulation", SIGGRAPH 2018, Algorithm 2).
//!
//! One local-global iteration is a fixed-point map x ↦ G(x). With the residual f = G(x) − x and
//! the differences ΔG_j = G(x_{j+1}) − G(x_j), ΔF_j = f_{j+1} − f_j of the last m iterations,
//! the accelerated iterate is
//!
//!   x_AA = G(x_k) − Σ_j θ_j ΔG_j,   θ = argmin_θ ‖f_k − Σ_j θ_j ΔF_j‖²
//!
//! (type-II Anderson mixing with full relaxation). The caller keeps the energy guarantee: it
//! accepts x_AA only when its energy is below the last accepted one, and otherwise takes the
//! plain G(x_k) and [`Anderson::reset`]s, as in the paper.

use faer::{Mat, Side};
use glam::DVec3;

/// Relative cutoff of the singular values of the m×m normal matrix ΔFᵀΔF: directions below it
/// are dropped (nearly dependent differences, as near convergence).
const RANK_CUTOFF: f64 = 1e-14;

/// The mixing state: the last m differences and the previous G(x) and f. Buffers are allocated
/// once per problem size and reused.
#[derive(Debug, Default)]
pub(crate) struct Anderson {
    window: usize,
    prev_g: Vec<DVec3>,
    prev_f: Vec<DVec3>,
    has_prev: bool,
    /// Ring buffers of ΔG and ΔF, `len` of them valid, the oldest at `start`.
    dg: Vec<Vec<DVec3>>,
    df: Vec<Vec<DVec3>>,
    len: usize,
    start: usize,
    f: Vec<DVec3>,
}

impl Anderson {
    /// Sizes the buffers for `n` points and a window of m = `window` differences (≥ 1); keeps
    /// them when nothing changed, and forgets the history otherwise.
    pub(crate) fn resize(&mut self, n: usize, window: usize) {
        if self.window == window && self.f.len() == n {
            return;
        }
        self.window = window;
        self.prev_g = vec![DVec3::ZERO; n];
        self.prev_f = vec![DVec3::ZERO; n];
        self.f = vec![DVec3::ZERO; n];
        self.dg = vec![vec![DVec3::ZERO; n]; window];
        self.df = vec![vec![DVec3::ZERO; n]; window];
        self.reset();
    }

    /// Forgets every previous iterate (after a rejected step, or when the map changed: moved
    /// targets, new weights, another starting point).
    pub(crate) fn reset(&mut self) {
        self.has_prev = false;
        self.len = 0;
        self.start = 0;
    }

    /// Records the iteration x ↦ g = G(x) and writes the accelerated iterate to `out` (g itself
    /// while there is no history). Returns whether `out` differs from g.
    pub(crate) fn mix(&mut self, x: &[DVec3], g: &[DVec3], out: &mut [DVec3]) -> bool {
        debug_assert!(x.len() == self.f.len() && g.len() == self.f.len() && out.len() == self.f.len());
        for ((f, &gi), &xi) in self.f.iter_mut().zip(g).zip(x) {
            *f = gi - xi;
        }
        if self.has_prev && self.window > 0 {
            // Slot for the newest difference: the oldest one's when the ring is full.
            let slot = (self.start + self.len) % self.window;
            for (((dg, df), (&gi, &fi)), (&pg, &pf)) in self.dg[slot]
                .iter_mut()
                .zip(self.df[slot].iter_mut())
                .zip(g.iter().zip(&self.f))
                .zip(self.prev_g.iter().zip(&self.prev_f))
            {
                *dg = gi - pg;
                *df = fi - pf;
            }
            if self.len < self.window {
                self.len += 1;
            } else {
                self.start = (self.start + 1) % self.window;
            }
        }
        self.prev_g.copy_from_slice(g);
        self.prev_f.copy_from_slice(&self.f);
        self.has_prev = true;
        out.copy_from_slice(g);
        let Some(theta) = self.coefficients() else { return false };
        for (j, &t) in theta.iter().enumerate() {
            let dg = &self.dg[(self.start + j) % self.window];
            out.iter_mut().zip(dg).for_each(|(o, &d)| *o -= t * d);
        }
        true
    }

    /// θ = argmin ‖f − ΔF θ‖², by the pseudo-inverse of the m×m normal equations (m is small),
    /// from their eigendecomposition.
    fn coefficients(&self) -> Option<Vec<f64>> {
        let m = self.len;
        if m == 0 {
            return None;
        }
        let column = |j: usize| &self.df[(self.start + j) % self.window];
        let mut normal = Mat::<f64>::zeros(m, m);
        let rhs: Vec<f64> = (0..m).map(|i| dot(column(i), &self.f)).collect();
        for i in 0..m {
            for j in 0..=i {
                let d = dot(column(i), column(j));
                normal[(i, j)] = d;
                normal[(j, i)] = d;
            }
        }
        let scale = (0..m).map(|i| normal[(i, i)]).fold(0.0, f64::max);
        if !(scale > 0.0 && scale.is_finite()) {
            return None;
        }
        let eigen = normal.self_adjoint_eigen(Side::Lower).ok()?;
        let (u, lambda) = (eigen.U(), eigen.S().column_vector());
        let mut theta = vec![0.0; m];
        for k in 0..m {
            if lambda[k] > RANK_CUTOFF * scale {
                let coefficient = (0..m).map(|i| u[(i, k)] * rhs[i]).sum::<f64>() / lambda[k];
                theta.iter_mut().enumerate().for_each(|(i, t)| *t += coefficient * u[(i, k)]);
            }
        }
        theta.iter().all(|t| t.is_finite()).then_some(theta)
    }
}

/// Σ_i a_i · b_i over points.
fn dot(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3Swizzles;

    /// On an affine map G(x) = A x + c with a contraction A, Anderson mixing with a window at
    /// least the dimension finds the fixed point in dimension + 1 steps (it is GMRES there),
    /// while the plain iteration is still far.
    #[test]
    fn solves_an_affine_fixed_point_in_few_steps() {
        // Three points = 9 unknowns; A couples them and contracts by 0.95 at most.
        let g = |x: &[DVec3]| -> Vec<DVec3> {
            let n = x.len();
            (0..n)
                .map(|i| {
                    let left = x[(i + n - 1) % n];
                    let right = x[(i + 1) % n];
                    0.5 * x[i] + 0.2 * left + 0.25 * right.zyx() + DVec3::new(1.0, -2.0, 0.5)
                })
                .collect()
        };
        let mut anderson = Anderson::default();
        anderson.resize(3, 9);
        let mut x = vec![DVec3::ZERO; 3];
        let mut out = vec![DVec3::ZERO; 3];
        for _ in 0..11 {
            let gx = g(&x);
            anderson.mix(&x, &gx, &mut out);
            x.clone_from(&out);
        }
        let residual: f64 = g(&x).iter().zip(&x).map(|(a, b)| (*a - *b).length()).sum();
        assert!(residual < 1e-9, "accelerated residual {residual}");
        let mut plain = vec![DVec3::ZERO; 3];
        for _ in 0..11 {
            plain = g(&plain);
        }
        let plain_residual: f64 = g(&plain).iter().zip(&plain).map(|(a, b)| (*a - *b).length()).sum();
        assert!(plain_residual > 1e-3, "plain residual {plain_residual}");
    }

    #[test]
    fn without_history_the_iterate_is_the_plain_one_and_reset_forgets() {
        let mut anderson = Anderson::default();
        anderson.resize(2, 5);
        let x = vec![DVec3::ZERO; 2];
        let g = vec![DVec3::ONE, DVec3::X];
        let mut out = vec![DVec3::ZERO; 2];
        assert!(!anderson.mix(&x, &g, &mut out));
        assert_eq!(out, g);
        anderson.reset();
        assert!(!anderson.mix(&g, &x, &mut out));
        assert_eq!(out, x);
    }
}
