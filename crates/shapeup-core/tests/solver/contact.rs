//! Contact: colliders of every kind, friction against tan θ = μ, self-collision checked by an
//! independent triangle–triangle test, tunnelling, moving colliders, one factorization per run.

use glam::DVec3;
use shapeup_core::scene::{Scene, SceneFormat, SceneSimulation};
use std::path::PathBuf;

/// A scene from TOML text (paths relative to the crate's test data).
fn scene(text: &str) -> Scene {
    Scene::parse(text, SceneFormat::Toml, &PathBuf::from("contact.toml"), PathBuf::from("tests/data")).unwrap()
}

fn start(text: &str) -> (shapeup_core::scene::LoadedScene, SceneSimulation) {
    let mut loaded = scene(text).load().unwrap();
    let sim = loaded.start_scene_simulation().unwrap();
    (loaded, sim)
}

const CLOTH: &str = r#"
[mesh]
generate = { kind = "cloth", vertices = [31, 31], size = [1.0, 1.0] }
normalize = false

[solver]
mode = "dynamic"
iterations = 10

[[constraints]]
type = "triangle_strain"
weight = 1.0

[[constraints]]
type = "bending"
weight = 0.001
"#;

#[test]
fn cloth_drapes_over_a_sphere_without_entering_it() {
    let text =
        format!("{CLOTH}\n[[colliders]]\ntype = \"sphere\"\ncenter = [0.0, -0.4, 0.0]\nradius = 0.3\nfriction = 0.3\n");
    let (_, mut sim) = start(&text);
    let center = DVec3::new(0.0, -0.4, 0.0);
    let thickness = sim.simulation.contact().unwrap().params().thickness;
    for k in 0..120 {
        let report = sim.step().unwrap();
        let inside =
            sim.simulation.positions().iter().map(|p| (*p - center).length() - 0.3).fold(f64::INFINITY, f64::min);
        if k % 10 == 0 {
            let y: Vec<f64> = sim.simulation.positions().iter().map(|p| p.y).collect();
            eprintln!(
                "step {k}: min dist {inside:.5} contacts {:?} min y {:.4} max y {:.4}",
                report.contact,
                y.iter().cloned().fold(f64::INFINITY, f64::min),
                y.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            );
        }
        assert!(inside >= thickness * (1.0 - 1e-6) - 1e-12, "step {k}: a vertex {inside} from the sphere");
    }
    assert_eq!(sim.simulation.system().factorizations(), 1);
}
