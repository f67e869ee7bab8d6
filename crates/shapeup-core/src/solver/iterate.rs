//! The three iteration schemes a solve runs: plain local-global, Anderson-accelerated and
//! L-BFGS, with the buffers they keep between solves.

use super::convergence::{Run, timed};
use super::{SolveError, SolveReport, System, global, lbfgs};
use glam::DVec3;
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::time::Instant;

/// Buffers of the accelerated iterations, allocated once per problem size and kept between
/// solves: G(x) (or L-BFGS's trial point) and Anderson's mixed iterate over all n points; x, g
/// and the direction over the solved vertices in the factor's order for L-BFGS.
#[derive(Debug, Default)]
pub(super) struct Scratch {
    plain: Vec<DVec3>,
    mixed: Vec<DVec3>,
    x: Vec<[f64; 4]>,
    pub(super) g: Vec<[f64; 4]>,
    d: Vec<[f64; 4]>,
    /// The search direction a line search halves (materials only).
    dir: Vec<[f64; 4]>,
}

/// Armijo's sufficient-decrease constant c₁ (Nocedal & Wright's usual 1e-4).
const ARMIJO: f64 = 1e-4;

/// Halvings a line search tries before it gives up on a direction (t down to 2⁻⁴⁰).
const MAX_BACKTRACKS: usize = 40;

impl System {
    /// The plain iteration: global step from the last projections, then the local step at the
    /// new q, whose projections give E(q) and feed the next global step. Each scheme returns
    /// whether it ended before its last iteration (the tolerance met, or `after_iteration`
    /// stopped it).
    pub(super) fn iterate_plain(
        &mut self,
        q: &mut [DVec3],
        mut run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<bool, SolveError> {
        for _ in 0..run.iterations {
            timed(&mut report.global_seconds, || self.global_step(q))?;
            timed(&mut report.local_seconds, || self.project(q));
            let energy = self.energy_of_projections(q);
            let objective = energy + self.inertial_energy(q);
            let (converged, stop) = run.record(report, energy, objective, after_iteration)?;
            if converged || stop {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// Anderson-accelerated iteration (see [`super::anderson`]): x_{k+1} is the mixed iterate when its
    /// objective (E, plus the inertial term in dynamic mode) is below x_k's, else the plain
    /// G(x_k), which never raises it; the history restarts after a rejection.
    pub(super) fn iterate_anderson(
        &mut self,
        q: &mut [DVec3],
        scratch: &mut Scratch,
        mut run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<bool, SolveError> {
        let n = q.len();
        self.anderson.resize(n, self.params.anderson_window);
        let (plain, mixed) = (&mut scratch.plain, &mut scratch.mixed);
        plain.resize(n, DVec3::ZERO);
        mixed.resize(n, DVec3::ZERO);
        for _ in 0..run.iterations {
            plain.copy_from_slice(q);
            timed(&mut report.global_seconds, || self.global_step(plain))?;
            let t = Instant::now();
            let is_mixed = self.anderson.mix(q, plain, mixed);
            let (mut energy, mut mixed_objective) = self.evaluate(mixed);
            let accepted_mixed = is_mixed && mixed_objective < run.objective;
            if is_mixed && !accepted_mixed {
                // The plain iterate: E(G(x)) ≤ E(x) by the local-global argument.
                self.anderson.reset();
                report.rejected += 1;
                (energy, mixed_objective) = self.evaluate(plain);
                q.copy_from_slice(plain);
            } else {
                q.copy_from_slice(mixed);
            }
            report.local_seconds += t.elapsed().as_secs_f64();
            let (mut converged, stop) = run.record(report, energy, mixed_objective, after_iteration)?;
            if converged && accepted_mixed {
                // A mixed step can creep along a flat valley by less than the tolerance: only
                // a plain iteration, the one the tolerance is defined on, may end the solve.
                self.anderson.reset();
                converged = false;
            }
            if converged || stop {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// L-BFGS iteration (see [`lbfgs`]): x_{k+1} = x_k + d_k, d_k = −H_k g_k, when it meets the
    /// Armijo condition on the objective (E, plus the inertial term in dynamic mode), else the
    /// plain step x_k − A⁻¹ g_k = G(x_k), which never raises it; the history restarts after a
    /// rejection.
    pub(super) fn iterate_lbfgs(
        &mut self,
        q: &mut [DVec3],
        scratch: &mut Scratch,
        mut run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<bool, SolveError> {
        let solved = self.assembly.num_solved();
        self.lbfgs.resize(solved, self.params.lbfgs_memory);
        let Scratch { plain: trial, x, g, d, dir, .. } = scratch;
        trial.resize(q.len(), DVec3::ZERO);
        for b in [&mut *x, &mut *g, &mut *d, &mut *dir] {
            b.resize(solved, [0.0; 4]);
        }
        // Terms that are not projective (materials): no step is safe without a line search.
        let energy_terms = self.energy_groups.contains(&true);
        // The next iteration is a plain step that confirms a quasi-Newton step's convergence.
        let mut confirm = false;
        for _ in 0..run.iterations {
            let t = Instant::now();
            // g at q: the projections and C q of the energy just evaluated there.
            self.half_gradient(q, g);
            report.start_gradient.get_or_insert_with(|| lbfgs::dot(g, g).sqrt());
            let Some(factor) = self.factor.as_mut() else { return Ok(true) };
            global::gather(&self.assembly, factor.permutation(), q, x);
            let quasi_newton = self.lbfgs.first_loop(x, g, d, confirm);
            factor.solve_permuted_in_place(d);
            if quasi_newton {
                self.lbfgs.second_loop(d);
            }
            // The directional derivative of the objective along −d is −2 gᵀd.
            let slope = -2.0 * lbfgs::dot(g, d);
            let (energy, trial_objective, accepted) = if energy_terms {
                report.global_seconds += t.elapsed().as_secs_f64();
                let mut found = self.line_search(x, d, dir, q, trial, slope, run.objective, report)?;
                if found.is_none() && quasi_newton {
                    // Not a descent direction after all: forget the history, search along −A⁻¹g.
                    self.lbfgs.reset();
                    report.rejected += 1;
                    self.plain_direction(g, d);
                    let slope = -2.0 * lbfgs::dot(g, d);
                    found = self.line_search(x, d, dir, q, trial, slope, run.objective, report)?;
                }
                let Some((energy, objective)) = found else {
                    // No step lowers the objective measurably along −A⁻¹g: a minimum to
                    // round-off, or a stall. The iteration is recorded unchanged and the solve
                    // ends as one that ran out of iterations, so that its residual is measured
                    // and a stall far from the minimum is said (SolveReport::unconverged).
                    let energy = report.energies.last().copied().unwrap_or(report.initial_energy);
                    let objective = run.objective;
                    // The projections and C q at q again, for the residual measured next.
                    self.evaluate(q);
                    run.record(report, energy, objective, after_iteration)?;
                    return Ok(false);
                };
                (energy, objective, true)
            } else {
                self.step_to(x, d, q, trial)?;
                report.global_seconds += t.elapsed().as_secs_f64();
                let t = Instant::now();
                let (mut energy, mut trial_objective) = self.evaluate(trial);
                report.local_seconds += t.elapsed().as_secs_f64();
                let accepted = !quasi_newton || (slope < 0.0 && trial_objective <= run.objective + ARMIJO * slope);
                if !accepted {
                    // The plain iterate x − A⁻¹ g = G(x): E(G(x)) ≤ E(x) by the local-global
                    // argument.
                    self.lbfgs.reset();
                    report.rejected += 1;
                    let t = Instant::now();
                    self.plain_direction(g, d);
                    self.step_to(x, d, q, trial)?;
                    report.global_seconds += t.elapsed().as_secs_f64();
                    let t = Instant::now();
                    (energy, trial_objective) = self.evaluate(trial);
                    report.local_seconds += t.elapsed().as_secs_f64();
                }
                (energy, trial_objective, accepted)
            };
            q.copy_from_slice(trial);
            let (mut converged, stop) = run.record(report, energy, trial_objective, after_iteration)?;
            confirm = converged && accepted && quasi_newton;
            if confirm {
                // As with Anderson, only a plain iteration, the one the tolerance is defined on,
                // may end the solve: the next one is plain. Unlike Anderson's mixing, the
                // history stays valid through a plain step (any step gives a secant pair), so it
                // is kept: a tight tolerance does not restart the Hessian estimate each time.
                converged = false;
            }
            if converged || stop {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// d = A⁻¹ g: the plain local-global step's direction (x − d = G(x)), L-BFGS without
    /// history.
    fn plain_direction(&mut self, g: &[[f64; 4]], d: &mut [[f64; 4]]) {
        d.copy_from_slice(g);
        if let Some(factor) = self.factor.as_mut() {
            factor.solve_permuted_in_place(d);
        }
    }

    /// Backtracking (Armijo) line search for terms that are not projective: `trial` = q moved
    /// to x − t d for the first t in 1, ½, ¼, … (at most [`MAX_BACKTRACKS`] halvings) whose
    /// objective is at most `objective` + c₁ t `slope` (`slope` the objective's derivative
    /// along −d, negative for a descent direction), returning its E and objective; `None`
    /// when no t does (or d is no descent direction). A trial with a NaN or an infinity is
    /// rejected like one that rises. `dir` keeps d; `d` is scratch. Each halving is counted in
    /// `report.rejected`.
    #[allow(clippy::too_many_arguments)]
    fn line_search(
        &mut self,
        x: &[[f64; 4]],
        d: &mut [[f64; 4]],
        dir: &mut [[f64; 4]],
        q: &[DVec3],
        trial: &mut [DVec3],
        slope: f64,
        objective: f64,
        report: &mut SolveReport,
    ) -> Result<Option<(f64, f64)>, SolveError> {
        // A NaN slope is no descent direction either.
        if slope.is_nan() || slope >= 0.0 {
            return Ok(None);
        }
        dir.copy_from_slice(d);
        let mut t = 1.0;
        for _ in 0..=MAX_BACKTRACKS {
            let started = Instant::now();
            for (di, ri) in d.iter_mut().zip(dir.iter()) {
                for k in 0..4 {
                    di[k] = t * ri[k];
                }
            }
            let finite = match self.step_to(x, d, q, trial) {
                Ok(()) => true,
                Err(SolveError::NonFinite) => false,
                Err(e) => return Err(e),
            };
            report.global_seconds += started.elapsed().as_secs_f64();
            if finite {
                let started = Instant::now();
                let (energy, trial_objective) = self.evaluate(trial);
                report.local_seconds += started.elapsed().as_secs_f64();
                if trial_objective.is_finite() && trial_objective <= objective + ARMIJO * t * slope {
                    return Ok(Some((energy, trial_objective)));
                }
            }
            report.rejected += 1;
            t *= 0.5;
        }
        Ok(None)
    }

    /// Half the objective's gradient over the solved vertices, in the factor's order (see
    /// [`lbfgs`]): g = Σ_r w_r c_rᵀ ((C q)_r − P_r) + μ (q − s) = A q − b(q), from the
    /// projections at q and `cq` = C q (both as the last energy evaluation at q left them;
    /// `cq` becomes the residual C q − P).
    pub(super) fn half_gradient(&mut self, q: &[DVec3], g: &mut [[f64; 4]]) {
        let Some(factor) = self.factor.as_ref() else { return };
        self.cq.par_iter_mut().zip(&self.projections).with_min_len(4096).for_each(|(r, p)| *r -= *p);
        match &self.inertia {
            Some(mu) => {
                for (gi, &s) in g.iter_mut().zip(factor.permutation()) {
                    let v = self.assembly.solved[s as usize] as usize;
                    let d = mu[v] * (q[v] - self.inertial_target.get(v).copied().unwrap_or(DVec3::ZERO));
                    *gi = [d.x, d.y, d.z, 0.0];
                }
            }
            None => g.fill([0.0; 4]),
        }
        global::right_hand_side(&self.assembly, &self.rhs_map, &self.cq, g, &mut self.rhs_partials);
        if !self.load_rhs.is_empty() {
            // −½ ∇ of −2 Σ g f·q.
            for (gi, &s) in g.iter_mut().zip(factor.permutation()) {
                let f = self.load_rhs[s as usize];
                gi[0] -= f.x;
                gi[1] -= f.y;
                gi[2] -= f.z;
            }
        }
    }

    /// ‖A q − b(q)‖, the norm of [`System::half_gradient`] at q, from the projections at q and
    /// C q that the last energy evaluation at q left (C q is recomputed after, as it was).
    /// `g` is scratch.
    pub(super) fn half_gradient_norm(&mut self, q: &[DVec3], g: &mut Vec<[f64; 4]>) -> f64 {
        g.resize(self.assembly.num_solved(), [0.0; 4]);
        self.half_gradient(q, g);
        global::apply_c(&self.assembly, q, &mut self.cq);
        lbfgs::dot(g, g).sqrt()
    }

    /// A static solve's relative residual at q, its end, whose energy evaluation at q is the
    /// last (see [`SolveReport::residual`]): ‖A q − b(q)‖ (half the gradient of E) over
    /// `start`, the same norm where the solve began. 0 when the residual is within its
    /// round-off ([`System::gradient_floor`]) or E is at most `floor` (the constraints met to
    /// round-off); unbounded when it started at a minimum (`start` 0) and left it.
    pub(super) fn relative_residual(
        &mut self,
        q: &[DVec3],
        start: f64,
        energy: f64,
        floor: f64,
        g: &mut Vec<[f64; 4]>,
    ) -> f64 {
        let residual = self.half_gradient_norm(q, g);
        if residual <= self.gradient_floor(q) || (0.0..=floor).contains(&energy) {
            0.0
        } else if start > 0.0 {
            residual / start
        } else {
            f64::INFINITY
        }
    }

    /// The local step at q, then E(q) and the objective (E plus the inertial term in dynamic
    /// mode) from its projections: what every accelerated iteration asks of a candidate.
    fn evaluate(&mut self, q: &[DVec3]) -> (f64, f64) {
        self.project(q);
        let energy = self.energy_of_projections(q);
        (energy, energy + self.inertial_energy(q))
    }

    /// `trial` = q with its solved vertices at x − d (factor order) and the held ones on their
    /// points; d is left holding x − d. [`SolveError::NonFinite`] if that holds a NaN or an
    /// infinity.
    fn step_to(&self, x: &[[f64; 4]], d: &mut [[f64; 4]], q: &[DVec3], trial: &mut [DVec3]) -> Result<(), SolveError> {
        for (di, xi) in d.iter_mut().zip(x) {
            for k in 0..3 {
                di[k] = xi[k] - di[k];
            }
        }
        trial.copy_from_slice(q);
        // Without a factor no vertex is solved: only the held ones move.
        if let Some(factor) = self.factor.as_ref()
            && !global::scatter(&self.assembly, factor.permutation(), d, trial)
        {
            return Err(SolveError::NonFinite);
        }
        self.pin_held(trial);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{ConstraintGroup, SolverParams};
    use super::*;
    use crate::constraints::{BuildContext, Params, Position, Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};

    impl System {
        /// ½ ∇ of the objective at q per vertex (0 for vertices outside the system), by the
        /// route L-BFGS takes: a local step at q, then [`System::half_gradient`].
        fn half_gradient_at(&mut self, q: &[DVec3]) -> Vec<DVec3> {
            self.prepare().unwrap();
            self.project(q);
            global::apply_c(&self.assembly, q, &mut self.cq);
            let mut g = vec![[0.0; 4]; self.assembly.num_solved()];
            self.half_gradient(q, &mut g);
            let mut out = vec![DVec3::ZERO; q.len()];
            global::scatter(&self.assembly, self.factor.as_ref().unwrap().permutation(), &g, &mut out);
            out
        }
    }

    /// L-BFGS's gradient, g = A q − b(q), is half the gradient of the objective: checked against
    /// central differences of E (plus the inertial term) on a bumpy sheet with strain, bending
    /// and springs, a hard and a soft handle, in static and dynamic mode.
    #[test]
    fn the_half_gradient_is_half_the_objectives_gradient() {
        let mesh = crate::generate::cloth_grid(6, 5, 1.0, 0.8);
        let positions: Vec<DVec3> =
            mesh.positions.iter().map(|p| *p + DVec3::Y * (0.1 * (3.0 * p.x).sin() * (2.0 * p.z).cos())).collect();
        let rest = RestGeometry::new(positions.clone(), mesh.triangles.clone(), vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        for dynamic in [false, true] {
            let mut system = System::new(positions.len(), SolverParams::default());
            for (kind, g) in [("triangle_strain", 3.0), ("bending", 0.5), ("edge_spring", 2.0)] {
                let built = build_constraints(kind, &ctx, Params::default()).unwrap();
                system.add_group(ConstraintGroup::new(kind, g, built)).unwrap();
            }
            let soft = Position::new(vec![0, 1], vec![positions[0] + DVec3::X * 0.2, positions[1]]).unwrap();
            system.add_group(ConstraintGroup::new("soft", 50.0, vec![Box::new(soft)])).unwrap();
            let last = positions.len() as u32 - 1;
            let hard = Position::new(vec![last], vec![positions[last as usize] + DVec3::Z * 0.1]).unwrap();
            system.add_group(ConstraintGroup::new("hard", 1.0, vec![Box::new(hard)]).with_hard(true)).unwrap();
            if dynamic {
                let mu: Vec<f64> = (0..positions.len()).map(|i| 2.0 + (i % 3) as f64).collect();
                system.set_inertia(Some(mu)).unwrap();
                let s: Vec<DVec3> = positions.iter().map(|p| *p - DVec3::Y * 0.05).collect();
                system.set_inertial_target(&s).unwrap();
            }
            // A deformed state, the held vertex on its target.
            let mut q: Vec<DVec3> = positions
                .iter()
                .enumerate()
                .map(|(i, p)| *p + 0.03 * DVec3::new((i as f64).sin(), (1.7 * i as f64).cos(), (0.3 * i as f64).sin()))
                .collect();
            q[last as usize] = positions[last as usize] + DVec3::Z * 0.1;
            let g = system.half_gradient_at(&q);
            let mut objective = |q: &[DVec3]| system.energy(q).unwrap().total + system.inertial_energy(q);
            let h = 1e-6;
            let mut worst: f64 = 0.0;
            let mut scale: f64 = 0.0;
            for v in 0..q.len() - 1 {
                for k in 0..3 {
                    let mut plus = q.clone();
                    plus[v][k] += h;
                    let mut minus = q.clone();
                    minus[v][k] -= h;
                    let numeric = (objective(&plus) - objective(&minus)) / (2.0 * h);
                    worst = worst.max((numeric - 2.0 * g[v][k]).abs());
                    scale = scale.max(numeric.abs());
                }
            }
            assert!(scale > 1e-3, "dynamic {dynamic}: the state is not at a minimum");
            assert!(worst <= 1e-6 * scale, "dynamic {dynamic}: gradient off by {worst:e} (scale {scale:e})");
            assert_eq!(g[last as usize], DVec3::ZERO, "the held vertex is not an unknown");
        }
    }
}
