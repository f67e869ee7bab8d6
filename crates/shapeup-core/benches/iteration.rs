//! One local-global iteration (local and global step measured separately) and the setup
//! (load, constraints, factorization) of the standard scenarios on the bundled bunny:
//! the 2 % lowest vertices fixed, the 2 % highest moved by (0.25 D, 0.1 D, 0).
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use shapeup_core::bench::{Scenario, load_scenario};
use shapeup_core::io::read_mesh;
use std::path::PathBuf;
use std::time::Duration;

fn bunny() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/stanford-bunny.obj"))
}

fn iteration(c: &mut Criterion) {
    let path = bunny();
    let mesh = read_mesh(&path).expect("bundled bunny").mesh;
    for scenario in Scenario::ALL {
        let mut loaded = load_scenario(scenario, &mesh, path.clone()).expect("scenario builds");
        loaded.system.prepare().expect("scenario is solvable");
        // Start from a deformed state, as in an interactive drag.
        let (mut q, _) = loaded.solve_static(Some(5)).expect("solve");
        let mut group = c.benchmark_group(scenario.name());
        group.sample_size(30).measurement_time(Duration::from_secs(4));
        group.bench_function("local", |b| b.iter(|| loaded.system.local_step(&q).expect("local")));
        group.bench_function("global", |b| b.iter(|| loaded.system.global_step(&mut q).expect("global")));
        group.bench_function("iteration", |b| b.iter(|| loaded.system.step(&mut q).expect("step")));
        group.sample_size(10).measurement_time(Duration::from_secs(6));
        group.bench_function("setup", |b| {
            b.iter(|| {
                let mesh = read_mesh(&path).expect("bunny").mesh;
                let mut loaded = load_scenario(scenario, &mesh, path.clone()).expect("scenario");
                loaded.system.prepare().expect("factor");
                loaded
            })
        });
        group.finish();
    }
}

criterion_group!(benches, iteration);
criterion_main!(benches);
