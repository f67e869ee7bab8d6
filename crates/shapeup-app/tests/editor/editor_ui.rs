//! The editor's UI driven without a window (egui_kittest, rendering on any wgpu adapter,
//! lavapipe included): buttons, sliders, radio buttons and shortcuts reach the document.

use crate::max_distance;
use eframe::egui;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::{NodeT, Queryable};
use glam::DVec3;
use shapeup_app::GroupKey;
use shapeup_app::OrbitCamera;
use shapeup_app::document::GroupRole;
use shapeup_app::gui::app::EditorApp;
use shapeup_app::gui::files::sample_path;
use shapeup_app::picking::{box_select, visible_vertices};
use shapeup_app::simulation::{Speed, tetrahedralize_available};
use shapeup_app::{Command, Document, SelectMode, ShapeModel};
use shapeup_core::mesh::Mesh;
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
    settle(&mut harness);
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

/// Runs frames until the UI is idle, at most a few: unlike `Harness::run`, it does not fail
/// while the solver thread keeps waking the UI (it may, for a while, on a loaded machine).
fn settle(harness: &mut Harness<'_, EditorApp>) {
    let _ = harness.run_ok();
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
    settle(&mut harness);
    let handle = harness.state().document().handles().next().expect("a handle").clone();
    assert_eq!(handle.vertices().map(<[usize]>::len), Some(20));
    assert_eq!(handle.role, GroupRole::Handle);
    // The handle is listed in the groups panel (name and type).
    harness.get_by_label(&format!("{} (position)", handle.spec.name));

    // Ctrl+Z undoes the fix, the Redo button redoes it.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    assert_eq!(num_handles(harness.state()), 0, "ctrl+z undid the fix");
    harness.get_by_label("Redo").click();
    settle(&mut harness);
    assert_eq!(num_handles(harness.state()), 1, "redo restored the handle");
    // Ctrl+Shift+Z after an undo redoes as well.
    harness.get_by_label("Undo").click();
    settle(&mut harness);
    assert_eq!(num_handles(harness.state()), 0);
    harness.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    settle(&mut harness);
    assert_eq!(num_handles(harness.state()), 1);
}

#[test]
fn undo_or_redo_with_nothing_to_take_back_leaves_a_converged_shape_alone() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("Fix selection").click();
    step_until(&mut harness, EditorApp::is_converged);
    let solves = harness.state().solves_applied();
    let status = harness.state().solve_status().to_owned();
    // Nothing to redo: no new solve starts (it would run up to the iteration limit again).
    harness.key_press_modifiers(egui::Modifiers::COMMAND | egui::Modifiers::SHIFT, egui::Key::Z);
    harness.step();
    assert!(harness.state().is_converged(), "still converged");
    settle(&mut harness);
    assert_eq!(harness.state().solves_applied(), solves);
    assert_eq!(harness.state().solve_status(), status);
    assert_eq!(num_handles(harness.state()), 1);
}

#[test]
fn the_weight_slider_sets_the_group_weight_and_undo_restores_it() {
    let mut harness = editor(spot_with_selection());
    let before = harness.state().document().groups()[0].spec.weight;
    assert_eq!(before, 10.0, "edge springs start at the reference multiplier");
    // The group's slider is labelled "weight" (the others: iterations, damping).
    let is_weight = |s: &egui_kittest::Node<'_>| s.accesskit_node().label().unwrap_or_default().contains("weight");
    let sliders: Vec<_> = harness.get_all_by_role(Role::Slider).collect();
    assert_eq!(sliders.iter().filter(|s| is_weight(s)).count(), 1, "one group, one weight slider");
    let group_slider = sliders.iter().find(|s| is_weight(s)).expect("the shape group's slider");
    // The slider runs over log10 of the weight.
    group_slider.set_value_accesskit(250f64.log10());
    settle(&mut harness);
    let after = harness.state().document().groups()[0].spec.weight;
    assert!((after - 250.0).abs() < 1e-9 * 250.0, "weight {after}");
    // The slider clamps to the logarithmic range [1e-4, 1e4].
    let sliders: Vec<_> = harness.get_all_by_role(Role::Slider).collect();
    let group_slider = sliders.iter().find(|s| is_weight(s)).unwrap();
    group_slider.set_value_accesskit(9.0);
    settle(&mut harness);
    assert_eq!(harness.state().document().groups()[0].spec.weight, 1e4);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    assert!((harness.state().document().groups()[0].spec.weight - 250.0).abs() < 1e-9 * 250.0, "undo restores 250");
}

#[test]
fn switching_the_shape_model_keeps_the_handles_and_a_solve_moves_nothing_at_rest() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("Fix selection").click();
    settle(&mut harness);
    harness.get_by_label(ShapeModel::StrainBending.label()).click();
    settle(&mut harness);
    let doc = harness.state().document();
    assert_eq!(doc.shape_model(), Some(ShapeModel::StrainBending));
    assert_eq!(num_handles(harness.state()), 1, "the handle survives the switch");
    let kinds: Vec<&str> = doc.groups().iter().map(|g| g.spec.kind.as_str()).collect();
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
    harness.get_by_label("Run from rest").click();
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

// ---- Helpers for the tests below ----

/// The editor on `document` opened from `path`, in a window of `size` points.
fn editor_at(document: Document, path: &Path, size: egui::Vec2) -> Harness<'static, EditorApp> {
    let path = path.to_path_buf();
    let mut harness =
        Harness::builder().with_size(size).wgpu().build_eframe(move |cc| EditorApp::new(cc, document, path));
    settle(&mut harness);
    harness
}

/// `pieces` flat n×n-cell grids in the XY plane, side by side (x offset 2 each), not joined.
fn grids(n: u32, pieces: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for p in 0..pieces {
        let base = p * (n + 1) * (n + 1);
        for y in 0..=n {
            for x in 0..=n {
                positions.push(DVec3::new(
                    2.0 * f64::from(p) + f64::from(x) / f64::from(n),
                    f64::from(y) / f64::from(n),
                    0.0,
                ));
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

/// Selects `vertices` and fixes them as a new handle; returns its key.
fn fix(doc: &mut Document, vertices: Vec<u32>) -> GroupKey {
    doc.apply(Command::Select { vertices, mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    doc.handles().last().unwrap().key
}

/// The 3D viewport's rectangle (the central panel's click-and-drag area, right of the panel).
fn viewport_rect(harness: &Harness<'_, EditorApp>) -> egui::Rect {
    let node = harness.get_by(|n| n.role() == Role::Unknown && n.bounding_box().is_some_and(|r| r.width() > 300.0));
    node.rect()
}

/// A rendered frame, RGBA rows.
struct Frame {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

impl Frame {
    fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = 4 * (y as usize * self.width as usize + x as usize);
        [self.rgba[i], self.rgba[i + 1], self.rgba[i + 2]]
    }

    /// The pixels inside `rect` (points, at 1 pixel per point), clipped to the frame.
    fn pixels_in(&self, rect: egui::Rect) -> impl Iterator<Item = (u32, u32)> + use<> {
        let (x0, y0) = (rect.left().max(0.0) as u32, rect.top().max(0.0) as u32);
        let (x1, y1) =
            ((rect.right().max(0.0) as u32).min(self.width), (rect.bottom().max(0.0) as u32).min(self.height));
        (y0..y1).flat_map(move |y| (x0..x1).map(move |x| (x, y)))
    }

    /// How many pixels inside `rect` satisfy `keep`.
    fn count(&self, rect: egui::Rect, keep: impl Fn([u8; 3]) -> bool) -> usize {
        self.pixels_in(rect).filter(|&(x, y)| keep(self.pixel(x, y))).count()
    }

    /// How many pixels inside `rect` differ from `other`'s by more than 40 in a channel.
    fn differing(&self, other: &Frame, rect: egui::Rect) -> usize {
        self.pixels_in(rect)
            .filter(|&(x, y)| {
                let (a, b) = (self.pixel(x, y), other.pixel(x, y));
                (0..3).any(|k| a[k].abs_diff(b[k]) > 40)
            })
            .count()
    }
}

/// Renders the last frame (the 3D view included).
fn render(harness: &mut Harness<'_, EditorApp>) -> Frame {
    let image = harness.render().expect("a frame");
    Frame { width: image.width(), height: image.height(), rgba: image.into_raw() }
}

/// The hover colour (orange) under any shading: red over green over blue, clearly apart.
fn is_orange([r, g, b]: [u8; 3]) -> bool {
    let (r, g, b) = (i32::from(r), i32::from(g), i32::from(b));
    r > g + 30 && g > b + 30 && r > 100
}

/// The banner's fill, rgb(180, 30, 30).
fn is_banner_red([r, g, b]: [u8; 3]) -> bool {
    r.abs_diff(180) <= 12 && g.abs_diff(30) <= 12 && b.abs_diff(30) <= 12
}

/// Replaces the text of the Open row's path field (labelled by the "Open…" button) and presses
/// Enter.
fn type_open_path(harness: &mut Harness<'_, EditorApp>, path: &str) {
    harness.get_by_role_and_label(Role::TextInput, "Open…").click();
    settle(harness);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    settle(harness);
    harness.get_by_role_and_label(Role::TextInput, "Open…").type_text(path);
    settle(harness);
    harness.key_press(egui::Key::Enter);
    harness.step();
}

const BUNNY_SPRINGS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples/bunny-springs.toml");

// ---- 1. Hover highlight ----

#[test]
fn hovering_a_groups_row_highlights_its_vertices_in_the_rendered_view() {
    // The upper half of Spot becomes a handle (green); hovering its row paints it orange.
    let mut doc = Document::open(Path::new(SPOT), ShapeModel::EdgeSprings).unwrap();
    let mut ys: Vec<f64> = doc.positions().iter().map(|p| p.y).collect();
    ys.sort_by(f64::total_cmp);
    let median = ys[ys.len() / 2];
    let upper: Vec<u32> = (0..doc.num_vertices() as u32).filter(|&v| doc.positions()[v as usize].y > median).collect();
    let handle = fix(&mut doc, upper);
    let mut harness = editor(doc);
    let name = format!("{} (position)", harness.state().document().group(handle).unwrap().spec.name);
    let viewport = viewport_rect(&harness);
    let away = viewport.max - egui::vec2(5.0, 5.0);
    // Only the viewport, away from any tooltip next to the panel.
    let view = egui::Rect::from_min_max(viewport.min + egui::vec2(150.0, 0.0), viewport.max);

    harness.hover_at(away);
    settle(&mut harness);
    assert_eq!(harness.state().hovered_group(), None);
    let plain = render(&mut harness);
    let plain_orange = plain.count(view, is_orange);

    // The row's label.
    harness.get_by_label(&name).hover();
    settle(&mut harness);
    assert_eq!(harness.state().hovered_group(), Some(handle), "hovering the row's name");
    let hovered = render(&mut harness);
    let hovered_orange = hovered.count(view, is_orange);
    let changed = hovered.differing(&plain, view);
    assert!(
        hovered_orange > plain_orange + 2000,
        "hovering the row paints the handle orange: {plain_orange} orange pixels before, {hovered_orange} after"
    );
    assert!(changed > 2000, "only {changed} viewport pixels changed");

    // Away again: the highlight goes.
    harness.hover_at(away);
    settle(&mut harness);
    assert_eq!(harness.state().hovered_group(), None);
    let again = render(&mut harness);
    let again_orange = again.count(view, is_orange);
    assert!(again_orange < plain_orange + 200, "the highlight stays: {again_orange} orange pixels");

    // The row's weight slider (below its name) highlights as well.
    let label_top = harness.get_by_label(&name).rect().top();
    let slider = harness
        .get_all_by_role_and_label(Role::Slider, "weight")
        .filter(|s| s.rect().top() > label_top)
        .min_by(|a, b| a.rect().top().total_cmp(&b.rect().top()))
        .expect("the handle's weight slider");
    slider.hover();
    settle(&mut harness);
    assert_eq!(harness.state().hovered_group(), Some(handle), "hovering the row's slider");
    let on_slider = render(&mut harness);
    let slider_orange = on_slider.count(view, is_orange);
    assert!(slider_orange > plain_orange + 2000, "{slider_orange} orange pixels with the pointer on the slider");
}

// ---- 2. The solve-error banner and "Pin free pieces" ----

#[test]
fn a_free_piece_shows_the_banner_keeps_the_shape_and_pin_free_pieces_clears_it() {
    // Two separate sheets in an OBJ file; a handle on the first sheet only, moved up.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two-sheets.obj");
    shapeup_core::io::write_mesh(&path, &grids(6, 2), &shapeup_core::io::Attributes::None).unwrap();
    let mut doc = Document::open(&path, ShapeModel::StrainBending).unwrap();
    assert_eq!(doc.pieces().count, 2);
    let left_column: Vec<u32> = (0..=6).map(|y| y * 7).collect();
    let handle = fix(&mut doc, left_column.clone());
    doc.apply(Command::MoveHandle { handle, delta: DVec3::new(0.0, 0.0, 0.3) }).unwrap();
    let rest = doc.positions().to_vec();
    let mut harness = editor_at(doc, &path, egui::vec2(1100.0, 800.0));
    let viewport = viewport_rect(&harness);
    let banner_area = egui::Rect::from_min_size(viewport.min, egui::vec2(400.0, 60.0));

    // The system is singular: the solve fails, the banner says so over the 3D view.
    step_until(&mut harness, |app| app.banner().is_some());
    settle(&mut harness);
    let banner = harness.state().banner().unwrap().to_owned();
    assert!(banner.starts_with("solve failed"), "banner: {banner}");
    harness.get_by_label("1 of 2 pieces has no handle");
    assert!(harness.state().document().positions() == &rest[..], "a failed solve keeps the last good shape");
    assert_eq!(harness.state().solves_applied(), 0);
    let frame = render(&mut harness);
    let red = frame.count(banner_area, is_banner_red);
    assert!(red > 1000, "only {red} banner-red pixels at the top left of the viewport");

    // Pin free pieces: the solve succeeds, the banner goes, no piece is free.
    harness.get_by_label("Pin free pieces").click();
    step_until(&mut harness, |app| app.banner().is_none() && app.solves_applied() > 0);
    settle(&mut harness);
    assert_eq!(harness.state().document().num_free_pieces(), 0);
    harness.get_by_label("0 of 2 pieces have no handle");
    assert!(harness.query_by_label("1 of 2 pieces has no handle").is_none());
    // The held sheet follows its handle up; the pinned one stays at rest.
    step_until(&mut harness, |app| (app.document().positions()[0].z - 0.3).abs() < 1e-2);
    let positions = harness.state().document().positions();
    for v in 49..98 {
        assert!((positions[v] - rest[v]).length() < 1e-6, "the pinned sheet moved at vertex {v}");
    }
    let frame = render(&mut harness);
    let red = frame.count(banner_area, is_banner_red);
    assert!(red < 50, "the banner is still drawn ({red} red pixels)");
}

/// Suzanne's eyes (separate pieces) are attached when she is opened; with that group removed,
/// "Attach free pieces" attaches them again and the gizmo stays on the user's handle.
#[test]
fn attach_free_pieces_attaches_the_eyes_and_leaves_the_gizmo_on_its_handle() {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj"));
    let mut doc = Document::open(path, ShapeModel::EdgeSprings).unwrap();
    assert_eq!(doc.num_attached_pieces(), 2);
    let attached = doc.groups().iter().find(|g| g.spec.kind == "attachment").unwrap().key;
    doc.apply(Command::RemoveGroup(attached)).unwrap();
    let piece = |v: u32| doc.pieces().of_vertex[v as usize];
    let size = |p: u32| (0..doc.num_vertices() as u32).filter(|&v| piece(v) == p).count();
    let largest = (0..3).max_by_key(|&p| size(p)).unwrap();
    let head: Vec<u32> = (0..doc.num_vertices() as u32).filter(|&v| piece(v) == largest).collect();
    fix(&mut doc, head[..10].to_vec());
    doc.apply(Command::Select { vertices: head[head.len() - 10..].to_vec(), mode: SelectMode::Replace }).unwrap();
    let mut harness = editor_at(doc, path, egui::vec2(1100.0, 800.0));
    harness.get_by_label("2 of 3 pieces have no handle");
    // The user's handle, made on screen, has the gizmo.
    harness.get_by_label("Fix selection").click();
    settle(&mut harness);
    let mine = harness.state().document().handles().last().unwrap().key;
    assert_eq!(harness.state().active_handle(), Some(mine));

    harness.get_by_label("Attach free pieces").click();
    settle(&mut harness);
    let app = harness.state();
    assert_eq!(app.document().num_attached_pieces(), 2);
    assert_eq!(app.document().num_free_pieces(), 0);
    assert_eq!(app.active_handle(), Some(mine), "the gizmo stays on the handle the user was working with");
    assert!(app.status().contains("2 pieces follow the surface under them"), "{}", app.status());
    harness.get_by_label("0 of 3 pieces have no handle");
}

// ---- 3. The Open row's path field ----

/// The bunny-ears scene as opened: its mesh, its two handles, and it opens solved (the ears
/// move off the rest shape).
fn assert_opened_bunny_scene(harness: &mut Harness<'_, EditorApp>, solves_before: u64) {
    assert_eq!(harness.state().path_input(), BUNNY_SPRINGS);
    let doc = harness.state().document();
    assert_eq!(doc.num_vertices(), 35_947, "the bunny's mesh");
    let names: Vec<&str> = doc.handles().map(|h| h.spec.name.as_str()).collect();
    assert_eq!(names, ["base", "ears"]);
    step_until(harness, |app| {
        app.solves_applied() > solves_before
            && max_distance(app.document().positions(), app.document().rest_positions()) > 1e-3
    });
    assert!(harness.state().banner().is_none(), "{:?}", harness.state().banner());
}

#[test]
fn typing_a_path_and_enter_opens_the_scene_solved() {
    let mut harness = editor(spot_with_selection());
    assert_eq!(harness.state().path_input(), SPOT);
    assert!(!harness.state().document().is_modified());
    let solves_before = harness.state().solves_applied();
    type_open_path(&mut harness, BUNNY_SPRINGS);
    settle(&mut harness);
    assert!(harness.query_by_label("Discard changes and open").is_none(), "nothing to lose: no question");
    assert_opened_bunny_scene(&mut harness, solves_before);
}

#[test]
fn the_samples_menu_opens_a_sample_and_shows_its_path() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("Samples").click();
    settle(&mut harness);
    harness.get_by_label("Suzanne (quads)").click();
    settle(&mut harness);
    // By its name, read from memory: no path compiled into the binary, whatever the working
    // directory.
    assert_eq!(sample_path("suzanne"), Path::new("suzanne"));
    assert_eq!(harness.state().path_input(), "suzanne");
    let doc = harness.state().document();
    assert_eq!(doc.source(), None, "a sample has no file: Save scene writes its mesh beside the scene");
    let file = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj"));
    assert_eq!(doc.rest_mesh().positions, Document::open(file, ShapeModel::EdgeSprings).unwrap().rest_mesh().positions);
    assert!(matches!(doc.attributes(), shapeup_core::io::Attributes::Obj(_)), "what the file carries comes along");
    assert_eq!(doc.num_selected(), 0, "a fresh document");
    assert_eq!(
        harness.state().status(),
        "opened the bundled sample suzanne; 2 pieces that sit on the body follow it (group \"attached pieces\"; remove it to let them go)"
    );
    assert_eq!(
        harness.get_by_role_and_label(Role::TextInput, "Open…").value(),
        Some("suzanne".to_string()),
        "the path field shows the sample's name"
    );
}

#[test]
fn opening_with_unsaved_changes_asks_first_and_cancel_keeps_the_document() {
    let mut harness = editor(spot_with_selection());
    harness.get_by_label("Fix selection").click();
    settle(&mut harness);
    assert!(harness.state().document().is_modified());
    let n = harness.state().document().num_vertices();
    let handles: Vec<_> = harness.state().document().handles().cloned().collect();
    assert_eq!(handles.len(), 1);

    type_open_path(&mut harness, BUNNY_SPRINGS);
    settle(&mut harness);
    harness.get_by_label("Discard changes and open");
    assert_eq!(harness.state().document().num_vertices(), n, "nothing opened before the answer");
    harness.get_by_label("Cancel").click();
    settle(&mut harness);
    assert!(harness.query_by_label("Discard changes and open").is_none(), "the question is gone");
    let doc = harness.state().document();
    assert_eq!(doc.num_vertices(), n);
    assert_eq!(doc.handles().cloned().collect::<Vec<_>>(), handles, "the same handles");
    assert!(doc.is_modified());
    assert_eq!(harness.state().path_input(), SPOT, "the path field shows the current file again");
    assert_eq!(harness.get_by_role_and_label(Role::TextInput, "Open…").value().as_deref(), Some(SPOT));

    // Asked again, discarding opens the scene.
    let solves_before = harness.state().solves_applied();
    type_open_path(&mut harness, BUNNY_SPRINGS);
    settle(&mut harness);
    harness.get_by_label("Discard changes and open").click();
    settle(&mut harness);
    assert!(harness.query_by_label("Discard changes and open").is_none());
    assert_opened_bunny_scene(&mut harness, solves_before);
}

/// Asks the window to close (the title bar's close button) and runs one frame; returns the
/// viewport commands that frame sent.
fn request_close(harness: &mut Harness<'_, EditorApp>) -> Vec<egui::ViewportCommand> {
    harness.input_mut().viewports.entry(egui::ViewportId::ROOT).or_default().events.push(egui::ViewportEvent::Close);
    harness.step();
    harness.output().viewport_output.get(&egui::ViewportId::ROOT).map(|v| v.commands.clone()).unwrap_or_default()
}

#[test]
fn closing_with_unsaved_changes_asks_first() {
    let mut harness = editor(spot_with_selection());
    // Nothing to lose: the window closes.
    assert!(!request_close(&mut harness).contains(&egui::ViewportCommand::CancelClose));
    assert!(!harness.state().is_confirming_close());

    harness.get_by_label("Fix selection").click();
    settle(&mut harness);
    assert!(request_close(&mut harness).contains(&egui::ViewportCommand::CancelClose), "the close is held");
    settle(&mut harness);
    assert!(harness.state().is_confirming_close());
    harness.get_by_label("Quit without saving?");
    harness.get_by_label("Cancel").click();
    settle(&mut harness);
    assert!(harness.query_by_label("Quit without saving?").is_none());
    assert_eq!(num_handles(harness.state()), 1, "the session goes on");

    assert!(request_close(&mut harness).contains(&egui::ViewportCommand::CancelClose));
    settle(&mut harness);
    harness.get_by_label("Discard changes and quit").click();
    harness.step();
    let commands =
        harness.output().viewport_output.get(&egui::ViewportId::ROOT).map(|v| v.commands.clone()).unwrap_or_default();
    assert!(commands.contains(&egui::ViewportCommand::Close), "{commands:?}");
    // The close that follows goes through.
    assert!(!request_close(&mut harness).contains(&egui::ViewportCommand::CancelClose));
}

// ---- 4. The Dynamics panel ----

#[test]
fn the_dynamics_panel_controls_settings_run_and_undo() {
    // Tall enough that the whole Dynamics section is on screen.
    let size = egui::vec2(1100.0, 1200.0);
    let mut harness = editor_at(spot_with_selection(), Path::new(SPOT), size);
    for label in ["Run from rest", "Continue", "Restart", "Stop"] {
        harness.get_by_role_and_label(Role::Button, label);
    }
    for label in ["Gravity", "Floor", "Tetrahedralize"] {
        harness.get_by_role_and_label(Role::CheckBox, label);
    }
    for label in ["Document's shape model", "Tet strain", "Real time", "Slow motion (¼)", "As fast as possible"] {
        harness.get_by_role_and_label(Role::RadioButton, label);
    }
    // Real time by default; the speed buttons edit the settings.
    assert_eq!(harness.state().dynamics_settings().speed, Speed::RealTime);
    harness.get_by_role_and_label(Role::RadioButton, "Slow motion (¼)").click();
    settle(&mut harness);
    assert_eq!(harness.state().dynamics_settings().speed, Speed::SlowMotion);
    harness.get_by_role_and_label(Role::RadioButton, "Real time").click();
    settle(&mut harness);
    assert_eq!(harness.state().dynamics_settings().speed, Speed::RealTime);
    for label in ["stiffness", "time step (ms)", "damping", "grab strength"] {
        harness.get_by_role_and_label(Role::Slider, label);
    }
    assert!(harness.get_by_role_and_label(Role::Button, "Restart").accesskit_node().is_disabled(), "no simulation");
    assert!(harness.get_by_role_and_label(Role::Button, "Stop").accesskit_node().is_disabled(), "no simulation");
    // Spot is closed: Tetrahedralize can be ticked exactly when this build has TetGen.
    let spot_tets = tetrahedralize_available(harness.state().document());
    assert_eq!(spot_tets.is_ok(), cfg!(feature = "tetgen"), "{spot_tets:?}");
    let tetrahedralize = harness.get_by_role_and_label(Role::CheckBox, "Tetrahedralize");
    assert_eq!(tetrahedralize.accesskit_node().is_disabled(), spot_tets.is_err());

    // The stiffness slider edits the settings.
    let before = harness.state().dynamics_settings().stiffness;
    harness.get_by_role_and_label(Role::Slider, "stiffness").set_value_accesskit(1000.0);
    settle(&mut harness);
    let stiffness = harness.state().dynamics_settings().stiffness;
    assert!(stiffness != before && (stiffness - 1000.0).abs() < 1e-6, "stiffness {before} → {stiffness}");
    // Also with the pointer: the left end of the rail is the least stiffness.
    let rail = harness.get_by_role_and_label(Role::Slider, "stiffness").rect();
    harness.get_by_role_and_label(Role::Slider, "stiffness").hover();
    settle(&mut harness);
    harness.drag_at(rail.left_center());
    harness.drop_at(rail.left_center());
    settle(&mut harness);
    assert_eq!(harness.state().dynamics_settings().stiffness, 1.0, "clicked at the rail's left end");
    harness.get_by_role_and_label(Role::Slider, "stiffness").set_value_accesskit(100.0);
    settle(&mut harness);

    // Run: the timings line appears, Restart and Stop are enabled.
    let before_run = harness.state().document().positions().to_vec();
    assert!(harness.query_by_label_contains("steps/s").is_none());
    harness.get_by_role_and_label(Role::Button, "Continue").click();
    harness.run_steps(2);
    assert!(harness.state().is_running());
    harness.get_by_label_contains("steps/s");
    assert!(!harness.get_by_role_and_label(Role::Button, "Stop").accesskit_node().is_disabled());
    step_until(&mut harness, |app| max_distance(app.document().positions(), &before_run) > 1e-3);

    // Stop, then undo: the shape from before the run comes back.
    harness.get_by_role_and_label(Role::Button, "Stop").click();
    harness.run_steps(2);
    assert!(!harness.state().is_simulating());
    assert!(harness.query_by_label_contains("steps/s").is_none());
    assert!(max_distance(harness.state().document().positions(), &before_run) > 1e-3, "stop keeps the shape");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    assert!(harness.state().document().positions() == &before_run[..], "undo brings back the shape before the run");

    // An open sheet cannot be tetrahedralized.
    let grid = Document::new(grids(4, 1), ShapeModel::StrainBending).unwrap();
    let grid_tets = tetrahedralize_available(&grid);
    assert!(grid_tets.is_err());
    if cfg!(feature = "tetgen") {
        assert!(grid_tets.as_ref().unwrap_err().to_string().contains("open"), "{grid_tets:?}");
    }
    let harness = editor_at(grid, Path::new("sheet.obj"), size);
    let tetrahedralize = harness.get_by_role_and_label(Role::CheckBox, "Tetrahedralize");
    assert!(tetrahedralize.accesskit_node().is_disabled(), "Tetrahedralize is disabled for an open mesh");
    assert!(harness.get_by_role_and_label(Role::RadioButton, "Tet strain").accesskit_node().is_disabled());
}

// ---- 5. Box selection ----

#[test]
fn a_box_selection_spans_from_the_press_point_to_the_release_point() {
    let mut harness = editor(spot_with_selection());
    let viewport = viewport_rect(&harness);
    // The app's camera on a fresh document: framed on the mesh from the front.
    let doc = harness.state().document();
    let mut camera = OrbitCamera::default();
    camera.frame_front(doc.positions(), doc.triangles());
    let size = glam::Vec2::new(viewport.width(), viewport.height());
    let local = |p: egui::Pos2| glam::Vec2::new(p.x - viewport.left(), p.y - viewport.top());
    let boxed =
        |a: egui::Pos2, b: egui::Pos2| box_select(doc.positions(), doc.triangles(), &camera, size, local(a), local(b));

    // The mesh's extent on screen.
    let (lo, hi) = doc
        .positions()
        .iter()
        .filter_map(|p| camera.project(p.as_vec3(), size))
        .fold((glam::Vec2::INFINITY, glam::Vec2::NEG_INFINITY), |(lo, hi), (pixel, _)| (lo.min(pixel), hi.max(pixel)));
    let screen = |p: glam::Vec2| viewport.min + egui::vec2(p.x, p.y);
    // Press above left of the mesh, release below right of it; the first motion egui reports
    // is already in the middle of the mesh.
    let press = screen(lo) - egui::vec2(10.0, 10.0);
    let release = screen(hi) + egui::vec2(10.0, 10.0);
    assert!(viewport.contains(press) && viewport.contains(release), "{press:?} {release:?} in {viewport:?}");
    let first_motion = press + (release - press) * 0.5;
    let expected = boxed(press, release);
    let from_first_motion = boxed(first_motion, release);
    let visible = visible_vertices(doc.positions(), doc.triangles(), &camera, size);
    assert_eq!(expected.len(), visible.iter().filter(|v| **v).count(), "the box holds every visible vertex");
    assert!(
        expected.len() > 2 * from_first_motion.len(),
        "the test needs boxes that differ: {} vs {}",
        expected.len(),
        from_first_motion.len()
    );

    let ctrl = egui::Modifiers::CTRL | egui::Modifiers::COMMAND;
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: ctrl,
    };
    harness.event(egui::Event::ModifiersChanged(ctrl));
    harness.event(egui::Event::PointerMoved(press));
    harness.event(button(press, true));
    for t in [0.5, 0.7, 0.9, 1.0] {
        harness.event(egui::Event::PointerMoved(press + (release - press) * t));
    }
    harness.event(button(release, false));
    harness.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    harness.step();
    settle(&mut harness);

    let selected = harness.state().document().selected_vertices();
    assert!(
        selected == expected,
        "selected {} vertices, the box from the press point holds {} (from the first motion: {})",
        selected.len(),
        expected.len(),
        from_first_motion.len()
    );
    harness.get_by_label(&format!("{} vertices selected", expected.len()));
}

// ---- 6. One undo step per slider drag ----

/// Presses the primary button at `from`, moves by each of `steps` (from `from`) in its own
/// frame and releases at the last point.
fn drag_through(harness: &mut Harness<'_, EditorApp>, from: egui::Pos2, steps: &[egui::Vec2]) {
    let button = |pos, pressed| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    harness.event(egui::Event::PointerMoved(from));
    harness.event(button(from, true));
    let mut end = from;
    for &step in steps {
        end = from + step;
        harness.event(egui::Event::PointerMoved(end));
    }
    harness.event(button(end, false));
    harness.step();
    settle(harness);
}

#[test]
fn dragging_a_weight_slider_is_one_undo_step() {
    let mut harness = editor(spot_with_selection());
    let weight = |h: &Harness<'_, EditorApp>| h.state().document().groups()[0].spec.weight;
    let before = weight(&harness);
    assert_eq!(before, 10.0);
    assert!(!harness.state().document().can_undo());
    let rail = harness.get_by_role_and_label(Role::Slider, "weight").rect();
    // Press on the knob (log10 10 = 1 on [-4, 4]), then drag right over several frames.
    let knob = egui::pos2(rail.left() + rail.width() * 5.0 / 8.0, rail.center().y);
    let right: Vec<egui::Vec2> = [8.0, 16.0, 24.0, 32.0].map(|dx| egui::vec2(dx, 0.0)).to_vec();
    drag_through(&mut harness, knob, &right);
    let after = weight(&harness);
    assert!(after > 2.0 * before, "the drag raised the weight: {before} → {after}");

    // A second drag, pressed on the rail away from the knob and moved left.
    let left: Vec<egui::Vec2> = [-6.0, -12.0, -18.0].map(|dx| egui::vec2(dx, 0.0)).to_vec();
    drag_through(&mut harness, egui::pos2(rail.left() + rail.width() * 0.4, rail.center().y), &left);
    let second = weight(&harness);
    assert!(second < before, "the second drag lowered the weight: {after} → {second}");

    // One ctrl+z per drag.
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    let undone = weight(&harness);
    assert!(undone == after, "one undo restores the weight before the second drag: {second} → {undone}, not {after}");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    let undone = weight(&harness);
    assert!(undone == before, "a second undo restores the weight before the first drag: {undone}, not {before}");
    assert!(!harness.state().document().can_undo(), "each drag was a single undo step");
}

#[test]
fn a_typed_weight_that_is_no_weight_is_said_under_its_row() {
    let mut harness = editor(spot_with_selection());
    let weight = |h: &Harness<'_, EditorApp>| h.state().document().groups()[0].spec.weight;
    for (typed, said) in [
        ("-3", "weight \"-3\" refused: type a number from 1e-4 to 1e4"),
        ("NaN", "weight \"NaN\" refused: type a number from 1e-4 to 1e4"),
        ("abc", "weight \"abc\" refused: type a number from 1e-4 to 1e4"),
        ("1e9", "weight \"1e9\" refused: type a number from 1e-4 to 1e4"),
        (
            "0",
            "weight \"0\" refused: a weight of 0 turns the group off; remove the group instead (weights go from 1e-4 to 1e4)",
        ),
    ] {
        type_weight(&mut harness, typed);
        assert_eq!(weight(&harness), 10.0, "{typed} left the weight");
        harness.get_by_label(said);
    }
    // A good one is taken, and the message goes.
    type_weight(&mut harness, "250");
    assert_eq!(weight(&harness), 250.0);
    assert!(harness.query_by_label_contains("refused").is_none());
}

/// Types `text` into the first group's weight field and presses Enter.
fn type_weight(harness: &mut Harness<'_, EditorApp>, text: &str) {
    let at = harness.get_all_by_role(Role::SpinButton).next().expect("the weight's number field").rect().center();
    let button = |pressed| egui::Event::PointerButton {
        pos: at,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    harness.event(egui::Event::PointerMoved(at));
    harness.step();
    harness.event(button(true));
    harness.step();
    harness.event(button(false));
    harness.step();
    harness.step();
    harness.key_combination_modifiers(egui::Modifiers::COMMAND, &[egui::Key::A]);
    // In edit the field keeps its role.
    let field = harness.get_all_by_role(Role::SpinButton).find(|n| n.accesskit_node().is_focused());
    field.expect("the weight's field, in edit").type_text(text);
    settle(harness);
    harness.key_press(egui::Key::Enter);
    settle(harness);
}

#[test]
fn f_frames_the_selection_esc_clears_it_ctrl_s_saves_ctrl_o_opens() {
    let dir = tempfile::tempdir().unwrap();
    let mut harness = editor(spot_with_selection());
    let whole = *harness.state().camera();
    // F: the view turns onto the selection's box (the 20 lowest vertices), from nearer.
    harness.key_press(egui::Key::F);
    settle(&mut harness);
    let doc = harness.state().document();
    let selected: Vec<glam::DVec3> = doc.selected_vertices().iter().map(|&v| doc.positions()[v as usize]).collect();
    let (lo, hi) = selected.iter().fold((selected[0], selected[0]), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let camera = *harness.state().camera();
    assert!((camera.target - (0.5 * (lo + hi)).as_vec3()).length() < 1e-5, "{:?}", camera.target);
    assert!(camera.distance < 0.5 * whole.distance, "{} vs {}", camera.distance, whole.distance);
    // Esc clears the selection; F then frames the whole shape. The panel keeps its rows
    // (nothing below the selection section moves).
    let below = harness.get_by_role_and_label(Role::Button, "Clear handles").rect();
    harness.key_press(egui::Key::Escape);
    settle(&mut harness);
    assert_eq!(harness.state().document().num_selected(), 0);
    assert_eq!(harness.get_by_role_and_label(Role::Button, "Clear handles").rect(), below, "the panel moved");
    assert!(harness.get_by_role_and_label(Role::Button, "Add constraint to selection").accesskit_node().is_disabled());
    harness.key_press(egui::Key::F);
    settle(&mut harness);
    assert!((harness.state().camera().distance - whole.distance).abs() < 1e-3 * whole.distance);

    // Ctrl+S saves to the Save row's path, also while typing it.
    let scene = dir.path().join("saved.toml");
    harness.get_by_role_and_label(Role::TextInput, "Save…").click();
    settle(&mut harness);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness.get_by_role_and_label(Role::TextInput, "Save…").type_text(&scene.display().to_string());
    settle(&mut harness);
    assert!(!scene.exists());
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::S);
    settle(&mut harness);
    assert!(scene.exists(), "{}", harness.state().status());
    // F typed into a text field is text, not a shortcut.
    let framed = *harness.state().camera();
    harness.get_by_role_and_label(Role::TextInput, "Save…").type_text("f");
    settle(&mut harness);
    assert_eq!(*harness.state().camera(), framed);

    // Ctrl+O asks for a file as Open… does: its button is disabled while the dialog is up, or
    // (no dialog service here) the status says none was chosen.
    harness.key_press(egui::Key::Escape);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::O);
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        harness.step();
        let asked = harness.get_by_role_and_label(Role::Button, "Open…").accesskit_node().is_disabled()
            || harness.state().status().contains("no file chosen");
        if asked {
            break;
        }
        assert!(Instant::now() < deadline, "Ctrl+O did nothing: {}", harness.state().status());
    }
}

#[test]
fn the_screenshot_button_saves_the_3d_view_beside_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    // Tall enough that the view settings row is on screen.
    let mut harness = editor_at(spot_with_selection(), Path::new(SPOT), egui::vec2(1100.0, 1500.0));
    harness.get_by_role_and_label(Role::TextInput, "Save…").click();
    settle(&mut harness);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::A);
    harness.get_by_role_and_label(Role::TextInput, "Save…").type_text(&dir.path().join("s.toml").display().to_string());
    harness.key_press(egui::Key::Escape);
    settle(&mut harness);
    for n in 1..=2 {
        harness.get_by_role_and_label(Role::Button, "Screenshot").click();
        let png = dir.path().join(format!("spot-view-{n}.png"));
        let said = format!("saved the view to {}", png.display());
        step_until(&mut harness, |app| app.status() == said || app.status().contains("not saved"));
        assert_eq!(harness.state().status(), said);
        // The view's pixels only (the panels left out), with the mesh on them.
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size()];
        let info = reader.next_frame(&mut pixels).unwrap();
        let window = harness.ctx.content_rect().size() * harness.ctx.pixels_per_point();
        assert!(info.width > 300 && (info.width as f32) < 0.8 * window.x, "{} of {}", info.width, window.x);
        assert!(info.height > 300 && info.height as f32 <= window.y, "{} of {}", info.height, window.y);
        let mesh = pixels.chunks(4).filter(|p| p[0] < 200 && p[2] > p[0]).count();
        assert!(mesh > 1000, "only {mesh} mesh-coloured pixels");
        harness.run_steps(2);
    }
}

#[test]
fn a_scene_weight_outside_the_slider_range_is_kept() {
    let text = format!(
        "[mesh]\npath = '{SPOT}'\n[[constraints]]\ntype = \"edge_spring\"\nweight = 1e5\n\
         [[constraints]]\ntype = \"position\"\nvertices = [0, 1, 2]\n\
         [[constraints]]\ntype = \"smoothing\"\nweight = 1e-5\n"
    );
    let scene = shapeup_core::scene::Scene::parse(
        &text,
        shapeup_core::scene::SceneFormat::Toml,
        Path::new("w.toml"),
        PathBuf::new(),
    )
    .unwrap();
    let mut harness = editor(Document::from_scene(&scene).unwrap());
    harness.run_steps(5);
    let weights: Vec<f64> = harness.state().document().groups().iter().map(|g| g.spec.weight).collect();
    assert_eq!(weights, [1e5, 1.0, 1e-5]);
    assert!(!harness.state().document().is_modified());
}

/// Presses at `from` holding `modifiers`, moves through `from + steps` one frame each, and
/// releases: a drag as a hand makes it, frame by frame.
fn drag_in_frames(
    harness: &mut Harness<'_, EditorApp>,
    from: egui::Pos2,
    steps: &[egui::Vec2],
    modifiers: egui::Modifiers,
) {
    let button =
        |pos, pressed| egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed, modifiers };
    harness.event(egui::Event::ModifiersChanged(modifiers));
    harness.event(egui::Event::PointerMoved(from));
    harness.step();
    harness.event(button(from, true));
    harness.step();
    let mut end = from;
    for &step in steps {
        end = from + step;
        harness.event(egui::Event::PointerMoved(end));
        harness.step();
    }
    harness.event(button(end, false));
    harness.step();
    harness.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
    settle(harness);
}

#[test]
fn a_shift_drag_moves_a_weight_ten_times_finer() {
    let mut harness = editor(spot_with_selection());
    let log_weight = |h: &Harness<'_, EditorApp>| h.state().document().groups()[0].spec.weight.log10();
    assert_eq!(log_weight(&harness), 1.0);
    let rail = harness.get_by_role_and_label(Role::Slider, "weight").rect();
    // The knob: log10 10 = 1 on [-4, 4].
    let knob = egui::pos2(rail.left() + rail.width() * 5.0 / 8.0, rail.center().y);
    let right: Vec<egui::Vec2> = [4.0, 8.0, 12.0, 16.0, 20.0].map(|dx| egui::vec2(dx, 0.0)).to_vec();
    // The press puts the knob under the pointer; the motion after it is compared.
    drag_in_frames(&mut harness, knob, &[], egui::Modifiers::NONE);
    let pressed = log_weight(&harness);
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    drag_in_frames(&mut harness, knob, &right, egui::Modifiers::NONE);
    let coarse = log_weight(&harness) - pressed;
    assert!(coarse > 0.1, "a plain 20 px drag moves {coarse} decades");
    harness.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    settle(&mut harness);
    assert_eq!(log_weight(&harness), 1.0);

    drag_in_frames(&mut harness, knob, &right, egui::Modifiers::SHIFT);
    let fine = log_weight(&harness) - 1.0;
    assert!((fine / coarse - 0.1).abs() < 0.01, "shift: {fine} decades where a plain drag moved {coarse}");
}

// ---- Contact ----

#[test]
fn the_contact_panel_adds_selects_edits_and_removes_colliders() {
    let cloth = Document::new(shapeup_core::generate::cloth_grid(11, 11, 1.0, 1.0), ShapeModel::EdgeSprings).unwrap();
    // Tall enough that the Contact section, under Dynamics, is on screen.
    let mut harness = editor_at(cloth, Path::new("cloth.obj"), egui::vec2(1100.0, 1600.0));
    harness.get_by_label("no colliders");
    harness.get_by_role_and_label(Role::TextInput, "Mesh…");
    harness.get_by_role_and_label(Role::Button, "Add sphere").click();
    settle(&mut harness);
    let colliders = harness.state().document().colliders().to_vec();
    assert_eq!(colliders.len(), 1);
    assert_eq!(colliders[0].kind(), "sphere");
    assert_eq!(harness.state().selected_collider(), Some(0), "the new collider gets the gizmo");
    harness.get_by_label("0: sphere");
    harness.get_by_label_contains("radius");
    // Its outline is drawn over the view in the selection's orange (the mesh has no orange).
    let view = viewport_rect(&harness);
    let orange = render(&mut harness).count(view, is_orange);
    assert!(orange > 100, "{orange} orange pixels");
    harness.get_by_label("0: sphere").click();
    settle(&mut harness);
    assert_eq!(harness.state().selected_collider(), None, "a second click deselects");
    assert_eq!(render(&mut harness).count(view, is_orange), 0, "not selected: grey");
    harness.get_by_label("0: sphere").click();
    settle(&mut harness);
    // A spin is switched on and edited from the panel.
    harness.get_by_role_and_label(Role::CheckBox, "spins").click();
    settle(&mut harness);
    let spin = harness.state().document().colliders()[0].spin;
    assert!(spin.is_some_and(|s| s.deg_per_s == 30.0 && s.axis == [0.0, 1.0, 0.0]), "{spin:?}");
    harness.get_by_label_contains("spin (°/s)");

    harness.get_by_role_and_label(Role::CheckBox, "Self-collision").click();
    settle(&mut harness);
    assert!(harness.state().document().contact_settings().self_collision);
    harness.get_by_label("Undo").click();
    settle(&mut harness);
    assert!(!harness.state().document().contact_settings().self_collision, "undone");

    harness.get_by_role_and_label(Role::Button, "Add plane").click();
    settle(&mut harness);
    assert_eq!(harness.state().document().colliders().len(), 2);
    harness.get_by_label("1: plane");
    harness.get_by_label("0: sphere").click();
    settle(&mut harness);
    assert_eq!(harness.state().selected_collider(), Some(0));
    // The selected collider's row shows its numbers; its own "remove" is the first.
    harness.get_all_by_role_and_label(Role::Button, "remove").next().unwrap().click();
    settle(&mut harness);
    let left: Vec<&str> = harness.state().document().colliders().iter().map(|c| c.kind()).collect();
    assert_eq!(left, ["plane"]);
    assert_eq!(harness.state().selected_collider(), None);
}
