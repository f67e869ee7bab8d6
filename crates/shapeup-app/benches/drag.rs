//! Dragging a handle, two ways.
//!
//! - One synchronous editor update: move the ears of the bunny (edge springs, base and ears
//!   fixed, as `examples/bunny-springs.toml`) and run 10 local-global iterations. Its inverse is
//!   the update rate the solver can sustain when rendering does not compete for the cores.
//! - The first result after a drag request: the 35k-vertex bunny (strain + bending, the lowest
//!   and the highest 5% of the vertices by y fixed, the top handle moved), timed from
//!   `SolverWorker::request` to the result `poll` returns, with the worker converging the
//!   previous request in between (mouse events every 16 ms). This is the latency the user sees.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stderr, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use shapeup_app::worker::SolveRequest;
use shapeup_app::{Command, Document, SelectMode, ShapeModel, SolveResult, SolverWorker};
use shapeup_core::scene::Scene;
use std::path::Path;
use std::sync::mpsc::channel;
use std::time::{Duration, Instant};

fn drag_update(c: &mut Criterion) {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/bunny-springs.toml"));
    let scene = Scene::from_file(path).unwrap();
    let mut document = Document::from_scene(&scene).unwrap();
    let ears = document.handles().find(|h| h.spec.name == "ears").unwrap().key;
    document.solve(50).unwrap();
    document.begin_drag();
    let mut step = 0usize;
    c.bench_function("drag update, bunny, edge springs, 10 iterations", |b| {
        b.iter(|| {
            // Sweep back and forth so the solve always has work to do.
            step += 1;
            let sign = if (step / 20).is_multiple_of(2) { 1.0 } else { -1.0 };
            document.apply(Command::MoveHandle { handle: ears, delta: DVec3::new(sign * 0.002, 0.0, 0.0) }).unwrap();
            document.solve(10).unwrap()
        });
    });
    document.end_drag();
}

/// Waits for the first result of request `seq`, woken by the worker's notify.
fn first_result(worker: &mut SolverWorker, woken: &std::sync::mpsc::Receiver<()>, seq: u64) -> SolveResult {
    loop {
        if let Some(r) = worker.poll_all().into_iter().find(|r| r.seq == seq) {
            return r;
        }
        woken.recv_timeout(Duration::from_secs(10)).expect("the worker answers");
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

fn first_update_after_drag(c: &mut Criterion) {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/stanford-bunny.obj"));
    let mut document = Document::open(path, ShapeModel::StrainBending).unwrap();
    let n = document.num_vertices();
    let mut order: Vec<u32> = (0..n as u32).collect();
    let y = |v: u32| document.positions()[v as usize].y;
    order.sort_by(|&a, &b| y(a).total_cmp(&y(b)));
    let count = n / 20;
    for vertices in [order[..count].to_vec(), order[n - count..].to_vec()] {
        document.apply(Command::Select { vertices, mode: SelectMode::Replace }).unwrap();
        document.apply(Command::FixSelection).unwrap();
    }
    let top = document.handles().last().unwrap().key;
    let lo = document.positions().iter().fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = document.positions().iter().fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    let step_length = 0.002 * (hi - lo).length();

    let (wake, woken) = channel();
    let mut worker = SolverWorker::spawn_with_notify(move || {
        let _ = wake.send(());
    })
    .unwrap();
    // Build and factor once, outside the measurement (a drag only moves targets).
    let seq = worker.request(SolveRequest::from_document(&document));
    first_result(&mut worker, &woken, seq);

    let mut firsts = Vec::new();
    let mut step = 0usize;
    document.begin_drag();
    c.bench_function("first result after a drag request, bunny 35k, strain + bending", |b| {
        b.iter_custom(|iterations| {
            let mut total = Duration::ZERO;
            for _ in 0..iterations {
                // A mouse event every 16 ms; the worker converges meanwhile.
                std::thread::sleep(Duration::from_millis(16));
                step += 1;
                let sign = if (step / 20).is_multiple_of(2) { 1.0 } else { -1.0 };
                let delta = DVec3::new(sign * step_length, step_length, 0.0);
                document.apply(Command::MoveHandle { handle: top, delta }).unwrap();
                let request = SolveRequest::from_document(&document);
                let started = Instant::now();
                let seq = worker.request(request);
                let first = first_result(&mut worker, &woken, seq);
                let elapsed = started.elapsed();
                total += elapsed;
                assert!(first.error.is_none(), "{:?}", first.error);
                firsts.push((1e3 * elapsed.as_secs_f64(), first));
            }
            total
        });
    });
    document.end_drag();

    // Later chunks: let the last request converge a while.
    let started = Instant::now();
    let (mut ms, mut iterations, mut results) = (0.0, 0, 0);
    while started.elapsed() < Duration::from_secs(3) {
        let _ = woken.recv_timeout(Duration::from_millis(100));
        for r in worker.poll_all() {
            ms += r.local_ms + r.global_ms;
            iterations += r.energy.len();
            results += 1;
        }
    }
    drop(worker);
    // The same iterations synchronously, in one call, for comparison.
    let report = document.solve(10).unwrap();
    let per = |seconds: f64| 1e3 * seconds / report.energies.len() as f64;

    let mut latency: Vec<f64> = firsts.iter().map(|f| f.0).collect();
    let mut local: Vec<f64> = firsts.iter().map(|f| f.1.local_ms / f.1.energy.len() as f64).collect();
    let mut global: Vec<f64> = firsts.iter().map(|f| f.1.global_ms / f.1.energy.len() as f64).collect();
    let sizes: Vec<usize> = firsts.iter().map(|f| f.1.energy.len()).collect();
    eprintln!(
        "first result after a drag request, {} samples: median {:.1} ms, min {:.1}, max {:.1}; \
         first chunk {}..{} iteration(s), per iteration median local {:.1} ms + global {:.1} ms",
        firsts.len(),
        median(&mut latency),
        latency.first().copied().unwrap_or(f64::NAN),
        latency.last().copied().unwrap_or(f64::NAN),
        sizes.iter().min().unwrap_or(&0),
        sizes.iter().max().unwrap_or(&0),
        median(&mut local),
        median(&mut global),
    );
    eprintln!(
        "converging on: {:.1} ms per iteration over {iterations} iterations in {results} results; \
         synchronous solve(10): local {:.1} ms + global {:.1} ms per iteration",
        ms / iterations.max(1) as f64,
        per(report.local_seconds),
        per(report.global_seconds),
    );
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = drag_update
}
criterion_group! {
    name = worker_benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    targets = first_update_after_drag
}
criterion_main!(benches, worker_benches);
