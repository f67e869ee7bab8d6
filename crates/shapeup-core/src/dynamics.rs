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

use crate::solver::{SolveError, System};
use glam::DVec3;
use std::time::Instant;

/// Time-stepping settings; the defaults are the math reference's.
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
    /// Local-global iterations per step (default 10).
    pub iterations: usize,
    /// Stop a step's iterations early below this relative energy change (default 0: off).
    pub tolerance: f64,
}

impl Default for DynamicsParams {
    fn default() -> Self {
        DynamicsParams {
            time_step: 1.0 / 60.0,
            stiffness: 100.0,
            damping: 0.0,
            gravity: DVec3::new(0.0, -9.81, 0.0),
            iterations: 10,
            tolerance: 0.0,
        }
    }
}

impl DynamicsParams {
    /// Checks every value, naming the first bad one.
    ///
    /// # Errors
    /// A one-line message: which setting, its value and the allowed range.
    pub fn validate(&self) -> Result<(), String> {
        let DynamicsParams { time_step, stiffness, damping, gravity, iterations, tolerance } = *self;
        if !(time_step.is_finite() && time_step > 0.0) {
            return Err(format!("time_step must be a finite number > 0, found {time_step}"));
        }
        if !(stiffness.is_finite() && stiffness > 0.0) {
            return Err(format!("stiffness must be a finite number > 0, found {stiffness}"));
        }
        if !(0.0..1.0).contains(&damping) {
            return Err(format!("damping must be in [0, 1), found {damping}"));
        }
        if !gravity.is_finite() {
            return Err(format!("gravity must be finite, found {gravity:?}"));
        }
        if iterations == 0 {
            return Err("iterations must be at least 1 in dynamic mode".into());
        }
        if !(tolerance.is_finite() && tolerance >= 0.0) {
            return Err(format!("tolerance must be a finite number ≥ 0, found {tolerance}"));
        }
        Ok(())
    }

    /// The inertia weight μ_i = m_i / (k h²) of each mass.
    pub fn inertia(&self, masses: &[f64]) -> Vec<f64> {
        let scale = 1.0 / (self.stiffness * self.time_step * self.time_step);
        masses.iter().map(|m| m * scale).collect()
    }
}

/// Why a simulation cannot be set up.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DynamicsError {
    /// A setting is out of range.
    #[error("dynamic mode: {0}")]
    BadParams(String),
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
    /// E(q) = Σ w_i ‖C_i q − p_i(q)‖² after the step (constraints only, without k or inertia).
    pub energy: f64,
    /// Iterations run (fewer than asked when the tolerance stopped them).
    pub iterations: usize,
    /// Seconds in local steps.
    pub local_seconds: f64,
    /// Seconds in global steps.
    pub global_seconds: f64,
    /// Seconds (re)assembling and factoring (only after a change of constraints or settings).
    pub setup_seconds: f64,
    /// Wall-clock seconds of the whole step.
    pub total_seconds: f64,
}

/// Vertices pulled towards points (the editor's mouse grab): each step moves their inertial
/// targets a fraction `strength` of the way from x_n + h v_n to the points — an external force
/// m (p − x_n − h v_n) · strength / h², so grabbing never refactors the matrix.
#[derive(Debug, Clone, PartialEq)]
pub struct Grab {
    /// The grabbed vertices.
    pub vertices: Vec<u32>,
    /// Where each is pulled (working frame).
    pub targets: Vec<DVec3>,
    /// Fraction in (0, 1] of the remaining distance closed per step by the force.
    pub strength: f64,
}

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
    grab: Option<Grab>,
    /// Inertial target and iterate buffers (reused every step).
    target: Vec<DVec3>,
    next: Vec<DVec3>,
    steps: u64,
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
        params.validate().map_err(DynamicsError::BadParams)?;
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
        system.set_inertia(Some(params.inertia(&masses)))?;
        Ok(Simulation {
            system,
            params,
            masses,
            velocities: vec![DVec3::ZERO; n],
            target: positions.clone(),
            next: positions.clone(),
            positions,
            forces: None,
            grab: None,
            steps: 0,
        })
    }

    /// Advances one time step (see the [module docs](self)).
    ///
    /// # Errors
    /// [`SolveError`] from the solver (e.g. non-finite positions); the state is unchanged then.
    pub fn step(&mut self) -> Result<StepReport, SolveError> {
        let started = Instant::now();
        let h = self.params.time_step;
        // 1. Inertial target s = x + h v + h² a_ext, q starts at s.
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
            *s = self.positions[i] + h * self.velocities[i] + h * h * a;
        }
        if let Some(grab) = &self.grab {
            for (&v, &p) in grab.vertices.iter().zip(&grab.targets) {
                let v = v as usize;
                let coasting = self.positions[v] + h * self.velocities[v];
                self.target[v] += grab.strength * (p - coasting);
            }
        }
        self.system.set_inertial_target(&self.target)?;
        self.next.copy_from_slice(&self.target);
        // 2. Local-global iterations on the inertia + constraint energy.
        let report = self.system.solve(&mut self.next, self.params.iterations, self.params.tolerance)?;
        // 3. Velocity update with damping, then the new positions.
        let keep = (1.0 - self.params.damping) / h;
        for ((v, x), q) in self.velocities.iter_mut().zip(&mut self.positions).zip(&self.next) {
            *v = keep * (*q - *x);
            *x = *q;
        }
        self.steps += 1;
        Ok(StepReport {
            energy: report.energies.last().copied().unwrap_or(0.0),
            iterations: report.energies.len(),
            local_seconds: report.local_seconds,
            global_seconds: report.global_seconds,
            setup_seconds: report.setup_seconds,
            total_seconds: started.elapsed().as_secs_f64(),
        })
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
        Ok(())
    }

    /// Changes the settings; a new time step or stiffness refactors the matrix numerically.
    ///
    /// # Errors
    /// [`DynamicsError::BadParams`].
    pub fn set_params(&mut self, params: DynamicsParams) -> Result<(), DynamicsError> {
        params.validate().map_err(DynamicsError::BadParams)?;
        self.system.set_inertia(Some(params.inertia(&self.masses)))?;
        self.params = params;
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

    /// Pulls `vertices` towards `targets` (working frame) from the next step on, closing a
    /// fraction `strength` ∈ (0, 1] of the distance per step (see [`Grab`]); replaces any
    /// previous grab. No refactorization.
    ///
    /// # Errors
    /// [`DynamicsError::BadState`] for mismatched lengths, an index out of range, a
    /// non-finite target or a strength outside (0, 1].
    pub fn grab(&mut self, vertices: Vec<u32>, targets: Vec<DVec3>, strength: f64) -> Result<(), DynamicsError> {
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
        self.grab = Some(Grab { vertices, targets, strength });
        Ok(())
    }

    /// Lets go of grabbed vertices.
    pub fn release(&mut self) {
        self.grab = None;
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
