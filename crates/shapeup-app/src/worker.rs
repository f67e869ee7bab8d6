//! A background solver thread that converges the shape while the UI stays responsive.
//!
//! The UI sends the newest [`SolveRequest`] (the document's editable state: handle targets,
//! weights, groups, the iteration cap and the tolerance) with [`SolverWorker::request`]. The
//! worker keeps its own [`EditSolver`] and iterates from its current positions in chunks, posting a
//! [`SolveResult`] after each, until
//! - an iteration meets the request's tolerance (`shapeup_core::solver::is_converged`: its
//!   relative energy change is at most the tolerance, or E is numerically zero),
//! - the request's iteration cap is reached,
//! - a newer request arrives: it takes over at once, from the current positions (a request that
//!   arrives while a chunk runs stops it after the current iteration and replaces any pending
//!   one, so stale targets are never solved),
//! - or the worker shuts down.
//!
//! Then it sleeps until the next request. A chunk lasts about [`WorkerParams::chunk_budget`]
//! (from the measured time per iteration), so a newer request waits about that long at most;
//! the first chunk after a request fits [`WorkerParams::first_chunk_budget`] (at least one
//! iteration), so the shape answers each drag event quickly. The system is rebuilt only when the groups or the
//! rest shape changed. Results come back through [`SolverWorker::poll`], which never blocks; a
//! result not taken yet absorbs the next chunk of the same request, so results never pile up
//! (a hidden window that does not poll holds one shape, not one per chunk). A UI that would
//! rather draw the answer to a drag than the shape before it can block briefly in
//! [`SolverWorker::wait_for`].

use crate::document::Document;
use crate::edit_state::{EditSolver, EditState, Rest};
use crate::error::EditorError;
use glam::DVec3;
use shapeup_core::solver::{ENERGY_FLOOR, STATIC_RESIDUAL_LIMIT, SolveError, SolveReport, is_converged};
use std::fmt;
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// What to solve.
#[derive(Debug, Clone)]
pub struct SolveRequest {
    /// The editable state: groups with their weights and handle targets, rest shape.
    pub state: EditState,
    /// The most local-global iterations the convergence after this request may run.
    pub iterations: usize,
    /// Convergence is reached when the relative energy change of an iteration,
    /// |E_k − E_{k−1}| / E_{k−1}, is at most this (or E = 0); 0 runs to the cap.
    pub tolerance: f64,
    /// The document's shape epoch: when it differs from the worker's, the worker restarts
    /// from `start` (after a reset or a new rest shape).
    pub epoch: u64,
    /// Positions (input frame) the epoch starts from.
    pub start: Arc<Vec<DVec3>>,
    /// Part of a drag: newer requests are expected within a frame. After such a request's first
    /// chunk the worker waits up to [`WorkerParams::live_pause`] for the next one before
    /// iterating on, leaving the CPU to the frame that draws its answer.
    pub live: bool,
}

impl SolveRequest {
    /// A request for the document's current state, iteration cap and tolerance.
    pub fn from_document(document: &Document) -> Self {
        SolveRequest {
            state: document.state().clone(),
            iterations: document.iterations(),
            tolerance: document.tolerance(),
            epoch: document.epoch(),
            start: Arc::clone(document.epoch_start()),
            live: document.is_dragging(),
        }
    }
}

/// One or more chunks of a convergence (consecutive ones merge until polled): the shape after
/// them and how far the convergence is.
#[derive(Debug, Clone, PartialEq)]
pub struct SolveResult {
    /// The sequence number [`SolverWorker::request`] returned for the request solved.
    pub seq: u64,
    /// The request's epoch (see [`Document::accept_positions`]).
    pub epoch: u64,
    /// Positions after the last chunk (input frame); the last good ones when `error` is set (empty
    /// if the worker never built a system).
    pub positions: Vec<DVec3>,
    /// Iterations run since the request began, this chunk included.
    pub iterations: usize,
    /// The tolerance was reached (then `finished` too).
    pub converged: bool,
    /// Nothing more comes for this request: converged, at the iteration cap, or failed.
    pub finished: bool,
    /// |E_k − E_{k−1}| / E_{k−1} of the last iteration; `None` when unknown (the first
    /// iteration after a request has no previous energy).
    pub relative_change: Option<f64>,
    /// Milliseconds in local steps (these chunks).
    pub local_ms: f64,
    /// Milliseconds in global steps (these chunks).
    pub global_ms: f64,
    /// Milliseconds rebuilding and factoring (these chunks).
    pub setup_ms: f64,
    /// E after each iteration of these chunks (the last `energy.len()` of `iterations`). With
    /// colliders or self-collision, one E per chunk of the core's static contact solve (a
    /// detection every 10 iterations), and `iterations` counts those chunks.
    pub energy: Vec<f64>,
    /// Why nothing was solved (no handles, a singular system, a group that cannot be built, a
    /// non-finite energy).
    pub error: Option<EditorError>,
    /// Per vertex, whether it touches a collider or the surface itself after the last chunk
    /// (empty without colliders and self-collision).
    pub touching: Vec<bool>,
    /// ‖∇E‖ after the last chunk over ‖∇E‖ where the request began, while every chunk ran all
    /// its iterations ([`shapeup_core::solver::SolveReport::residual`]; each chunk starts where
    /// the last ended, so the request's is the product of its chunks'); `None` otherwise.
    pub residual: Option<f64>,
    /// Groups whose weights the factorization cannot resolve
    /// ([`shapeup_core::solver::SolveReport::lost_groups`]): how many, and the first described.
    pub lost_groups: Option<(usize, String)>,
    /// Seconds the convergence should still take, while it runs: iterations until the
    /// relative change reaches the tolerance at the rate it has fallen over the last iterations
    /// (geometric, as local-global iterations converge), times the seconds per iteration; at
    /// most what the iteration cap leaves. `None` when unknown (too few iterations, no fall).
    pub seconds_left: Option<f64>,
    /// The user stopped the convergence ([`SolverWorker::stop`]): finished, not converged.
    pub stopped: bool,
}

impl SolveResult {
    /// A result of `job` where it stands, with nothing of a chunk in it yet (no positions,
    /// energies, timings; not finished), for [`Converger`] to fill in.
    fn nothing_yet(job: &Job) -> SolveResult {
        SolveResult {
            seq: job.seq,
            epoch: job.request.epoch,
            positions: Vec::new(),
            iterations: job.done,
            converged: false,
            finished: false,
            relative_change: None,
            local_ms: 0.0,
            global_ms: 0.0,
            setup_ms: 0.0,
            energy: Vec::new(),
            error: None,
            touching: Vec::new(),
            residual: None,
            lost_groups: None,
            seconds_left: None,
            stopped: false,
        }
    }

    /// Hands the positions to the document (when of its current epoch and without error);
    /// returns whether they were taken.
    pub fn apply_to(&self, document: &mut Document) -> bool {
        self.error.is_none() && document.accept_positions(self.epoch, &self.positions)
    }

    /// E after the last iteration.
    pub fn last_energy(&self) -> Option<f64> {
        self.energy.last().copied()
    }

    /// Milliseconds per local-global iteration in these chunks (setup excluded).
    pub fn ms_per_iteration(&self) -> Option<f64> {
        (!self.energy.is_empty()).then(|| (self.local_ms + self.global_ms) / self.energy.len() as f64)
    }

    /// One line for the status bar, e.g. "converged: 153 iterations, E 1.234e-3" (same as
    /// its `Display`).
    pub fn status(&self) -> String {
        self.to_string()
    }

    /// Takes in the next chunk of the same request, which the UI did not see apart.
    fn absorb(&mut self, next: SolveResult) {
        self.positions = next.positions;
        self.iterations = next.iterations;
        self.converged = next.converged;
        self.finished = next.finished;
        self.relative_change = next.relative_change;
        self.local_ms += next.local_ms;
        self.global_ms += next.global_ms;
        self.setup_ms += next.setup_ms;
        self.energy.extend(next.energy);
        self.error = next.error;
        self.touching = next.touching;
        self.residual = next.residual;
        self.lost_groups = next.lost_groups;
        self.seconds_left = next.seconds_left;
        self.stopped = next.stopped;
    }
}

impl fmt::Display for SolveResult {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(error) = &self.error {
            return write!(f, "solve failed: {error}");
        }
        let n = self.iterations;
        let noun = if n == 1 { "iteration" } else { "iterations" };
        if self.converged {
            write!(f, "converged: {n} {noun}")?;
        } else if self.stopped {
            write!(f, "stopped at {n} {noun}, not converged (any change converges again)")?;
        } else if self.finished {
            write!(f, "stopped at the {n}-iteration cap")?;
            if let Some(r) = self.residual.filter(|&r| r > STATIC_RESIDUAL_LIMIT) {
                // As the command line's `unconverged` warning says it.
                write!(f, " short of the minimum (the energy's gradient {r:.3} times the start's; raise the cap)")?;
            }
        } else {
            write!(f, "solving… {n} {noun}")?;
        }
        if let Some(e) = self.last_energy() {
            write!(f, ", E {e:.3e}")?;
        }
        if let Some(left) = self.seconds_left.filter(|_| !self.finished) {
            write!(f, ", about {} left", seconds_text(left))?;
        }
        if let Some((count, first)) = &self.lost_groups {
            // As the command line's `groups_lost_to_round_off` warning says it.
            write!(
                f,
                "; {count} group(s) left to round-off, first {first}: bring the weights within 1e12 of each other"
            )?;
        }
        Ok(())
    }
}

/// "0.4 s", "12 s", "3 min 20 s": a time left, as precise as it is worth.
fn seconds_text(s: f64) -> String {
    if s < 10.0 {
        format!("{s:.1} s")
    } else if s < 60.0 {
        format!("{s:.0} s")
    } else {
        let whole = s.round().min(1e9) as u64;
        format!("{} min {} s", whole / 60, whole % 60)
    }
}

/// How the worker sizes its chunks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WorkerParams {
    /// Wall time a chunk aims at, about a frame: the longest a newer request waits and the
    /// interval between results.
    pub chunk_budget: Duration,
    /// Wall time the first chunk after a request aims at (at least one iteration), so that the
    /// first update after a drag event comes fast.
    pub first_chunk_budget: Duration,
    /// How long the worker waits for a newer request after the first chunk of a live one
    /// ([`SolveRequest::live`]) before converging on: a user holding still mid-drag sees the
    /// shape settle after this.
    pub live_pause: Duration,
}

/// [`WorkerParams::chunk_budget`] by default: about two frames at 60 Hz.
pub const DEFAULT_CHUNK_BUDGET: Duration = Duration::from_millis(30);

/// [`WorkerParams::first_chunk_budget`] by default.
pub const DEFAULT_FIRST_CHUNK_BUDGET: Duration = Duration::from_millis(10);

/// [`WorkerParams::live_pause`] by default: longer than a frame on a software renderer, short
/// enough that holding still looks like letting go.
pub const DEFAULT_LIVE_PAUSE: Duration = Duration::from_millis(100);

impl Default for WorkerParams {
    fn default() -> Self {
        WorkerParams {
            chunk_budget: DEFAULT_CHUNK_BUDGET,
            first_chunk_budget: DEFAULT_FIRST_CHUNK_BUDGET,
            live_pause: DEFAULT_LIVE_PAUSE,
        }
    }
}

/// The request slot shared with the thread.
#[derive(Default)]
struct Pending {
    request: Option<(u64, SolveRequest)>,
    /// The thread is converging a request (cleared before its finished result is sent).
    converging: bool,
    /// [`SolverWorker::stop`] asked to end the convergence under way.
    stop: bool,
    shutdown: bool,
}

#[derive(Default)]
struct Shared {
    pending: Mutex<Pending>,
    wake: Condvar,
    /// Results not polled yet, oldest first, at most one per request.
    results: Mutex<Vec<SolveResult>>,
    /// Signalled whenever a result is queued.
    posted: Condvar,
}

impl Shared {
    fn lock(&self) -> MutexGuard<'_, Pending> {
        self.pending.lock().unwrap_or_else(PoisonError::into_inner)
    }

    fn results(&self) -> MutexGuard<'_, Vec<SolveResult>> {
        self.results.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Queues a result, merged into the one of the same request the UI has not taken yet.
    fn post(&self, result: SolveResult) {
        let mut results = self.results();
        match results.last_mut() {
            Some(last) if last.seq == result.seq => last.absorb(result),
            _ => results.push(result),
        }
        self.posted.notify_all();
    }

    /// Waits up to `pause` for a newer request (or shutdown).
    fn pause_for_next(&self, pause: Duration) {
        let deadline = Instant::now() + pause;
        let mut pending = self.lock();
        while pending.request.is_none() && !pending.shutdown {
            let Some(left) = deadline.checked_duration_since(Instant::now()) else { return };
            pending = self.wake.wait_timeout(pending, left).unwrap_or_else(PoisonError::into_inner).0;
        }
    }

    /// Whether a newer request or a stop waits: the chunk under way stops after its current
    /// iteration.
    fn interrupted(&self) -> bool {
        let pending = self.lock();
        pending.request.is_some() || pending.stop
    }
}

/// A solver on its own thread; dropping it stops and joins the thread.
#[derive(Debug)]
pub struct SolverWorker {
    shared: Arc<Shared>,
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
        Self::spawn_with(WorkerParams::default(), || {})
    }

    /// Starts the thread; `notify` is called (on the solver thread) after each chunk's result is
    /// queued, e.g. to wake the UI so that it polls without redrawing continuously.
    ///
    /// # Errors
    /// The OS refused to start a thread.
    pub fn spawn_with_notify(notify: impl Fn() + Send + 'static) -> std::io::Result<SolverWorker> {
        Self::spawn_with(WorkerParams::default(), notify)
    }

    /// [`SolverWorker::spawn_with_notify`] with chosen chunk budgets.
    ///
    /// # Errors
    /// The OS refused to start a thread.
    pub fn spawn_with(params: WorkerParams, notify: impl Fn() + Send + 'static) -> std::io::Result<SolverWorker> {
        let shared = Arc::new(Shared::default());
        let thread_shared = Arc::clone(&shared);
        let thread = std::thread::Builder::new()
            .name("shapeup-solver".into())
            .spawn(move || run(&thread_shared, &notify, params))?;
        Ok(SolverWorker { shared, thread: Some(thread), next_seq: 0 })
    }

    /// Ends the convergence under way after its current iteration (dropping any request not
    /// started yet): its last result comes finished, with [`SolveResult::stopped`], at the
    /// shape reached. Nothing happens when the worker is idle. The next request converges on
    /// from there.
    pub fn stop(&mut self) {
        let mut pending = self.shared.lock();
        pending.request = None;
        pending.stop = pending.converging;
        self.shared.wake.notify_all();
    }

    /// Queues a request, replacing any pending one not started yet; the convergence under way
    /// switches to it after its current chunk. Returns its sequence number (increasing from 1).
    pub fn request(&mut self, request: SolveRequest) -> u64 {
        self.next_seq += 1;
        let mut pending = self.shared.lock();
        pending.request = Some((self.next_seq, request));
        self.shared.wake.notify_one();
        self.next_seq
    }

    /// The newest result that arrived since the last poll (those of older requests are
    /// dropped), without blocking. It holds every chunk of its request since the last poll.
    pub fn poll(&mut self) -> Option<SolveResult> {
        self.poll_all().pop()
    }

    /// The results that arrived since the last poll, oldest first, one per request (its chunks
    /// merged), without blocking (e.g. to plot the energy of every iteration).
    pub fn poll_all(&mut self) -> Vec<SolveResult> {
        std::mem::take(&mut *self.shared.results())
    }

    /// Blocks until a result of request `seq` (or a newer one) is queued, the worker has nothing
    /// left to do, or `timeout` passes; whether such a result is there to poll. An editor calls
    /// it before drawing a frame right after a drag, so the frame shows the answer to the drag
    /// instead of the shape before it.
    pub fn wait_for(&self, seq: u64, timeout: Duration) -> bool {
        let deadline = Instant::now() + timeout;
        let arrived = || self.shared.results().iter().any(|r| r.seq >= seq);
        loop {
            // The results lock is never held while taking the request lock (the thread takes
            // them in the other order).
            let now = Instant::now();
            if arrived() || now >= deadline || !self.is_busy() {
                return arrived();
            }
            let results = self.shared.results();
            if results.iter().any(|r| r.seq >= seq) {
                return true;
            }
            // Short slices: a worker that goes idle without a result wakes nobody.
            let slice = (deadline - now).min(Duration::from_millis(5));
            drop(self.shared.posted.wait_timeout(results, slice).unwrap_or_else(PoisonError::into_inner));
        }
    }

    /// Whether a request is queued and not started yet.
    pub fn is_pending(&self) -> bool {
        self.shared.lock().request.is_some()
    }

    /// Whether a request is queued or being converged: more results will come. Once false, the
    /// finished result of the newest request is there to poll.
    pub fn is_busy(&self) -> bool {
        let pending = self.shared.lock();
        pending.request.is_some() || pending.converging
    }

    /// Stops the thread after its current chunk and waits for it (also done on drop).
    pub fn shutdown(&mut self) {
        {
            let mut pending = self.shared.lock();
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

/// The thread: takes the newest request, converges it chunk by chunk, posts each result; sleeps
/// on the condvar when nothing is left to do.
fn run(shared: &Shared, notify: &dyn Fn(), params: WorkerParams) {
    let mut worker = Converger::new(params);
    let mut job: Option<Job> = None;
    loop {
        {
            let mut pending = shared.lock();
            loop {
                if pending.shutdown {
                    return;
                }
                // A stop ends the convergence where it is: one finished result says so.
                if std::mem::take(&mut pending.stop)
                    && let Some(stopped) = job.take()
                {
                    pending.converging = false;
                    shared.post(worker.stopped(&stopped));
                    drop(pending);
                    notify();
                    pending = shared.lock();
                    continue;
                }
                // The newest target wins at once, continuing from the current positions.
                if let Some((seq, request)) = pending.request.take() {
                    job = Some(Job::new(seq, request));
                    pending.converging = true;
                    break;
                }
                if job.is_some() {
                    break;
                }
                pending = shared.wake.wait(pending).unwrap_or_else(PoisonError::into_inner);
            }
        }
        let Some(current) = job.as_mut() else { continue };
        let first = current.done == 0;
        let result = worker.step(current, &|| shared.interrupted());
        if result.finished {
            job = None;
            // Under the request lock, so that whoever sees the worker idle finds the result.
            let mut pending = shared.lock();
            pending.converging = false;
            shared.post(result);
        } else {
            let pause = first && current.request.live;
            shared.post(result);
            notify();
            if pause {
                shared.pause_for_next(params.live_pause);
            }
            continue;
        }
        notify();
    }
}

/// One request being converged.
struct Job {
    seq: u64,
    request: SolveRequest,
    /// Synced the solver with the request's state.
    started: bool,
    /// Iterations since the request began.
    done: usize,
    /// E after the last iteration, for the relative change across chunks.
    last_energy: Option<f64>,
    /// Iterations of the last chunk (a chunk at most doubles the previous one, in case the
    /// time estimate was off).
    last_chunk: usize,
    /// The request's relative residual so far ([`SolveResult::residual`]).
    residual: Option<f64>,
    /// (iterations done, relative change) after recent chunks, for [`Job::seconds_left`].
    changes: std::collections::VecDeque<(usize, f64)>,
}

impl Job {
    fn new(seq: u64, request: SolveRequest) -> Self {
        Job {
            seq,
            request,
            started: false,
            done: 0,
            last_energy: None,
            last_chunk: 0,
            residual: Some(1.0),
            changes: std::collections::VecDeque::new(),
        }
    }

    /// [`SolveResult::seconds_left`] after a chunk that ended at relative change `change`.
    fn seconds_left(&mut self, change: Option<f64>, seconds_per_iteration: Option<f64>) -> Option<f64> {
        let change = change.filter(|c| c.is_finite() && *c > 0.0)?;
        self.changes.push_back((self.done, change));
        // The rate over at least RATE_SPAN iterations back (accelerated iterations' changes
        // wander: a longer span smooths them), from the newest sample that far back.
        while self.changes.len() > 2 && self.changes[1].0 + RATE_SPAN <= self.done {
            self.changes.pop_front();
        }
        let &(k0, c0) = self.changes.front()?;
        let tolerance = self.request.tolerance;
        if self.done < k0 + RATE_SPAN || tolerance <= 0.0 {
            return None;
        }
        let rate = (change / c0).ln() / (self.done - k0) as f64;
        // Not falling (or NaN): no estimate.
        if rate.is_nan() || rate >= 0.0 {
            return None;
        }
        let left = if change <= tolerance { 0.0 } else { (tolerance / change).ln() / rate };
        let left = left.min(self.request.iterations.saturating_sub(self.done) as f64);
        seconds_per_iteration.map(|s| left * s)
    }
}

/// Iterations over which [`Job::seconds_left`] measures how fast the relative change falls.
const RATE_SPAN: usize = 20;

/// The thread's solver and what it remembers between requests.
struct Converger {
    params: WorkerParams,
    solver: EditSolver,
    /// The epoch the solver's positions belong to.
    epoch: Option<u64>,
    /// Positions (input frame) after the last good chunk of `epoch`, restored after a failure.
    last_good: Vec<DVec3>,
    /// Seconds per iteration measured on the last chunk.
    seconds_per_iteration: Option<f64>,
    /// The rest shape the estimate was measured on (another mesh, another cost).
    measured_on: Option<Arc<Rest>>,
}

impl Converger {
    fn new(params: WorkerParams) -> Self {
        Converger {
            params,
            solver: EditSolver::new(),
            epoch: None,
            last_good: Vec::new(),
            seconds_per_iteration: None,
            measured_on: None,
        }
    }

    /// Iterations for the next chunk of `job`: as many as fit its budget, at least one, at most
    /// twice the previous chunk and no more than the cap leaves.
    fn chunk_size(&self, job: &Job) -> usize {
        let remaining = job.request.iterations.saturating_sub(job.done);
        let budget = if job.done == 0 { self.params.first_chunk_budget } else { self.params.chunk_budget };
        let fit = match self.seconds_per_iteration {
            // A float-to-int `as` saturates, so a tiny estimate cannot overflow.
            Some(s) if s > 0.0 => (budget.as_secs_f64() / s) as usize,
            _ => 1,
        };
        let fit = if job.done == 0 { fit } else { fit.min(job.last_chunk.saturating_mul(2)) };
        fit.max(1).min(remaining)
    }

    /// Syncs the solver with the request and moves to its epoch.
    fn start(&mut self, request: &SolveRequest) -> Result<(), EditorError> {
        self.solver.sync(&request.state)?;
        if self.epoch != Some(request.epoch) {
            self.solver.set_positions(&request.start);
            self.epoch = Some(request.epoch);
            self.last_good = self.solver.positions();
        }
        if !self.measured_on.as_ref().is_some_and(|r| Arc::ptr_eq(r, &request.state.rest)) {
            self.seconds_per_iteration = None;
            self.measured_on = Some(Arc::clone(&request.state.rest));
        }
        if request.state.has_handles() { Ok(()) } else { Err(EditorError::NoHandles) }
    }

    /// The finished result of `job`, stopped by the user where its last chunk left it.
    fn stopped(&self, job: &Job) -> SolveResult {
        SolveResult {
            positions: self.solver.positions(),
            finished: true,
            energy: job.last_energy.into_iter().collect(),
            touching: self.solver.touching().map(<[bool]>::to_vec).unwrap_or_default(),
            residual: job.residual,
            stopped: true,
            ..SolveResult::nothing_yet(job)
        }
    }

    /// Runs one chunk of `job` and says how far it got.
    fn step(&mut self, job: &mut Job, interrupted: &dyn Fn() -> bool) -> SolveResult {
        let started = Instant::now();
        let mut result = SolveResult::nothing_yet(job);
        let outcome = self.chunk(job, interrupted);
        match outcome {
            Ok((report, positions)) => {
                let k = report.energies.len();
                if k > 0 {
                    self.seconds_per_iteration = Some((report.local_seconds + report.global_seconds) / k as f64);
                }
                job.done += k;
                job.last_chunk = k;
                let tolerance = job.request.tolerance;
                let mut previous = None;
                for &e in &report.energies {
                    result.relative_change = job.last_energy.map(|p| relative_change(p, e));
                    previous = job.last_energy;
                    job.last_energy = Some(e);
                }
                // The solver's own stopping test (it stopped this chunk on it), or a round-off E
                // when there is no previous energy to compare with.
                result.converged = match (previous, job.last_energy) {
                    (Some(p), Some(e)) if tolerance > 0.0 => is_converged(p, e, tolerance, report.energy_floor),
                    (_, Some(e)) => e <= report.energy_floor.max(ENERGY_FLOOR),
                    _ => false,
                };
                result.finished = result.converged || job.done >= job.request.iterations;
                job.residual = job.residual.zip(report.residual).map(|(so_far, chunk)| so_far * chunk);
                result.residual = job.residual;
                result.lost_groups = report.lost_groups.first().map(|g| (report.lost_groups.len(), g.describe()));
                result.iterations = job.done;
                result.seconds_left = job.seconds_left(result.relative_change, self.seconds_per_iteration);
                result.local_ms = 1e3 * report.local_seconds;
                result.global_ms = 1e3 * report.global_seconds;
                result.setup_ms = 1e3 * report.setup_seconds;
                result.energy = report.energies;
                self.last_good.clone_from(&positions);
                result.positions = positions;
                result.touching = self.solver.touching().map(<[bool]>::to_vec).unwrap_or_default();
            }
            Err(e) => {
                result.setup_ms = 1e3 * started.elapsed().as_secs_f64();
                result.error = Some(e);
                result.finished = true;
                result.positions = if self.epoch == Some(job.request.epoch) {
                    // A failed solve may have moved them: back to the last good shape.
                    self.solver.set_positions(&self.last_good);
                    self.last_good.clone()
                } else {
                    job.request.start.to_vec()
                };
            }
        }
        result
    }

    /// Syncs on the first chunk, then iterates; the report and the new positions.
    fn chunk(
        &mut self,
        job: &mut Job,
        interrupted: &dyn Fn() -> bool,
    ) -> Result<(SolveReport, Vec<DVec3>), EditorError> {
        if !job.started {
            self.start(&job.request)?;
            job.started = true;
        }
        let k = self.chunk_size(job);
        // Stops at the first iteration that meets the tolerance, as `shapeup deform` does, so the
        // converged shape is the one a saved scene replays.
        let report = if k > 0 {
            self.solver.solve_until(k, job.request.tolerance, interrupted)?
        } else {
            SolveReport::default()
        };
        if report.energies.iter().any(|e| !e.is_finite()) {
            return Err(SolveError::NonFiniteEnergy.into());
        }
        let positions = self.solver.positions();
        if !positions.iter().all(|p| p.is_finite()) {
            return Err(SolveError::NonFinite.into());
        }
        Ok((report, positions))
    }
}

/// |E_k − E_{k−1}| / E_{k−1}; 0 when both are 0.
fn relative_change(previous: f64, energy: f64) -> f64 {
    let change = (previous - energy).abs();
    if change == 0.0 { 0.0 } else { change / previous.abs() }
}
