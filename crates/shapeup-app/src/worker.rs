//! A background solver thread, so that the UI never waits for a solve.
//!
//! The UI sends the newest [`SolveRequest`] (the document's editable state: handle targets,
//! weights, groups, plus iterations) with [`SolverWorker::request`]; a request that arrives
//! while the worker is busy replaces any pending one, so stale targets are never solved. The
//! worker keeps its own [`Solver`] and warm-starts every solve from its last positions; it
//! rebuilds the system only when the groups or the rest shape changed. Results come back
//! through [`SolverWorker::poll`], which never blocks.

use crate::document::{Document, EditState, EditorError, Solver};
use glam::DVec3;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;

/// What to solve.
#[derive(Debug, Clone)]
pub struct SolveRequest {
    /// The editable state: groups with their weights and handle targets, rest shape.
    pub state: EditState,
    /// Local-global iterations to run.
    pub iterations: usize,
    /// The document's shape epoch: when it differs from the worker's, the worker restarts
    /// from `start` (after a reset or a new rest shape).
    pub epoch: u64,
    /// Positions (input frame) the epoch starts from.
    pub start: Arc<Vec<DVec3>>,
}

impl SolveRequest {
    /// A request for the document's current state and iteration count.
    pub fn from_document(document: &Document) -> Self {
        SolveRequest {
            state: document.state().clone(),
            iterations: document.iterations(),
            epoch: document.epoch(),
            start: Arc::clone(document.epoch_start()),
        }
    }
}

/// What a solve produced.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveResult {
    /// The sequence number [`SolverWorker::request`] returned for the request solved.
    pub seq: u64,
    /// The request's epoch (see [`Document::accept_positions`]).
    pub epoch: u64,
    /// Positions after the solve (input frame); the previous ones when `error` is set (empty
    /// if the worker never built a system).
    pub positions: Vec<DVec3>,
    /// Milliseconds in local steps.
    pub local_ms: f64,
    /// Milliseconds in global steps.
    pub global_ms: f64,
    /// Milliseconds rebuilding and factoring.
    pub setup_ms: f64,
    /// E after each iteration.
    pub energy: Vec<f64>,
    /// Why nothing was solved (no handles, a singular system, a group that cannot be built).
    pub error: Option<EditorError>,
}

impl SolveResult {
    /// Hands the positions to the document (when of its current epoch and without error);
    /// returns whether they were taken.
    pub fn apply_to(&self, document: &mut Document) -> bool {
        self.error.is_none() && document.accept_positions(self.epoch, &self.positions)
    }
}

/// The request slot shared with the thread.
#[derive(Default)]
struct Pending {
    request: Option<(u64, SolveRequest)>,
    shutdown: bool,
}

#[derive(Default)]
struct Shared {
    pending: Mutex<Pending>,
    wake: Condvar,
}

/// A solver on its own thread; dropping it stops and joins the thread.
#[derive(Debug)]
pub struct SolverWorker {
    shared: Arc<Shared>,
    results: Receiver<SolveResult>,
    thread: Option<JoinHandle<()>>,
    next_seq: u64,
}

impl std::fmt::Debug for Shared {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Shared")
    }
}

impl SolverWorker {
    /// Starts the thread (it waits for requests).
    ///
    /// # Errors
    /// The OS refused to start a thread.
    pub fn spawn() -> std::io::Result<SolverWorker> {
        Self::spawn_with_notify(|| {})
    }

    /// Starts the thread; `notify` is called (on the solver thread) after each result is sent,
    /// e.g. to wake the UI so that it polls without redrawing continuously.
    ///
    /// # Errors
    /// The OS refused to start a thread.
    pub fn spawn_with_notify(notify: impl Fn() + Send + 'static) -> std::io::Result<SolverWorker> {
        let shared = Arc::new(Shared::default());
        let (sender, results) = channel();
        let thread_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("shapeup-solver".into())
            .spawn(move || run(&thread_shared, &sender, &notify))?;
        Ok(SolverWorker { shared, results, thread: Some(thread), next_seq: 0 })
    }

    /// Queues a request, replacing any pending one not started yet; returns its sequence
    /// number (increasing from 1).
    pub fn request(&mut self, request: SolveRequest) -> u64 {
        self.next_seq += 1;
        let mut pending = self.shared.pending.lock().unwrap_or_else(PoisonError::into_inner);
        pending.request = Some((self.next_seq, request));
        self.shared.wake.notify_one();
        self.next_seq
    }

    /// The newest result that arrived since the last poll (older ones are dropped), without
    /// blocking.
    pub fn poll(&mut self) -> Option<SolveResult> {
        let mut newest = None;
        loop {
            match self.results.try_recv() {
                Ok(result) => newest = Some(result),
                Err(TryRecvError::Empty | TryRecvError::Disconnected) => return newest,
            }
        }
    }

    /// Whether a request is queued and not started yet.
    pub fn is_pending(&self) -> bool {
        self.shared.pending.lock().unwrap_or_else(PoisonError::into_inner).request.is_some()
    }

    /// Stops the thread after its current solve and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        {
            let mut pending = self.shared.pending.lock().unwrap_or_else(PoisonError::into_inner);
            pending.shutdown = true;
            pending.request = None;
            self.shared.wake.notify_one();
        }
        if let Some(thread) = self.thread.take() {
            // A panic in the solver thread has already been reported by the panic hook.
            let _ = thread.join();
        }
    }
}

impl Drop for SolverWorker {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// The thread: waits for the newest request, solves it, sends the result.
fn run(shared: &Shared, results: &Sender<SolveResult>, notify: &dyn Fn()) {
    let mut solver = Solver::new();
    let mut epoch = None;
    loop {
        let (seq, request) = {
            let mut pending = shared.pending.lock().unwrap_or_else(PoisonError::into_inner);
            loop {
                if pending.shutdown {
                    return;
                }
                if let Some(request) = pending.request.take() {
                    break request;
                }
                pending = shared.wake.wait(pending).unwrap_or_else(PoisonError::into_inner);
            }
        };
        let result = solve(&mut solver, &mut epoch, seq, &request);
        if results.send(result).is_err() {
            return;
        }
        notify();
    }
}

fn solve(solver: &mut Solver, epoch: &mut Option<u64>, seq: u64, request: &SolveRequest) -> SolveResult {
    let mut result = SolveResult {
        seq,
        epoch: request.epoch,
        positions: Vec::new(),
        local_ms: 0.0,
        global_ms: 0.0,
        setup_ms: 0.0,
        energy: Vec::new(),
        error: None,
    };
    let started = std::time::Instant::now();
    let outcome = solver.sync(&request.state).and_then(|()| {
        if *epoch != Some(request.epoch) {
            solver.set_positions(&request.start);
            *epoch = Some(request.epoch);
        }
        if !request.state.has_handles() {
            return Err(EditorError::NoHandles);
        }
        solver.solve(request.iterations)
    });
    match outcome {
        Ok(report) => {
            result.local_ms = 1e3 * report.local_seconds;
            result.global_ms = 1e3 * report.global_seconds;
            result.setup_ms = 1e3 * report.setup_seconds;
            result.energy = report.energies;
        }
        Err(e) => {
            result.setup_ms = 1e3 * started.elapsed().as_secs_f64();
            result.error = Some(e);
        }
    }
    result.positions = solver.positions();
    result
}
