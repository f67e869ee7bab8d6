//! Dynamic mode in the editor: a Projective Dynamics simulation of the document's constraints
//! (shape model or tetrahedral strain, handles as pins, smoothing) stepping on its own thread.
//!
//! [`SimulationRunner::start`] builds a simulation from the document's groups (optionally with
//! gravity, a floor just below the shape and TetGen tetrahedra), each through the library's one
//! route ([`GroupSpec::build`]), and starts from the current shape at rest. The UI polls the newest positions ([`SimulationRunner::poll`], never blocking), holds
//! vertices at the cursor with [`SimulationRunner::grab`], pauses or resumes it, and changes
//! gravity, stiffness, time step, damping and grab strength on the fly
//! ([`SimulationRunner::update_settings`]); a change of the document's constraints, of the
//! model, the floor or the tetrahedra means a new runner. The document's colliders and
//! `[contact]` settings become the core's contact model by the scene's rule
//! ([`crate::collider::contact_model`]) and can change while it runs
//! ([`SimulationRunner::set_contact`]); which vertices touch something comes back with the
//! positions ([`SimulationRunner::touching`]).

use crate::collider::contact_model;
use crate::document::Document;
use crate::edit_state::{Rest, build_system};
use crate::error::{Cause, EditorError, RunnerError, SettingsError, SimulationError, TetrahedraError};
use crate::group::GroupRole;
use glam::DVec3;
use serde_json::{Map, Value};
use shapeup_core::contact::{ColliderSpec, ContactSettings};
use shapeup_core::dynamics::{DynamicsError, DynamicsParams, Simulation, StepReport};
use shapeup_core::geometry::WorkingFrame;
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{GroupSpec, Mode, SelectionSpec, SolverSettings, Targets, lumped_masses};
use std::collections::{HashMap, VecDeque};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What keeps the body's shape in dynamic mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum DynamicsModel {
    /// The document's own shape-model groups (edge springs, strain + bending, iso one-rings).
    #[default]
    Document,
    /// One `tet_strain` group over every tetrahedron instead of the document's shape-model
    /// groups (handles, smoothing and other groups stay): a solid that keeps its volume.
    /// Needs tetrahedra (Tetrahedralize, or a tetrahedral mesh).
    TetStrain,
}

impl DynamicsModel {
    /// Every model, in menu order.
    pub const ALL: [DynamicsModel; 2] = [DynamicsModel::Document, DynamicsModel::TetStrain];

    /// Name for menus (the panel's radio buttons).
    pub fn label(self) -> &'static str {
        match self {
            DynamicsModel::Document => "Document's shape model",
            DynamicsModel::TetStrain => "Tet strain",
        }
    }
}

/// The default grab strength: the grabbed vertices close 95 % of their gap to the cursor in
/// every solver iteration (see [`shapeup_core::dynamics::Simulation::hold`]), so they follow it
/// closely while the rest of the body still pulls back a little.
pub const DEFAULT_GRAB_STRENGTH: f64 = 0.95;

/// How fast the simulation plays: simulated seconds per wall-clock second.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Speed {
    /// One simulated second per second (default): a fall is seen at its real speed.
    #[default]
    RealTime,
    /// A quarter of real time.
    SlowMotion,
    /// Each step as soon as the last is done.
    AsFastAsPossible,
}

impl Speed {
    /// Every speed, in the panel's order.
    pub const ALL: [Speed; 3] = [Speed::RealTime, Speed::SlowMotion, Speed::AsFastAsPossible];

    /// The panel's label.
    pub fn label(self) -> &'static str {
        match self {
            Speed::RealTime => "Real time",
            Speed::SlowMotion => "Slow motion (¼)",
            Speed::AsFastAsPossible => "As fast as possible",
        }
    }

    /// Simulated seconds per wall-clock second; `None`: not paced.
    pub fn factor(self) -> Option<f64> {
        match self {
            Speed::RealTime => Some(1.0),
            Speed::SlowMotion => Some(0.25),
            Speed::AsFastAsPossible => None,
        }
    }
}

/// Where a new simulation starts (the panel's Run from rest and Continue).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StartShape {
    /// The document's rest shape, at rest (Run from rest).
    Rest,
    /// The shape on screen, at rest (Continue without a paused simulation): the static solve's
    /// result, or where a stopped simulation left the body.
    #[default]
    OnScreen,
}

/// What the simulation adds to the document's constraints, and how it steps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationSettings {
    /// Gravity (the scene default, (0, −9.81, 0) in the mesh's units per s²), or none.
    pub gravity: bool,
    /// A floor just below the current shape (all vertices, the floor type's default multiplier).
    pub floor: bool,
    /// Fill the closed surface with tetrahedra (TetGen; needs the `tetgen` feature, see
    /// [`tetrahedralize_available`]).
    pub tetrahedralize: bool,
    /// What keeps the shape (default: the document's shape model).
    pub model: DynamicsModel,
    /// Stiffness k of every constraint against inertia (the scene's `[solver] stiffness`; default
    /// the scene default, 100).
    pub stiffness: f64,
    /// Time step h in seconds (the scene's `[solver] time_step`; default the scene default, 1/60).
    pub time_step: f64,
    /// Velocity damping d ∈ [0, 1) (default 0.02: a little, so that bodies come to rest).
    pub damping: f64,
    /// How firmly a grab holds the grabbed vertices at the cursor, in (0, 1] (default
    /// [`DEFAULT_GRAB_STRENGTH`]; 1 pins them to it).
    pub grab_strength: f64,
    /// How fast steps are taken (default [`Speed::RealTime`]: a step of h every h seconds).
    pub speed: Speed,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        let scene = SolverSettings::default();
        SimulationSettings {
            gravity: true,
            floor: true,
            tetrahedralize: false,
            model: DynamicsModel::Document,
            stiffness: scene.stiffness,
            time_step: scene.time_step,
            damping: 0.02,
            grab_strength: DEFAULT_GRAB_STRENGTH,
            speed: Speed::default(),
        }
    }
}

impl SimulationSettings {
    /// Whether going from `self` to `other` needs a new runner (another model, floor or
    /// tetrahedralization); everything else [`SimulationRunner::update_settings`] applies live.
    pub fn needs_restart(&self, other: &SimulationSettings) -> bool {
        (self.floor, self.tetrahedralize, self.model) != (other.floor, other.tetrahedralize, other.model)
    }

    /// Checks the numbers, naming the first bad one.
    ///
    /// # Errors
    /// [`SettingsError`]: the stiffness, time step or damping out of range, or a grab strength
    /// outside (0, 1].
    pub fn validate(&self) -> Result<(), SettingsError> {
        // The one mapping to the core's settings, checked by the core (gravity is finite).
        self.params(1.0).validate()?;
        if !(self.grab_strength > 0.0 && self.grab_strength <= 1.0) {
            return Err(SettingsError::GrabStrength(self.grab_strength));
        }
        Ok(())
    }

    /// The time-stepping settings in the working frame of scale `scale` (gravity scales with
    /// lengths); iterations per step and the tolerance are the solver's.
    fn params(&self, scale: f64) -> DynamicsParams {
        let gravity =
            if self.gravity { DVec3::from_array(SolverSettings::default().gravity) * scale } else { DVec3::ZERO };
        DynamicsParams { time_step: self.time_step, stiffness: self.stiffness, damping: self.damping, gravity }
    }
}

/// Whether Tetrahedralize can be ticked for `document`.
///
/// # Errors
/// The reason (one line for a tooltip): this build has no TetGen (cargo feature `tetgen`), the
/// mesh already has tetrahedra, it has no triangles, or the surface is not closed (every edge
/// must be shared by exactly two triangles).
pub fn tetrahedralize_available(document: &Document) -> Result<(), TetrahedraError> {
    if !cfg!(feature = "tetgen") {
        return Err(TetrahedraError::NoTetGen);
    }
    if document.rest_mesh().num_tetrahedra() > 0 {
        return Err(TetrahedraError::AlreadyTetrahedra);
    }
    closed_surface(document.triangles())
}

/// Ok when every edge of `triangles` is shared by exactly two of them.
fn closed_surface(triangles: &[[u32; 3]]) -> Result<(), TetrahedraError> {
    if triangles.is_empty() {
        return Err(TetrahedraError::NoTriangles);
    }
    let mut uses: HashMap<(u32, u32), u32> = HashMap::with_capacity(3 * triangles.len() / 2);
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let mut bad: Vec<((u32, u32), u32)> = uses.into_iter().filter(|&(_, n)| n != 2).collect();
    if bad.is_empty() {
        return Ok(());
    }
    bad.sort_unstable();
    let border = bad.iter().filter(|&&(_, n)| n == 1).count();
    let ((a, b), _) = bad[0];
    Err(if border == bad.len() {
        TetrahedraError::Open { border, a, b }
    } else {
        TetrahedraError::NotClosed { count: bad.len(), a, b }
    })
}

/// A runner's timings and state, for the panel.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SimulationStats {
    /// Time steps since the start or the last restart.
    pub steps: u64,
    /// Steps taken in the last second (0 while paused).
    pub steps_per_second: f64,
    /// Milliseconds of the last step (all of it: inertia, iterations, any refactorization).
    pub step_ms: f64,
    /// Milliseconds of the last step's local steps (projections).
    pub local_ms: f64,
    /// Milliseconds of the last step's global steps (triangular solves).
    pub global_ms: f64,
    /// Milliseconds of the last step's contact detection and projection.
    pub contact_ms: f64,
    /// Vertices touching a collider or the surface itself at the end of the last step.
    pub contact_vertices: usize,
    /// Steps checked for stopping short ([`shapeup_core::dynamics::is_checked_step`]).
    pub checked_steps: u64,
    /// Of those, steps that stopped short of the converged step.
    pub unconverged_steps: u64,
    /// The largest share of a step's motion missed among those.
    pub worst_residual: f64,
    /// The error that stopped the stepping, or that a setting or grab caused, if any.
    pub error: Option<RunnerError>,
}

#[derive(Default)]
struct Shared {
    running: bool,
    /// Steps to take before pausing ([`SimulationRunner::run_for`]); `None`: until paused.
    steps_left: Option<u64>,
    shutdown: bool,
    reset: bool,
    /// Vertices and targets (input frame) to hold; `grab_changed` says the thread must look.
    grab: Option<(Vec<u32>, Vec<DVec3>)>,
    grab_changed: bool,
    /// The settings the simulation runs with (live ones applied by the thread when
    /// `params_changed`).
    settings: SimulationSettings,
    params_changed: bool,
    /// Newest positions (input frame), taken by `poll`.
    latest: Option<Vec<DVec3>>,
    /// Per document vertex, whether it touched something at the end of the newest step
    /// (empty without contact).
    touching: Vec<bool>,
    /// New colliders and contact settings; `contact_changed` says the thread must look.
    contact: Option<(Vec<ColliderSpec>, ContactSettings)>,
    contact_changed: bool,
    /// When the steps of the last second ended.
    recent: VecDeque<Instant>,
    stats: SimulationStats,
}

#[derive(Default)]
struct Channel {
    state: Mutex<Shared>,
    wake: Condvar,
}

/// A simulation on its own thread; dropping it stops and joins the thread.
pub struct SimulationRunner {
    channel: Arc<Channel>,
    thread: Option<JoinHandle<()>>,
    /// Tetrahedra of the simulated mesh (0 for a surface).
    pub num_tetrahedra: usize,
    /// The floor's height y (input frame), when the settings have a floor: just below the
    /// shape the simulation started from (the viewport draws it).
    pub floor_height: Option<f64>,
}

impl std::fmt::Debug for SimulationRunner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SimulationRunner").field("num_tetrahedra", &self.num_tetrahedra).finish()
    }
}

impl SimulationRunner {
    /// Builds the simulation of `document` from its current shape, paused; `notify` is called
    /// on the simulation thread after each step (e.g. to wake the UI).
    ///
    /// # Errors
    /// [`EditorError::Simulation`] with one line when the dynamic system cannot be built: bad
    /// settings, a surface TetGen cannot fill (open, or a build without TetGen), the tet strain
    /// model without tetrahedra, or a singular system.
    pub fn start(
        document: &Document,
        settings: SimulationSettings,
        notify: impl Fn() + Send + 'static,
    ) -> Result<SimulationRunner, EditorError> {
        Self::start_from(document, settings, StartShape::OnScreen, notify)
    }

    /// [`SimulationRunner::start`] from `from`: the shape on screen or the rest shape.
    ///
    /// # Errors
    /// As [`SimulationRunner::start`]; also Tetrahedralize from the shape on screen
    /// ([`SimulationError::TetrahedraFromRestOnly`]).
    pub fn start_from(
        document: &Document,
        settings: SimulationSettings,
        from: StartShape,
        notify: impl Fn() + Send + 'static,
    ) -> Result<SimulationRunner, EditorError> {
        Self::try_start(document, settings, from, notify).map_err(EditorError::Simulation)
    }

    /// [`SimulationRunner::start_from`]: the mesh, its start shape, the simulated groups, the
    /// simulation at that shape, then its thread.
    fn try_start(
        document: &Document,
        settings: SimulationSettings,
        from: StartShape,
        notify: impl Fn() + Send + 'static,
    ) -> Result<SimulationRunner, SimulationError> {
        settings.validate()?;
        if settings.tetrahedralize
            && from == StartShape::OnScreen
            && document.rest_mesh().num_tetrahedra() == 0
            && !is_rest_shape(document.positions(), document.rest_mesh())
        {
            return Err(SimulationError::TetrahedraFromRestOnly);
        }
        let mesh = simulated_mesh(document, &settings)?;
        let start = match from {
            StartShape::Rest => mesh.positions.clone(),
            StartShape::OnScreen => start_shape(document, &mesh),
        };
        let (groups, floor) = dynamic_groups(document, &settings, &mesh, &start)?;
        let solver = dynamic_solver_settings(document, &settings);
        let rest = Rest::new(mesh, document.state().rest.normalize);
        let contact = (document.colliders().to_vec(), document.contact_settings());
        let stepper = Stepper::new(&groups, &solver, rest, &start, floor, document.num_vertices(), &contact)?;
        let num_tetrahedra = stepper.num_tetrahedra;
        let channel = Arc::new(Channel::default());
        channel.state.lock().unwrap_or_else(PoisonError::into_inner).settings = settings;
        let thread_channel = Arc::clone(&channel);
        let thread = std::thread::Builder::new()
            .name("shapeup-simulation".into())
            .spawn(move || stepper.run(&thread_channel, notify))
            .map_err(|e| SimulationError::Thread(Cause::new(e)))?;
        Ok(SimulationRunner { channel, thread: Some(thread), num_tetrahedra, floor_height: floor })
    }

    fn with_state<T>(&self, f: impl FnOnce(&mut Shared) -> T) -> T {
        let mut state = self.channel.state.lock().unwrap_or_else(PoisonError::into_inner);
        let out = f(&mut state);
        self.channel.wake.notify_one();
        out
    }

    /// Runs or pauses the time stepping.
    pub fn set_running(&self, running: bool) {
        self.with_state(|s| {
            s.running = running;
            s.steps_left = None;
        });
    }

    /// Takes exactly `steps` more time steps, then pauses (e.g. to compare with another
    /// simulation step for step).
    pub fn run_for(&self, steps: u64) {
        self.with_state(|s| {
            s.running = steps > 0;
            s.steps_left = (steps > 0).then_some(steps);
        });
    }

    /// Whether it is stepping.
    pub fn is_running(&self) -> bool {
        self.with_state(|s| s.running)
    }

    /// Back to the shape it started from, at rest (stays running or paused); clears the stats
    /// and the error.
    pub fn reset(&self) {
        self.with_state(|s| s.reset = true);
    }

    /// Holds `vertices` at `targets` (input frame) from the next step on, with the settings'
    /// grab strength; call it again as the cursor moves (same vertices: no refactorization).
    pub fn grab(&self, vertices: Vec<u32>, targets: Vec<DVec3>) {
        self.with_state(|s| {
            s.grab = Some((vertices, targets));
            s.grab_changed = true;
        });
    }

    /// Lets go.
    pub fn release(&self) {
        self.with_state(|s| {
            s.grab = None;
            s.grab_changed = true;
        });
    }

    /// The newest positions of the document's vertices (input frame) since the last poll.
    pub fn poll(&self) -> Option<Vec<DVec3>> {
        self.with_state(|s| s.latest.take())
    }

    /// Per document vertex, whether it touched a collider or the surface itself at the end of
    /// the newest step (`touching()` of the core's contact model); empty without contact.
    pub fn touching(&self) -> Vec<bool> {
        self.with_state(|s| s.touching.clone())
    }

    /// Takes over new colliders and contact settings from the next step (the document's,
    /// after a collider was added, moved or edited): the contact model is built again, and
    /// vertices now inside a collider are moved out without velocity. A collider that cannot
    /// be built shows as the stats' error and the old ones stay.
    pub fn set_contact(&self, colliders: Vec<ColliderSpec>, settings: ContactSettings) {
        self.with_state(|s| {
            s.contact = Some((colliders, settings));
            s.contact_changed = true;
        });
    }

    /// Steps, steps per second over the last second, the last step's timings, and the error.
    pub fn stats(&self) -> SimulationStats {
        self.with_state(|s| {
            let now = Instant::now();
            let recent = s.recent.iter().filter(|&&t| now.duration_since(t) <= Duration::from_secs(1)).count();
            SimulationStats { steps_per_second: recent as f64, ..s.stats.clone() }
        })
    }

    /// The settings it runs with.
    pub fn settings(&self) -> SimulationSettings {
        self.with_state(|s| s.settings)
    }

    /// Takes over new settings: gravity, stiffness, time step, damping and grab strength apply
    /// from the next step (a new stiffness or time step refactors once). Returns `false`, and
    /// changes nothing, when they need a new runner ([`SimulationSettings::needs_restart`]).
    /// Invalid numbers show as the stats' error.
    pub fn update_settings(&self, settings: &SimulationSettings) -> bool {
        self.with_state(|s| {
            if s.settings.needs_restart(settings) {
                return false;
            }
            if s.settings != *settings {
                if s.settings.grab_strength != settings.grab_strength && s.grab.is_some() {
                    s.grab_changed = true;
                }
                s.settings = *settings;
                s.params_changed = true;
            }
            true
        })
    }
}

/// Whether `positions` are `rest`'s shape: no vertex apart by more than 1e-9 of its
/// bounding-box diagonal.
fn is_rest_shape(positions: &[DVec3], rest: &Mesh) -> bool {
    let (lo, hi) = rest.bounding_box();
    let limit = 1e-9 * (hi - lo).length();
    positions.len() == rest.positions.len()
        && positions.iter().zip(&rest.positions).all(|(p, q)| p.distance(*q) <= limit)
}

/// The current shape on `mesh` (input frame); points TetGen added follow it.
fn start_shape(document: &Document, mesh: &Mesh) -> Vec<DVec3> {
    let mut start = mesh.positions.clone();
    start.iter_mut().zip(document.positions()).for_each(|(q, p)| *q = *p);
    follow_surface(&mut start, &mesh.positions, document.num_vertices(), &mesh.tetrahedra);
    start
}

/// What the simulation thread owns: the simulation and what a restart goes back to.
struct Stepper {
    simulation: Simulation,
    /// The simulated mesh and its rest geometry (contact is built on them).
    rest: Rest,
    frame: WorkingFrame,
    /// The floor's height, working frame.
    floor: Option<f64>,
    /// Start positions and velocities, working frame.
    initial: (Vec<DVec3>, Vec<DVec3>),
    /// The document's vertices (the first ones; TetGen's points follow).
    surface_vertices: usize,
    num_tetrahedra: usize,
}

/// A grab or release to pass on: `Some(None)` lets go.
type GrabChange = Option<Option<(Vec<u32>, Vec<DVec3>)>>;

/// What the UI asked for since the thread last looked.
enum Work {
    /// The runner is dropped.
    Shutdown,
    /// A restart, already done.
    Reset,
    /// New settings, a grab or release and new contact, if any, and the grab strength.
    Changes {
        grab: GrabChange,
        settings: Option<SimulationSettings>,
        strength: f64,
        contact: Option<(Vec<ColliderSpec>, ContactSettings)>,
    },
}

impl Stepper {
    /// Builds the simulation of `groups` on `rest` (the simulated mesh and its frame) with the
    /// `solver` settings, at `start` (input frame), at rest, with `contact`'s colliders and
    /// settings. `floor` is the floor's height (input frame), if any.
    fn new(
        groups: &[GroupSpec],
        solver: &SolverSettings,
        rest: Rest,
        start: &[DVec3],
        floor: Option<f64>,
        surface_vertices: usize,
        contact: &(Vec<ColliderSpec>, ContactSettings),
    ) -> Result<Stepper, SimulationError> {
        let (system, _) = build_system(&rest, groups, solver.solver_params())?;
        let frame = rest.frame;
        let masses = lumped_masses(&rest.geometry, solver.density);
        let params = solver.dynamics_params(frame.scale);
        let model = contact_model(&contact.0, contact.1, &rest.mesh, &rest.geometry, &frame)
            .map_err(|e| SimulationError::Collider(e.to_string()))?;
        let mut simulation = Simulation::new(system, masses, rest.geometry.positions.clone(), params)?;
        let floor = floor.map(|y| frame.to_working(DVec3::new(0.0, y, 0.0)).y);
        let start: Vec<DVec3> = start.iter().map(|&p| frame.to_working(p)).collect();
        let zero = vec![DVec3::ZERO; start.len()];
        simulation.set_state(&start, &zero)?;
        // As a scene's simulation: vertices starting in a collider are moved out, at rest.
        simulation.set_contact(model)?;
        let num_tetrahedra = rest.mesh.num_tetrahedra();
        Ok(Stepper { simulation, rest, frame, floor, initial: (start, zero), surface_vertices, num_tetrahedra })
    }

    /// The thread's loop: waits for work, applies it, steps while running, at the settings'
    /// speed.
    fn run(mut self, channel: &Channel, notify: impl Fn()) {
        // When the step just taken was due (None: the next one is due at once).
        let mut due = None;
        loop {
            match self.wait(channel) {
                Work::Shutdown => return,
                Work::Reset => {
                    due = None;
                    notify();
                }
                Work::Changes { grab, settings, strength, contact } => {
                    let new_contact = contact.is_some();
                    let problem = self.apply(grab, settings, strength, contact);
                    let running = {
                        let mut state = channel.state.lock().unwrap_or_else(PoisonError::into_inner);
                        if problem.is_some() {
                            state.stats.error = problem;
                        }
                        state.running
                    };
                    if !running {
                        due = None;
                        // Only settings changed while paused; new colliders may have pushed
                        // vertices out: show them.
                        if new_contact {
                            self.show(&mut channel.state.lock().unwrap_or_else(PoisonError::into_inner));
                            notify();
                        }
                        continue;
                    }
                    let outcome = self.step();
                    self.publish(channel, outcome);
                    notify();
                    due = self.pace(channel, due);
                }
            }
        }
    }

    /// After a step: waits until the next one is due at the settings' speed (h / factor after
    /// the last was due, or now when the steps fall behind, so that a slow step is not made up
    /// by a burst), unless the run is paused, reset or shut down meanwhile. Returns when the
    /// next step is due.
    fn pace(&self, channel: &Channel, due: Option<Instant>) -> Option<Instant> {
        let mut state = channel.state.lock().unwrap_or_else(PoisonError::into_inner);
        let factor = state.settings.speed.factor()?;
        // A time step beyond what a Duration holds (a scene's 1e30 s) is not paced.
        let interval = Duration::try_from_secs_f64(self.simulation.params().time_step / factor).ok()?;
        let now = Instant::now();
        let next = due.unwrap_or(now).checked_add(interval)?.max(now);
        while !state.shutdown && !state.reset && state.running {
            let now = Instant::now();
            if now >= next {
                break;
            }
            state = channel.wake.wait_timeout(state, next - now).unwrap_or_else(PoisonError::into_inner).0;
        }
        Some(next)
    }

    /// Waits until there is something to do; a restart is done here, under the lock.
    fn wait(&mut self, channel: &Channel) -> Work {
        let mut state = channel.state.lock().unwrap_or_else(PoisonError::into_inner);
        while !state.shutdown && !state.running && !state.reset && !state.params_changed && !state.contact_changed {
            state = channel.wake.wait(state).unwrap_or_else(PoisonError::into_inner);
        }
        if state.shutdown {
            return Work::Shutdown;
        }
        if std::mem::take(&mut state.reset) {
            // Checked: same lengths as the simulation's.
            let _ = self.simulation.set_state(&self.initial.0, &self.initial.1);
            // Back to the start, moved out of the colliders as at the start.
            self.show(&mut state);
            state.recent.clear();
            state.stats = SimulationStats::default();
            return Work::Reset;
        }
        let settings = std::mem::take(&mut state.params_changed).then_some(state.settings);
        let strength = state.settings.grab_strength;
        let grab = std::mem::take(&mut state.grab_changed).then(|| state.grab.clone());
        let contact = if std::mem::take(&mut state.contact_changed) { state.contact.take() } else { None };
        Work::Changes { grab, settings, strength, contact }
    }

    /// Hands the current positions and what touches to the UI.
    fn show(&self, state: &mut Shared) {
        let n = self.surface_vertices;
        state.latest = Some(to_input(&self.frame, &self.simulation.positions()[..n]));
        state.touching = self.simulation.contact().map(|c| c.touching()[..n].to_vec()).unwrap_or_default();
    }

    /// Applies new settings, a grab or release and new contact; the last problem, if any.
    fn apply(
        &mut self,
        grab: GrabChange,
        settings: Option<SimulationSettings>,
        strength: f64,
        contact: Option<(Vec<ColliderSpec>, ContactSettings)>,
    ) -> Option<RunnerError> {
        let mut problem = None;
        if let Some((colliders, contact)) = contact {
            let rest = &self.rest;
            let built = contact_model(&colliders, contact, &rest.mesh, &rest.geometry, &self.frame)
                .map_err(|e| e.to_string())
                .and_then(|model| self.simulation.set_contact(model).map_err(|e| e.to_string()));
            if let Err(e) = built {
                problem = Some(RunnerError::Contact(e));
            }
        }
        if let Some(settings) = settings
            && let Err(e) = self.simulation.set_params(settings.params(self.frame.scale))
        {
            problem = Some(RunnerError::Settings(e));
        }
        match grab {
            Some(Some((vertices, targets))) => {
                let working = targets.iter().map(|&t| self.frame.to_working(t)).collect();
                if let Err(e) = self.simulation.hold(vertices, working, strength) {
                    problem = Some(RunnerError::Grab(e));
                }
            }
            Some(None) => self.simulation.release(),
            None => {}
        }
        problem
    }

    /// One time step, then the floor's collision.
    fn step(&mut self) -> Result<StepReport, RunnerError> {
        let report = self.simulation.step().map_err(RunnerError::Step)?;
        if let Some(floor) = self.floor {
            collide(&mut self.simulation, floor).map_err(RunnerError::Floor)?;
        }
        Ok(report)
    }

    /// Hands a step's positions and timings to the UI, or its error (which pauses).
    fn publish(&self, channel: &Channel, outcome: Result<StepReport, RunnerError>) {
        let mut state = channel.state.lock().unwrap_or_else(PoisonError::into_inner);
        match outcome {
            Ok(report) => {
                self.show(&mut state);
                let now = Instant::now();
                state.recent.push_back(now);
                while state.recent.front().is_some_and(|&t| now.duration_since(t) > Duration::from_secs(1)) {
                    state.recent.pop_front();
                }
                let stats = &mut state.stats;
                stats.steps += 1;
                stats.step_ms = 1e3 * report.total_seconds;
                stats.local_ms = 1e3 * report.local_seconds;
                stats.global_ms = 1e3 * report.global_seconds;
                stats.contact_ms = 1e3 * report.contact_seconds;
                stats.contact_vertices = report.contact.vertices;
                if let Some(r) = report.residual {
                    stats.checked_steps += 1;
                    if report.unconverged {
                        stats.unconverged_steps += 1;
                        stats.worst_residual = stats.worst_residual.max(r);
                    }
                }
                if let Some(left) = state.steps_left.as_mut() {
                    *left -= 1;
                    if *left == 0 {
                        state.steps_left = None;
                        state.running = false;
                    }
                }
            }
            Err(e) => {
                state.stats.error = Some(e);
                state.running = false;
                state.steps_left = None;
            }
        }
    }
}

/// The document's rest mesh, filled with tetrahedra when asked.
fn simulated_mesh(document: &Document, settings: &SimulationSettings) -> Result<Mesh, SimulationError> {
    let mesh = document.rest_mesh().clone();
    if !settings.tetrahedralize || mesh.num_tetrahedra() > 0 {
        return Ok(mesh);
    }
    let name = document.source().map_or_else(|| "the mesh".to_string(), |p| p.display().to_string());
    let refuse = |why| SimulationError::Tetrahedralize { mesh: name.clone(), why };
    // TetGen's own message for an open surface is cryptic: check first.
    closed_surface(document.triangles()).map_err(refuse)?;
    tetrahedralize(&mesh).map_err(refuse)
}

#[cfg(feature = "tetgen")]
fn tetrahedralize(mesh: &Mesh) -> Result<Mesh, TetrahedraError> {
    use shapeup_core::tetrahedralize::TetrahedralizeError;
    shapeup_core::tetrahedralize::tetrahedralize(mesh, None).map_err(|e| match e {
        // Closed already (checked before): what is left is mostly a surface crossing itself.
        TetrahedralizeError::TetGen(why) => TetrahedraError::TetGen(why),
        TetrahedralizeError::BadInput(why) => TetrahedraError::BadInput(why),
    })
}

#[cfg(not(feature = "tetgen"))]
fn tetrahedralize(_mesh: &Mesh) -> Result<Mesh, TetrahedraError> {
    Err(TetrahedraError::NotBuilt)
}

/// The `[solver]` settings of the document's simulation: the document's (factorization,
/// acceleration, density…) with the panel's time stepping, and the scene default iterations per
/// step without a tolerance (the document's cap and tolerance are for converging static solves).
fn dynamic_solver_settings(document: &Document, settings: &SimulationSettings) -> SolverSettings {
    let defaults = SolverSettings::default();
    SolverSettings {
        mode: Mode::Dynamic,
        iterations: defaults.iterations,
        steps: 1,
        tolerance: 0.0,
        time_step: settings.time_step,
        gravity: if settings.gravity { defaults.gravity } else { [0.0; 3] },
        stiffness: settings.stiffness,
        damping: settings.damping,
        ..document.solver_settings()
    }
}

/// The groups the document's simulation on `mesh` (the rest mesh, maybe with tetrahedra) that
/// starts at `start` (input frame) is built from: the document's (its shape model replaced by
/// one `tet_strain` group for [`DynamicsModel::TetStrain`]) and a floor; and the floor's height
/// (input frame), if any.
fn dynamic_groups(
    document: &Document,
    settings: &SimulationSettings,
    mesh: &Mesh,
    start: &[DVec3],
) -> Result<(Vec<GroupSpec>, Option<f64>), SimulationError> {
    let default_weight = |kind: &str| {
        shapeup_core::constraints::constraint_type(kind)
            .map(|t| t.default_multiplier())
            .map_err(SimulationError::Constraint)
    };
    let tet_strain = settings.model == DynamicsModel::TetStrain;
    if tet_strain && mesh.num_tetrahedra() == 0 {
        return Err(SimulationError::NeedsTetrahedra);
    }
    let mut groups: Vec<GroupSpec> = Vec::with_capacity(document.groups().len() + 2);
    if tet_strain {
        groups.push(GroupSpec {
            kind: "tet_strain".into(),
            name: "tet_strain".into(),
            weight: default_weight("tet_strain")?,
            selection: SelectionSpec::All,
            targets: Targets::default(),
            options: Map::new(),
        });
    }
    let kept = document.groups().iter().filter(|g| !(tet_strain && g.role == GroupRole::Shape));
    groups.extend(kept.map(|g| g.spec.clone()));
    if !settings.floor {
        return Ok((groups, None));
    }
    // Just below the current shape (the floor type's default is below the rest shape), and
    // over the vertices near it only: an inactive floor term still holds its vertices where
    // they are in every iteration, so over the whole body it keeps the shape model from
    // acting (Spot sank to 60 % of its height with tet strain and went flat with edge
    // springs). The others are kept above it by `collide`.
    let mut used = vec![false; start.len()];
    mesh.triangles.iter().flatten().chain(mesh.tetrahedra.iter().flatten()).for_each(|&v| used[v as usize] = true);
    let lowest = start.iter().zip(&used).filter(|(_, u)| **u).map(|(p, _)| p.y).fold(f64::INFINITY, f64::min);
    let (lo, hi) = document.rest_mesh().bounding_box();
    let diagonal = (hi - lo).length();
    let height = lowest - FLOOR_GAP * diagonal;
    let near: Vec<usize> =
        (0..start.len()).filter(|&v| used[v] && start[v].y <= lowest + FLOOR_BAND * diagonal).collect();
    let mut options = Map::new();
    options.insert("height".into(), Value::from(height));
    groups.push(GroupSpec {
        kind: "floor".into(),
        name: "floor".into(),
        weight: default_weight("floor")?,
        selection: SelectionSpec::Vertices(near),
        targets: Targets::default(),
        options,
    });
    Ok((groups, Some(height)))
}

/// The floor lies this fraction of the rest mesh's diagonal below the lowest vertex.
const FLOOR_GAP: f64 = 0.01;

/// The floor constraint covers the vertices up to this fraction of the rest mesh's diagonal
/// above the lowest one (Spot: its hooves; it stands at 98 % of its height with tet strain).
const FLOOR_BAND: f64 = 0.05;

/// Puts the vertices that went below the floor (working frame) back on it, without downward
/// speed and with half their sliding speed (friction). A collision, after the step: what
/// keeps the vertices the floor constraint does not cover above it.
fn collide(simulation: &mut Simulation, floor: f64) -> Result<(), DynamicsError> {
    let below = |(p, m): (&DVec3, &f64)| p.y < floor && *m > 0.0;
    if !simulation.positions().iter().zip(simulation.masses()).any(below) {
        return Ok(());
    }
    let mut x = simulation.positions().to_vec();
    let mut v = simulation.velocities().to_vec();
    for ((x, v), m) in x.iter_mut().zip(&mut v).zip(simulation.masses()) {
        if below((x, m)) {
            x.y = floor;
            *v = DVec3::new(0.5 * v.x, v.y.max(0.0), 0.5 * v.z);
        }
    }
    simulation.set_state(&x, &v)
}

/// Moves the points TetGen added (after the first `surface` vertices) with the surface: the
/// document may be deformed, and interior points left at their rest places would start the
/// body inverted. Their displacements are made harmonic over the tetrahedra's edges
/// (Gauss–Seidel from the mean surface displacement).
fn follow_surface(q: &mut [DVec3], rest: &[DVec3], surface: usize, tetrahedra: &[[u32; 4]]) {
    let n = q.len();
    if n <= surface || tetrahedra.is_empty() {
        return;
    }
    let moved: Vec<DVec3> = q[..surface].iter().zip(rest).map(|(a, b)| *a - *b).collect();
    let largest = moved.iter().map(|d| d.length()).fold(0.0, f64::max);
    if largest == 0.0 {
        return;
    }
    let mut neighbours = vec![Vec::new(); n - surface];
    for t in tetrahedra {
        for (i, &a) in t.iter().enumerate() {
            for &b in &t[i + 1..] {
                let (a, b) = (a as usize, b as usize);
                if a >= surface {
                    neighbours[a - surface].push(b);
                }
                if b >= surface {
                    neighbours[b - surface].push(a);
                }
            }
        }
    }
    let mean = moved.iter().copied().sum::<DVec3>() / surface as f64;
    let mut d: Vec<DVec3> = moved;
    d.resize(n, mean);
    for _ in 0..500 {
        let mut change: f64 = 0.0;
        for (i, list) in neighbours.iter().enumerate().filter(|(_, l)| !l.is_empty()) {
            let next = list.iter().map(|&j| d[j]).sum::<DVec3>() / list.len() as f64;
            change = change.max((next - d[surface + i]).length());
            d[surface + i] = next;
        }
        if change < 1e-4 * largest {
            break;
        }
    }
    for ((q, r), d) in q.iter_mut().zip(rest).zip(&d).skip(surface) {
        *q = *r + *d;
    }
}

fn to_input(frame: &WorkingFrame, q: &[DVec3]) -> Vec<DVec3> {
    q.iter().map(|&p| frame.to_input(p)).collect()
}

impl Drop for SimulationRunner {
    fn drop(&mut self) {
        self.with_state(|s| s.shutdown = true);
        if let Some(thread) = self.thread.take() {
            // A panic in the thread has already been reported by the panic hook.
            let _ = thread.join();
        }
    }
}
