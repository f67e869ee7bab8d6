//! One Projective Dynamics time step (10 local-global iterations) of the dynamic benchmark
//! scenarios: cloths of 10k and 40k vertices and a box of 20k tetrahedra. Frames per second
//! = 1 / (time per step).
#![allow(missing_docs, clippy::unwrap_used, clippy::expect_used)]

use criterion::{Criterion, criterion_group, criterion_main};
use shapeup_core::bench::DynamicScenario;
use std::time::Duration;

fn step(c: &mut Criterion) {
    for scenario in DynamicScenario::ALL {
        let (_, mut simulation) = scenario.load().expect("scenario builds");
        // Factor once and get moving before timing.
        for _ in 0..5 {
            simulation.step().expect("step");
        }
        let mut group = c.benchmark_group(scenario.name());
        group.sample_size(20).measurement_time(Duration::from_secs(6));
        group.bench_function("step (10 iterations)", |b| b.iter(|| simulation.step().expect("step")));
        group.finish();
    }
}

/// One time step of each contact scenario with and without its contact, after 60 untimed steps.
fn contact(c: &mut Criterion) {
    use shapeup_core::bench::ContactScenario;
    for scenario in ContactScenario::ALL {
        let mut group = c.benchmark_group(format!("contact/{}", scenario.name()));
        group.sample_size(10).measurement_time(Duration::from_secs(5));
        for with in [false, true] {
            let (_, mut simulation, _dir) = scenario.load(with).expect("scenario builds");
            for _ in 0..60 {
                simulation.step().expect("step");
            }
            let label = if with { "step with contact" } else { "step without contact" };
            group.bench_function(label, |b| b.iter(|| simulation.step().expect("step")));
        }
        group.finish();
    }
}

criterion_group!(benches, step, contact);
criterion_main!(benches);
