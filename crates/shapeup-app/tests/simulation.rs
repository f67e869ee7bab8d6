//! Dynamic mode of the editor: the document falls, lands on a floor, follows a grab, pauses and
//! resets, all on the simulation thread.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use glam::DVec3;
use shapeup_app::simulation::{SimulationRunner, SimulationSettings};
use shapeup_app::{Command, Document, SelectMode, ShapeModel};
use std::path::Path;
use std::time::{Duration, Instant};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Polls until `steps` steps were taken; returns the newest positions.
fn run_steps(runner: &SimulationRunner, steps: u64) -> Vec<DVec3> {
    let deadline = Instant::now() + Duration::from_secs(120);
    let mut latest = None;
    loop {
        if let Some(p) = runner.poll() {
            latest = Some(p);
        }
        let (done, _, error) = runner.stats();
        assert!(error.is_none(), "{error:?}");
        if done >= steps
            && let Some(p) = latest.take()
        {
            return p;
        }
        assert!(Instant::now() < deadline, "only {done} steps");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn lowest(p: &[DVec3]) -> f64 {
    p.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)
}

#[test]
fn the_shape_falls_onto_the_floor_and_stays_above_it() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::IsoOneRing).unwrap();
    let start_low = lowest(doc.positions());
    let runner = SimulationRunner::start(&doc, SimulationSettings::default(), || {}).unwrap();
    assert!(runner.poll().is_none(), "paused until run");
    runner.set_running(true);
    let fallen = run_steps(&runner, 90);
    let mean = |p: &[DVec3]| p.iter().map(|p| p.y).sum::<f64>() / p.len() as f64;
    assert!(mean(&fallen) < mean(doc.positions()) - 0.005, "it fell");
    // The floor lies 1 % of the diagonal below the lowest vertex; the shape lands on it.
    let (lo, hi) = doc.rest_mesh().bounding_box();
    let floor = start_low - 0.01 * (hi - lo).length();
    assert!(lowest(&fallen) > floor - 0.01 * (hi - lo).length(), "{} below the floor {floor}", lowest(&fallen));
    runner.set_running(false);
    assert!(!runner.is_running());
}

#[test]
fn a_grab_pulls_a_vertex_and_reset_brings_the_shape_back() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    // Pin the lowest vertices; grab the 30 highest (the head) and pull them up.
    let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
    order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
    doc.apply(Command::Select { vertices: order[..30].to_vec(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    let top = *order.last().unwrap();
    let start = doc.positions()[top as usize];
    let settings = SimulationSettings { gravity: false, floor: false, ..SimulationSettings::default() };
    let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
    let head: Vec<u32> = order[order.len() - 30..].to_vec();
    let lift = DVec3::new(0.0, 0.3, 0.0);
    runner.grab(head.clone(), head.iter().map(|&v| doc.positions()[v as usize] + lift).collect());
    runner.set_running(true);
    let pulled = run_steps(&runner, 120);
    assert!(pulled[top as usize].y > start.y + 0.1, "pulled from {} to {}", start.y, pulled[top as usize].y);
    assert!((pulled[order[0] as usize] - doc.positions()[order[0] as usize]).length() < 0.02, "the pins held");
    runner.release();
    runner.set_running(false);
    runner.reset();
    let deadline = Instant::now() + Duration::from_secs(30);
    let back = loop {
        if let Some(p) = runner.poll() {
            break p;
        }
        assert!(Instant::now() < deadline, "no reset");
        std::thread::sleep(Duration::from_millis(2));
    };
    for (a, b) in back.iter().zip(doc.positions()) {
        assert!((*a - *b).length() < 1e-9);
    }
    assert_eq!(runner.stats().0, 0);
}

#[cfg(feature = "tetgen")]
#[test]
fn a_closed_surface_is_simulated_as_a_volume() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let settings = SimulationSettings { tetrahedralize: true, ..SimulationSettings::default() };
    let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
    assert!(runner.num_tetrahedra > 10_000, "{}", runner.num_tetrahedra);
    runner.set_running(true);
    let p = run_steps(&runner, 5);
    assert_eq!(p.len(), doc.num_vertices(), "the editor gets its own vertices back");
}
