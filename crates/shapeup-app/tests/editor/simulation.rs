//! Dynamic mode of the editor: the document falls, lands on a floor, stands as a tet-strain
//! solid, follows a grab, pauses and resets, all on the simulation thread.

use crate::max_distance;
use glam::DVec3;
use shapeup_app::simulation::{
    DynamicsModel, SimulationRunner, SimulationSettings, SimulationStats, Speed, StartShape, tetrahedralize_available,
};
use shapeup_app::{Command, Document, SelectMode, ShapeModel};
use shapeup_core::scene::{Mode, SolverSettings};
use std::path::Path;
use std::time::{Duration, Instant};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Polls until `steps` steps were taken, then pauses; returns the newest positions.
fn run_steps(runner: &SimulationRunner, steps: u64) -> Vec<DVec3> {
    let deadline = Instant::now() + Duration::from_secs(300);
    let mut latest = None;
    loop {
        if let Some(p) = runner.poll() {
            latest = Some(p);
        }
        let SimulationStats { steps: done, error, .. } = runner.stats();
        assert!(error.is_none(), "{error:?}");
        if done >= steps
            && let Some(p) = latest.take()
        {
            runner.set_running(false);
            return p;
        }
        assert!(Instant::now() < deadline, "only {done} steps");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn lowest(p: &[DVec3]) -> f64 {
    p.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)
}

fn height(p: &[DVec3]) -> f64 {
    p.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max) - lowest(p)
}

/// Vertex indices of `doc` sorted by height, lowest first.
fn by_height(doc: &Document) -> Vec<u32> {
    let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
    order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
    order
}

#[test]
fn the_defaults_are_the_scene_defaults() {
    let s = SimulationSettings::default();
    let scene = SolverSettings::default();
    assert_eq!((s.stiffness, s.time_step), (scene.stiffness, scene.time_step));
    assert_eq!(s.model, DynamicsModel::Document);
    assert!(s.gravity && s.floor && !s.tetrahedralize);
    assert!(s.grab_strength > 0.5 && s.grab_strength <= 1.0, "{}", s.grab_strength);
    assert!(s.validate().is_ok());
    assert!(SimulationSettings { grab_strength: 0.0, ..s }.validate().is_err());
    assert!(SimulationSettings { stiffness: -1.0, ..s }.validate().unwrap_err().to_string().contains("stiffness"));
    assert_eq!(DynamicsModel::TetStrain.label(), "Tet strain");
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
    assert!(lowest(&fallen) > floor - 1e-9, "{} below the floor {floor}", lowest(&fallen));
    assert!(!runner.is_running());
}

#[test]
fn run_from_rest_starts_at_the_rest_shape_continue_at_the_shape_on_screen() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let rest = doc.rest_positions().to_vec();
    let (lo, hi) = doc.rest_mesh().bounding_box();
    let diagonal = (hi - lo).length();
    // What a stopped simulation leaves on screen: the body squashed to half its height.
    let squashed: Vec<DVec3> = rest.iter().map(|p| DVec3::new(p.x, lo.y + 0.5 * (p.y - lo.y), p.z)).collect();
    assert!(doc.accept_positions(doc.epoch(), &squashed));
    let settings = SimulationSettings { gravity: false, ..SimulationSettings::default() };

    // From rest: nothing pulls at the rest shape, so a step stays there; the floor lies
    // 1 % of the diagonal below it.
    let from_rest = SimulationRunner::start_from(&doc, settings, StartShape::Rest, || {}).unwrap();
    from_rest.run_for(1);
    let p = run_steps(&from_rest, 1);
    assert!(max_distance(&p, &rest) < 1e-6 * diagonal, "{} from rest", max_distance(&p, &rest));
    let floor = from_rest.floor_height.unwrap();
    assert!((floor - (lowest(&rest) - 0.01 * diagonal)).abs() < 1e-12 * diagonal, "floor at {floor}");

    // From the shape on screen: the squashed body springs back from there.
    let on_screen = SimulationRunner::start(&doc, settings, || {}).unwrap();
    on_screen.run_for(1);
    let p = run_steps(&on_screen, 1);
    assert!(max_distance(&p, &squashed) < 0.5 * max_distance(&p, &rest), "it started from the squashed shape");
    assert!(max_distance(&p, &squashed) > 1e-6 * diagonal, "and springs back");

    // No floor, none drawn.
    let bare = SimulationRunner::start(&doc, SimulationSettings { floor: false, ..settings }, || {}).unwrap();
    assert_eq!(bare.floor_height, None);

    // TetGen fills the rest shape: a solid from a deformed shape on screen is refused in one
    // line that says what to do; from rest it starts.
    let solid = SimulationSettings { tetrahedralize: true, ..settings };
    let e = SimulationRunner::start(&doc, solid, || {}).unwrap_err().to_string();
    assert_eq!(e, "simulation: Tetrahedralize fills the rest shape: start the solid with Run from rest");
    if cfg!(feature = "tetgen") {
        let runner = SimulationRunner::start_from(&doc, solid, StartShape::Rest, || {}).unwrap();
        assert!(runner.num_tetrahedra > 0);
    }
}

#[test]
fn a_grab_pulls_a_vertex_and_reset_brings_the_shape_back() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    // Pin the lowest vertices; grab the 30 highest (the head) and pull them up.
    let order = by_height(&doc);
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
    assert!(pulled[top as usize].y > start.y + 0.25, "pulled from {} to {}", start.y, pulled[top as usize].y);
    assert!((pulled[order[0] as usize] - doc.positions()[order[0] as usize]).length() < 0.02, "the pins held");
    runner.release();
    runner.reset();
    // A step that was under way when it paused may still deliver its positions first.
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        if let Some(back) = runner.poll()
            && back.iter().zip(doc.positions()).all(|(a, b)| (*a - *b).length() < 1e-9)
        {
            break;
        }
        assert!(Instant::now() < deadline, "no reset");
        std::thread::sleep(Duration::from_millis(2));
    }
    assert_eq!(runner.stats(), SimulationStats::default(), "reset clears the stats");
}

/// Largest distance of `vertices` (in `p`) from their targets.
fn gap(p: &[DVec3], vertices: &[u32], targets: &[DVec3]) -> f64 {
    vertices.iter().zip(targets).map(|(&v, t)| (p[v as usize] - *t).length()).fold(0.0, f64::max)
}

#[test]
fn a_full_strength_grab_follows_the_cursor_where_the_old_force_grab_lagged() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::StrainBending).unwrap();
    let order = by_height(&doc);
    let head: Vec<u32> = order[order.len() - 30..].to_vec();
    let lift = DVec3::new(0.0, 0.3, 0.0);
    let targets: Vec<DVec3> = head.iter().map(|&v| doc.positions()[v as usize] + lift).collect();
    let free = SimulationSettings { gravity: false, floor: false, ..SimulationSettings::default() };

    let runner = SimulationRunner::start(&doc, SimulationSettings { grab_strength: 1.0, ..free }, || {}).unwrap();
    runner.grab(head.clone(), targets.clone());
    runner.set_running(true);
    let held = run_steps(&runner, 5);
    assert!(gap(&held, &head, &targets) < 0.003, "within 1 % of the pull: {}", gap(&held, &head, &targets));

    // The default strength follows closely too, and a soft grab still pulls.
    for (strength, within) in [(SimulationSettings::default().grab_strength, 0.1), (0.3, 0.2)] {
        let runner =
            SimulationRunner::start(&doc, SimulationSettings { grab_strength: strength, ..free }, || {}).unwrap();
        runner.grab(head.clone(), targets.clone());
        runner.set_running(true);
        let p = run_steps(&runner, 30);
        assert!(gap(&p, &head, &targets) < within * 0.3, "strength {strength}: {}", gap(&p, &head, &targets));
    }

    // The old grab, an inertial-target force of strength 0.3, on the same system.
    let mut scene = doc.to_scene("");
    scene.solver =
        SolverSettings { mode: Mode::Dynamic, gravity: [0.0; 3], damping: free.damping, ..SolverSettings::default() };
    let mut loaded = scene.build(doc.rest_mesh().clone(), shapeup_core::warnings::Warnings::new(), 0.0).unwrap();
    let mut sim = loaded.start_simulation().unwrap();
    let frame = loaded.frame;
    sim.grab(head.clone(), targets.iter().map(|&t| frame.to_working(t)).collect(), 0.3).unwrap();
    for _ in 0..30 {
        sim.step().unwrap();
    }
    let old: Vec<DVec3> = sim.positions().iter().map(|&q| frame.to_input(q)).collect();
    assert!(gap(&old, &head, &targets) > 0.15, "the old grab lagged: {}", gap(&old, &head, &targets));
}

#[test]
fn stats_report_the_step_rate_and_timings() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let runner = SimulationRunner::start(&doc, SimulationSettings::default(), || {}).unwrap();
    assert_eq!(runner.stats(), SimulationStats::default());
    runner.set_running(true);
    let deadline = Instant::now() + Duration::from_secs(60);
    while runner.stats().steps < 20 {
        assert!(Instant::now() < deadline);
        std::thread::sleep(Duration::from_millis(5));
    }
    let stats = runner.stats();
    assert!(stats.steps_per_second > 0.0, "{stats:?}");
    assert!(stats.step_ms > 0.0 && stats.local_ms > 0.0 && stats.global_ms > 0.0, "{stats:?}");
    assert!(stats.local_ms + stats.global_ms <= stats.step_ms, "{stats:?}");
    assert!(stats.error.is_none());
    runner.set_running(false);
    std::thread::sleep(Duration::from_millis(1100));
    assert_eq!(runner.stats().steps_per_second, 0.0, "paused for a second");
}

#[test]
fn live_settings_apply_and_structural_ones_need_a_new_runner() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let settings = SimulationSettings { floor: false, ..SimulationSettings::default() };
    let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
    let weightless =
        SimulationSettings { gravity: false, stiffness: 1e3, damping: 0.1, grab_strength: 0.5, ..settings };
    assert!(runner.update_settings(&weightless));
    assert_eq!(runner.settings(), weightless);
    runner.set_running(true);
    let p = run_steps(&runner, 30);
    let drift = p.iter().zip(doc.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(drift < 1e-6, "no gravity, no motion: {drift}");
    assert!(!runner.update_settings(&SimulationSettings { floor: true, ..weightless }));
    assert!(!runner.update_settings(&SimulationSettings { model: DynamicsModel::TetStrain, ..weightless }));
    assert_eq!(runner.settings(), weightless, "unchanged");
    assert!(runner.update_settings(&SimulationSettings { time_step: 0.0, ..weightless }), "a live setting");
    runner.set_running(true);
    let deadline = Instant::now() + Duration::from_secs(30);
    while runner.stats().error.is_none() {
        assert!(Instant::now() < deadline, "a bad time step is reported");
        std::thread::sleep(Duration::from_millis(2));
    }
    assert!(runner.stats().error.unwrap().to_string().contains("time_step"));
}

#[test]
fn tet_strain_needs_tetrahedra_and_a_tetrahedral_mesh_stands_with_it() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let tet_strain = SimulationSettings { model: DynamicsModel::TetStrain, ..SimulationSettings::default() };
    let e = SimulationRunner::start(&doc, tet_strain, || {}).unwrap_err().to_string();
    assert!(e.contains("tet strain") && e.contains("Tetrahedralize"), "{e}");

    // A tall box of tetrahedra, as from a .msh file: tet strain needs no TetGen then.
    let solid = shapeup_core::generate::tet_box([2, 6, 2], DVec3::new(0.4, 1.2, 0.4));
    let doc = Document::new(solid, ShapeModel::EdgeSprings).unwrap();
    assert!(tetrahedralize_available(&doc).is_err(), "it has tetrahedra already");
    let runner = SimulationRunner::start(&doc, tet_strain, || {}).unwrap();
    assert!(runner.num_tetrahedra > 0);
    runner.set_running(true);
    let p = run_steps(&runner, 120);
    let rest = height(doc.positions());
    assert!(height(&p) > 0.95 * rest, "{} of {rest}", height(&p));
    assert!(lowest(&p) < lowest(doc.positions()), "it fell onto the floor");
}

#[test]
fn tetrahedralize_needs_a_closed_surface_and_says_why_in_one_line() {
    let grid = shapeup_core::generate::cloth_grid(5, 5, 1.0, 1.0);
    let open = Document::new(grid, ShapeModel::EdgeSprings).unwrap();
    let why = tetrahedralize_available(&open).unwrap_err().to_string();
    let spot = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    if cfg!(feature = "tetgen") {
        assert!(why.contains("open"), "{why}");
        assert!(tetrahedralize_available(&spot).is_ok());
    } else {
        assert!(why.contains("TetGen"), "{why}");
        assert!(tetrahedralize_available(&spot).unwrap_err().to_string().contains("TetGen"));
    }
    let settings = SimulationSettings { tetrahedralize: true, ..SimulationSettings::default() };
    let e = SimulationRunner::start(&open, settings, || {}).unwrap_err().to_string();
    assert!(e.starts_with("simulation: TetGen could not tetrahedralize "), "{e}");
    assert!(!e.contains(": :") && !e.contains('\n'), "{e}");
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

/// The reported bug: Spot with edge springs sags flat within two seconds; as a tet-strain
/// solid it stands on its hooves.
#[cfg(feature = "tetgen")]
#[test]
fn spot_stands_as_a_tet_strain_solid_where_edge_springs_sag() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let rest = height(doc.positions());
    let two_seconds = (2.0 / SimulationSettings::default().time_step).round() as u64;
    let springs = SimulationRunner::start(&doc, SimulationSettings::default(), || {}).unwrap();
    springs.set_running(true);
    let sagged = run_steps(&springs, two_seconds);
    assert!(height(&sagged) < 0.5 * rest, "edge springs: {} of {rest}", height(&sagged));

    let settings =
        SimulationSettings { tetrahedralize: true, model: DynamicsModel::TetStrain, ..SimulationSettings::default() };
    let solid = SimulationRunner::start(&doc, settings, || {}).unwrap();
    solid.set_running(true);
    let stood = run_steps(&solid, two_seconds);
    assert!(height(&stood) >= 0.9 * rest, "tet strain: {} of {rest}", height(&stood));
    assert!(lowest(&stood) < lowest(doc.positions()), "it stands on the floor");
}

/// Tetrahedralize fills the rest shape (issue 29: a collapsed shape on screen, filled, blew up):
/// a document moved away from its rest shape is refused from the screen (Continue) in one line,
/// and Run from rest starts the solid at rest, where TetGen's inner points belong.
#[cfg(feature = "tetgen")]
#[test]
fn a_moved_shape_with_tetrahedra_starts_from_rest() {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let moved: Vec<DVec3> = doc.rest_mesh().positions.iter().map(|&p| p + DVec3::new(2.0, 0.0, 0.0)).collect();
    assert!(doc.accept_positions(doc.epoch(), &moved));
    let settings = SimulationSettings {
        gravity: false,
        floor: false,
        tetrahedralize: true,
        model: DynamicsModel::TetStrain,
        ..SimulationSettings::default()
    };
    let e = SimulationRunner::start(&doc, settings, || {}).unwrap_err().to_string();
    assert!(e.contains("Run from rest"), "{e}");
    let runner = SimulationRunner::start_from(&doc, settings, StartShape::Rest, || {}).unwrap();
    runner.set_running(true);
    let p = run_steps(&runner, 10);
    let rest = &doc.rest_mesh().positions;
    let drift = p.iter().zip(rest).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(drift < 1e-6, "at rest where it rests: {drift}");
}

/// The Dynamics panel alone (feature `gui`): labels, what each control reports, and what it
/// offers when.
#[cfg(feature = "gui")]
mod panel {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::{NodeT, Queryable};
    use shapeup_app::error::TetrahedraError;
    use shapeup_app::gui::dynamics_panel::{DynamicsAction, dynamics_panel};

    struct Panel {
        settings: SimulationSettings,
        runner: Option<SimulationRunner>,
        tetrahedralize: Result<(), TetrahedraError>,
        actions: Vec<DynamicsAction>,
    }

    fn harness(
        runner: Option<SimulationRunner>,
        tetrahedralize: Result<(), TetrahedraError>,
    ) -> Harness<'static, Panel> {
        let state = Panel { settings: SimulationSettings::default(), runner, tetrahedralize, actions: Vec::new() };
        let mut harness = Harness::new_ui_state(
            |ui, p: &mut Panel| {
                if let Some(a) = dynamics_panel(ui, &mut p.settings, p.runner.as_ref(), p.tetrahedralize.clone()) {
                    p.actions.push(a);
                }
            },
            state,
        );
        harness.run();
        harness
    }

    #[test]
    fn without_a_runner_it_offers_run_from_rest_continue_and_the_settings() {
        let mut h = harness(None, Ok(()));
        assert!(h.get_by_label("Restart").accesskit_node().is_disabled());
        assert!(h.get_by_label("Stop").accesskit_node().is_disabled());
        assert!(h.get_by_label("Tet strain").accesskit_node().is_disabled(), "no tetrahedra yet");
        assert!(h.query_by_label("Pause").is_none());
        h.get_by_label("Run from rest").click();
        h.run();
        h.get_by_label("Continue").click();
        h.run();
        assert_eq!(h.state().actions, [DynamicsAction::RunFromRest, DynamicsAction::Continue]);
        h.get_by_label("Gravity").click();
        h.run();
        assert!(!h.state().settings.gravity);
        assert_eq!(h.state().actions.last(), Some(&DynamicsAction::SettingsChanged));
        // Ticking Tetrahedralize picks the solid's model; unticking goes back.
        h.get_by_label("Tetrahedralize").click();
        h.run();
        assert!(h.state().settings.tetrahedralize);
        assert_eq!(h.state().settings.model, DynamicsModel::TetStrain);
        // A solid is made on the rest shape: Continue (from the shape on screen) is disabled.
        assert!(h.get_by_label("Continue").accesskit_node().is_disabled());
        assert!(!h.get_by_label("Run from rest").accesskit_node().is_disabled());
        assert!(!h.get_by_label("Tet strain").accesskit_node().is_disabled());
        h.get_by_label(DynamicsModel::Document.label()).click();
        h.run();
        assert_eq!(h.state().settings.model, DynamicsModel::Document, "the document's model on tetrahedra");
        h.get_by_label("Tetrahedralize").click();
        h.run();
        assert!(!h.state().settings.tetrahedralize);
        assert_eq!(h.state().settings.model, DynamicsModel::Document);
        assert!(h.query_by_label("alt+left drag: grab and pull the mesh").is_none(), "no runner, no hint");
    }

    #[test]
    fn tetrahedralize_is_disabled_with_the_reason() {
        let mut h = harness(None, Err(TetrahedraError::Open { border: 4, a: 0, b: 1 }));
        let tick = h.get_by_label("Tetrahedralize");
        assert!(tick.accesskit_node().is_disabled());
        tick.click();
        h.run();
        assert!(!h.state().settings.tetrahedralize);
        assert!(h.state().actions.is_empty());
    }

    #[test]
    fn with_a_running_runner_it_offers_pause_and_shows_the_timings() {
        let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
        let runner = SimulationRunner::start(&doc, SimulationSettings::default(), || {}).unwrap();
        runner.set_running(true);
        let deadline = Instant::now() + Duration::from_secs(60);
        while runner.stats().steps < 3 {
            assert!(Instant::now() < deadline);
            std::thread::sleep(Duration::from_millis(5));
        }
        let mut h = harness(Some(runner), Ok(()));
        h.get_by_label("alt+left drag: grab and pull the mesh");
        let node = h.get_by_label_contains("steps/s");
        let timings = node.accesskit_node().label().or_else(|| node.accesskit_node().value()).unwrap_or_default();
        assert!(timings.contains("ms per step (local") && timings.contains("global"), "{timings}");
        for (label, action) in
            [("Pause", DynamicsAction::Pause), ("Restart", DynamicsAction::Restart), ("Stop", DynamicsAction::Stop)]
        {
            h.get_by_label(label).click();
            h.run();
            assert_eq!(h.state().actions.last(), Some(&action));
        }
    }
}

/// Steps 1, 2, 4, …, 64 are checked for stopping short, and the stats say how many did: none
/// for a cloth at the default stiffness, most at stiffness 1e8 (10 iterations a step barely
/// move it where converged steps swing it down on its two pins).
#[test]
fn the_stats_count_steps_that_stopped_short() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cloth.obj");
    let mut obj = String::new();
    for i in 0..9 {
        for j in 0..9 {
            obj += &format!("v {} 0 {}\n", i as f64 / 8.0 - 0.5, j as f64 / 8.0 - 0.5);
        }
    }
    for i in 0..8 {
        for j in 0..8 {
            let v = i * 9 + j + 1;
            obj += &format!("f {} {} {}\nf {} {} {}\n", v, v + 9, v + 1, v + 1, v + 9, v + 10);
        }
    }
    std::fs::write(&path, obj).unwrap();
    for (stiffness, short) in [(SimulationSettings::default().stiffness, false), (1e8, true)] {
        let mut doc = Document::open(&path, ShapeModel::StrainBending).unwrap();
        doc.apply(Command::Select { vertices: vec![0, 8], mode: SelectMode::Replace }).unwrap();
        doc.apply(Command::FixSelection).unwrap();
        let settings = SimulationSettings { floor: false, stiffness, ..SimulationSettings::default() };
        let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
        runner.set_running(true);
        run_steps(&runner, 70);
        let stats = runner.stats();
        // It may take a step or two more before it pauses, not up to 128.
        assert_eq!(stats.checked_steps, 7, "{stats:?}");
        if short {
            assert!(stats.unconverged_steps >= 5 && stats.worst_residual > 0.5, "{stats:?}");
        } else {
            assert!(stats.unconverged_steps == 0 && stats.worst_residual == 0.0, "{stats:?}");
        }
    }
}

/// Real time by default: a step of h every h seconds, so a fall is seen at its speed; slow
/// motion takes four times as long; pausing stops the wait at once. (A lower bound on wall time
/// is what pacing promises; how fast unpaced steps are is for the benchmarks.)
#[test]
fn steps_are_paced_to_real_time_or_slow_motion() {
    let doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    assert_eq!(SimulationSettings::default().speed, Speed::RealTime);
    for (speed, steps, h) in [(Speed::RealTime, 13, 1.0 / 60.0), (Speed::SlowMotion, 4, 1.0 / 60.0)] {
        let settings = SimulationSettings { speed, time_step: h, floor: false, ..SimulationSettings::default() };
        let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
        let started = Instant::now();
        runner.run_for(steps);
        let deadline = started + Duration::from_secs(60);
        while runner.is_running() {
            assert!(Instant::now() < deadline, "only {} steps", runner.stats().steps);
            std::thread::sleep(Duration::from_millis(1));
        }
        let elapsed = started.elapsed().as_secs_f64();
        // The first step is taken at once, each later one h / factor after the one before.
        let paced = (steps - 1) as f64 * h / speed.factor().unwrap();
        assert!(elapsed >= paced * 0.99, "{speed:?}: {steps} steps in {elapsed} s, paced at {paced} s");
        assert_eq!(runner.stats().steps, steps);
    }
    // Slow motion with a long step: a pause comes through without waiting out the interval.
    let settings =
        SimulationSettings { speed: Speed::SlowMotion, time_step: 0.5, floor: false, ..SimulationSettings::default() };
    let runner = SimulationRunner::start(&doc, settings, || {}).unwrap();
    runner.set_running(true);
    let deadline = Instant::now() + Duration::from_secs(60);
    while runner.stats().steps < 1 {
        assert!(Instant::now() < deadline);
        std::thread::sleep(Duration::from_millis(1));
    }
    let paused = Instant::now();
    runner.set_running(false);
    drop(runner);
    // Dropping joins the thread: it left its 2 s wait when paused.
    assert!(paused.elapsed() < Duration::from_secs(1), "{:?}", paused.elapsed());
}
