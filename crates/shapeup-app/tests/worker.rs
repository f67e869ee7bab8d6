//! The background solver: newest request wins, results never block, drop joins.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use glam::DVec3;
use shapeup_app::worker::SolveRequest;
use shapeup_app::{Command, Document, EditorError, SelectMode, ShapeModel, SolverWorker};
use std::path::Path;
use std::time::{Duration, Instant};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Waits (bounded) for the result of request `seq`.
fn wait_for(worker: &mut SolverWorker, seq: u64) -> shapeup_app::SolveResult {
    let deadline = Instant::now() + Duration::from_secs(60);
    loop {
        if let Some(r) = worker.poll()
            && r.seq == seq
        {
            return r;
        }
        assert!(Instant::now() < deadline, "no result for request {seq}");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn document_with_handles() -> (Document, shapeup_app::GroupKey) {
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
    // Converge on the last targets, then compare with a synchronous solve of the same state.
    let mut request = SolveRequest::from_document(&doc);
    request.iterations = 400;
    let seq = worker.request(request);
    let result = wait_for(&mut worker, seq);
    assert!(result.apply_to(&mut doc));
    let handle = doc.group(head).unwrap();
    for (&v, t) in handle.vertices.as_ref().unwrap().iter().zip(&handle.targets) {
        assert!((doc.positions()[v as usize] - *t).length() < 0.05, "handle vertex follows its last target");
    }
    assert!(worker.poll().is_none(), "nothing further arrives");
}

#[test]
fn each_burst_is_solved_at_least_once_and_errors_are_reported() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let mut worker = SolverWorker::spawn().unwrap();
    let seq = worker.request(SolveRequest::from_document(&doc));
    let result = wait_for(&mut worker, seq);
    assert_eq!(result.error, Some(EditorError::NoHandles));
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
    }
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
    request.iterations = 50;
    worker.request(request);
    let start = Instant::now();
    drop(worker);
    assert!(start.elapsed() < Duration::from_secs(30));
    let mut worker = SolverWorker::spawn().unwrap();
    worker.shutdown();
    worker.shutdown();
    assert!(!worker.is_pending());
}

#[test]
fn notify_is_called_once_a_result_can_be_polled() {
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
    worker.request(SolveRequest::from_document(&doc));
    let deadline = Instant::now() + Duration::from_secs(60);
    while calls.load(Ordering::SeqCst) == 0 {
        assert!(Instant::now() < deadline, "notify never called");
        std::thread::sleep(Duration::from_millis(2));
    }
    // The UI is woken after the send, so its poll finds the result without waiting.
    let result = worker.poll().expect("the result is there when notify runs");
    assert!(result.error.is_none(), "{:?}", result.error);
    assert_eq!(calls.load(Ordering::SeqCst), 1);
}
