//! The editor's UI driven without a window (egui_kittest, rendering on any wgpu adapter,
//! lavapipe included): buttons, sliders, radio buttons and shortcuts reach the document.
#![cfg(feature = "gui")]
#![allow(clippy::unwrap_used, clippy::expect_used)]

use eframe::egui;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use shapeup_app::document::GroupRole;
use shapeup_app::gui::app::EditorApp;
use shapeup_app::{Command, Document, SelectMode, ShapeModel};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Spot with edge springs and its 20 lowest vertices selected.
fn spot_with_selection() -> Document {
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
    order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
    doc.apply(Command::Select { vertices: order[..20].to_vec(), mode: SelectMode::Replace }).unwrap();
    doc
}

fn editor(document: Document) -> Harness<'static, EditorApp> {
    let mut harness = Harness::builder()
        .with_size(egui::vec2(1100.0, 800.0))
        .wgpu()
        .build_eframe(|cc| EditorApp::new(cc, document, PathBuf::from(SPOT)));
    harness.run();
    harness
}

/// Steps the UI until `done` holds (the solver answers on its own thread), at most 60 s.
fn step_until(harness: &mut Harness<'_, EditorApp>, done: impl Fn(&EditorApp) -> bool) {
    let deadline = Instant::now() + Duration::from_secs(60);
    while !done(harness.state()) {
        assert!(Instant::now() < deadline, "the editor never reached the expected state");
        harness.step();
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn num_handles(app: &EditorApp) -> usize {
    app.document().handles().count()
}

#[test]
fn fix_selection_makes_a_handle_and_undo_redo_take_it_back() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("20 vertices selected");
    assert_eq!(num_handles(harness.state()), 0);

    harness.get_by_label("Fix selection").click();
    harness.run();
    let handle = harness.state().document().handles().next().expect("a handle").clone();
    assert_eq!(handle.vertices().map(<[u32]>::len), Some(20));
    assert_eq!(handle.role, GroupRole::Handle);
    // The handle is listed in the groups panel (name and type).
    harness.get_by_label(&format!("{} (position)", handle.name));

    // Ctrl+Z undoes the fix, the Redo button redoes it.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.run();
    assert_eq!(num_handles(harness.state()), 0, "ctrl+z undid the fix");
    harness.get_by_label("Redo").click();
    harness.run();
    assert_eq!(num_handles(harness.state()), 1, "redo restored the handle");
    // Ctrl+Shift+Z after an undo redoes as well.
    harness.get_by_label("Undo").click();
    harness.run();
    assert_eq!(num_handles(harness.state()), 0);
    harness.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    harness.run();
    assert_eq!(num_handles(harness.state()), 1);
}

#[test]
fn the_weight_slider_sets_the_group_weight_and_undo_restores_it() {
    let mut harness = editor(spot_with_selection());
    let before = harness.state().document().groups()[0].weight;
    assert_eq!(before, 10.0, "edge springs start at the reference multiplier");
    // The group's slider is labelled "weight" (the others: iterations, damping).
    let is_weight = |s: &egui_kittest::Node<'_>| s.accesskit_node().label().unwrap_or_default().contains("weight");
    let sliders: Vec<_> = harness.get_all_by_role(Role::Slider).collect();
    assert_eq!(sliders.iter().filter(|s| is_weight(s)).count(), 1, "one group, one weight slider");
    let group_slider = sliders.iter().find(|s| is_weight(s)).expect("the shape group's slider");
    // The slider runs over log10 of the weight.
    group_slider.set_value_accesskit(250f64.log10());
    harness.run();
    let after = harness.state().document().groups()[0].weight;
    assert!((after - 250.0).abs() < 1e-9 * 250.0, "weight {after}");
    // The slider clamps to the logarithmic range [1e-4, 1e4].
    let sliders: Vec<_> = harness.get_all_by_role(Role::Slider).collect();
    let group_slider = sliders.iter().find(|s| is_weight(s)).unwrap();
    group_slider.set_value_accesskit(9.0);
    harness.run();
    assert_eq!(harness.state().document().groups()[0].weight, 1e4);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    harness.run();
    assert!((harness.state().document().groups()[0].weight - 250.0).abs() < 1e-9 * 250.0, "undo restores 250");
}

#[test]
fn switching_the_shape_model_keeps_the_handles_and_a_solve_moves_nothing_at_rest() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("Fix selection").click();
    harness.run();
    harness.get_by_label(ShapeModel::StrainBending.label()).click();
    harness.run();
    let doc = harness.state().document();
    assert_eq!(doc.shape_model(), Some(ShapeModel::StrainBending));
    assert_eq!(num_handles(harness.state()), 1, "the handle survives the switch");
    let kinds: Vec<&str> = doc.groups().iter().map(|g| g.kind.as_str()).collect();
    assert!(kinds.contains(&"triangle_strain") && kinds.contains(&"bending"), "{kinds:?}");
    // With handles at their rest positions the solver's answer is the rest shape.
    let rest = doc.positions().to_vec();
    step_until(&mut harness, |app| app.solves_applied() > 0);
    let moved =
        harness.state().document().positions().iter().zip(&rest).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(moved < 1e-9, "rest shape moved by {moved}");
}

#[test]
fn the_viewport_shows_the_mesh() {
    let mut harness = editor(spot_with_selection());
    let image = harness.render().expect("a frame");
    // Right of the panel, count pixels that are neither background nor panel grey: the mesh
    // (shaded grey-blue) and the selection (blue).
    let (w, h) = image.dimensions();
    let mut mesh = 0;
    for y in (0..h).step_by(2) {
        for x in (w / 2..w).step_by(2) {
            let [r, g, b, _] = image.get_pixel(x, y).0.map(i32::from);
            if b > r + 15 && b > 80 && g < 235 {
                mesh += 1;
            }
        }
    }
    assert!(mesh > 2000, "only {mesh} mesh pixels in the viewport");
}

#[test]
fn run_simulates_the_shape_under_gravity_and_pause_stops_it() {
    let mut harness = editor(spot_with_selection());
    let rest = harness.state().document().positions().to_vec();
    assert!(!harness.state().is_simulating());
    harness.get_by_label("Run").click();
    harness.run_steps(2);
    assert!(harness.state().is_simulating());
    // Gravity pulls every vertex down; wait until it shows.
    step_until(&mut harness, |app| app.document().positions().iter().zip(&rest).all(|(p, r)| p.y < r.y - 1e-3));
    harness.get_by_label("Pause").click();
    harness.run_steps(2);
    assert!(!harness.state().is_running(), "paused");
    // A step already under way may still land.
    std::thread::sleep(Duration::from_millis(300));
    harness.run_steps(3);
    let paused = harness.state().document().positions().to_vec();
    std::thread::sleep(Duration::from_millis(300));
    harness.run_steps(3);
    assert!(harness.state().document().positions() == &paused[..], "paused: nothing moves");
    // Stop leaves dynamic mode with the current shape.
    harness.get_by_label("Stop").click();
    harness.run_steps(2);
    assert!(!harness.state().is_simulating());
    assert!(harness.state().document().positions() == &paused[..], "stop keeps the shape");
}
