//! The solve state behind a document: the rest shape ([`Rest`]), what undo snapshots and the
//! worker solves ([`EditState`]), and the [`EditSolver`] that turns an `EditState` into a
//! `shapeup-core` [`System`] (`build_system`, which dynamic mode uses too) and keeps the
//! working positions: a structural change rebuilds the
//! system, a handle move only sets targets ([`System::set_targets`], no refactorization), a
//! weight change only refactors. With colliders or self-collision the solve is the core's
//! static solve with contact (`solve_static_with_contact`), so dragging into a collider stops
//! at it.

use crate::collider::contact_model;
use crate::error::{Cause, EditorError, GroupError};
use crate::group::{Group, GroupKey, GroupRole, ShapeModel, Structure};
use glam::DVec3;
use shapeup_core::contact::{ColliderSpec, ContactModel, ContactSettings};
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{GroupSpec, solve_static_with_contact};
use shapeup_core::solver::{Acceleration, GroupId, SolveReport, SolverParams, System, is_converged};
use std::ops::ControlFlow;
use std::sync::Arc;

/// The editor's default convergence tolerance on the relative energy change of an iteration,
/// used when a scene sets none (`tolerance = 0`).
pub const DEFAULT_TOLERANCE: f64 = 1e-6;

/// The editor's default cap on the iterations of one convergence, used when a scene sets no
/// tolerance (its `iterations` were then a fixed count, not a cap).
pub const DEFAULT_MAX_ITERATIONS: usize = 10_000;

/// The rest shape: the mesh in its input frame and its rest geometry in the working frame.
#[derive(Debug)]
pub struct Rest {
    /// Rest mesh, input frame.
    pub mesh: Mesh,
    /// Input ↔ working frame.
    pub frame: WorkingFrame,
    /// Whether the frame was fitted (`[mesh] normalize`).
    pub normalize: bool,
    /// Rest geometry (working frame).
    pub geometry: RestGeometry,
}

impl Rest {
    /// The rest state of a mesh, in the normalized frame when `normalize` (as a scene loads it).
    pub fn new(mesh: Mesh, normalize: bool) -> Self {
        let frame = if normalize { WorkingFrame::fit(&mesh.positions) } else { WorkingFrame::IDENTITY };
        let working = mesh.positions.iter().map(|&p| frame.to_working(p)).collect();
        let geometry = RestGeometry::of_mesh(working, &mesh);
        Rest { mesh, frame, normalize, geometry }
    }
}

/// The editable state that undo snapshots and the worker solves: cheap to clone (the rest shape
/// is shared).
#[derive(Debug, Clone)]
pub struct EditState {
    /// The rest shape.
    pub rest: Arc<Rest>,
    /// The shape model, `None` when the shape groups came from a scene that matches no model.
    pub shape_model: Option<ShapeModel>,
    /// Every group, in system (and scene) order.
    pub groups: Vec<Group>,
    /// The most local-global iterations one convergence runs after a change (the scene's
    /// `[solver] iterations`).
    pub iterations: usize,
    /// Convergence stops when the relative energy change of an iteration is at most this
    /// (the scene's `[solver] tolerance`).
    pub tolerance: f64,
    /// How iterates are combined (the scene's `[solver] acceleration`).
    pub acceleration: Acceleration,
    /// Iterations Anderson acceleration mixes (the scene's `[solver] anderson_window`).
    pub anderson_window: usize,
    /// Pairs L-BFGS keeps (the scene's `[solver] lbfgs_memory`).
    pub lbfgs_memory: usize,
    /// The colliders (a scene's `[[colliders]]`, input frame; mesh paths absolute, resolved
    /// against the scene's folder when opened).
    pub colliders: Vec<ColliderSpec>,
    /// The `[contact]` settings (self-collision, thickness, self friction).
    pub contact: ContactSettings,
}

impl PartialEq for EditState {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.rest, &other.rest)
            && self.shape_model == other.shape_model
            && self.groups == other.groups
            && self.iterations == other.iterations
            && self.tolerance.to_bits() == other.tolerance.to_bits()
            && self.acceleration == other.acceleration
            && self.anderson_window == other.anderson_window
            && self.lbfgs_memory == other.lbfgs_memory
            && self.colliders == other.colliders
            && self.contact == other.contact
    }
}

impl EditState {
    /// The group with this key.
    pub fn group(&self, key: GroupKey) -> Option<&Group> {
        self.groups.iter().find(|g| g.key == key)
    }

    pub(crate) fn group_mut(&mut self, key: GroupKey) -> Result<&mut Group, EditorError> {
        self.groups.iter_mut().find(|g| g.key == key).ok_or(EditorError::UnknownGroup(key))
    }

    pub(crate) fn handle_mut(&mut self, key: GroupKey) -> Result<&mut Group, EditorError> {
        let group = self.group_mut(key)?;
        if group.role == GroupRole::Handle { Ok(group) } else { Err(EditorError::NotAHandle(key)) }
    }

    /// Whether some handle exists (without one a solve has nothing to do).
    pub fn has_handles(&self) -> bool {
        self.groups.iter().any(|g| g.role == GroupRole::Handle)
    }
}

/// A system of `groups` on `rest` with solver `params`: each group built through the library's
/// one route ([`GroupSpec::build`]), in order, then the vertices only zero-area triangles use
/// attached to their edge (as a scene does). Returns the system and each group's id, in order.
///
/// # Errors
/// [`GroupError::Build`] naming the first group that cannot be built or added.
pub(crate) fn build_system<'a>(
    rest: &Rest,
    groups: impl IntoIterator<Item = &'a GroupSpec>,
    params: SolverParams,
) -> Result<(System, Vec<GroupId>), GroupError> {
    let mut system = System::new(rest.mesh.num_vertices(), params);
    let mut ids = Vec::new();
    for spec in groups {
        let refused = |source| GroupError::Build { group: spec.name.clone(), source };
        let group = spec.build(&rest.mesh, &rest.geometry, &rest.frame).map_err(|e| refused(Cause::new(e)))?;
        ids.push(system.add_group(group).map_err(|e| refused(Cause::new(e)))?);
    }
    let (group, _, _) =
        shapeup_core::constraints::attach_degenerate_vertices(&rest.geometry, system.groups().map(|(_, g)| g));
    if let Some(group) = group {
        let name = group.name.clone();
        system.add_group(group).map_err(|e| GroupError::Build { group: name, source: Cause::new(e) })?;
    }
    Ok((system, ids))
}

/// The solve state of an [`EditState`]: its [`System`] and the working positions (named apart
/// from the library's `System` and the app's background [`SolverWorker`](crate::worker::SolverWorker)).
#[derive(Debug, Default)]
pub struct EditSolver {
    rest: Option<Arc<Rest>>,
    /// What each group the system was built from depends on.
    structure: Vec<Structure>,
    system: Option<System>,
    ids: Vec<GroupId>,
    /// Current positions, working frame.
    q: Vec<DVec3>,
    /// The colliders and self-collision of the synced state (`None`: nothing can touch).
    contact: Option<ContactModel>,
    /// What `contact` was built from.
    contact_of: Option<(Vec<ColliderSpec>, ContactSettings)>,
}

impl EditSolver {
    /// A solver with nothing built; the first [`EditSolver::sync`] builds the system and starts
    /// from the rest shape.
    pub fn new() -> Self {
        EditSolver::default()
    }

    /// Brings the system up to date with `state`: rebuilds it when the rest shape or the set of
    /// groups changed (the positions are carried over through the frames), else only sets the
    /// handles' targets and the weights. On error nothing changes.
    ///
    /// # Errors
    /// [`EditorError::Constraint`] when a group cannot be built.
    pub fn sync(&mut self, state: &EditState) -> Result<(), EditorError> {
        let same_rest = self.rest.as_ref().is_some_and(|r| Arc::ptr_eq(r, &state.rest));
        let same_groups = self.structure.len() == state.groups.len()
            && self.structure.iter().zip(&state.groups).all(|(s, g)| s.matches(g));
        let same_contact =
            same_rest && self.contact_of.as_ref().is_some_and(|(c, s)| *c == state.colliders && *s == state.contact);
        // Built first, so that a collider that cannot be used changes nothing.
        let contact = if same_contact {
            None
        } else {
            let rest = &state.rest;
            Some(contact_model(&state.colliders, state.contact, &rest.mesh, &rest.geometry, &rest.frame)?)
        };
        // The contact weights are relative to the static matrix's diagonal: set again after a
        // rebuild, a weight change or new contact (`solve_static_with_contact` sets them).
        let mut stale_weights = contact.is_some();
        let params = SolverParams {
            iterations: state.iterations,
            acceleration: state.acceleration,
            anderson_window: state.anderson_window,
            lbfgs_memory: state.lbfgs_memory,
            ..SolverParams::default()
        };
        match self.system.as_mut() {
            Some(system) if same_rest && same_groups => {
                if *system.params() != params {
                    system.set_params(params);
                }
                for (group, &id) in state.groups.iter().zip(&self.ids) {
                    if group.role == GroupRole::Handle {
                        let working: Vec<DVec3> =
                            group.targets().into_iter().map(|t| state.rest.frame.to_working(t)).collect();
                        system.set_targets(id, &working)?;
                    }
                    stale_weights |= system.group(id).is_some_and(|g| g.multiplier != group.spec.weight);
                    system.set_multiplier(id, group.spec.weight)?;
                }
            }
            _ => {
                let rest = &state.rest;
                let (system, ids) = build_system(rest, state.groups.iter().map(|g| &g.spec), params)
                    .map_err(EditorError::Constraint)?;
                self.q = match &self.rest {
                    // Same positions in the input frame, seen in the new working frame.
                    Some(old) if !same_rest && self.q.len() == rest.mesh.num_vertices() => {
                        self.q.iter().map(|&p| rest.frame.to_working(old.frame.to_input(p))).collect()
                    }
                    Some(_) if same_rest => std::mem::take(&mut self.q),
                    _ => rest.geometry.positions.clone(),
                };
                self.structure = state.groups.iter().map(Structure::of).collect();
                self.system = Some(system);
                self.ids = ids;
                self.rest = Some(Arc::clone(rest));
                stale_weights = true;
            }
        }
        if let Some(contact) = contact {
            self.contact = contact.filter(ContactModel::is_active);
            self.contact_of = Some((state.colliders.clone(), state.contact));
        }
        if let Some(system) = self.system.as_mut()
            && system.contact_weights().is_some()
            && (stale_weights || self.contact.is_none())
        {
            system.set_contact_weights(None)?;
        }
        Ok(())
    }

    /// Sets the current positions (input frame), e.g. back to the rest shape. Ignored before
    /// the first [`EditSolver::sync`] or with the wrong length.
    pub fn set_positions(&mut self, positions: &[DVec3]) {
        if let Some(rest) = &self.rest
            && positions.len() == rest.mesh.num_vertices()
        {
            self.q = positions.iter().map(|&p| rest.frame.to_working(p)).collect();
        }
    }

    /// Runs `iterations` local-global iterations from the current positions.
    ///
    /// # Errors
    /// [`EditorError::NoHandles`] before any sync, [`EditorError::Solve`] for a singular system.
    pub fn solve(&mut self, iterations: usize) -> Result<SolveReport, EditorError> {
        self.solve_to(iterations, 0.0)
    }

    /// Runs at most `iterations` local-global iterations from the current positions, stopping
    /// after the first whose relative energy change is at most `tolerance` (> 0).
    ///
    /// # Errors
    /// As [`EditSolver::solve`].
    pub fn solve_to(&mut self, iterations: usize, tolerance: f64) -> Result<SolveReport, EditorError> {
        self.solve_until(iterations, tolerance, || false)
    }

    /// [`EditSolver::solve_to`] that also stops after any iteration for which `interrupted()` is
    /// true (a newer request in the background worker); at least one iteration runs.
    ///
    /// # Errors
    /// As [`EditSolver::solve`].
    pub fn solve_until(
        &mut self,
        iterations: usize,
        tolerance: f64,
        interrupted: impl Fn() -> bool,
    ) -> Result<SolveReport, EditorError> {
        let system = self.system.as_mut().ok_or(EditorError::NoHandles)?;
        let Some(contact) = self.contact.as_mut() else {
            return Ok(system.solve_with(&mut self.q, iterations, tolerance, |_, _| {
                if interrupted() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            })?);
        };
        // With contact: the core's static solve, a detection every few iterations and the
        // projection out of colliders after each, with E recorded after each such chunk; the
        // tolerance is checked between chunks.
        let mut previous: Option<f64> = None;
        Ok(solve_static_with_contact(system, contact, &mut self.q, iterations, |_, energy| {
            let converged = tolerance > 0.0 && previous.is_some_and(|p| is_converged(p, energy, tolerance, 0.0));
            previous = Some(energy);
            if converged || interrupted() { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        })?)
    }

    /// Per vertex, whether it touched a collider or another part of the surface at the end of
    /// the last solve; `None` without colliders and self-collision.
    pub fn touching(&self) -> Option<&[bool]> {
        self.contact.as_ref().map(ContactModel::touching)
    }

    /// The current positions in the input frame; vertices no constraint touches keep their rest
    /// positions bit for bit (as `shapeup deform` writes them).
    pub fn positions(&self) -> Vec<DVec3> {
        let (Some(rest), Some(system)) = (&self.rest, &self.system) else { return Vec::new() };
        self.q
            .iter()
            .zip(&rest.mesh.positions)
            .enumerate()
            .map(|(v, (&p, &input))| if system.is_solved(v) { rest.frame.to_input(p) } else { input })
            .collect()
    }

    /// E of the current positions, per group (in the order of the synced state's groups).
    ///
    /// # Errors
    /// [`EditorError::Solve`] (e.g. no constraints).
    pub fn energy(&mut self) -> Result<Vec<f64>, EditorError> {
        let system = self.system.as_mut().ok_or(EditorError::NoHandles)?;
        let energy = system.energy(&self.q)?;
        Ok(self.ids.iter().map(|id| energy.per_group.iter().find(|(g, _)| g == id).map_or(0.0, |(_, e)| *e)).collect())
    }
}
