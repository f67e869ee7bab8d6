//! When a solve stops and what it reports: the round-off floors, [`is_converged`],
//! [`SolveReport`] and the bookkeeping of each iteration.

use super::{SolveError, System};
use glam::DVec3;
use std::ops::ControlFlow;
use std::time::Instant;

/// E at or below this counts as converged for [`is_converged`] whatever its relative change:
/// round-off, e.g. a rest shape moved rigidly, whose E is about 1e-28 and changes by its own
/// size every iteration. In the working frame (the mesh about one unit across when
/// normalized), E ≤ 1e-20 means the constraints are met to about 1e-10 of the mesh's size.
/// A solve's own test does not use it: an absolute bound would stop every tolerance run after
/// one iteration on a mesh 1e-12 across or with weights of 1e-12; it uses the system's
/// relative floor ([`SolveReport::energy_floor`]).
pub const ENERGY_FLOOR: f64 = 1e-20;

/// Relative round-off floor: E ≤ this × Σ_i w_i ‖p_i‖² (the weighted size of the projections,
/// so of the terms E compares with them) is round-off, the constraints met to about 1e-9 of
/// their own size. Each global step's Cholesky solve perturbs q by about κ·ε (κ the
/// matrix's condition number), so a shape at its minimum does not keep E at 0: on the
/// 35k-vertex bunny with strain + bending at rest, E random-walks from 1e-20 up to 2e-19 over
/// 300 iterations, by about 0.5 % per iteration, and would never meet a 1e-6 relative change.
pub const ROUND_OFF_FLOOR: f64 = 1e-18;

/// Round-off floor of rows whose projection is 0 or small (smoothing, a Laplacian at rest):
/// E ≤ this × Σ_r w_r m_r², with m_r = Σ_v |c_rv| ‖q_v‖ the size of the terms that cancel in
/// (C q)_r (its rounding is ε m_r), is C q met to about 100 ε of its terms ((100 ε)² ≈ 5e-28,
/// with room for the solve's κ ε).
pub const ROW_ROUND_OFF_FLOOR: f64 = 1e-26;

/// The stopping test of a tolerance run: after an iteration that took E from `previous` to
/// `energy`, the relative change |E_k − E_{k−1}| / E_{k−1} is at most `tolerance`, or E is at
/// most `floor` (E = 0 included; see [`SolveReport::energy_floor`], at least [`ENERGY_FLOOR`]).
pub fn is_converged(previous: f64, energy: f64, tolerance: f64, floor: f64) -> bool {
    meets_tolerance(previous, energy, tolerance, floor.max(ENERGY_FLOOR))
}

/// [`is_converged`] without [`ENERGY_FLOOR`]: what a solve tests, with its own relative floor.
fn meets_tolerance(previous: f64, energy: f64, tolerance: f64, floor: f64) -> bool {
    // A load makes E negative: the round-off floor is for E ≥ 0 (constraints met).
    (0.0..=floor).contains(&energy) || (previous - energy).abs() <= tolerance * previous.abs()
}

/// A static solve that ran all its iterations ended short of its minimum when its relative
/// residual ‖∇E(q)‖ / ‖∇E(q₀)‖ (the gradient left, over the gradient it started from) is above
/// this. Measured at the examples' caps: 0.3 to 17 where the gradient has not fallen (bunny
/// strain + bending, Spot's rigid head, the roof's planarization; springs of weight 1e8 against
/// handles of weight 1: 5 % to 10 % of the diagonal from long runs), 2e-6 to 3e-3 where it has
/// collapsed. A collapsed gradient is no promise of the shape: soft modes can still be a few
/// percent of the diagonal away (the math reference, "When a solve stops short").
pub const STATIC_RESIDUAL_LIMIT: f64 = 1e-2;

/// Relative round-off of the gradient (see `System::gradient_floor`): about 2 ε, ε ≈ 2.2e-16,
/// since the nearest point to a minimum that f64 holds has a gradient of that order. Where the
/// springs' round-off held a converged sheet's ‖g‖ at 6e-5, this bound is 0.02; a stiff sheet
/// 1e6 from the origin, whose coordinates keep ten digits, still shows a real gradient (its
/// shape moves on with more iterations) at twice the bound.
pub const GRADIENT_ROUND_OFF: f64 = 5e-16;

/// What a [`System::solve`] did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SolveReport {
    /// E at the start, before the first iteration (0 from [`System::iterate`], which computes
    /// no energies).
    pub initial_energy: f64,
    /// E after each iteration.
    pub energies: Vec<f64>,
    /// Seconds spent in local steps.
    pub local_seconds: f64,
    /// Seconds spent in global steps.
    pub global_seconds: f64,
    /// Seconds spent (re)assembling and factoring before the iterations.
    pub setup_seconds: f64,
    /// Accelerated iterations whose iterate did not lower the energy (Anderson) or not enough
    /// (L-BFGS's Armijo condition) and were replaced by the plain one.
    pub rejected: usize,
    /// E at or below this is round-off for this system and counts as converged:
    /// [`ROUND_OFF_FLOOR`] × Σ_i w_i ‖p_i‖² + [`ROW_ROUND_OFF_FLOOR`] × Σ_r w_r m_r² at the
    /// start of the solve (m_r = Σ_v |c_rv| ‖q_v‖; hard groups left out): relative to the
    /// terms' size, so that a solve stops alike at every scale of coordinates and weights.
    pub energy_floor: f64,
    /// A static solve's relative residual when it ran all its iterations (neither met its
    /// tolerance nor was stopped): [`STATIC_RESIDUAL_LIMIT`]'s ratio, 0 when E is at its
    /// round-off floor. `None` for a solve that ended early, ran no iteration, computed no
    /// energies ([`System::iterate`]) or is a time step's (not measured yet: see the math
    /// reference, "When a solve stops short").
    pub residual: Option<f64>,
    /// The residual is above [`STATIC_RESIDUAL_LIMIT`]: the solve stopped at its iteration cap
    /// short of its minimum (raise the iterations, with a tolerance to stop once converged).
    pub unconverged: bool,
    /// ‖A q − b(q)‖ where the solve began, when an iteration computed it (L-BFGS's first):
    /// the static residual's denominator without a gradient pass of its own.
    pub(super) start_gradient: Option<f64>,
    /// The groups the factorization could not see ([`super::LostGroup`]): their weights so far
    /// below the others' where they act that the shape ignores them.
    pub lost_groups: Vec<super::LostGroup>,
}

impl SolveReport {
    /// The `unconverged` warning of a solve that stopped at its iteration cap short of its
    /// minimum (see [`SolveReport::residual`]); none otherwise. Every door says it in these
    /// words: the scene's solve (naming the file), Python's `Solver.solve`.
    pub fn warnings(&self) -> crate::warnings::Warnings {
        let mut found = crate::warnings::Warnings::new();
        if let (true, Some(residual)) = (self.unconverged, self.residual) {
            let message = format!(
                "static solve stopped at its {}-iteration cap short of its minimum: the energy's gradient is {} times what it was at the start (the limit is {STATIC_RESIDUAL_LIMIT}); raise `iterations` (or --iterations), with a `tolerance` to stop once converged",
                self.energies.len(),
                crate::text::three_digits(residual),
            );
            found.add("unconverged", &message, String::new);
        }
        super::round_off::add_lost_groups_warning(&mut found, &self.lost_groups);
        found
    }
}

/// What a solve asks of its iterations.
#[derive(Debug, Clone, Copy)]
pub(super) struct Run {
    pub(super) iterations: usize,
    pub(super) tolerance: f64,
    /// The objective (E, plus the inertial term in dynamic mode) at the current iterate: at
    /// the start (the projections at q are current), then after each recorded iteration. What
    /// the accelerated schemes compare a candidate with.
    pub(super) objective: f64,
}

/// Runs `f`, adding its wall time in seconds to `seconds`.
pub(super) fn timed<T>(seconds: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let result = f();
    *seconds += t.elapsed().as_secs_f64();
    result
}

impl Run {
    /// After an iteration with energy E and objective `objective` (E, plus the inertial term in
    /// dynamic mode): records E and says whether the objective met the tolerance (against the
    /// run's objective before it, then set to it) and whether `after_iteration` asks to stop.
    /// The tolerance is on the objective, the function the iterations minimize: in dynamic
    /// mode E alone is a small part of it whose relative change stays at the objective's
    /// round-off (1e-8 of E on a draped cloth) long after the step has converged.
    ///
    /// # Errors
    /// [`SolveError::NonFiniteEnergy`] for a NaN or infinite E.
    pub(super) fn record(
        &mut self,
        report: &mut SolveReport,
        energy: f64,
        objective: f64,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
    ) -> Result<(bool, bool), SolveError> {
        if !energy.is_finite() {
            return Err(SolveError::NonFiniteEnergy);
        }
        report.energies.push(energy);
        let converged =
            self.tolerance > 0.0 && meets_tolerance(self.objective, objective, self.tolerance, report.energy_floor);
        self.objective = objective;
        let stop = after_iteration(report.energies.len(), energy).is_break();
        Ok((converged, stop))
    }
}

impl System {
    /// Calls `f(r, w_r, m_r)` for each row r of the groups that are not hard: its weight
    /// w_r (multiplier × row weight) and m_r = Σ_v |c_rv| ‖q_v‖, the size of the terms that
    /// cancel in (C q)_r. What the round-off floors are made of.
    fn for_each_soft_row(&self, q: &[DVec3], mut f: impl FnMut(usize, f64, f64)) {
        let g = self.multipliers();
        let a = &self.assembly;
        for ((rows, gk), &slot) in a.groups.iter().zip(&g).zip(&self.order) {
            if self.slots[slot].as_ref().is_none_or(|group| group.hard) {
                continue;
            }
            for r in rows.range() {
                let m: f64 =
                    (a.c_ptr[r]..a.c_ptr[r + 1]).map(|k| a.c_val[k].abs() * q[a.c_col[k] as usize].length()).sum();
                f(r, gk * a.row_weight[r], m);
            }
        }
    }

    /// [`SolveReport::energy_floor`] at q from the current projections.
    pub(super) fn energy_floor(&self, q: &[DVec3]) -> f64 {
        let mut projections = 0.0;
        let mut terms = 0.0;
        self.for_each_soft_row(q, |r, w, m| {
            projections += w * self.projections[r].length_squared();
            terms += w * m * m;
        });
        ROUND_OFF_FLOOR * projections + ROW_ROUND_OFF_FLOOR * terms
    }

    /// The round-off of ‖A q − b(q)‖ at q (static mode): a row's residual (C q)_r − P_r is
    /// computed to a few ε of the terms that cancel in it, m_r (as for
    /// [`ROW_ROUND_OFF_FLOOR`]), and enters g times w_r c_rv, so
    /// [`GRADIENT_ROUND_OFF`] × (Σ_r w_r² m_r² Σ_v c_rv²)^½ is what g can be at a minimum.
    /// Springs of weight 1e12 holding a sheet that two handles of weight 1 shift by 1e-3 end
    /// exactly at the shifted sheet with ‖g‖ at 4 % of its start: round-off of the springs'
    /// terms, which more iterations do not lower.
    pub(super) fn gradient_floor(&self, q: &[DVec3]) -> f64 {
        let a = &self.assembly;
        let mut sum = 0.0;
        self.for_each_soft_row(q, |r, w, m| {
            let c2: f64 = (a.c_ptr[r]..a.c_ptr[r + 1]).map(|k| a.c_val[k] * a.c_val[k]).sum();
            sum += (w * m) * (w * m) * c2;
        });
        GRADIENT_ROUND_OFF * sum.sqrt()
    }
}
