//! How far a solve's end is from the objective's minimum, estimated by a few Newton–CG
//! iterations: the step δ that solves H δ = −g, with H the objective's true Hessian (not the
//! global matrix A, which Projective Dynamics puts in its place) and g its gradient, by
//! preconditioned conjugate gradients with the prefactored A as preconditioner (Nocedal &
//! Wright, *Numerical Optimization*, 2nd ed., Algorithm 7.1, "CG–Steihaug", stopped at
//! negative curvature). H v is a forward difference of the gradient along v, so no constraint
//! needs a Hessian of its own.
//!
//! Why it is needed: where stiff terms dwarf the inertia, A models the soft modes (a cloth
//! swinging on its pins) with a curvature up to 10⁶ times too high, so each local-global
//! iteration moves them by that fraction of the way, and their gradient is small for the
//! distance they have left: neither the gradient nor the motion of the last iterations tells
//! such a solve from a converged one (math reference, "When a solve stops short"). CG on the
//! true curvature finds those modes in its first iterations (they are the extreme eigenvalues
//! of A⁻¹H), and its iterates grow monotonically in the A-norm (Steihaug 1983), so a few
//! iterations give a lower bound of the remaining step, not an overestimate.

use super::{SolveError, System, global, lbfgs};
use glam::DVec3;

impl System {
    /// The Newton step still left at q, estimated by `iterations` preconditioned CG iterations
    /// on the objective's true Hessian (see the [module docs](self)): per vertex, 0 for the
    /// held ones and those outside the system. Leaves the projections at a point near q (the
    /// next solve projects again).
    ///
    /// # Errors
    /// As [`System::prepare`]; [`SolveError::NonFinite`] for a gradient that is not finite.
    pub fn remaining_step(&mut self, q: &[DVec3], iterations: usize) -> Result<Vec<DVec3>, SolveError> {
        self.check_length(q)?;
        self.prepare()?;
        let mut out = vec![DVec3::ZERO; q.len()];
        let Some(factor) = self.factor.as_ref() else { return Ok(out) };
        let forward = factor.permutation().to_vec();
        let n = self.assembly.num_solved();
        let mut x = vec![[0.0; 4]; n];
        global::gather(&self.assembly, &forward, q, &mut x);
        let mut g0 = vec![[0.0; 4]; n];
        self.gradient_at(q, &mut g0);
        // r = −g − H δ with δ = 0.
        let mut r: Vec<[f64; 4]> = g0.iter().map(|g| [-g[0], -g[1], -g[2], 0.0]).collect();
        let mut z = r.clone();
        self.precondition(&mut z);
        let mut p = z.clone();
        let mut rz = lbfgs::dot(&r, &z);
        let mut delta = vec![[0.0; 4]; n];
        let mut hp = vec![[0.0; 4]; n];
        let mut trial = q.to_vec();
        let mut moved = vec![[0.0; 4]; n];
        let scale = x.iter().flat_map(|c| c[..3].iter()).fold(0.0_f64, |m, c| m.max(c.abs())).max(1e-300);
        for _ in 0..iterations {
            let p_max = p.iter().flat_map(|c| c[..3].iter()).fold(0.0_f64, |m, c| m.max(c.abs()));
            if !(p_max > 0.0 && rz > 0.0) {
                break;
            }
            // H p ≈ (g(q + ε p) − g(q)) / ε, ε p about √ε_mach of the coordinates' size.
            let eps = 1.5e-8 * scale / p_max;
            for ((m, xi), pi) in moved.iter_mut().zip(&x).zip(&p) {
                *m = [xi[0] + eps * pi[0], xi[1] + eps * pi[1], xi[2] + eps * pi[2], 0.0];
            }
            if !global::scatter(&self.assembly, &forward, &moved, &mut trial) {
                return Err(SolveError::NonFinite);
            }
            self.gradient_at(&trial, &mut hp);
            for (h, g) in hp.iter_mut().zip(&g0) {
                for k in 0..3 {
                    h[k] = (h[k] - g[k]) / eps;
                }
            }
            let curvature = lbfgs::dot(&p, &hp);
            if curvature.is_nan() || curvature <= 0.0 {
                // Negative curvature (a buckling mode): δ so far.
                break;
            }
            let alpha = rz / curvature;
            for (((d, ri), pi), hi) in delta.iter_mut().zip(&mut r).zip(&p).zip(&hp) {
                for k in 0..3 {
                    d[k] += alpha * pi[k];
                    ri[k] -= alpha * hi[k];
                }
            }
            z.copy_from_slice(&r);
            self.precondition(&mut z);
            let rz_next = lbfgs::dot(&r, &z);
            let beta = rz_next / rz;
            rz = rz_next;
            for (pi, zi) in p.iter_mut().zip(&z) {
                for k in 0..3 {
                    pi[k] = zi[k] + beta * pi[k];
                }
            }
        }
        // Only the solved vertices are written: the held ones and those outside stay 0.
        if !global::scatter(&self.assembly, &forward, &delta, &mut out) {
            return Err(SolveError::NonFinite);
        }
        Ok(out)
    }

    /// ‖A q − b(q)‖ at any q (half the gradient of E; of the objective in dynamic mode), after
    /// a local step there: what [`SolveReport::residual`](super::SolveReport::residual)
    /// divides, for a reference of the caller's (a scene's rest shape when it starts elsewhere).
    pub fn half_gradient_norm_at(&mut self, q: &[DVec3]) -> f64 {
        let Some(n) = self.factor.as_ref().map(|_| self.assembly.num_solved()) else { return 0.0 };
        let mut g = vec![[0.0; 4]; n];
        self.gradient_at(q, &mut g);
        super::lbfgs::dot(&g, &g).sqrt()
    }

    /// Half the objective's gradient at q ([`System::half_gradient`]) after a local step there.
    fn gradient_at(&mut self, q: &[DVec3], g: &mut [[f64; 4]]) {
        self.project(q);
        global::apply_c(&self.assembly, q, &mut self.cq);
        self.half_gradient(q, g);
    }

    /// z ← A⁻¹ z with the prefactored global matrix.
    fn precondition(&mut self, z: &mut [[f64; 4]]) {
        if let Some(factor) = self.factor.as_mut() {
            factor.solve_permuted_in_place(z);
        }
    }
}
