//! Dynamic mode in the editor: a Projective Dynamics simulation of the document's constraints
//! (shape model, handles as pins, smoothing) stepping on its own thread.
//!
//! [`SimulationRunner::start`] turns the document into a dynamic scene (optionally with gravity,
//! a floor just below the shape and TetGen tetrahedra) and starts from the current shape at
//! rest. The UI polls the newest positions ([`SimulationRunner::poll`], never blocking), pulls
//! vertices with [`SimulationRunner::grab`] (no refactorization) and pauses or resumes it; a
//! change of the document's constraints means a new runner.

use crate::document::{Document, EditorError};
use glam::DVec3;
use serde_json::{Map, Value};
use shapeup_core::scene::{GroupSpec, Mode, SelectionSpec, Targets};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::Instant;

/// What the simulation adds to the document's constraints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimulationSettings {
    /// Gravity (0, −9.81, 0) in the mesh's units per s², or none.
    pub gravity: bool,
    /// A floor just below the current shape (all vertices, the floor type's default multiplier).
    pub floor: bool,
    /// Fill the closed surface with tetrahedra (TetGen; needs the `tetgen` feature).
    pub tetrahedralize: bool,
    /// Velocity damping d ∈ [0, 1).
    pub damping: f64,
}

impl Default for SimulationSettings {
    fn default() -> Self {
        SimulationSettings { gravity: true, floor: true, tetrahedralize: false, damping: 0.02 }
    }
}

/// How strongly a grab pulls (fraction of the distance closed per step).
pub const GRAB_STRENGTH: f64 = 0.3;

#[derive(Default)]
struct Shared {
    running: bool,
    shutdown: bool,
    reset: bool,
    grab: Option<(Vec<u32>, Vec<DVec3>)>,
    /// Newest positions (input frame), taken by `poll`.
    latest: Option<Vec<DVec3>>,
    steps: u64,
    step_ms: f64,
    error: Option<String>,
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
    /// [`EditorError::Simulation`] when the dynamic system cannot be built (e.g. tetrahedralization
    /// of an open surface, or a build without TetGen).
    pub fn start(
        document: &Document,
        settings: SimulationSettings,
        notify: impl Fn() + Send + 'static,
    ) -> Result<SimulationRunner, EditorError> {
        let mut scene = document.to_scene("");
        scene.solver.mode = Mode::Dynamic;
        scene.solver.gravity = if settings.gravity { [0.0, -9.81, 0.0] } else { [0.0; 3] };
        scene.solver.damping = settings.damping;
        scene.mesh.tetrahedralize = settings.tetrahedralize;
        if settings.floor {
            // Just below the current shape (the floor type's default is below the rest shape).
            let lowest = document.positions().iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
            let (lo, hi) = document.rest_mesh().bounding_box();
            let mut options = Map::new();
            options.insert("height".into(), Value::from(lowest - 0.01 * (hi - lo).length()));
            scene.groups.push(GroupSpec {
                kind: "floor".into(),
                name: "floor".into(),
                weight: shapeup_core::constraints::constraint_type("floor")
                    .map_err(|e| EditorError::Simulation(e.to_string()))?
                    .default_multiplier(),
                selection: SelectionSpec::All,
                targets: Targets::default(),
                options,
            });
        }
        let solve_error = EditorError::Simulation;
        let mut loaded = scene
            .build(document.rest_mesh().clone(), shapeup_core::warnings::Warnings::new(), 0.0)
            .map_err(|e| solve_error(e.to_string()))?;
        let mut simulation = loaded.start_simulation().map_err(|e| solve_error(e.to_string()))?;
        // Start from the current shape at rest (vertices TetGen added start at their rest place).
        let mut start = loaded.rest.positions.clone();
        for (q, &p) in start.iter_mut().zip(document.positions()) {
            *q = loaded.frame.to_working(p);
        }
        let zero = vec![DVec3::ZERO; start.len()];
        simulation.set_state(&start, &zero).map_err(|e| solve_error(e.to_string()))?;
        let initial = (start.clone(), zero);
        let surface_vertices = document.num_vertices();
        let frame = loaded.frame;
        let channel = Arc::new(Channel::default());
        let thread_channel = Arc::clone(&channel);
        let thread = std::thread::Builder::new()
            .name("shapeup-simulation".into())
            .spawn(move || {
                loop {
                    let grab = {
                        let mut state = thread_channel.state.lock().unwrap_or_else(PoisonError::into_inner);
                        while !state.shutdown && !state.running && !state.reset {
                            state = thread_channel.wake.wait(state).unwrap_or_else(PoisonError::into_inner);
                        }
                        if state.shutdown {
                            return;
                        }
                        if std::mem::take(&mut state.reset) {
                            // Checked: same lengths as the simulation's.
                            let _ = simulation.set_state(&initial.0, &initial.1);
                            state.latest = Some(to_input(&frame, &initial.0[..surface_vertices]));
                            state.steps = 0;
                            drop(state);
                            notify();
                            continue;
                        }
                        state.grab.clone()
                    };
                    let grabbed = match grab {
                        Some((vertices, targets)) => {
                            let working = targets.iter().map(|&t| frame.to_working(t)).collect();
                            simulation.grab(vertices, working, GRAB_STRENGTH).is_ok()
                        }
                        None => false,
                    };
                    if !grabbed {
                        simulation.release();
                    }
                    let t = Instant::now();
                    let outcome = simulation.step();
                    let mut state = thread_channel.state.lock().unwrap_or_else(PoisonError::into_inner);
                    match outcome {
                        Ok(_) => {
                            state.latest = Some(to_input(&frame, &simulation.positions()[..surface_vertices]));
                            state.steps += 1;
                            state.step_ms = 1e3 * t.elapsed().as_secs_f64();
                        }
                        Err(e) => {
                            state.error = Some(e.to_string());
                            state.running = false;
                        }
                    }
                    drop(state);
                    notify();
                }
            })
            .map_err(|e| solve_error(format!("cannot start the simulation thread: {e}")))?;
        Ok(SimulationRunner { channel, thread: Some(thread), num_tetrahedra: loaded.mesh.num_tetrahedra() })
    }

    fn with_state<T>(&self, f: impl FnOnce(&mut Shared) -> T) -> T {
        let mut state = self.channel.state.lock().unwrap_or_else(PoisonError::into_inner);
        let out = f(&mut state);
        self.channel.wake.notify_one();
        out
    }

    /// Runs or pauses the time stepping.
    pub fn set_running(&self, running: bool) {
        self.with_state(|s| s.running = running);
    }

    /// Whether it is stepping.
    pub fn is_running(&self) -> bool {
        self.with_state(|s| s.running)
    }

    /// Back to the shape it started from, at rest (stays running or paused).
    pub fn reset(&self) {
        self.with_state(|s| s.reset = true);
    }

    /// Pulls `vertices` towards `targets` (input frame) from the next step on.
    pub fn grab(&self, vertices: Vec<u32>, targets: Vec<DVec3>) {
        self.with_state(|s| s.grab = Some((vertices, targets)));
    }

    /// Lets go.
    pub fn release(&self) {
        self.with_state(|s| s.grab = None);
    }

    /// The newest positions of the document's vertices (input frame) since the last poll.
    pub fn poll(&self) -> Option<Vec<DVec3>> {
        self.with_state(|s| s.latest.take())
    }

    /// Steps taken, milliseconds of the last step, and the error that stopped it, if any.
    pub fn stats(&self) -> (u64, f64, Option<String>) {
        self.with_state(|s| (s.steps, s.step_ms, s.error.clone()))
    }
}

fn to_input(frame: &shapeup_core::geometry::WorkingFrame, q: &[DVec3]) -> Vec<DVec3> {
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
