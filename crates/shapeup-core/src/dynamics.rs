//! Projective Dynamics (Bouaziz, Martin, Liu, Kavan, Pauly, SIGGRAPH 2014): implicit time
//! stepping with the same local-global solver and the same constraints as static ShapeUp.
//!
//! One time step h from positions x_n and velocities v_n (math reference, "Dynamic mode"):
//! 1. inertial target s = x_n + h v_n + h² a_ext (gravity plus per-vertex forces over mass);
//! 2. from q = s, minimize (1/h²)‖M^½(q − s)‖² + k Σ_i w_i ‖C_i q − p_i(q)‖² by local-global
//!    iterations — the [`System`] with inertia weights μ_i = m_i / (k h²), whose matrix
//!    diag(μ) + Σ w_i C_iᵀC_i is factored once and reused by every step;
//! 3. v_{n+1} = (1 − d)(x_{n+1} − x_n)/h.
//!
//! Everything is in the working frame (see [`crate::geometry::WorkingFrame`]); the scene layer
//! converts gravity and forces from input units.

use crate::constraints::RowSink;
use crate::contact::{ContactModel, ContactStats, solve_with_contact};
use crate::solver::{SolveError, SolverParams, System};
use glam::DVec3;
use std::time::Instant;

/// Time-stepping settings; the defaults are the math reference's. Iterations per step and the
/// tolerance are the system's [`SolverParams`] (one home for both, in static and dynamic mode).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicsParams {
    /// Time step h in seconds (default 1/60).
    pub time_step: f64,
    /// Stiffness k scaling every constraint against inertia (default 100).
    pub stiffness: f64,
    /// Velocity damping d ∈ [0, 1) (default 0).
    pub damping: f64,
    /// Gravity, an acceleration in working-frame units per s² (default (0, −9.81, 0)).
    pub gravity: DVec3,
}

impl Default for DynamicsParams {
    fn default() -> Self {
        DynamicsParams { time_step: 1.0 / 60.0, stiffness: 100.0, damping: 0.0, gravity: DVec3::new(0.0, -9.81, 0.0) }
    }
}

impl DynamicsParams {
    /// Checks every value, naming the first bad one.
    ///
    /// # Errors
    /// [`ParamError`]: which setting, its value and the allowed range.
    pub fn validate(&self) -> Result<(), ParamError> {
        let DynamicsParams { time_step, stiffness, damping, gravity } = *self;
        if !(time_step.is_finite() && time_step > 0.0) {
            return Err(ParamError::TimeStep(time_step));
        }
        if !(stiffness.is_finite() && stiffness > 0.0) {
            return Err(ParamError::Stiffness(stiffness));
        }
        if !(0.0..1.0).contains(&damping) {
            return Err(ParamError::Damping(damping));
        }
        if !gravity.is_finite() {
            return Err(ParamError::Gravity(gravity));
        }
        // The inertia weights m / (k h²) scale by 1 / (k h²): far from f64's ends, so that the
        // matrix, the right-hand side and the energies stay finite (k h² of 1e-250 overflowed
        // them mid-run).
        if !(INERTIA_SCALE_RANGE.contains(&(stiffness * time_step * time_step))) {
            return Err(ParamError::InertiaScale { time_step, stiffness });
        }
        Ok(())
    }

    /// Checks the solver settings a time step runs with ([`SolverParams::iterations`] per step,
    /// [`SolverParams::tolerance`]), naming the first bad one.
    ///
    /// # Errors
    /// [`ParamError::NoIterations`] or [`ParamError::Tolerance`].
    pub fn validate_solver(solver: &SolverParams) -> Result<(), ParamError> {
        if solver.iterations == 0 {
            return Err(ParamError::NoIterations);
        }
        if !(solver.tolerance.is_finite() && solver.tolerance >= 0.0) {
            return Err(ParamError::Tolerance(solver.tolerance));
        }
        Ok(())
    }

    /// The inertia weight μ_i = m_i / (k h²) of each mass.
    pub fn inertia(&self, masses: &[f64]) -> Vec<f64> {
        let scale = 1.0 / (self.stiffness * self.time_step * self.time_step);
        masses.iter().map(|m| m * scale).collect()
    }
}

/// The range of k h² ([`DynamicsParams::validate`]): the inertia weights are m / (k h²).
pub const INERTIA_SCALE_RANGE: std::ops::RangeInclusive<f64> = 1e-100..=1e100;

/// A time-stepping setting out of range ([`DynamicsParams::validate`]).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// h is not a finite number > 0.
    #[error("time_step must be a finite number > 0, found {0}")]
    TimeStep(f64),
    /// k is not a finite number > 0.
    #[error("stiffness must be a finite number > 0, found {0}")]
    Stiffness(f64),
    /// d is outside [0, 1).
    #[error("damping must be in [0, 1), found {0}")]
    Damping(f64),
    /// Gravity has a non-finite component.
    #[error("gravity must be finite, found {0:?}")]
    Gravity(DVec3),
    /// k h² outside [`INERTIA_SCALE_RANGE`].
    #[error(
        "time_step {} and stiffness {} put stiffness · time_step² at {}, outside 1e-100 to 1e100: the inertia m / (stiffness · time_step²) would overflow or vanish",
        crate::text::three_digits(*time_step),
        crate::text::three_digits(*stiffness),
        crate::text::three_digits(stiffness * time_step * time_step)
    )]
    InertiaScale {
        /// h.
        time_step: f64,
        /// k.
        stiffness: f64,
    },
    /// No iterations per step.
    #[error("iterations must be at least 1 in dynamic mode")]
    NoIterations,
    /// The tolerance is not a finite number ≥ 0.
    #[error("tolerance must be a finite number ≥ 0, found {0}")]
    Tolerance(f64),
}

/// Why a simulation cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A setting is out of range.
    #[error("dynamic mode: {0}")]
    BadParams(#[from] ParamError),
    /// Masses, positions or velocities do not match the vertex count, or a mass is not > 0.
    #[error("dynamic mode: {0}")]
    BadState(String),
    /// The solver refused.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// What one time step did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StepReport {
    /// E(q) = Σ w_i ‖C_i q − p_i(q)‖² after the step (constraints only, without k or inertia)
    /// when the iterations computed it (a tolerance, or an acceleration, whose safeguard needs
    /// it); `None` after plain iterations, which skip it: [`Simulation::energy`] computes
    /// it when wanted.
    pub energy: Option<f64>,
    /// Iterations run (fewer than asked when the tolerance stopped them).
    pub iterations: usize,
    /// Accelerated iterations replaced by the plain one ([`crate::solver::SolveReport::rejected`]).
    pub rejected: usize,
    /// Seconds in local steps.
    pub local_seconds: f64,
    /// Seconds in global steps.
    pub global_seconds: f64,
    /// Seconds (re)assembling and factoring (only after a change of constraints or settings).
    pub setup_seconds: f64,
    /// Wall-clock seconds of the whole step.
    pub total_seconds: f64,
    /// What contact did in this step (all 0 without contact).
    pub contact: ContactStats,
    /// Seconds in contact detection and the end-of-step projection.
    pub contact_seconds: f64,
    /// On a checked step ([`is_checked_step`]) without contact, whether it ran all its
    /// iterations or its tolerance ended it (a stiff step's energy stalls long before it is
    /// converged, so a tolerance is no promise): the share of the converged step's motion it still misses, ‖δ‖_M / ‖x_{n+1} + δ − x_n‖_M,
    /// δ the Newton step left ([`System::remaining_step`], [`CHECK_ITERATIONS`] iterations),
    /// ‖·‖_M the mass-weighted norm; 0 when δ's root mean square is within
    /// [`MISSING_MOTION_FLOOR`] of the bounding box's diagonal. `None` where not measured.
    pub residual: Option<f64>,
    /// The residual is above [`DYNAMIC_RESIDUAL_LIMIT`]: the step stopped (at its iteration cap
    /// or its tolerance) short of its converged motion.
    pub unconverged: bool,
    /// Seconds in that check (0 on the steps not checked).
    pub check_seconds: f64,
    /// Groups the factorization cannot resolve ([`crate::solver::SolveReport::lost_groups`]).
    pub lost_groups: Vec<crate::solver::LostGroup>,
}

/// A time step whose residual ([`StepReport::residual`]) is above this stopped short: it misses
/// half the motion of the converged step or more. Measured (math reference, "When a solve
/// stops short"): at most 0.13 on the examples' steps and a soft cloth's, a median of 0.92 for
/// a cloth of stiffness 1e8 that barely moves in 10 iterations a step.
pub const DYNAMIC_RESIDUAL_LIMIT: f64 = 0.5;

/// Newton–CG iterations of a time step's check ([`System::remaining_step`]): enough to find a
/// stiff cloth's swing (8 find it from the second step on), each about one L-BFGS iteration.
pub const CHECK_ITERATIONS: usize = 16;

/// A missing motion whose root mean square is at most this share of the bounding box's
/// diagonal is not measured (residual 0): the round-off of a settled or free-falling state.
/// Not larger: steps of a short time step move little, and 1e-6 hid a cloth they froze.
pub const MISSING_MOTION_FLOOR: f64 = 1e-12;

/// Whether time step `k` (from 1) is checked for stopping short: 1, 2, 4, …, 64, then every
/// 64th. A check costs about 1.6 steps of 10 iterations, so a long run pays about 2.5 %.
pub fn is_checked_step(k: u64) -> bool {
    k.is_power_of_two() || k.is_multiple_of(64)
}

/// Vertices pulled towards points (the editor's mouse grab). [`Simulation::grab`]: each step
/// moves their inertial targets a fraction `strength` of the way from x_n + h v_n to the
/// points — an external force m (p − x_n − h v_n) · strength / h², so grabbing never refactors
/// the matrix. [`Simulation::hold`]: a stiff spring to the points inside the implicit solve.
#[derive(Debug, Clone, PartialEq)]
pub struct Grab {
    /// The grabbed vertices.
    pub vertices: Vec<u32>,
    /// Where each is pulled (working frame).
    pub targets: Vec<DVec3>,
    /// In (0, 1]: the fraction of the remaining distance closed per step by the force
    /// ([`Simulation::grab`]), or at least per iteration by the spring ([`Simulation::hold`]).
    pub strength: f64,
}

/// The largest hold weight, in units of a vertex's diagonal (strength 1): stiff enough to pin a
/// vertex to its target, far from the round-off of the Cholesky factor.
const MAX_HOLD_RATIO: f64 = 1e6;

/// A Projective Dynamics simulation: a [`System`] in dynamic mode plus the state (x, v).
#[derive(Debug)]
pub struct Simulation {
    system: System,
    params: DynamicsParams,
    masses: Vec<f64>,
    positions: Vec<DVec3>,
    velocities: Vec<DVec3>,
    /// Per-vertex external forces (working frame), if any.
    forces: Option<Vec<DVec3>>,
    /// The wind on the surface's triangles ([`Simulation::set_wind`]), and its forces of the
    /// step (reused).
    wind: Option<(crate::materials::Wind, Vec<[u32; 3]>)>,
    wind_forces: Vec<DVec3>,
    grab: Option<Grab>,
    /// For a grab by [`Simulation::hold`]: the weight added to each grabbed vertex's inertia
    /// (in the order of the grab's vertices); `None` for a force grab.
    hold: Option<Vec<f64>>,
    /// Inertial target and iterate buffers (reused every step).
    target: Vec<DVec3>,
    next: Vec<DVec3>,
    steps: u64,
    /// Colliders and self-collision, if any ([`Simulation::set_contact`]).
    contact: Option<ContactModel>,
}

impl Simulation {
    /// A simulation of `system`'s constraints on vertices with `masses`, starting at rest at
    /// `positions` (working frame). A vertex of mass 0 has no inertia: if no constraint touches
    /// it, it stays where it is (as a vertex in no element does in static mode).
    ///
    /// # Errors
    /// [`DynamicsError`] for bad settings, a wrong length or a mass that is negative or not
    /// finite.
    pub fn new(
        mut system: System,
        masses: Vec<f64>,
        positions: Vec<DVec3>,
        params: DynamicsParams,
    ) -> Result<Self, DynamicsError> {
        params.validate()?;
        DynamicsParams::validate_solver(system.params())?;
        let n = system.num_vertices();
        if masses.len() != n || positions.len() != n {
            return Err(DynamicsError::BadState(format!(
                "{n} vertices but {} masses and {} positions",
                masses.len(),
                positions.len()
            )));
        }
        if let Some(i) = masses.iter().position(|m| !(m.is_finite() && *m >= 0.0)) {
            return Err(DynamicsError::BadState(format!("vertex {i} has mass {}, must be ≥ 0", masses[i])));
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(DynamicsError::BadState(format!("vertex {i} has a non-finite position")));
        }
        let inertia = params.inertia(&masses);
        if let Some(i) = inertia.iter().position(|mu| !mu.is_finite()) {
            // A density so high that m / (k h²) overflows: said in the settings' words.
            return Err(DynamicsError::BadState(format!(
                "vertex {i}'s inertia m / (stiffness · time_step²) is not a finite number (mass {}): lower `density`, or raise `stiffness` or `time_step`",
                crate::text::three_digits(masses[i])
            )));
        }
        system.set_inertia(Some(inertia))?;
        system.set_load_scale(1.0 / params.stiffness)?;
        Ok(Simulation {
            system,
            params,
            masses,
            velocities: vec![DVec3::ZERO; n],
            target: positions.clone(),
            next: positions.clone(),
            positions,
            forces: None,
            wind: None,
            wind_forces: Vec::new(),
            grab: None,
            hold: None,
            steps: 0,
            contact: None,
        })
    }

    /// Advances one time step (see the [module docs](self)).
    ///
    /// # Errors
    /// [`SolveError`] from the solver (e.g. non-finite positions); the state is unchanged then.
    pub fn step(&mut self) -> Result<StepReport, SolveError> {
        // On one of rayon's threads, so that each of the step's parallel loops (a contact step
        // runs some hundred) starts on the thread that reaches it, and at 1 thread runs there,
        // instead of being handed to the pool while the caller's thread sleeps: 15–30 % of a
        // step at 1 thread. Called from a pool thread (the command line runs there), it runs
        // in place. Either way the loops split alike, so every caller gets the same numbers.
        rayon::scope(|_| self.step_on_pool())
    }

    fn step_on_pool(&mut self) -> Result<StepReport, SolveError> {
        let started = Instant::now();
        let h = self.params.time_step;
        // 1. Inertial target s = x + h v + h² a_ext, q starts at s. The wind's force is
        // explicit: from the step's start.
        if let Some((wind, triangles)) = &self.wind {
            self.wind_forces.clear();
            self.wind_forces.resize(self.positions.len(), DVec3::ZERO);
            crate::materials::add_wind_forces(
                wind,
                triangles,
                &self.positions,
                &self.velocities,
                &mut self.wind_forces,
            );
        }
        for (i, s) in self.target.iter_mut().enumerate() {
            if self.masses[i] == 0.0 {
                // No mass (a vertex in no element): no inertia and no gravity; it stays where it
                // is unless a constraint moves it.
                *s = self.positions[i];
                continue;
            }
            let mut a = self.params.gravity;
            if let Some(f) = &self.forces
                && self.masses[i] > 0.0
            {
                a += f[i] / self.masses[i];
            }
            if self.wind.is_some() {
                a += self.wind_forces[i] / self.masses[i];
            }
            *s = self.positions[i] + h * self.velocities[i] + h * h * a;
        }
        match (&self.grab, &self.hold) {
            (Some(grab), None) => {
                for (&v, &p) in grab.vertices.iter().zip(&grab.targets) {
                    let v = v as usize;
                    let coasting = self.positions[v] + h * self.velocities[v];
                    self.target[v] += grab.strength * (p - coasting);
                }
            }
            (Some(grab), Some(weights)) => {
                // The system's inertia is μ_v + g_v there: its target is the weighted mean.
                let scale = 1.0 / (self.params.stiffness * h * h);
                for ((&v, &p), &g) in grab.vertices.iter().zip(&grab.targets).zip(weights) {
                    let v = v as usize;
                    let mu = self.masses[v] * scale;
                    if g > 0.0 {
                        self.target[v] = (mu * self.target[v] + g * p) / (mu + g);
                    }
                }
            }
            (None, _) => {}
        }
        self.system.set_inertial_target(&self.target)?;
        self.next.copy_from_slice(&self.target);
        // Contact: what may touch during this step, from x_n and the prediction s.
        let contact_started = Instant::now();
        let (t0, t1) = (self.time(), self.time() + h);
        if let Some(contact) = &mut self.contact {
            contact.begin_step(&self.positions, &self.target, t0, t1);
        }
        let mut contact_seconds = contact_started.elapsed().as_secs_f64();
        // 2. Local-global iterations on the inertia + constraint energy; E only if they need it.
        let solver = *self.system.params();
        let needs_energy = solver.needs_energy() && self.contact.is_none();
        let report = match &mut self.contact {
            // With contact, plain iterations with its targets (the matrix stays the same).
            Some(contact) => solve_with_contact(&mut self.system, contact, &mut self.next, solver.iterations)?,
            None if needs_energy => self.system.solve(&mut self.next, solver.iterations, solver.tolerance)?,
            None => self.system.iterate(&mut self.next, solver.iterations)?,
        };
        // Did it stop short? Measured on checked steps, at the cap or the tolerance.
        let check_started = Instant::now();
        let residual =
            // Not with a material: the check runs plain local-global iterations, which its
            // energy needs a line search for (they would report motion that is not there).
            (self.contact.is_none() && !self.system.has_energy_terms() && is_checked_step(self.steps + 1))
                .then(|| self.missing_motion())
                .flatten();
        let check_seconds = if residual.is_some() { check_started.elapsed().as_secs_f64() } else { 0.0 };
        let mut contact_stats = ContactStats::default();
        if let Some(contact) = &mut self.contact {
            let t = Instant::now();
            // A vertex a hard group holds must not move: inverse mass 0.
            let held = self.system.held_mask();
            let inverse_mass: Vec<f64> =
                self.masses.iter().zip(&held).map(|(&m, &h)| if m > 0.0 && !h { 1.0 / m } else { 0.0 }).collect();
            contact.finish_step(&mut self.next, &inverse_mass);
            contact_stats = contact.stats();
            contact_seconds += t.elapsed().as_secs_f64();
        }
        // 3. Velocity update with damping, then the new positions.
        let keep = (1.0 - self.params.damping) / h;
        for ((v, x), q) in self.velocities.iter_mut().zip(&mut self.positions).zip(&self.next) {
            *v = keep * (*q - *x);
            *x = *q;
        }
        self.steps += 1;
        Ok(StepReport {
            energy: report.energies.last().copied(),
            iterations: if needs_energy { report.energies.len() } else { solver.iterations },
            rejected: report.rejected,
            local_seconds: report.local_seconds,
            global_seconds: report.global_seconds,
            setup_seconds: report.setup_seconds,
            total_seconds: started.elapsed().as_secs_f64(),
            contact: contact_stats,
            contact_seconds,
            residual,
            unconverged: residual.is_some_and(|r| r > DYNAMIC_RESIDUAL_LIMIT),
            check_seconds,
            lost_groups: report.lost_groups,
        })
    }

    /// The residual of the step just solved into `next` from `positions`
    /// ([`StepReport::residual`]); `None` when the check fails (a non-finite gradient: the
    /// step's own result stands).
    fn missing_motion(&mut self) -> Option<f64> {
        let delta = self.system.remaining_step(&self.next, CHECK_ITERATIONS).ok()?;
        let (mut missing, mut motion, mut mass) = (0.0, 0.0, 0.0);
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        for (((&m, d), q), x) in self.masses.iter().zip(&delta).zip(&self.next).zip(&self.positions) {
            missing += m * d.length_squared();
            motion += m * (*q + *d - *x).length_squared();
            mass += m;
            lo = lo.min(*q);
            hi = hi.max(*q);
        }
        let diagonal = (hi - lo).length();
        if !(missing.is_finite() && motion.is_finite()) {
            return None;
        }
        if mass <= 0.0 || (missing / mass).sqrt() <= MISSING_MOTION_FLOOR * diagonal {
            return Some(0.0);
        }
        Some(if motion > 0.0 { (missing / motion).sqrt() } else { f64::INFINITY })
    }

    /// Sets the colliders and self-collision the next steps respect (`None`: none). The
    /// system's matrix is unchanged: contact is a force on the global step's right-hand side
    /// ([`crate::contact`]).
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] when the model is for another vertex count.
    pub fn set_contact(&mut self, contact: Option<ContactModel>) -> Result<(), DynamicsError> {
        if let Some(c) = &contact
            && c.touching().len() != self.masses.len()
        {
            return Err(DynamicsError::BadState(format!(
                "contact for {} vertices in a simulation of {}",
                c.touching().len(),
                self.masses.len()
            )));
        }
        self.contact = contact.filter(ContactModel::is_active);
        let weights = self.contact.as_ref().map(|c| c.weights(&self.params.inertia(&self.masses)));
        self.system.set_contact_weights(weights)?;
        self.push_out_of_colliders();
        Ok(())
    }

    /// Before a run (or after [`Simulation::set_state`]): vertices that overlap a collider are
    /// moved out to the thickness without velocity, so that a rest shape placed in a collider
    /// is not thrown off it.
    fn push_out_of_colliders(&mut self) {
        if let Some(contact) = &self.contact {
            let t = self.time();
            contact.push_out(&mut self.positions, t);
        }
    }

    /// The contact model, if any.
    pub fn contact(&self) -> Option<&ContactModel> {
        self.contact.as_ref()
    }

    /// E(x_n) = Σ w_i ‖C_i x_n − p_i(x_n)‖² at the current positions (constraints only, without
    /// k or inertia): one local step.
    ///
    /// # Errors
    /// [`SolveError`] from the solver; [`SolveError::NonFiniteEnergy`] when E overflows (plain
    /// steps evaluate no E, so an absurd gravity or time step shows first here).
    pub fn energy(&mut self) -> Result<f64, SolveError> {
        self.system.finite_energy(&self.positions)
    }

    /// Positions x_n (working frame).
    pub fn positions(&self) -> &[DVec3] {
        &self.positions
    }

    /// Velocities v_n (working frame units per second).
    pub fn velocities(&self) -> &[DVec3] {
        &self.velocities
    }

    /// Lumped masses m_i.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The settings.
    pub fn params(&self) -> &DynamicsParams {
        &self.params
    }

    /// Time steps taken.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Simulated time, steps × h.
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.params.time_step
    }

    /// Replaces the state (x, v), e.g. to reset; lengths must match.
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] for a wrong length or non-finite values.
    pub fn set_state(&mut self, positions: &[DVec3], velocities: &[DVec3]) -> Result<(), DynamicsError> {
        let n = self.masses.len();
        if positions.len() != n || velocities.len() != n {
            return Err(DynamicsError::BadState(format!(
                "{n} vertices but {} positions and {} velocities",
                positions.len(),
                velocities.len()
            )));
        }
        if positions.iter().chain(velocities).any(|p| !p.is_finite()) {
            return Err(DynamicsError::BadState("non-finite position or velocity".into()));
        }
        self.positions.copy_from_slice(positions);
        self.velocities.copy_from_slice(velocities);
        self.push_out_of_colliders();
        Ok(())
    }

    /// Changes the settings; a new time step or stiffness refactors the matrix numerically.
    ///
    /// # Errors
    /// [`DynamicsError::BadParams`].
    pub fn set_params(&mut self, params: DynamicsParams) -> Result<(), DynamicsError> {
        params.validate()?;
        let old = std::mem::replace(&mut self.params, params);
        // A hold's weights are relative to the matrix's diagonal, which k and h scale.
        let held = self.hold.is_some().then(|| self.grab.clone()).flatten();
        let inertia = match &held {
            Some(grab) => {
                let weights = self.hold_weights(&grab.vertices, grab.strength);
                let inertia = self.inertia_with(&grab.vertices, &weights);
                self.hold = Some(weights);
                inertia
            }
            None => params.inertia(&self.masses),
        };
        if let Err(e) = self.system.set_inertia(Some(inertia)) {
            self.params = old;
            return Err(e.into());
        }
        // The contact weights are relative to the inertia.
        let weights = self.contact.as_ref().map(|c| c.weights(&params.inertia(&self.masses)));
        self.system.set_contact_weights(weights)?;
        self.system.set_load_scale(1.0 / params.stiffness)?;
        Ok(())
    }

    /// Per-vertex external forces (working frame; `None` for none).
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] for a wrong length or a non-finite force.
    pub fn set_external_forces(&mut self, forces: Option<Vec<DVec3>>) -> Result<(), DynamicsError> {
        if let Some(f) = &forces {
            if f.len() != self.masses.len() {
                return Err(DynamicsError::BadState(format!("{} forces for {} vertices", f.len(), self.masses.len())));
            }
            if let Some(i) = f.iter().position(|x| !x.is_finite()) {
                return Err(DynamicsError::BadState(format!("the force on vertex {i} is not finite")));
            }
        }
        self.forces = forces;
        Ok(())
    }

    /// The wind on `triangles` (the surface, working frame: metres, m/s) from the next step
    /// on, or none ([`crate::materials::add_wind_forces`]: drag and lift through each face's
    /// velocity relative to the air, applied explicitly from each step's start).
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] for a non-finite velocity or coefficient, a negative air
    /// density or a triangle with a vertex out of range.
    pub fn set_wind(&mut self, wind: Option<(crate::materials::Wind, Vec<[u32; 3]>)>) -> Result<(), DynamicsError> {
        if let Some((w, triangles)) = &wind {
            if !(w.velocity.is_finite() && w.drag.is_finite() && w.lift.is_finite()) {
                return Err(DynamicsError::BadState("the wind's velocity and coefficients must be finite".into()));
            }
            if !(w.air_density.is_finite() && w.air_density >= 0.0) {
                return Err(DynamicsError::BadState(format!(
                    "the air's density must be a finite number ≥ 0, found {}",
                    w.air_density
                )));
            }
            if let Some(t) = triangles.iter().find(|t| t.iter().any(|&v| v as usize >= self.masses.len())) {
                return Err(DynamicsError::BadState(format!(
                    "wind triangle {t:?} names a vertex out of range ({} vertices)",
                    self.masses.len()
                )));
            }
        }
        self.wind = wind;
        Ok(())
    }

    /// Pulls `vertices` towards `targets` (working frame) from the next step on, closing a
    /// fraction `strength` ∈ (0, 1] of the distance per step (see [`Grab`]); replaces any
    /// previous grab. No refactorization (but after a [`Simulation::hold`], whose matrix it
    /// restores). A force that weak against stiff constraints barely moves them: to make
    /// vertices follow a cursor, use [`Simulation::hold`].
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] for mismatched lengths, an index out of range, a
    /// non-finite target or a strength outside (0, 1].
    pub fn grab(&mut self, vertices: Vec<u32>, targets: Vec<DVec3>, strength: f64) -> Result<(), DynamicsError> {
        self.check_grab(&vertices, &targets, strength)?;
        self.end_hold()?;
        self.grab = Some(Grab { vertices, targets, strength });
        Ok(())
    }

    /// Holds `vertices` at `targets` (working frame) from the next step on: a spring inside the
    /// implicit solve, g_v ‖q_v − p_v‖² next to the inertia term μ_v ‖q_v − s_v‖² of each
    /// grabbed vertex, with g_v = γ D_v, D_v the vertex's diagonal entry of the system matrix
    /// (inertia plus constraints) and γ = strength / (1 − strength) (at most 10⁶). The global
    /// step then puts a grabbed vertex a fraction `strength` ∈ (0, 1] of the way from where the
    /// rest of the system pulls it to its target, whatever the stiffness, time step or mesh
    /// resolution: strength 1 pins the vertices to the targets (they follow a cursor), small
    /// strengths pull softly. A vertex of mass 0 is not held.
    ///
    /// The first hold of a vertex set (or a new strength) refactors the matrix numerically
    /// (same pattern); moving the targets of the same vertices costs nothing, so call it on
    /// every cursor move. [`Simulation::release`] or [`Simulation::grab`] restore the matrix.
    ///
    /// # Errors
    /// As [`Simulation::grab`], and a vertex listed twice; the previous grab then stays.
    pub fn hold(&mut self, vertices: Vec<u32>, targets: Vec<DVec3>, strength: f64) -> Result<(), DynamicsError> {
        self.check_grab(&vertices, &targets, strength)?;
        let mut seen = vec![false; self.masses.len()];
        if let Some(v) = vertices.iter().find(|&&v| std::mem::replace(&mut seen[v as usize], true)) {
            return Err(DynamicsError::BadState(format!("grab: vertex {v} is listed twice")));
        }
        let same =
            self.hold.is_some() && self.grab.as_ref().is_some_and(|g| g.vertices == vertices && g.strength == strength);
        if !same {
            let weights = self.hold_weights(&vertices, strength);
            self.system.set_inertia(Some(self.inertia_with(&vertices, &weights)))?;
            self.hold = Some(weights);
        }
        self.grab = Some(Grab { vertices, targets, strength });
        Ok(())
    }

    /// g_v = γ D_v for each vertex (see [`Simulation::hold`]); 0 for a vertex without mass.
    fn hold_weights(&self, vertices: &[u32], strength: f64) -> Vec<f64> {
        let ratio = if strength >= 1.0 { MAX_HOLD_RATIO } else { (strength / (1.0 - strength)).min(MAX_HOLD_RATIO) };
        let mu = self.params.inertia(&self.masses);
        let mut slot = vec![usize::MAX; self.masses.len()];
        for (i, &v) in vertices.iter().enumerate() {
            slot[v as usize] = i;
        }
        let mut diagonal: Vec<f64> = vertices.iter().map(|&v| mu[v as usize]).collect();
        let mut sink = RowSink::default();
        for (_, group) in self.system.groups() {
            for c in group.constraints.iter().filter(|c| c.vertices().iter().any(|&v| slot[v as usize] != usize::MAX)) {
                sink.entries.clear();
                c.rows(&mut sink);
                // Repeated (row, vertex) entries add up before squaring, as in the assembly.
                sink.entries.sort_unstable_by_key(|e| (e.row, e.vertex));
                let w = group.multiplier * c.element_weight();
                for run in sink.entries.chunk_by(|a, b| (a.row, a.vertex) == (b.row, b.vertex)) {
                    let i = slot[run[0].vertex as usize];
                    if i != usize::MAX {
                        let coeff: f64 = run.iter().map(|e| e.coeff).sum();
                        diagonal[i] += w * coeff * coeff;
                    }
                }
            }
        }
        vertices.iter().zip(&diagonal).map(|(&v, &d)| if mu[v as usize] > 0.0 { ratio * d } else { 0.0 }).collect()
    }

    /// μ = m / (k h²) plus the hold weights of `vertices`.
    fn inertia_with(&self, vertices: &[u32], weights: &[f64]) -> Vec<f64> {
        let mut inertia = self.params.inertia(&self.masses);
        for (&v, &g) in vertices.iter().zip(weights) {
            inertia[v as usize] += g;
        }
        inertia
    }

    /// Ends a hold: the plain inertia again.
    fn end_hold(&mut self) -> Result<(), SolveError> {
        if self.hold.take().is_some() {
            self.system.set_inertia(Some(self.params.inertia(&self.masses)))?;
        }
        Ok(())
    }

    fn check_grab(&self, vertices: &[u32], targets: &[DVec3], strength: f64) -> Result<(), DynamicsError> {
        if vertices.len() != targets.len() {
            return Err(DynamicsError::BadState(format!(
                "grab: {} vertices but {} targets",
                vertices.len(),
                targets.len()
            )));
        }
        if let Some(v) = vertices.iter().find(|&&v| v as usize >= self.masses.len()) {
            return Err(DynamicsError::BadState(format!(
                "grab: vertex {v} out of range ({} vertices)",
                self.masses.len()
            )));
        }
        if targets.iter().any(|t| !t.is_finite()) || !(strength > 0.0 && strength <= 1.0) {
            return Err(DynamicsError::BadState(format!(
                "grab: targets must be finite and strength in (0, 1], found {strength}"
            )));
        }
        Ok(())
    }

    /// Lets go of grabbed vertices (after a [`Simulation::hold`], the next step refactors).
    pub fn release(&mut self) {
        self.grab = None;
        // Cannot fail: the plain inertia was accepted when the simulation was made.
        let _ = self.end_hold();
    }

    /// The current grab, if any.
    pub fn grabbed(&self) -> Option<&Grab> {
        self.grab.as_ref()
    }

    /// The constraint system (e.g. to move handle targets or add groups between steps).
    pub fn system_mut(&mut self) -> &mut System {
        &mut self.system
    }

    /// The constraint system.
    pub fn system(&self) -> &System {
        &self.system
    }

    /// Kinetic energy ½ Σ m_i ‖v_i‖².
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.masses.iter().zip(&self.velocities).map(|(m, v)| m * v.length_squared()).sum::<f64>()
    }

    /// Linear momentum Σ m_i v_i.
    pub fn momentum(&self) -> DVec3 {
        self.masses.iter().zip(&self.velocities).map(|(m, v)| *m * *v).sum()
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::{BuildContext, Params, Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame, lumped_masses_surface};
    use crate::solver::{ConstraintGroup, SolverParams};

    /// A 6×6 cloth of stiff edge springs, at rest, without gravity.
    fn cloth() -> Simulation {
        let mesh = crate::generate::cloth_grid(6, 6, 1.0, 1.0);
        let rest = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let mut system = System::new(mesh.num_vertices(), SolverParams::default());
        let springs = build_constraints("edge_spring", &ctx, Params::default()).unwrap();
        system.add_group(ConstraintGroup::new("shape", 100.0, springs)).unwrap();
        let masses = lumped_masses_surface(mesh.num_vertices(), &mesh.triangles, &rest.triangle_areas, 1.0);
        let params = DynamicsParams { gravity: DVec3::ZERO, ..DynamicsParams::default() };
        Simulation::new(system, masses, mesh.positions, params).unwrap()
    }

    #[test]
    fn a_full_strength_hold_follows_its_target_where_a_force_grab_lags() {
        let mut held = cloth();
        let mut pushed = cloth();
        let corner = vec![35];
        let target = vec![held.positions()[35] + DVec3::new(0.0, 0.0, 0.5)];
        held.hold(corner.clone(), target.clone(), 1.0).unwrap();
        pushed.grab(corner, target.clone(), 0.3).unwrap();
        for _ in 0..3 {
            held.step().unwrap();
            pushed.step().unwrap();
        }
        let gap = |s: &Simulation| (s.positions()[35] - target[0]).length();
        assert!(gap(&held) < 1e-3, "held {}", gap(&held));
        assert!(gap(&pushed) > 0.25, "the force grab lags: {}", gap(&pushed));
        assert!(held.positions()[28].z > 0.05, "the cloth follows the corner");
    }

    #[test]
    fn moving_a_hold_does_not_refactor_and_release_restores_the_inertia() {
        let mut sim = cloth();
        let plain = sim.params().inertia(sim.masses());
        let start = sim.positions()[35];
        sim.hold(vec![35], vec![start], 0.9).unwrap();
        assert!(sim.step().unwrap().setup_seconds > 0.0, "a new hold refactors");
        assert!(sim.system().inertia().unwrap()[35] > 9.0 * plain[35]);
        let mut setup = 0.0;
        for k in 1..=50 {
            let to = start + DVec3::new(0.0, 0.0, 0.01 * f64::from(k));
            sim.hold(vec![35], vec![to], 0.9).unwrap();
            setup += sim.step().unwrap().setup_seconds;
        }
        assert!(setup < 1e-3, "moving the targets does not refactor ({setup} s)");
        let end = start + DVec3::new(0.0, 0.0, 0.5);
        assert!((sim.positions()[35] - end).length() < 0.05, "{} from {end}", sim.positions()[35]);
        // A new stiffness rescales the hold's weights with the matrix.
        sim.set_params(DynamicsParams { stiffness: 1e3, ..*sim.params() }).unwrap();
        assert!(sim.system().inertia().unwrap()[35] > 9.0 * sim.params().inertia(sim.masses())[35]);
        assert!(sim.hold(vec![35, 35], vec![start, start], 0.9).is_err(), "listed twice");
        assert!(sim.hold(vec![35], vec![start], 0.0).is_err(), "strength 0");
        sim.release();
        assert!(sim.grabbed().is_none());
        assert_eq!(sim.system().inertia().unwrap(), &sim.params().inertia(sim.masses())[..]);
        sim.hold(vec![35], vec![start], 0.5).unwrap();
        sim.grab(vec![35], vec![start], 0.5).unwrap();
        assert_eq!(
            sim.system().inertia().unwrap(),
            &sim.params().inertia(sim.masses())[..],
            "a force grab ends a hold"
        );
    }
}
