//! The local-global solver (ShapeUp, Bouaziz et al. 2012).
//!
//! Minimizes E(q) = Σ_i w_i ‖C_i q − p_i(q)‖² by alternating
//! 1. the **local step**: P_i = p_i(q) for every constraint, in parallel, and
//! 2. the **global step**: solve (Σ w_i C_iᵀC_i) q = Σ w_i C_iᵀ P_i for x, y and z with a
//!    Cholesky factor computed once per change of the constraint set.
//!
//! E never increases from one iteration to the next. [`System`] owns the constraint groups;
//! adding or removing a group re-assembles and re-analyzes the matrix, changing a multiplier
//! only refactors it numerically, and moving a handle's targets changes neither.
//!
//! For Projective Dynamics ([`crate::dynamics`]) the same system takes per-vertex inertia
//! weights μ_i and an inertial target s: the global step then solves
//! (diag(μ) + Σ w_i C_iᵀC_i) q = μ s + Σ w_i C_iᵀ P_i.

mod anderson;
mod assemble;
mod cholesky;
mod global;
mod lbfgs;
mod local;
mod ordering;
mod triangular;

pub use crate::constraints::{ConstraintGroup, GroupId};
pub use cholesky::{FactorError, Factorization};

use crate::constraints::Constraint;
use anderson::Anderson;
use assemble::Assembly;
use cholesky::SparseCholesky;
use glam::DVec3;
use lbfgs::Lbfgs;
use rayon::prelude::*;
use std::ops::ControlFlow;
use std::time::Instant;

/// Solver settings. Each default is written once, here and in the scene contract.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverParams {
    /// Local-global iterations per solve (default 10).
    pub iterations: usize,
    /// Stop early when the relative energy change of an iteration is below this (default 0: off).
    pub tolerance: f64,
    /// Factorization layout (default: chosen by faer).
    pub factorization: Factorization,
    /// How the local-global iterates are combined (default: L-BFGS).
    pub acceleration: Acceleration,
    /// Anderson acceleration: how many previous iterations are mixed, m (default 5).
    pub anderson_window: usize,
    /// L-BFGS: how many previous steps and gradient changes shape the Hessian estimate, m
    /// (default 5).
    pub lbfgs_memory: usize,
}

impl SolverParams {
    /// Whether iterations are accelerated (Anderson with a window, or L-BFGS with a memory, of
    /// at least 1).
    pub fn is_accelerated(&self) -> bool {
        match self.acceleration {
            Acceleration::None => false,
            Acceleration::Anderson => self.anderson_window > 0,
            Acceleration::Lbfgs => self.lbfgs_memory > 0,
        }
    }
}

/// [`SolverParams::anderson_window`] by default: the m of Peng et al. 2018's experiments.
pub const DEFAULT_ANDERSON_WINDOW: usize = 5;

/// The largest [`SolverParams::anderson_window`] a scene may ask for: more mixed iterations
/// only cost time and conditioning.
pub const MAX_ANDERSON_WINDOW: usize = 50;

/// [`SolverParams::lbfgs_memory`] by default: the m of Liu, Bouaziz and Kavan 2017, and
/// within the 3–20 Nocedal and Wright recommend.
pub const DEFAULT_LBFGS_MEMORY: usize = 5;

/// The largest [`SolverParams::lbfgs_memory`] a scene may ask for: each pair costs four passes
/// over n points per iteration.
pub const MAX_LBFGS_MEMORY: usize = 50;

impl Default for SolverParams {
    fn default() -> Self {
        SolverParams {
            iterations: 10,
            tolerance: 0.0,
            factorization: Factorization::Auto,
            acceleration: Acceleration::default(),
            anderson_window: DEFAULT_ANDERSON_WINDOW,
            lbfgs_memory: DEFAULT_LBFGS_MEMORY,
        }
    }
}

/// How successive local-global iterates are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Acceleration {
    /// The plain iteration x_{k+1} = G(x_k): one local and one global step per iteration.
    None,
    /// Anderson acceleration (Peng, Deng, Zhang, Pauly, SIGGRAPH 2018): x_{k+1} mixes the last
    /// m iterates of G; a mixed iterate that does not lower the energy is replaced by the plain
    /// one (and the history restarts), so the energy never increases. An iteration costs one
    /// more energy evaluation, and a rejected one also a second local step.
    Anderson,
    /// L-BFGS with the global matrix as initial Hessian (Liu, Bouaziz, Kavan, ACM TOG 2017): the
    /// plain step is a gradient step preconditioned by the global matrix, and the last m
    /// iterates' gradients refine it into a quasi-Newton step; a step that misses the Armijo
    /// condition is replaced by the plain one (and the history restarts), so the energy never
    /// increases. An iteration costs one gradient (a right-hand-side pass) more than a plain
    /// one, and a rejected one a second solve and local step. The default: on the standard
    /// scenarios it reaches a converged shape in the fewest iterations and the least time (the
    /// README's performance section), and matches Anderson per time step in dynamic mode.
    #[default]
    Lbfgs,
}

impl Acceleration {
    /// Every kind, in the order the CLI and the editor list them.
    pub const ALL: [Acceleration; 3] = [Acceleration::Lbfgs, Acceleration::Anderson, Acceleration::None];

    /// The scene's and the CLI's name (`"anderson"`, `"lbfgs"`, `"none"`).
    pub fn name(self) -> &'static str {
        match self {
            Acceleration::None => "none",
            Acceleration::Anderson => "anderson",
            Acceleration::Lbfgs => "lbfgs",
        }
    }

    /// The kind named `name` ([`Acceleration::name`]).
    pub fn from_name(name: &str) -> Option<Acceleration> {
        Acceleration::ALL.into_iter().find(|a| a.name() == name)
    }
}

/// An error from the solver. Messages are one line and say what to do.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    /// No constraint at all.
    #[error("there are no constraints to solve (add a shape constraint and a position handle)")]
    NoConstraints,
    /// A connected piece of constrained vertices has no position-like constraint (static mode).
    #[error(
        "singular system: a connected piece of {piece_size} vertices (e.g. vertex {vertex}) has no position \
         constraint, so it can move freely ({num_pieces} piece(s) in all); add a position group that touches it"
    )]
    Unanchored {
        /// Number of vertices of the piece.
        piece_size: usize,
        /// One of its vertices (original index).
        vertex: usize,
        /// Number of connected pieces.
        num_pieces: usize,
    },
    /// The factorization found the matrix singular or indefinite.
    #[error(
        "singular system: {0}; some vertices are not held in place by the constraints (add a position \
         group, or a shape constraint over all vertices)"
    )]
    Singular(FactorError),
    /// The factorization could not be built: its factor overflows 32-bit indices or memory (a
    /// mesh of millions of vertices, or constraints that couple wide neighbourhoods).
    #[error(
        "the system is too large to factor ({0}): use fewer vertices, or constraints that couple fewer \
         of them (springs or strain instead of bending)"
    )]
    TooLarge(FactorError),
    /// The solve produced NaN or infinity.
    #[error("the solve produced non-finite positions (the system is numerically singular); check the weights")]
    NonFinite,
    /// The energy overflowed (targets, forces or coordinates too large for f64).
    #[error(
        "the energy is not a finite number (targets, gravity or coordinates too large); check the translations, targets and gravity"
    )]
    NonFiniteEnergy,
    /// A negative or non-finite multiplier.
    #[error("group \"{name}\": weight must be a finite number ≥ 0, found {value}")]
    BadWeight {
        /// Group name.
        name: String,
        /// The value given.
        value: f64,
    },
    /// A group id that is not (or no longer) in the system.
    #[error("no constraint group with id {0}")]
    UnknownGroup(u32),
    /// Targets for a group that is not a position group, or of the wrong count.
    #[error("group \"{name}\" {problem}")]
    BadTargets {
        /// Group name.
        name: String,
        /// What is wrong.
        problem: String,
    },
    /// A hard group of a type that cannot hold its vertices exactly.
    #[error("group \"{name}\" cannot be hard: only position groups hold their vertices exactly, not {kind}")]
    NotHardable {
        /// Group name.
        name: String,
        /// Its constraint type.
        kind: String,
    },
    /// Positions of the wrong length.
    #[error("expected {expected} positions, got {found}")]
    WrongLength {
        /// Vertices of the system.
        expected: usize,
        /// Length given.
        found: usize,
    },
}

impl SolveError {
    /// A failed factorization: a non-positive pivot is a singular system; anything else (faer's
    /// index overflow, an allocation) is a system too large, not a missing handle.
    fn from_factor(e: FactorError) -> Self {
        match e {
            FactorError::NotPositiveDefinite(_) => SolveError::Singular(e),
            FactorError::Other(_) => SolveError::TooLarge(e),
        }
    }
}

/// What must be redone before the next iteration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stale {
    /// Factorization up to date.
    Fresh,
    /// Only multipliers changed: numeric refactorization on the same pattern.
    Values,
    /// Groups were added or removed: re-assemble, re-analyze, refactor.
    Pattern,
}

/// Energy of a configuration, in total and per group (each including its multiplier).
#[derive(Debug, Clone, PartialEq)]
pub struct Energy {
    /// E(q) = Σ_i w_i ‖C_i q − p_i(q)‖².
    pub total: f64,
    /// (group, its share of E) for every group, in id order.
    pub per_group: Vec<(GroupId, f64)>,
}

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
}

/// The ShapeUp system: constraint groups over n vertices, their assembled matrix, its factor and
/// the buffers an iteration uses (allocated when the constraint set changes, never per iteration).
#[derive(Debug)]
pub struct System {
    num_vertices: usize,
    params: SolverParams,
    /// Groups by id; removed ones leave `None` so ids stay stable.
    slots: Vec<Option<ConstraintGroup>>,
    stale: Stale,
    /// Slot index of each group in assembly order.
    order: Vec<usize>,
    assembly: Assembly,
    factor: Option<SparseCholesky>,
    /// Where each entry of C goes in the right-hand side, with its weight.
    rhs_map: global::RhsMap,
    /// Projections P, one row per constraint row.
    projections: Vec<DVec3>,
    /// The q the projections were computed at (empty when they are stale): a solve that starts
    /// from that q again (the next chunk of an interactive convergence) reuses them instead of
    /// running a whole local step, re-projecting only the groups in `retargeted`.
    projected_at: Vec<DVec3>,
    /// Slots whose targets moved since the projections were computed.
    retargeted: Vec<usize>,
    /// The fixed-point map changed since the last solve (weights, targets, groups, inertia):
    /// the acceleration's history no longer applies.
    map_changed: bool,
    anderson: Anderson,
    lbfgs: Lbfgs,
    /// The accelerated iterations' buffers, kept between solves.
    scratch: Scratch,
    /// C q, for energies.
    cq: Vec<DVec3>,
    /// Right-hand side / solution over solved vertices in the factor's permuted order, a
    /// vertex's x, y, z side by side.
    rhs: Vec<[f64; 4]>,
    /// Per extra thread, its share of the right-hand side (kept between iterations).
    rhs_partials: Vec<Vec<[f64; 4]>>,
    assembled: bool,
    /// Inertia weight μ_i of every vertex (dynamic mode), or `None` (static mode).
    inertia: Option<Vec<f64>>,
    /// The inertial target s (all vertices), kept to rebuild `constant_rhs` after re-assembly.
    inertial_target: Vec<DVec3>,
    /// The held vertices' share of the right-hand side per solved vertex,
    /// −Σ_r w_r c_{r,v} Σ_{f fixed} c_{r,f} x_f; empty when no vertex is held. Recomputed only
    /// when held points, weights or the assembly change, not on every time step.
    held_rhs: Vec<DVec3>,
    /// Vertices held by hard groups and where (the last hard group holding a vertex wins).
    held: Vec<(u32, DVec3)>,
    /// The loads' share of the right-hand side per solved vertex, Σ g f_v over the groups'
    /// [`Constraint::load`]s; empty when there is none. Recomputed when weights or the
    /// assembly change.
    load_rhs: Vec<DVec3>,
    /// What the loads are multiplied by besides their group's multiplier: 1 in static mode,
    /// 1/k in dynamic mode (k the stiffness, which scales the constraint terms but not a force).
    load_scale: f64,
    /// Numeric factorizations so far.
    factorizations: u64,
    /// What does not change between iterations per solved vertex: μ s (dynamic mode) minus the
    /// fixed vertices' share, −Σ_r w_r c_{r,v} Σ_{f fixed} c_{r,f} x_f; empty when neither.
    constant_rhs: Vec<DVec3>,
}

impl System {
    /// An empty system over `num_vertices` vertices.
    pub fn new(num_vertices: usize, params: SolverParams) -> Self {
        System {
            num_vertices,
            params,
            slots: Vec::new(),
            stale: Stale::Pattern,
            order: Vec::new(),
            assembly: Assembly::default(),
            factor: None,
            rhs_map: global::RhsMap::default(),
            projections: Vec::new(),
            projected_at: Vec::new(),
            retargeted: Vec::new(),
            map_changed: true,
            anderson: Anderson::default(),
            lbfgs: Lbfgs::default(),
            scratch: Scratch::default(),
            cq: Vec::new(),
            rhs: Vec::new(),
            rhs_partials: Vec::new(),
            assembled: false,
            inertia: None,
            inertial_target: Vec::new(),
            held_rhs: Vec::new(),
            held: Vec::new(),
            load_rhs: Vec::new(),
            load_scale: 1.0,
            factorizations: 0,
            constant_rhs: Vec::new(),
        }
    }

    /// Sets per-vertex inertia weights μ_i ≥ 0 (dynamic mode: μ_i = m_i / (k h²)), adding
    /// diag(μ) to the global matrix and μ s to its right-hand side (see
    /// [`System::set_inertial_target`]); `None` goes back to the static problem. Switching
    /// modes re-assembles (every vertex is solved in dynamic mode); new values only refactor.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`], or [`SolveError::BadWeight`] for a negative or non-finite μ.
    pub fn set_inertia(&mut self, inertia: Option<Vec<f64>>) -> Result<(), SolveError> {
        if let Some(mu) = &inertia {
            self.check_length(mu)?;
            if let Some(&bad) = mu.iter().find(|m| crate::constraints::check_weight(**m).is_err()) {
                return Err(SolveError::BadWeight { name: "inertia".into(), value: bad });
            }
        }
        match (&self.inertia, &inertia) {
            (None, None) => return Ok(()),
            (Some(old), Some(new)) if old == new => return Ok(()),
            // Which vertices have inertia decides which are solved.
            (Some(old), Some(new)) if old.iter().zip(new).all(|(a, b)| (*a > 0.0) == (*b > 0.0)) => {
                self.mark(Stale::Values)
            }
            (Some(_), Some(_)) => self.mark(Stale::Pattern),
            _ => self.mark(Stale::Pattern),
        }
        self.inertia = inertia;
        Ok(())
    }

    /// The inertia weights, if in dynamic mode.
    pub fn inertia(&self) -> Option<&[f64]> {
        self.inertia.as_deref()
    }

    /// Sets the inertial target s (all vertices, working frame) that diag(μ) pulls towards;
    /// ignored in static mode. Changing it needs no refactorization.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`].
    pub fn set_inertial_target(&mut self, target: &[DVec3]) -> Result<(), SolveError> {
        self.check_length(target)?;
        self.inertial_target.clear();
        self.inertial_target.extend_from_slice(target);
        self.update_constant_rhs();
        self.map_changed = true;
        Ok(())
    }

    /// [`System::constant_rhs`](Self): μ s (dynamic mode) plus the held vertices' share, in one
    /// pass over the solved vertices (this runs once per time step).
    fn update_constant_rhs(&mut self) {
        self.constant_rhs.clear();
        let a = &self.assembly;
        if self.assembled && !self.load_rhs.is_empty() {
            // Loads are rare and static: the general form, without the fast paths below.
            self.constant_rhs.extend(a.solved.iter().enumerate().map(|(s, &v)| {
                let v = v as usize;
                let inertial = match &self.inertia {
                    Some(mu) => mu[v] * self.inertial_target.get(v).copied().unwrap_or(DVec3::ZERO),
                    None => DVec3::ZERO,
                };
                inertial + self.held_rhs.get(s).copied().unwrap_or(DVec3::ZERO) + self.load_rhs[s]
            }));
            return;
        }
        match (&self.inertia, self.held_rhs.is_empty()) {
            _ if !self.assembled => {}
            (None, true) => {}
            (None, false) => self.constant_rhs.extend_from_slice(&self.held_rhs),
            (Some(mu), held_is_empty) => {
                let target = &self.inertial_target;
                self.constant_rhs.extend(a.solved.iter().enumerate().map(|(s, &v)| {
                    let v = v as usize;
                    let inertial = mu[v] * target.get(v).copied().unwrap_or(DVec3::ZERO);
                    if held_is_empty { inertial } else { inertial + self.held_rhs[s] }
                }));
            }
        }
    }

    /// Sets the factor every load is multiplied by besides its group's multiplier (1 by
    /// default; dynamic mode sets 1/k so that a load is the physical force g f).
    ///
    /// # Errors
    /// [`SolveError::BadWeight`] for a negative or non-finite scale.
    pub fn set_load_scale(&mut self, scale: f64) -> Result<(), SolveError> {
        check_weight("load scale", scale)?;
        if scale != self.load_scale {
            self.load_scale = scale;
            self.update_load_rhs();
            self.update_constant_rhs();
            self.map_changed = true;
        }
        Ok(())
    }

    /// [`System::load_rhs`](Self): Σ g f_v per solved vertex over every group's loads.
    fn update_load_rhs(&mut self) {
        self.load_rhs.clear();
        if !self.assembled {
            return;
        }
        let a = &self.assembly;
        let mut any = false;
        for group in self.slots.iter().flatten() {
            for load in group.constraints.iter().filter_map(|c| c.load()) {
                if !any {
                    self.load_rhs.resize(a.num_solved(), DVec3::ZERO);
                    any = true;
                }
                for (&v, f) in load.vertices.iter().zip(load.forces) {
                    if let Some(b) = a.solved_index.get(v as usize).and_then(|&s| self.load_rhs.get_mut(s as usize)) {
                        *b += self.load_scale * group.multiplier * *f;
                    }
                }
            }
        }
    }

    /// The loads' share of E at q: −2 Σ g f_v · (q_v − x⁰_v) over the groups in `slots`.
    fn load_energy(&self, q: &[DVec3], slots: impl IntoIterator<Item = usize>) -> f64 {
        let mut e = 0.0;
        for group in slots.into_iter().filter_map(|s| self.slots.get(s).and_then(Option::as_ref)) {
            for load in group.constraints.iter().filter_map(|c| c.load()) {
                e += self.load_scale * group.multiplier * load.energy(q);
            }
        }
        e
    }

    /// [`System::held_rhs`](Self) from the held vertices' points and the current weights, then
    /// the constant right-hand side.
    fn update_held_rhs(&mut self) {
        self.held_rhs.clear();
        let a = &self.assembly;
        if self.assembled && !self.held.is_empty() {
            let mut at = vec![DVec3::ZERO; self.num_vertices];
            for &(v, x) in &self.held {
                at[v as usize] = x;
            }
            // Per row, the fixed vertices' part of C_r x; then minus Cᵀ W of it per solved vertex.
            let fixed_part: Vec<DVec3> = (0..a.num_rows())
                .map(|r| {
                    (a.c_ptr[r]..a.c_ptr[r + 1])
                        .filter(|&k| a.is_fixed(a.c_col[k] as usize))
                        .map(|k| a.c_val[k] * at[a.c_col[k] as usize])
                        .sum()
                })
                .collect();
            self.held_rhs.resize(a.num_solved(), DVec3::ZERO);
            for (r, fixed) in fixed_part.iter().enumerate().filter(|(_, f)| **f != DVec3::ZERO) {
                for k in a.c_ptr[r]..a.c_ptr[r + 1] {
                    if let Some(b) = self.held_rhs.get_mut(a.solved_index[a.c_col[k] as usize] as usize) {
                        *b -= self.rhs_map.weighted[k] * *fixed;
                    }
                }
            }
        }
        self.update_constant_rhs();
    }

    /// Moves the held vertices of `q` to their points.
    fn pin_held(&self, q: &mut [DVec3]) {
        for &(v, x) in &self.held {
            q[v as usize] = x;
        }
    }

    /// The hard groups' vertices and points, in slot order.
    fn collect_held(&self) -> Result<Vec<(u32, DVec3)>, SolveError> {
        let mut held = Vec::new();
        for group in self.slots.iter().flatten().filter(|g| g.hard) {
            for c in &group.constraints {
                let (vertices, points) = c
                    .held_points()
                    .ok_or_else(|| SolveError::NotHardable { name: group.name.clone(), kind: group.kind.clone() })?;
                held.extend(vertices.iter().copied().zip(points.iter().copied()));
            }
        }
        Ok(held)
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.num_vertices
    }

    /// The solver settings.
    pub fn params(&self) -> &SolverParams {
        &self.params
    }

    /// Changes the settings (a new factorization layout re-analyzes the matrix).
    pub fn set_params(&mut self, params: SolverParams) {
        if params.factorization != self.params.factorization {
            self.mark(Stale::Pattern);
        }
        self.params = params;
    }

    /// Adds a group; the next solve re-assembles the system.
    ///
    /// # Errors
    /// [`SolveError::BadWeight`] for a negative or non-finite multiplier.
    pub fn add_group(&mut self, group: ConstraintGroup) -> Result<GroupId, SolveError> {
        check_weight(&group.name, group.multiplier)?;
        self.slots.push(Some(group));
        self.mark(Stale::Pattern);
        Ok(GroupId(self.slots.len() as u32 - 1))
    }

    /// Removes a group and returns it; the next solve re-assembles the system.
    pub fn remove_group(&mut self, id: GroupId) -> Option<ConstraintGroup> {
        let removed = self.slots.get_mut(id.0 as usize)?.take();
        if removed.is_some() {
            self.mark(Stale::Pattern);
        }
        removed
    }

    /// The group with this id.
    pub fn group(&self, id: GroupId) -> Option<&ConstraintGroup> {
        self.slots.get(id.0 as usize)?.as_ref()
    }

    /// Every group with its id, in id order.
    pub fn groups(&self) -> impl Iterator<Item = (GroupId, &ConstraintGroup)> {
        self.slots.iter().enumerate().filter_map(|(i, g)| g.as_ref().map(|g| (GroupId(i as u32), g)))
    }

    /// Total number of constraints.
    pub fn num_constraints(&self) -> usize {
        self.groups().map(|(_, g)| g.constraints.len()).sum()
    }

    /// Sets a group's multiplier g; the next solve refactors numerically (same pattern).
    ///
    /// # Errors
    /// Unknown group, or a negative or non-finite weight.
    pub fn set_multiplier(&mut self, id: GroupId, multiplier: f64) -> Result<(), SolveError> {
        let group = self.slots.get_mut(id.0 as usize).and_then(Option::as_mut).ok_or(SolveError::UnknownGroup(id.0))?;
        check_weight(&group.name, multiplier)?;
        if group.multiplier != multiplier {
            group.multiplier = multiplier;
            self.mark(Stale::Values);
        }
        Ok(())
    }

    /// Makes a group hard or soft again ([`ConstraintGroup::hard`]); the next solve re-assembles.
    ///
    /// # Errors
    /// Unknown group, or [`SolveError::NotHardable`] for a group that cannot hold its vertices.
    pub fn set_hard(&mut self, id: GroupId, hard: bool) -> Result<(), SolveError> {
        let group = self.slots.get_mut(id.0 as usize).and_then(Option::as_mut).ok_or(SolveError::UnknownGroup(id.0))?;
        if hard && group.constraints.iter().any(|c| c.held_points().is_none()) {
            return Err(SolveError::NotHardable { name: group.name.clone(), kind: group.kind.clone() });
        }
        if group.hard != hard {
            group.hard = hard;
            self.mark(Stale::Pattern);
        }
        Ok(())
    }

    /// Moves the targets of a group with targets (a handle: its constraints'
    /// [`Constraint::held_points`]), working frame, one per held vertex in constraint order
    /// ([`crate::constraints::held_vertices`]); no refactorization is needed.
    ///
    /// # Errors
    /// Unknown group, a group without targets, or a target count different from its held
    /// vertex count.
    pub fn set_targets(&mut self, id: GroupId, targets: &[DVec3]) -> Result<(), SolveError> {
        let group = self.slots.get_mut(id.0 as usize).and_then(Option::as_mut).ok_or(SolveError::UnknownGroup(id.0))?;
        let name = group.name.clone();
        let bad = |problem: String| SolveError::BadTargets { name: name.clone(), problem };
        let counts: Vec<usize> =
            group.constraints.iter().map(|c| c.held_points().map_or(0, |(v, _)| v.len())).collect();
        let expected: usize = counts.iter().sum();
        if expected == 0 {
            return Err(bad(format!("has no targets (a {} group)", group.kind)));
        }
        if targets.len() != expected {
            return Err(bad(format!("has {expected} vertices but {} targets were given", targets.len())));
        }
        let mut start = 0;
        for (c, &k) in group.constraints.iter_mut().zip(&counts) {
            if k > 0 && !c.set_targets(&targets[start..start + k]) {
                return Err(bad("does not take targets".into()));
            }
            start += k;
        }
        if group.hard {
            // Held points: only the right-hand side changes.
            if self.assembled {
                self.held = self.collect_held()?;
                self.update_held_rhs();
            }
        } else {
            self.retargeted.push(id.0 as usize);
        }
        self.map_changed = true;
        Ok(())
    }

    fn mark(&mut self, stale: Stale) {
        self.map_changed = true;
        self.stale = match (self.stale, stale) {
            (Stale::Pattern, _) | (_, Stale::Pattern) => Stale::Pattern,
            _ => Stale::Values,
        };
        if stale == Stale::Pattern {
            self.assembled = false;
        }
    }

    fn multipliers(&self) -> Vec<f64> {
        self.order.iter().map(|&s| self.slots[s].as_ref().map_or(0.0, |g| g.multiplier)).collect()
    }

    /// Stacks the rows of every group (once per change of the constraint set).
    fn ensure_assembled(&mut self) -> Result<(), SolveError> {
        if self.assembled {
            return Ok(());
        }
        self.order = (0..self.slots.len()).filter(|&s| self.slots[s].is_some()).collect();
        let lists: Vec<&[Box<dyn Constraint>]> =
            self.order.iter().filter_map(|&s| self.slots[s].as_ref().map(|g| g.constraints.as_slice())).collect();
        if lists.iter().all(|l| l.is_empty()) && self.inertia.is_none() {
            return Err(SolveError::NoConstraints);
        }
        let hard: Vec<bool> = self.order.iter().map(|&s| self.slots[s].as_ref().is_some_and(|g| g.hard)).collect();
        self.held = self.collect_held()?;
        let mut fixed = Vec::new();
        if !self.held.is_empty() {
            fixed = vec![false; self.num_vertices];
            for &(v, _) in &self.held {
                *fixed
                    .get_mut(v as usize)
                    .ok_or(SolveError::WrongLength { expected: self.num_vertices, found: v as usize + 1 })? = true;
            }
        }
        self.assembly = Assembly::new(self.num_vertices, &lists, &hard, fixed, self.inertia.as_deref());
        let rows = self.assembly.num_rows();
        self.projections = vec![DVec3::ZERO; rows];
        self.projected_at.clear();
        self.cq = vec![DVec3::ZERO; rows];
        self.rhs = vec![[0.0; 4]; self.assembly.num_solved()];
        self.factor = None;
        self.assembled = true;
        self.update_weights();
        self.update_load_rhs();
        self.update_held_rhs();
        Ok(())
    }

    /// Applies the current multipliers to W C: g · w_r · c_rk per entry of C.
    fn update_weights(&mut self) {
        let g = self.multipliers();
        let a = &self.assembly;
        self.rhs_map.weighted.clear();
        for r in 0..a.num_rows() {
            let w = g[a.row_group[r] as usize] * a.row_weight[r];
            self.rhs_map.weighted.extend(a.c_val[a.c_ptr[r]..a.c_ptr[r + 1]].iter().map(|c| w * c));
        }
    }

    /// Where each entry of C lands in the factor's permuted right-hand side (after a new
    /// symbolic analysis).
    fn update_rhs_slots(&mut self) {
        let (a, Some(factor)) = (&self.assembly, &self.factor) else { return };
        let forward = factor.permutation();
        let mut position = vec![u32::MAX; a.num_solved()];
        for (i, &s) in forward.iter().enumerate() {
            position[s as usize] = i as u32;
        }
        self.rhs_map.slot = a
            .c_col
            .iter()
            .map(|&v| position.get(a.solved_index[v as usize] as usize).copied().unwrap_or(u32::MAX))
            .collect();
    }

    /// Brings the factorization up to date: re-assembly and symbolic analysis after the
    /// constraint set changed, numeric refactorization after a multiplier changed.
    ///
    /// # Errors
    /// [`SolveError::Unanchored`] or [`SolveError::Singular`] for a singular system.
    pub fn prepare(&mut self) -> Result<(), SolveError> {
        if self.stale == Stale::Fresh {
            return Ok(());
        }
        self.ensure_assembled()?;
        let g = self.multipliers();
        if self.inertia.is_none() {
            // Inertia anchors every vertex in dynamic mode.
            self.assembly.check_anchored(&g)?;
        }
        if self.factor.is_none() {
            let a = &self.assembly;
            self.factor = Some(
                SparseCholesky::analyze(
                    a.num_solved(),
                    a.lhs_col_ptr.clone(),
                    a.lhs_row_idx.clone(),
                    self.params.factorization,
                )
                .map_err(SolveError::from_factor)?,
            );
            self.update_rhs_slots();
        }
        self.update_weights();
        self.update_load_rhs();
        self.update_held_rhs();
        let mut values = vec![0.0; self.assembly.lhs_row_idx.len()];
        for (group, &gk) in self.assembly.group_lhs.iter().zip(&g) {
            values.iter_mut().zip(group).for_each(|(v, x)| *v += gk * x);
        }
        if let Some(mu) = &self.inertia {
            for (s, &v) in self.assembly.solved.iter().enumerate() {
                values[self.assembly.slot(s, s)] += mu[v as usize];
            }
        }
        if let Some(factor) = self.factor.as_mut() {
            factor.factorize(&values).map_err(SolveError::from_factor)?;
            self.factorizations += 1;
        }
        self.stale = Stale::Fresh;
        Ok(())
    }

    /// One local-global iteration from q (positions of all n vertices, working frame).
    ///
    /// # Errors
    /// As [`System::prepare`], or [`SolveError::NonFinite`].
    pub fn step(&mut self, q: &mut [DVec3]) -> Result<(), SolveError> {
        self.check_length(q)?;
        self.prepare()?;
        self.pin_held(q);
        // Local step: P_i = p_i(q) for every constraint, in parallel.
        self.project(q);
        // Global step: solve (Σ w_i C_iᵀC_i) q = Σ w_i C_iᵀ P_i for x, y and z.
        self.global_step(q)
    }

    /// Runs `iterations` local-global iterations from q, recording E after each; stops early
    /// when `tolerance` > 0 and an iteration meets it ([`is_converged`]: the relative energy
    /// change is at most `tolerance`, or E is round-off: [`SolveReport::energy_floor`]).
    ///
    /// # Errors
    /// As [`System::step`].
    pub fn solve(&mut self, q: &mut [DVec3], iterations: usize, tolerance: f64) -> Result<SolveReport, SolveError> {
        self.solve_with(q, iterations, tolerance, |_, _| ControlFlow::Continue(()))
    }

    /// `iterations` plain local-global iterations from q without evaluating E: each a local
    /// step at q then a global step, the work of ShapeOp's and the DGP core's loops, and no
    /// more. For fixed-count runs that need no energy (a time step without a tolerance or a
    /// report): [`System::solve`] adds a local step at the result and E after every iteration.
    /// Whatever [`SolverParams::acceleration`] says, the iteration is the plain one (the
    /// acceleration's safeguard needs E). `report.energies` stays empty.
    ///
    /// # Errors
    /// As [`System::step`].
    pub fn iterate(&mut self, q: &mut [DVec3], iterations: usize) -> Result<SolveReport, SolveError> {
        let (mut report, at_last_projection) = self.begin_solve(q)?;
        // Plain iterates are not the accelerated run's: a later accelerated solve starts afresh.
        self.map_changed = true;
        for k in 0..iterations {
            timed(&mut report.local_seconds, || match k {
                0 => self.project_unless_current(q, at_last_projection),
                _ => self.project(q),
            });
            timed(&mut report.global_seconds, || self.global_step(q))?;
        }
        Ok(report)
    }

    /// What every solve does first: checks q's length, brings the factorization up to date and
    /// puts the held vertices on their points (timed as setup). Also says whether the last
    /// projections were computed at this very q (false after a re-assembly), compared once.
    fn begin_solve(&mut self, q: &mut [DVec3]) -> Result<(SolveReport, bool), SolveError> {
        self.check_length(q)?;
        let mut report = SolveReport::default();
        timed(&mut report.setup_seconds, || {
            self.prepare()?;
            self.pin_held(q);
            Ok::<_, SolveError>(())
        })?;
        let at_last_projection = self.projected_at.as_slice() == &q[..];
        Ok((report, at_last_projection))
    }

    /// [`System::solve`], calling `after_iteration(k, E_k)` after iteration k (from 1): it can
    /// report progress, or stop the solve with [`ControlFlow::Break`] (a newer target in an
    /// editor, an interrupt), leaving q at that iteration's result. The report then holds the
    /// iterations that ran.
    ///
    /// # Errors
    /// As [`System::step`].
    pub fn solve_with(
        &mut self,
        q: &mut [DVec3],
        iterations: usize,
        tolerance: f64,
        mut after_iteration: impl FnMut(usize, f64) -> ControlFlow<()>,
    ) -> Result<SolveReport, SolveError> {
        let map_changed = std::mem::take(&mut self.map_changed);
        let (mut report, at_last_projection) = self.begin_solve(q)?;
        // Whether this solve continues the last one: same map, starting where it stopped.
        let continuing = !map_changed && at_last_projection;
        timed(&mut report.local_seconds, || self.project_unless_current(q, at_last_projection));
        let energy = self.energy_of_projections(q);
        if !energy.is_finite() {
            return Err(SolveError::NonFiniteEnergy);
        }
        report.initial_energy = energy;
        report.energy_floor = self.energy_floor(q);
        let run = Run { iterations, tolerance, initial_energy: energy };
        // Taken out while a loop borrows the system, and put back whatever the outcome.
        let mut scratch = std::mem::take(&mut self.scratch);
        let result = match self.params.acceleration {
            Acceleration::Anderson if self.params.is_accelerated() => {
                if !continuing {
                    self.anderson.reset();
                }
                self.iterate_anderson(q, &mut scratch, run, &mut after_iteration, &mut report)
            }
            Acceleration::Lbfgs if self.params.is_accelerated() && self.factor.is_some() => {
                if !continuing {
                    self.lbfgs.reset();
                }
                self.iterate_lbfgs(q, &mut scratch, run, &mut after_iteration, &mut report)
            }
            _ => self.iterate_plain(q, run, &mut after_iteration, &mut report),
        };
        self.scratch = scratch;
        result.map(|()| report)
    }

    /// The plain iteration: global step from the last projections, then the local step at the
    /// new q, whose projections give E(q) and feed the next global step.
    fn iterate_plain(
        &mut self,
        q: &mut [DVec3],
        run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<(), SolveError> {
        let tolerance = run.tolerance;
        let mut previous = run.initial_energy + self.inertial_energy(q);
        for _ in 0..run.iterations {
            timed(&mut report.global_seconds, || self.global_step(q))?;
            timed(&mut report.local_seconds, || self.project(q));
            let energy = self.energy_of_projections(q);
            let objective = energy + self.inertial_energy(q);
            let (converged, stop) =
                record_iteration(report, &mut previous, energy, objective, tolerance, after_iteration)?;
            if converged || stop {
                break;
            }
        }
        Ok(())
    }

    /// Anderson-accelerated iteration (see [`anderson`]): x_{k+1} is the mixed iterate when its
    /// objective (E, plus the inertial term in dynamic mode) is below x_k's, else the plain
    /// G(x_k), which never raises it; the history restarts after a rejection.
    fn iterate_anderson(
        &mut self,
        q: &mut [DVec3],
        scratch: &mut Scratch,
        run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<(), SolveError> {
        let n = q.len();
        self.anderson.resize(n, self.params.anderson_window);
        let (plain, mixed) = (&mut scratch.plain, &mut scratch.mixed);
        plain.resize(n, DVec3::ZERO);
        mixed.resize(n, DVec3::ZERO);
        let tolerance = run.tolerance;
        let mut objective = run.initial_energy + self.inertial_energy(q);
        let mut previous = objective;
        for _ in 0..run.iterations {
            plain.copy_from_slice(q);
            timed(&mut report.global_seconds, || self.global_step(plain))?;
            let t = Instant::now();
            let is_mixed = self.anderson.mix(q, plain, mixed);
            let (mut energy, mut mixed_objective) = self.evaluate(mixed);
            let accepted_mixed = is_mixed && mixed_objective < objective;
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
            objective = mixed_objective;
            let (mut converged, stop) =
                record_iteration(report, &mut previous, energy, objective, tolerance, after_iteration)?;
            if converged && accepted_mixed {
                // A mixed step can creep along a flat valley by less than the tolerance: only
                // a plain iteration, the one the tolerance is defined on, may end the solve.
                self.anderson.reset();
                converged = false;
            }
            if converged || stop {
                break;
            }
        }
        Ok(())
    }

    /// L-BFGS iteration (see [`lbfgs`]): x_{k+1} = x_k + d_k, d_k = −H_k g_k, when it meets the
    /// Armijo condition on the objective (E, plus the inertial term in dynamic mode), else the
    /// plain step x_k − A⁻¹ g_k = G(x_k), which never raises it; the history restarts after a
    /// rejection.
    fn iterate_lbfgs(
        &mut self,
        q: &mut [DVec3],
        scratch: &mut Scratch,
        run: Run,
        after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
        report: &mut SolveReport,
    ) -> Result<(), SolveError> {
        let solved = self.assembly.num_solved();
        self.lbfgs.resize(solved, self.params.lbfgs_memory);
        let Scratch { plain: trial, x, g, d, .. } = scratch;
        trial.resize(q.len(), DVec3::ZERO);
        for b in [&mut *x, &mut *g, &mut *d] {
            b.resize(solved, [0.0; 4]);
        }
        /// Armijo's sufficient-decrease constant c₁ (Nocedal & Wright's usual 1e-4).
        const ARMIJO: f64 = 1e-4;
        let tolerance = run.tolerance;
        let mut objective = run.initial_energy + self.inertial_energy(q);
        let mut previous = objective;
        // The next iteration is a plain step that confirms a quasi-Newton step's convergence.
        let mut confirm = false;
        for _ in 0..run.iterations {
            let t = Instant::now();
            // g at q: the projections and C q of the energy just evaluated there.
            self.half_gradient(q, g);
            let Some(factor) = self.factor.as_mut() else { break };
            global::gather(&self.assembly, factor.permutation(), q, x);
            let quasi_newton = self.lbfgs.first_loop(x, g, d, confirm);
            factor.solve_permuted_in_place(d);
            if quasi_newton {
                self.lbfgs.second_loop(d);
            }
            // The directional derivative of the objective along −d is −2 gᵀd.
            let slope = -2.0 * lbfgs::dot(g, d);
            self.step_to(x, d, q, trial)?;
            report.global_seconds += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let (mut energy, mut trial_objective) = self.evaluate(trial);
            report.local_seconds += t.elapsed().as_secs_f64();
            let accepted = !quasi_newton || (slope < 0.0 && trial_objective <= objective + ARMIJO * slope);
            if !accepted {
                // The plain iterate x − A⁻¹ g = G(x): E(G(x)) ≤ E(x) by the local-global argument.
                self.lbfgs.reset();
                report.rejected += 1;
                let t = Instant::now();
                d.copy_from_slice(g);
                if let Some(factor) = self.factor.as_mut() {
                    factor.solve_permuted_in_place(d);
                }
                self.step_to(x, d, q, trial)?;
                report.global_seconds += t.elapsed().as_secs_f64();
                let t = Instant::now();
                (energy, trial_objective) = self.evaluate(trial);
                report.local_seconds += t.elapsed().as_secs_f64();
            }
            q.copy_from_slice(trial);
            objective = trial_objective;
            let (mut converged, stop) =
                record_iteration(report, &mut previous, energy, objective, tolerance, after_iteration)?;
            confirm = converged && accepted && quasi_newton;
            if confirm {
                // As with Anderson, only a plain iteration, the one the tolerance is defined on,
                // may end the solve: the next one is plain. Unlike Anderson's mixing, the
                // history stays valid through a plain step (any step gives a secant pair), so it
                // is kept: a tight tolerance does not restart the Hessian estimate each time.
                converged = false;
            }
            if converged || stop {
                break;
            }
        }
        Ok(())
    }

    /// Half the objective's gradient over the solved vertices, in the factor's order (see
    /// [`lbfgs`]): g = Σ_r w_r c_rᵀ ((C q)_r − P_r) + μ (q − s) = A q − b(q), from the
    /// projections at q and `cq` = C q (both as the last energy evaluation at q left them;
    /// `cq` becomes the residual C q − P).
    fn half_gradient(&mut self, q: &[DVec3], g: &mut [[f64; 4]]) {
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

    /// Σ_v μ_v ‖q_v − s_v‖²: the inertial part of the objective in dynamic mode (0 in static).
    fn inertial_energy(&self, q: &[DVec3]) -> f64 {
        let (Some(mu), false) = (&self.inertia, self.inertial_target.is_empty()) else { return 0.0 };
        mu.iter().zip(q).zip(&self.inertial_target).map(|((m, p), s)| m * (*p - *s).length_squared()).sum()
    }

    /// E(q) and its share per group, without solving (the matrix need not be invertible).
    ///
    /// # Errors
    /// [`SolveError::NoConstraints`] or a wrong length.
    pub fn energy(&mut self, q: &[DVec3]) -> Result<Energy, SolveError> {
        self.check_length(q)?;
        self.ensure_assembled()?;
        self.project(q);
        global::apply_c(&self.assembly, q, &mut self.cq);
        let per_group = self
            .order
            .iter()
            .zip(&self.assembly.groups)
            .map(|(&slot, rows)| {
                let g = self.slots[slot].as_ref().map_or(0.0, |g| g.multiplier);
                (GroupId(slot as u32), g * self.weighted_residual(rows.range()) + self.load_energy(q, [slot]))
            })
            .collect::<Vec<_>>();
        Ok(Energy { total: per_group.iter().map(|(_, e)| e).sum(), per_group })
    }

    /// Local step alone: every projection P_i = p_i(q), in parallel, into the system's buffer
    /// (for benchmarks and custom loops; [`System::step`] runs both steps).
    ///
    /// # Errors
    /// As [`System::prepare`], or a wrong length.
    pub fn local_step(&mut self, q: &[DVec3]) -> Result<(), SolveError> {
        self.check_length(q)?;
        self.prepare()?;
        self.project(q);
        Ok(())
    }

    /// Every projection into the buffer (assembled, not necessarily factored).
    fn project(&mut self, q: &[DVec3]) {
        for (&slot, rows) in self.order.iter().zip(&self.assembly.groups) {
            if let Some(group) = self.slots[slot].as_ref().filter(|g| !g.hard) {
                local::project_all(&group.constraints, &rows.offsets, q, &mut self.projections[rows.range()]);
            }
        }
        self.projected_at.clear();
        self.projected_at.extend_from_slice(q);
        self.retargeted.clear();
    }

    /// [`System::project`], except that when the projections were computed at this very q
    /// (`at_last_projection`) only the groups whose targets moved since are projected again (the
    /// same numbers as a full local step: a projection depends on q and its own constraint only).
    fn project_unless_current(&mut self, q: &[DVec3], at_last_projection: bool) {
        if !at_last_projection {
            self.project(q);
            return;
        }
        for (&slot, rows) in self.order.iter().zip(&self.assembly.groups) {
            if let (true, Some(group)) =
                (self.retargeted.contains(&slot), self.slots[slot].as_ref().filter(|g| !g.hard))
            {
                local::project_all(&group.constraints, &rows.offsets, q, &mut self.projections[rows.range()]);
            }
        }
        self.retargeted.clear();
    }

    /// Global step alone: q = (Σ w CᵀC)⁻¹ Σ w Cᵀ P over the solved vertices, from the last
    /// local step's projections (call [`System::local_step`] first).
    ///
    /// # Errors
    /// As [`System::prepare`]; [`SolveError::NonFinite`] if the solve produced NaN or infinity
    /// (nothing is written).
    pub fn global_step(&mut self, q: &mut [DVec3]) -> Result<(), SolveError> {
        self.check_length(q)?;
        self.prepare()?;
        let Some(factor) = self.factor.as_mut() else { return Ok(()) };
        // b = the constant part (inertia, held vertices), then Σ w Cᵀ P, in the factor's order.
        if self.constant_rhs.is_empty() {
            self.rhs.fill([0.0; 4]);
        } else {
            for (b, &s) in self.rhs.iter_mut().zip(factor.permutation()) {
                let c = self.constant_rhs[s as usize];
                *b = [c.x, c.y, c.z, 0.0];
            }
        }
        global::right_hand_side(
            &self.assembly,
            &self.rhs_map,
            &self.projections,
            &mut self.rhs,
            &mut self.rhs_partials,
        );
        factor.solve_permuted_in_place(&mut self.rhs);
        if !global::scatter(&self.assembly, factor.permutation(), &self.rhs, q) {
            return Err(SolveError::NonFinite);
        }
        self.pin_held(q);
        Ok(())
    }

    /// E(q) from the current projections (which must be p(q)).
    fn energy_of_projections(&mut self, q: &[DVec3]) -> f64 {
        global::apply_c(&self.assembly, q, &mut self.cq);
        let g = self.multipliers();
        let projective: f64 =
            self.assembly.groups.iter().zip(&g).map(|(rows, gk)| gk * self.weighted_residual(rows.range())).sum();
        // `load_rhs` is non-empty exactly when some group carries a load (set on assembly).
        if self.load_rhs.is_empty() {
            return projective;
        }
        projective + self.load_energy(q, self.order.clone())
    }

    /// [`SolveReport::energy_floor`] at q from the current projections.
    fn energy_floor(&self, q: &[DVec3]) -> f64 {
        let g = self.multipliers();
        let a = &self.assembly;
        let mut projections = 0.0;
        let mut terms = 0.0;
        for ((rows, gk), &slot) in a.groups.iter().zip(&g).zip(&self.order) {
            if self.slots[slot].as_ref().is_none_or(|group| group.hard) {
                continue;
            }
            for r in rows.range() {
                let w = gk * a.row_weight[r];
                projections += w * self.projections[r].length_squared();
                let m: f64 =
                    (a.c_ptr[r]..a.c_ptr[r + 1]).map(|k| a.c_val[k].abs() * q[a.c_col[k] as usize].length()).sum();
                terms += w * m * m;
            }
        }
        ROUND_OFF_FLOOR * projections + ROW_ROUND_OFF_FLOOR * terms
    }

    /// Σ_r ω_r ‖(Cq)_r − P_r‖² over a range of rows (no multiplier).
    fn weighted_residual(&self, rows: std::ops::Range<usize>) -> f64 {
        rows.map(|r| self.assembly.row_weight[r] * (self.cq[r] - self.projections[r]).length_squared()).sum()
    }

    fn check_length<T>(&self, q: &[T]) -> Result<(), SolveError> {
        if q.len() == self.num_vertices {
            Ok(())
        } else {
            Err(SolveError::WrongLength { expected: self.num_vertices, found: q.len() })
        }
    }

    /// Whether the solve sets vertex `v`: it is in the linear system (some constraint touches
    /// it) or held by a hard group; `false` before the first solve or energy evaluation (the
    /// others keep their positions).
    pub fn is_solved(&self, v: usize) -> bool {
        self.assembled
            && (self.assembly.solved_index.get(v).is_some_and(|&s| s != u32::MAX) || self.assembly.is_fixed(v))
    }

    /// Numeric factorizations of the global matrix so far (a diagnostic: moving targets, hard
    /// or soft, never adds one; a new weight does).
    pub fn factorizations(&self) -> u64 {
        self.factorizations
    }

    /// Number of vertices in the linear system (those some constraint touches), once assembled.
    pub fn num_solved_vertices(&self) -> usize {
        self.assembly.num_solved()
    }

    /// Stored entries of the global matrix's lower triangle and of its Cholesky factor (0, 0
    /// before the first solve).
    pub fn factor_sizes(&self) -> (usize, usize) {
        self.factor.as_ref().map_or((0, 0), |f| (f.nnz(), f.nnz_l()))
    }
}

/// What a solve asks of its iterations.
#[derive(Debug, Clone, Copy)]
struct Run {
    iterations: usize,
    tolerance: f64,
    /// E at the start (the projections at q are current).
    initial_energy: f64,
}

/// Buffers of the accelerated iterations, allocated once per problem size and kept between
/// solves: G(x) (or L-BFGS's trial point) and Anderson's mixed iterate over all n points; x, g
/// and the direction over the solved vertices in the factor's order for L-BFGS.
#[derive(Debug, Default)]
struct Scratch {
    plain: Vec<DVec3>,
    mixed: Vec<DVec3>,
    x: Vec<[f64; 4]>,
    g: Vec<[f64; 4]>,
    d: Vec<[f64; 4]>,
}

/// Runs `f`, adding its wall time in seconds to `seconds`.
fn timed<T>(seconds: &mut f64, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let result = f();
    *seconds += t.elapsed().as_secs_f64();
    result
}

/// After an iteration with energy E and objective `objective` (E, plus the inertial term in
/// dynamic mode): records E and says whether the objective met the tolerance (against
/// `previous`, then set to it) and whether `after_iteration` asks to stop. The tolerance is on
/// the objective, the function the iterations minimize: in dynamic mode E alone is a small part
/// of it whose relative change stays at the objective's round-off (1e-8 of E on a draped cloth)
/// long after the step has converged.
///
/// # Errors
/// [`SolveError::NonFiniteEnergy`] for a NaN or infinite E.
fn record_iteration(
    report: &mut SolveReport,
    previous: &mut f64,
    energy: f64,
    objective: f64,
    tolerance: f64,
    after_iteration: &mut impl FnMut(usize, f64) -> ControlFlow<()>,
) -> Result<(bool, bool), SolveError> {
    if !energy.is_finite() {
        return Err(SolveError::NonFiniteEnergy);
    }
    report.energies.push(energy);
    let converged = tolerance > 0.0 && meets_tolerance(*previous, objective, tolerance, report.energy_floor);
    *previous = objective;
    let stop = after_iteration(report.energies.len(), energy).is_break();
    Ok((converged, stop))
}

/// [`crate::constraints::check_weight`], naming the group (or `"inertia"`, `"load scale"`) in the error.
fn check_weight(name: &str, value: f64) -> Result<(), SolveError> {
    crate::constraints::check_weight(value).map(|_| ()).map_err(|_| SolveError::BadWeight { name: name.into(), value })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_factorization_that_cannot_be_built_is_not_called_singular() {
        let too_large = SolveError::from_factor(FactorError::Other("IndexOverflow".into())).to_string();
        assert!(too_large.starts_with("the system is too large to factor") && too_large.contains("IndexOverflow"));
        let singular = SolveError::from_factor(FactorError::NotPositiveDefinite(3)).to_string();
        assert!(singular.starts_with("singular system"), "{singular}");
    }
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
