//! One editor update while dragging a handle: move the ears of the bunny (edge springs, base
//! and ears fixed, as `examples/bunny-springs.toml`) and run 10 local-global iterations — the
//! work the solver thread does per mouse move. Its inverse is the update rate the solver can
//! sustain when rendering does not compete for the cores.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use criterion::{Criterion, criterion_group, criterion_main};
use glam::DVec3;
use shapeup_app::{Command, Document};
use shapeup_core::scene::Scene;
use std::path::Path;

fn drag_update(c: &mut Criterion) {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/bunny-springs.toml"));
    let scene = Scene::from_file(path).unwrap();
    let mut document = Document::from_scene(&scene).unwrap();
    let ears = document.handles().find(|h| h.name == "ears").unwrap().key;
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

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(30);
    targets = drag_update
}
criterion_main!(benches);
