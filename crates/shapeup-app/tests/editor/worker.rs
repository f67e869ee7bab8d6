//! The background solver: it converges each request in chunks and then stops, the newest
//! request wins, a failure keeps the last good shape, results never block, drop joins.

use crate::max_distance;
use glam::DVec3;
use shapeup_app::worker::{SolveRequest, WorkerParams};
use shapeup_app::{Command, Document, EditorError, GroupKey, SelectMode, ShapeModel, SolveResult, SolverWorker};
use shapeup_core::mesh::Mesh;
use std::path::Path;
use std::sync::mpsc::{Receiver, SyncSender, sync_channel};
use std::time::{Duration, Instant};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Waits (bounded) for the first result of request `seq`.
fn wait_for(worker: &mut SolverWorker, seq: u64) -> SolveResult {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(r) = worker.poll_all().into_iter().find(|r| r.seq == seq) {
            return r;
        }
        assert!(Instant::now() < deadline, "no result for request {seq}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// Every result of request `seq` until its finished one (bounded wait), each checked to
/// continue the previous one; results of older requests are checked to be older and dropped.
fn until_finished(worker: &mut SolverWorker, seq: u64) -> Vec<SolveResult> {
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut results: Vec<SolveResult> = Vec::new();
    loop {
        for r in worker.poll_all() {
            assert!(r.seq <= seq, "a result for a request not sent");
            assert!(results.last().is_none_or(|l| !l.finished), "a result after the finished one");
            if r.seq == seq {
                match results.last() {
                    Some(l) => assert_eq!(r.iterations, l.iterations + r.energy.len(), "iterations add up"),
                    None => assert!(r.iterations >= r.energy.len()),
                }
                results.push(r);
            }
        }
        if results.last().is_some_and(|r| r.finished) {
            return results;
        }
        assert!(Instant::now() < deadline, "request {seq} did not finish");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// A worker whose thread waits after each chunk until the test has polled, so that every chunk
/// is seen on its own.
struct Lockstep {
    // Dropped before the worker, which then is no longer held in its notify.
    ready: Receiver<()>,
    go: SyncSender<()>,
    worker: SolverWorker,
}

impl Lockstep {
    fn new(params: WorkerParams) -> Lockstep {
        let (ready_tx, ready) = sync_channel(0);
        let (go, go_rx) = sync_channel(0);
        let worker = SolverWorker::spawn_with(params, move || {
            if ready_tx.send(()).is_ok() {
                let _ = go_rx.recv();
            }
        })
        .unwrap();
        Lockstep { ready, go, worker }
    }

    /// The next chunk's result, alone.
    fn next(&mut self) -> SolveResult {
        self.ready.recv_timeout(Duration::from_secs(60)).expect("a chunk within a minute");
        let mut results = self.worker.poll_all();
        self.go.send(()).unwrap();
        assert_eq!(results.len(), 1, "one result per chunk in lockstep");
        results.pop().unwrap()
    }

    /// The chunks of the request just sent, up to its finished one.
    fn chunks(&mut self) -> Vec<SolveResult> {
        let mut chunks = vec![self.next()];
        while !chunks.last().unwrap().finished {
            chunks.push(self.next());
        }
        chunks
    }
}

fn document_with_handles() -> (Document, GroupKey) {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
    order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
    doc.apply(Command::Select { vertices: order[..5].to_vec(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    doc.apply(Command::Select { vertices: order[order.len() - 5..].to_vec(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    let head = doc.handles().last().unwrap().key;
    (doc, head)
}

/// `pieces` flat n×n-cell grids in the XY plane, side by side (x offset 2 each), not joined.
fn grids(n: u32, pieces: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for p in 0..pieces {
        let base = p * (n + 1) * (n + 1);
        for y in 0..=n {
            for x in 0..=n {
                positions.push(DVec3::new(2.0 * p as f64 + x as f64 / n as f64, y as f64 / n as f64, 0.0));
            }
        }
        for y in 0..n {
            for x in 0..n {
                let v = base + y * (n + 1) + x;
                triangles.push([v, v + 1, v + n + 2]);
                triangles.push([v, v + n + 2, v + n + 1]);
            }
        }
    }
    Mesh::new(positions, triangles).unwrap()
}

/// The vertices of column `x` of grid `piece` (see [`grids`]).
fn column(n: u32, piece: u32, x: u32) -> Vec<u32> {
    (0..=n).map(|y| piece * (n + 1) * (n + 1) + y * (n + 1) + x).collect()
}

/// Fixes `vertices` as a new handle and returns its key.
fn fix(doc: &mut Document, vertices: Vec<u32>) -> GroupKey {
    doc.apply(Command::Select { vertices, mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    doc.handles().last().unwrap().key
}

/// One n×n grid, strain + bending, its left column held and its right column moved and turned.
fn bent_grid(n: u32) -> (Document, GroupKey) {
    let mut doc = Document::new(grids(n, 1), ShapeModel::StrainBending).unwrap();
    fix(&mut doc, column(n, 0, 0));
    let right = fix(&mut doc, column(n, 0, n));
    doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(-0.3, 0.1, 0.4) }).unwrap();
    doc.apply(Command::RotateHandle { handle: right, axis: DVec3::Y, angle: -0.6 }).unwrap();
    (doc, right)
}

fn diagonal(positions: &[DVec3]) -> f64 {
    let lo = positions.iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = positions.iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    (hi - lo).length()
}

fn relative_change(previous: f64, energy: f64) -> f64 {
    (previous - energy).abs() / previous.abs()
}

#[test]
fn converges_to_the_tolerance_and_matches_a_synchronous_solve() {
    const TOL: f64 = 1e-6;
    let (mut doc, _) = bent_grid(8);
    let mut worker = SolverWorker::spawn().unwrap();
    let mut request = SolveRequest::from_document(&doc);
    assert_eq!((request.iterations, request.tolerance), (doc.iterations(), doc.tolerance()));
    request.iterations = 100_000;
    request.tolerance = TOL;
    let seq = worker.request(request);
    let results = until_finished(&mut worker, seq);

    // Chunks in order, each picking up where the previous one stopped.
    let last = results.last().unwrap();
    assert!(last.finished && last.converged && last.error.is_none(), "{last:?}");
    assert_eq!(results[0].iterations, results[0].energy.len(), "iterations count from the request");
    for r in &results {
        assert!(!r.energy.is_empty() && r.error.is_none());
        assert!(r.local_ms >= 0.0 && r.global_ms >= 0.0 && r.setup_ms >= 0.0);
    }
    for r in &results[..results.len() - 1] {
        assert!(!r.finished && !r.converged);
        assert!(r.relative_change.is_none_or(|c| c > TOL), "it went on although converged");
        let noun = if r.iterations == 1 { "iteration" } else { "iterations" };
        assert!(r.status().starts_with(&format!("solving… {} {noun}, E ", r.iterations)), "{}", r.status());
    }
    assert_eq!(
        last.status(),
        format!("converged: {} iterations, E {:.3e}", last.iterations, last.last_energy().unwrap())
    );
    let energies: Vec<f64> = results.iter().flat_map(|r| r.energy.iter().copied()).collect();
    let n = energies.len();
    assert!(n >= 2 && n == last.iterations);
    let change = relative_change(energies[n - 2], energies[n - 1]);
    assert!(change <= TOL, "last relative change {change}");
    assert_eq!(last.relative_change, Some(change));

    // The shape is converged: one more iteration changes E by less than the tolerance.
    let diag = diagonal(doc.rest_positions());
    assert!(last.apply_to(&mut doc));
    let e0: f64 = doc.group_energies().unwrap().iter().map(|(_, e)| e).sum();
    let e1 = doc.solve(1).unwrap().energies[0];
    assert!(relative_change(e0, e1) <= TOL, "next change {}", relative_change(e0, e1));

    // The same convergence synchronously gives the same shape; a long solve nearly the same.
    let (mut sync, _) = bent_grid(8);
    sync.apply(Command::SetTolerance(TOL)).unwrap();
    sync.apply(Command::SetIterations(100_000)).unwrap();
    assert_eq!(sync.converge().unwrap().energies.len(), last.iterations);
    let same = max_distance(sync.positions(), &last.positions);
    assert!(same < 1e-9 * diag, "chunked vs one solve: {same}");
    sync.solve(20_000).unwrap();
    let far = max_distance(sync.positions(), &last.positions);
    assert!(far < 1e-2 * diag, "converged to 1e-6 vs 20000 more iterations: {far} (diagonal {diag})");
}

#[test]
fn nothing_arrives_after_the_finished_result() {
    let (doc, _) = bent_grid(6);
    let mut worker = SolverWorker::spawn().unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.tolerance = 1e-8;
    let seq = worker.request(request);
    let results = until_finished(&mut worker, seq);
    assert!(results.last().unwrap().converged);
    assert!(!worker.is_busy() && !worker.is_pending(), "idle once finished");
    std::thread::sleep(Duration::from_millis(300));
    assert!(worker.poll_all().is_empty(), "the worker sleeps once converged");
    assert!(!worker.is_busy());

    // A new request wakes it again.
    // (It may already be done: from a converged shape the first iteration meets the tolerance.)
    let seq = worker.request(SolveRequest::from_document(&doc));
    let again = until_finished(&mut worker, seq);
    assert!(again.last().unwrap().converged);
}

#[test]
fn the_newest_target_wins() {
    const N: u32 = 6;
    let moves: Vec<DVec3> = (0..12).map(|i| DVec3::new(-0.02, 0.01 * (i % 3) as f64, 0.03)).collect();
    let (mut doc, right) = bent_grid(N);
    // Short chunks, so that requests also arrive between chunks of a convergence.
    let params = WorkerParams {
        chunk_budget: Duration::from_millis(1),
        first_chunk_budget: Duration::ZERO,
        ..WorkerParams::default()
    };
    let mut worker = SolverWorker::spawn_with(params, || {}).unwrap();
    let mut last = 0;
    doc.begin_drag();
    for (i, &delta) in moves.iter().enumerate() {
        doc.apply(Command::MoveHandle { handle: right, delta }).unwrap();
        let mut request = SolveRequest::from_document(&doc);
        // Position error goes as the square root of the energy change: 1e-14 for ~1e-7.
        request.tolerance = 1e-14;
        request.iterations = 200_000;
        last = worker.request(request);
        // Some requests find the worker mid-convergence, some replace a pending one.
        if i % 2 == 0 {
            std::thread::sleep(Duration::from_millis(2));
        }
    }
    doc.end_drag();
    let results = until_finished(&mut worker, last);
    let final_result = results.last().unwrap();
    assert!(final_result.converged && final_result.error.is_none(), "{final_result:?}");

    // The synchronous solve of the last targets, from the rest shape.
    let (mut sync, right) = bent_grid(N);
    for &delta in &moves {
        sync.apply(Command::MoveHandle { handle: right, delta }).unwrap();
    }
    let report = sync.solve(30_000).unwrap();
    let e = &report.energies;
    assert!(relative_change(e[e.len() - 2], e[e.len() - 1]) < 1e-14, "the reference is converged");
    let diag = diagonal(sync.positions());
    let error = max_distance(sync.positions(), &final_result.positions);
    assert!(error < 1e-6 * diag, "newest targets, converged: off by {error} (diagonal {diag})");
    let handle = sync.group(right).unwrap();
    for (&v, t) in handle.vertices().unwrap().iter().zip(&handle.targets()) {
        assert!((final_result.positions[v] - *t).length() < 0.05 * diag, "the handle follows its last target");
    }
}

#[test]
fn stops_at_the_iteration_cap() {
    let (doc, _) = bent_grid(6);
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 5;
    request.tolerance = 0.0;
    // Zero budgets: one iteration per chunk, each seen.
    let mut lockstep = Lockstep::new(WorkerParams {
        chunk_budget: Duration::ZERO,
        first_chunk_budget: Duration::ZERO,
        ..WorkerParams::default()
    });
    lockstep.worker.request(request.clone());
    let chunks = lockstep.chunks();
    assert_eq!(chunks.iter().map(|r| r.iterations).collect::<Vec<_>>(), [1, 2, 3, 4, 5]);
    assert!(chunks.iter().all(|r| r.energy.len() == 1));
    let last = chunks.last().unwrap();
    assert!(last.finished && !last.converged && last.error.is_none());
    // Five iterations leave the bent grid short of its minimum, and the status says so: the
    // request's residual is the product of its chunks' (each starts where the last ended).
    let residual = last.residual.unwrap();
    assert!(residual > shapeup_core::solver::STATIC_RESIDUAL_LIMIT, "{residual}");
    assert!(
        last.status().starts_with("stopped at the 5-iteration cap short of the minimum (the energy's gradient "),
        "{}",
        last.status()
    );
    assert_eq!(chunks[0].status(), format!("solving… 1 iteration, E {:.3e}", chunks[0].energy[0]));

    // With default chunks, still exactly 5 in all, and then nothing.
    let mut worker = SolverWorker::spawn().unwrap();
    let seq = worker.request(request);
    let results = until_finished(&mut worker, seq);
    assert_eq!(results.iter().map(|r| r.energy.len()).sum::<usize>(), 5);
    assert_eq!(results.last().unwrap().iterations, 5);
    let in_larger_chunks = results.last().unwrap().residual.unwrap();
    assert!((in_larger_chunks - residual).abs() <= 1e-9 * residual, "{in_larger_chunks} vs {residual}");
    std::thread::sleep(Duration::from_millis(100));
    assert!(worker.poll_all().is_empty());
}

/// A scene whose handles are 10¹⁶ times lighter than its springs (the editor's weights stay
/// within 10⁸ of each other, a scene's need not): the status line names the group the
/// factorization cannot resolve, as the command line's warning does.
#[test]
fn the_status_names_groups_left_to_round_off() {
    let text = "[mesh]\ngenerate = { kind = \"cloth\", vertices = [6, 6], size = [1.0, 1.0] }\n\
                [[constraints]]\ntype = \"edge_spring\"\nweight = 1e8\n\
                [[constraints]]\ntype = \"position\"\nname = \"anchor\"\nvertices = [0]\n\
                [[constraints]]\ntype = \"position\"\nname = \"pin\"\nvertices = [0, 5]\nweight = 1e-8\n";
    let scene = shapeup_core::scene::Scene::parse(
        text,
        shapeup_core::scene::SceneFormat::Toml,
        std::path::Path::new("l.toml"),
        std::path::PathBuf::new(),
    )
    .unwrap();
    let doc = Document::from_scene(&scene).unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 3;
    let mut worker = SolverWorker::spawn().unwrap();
    let seq = worker.request(request);
    let last = until_finished(&mut worker, seq).pop().unwrap();
    assert_eq!(last.lost_groups.as_ref().map(|g| g.0), Some(1), "{}", last.status());
    assert!(
        last.status()
            .contains("1 group(s) left to round-off, first \"pin\" (weight 1e-8) against \"edge_spring\" (weight 1e8)"),
        "{}",
        last.status()
    );
}

#[test]
fn the_first_chunk_after_a_request_is_small_then_chunks_grow() {
    let (mut doc, right) = bent_grid(8);
    let mut lockstep = Lockstep::new(WorkerParams { first_chunk_budget: Duration::ZERO, ..WorkerParams::default() });
    for _ in 0..3 {
        doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(0.0, 0.05, 0.0) }).unwrap();
        let mut request = SolveRequest::from_document(&doc);
        request.tolerance = 1e-13;
        request.iterations = 3000;
        lockstep.worker.request(request);
        let chunks = lockstep.chunks();
        let sizes: Vec<usize> = chunks.iter().map(|r| r.energy.len()).collect();
        assert_eq!(sizes[0], 1, "the first update after a request is one iteration");
        for pair in sizes.windows(2) {
            assert!(pair[1] <= 2 * pair[0], "a chunk at most doubles: {sizes:?}");
        }
        // A grid iteration takes microseconds: chunks grow to many iterations.
        assert!(sizes.iter().any(|&c| c > 8), "{sizes:?}");
        for r in &chunks {
            assert!(r.ms_per_iteration().unwrap() >= 0.0);
            assert!(r.local_ms + r.global_ms < 1000.0, "a chunk stays near its budget: {r:?}");
        }
    }
    // Default budgets: the first chunk fits 10 ms, more than one grid iteration.
    let mut lockstep = Lockstep::new(WorkerParams::default());
    for k in 0..2 {
        doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(0.0, -0.05, 0.0) }).unwrap();
        lockstep.worker.request(SolveRequest::from_document(&doc));
        let chunks = lockstep.chunks();
        // The very first has no time estimate yet: one iteration.
        assert!(k == 0 || chunks[0].energy.len() > 1, "{}", chunks[0].energy.len());
    }
}

#[test]
fn chunks_not_polled_yet_merge_into_one_result() {
    let (doc, _) = bent_grid(6);
    let params =
        WorkerParams { chunk_budget: Duration::ZERO, first_chunk_budget: Duration::ZERO, ..WorkerParams::default() };
    let mut worker = SolverWorker::spawn_with(params, || {}).unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 300;
    request.tolerance = 0.0;
    worker.request(request);
    let deadline = Instant::now() + Duration::from_secs(60);
    while worker.is_busy() {
        assert!(Instant::now() < deadline);
        std::thread::sleep(Duration::from_millis(5));
    }
    // 300 one-iteration chunks, never polled: one result with every energy.
    let results = worker.poll_all();
    assert_eq!(results.len(), 1);
    let r = &results[0];
    assert!(r.finished && r.iterations == 300 && r.energy.len() == 300);
    assert!(r.energy.windows(2).all(|e| e[1] <= e[0] * (1.0 + 1e-12)), "E decreases");
}

#[test]
fn a_failed_solve_keeps_the_last_good_shape() {
    const N: u32 = 5;
    let mut doc = Document::new(grids(N, 2), ShapeModel::StrainBending).unwrap();
    fix(&mut doc, column(N, 0, 0));
    let right = fix(&mut doc, column(N, 0, N));
    let other = fix(&mut doc, column(N, 1, 0));
    doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(-0.2, 0.0, 0.3) }).unwrap();
    doc.apply(Command::MoveHandle { handle: other, delta: DVec3::new(0.0, 0.1, 0.0) }).unwrap();
    let mut worker = SolverWorker::spawn().unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.tolerance = 1e-9;
    let seq = worker.request(request.clone());
    let good = until_finished(&mut worker, seq).pop().unwrap();
    assert!(good.converged && good.error.is_none());
    assert!(good.apply_to(&mut doc));

    // The second grid loses its only handle: singular.
    doc.apply(Command::DeleteHandle(other)).unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.tolerance = 1e-9;
    let seq = worker.request(request);
    let failed = until_finished(&mut worker, seq);
    assert_eq!(failed.len(), 1, "a failure finishes the request");
    let failed = &failed[0];
    assert!(matches!(failed.error, Some(EditorError::Solve(_))), "{:?}", failed.error);
    assert!(failed.finished && !failed.converged);
    assert_eq!(failed.positions, good.positions, "the last good shape, not the rest shape");
    assert!(failed.status().starts_with("solve failed: "), "{}", failed.status());
    assert!(!failed.apply_to(&mut doc));
    assert_eq!(doc.positions(), good.positions.as_slice());
    std::thread::sleep(Duration::from_millis(100));
    assert!(worker.poll_all().is_empty(), "no retry after a failure");

    // The handle comes back: the worker recovers, from the last good shape.
    doc.apply(Command::Undo).unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.tolerance = 1e-9;
    let seq = worker.request(request);
    let recovered = until_finished(&mut worker, seq);
    let diag = diagonal(&good.positions);
    assert!(max_distance(&recovered[0].positions, &good.positions) < 1e-3 * diag, "resumes where it was");
    let last = recovered.last().unwrap();
    assert!(last.converged && last.error.is_none(), "{:?}", last.error);
    assert!(max_distance(&last.positions, &good.positions) < 1e-3 * diag);
    assert!(last.apply_to(&mut doc));
}

#[test]
fn the_last_of_many_rapid_requests_is_solved() {
    let (mut doc, head) = document_with_handles();
    let mut worker = SolverWorker::spawn().unwrap();
    let mut last = 0;
    doc.begin_drag();
    for _ in 0..50 {
        doc.apply(Command::MoveHandle { handle: head, delta: DVec3::new(0.002, 0.004, 0.0) }).unwrap();
        last = worker.request(SolveRequest::from_document(&doc));
    }
    doc.end_drag();
    let result = wait_for(&mut worker, last);
    assert!(result.error.is_none(), "{:?}", result.error);
    assert!(!result.energy.is_empty() && result.local_ms >= 0.0 && result.global_ms >= 0.0);
    // Converge on the last targets (at most 400 iterations), then check the handle follows.
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 400;
    let seq = worker.request(request);
    let result = until_finished(&mut worker, seq).pop().unwrap();
    assert!(result.iterations <= 400);
    assert!(result.apply_to(&mut doc));
    let handle = doc.group(head).unwrap();
    for (&v, t) in handle.vertices().unwrap().iter().zip(&handle.targets()) {
        assert!((doc.positions()[v] - *t).length() < 0.05, "handle vertex follows its last target");
    }
    std::thread::sleep(Duration::from_millis(50));
    assert!(worker.poll().is_none(), "nothing further arrives");
}

#[test]
fn each_burst_is_solved_at_least_once_and_errors_are_reported() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let mut worker = SolverWorker::spawn().unwrap();
    let seq = worker.request(SolveRequest::from_document(&doc));
    let result = wait_for(&mut worker, seq);
    assert_eq!(result.error, Some(EditorError::NoHandles));
    assert!(result.finished);
    assert_eq!(result.positions, doc.positions(), "an error leaves the shape as it was");
    assert!(!result.apply_to(&mut doc));

    let (doc, head) = document_with_handles();
    let mut doc = doc;
    for burst in 0..3 {
        let mut seqs = Vec::new();
        for _ in 0..5 {
            doc.apply(Command::MoveHandle { handle: head, delta: DVec3::X * 0.01 }).unwrap();
            seqs.push(worker.request(SolveRequest::from_document(&doc)));
        }
        let result = wait_for(&mut worker, *seqs.last().unwrap());
        assert!(result.error.is_none(), "burst {burst}: {:?}", result.error);
        assert!(result.apply_to(&mut doc));
    }
    assert_ne!(doc.positions(), doc.rest_positions());
    // A result from before a reset belongs to an old epoch and is not taken.
    let seq = worker.request(SolveRequest::from_document(&doc));
    let stale = wait_for(&mut worker, seq);
    doc.apply(Command::ResetShape).unwrap();
    assert!(!stale.apply_to(&mut doc));
    assert_eq!(doc.positions(), doc.rest_positions());
}

#[test]
fn dropping_the_worker_joins_its_thread() {
    let (doc, _) = document_with_handles();
    let mut worker = SolverWorker::spawn().unwrap();
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 100_000;
    request.tolerance = 0.0;
    worker.request(request);
    std::thread::sleep(Duration::from_millis(20));
    // Mid-convergence: it stops after its current chunk.
    let start = Instant::now();
    drop(worker);
    assert!(start.elapsed() < Duration::from_secs(30));
    let mut worker = SolverWorker::spawn().unwrap();
    worker.shutdown();
    worker.shutdown();
    assert!(!worker.is_pending() && !worker.is_busy());
}

#[test]
fn notify_is_called_after_each_chunk_until_finished() {
    use std::sync::Arc;
    use std::sync::atomic::{AtomicUsize, Ordering};
    let (doc, _) = document_with_handles();
    let calls = Arc::new(AtomicUsize::new(0));
    let counter = Arc::clone(&calls);
    let mut worker = SolverWorker::spawn_with_notify(move || {
        counter.fetch_add(1, Ordering::SeqCst);
    })
    .unwrap();
    assert_eq!(calls.load(Ordering::SeqCst), 0, "no result, no wake-up");
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 60;
    let seq = worker.request(request);
    let deadline = Instant::now() + Duration::from_secs(60);
    while calls.load(Ordering::SeqCst) == 0 {
        assert!(Instant::now() < deadline, "notify never called");
        std::thread::sleep(Duration::from_millis(1));
    }
    // The UI is woken after the post, so its poll finds the result without waiting.
    let mut results = worker.poll_all();
    assert!(!results.is_empty(), "the result is there when notify runs");
    assert!(results[0].error.is_none(), "{:?}", results[0].error);
    if !results.last().unwrap().finished {
        results.extend(until_finished(&mut worker, seq));
    }
    // At least one wake-up per result (more when chunks merged), none after the finished one.
    std::thread::sleep(Duration::from_millis(50));
    let after = calls.load(Ordering::SeqCst);
    assert!(after >= results.len());
    std::thread::sleep(Duration::from_millis(100));
    assert_eq!(calls.load(Ordering::SeqCst), after);
}

/// A newer request stops the chunk under way after its current iteration, however long that
/// chunk was meant to run; `wait_for` returns once the newer request's first result is there.
#[test]
fn a_newer_request_interrupts_a_long_chunk_and_wait_for_sees_its_first_result() {
    let (mut doc, right) = bent_grid(8);
    let minute = Duration::from_secs(60);
    let worker = &mut SolverWorker::spawn_with(
        WorkerParams { chunk_budget: minute, first_chunk_budget: minute, ..WorkerParams::default() },
        || {},
    )
    .unwrap();
    // A short request measures the time per iteration ...
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 3;
    let seq = worker.request(request);
    until_finished(worker, seq);
    // ... so this one's first chunk aims at a minute of iterations.
    doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(0.0, 0.05, 0.0) }).unwrap();
    let mut long = SolveRequest::from_document(&doc);
    long.iterations = usize::MAX;
    long.tolerance = 0.0;
    let long_seq = worker.request(long);
    std::thread::sleep(Duration::from_millis(100));
    assert!(worker.is_busy());
    doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(0.0, -0.05, 0.0) }).unwrap();
    let mut short = SolveRequest::from_document(&doc);
    short.iterations = 1;
    let started = Instant::now();
    let short_seq = worker.request(short);
    assert!(worker.wait_for(short_seq, Duration::from_secs(30)), "the newer request was not answered");
    assert!(started.elapsed() < Duration::from_secs(30));
    let results = worker.poll_all();
    let interrupted = results.iter().find(|r| r.seq == long_seq).expect("the interrupted chunk is posted");
    assert!(!interrupted.finished && interrupted.error.is_none(), "{interrupted:?}");
    assert!(interrupted.iterations > 0);
    let answer = results.iter().find(|r| r.seq == short_seq).unwrap();
    assert_eq!(answer.iterations, 1);
    // Nothing more to come: waiting for a request never sent returns at once, empty-handed.
    let idle = Instant::now();
    assert!(!worker.wait_for(short_seq + 1, minute));
    assert!(idle.elapsed() < Duration::from_secs(30));
}

/// During a drag (live requests) the worker answers each request with one chunk and then
/// leaves the CPU to the UI until the next request or the pause ends; then it converges on.
#[test]
fn live_requests_pause_after_their_first_chunk() {
    let (mut doc, right) = bent_grid(6);
    let pause = Duration::from_secs(2);
    let params = WorkerParams { chunk_budget: Duration::ZERO, first_chunk_budget: Duration::ZERO, live_pause: pause };
    let worker = &mut SolverWorker::spawn_with(params, || {}).unwrap();
    doc.begin_drag();
    doc.apply(Command::MoveHandle { handle: right, delta: DVec3::new(0.0, 0.05, 0.0) }).unwrap();
    let live = SolveRequest::from_document(&doc);
    assert!(live.live);
    let seq = worker.request(live);
    assert!(worker.wait_for(seq, Duration::from_secs(30)));
    let sent = Instant::now();
    std::thread::sleep(pause / 4);
    let during: usize = worker.poll_all().iter().map(|r| r.energy.len()).sum();
    assert!(sent.elapsed() < pause, "the check ran late");
    assert_eq!(during, 1, "one iteration, then the pause");
    assert!(worker.is_busy(), "paused, not finished");
    // A newer request ends the pause at once; after the drag the worker converges.
    doc.end_drag();
    let mut last = SolveRequest::from_document(&doc);
    assert!(!last.live);
    last.tolerance = 1e-10;
    let seq = worker.request(last);
    let results = until_finished(worker, seq);
    assert!(results.last().unwrap().converged);
    assert!(results.iter().map(|r| r.energy.len()).sum::<usize>() > 1);
}

#[test]
fn a_long_convergence_says_the_time_left_and_stops_when_asked() {
    let (doc, _) = bent_grid(30);
    let mut request = SolveRequest::from_document(&doc);
    // Far past what a test waits for: only the stop ends it.
    request.iterations = 1_000_000;
    request.tolerance = 1e-300;
    let mut worker = SolverWorker::spawn().unwrap();
    let seq = worker.request(request.clone());
    let deadline = Instant::now() + Duration::from_secs(60);
    let estimate = loop {
        let results = worker.poll_all();
        if let Some(r) = results.iter().rev().find(|r| r.seconds_left.is_some()) {
            break r.clone();
        }
        assert!(results.iter().all(|r| !r.finished), "finished before any estimate");
        assert!(Instant::now() < deadline, "no estimate of the time left");
        std::thread::sleep(Duration::from_millis(2));
    };
    let left = estimate.seconds_left.unwrap();
    assert!(left.is_finite() && left > 0.0, "{left}");
    assert!(estimate.status().contains(" left"), "{}", estimate.status());
    assert!(estimate.iterations >= 20, "measured over 20 iterations at least: {}", estimate.iterations);

    worker.stop();
    let results = until_finished(&mut worker, seq);
    let last = results.last().unwrap();
    assert!(last.stopped && last.finished && !last.converged && last.error.is_none(), "{last:?}");
    assert!(last.iterations < request.iterations);
    assert!(last.status().starts_with(&format!("stopped at {} iterations, not converged", last.iterations)));
    assert!(!last.status().contains(" left"), "{}", last.status());
    assert!(!worker.is_busy());
    // Nothing more comes; a stop while idle does nothing.
    worker.stop();
    std::thread::sleep(Duration::from_millis(50));
    assert!(worker.poll_all().is_empty());

    // The next request converges on from the shape reached.
    let mut next = request.clone();
    next.tolerance = 1e-6;
    let seq = worker.request(next);
    let results = until_finished(&mut worker, seq);
    assert!(results.last().unwrap().converged);
    assert!(!results.last().unwrap().stopped);
}
