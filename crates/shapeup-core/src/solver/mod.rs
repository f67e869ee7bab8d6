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
//!
//! This file is the algorithm: groups, prepare, step, solve, energy, the local and global
//! steps. Around it, one file per phase: `params` (settings), `rhs` (the right-hand side's
//! constant part), `iterate` (plain, Anderson, L-BFGS), `convergence` (stopping, reports),
//! `error`; below them `assemble`, `cholesky`, `global`, `local`.

mod anderson;
mod assemble;
mod cholesky;
mod convergence;
mod error;
mod global;
mod iterate;
mod lbfgs;
mod local;
mod ordering;
mod params;
mod remaining;
mod rhs;
mod round_off;
mod triangular;

pub use crate::constraints::{ConstraintGroup, GroupId};
pub use cholesky::{FactorError, Factorization};
pub use convergence::{
    ENERGY_FLOOR, GRADIENT_ROUND_OFF, ROUND_OFF_FLOOR, ROW_ROUND_OFF_FLOOR, STATIC_RESIDUAL_LIMIT, SolveReport,
    is_converged,
};
pub use error::{RUNAWAY, SolveError};
pub use params::{
    Acceleration, DEFAULT_ANDERSON_WINDOW, DEFAULT_LBFGS_MEMORY, MAX_ANDERSON_WINDOW, MAX_LBFGS_MEMORY, SolverParams,
};
pub use round_off::{LostGroup, ROUND_OFF_SHARE, add_lost_groups_warning};

use crate::constraints::Constraint;
use anderson::Anderson;
use assemble::Assembly;
use cholesky::SparseCholesky;
use convergence::{Run, timed};
use error::check_weight;
use glam::DVec3;
use iterate::Scratch;
use lbfgs::Lbfgs;
use std::ops::ControlFlow;

/// What must be redone before the next iteration, from least to most.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Stale {
    /// Factorization up to date.
    Fresh,
    /// Only multipliers changed: numeric refactorization on the same pattern.
    Values,
    /// Assembled since the constraint set changed (an energy, or a failed prepare), not yet
    /// factored: re-analyze, refactor.
    Analysis,
    /// Groups were added or removed: re-assemble, re-analyze, refactor.
    Pattern,
}

/// Terms per parallel task when summing a material's energy (also fixes the summation order).
const ENERGY_CHUNK: usize = 2048;

/// Energy of a configuration, in total and per group (each including its multiplier).
#[derive(Debug, Clone, PartialEq)]
pub struct Energy {
    /// E(q) = Σ_i w_i ‖C_i q − p_i(q)‖².
    pub total: f64,
    /// (group, its share of E) for every group, in id order.
    pub per_group: Vec<(GroupId, f64)>,
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
    /// The diagonal of the global matrix per vertex (0 outside the system), from the last
    /// factorization: how contact estimates a vertex's response ([`crate::contact`]).
    diagonal: Vec<f64>,
    /// Contact forces per vertex added to the next global steps' right-hand side; empty when
    /// none ([`System::set_contact_forces`]).
    contact_rhs: Vec<DVec3>,
    /// Contact weights W_v on the matrix's diagonal ([`System::set_contact_weights`]).
    contact_weights: Option<Vec<f64>>,
    /// What does not change between iterations per solved vertex: μ s (dynamic mode) minus the
    /// fixed vertices' share, −Σ_r w_r c_{r,v} Σ_{f fixed} c_{r,f} x_f; empty when neither.
    constant_rhs: Vec<DVec3>,
    /// The groups lost to round-off in the matrix last factored ([`LostGroup`]).
    lost: Vec<LostGroup>,
    /// Per group in assembly order, whether its terms are not projective (a material,
    /// [`Constraint::is_projective`]): their energy comes from C q, and a solve needs a line
    /// search.
    energy_groups: Vec<bool>,
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
            inertia: None,
            inertial_target: Vec::new(),
            diagonal: Vec::new(),
            contact_rhs: Vec::new(),
            contact_weights: None,
            held_rhs: Vec::new(),
            held: Vec::new(),
            load_rhs: Vec::new(),
            load_scale: 1.0,
            factorizations: 0,
            constant_rhs: Vec::new(),
            lost: Vec::new(),
            energy_groups: Vec::new(),
        }
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

    /// Per vertex, whether a hard group holds it (as of the last assembly).
    pub fn held_mask(&self) -> Vec<bool> {
        let mut mask = vec![false; self.num_vertices];
        for &(v, _) in &self.held {
            if let Some(m) = mask.get_mut(v as usize) {
                *m = true;
            }
        }
        mask
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
            return Err(bad(format!("has no targets (its type, {}, has none)", group.kind)));
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
            if self.is_assembled() {
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
        self.stale = self.stale.max(stale);
    }

    /// Whether the rows are stacked for the current constraint set (not necessarily factored).
    fn is_assembled(&self) -> bool {
        self.stale != Stale::Pattern
    }

    /// The multiplier of the group in `slot` (0 for a removed one).
    fn multiplier(&self, slot: usize) -> f64 {
        self.slots[slot].as_ref().map_or(0.0, |g| g.multiplier)
    }

    /// Every group's multiplier, in assembly order.
    fn multipliers(&self) -> Vec<f64> {
        self.order.iter().map(|&s| self.multiplier(s)).collect()
    }

    /// Stacks the rows of every group (once per change of the constraint set).
    fn ensure_assembled(&mut self) -> Result<(), SolveError> {
        if self.is_assembled() {
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
        self.energy_groups =
            self.order.iter().map(|&s| self.slots[s].as_ref().is_some_and(|g| !g.is_projective())).collect();
        self.assembly = Assembly::new(self.num_vertices, &lists, &hard, fixed, self.inertia.as_deref());
        let rows = self.assembly.num_rows();
        self.projections = vec![DVec3::ZERO; rows];
        self.projected_at.clear();
        self.cq = vec![DVec3::ZERO; rows];
        self.rhs = vec![[0.0; 4]; self.assembly.num_solved()];
        self.factor = None;
        self.stale = Stale::Analysis;
        self.update_weights();
        self.update_load_rhs();
        self.update_held_rhs();
        Ok(())
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
        let mut values = self.values_without_contact(&g);
        if let Some(w) = &self.contact_weights {
            for (s, &v) in self.assembly.solved.iter().enumerate() {
                values[self.assembly.slot(s, s)] += w[v as usize];
            }
        }
        self.diagonal.clear();
        self.diagonal.resize(self.num_vertices, 0.0);
        for (s, &v) in self.assembly.solved.iter().enumerate() {
            self.diagonal[v as usize] = values[self.assembly.slot(s, s)];
        }
        self.lost = self.groups_lost_to_round_off(&values, &g);
        if let Some(factor) = self.factor.as_mut() {
            factor.factorize(&values).map_err(|e| match (SolveError::from_factor(e), self.lost.first()) {
                // Said as the cause, not as a piece without a handle.
                (SolveError::Singular(_), Some(lost)) => {
                    SolveError::LostToRoundOff { first: lost.describe(), count: self.lost.len() }
                }
                (e, _) => e,
            })?;
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

    /// The solve the settings ask for: [`SolverParams::iterations`] iterations from q, stopping
    /// early at [`SolverParams::tolerance`]. With energies ([`System::solve`]) when the tolerance
    /// or the acceleration needs them ([`SolverParams::needs_energy`]); otherwise the plain
    /// [`System::iterate`], whose report has no energies (all the iterations ran). What a time
    /// step runs.
    ///
    /// # Errors
    /// As [`System::step`].
    pub fn run(&mut self, q: &mut [DVec3]) -> Result<SolveReport, SolveError> {
        let SolverParams { iterations, tolerance, .. } = self.params;
        if self.params.needs_energy() || self.has_energy_terms() {
            self.solve(q, iterations, tolerance)
        } else {
            self.iterate(q, iterations)
        }
    }

    /// [`System::solve_with`] for the settings' [`SolverParams::iterations`] and
    /// [`SolverParams::tolerance`]: always with energies, calling `after_iteration`.
    ///
    /// # Errors
    /// As [`System::step`].
    pub fn run_with(
        &mut self,
        q: &mut [DVec3],
        after_iteration: impl FnMut(usize, f64) -> ControlFlow<()>,
    ) -> Result<SolveReport, SolveError> {
        let SolverParams { iterations, tolerance, .. } = self.params;
        self.solve_with(q, iterations, tolerance, after_iteration)
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
        report.lost_groups.clone_from(&self.lost);
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
        let run = Run { iterations, tolerance, objective: energy + self.inertial_energy(q) };
        // Taken out while a loop borrows the system, and put back whatever the outcome.
        let mut scratch = std::mem::take(&mut self.scratch);
        // A static solve's residual is relative to the gradient it starts from (a time step's
        // is not measured: see SolveReport::residual).
        let measured = !self.has_inertial_term() && iterations > 0;
        // Terms that are not projective need L-BFGS's line search, whatever the acceleration.
        let energy_terms = self.energy_groups.contains(&true);
        let lbfgs = (energy_terms || self.params.acceleration == Acceleration::Lbfgs && self.params.is_accelerated())
            && self.factor.is_some();
        // L-BFGS's first iteration computes it (SolveReport::start_gradient); the others do not.
        let start_gradient = if measured && !lbfgs { self.half_gradient_norm(q, &mut scratch.g) } else { 0.0 };
        let start = (measured && energy_terms).then(|| q.to_vec());
        let result = if lbfgs {
            if !continuing {
                self.lbfgs.reset();
            }
            self.iterate_lbfgs(q, &mut scratch, run, &mut after_iteration, &mut report)
        } else if self.params.acceleration == Acceleration::Anderson && self.params.is_accelerated() {
            if !continuing {
                self.anderson.reset();
            }
            self.iterate_anderson(q, &mut scratch, run, &mut after_iteration, &mut report)
        } else {
            self.iterate_plain(q, run, &mut after_iteration, &mut report)
        };
        if let (Ok(false), true, Some(&energy)) = (&result, measured, report.energies.last()) {
            let start_gradient = report.start_gradient.unwrap_or(start_gradient);
            let residual = self.relative_residual(q, start_gradient, energy, report.energy_floor, &mut scratch.g);
            report.residual = Some(residual);
            report.unconverged = residual > STATIC_RESIDUAL_LIMIT;
        }
        self.scratch = scratch;
        if let Some(start) = start {
            ran_away(&start, q)?;
        }
        result.map(|_| report)
    }

    /// Whether the objective has the inertial term (dynamic mode, with a target set).
    fn has_inertial_term(&self) -> bool {
        self.inertia.is_some() && !self.inertial_target.is_empty()
    }

    /// Σ_v μ_v ‖q_v − s_v‖²: the inertial part of the objective in dynamic mode (0 in static).
    fn inertial_energy(&self, q: &[DVec3]) -> f64 {
        let (Some(mu), false) = (&self.inertia, self.inertial_target.is_empty()) else { return 0.0 };
        mu.iter().zip(q).zip(&self.inertial_target).map(|((m, p), s)| m * (*p - *s).length_squared()).sum()
    }

    /// E(q), the total of [`System::energy`], refused when it is not a finite number
    /// (targets, forces or coordinates too large for f64).
    ///
    /// # Errors
    /// As [`System::energy`]; [`SolveError::NonFiniteEnergy`].
    pub fn finite_energy(&mut self, q: &[DVec3]) -> Result<f64, SolveError> {
        let energy = self.energy(q)?.total;
        if energy.is_finite() { Ok(energy) } else { Err(SolveError::NonFiniteEnergy) }
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
            .enumerate()
            .map(|(k, (&slot, rows))| {
                let g = self.slots[slot].as_ref().map_or(0.0, |g| g.multiplier);
                (GroupId(slot as u32), g * self.group_energy(k, slot, rows) + self.load_energy(q, [slot]))
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
        if !self.contact_rhs.is_empty() {
            for (b, &s) in self.rhs.iter_mut().zip(factor.permutation()) {
                let f = self.contact_rhs[self.assembly.solved[s as usize] as usize];
                b[0] += f.x;
                b[1] += f.y;
                b[2] += f.z;
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
        // Per iteration: the multipliers read in place, not collected.
        let projective: f64 = self
            .assembly
            .groups
            .iter()
            .zip(&self.order)
            .enumerate()
            .map(|(k, (rows, &slot))| self.multiplier(slot) * self.group_energy(k, slot, rows))
            .sum();
        // `load_rhs` is non-empty exactly when some group carries a load (set on assembly).
        if self.load_rhs.is_empty() {
            return projective;
        }
        projective + self.load_energy(q, self.order.iter().copied())
    }

    /// Σ_r ω_r ‖(Cq)_r − P_r‖² over a range of rows (no multiplier).
    fn weighted_residual(&self, rows: std::ops::Range<usize>) -> f64 {
        rows.map(|r| self.assembly.row_weight[r] * (self.cq[r] - self.projections[r]).length_squared()).sum()
    }

    /// The energy of the `k`-th group in assembly order (in `slot`, on `rows`) without its
    /// multiplier, from C q and the projections: [`System::weighted_residual`], or for terms
    /// that are not projective the sum of their [`Constraint::energy_from_rows`] (in parallel,
    /// in a fixed order whatever the thread count).
    fn group_energy(&self, k: usize, slot: usize, rows: &assemble::GroupRows) -> f64 {
        let Some(group) = self.slots[slot].as_ref().filter(|_| self.energy_groups.get(k) == Some(&true)) else {
            return self.weighted_residual(rows.range());
        };
        use rayon::prelude::*;
        let cq = &self.cq[rows.range()];
        let parts: Vec<f64> = group
            .constraints
            .par_chunks(ENERGY_CHUNK)
            .enumerate()
            .map(|(chunk, constraints)| {
                let first = chunk * ENERGY_CHUNK;
                constraints
                    .iter()
                    .enumerate()
                    .map(|(i, c)| {
                        let (a, b) = (rows.offsets[first + i], rows.offsets[first + i + 1]);
                        c.energy_from_rows(&cq[a..b]).unwrap_or(0.0)
                    })
                    .sum::<f64>()
            })
            .collect();
        parts.iter().sum()
    }

    /// Whether some group's terms are not projective (a material): then every solve is L-BFGS
    /// with a line search, and E is evaluated at every iteration.
    pub fn has_energy_terms(&self) -> bool {
        self.groups().any(|(_, g)| !g.is_projective())
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
        self.is_assembled()
            && (self.assembly.solved_index.get(v).is_some_and(|&s| s != u32::MAX) || self.assembly.is_fixed(v))
    }

    /// The global matrix's diagonal entry of every vertex without the contact weights (0 for a
    /// vertex outside the system), from the current weights and inertia: assembles the system if
    /// it has to, but does not factor it, so that contact weights made from it are in the first
    /// factorization (a static solve with contact factors once, as a simulation does).
    ///
    /// # Errors
    /// As assembling in [`System::prepare`].
    pub fn diagonal_without_contact(&mut self) -> Result<Vec<f64>, SolveError> {
        self.ensure_assembled()?;
        let values = self.values_without_contact(&self.multipliers());
        let mut diagonal = vec![0.0; self.num_vertices];
        for (s, &v) in self.assembly.solved.iter().enumerate() {
            diagonal[v as usize] = values[self.assembly.slot(s, s)];
        }
        Ok(diagonal)
    }

    /// The global matrix's stored values (lower triangle, CSC order) for group multipliers `g`
    /// and the inertia, without the contact weights.
    fn values_without_contact(&self, g: &[f64]) -> Vec<f64> {
        let mut values = vec![0.0; self.assembly.lhs_row_idx.len()];
        for (group, &gk) in self.assembly.group_lhs.iter().zip(g) {
            values.iter_mut().zip(group).for_each(|(v, x)| *v += gk * x);
        }
        if let Some(mu) = &self.inertia {
            for (s, &v) in self.assembly.solved.iter().enumerate() {
                values[self.assembly.slot(s, s)] += mu[v as usize];
            }
        }
        values
    }

    /// The global matrix's diagonal entry of every vertex (0 for a vertex outside the
    /// system), as of the last factorization ([`System::prepare`]).
    pub fn diagonal(&self) -> Vec<f64> {
        if self.diagonal.len() == self.num_vertices { self.diagonal.clone() } else { vec![0.0; self.num_vertices] }
    }

    /// Adds the forces r (one per vertex, in the matrix's units: the global step solves
    /// A q = b + r) to the right-hand side of every global step until
    /// [`System::clear_contact_forces`]. No refactorization.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`].
    pub fn set_contact_forces(&mut self, forces: &[DVec3]) -> Result<(), SolveError> {
        self.check_length(forces)?;
        self.contact_rhs.clear();
        self.contact_rhs.extend_from_slice(forces);
        self.map_changed = true;
        Ok(())
    }

    /// Puts contact weights W_v (one per vertex, ≥ 0) on the matrix's diagonal, or removes
    /// them (`None`): a numeric refactorization at the next solve. With weights, every global
    /// step must get W_v p_v on its right-hand side ([`System::set_contact_forces`]; p_v = q_v
    /// for a vertex nothing touches): [`crate::contact::solve_with_contact`] does.
    ///
    /// # Errors
    /// [`SolveError::WrongLength`], or a weight that is negative or not finite.
    pub fn set_contact_weights(&mut self, weights: Option<Vec<f64>>) -> Result<(), SolveError> {
        if let Some(w) = &weights {
            self.check_length(w)?;
            if let Some(&bad) = w.iter().find(|w| !(w.is_finite() && **w >= 0.0)) {
                return Err(SolveError::BadWeight { name: "contact".into(), value: bad });
            }
        }
        self.contact_weights = weights;
        self.mark(Stale::Values);
        self.map_changed = true;
        Ok(())
    }

    /// The contact weights, if set ([`System::set_contact_weights`]).
    pub fn contact_weights(&self) -> Option<&[f64]> {
        self.contact_weights.as_deref()
    }

    /// Removes the forces [`System::set_contact_forces`] set.
    pub fn clear_contact_forces(&mut self) {
        self.contact_rhs.clear();
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

/// [`SolveError::RanAway`] when a vertex of `q` is [`error::RUNAWAY`] sizes of `start` (its
/// bounding-box diagonal, at least 1e-300) from where it started.
fn ran_away(start: &[DVec3], q: &[DVec3]) -> Result<(), SolveError> {
    let (lo, hi) = start.iter().fold((DVec3::MAX, DVec3::MIN), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let size = if start.is_empty() { 1.0 } else { (hi - lo).length().max(1e-300) };
    let moved = start.iter().zip(q).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    if moved.is_nan() || moved > error::RUNAWAY * size {
        return Err(SolveError::RanAway { factor: moved / size });
    }
    Ok(())
}
