//! The editor model driven by commands, as the GUI will: select → fix → drag → solve, undo,
//! and the scene round trip through `shapeup deform`'s code path.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use glam::DVec3;
use shapeup_app::document::{GroupRole, WEIGHT_RANGE};
use shapeup_app::{Command, Document, EditorError, SelectMode, ShapeModel};
use shapeup_core::io::read_mesh;
use shapeup_core::scene::{Scene, SceneFormat};
use std::path::Path;

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

fn spot(model: ShapeModel) -> Document {
    Document::open(Path::new(SPOT), model).unwrap()
}

/// Vertices with the largest and the smallest y: a "head" and a "foot" to hold.
fn extremes(doc: &Document, count: usize) -> (Vec<u32>, Vec<u32>) {
    let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
    order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
    (order[order.len() - count..].to_vec(), order[..count].to_vec())
}

/// Fixes `vertices` as a new handle and returns its key.
fn fix(doc: &mut Document, vertices: &[u32]) -> shapeup_app::GroupKey {
    doc.apply(Command::Select { vertices: vertices.to_vec(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    doc.handles().last().unwrap().key
}

#[test]
fn saved_scene_reproduces_the_editor_solve() {
    let mut doc = spot(ShapeModel::StrainBending);
    let (top, bottom) = extremes(&doc, 5);
    let head = fix(&mut doc, &top);
    fix(&mut doc, &bottom);
    doc.apply(Command::MoveHandle { handle: head, delta: DVec3::new(0.1, 0.15, -0.05) }).unwrap();
    doc.apply(Command::RotateHandle { handle: head, axis: DVec3::Z, angle: 0.3 }).unwrap();
    let smooth: Vec<u32> = (0..200).collect();
    doc.apply(Command::Select { vertices: smooth, mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::AddSmoothing).unwrap();
    const N: usize = 15;
    doc.solve(N).unwrap();
    assert!(doc.positions().iter().zip(doc.rest_positions()).any(|(p, r)| (*p - *r).length() > 1e-3));

    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("edit.toml");
    doc.save_scene(&scene_path, SPOT).unwrap();

    // What `shapeup deform --iterations N` does.
    let scene = Scene::from_file(&scene_path).unwrap();
    let mut loaded = scene.load().unwrap();
    let (q, _) = loaded.solve_static(Some(N)).unwrap();
    let deformed = loaded.mesh_at(&q);
    let worst = deformed.positions.iter().zip(doc.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(worst < 1e-9, "max difference {worst}");

    // The written text parses back to the scene the document produced.
    let text = std::fs::read_to_string(&scene_path).unwrap();
    let reparsed = Scene::parse(&text, SceneFormat::Toml, Path::new(""), Default::default()).unwrap();
    assert_eq!(reparsed, doc.to_scene(SPOT));

    // And a document opened on the scene has the same groups.
    let reopened = Document::from_scene(&scene).unwrap();
    assert_eq!(reopened.shape_model(), Some(ShapeModel::StrainBending));
    let summary = |d: &Document| {
        d.groups()
            .iter()
            .map(|g| (g.name.clone(), g.role, g.weight, g.vertices.clone(), g.targets.clone()))
            .collect::<Vec<_>>()
    };
    assert_eq!(summary(&reopened), summary(&doc));
}

#[test]
fn fix_selection_makes_one_handle_at_the_current_positions() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let key = fix(&mut doc, &[7, 3, 11]);
    let handles: Vec<_> = doc.handles().collect();
    assert_eq!(handles.len(), 1);
    let handle = handles[0];
    assert_eq!((handle.key, handle.role, handle.weight), (key, GroupRole::Handle, 1.0));
    assert_eq!(handle.vertices.as_deref(), Some(&[3, 7, 11][..]));
    let expected: Vec<DVec3> = [3, 7, 11].iter().map(|&v| doc.positions()[v]).collect();
    assert_eq!(handle.targets, expected);
    assert!(handle.covers(7) && !handle.covers(8));
    assert_eq!(doc.groups()[0].role, GroupRole::Shape);
    assert!(doc.groups()[0].covers(12345 % doc.num_vertices() as u32), "shape groups cover every vertex");
}

#[test]
fn undo_and_redo() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let before = doc.state().clone();
    let key = fix(&mut doc, &[1, 2]);
    doc.apply(Command::MoveHandle { handle: key, delta: DVec3::X }).unwrap();
    let moved = doc.state().clone();
    assert!(doc.undo());
    assert_eq!(doc.group(key).unwrap().targets[0], doc.rest_positions()[1]);
    assert!(doc.undo());
    assert_eq!(doc.state(), &before);
    assert!(!doc.can_undo() && !doc.undo());
    assert!(doc.redo() && doc.redo());
    assert_eq!(doc.state(), &moved);
    assert!(!doc.can_redo());
    // A new edit after an undo drops the redo history.
    doc.apply(Command::Undo).unwrap();
    doc.apply(Command::SetIterations(3)).unwrap();
    assert!(!doc.can_redo());
    // Solving follows the restored state (the system is rebuilt or retargeted as needed).
    doc.solve(3).unwrap();
}

#[test]
fn a_drag_is_one_undo_step() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let key = fix(&mut doc, &[5]);
    let (head, foot) = extremes(&doc, 3);
    fix(&mut doc, &foot);
    let _ = head;
    let before = doc.state().clone();
    doc.begin_drag();
    for _ in 0..10 {
        doc.apply(Command::MoveHandle { handle: key, delta: DVec3::new(0.01, 0.0, 0.0) }).unwrap();
        doc.solve(2).unwrap();
    }
    doc.end_drag();
    let target = doc.group(key).unwrap().targets[0];
    assert!((target - doc.rest_positions()[5] - DVec3::new(0.1, 0.0, 0.0)).length() < 1e-12);
    assert!(doc.undo());
    assert_eq!(doc.state(), &before, "one undo step undoes the whole drag");
    assert!(doc.undo(), "the fixes before it are separate steps");
}

#[test]
fn switching_the_model_keeps_handles() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let (top, bottom) = extremes(&doc, 4);
    let a = fix(&mut doc, &top);
    let b = fix(&mut doc, &bottom);
    doc.apply(Command::MoveHandle { handle: a, delta: DVec3::Y * 0.1 }).unwrap();
    let handles_before: Vec<_> = doc.handles().cloned().collect();
    for model in ShapeModel::ALL {
        doc.apply(Command::SetShapeModel(model)).unwrap();
        assert_eq!(doc.shape_model(), Some(model));
        let kinds: Vec<&str> =
            doc.groups().iter().filter(|g| g.role == GroupRole::Shape).map(|g| g.kind.as_str()).collect();
        let expected: Vec<&str> = model.groups().iter().map(|(k, _)| *k).collect();
        assert_eq!(kinds, expected);
        for (g, (_, w)) in doc.groups().iter().zip(model.groups()) {
            assert_eq!(g.weight, *w, "default weight of {}", g.kind);
        }
        assert_eq!(doc.handles().cloned().collect::<Vec<_>>(), handles_before);
        doc.solve(3).unwrap();
    }
    assert!(doc.group(b).is_some());
    // Shape groups are replaced, not removed.
    let shape = doc.groups()[0].key;
    assert_eq!(doc.apply(Command::RemoveGroup(shape)).unwrap_err(), EditorError::ShapeGroup(shape));
}

#[test]
fn weights_are_clamped_and_nan_rejected() {
    let mut doc = spot(ShapeModel::IsoOneRing);
    let key = fix(&mut doc, &[0, 1]);
    for (given, expected) in
        [(1e9, WEIGHT_RANGE.1), (0.0, WEIGHT_RANGE.0), (-5.0, WEIGHT_RANGE.0), (3.5, 3.5), (f64::INFINITY, 1e4)]
    {
        doc.apply(Command::SetWeight { group: key, weight: given }).unwrap();
        assert_eq!(doc.group(key).unwrap().weight, expected);
    }
    let steps = doc.state().clone();
    let error = doc.apply(Command::SetWeight { group: key, weight: f64::NAN }).unwrap_err();
    assert!(matches!(error, EditorError::BadWeight(w) if w.is_nan()), "{error}");
    assert_eq!(doc.state(), &steps, "a failed command changes nothing");
    let gone = shapeup_app::GroupKey(9999);
    assert_eq!(
        doc.apply(Command::SetWeight { group: gone, weight: 1.0 }).unwrap_err(),
        EditorError::UnknownGroup(gone)
    );
}

#[test]
fn reset_make_rest_and_group_removal() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let (top, bottom) = extremes(&doc, 4);
    let a = fix(&mut doc, &top);
    let b = fix(&mut doc, &bottom);
    doc.apply(Command::MoveHandle { handle: a, delta: DVec3::Y * 0.2 }).unwrap();
    doc.solve(10).unwrap();
    let deformed = doc.positions().to_vec();
    let epoch = doc.epoch();

    doc.apply(Command::MakeRest).unwrap();
    assert_eq!(doc.rest_positions(), &deformed[..]);
    assert!(doc.epoch() > epoch);
    // At rest on the new shape with the handles where they were, a solve barely moves.
    doc.apply(Command::ResetShape).unwrap();
    assert_eq!(doc.positions(), &deformed[..]);
    assert!(doc.undo(), "make rest is undoable");
    assert_ne!(doc.rest_positions(), &deformed[..]);
    doc.apply(Command::ResetShape).unwrap();
    assert_eq!(doc.positions(), doc.rest_positions());

    // Smoothing on the selection; removal of groups.
    doc.apply(Command::Select { vertices: (0..300).collect(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::AddSmoothing).unwrap();
    let smoothing = doc.groups().last().unwrap().key;
    assert_eq!(doc.group(smoothing).unwrap().role, GroupRole::Smoothing);
    assert_eq!(doc.apply(Command::DeleteHandle(smoothing)).unwrap_err(), EditorError::NotAHandle(smoothing));
    doc.apply(Command::RemoveGroup(smoothing)).unwrap();
    doc.apply(Command::RenameHandle { handle: b, name: "feet".into() }).unwrap();
    assert_eq!(doc.group(b).unwrap().name, "feet");
    doc.apply(Command::DeleteHandle(a)).unwrap();
    assert_eq!(doc.handles().count(), 1);
    doc.apply(Command::ClearHandles).unwrap();
    assert_eq!(doc.handles().count(), 0);
    assert_eq!(doc.solve(5).unwrap_err(), EditorError::NoHandles);
    assert_eq!(doc.apply(Command::SetIterations(0)).unwrap_err().to_string(), "iterations must be at least 1");
}

#[test]
fn scene_groups_become_editor_groups() {
    let text = format!(
        r#"
        [mesh]
        path = "{SPOT}"
        [[constraints]]
        type = "edge_spring"
        name = "springs"
        weight = 5.0
        [[constraints]]
        type = "position"
        name = "top"
        box = {{ min = [-10, 0.6, -10], max = [10, 10, 10] }}
        translate = [0.0, 0.1, 0.0]
        [[constraints]]
        type = "floor"
        height = -0.5
        "#
    );
    let scene = Scene::parse(&text, SceneFormat::Toml, Path::new("s.toml"), Default::default()).unwrap();
    let mut doc = Document::from_scene(&scene).unwrap();
    assert_eq!(doc.shape_model(), Some(ShapeModel::EdgeSprings));
    let roles: Vec<GroupRole> = doc.groups().iter().map(|g| g.role).collect();
    assert_eq!(roles, [GroupRole::Shape, GroupRole::Handle, GroupRole::Other]);
    assert_eq!(doc.groups()[0].weight, 5.0);
    let top = &doc.groups()[1];
    let mesh = read_mesh(Path::new(SPOT)).unwrap().mesh;
    for (&v, t) in top.vertices.as_ref().unwrap().iter().zip(&top.targets) {
        assert!(mesh.positions[v as usize].y >= 0.6);
        assert_eq!(*t, mesh.positions[v as usize] + DVec3::new(0.0, 0.1, 0.0));
    }
    doc.solve(5).unwrap();
    // The floor keeps its option when saved.
    let saved = doc.to_scene(SPOT);
    assert_eq!(saved.groups[2].options.get("height").and_then(|h| h.as_f64()), Some(-0.5));
}

#[test]
fn export_keeps_every_vertex_the_polygons_and_the_texture_coordinates() {
    // A 4 × 4 grid of textured quads with unused vertices first, in the middle and last.
    let dir = tempfile::tempdir().unwrap();
    let n = 5;
    let mut text = String::from("# textured grid\nmtllib grid.mtl\nv 9 9 9\n");
    let mut index = vec![0usize; n * n];
    let mut v = 1;
    for j in 0..n {
        for i in 0..n {
            if j == 2 && i == 0 {
                text.push_str("v -5 -5 -5\n");
                v += 1;
            }
            index[j * n + i] = v;
            text.push_str(&format!(
                "v {} {} 0\nvt {} {}\n",
                i as f64 / 4.0,
                j as f64 / 4.0,
                i as f64 / 4.0,
                j as f64 / 4.0
            ));
            v += 1;
        }
    }
    text.push_str("v 7 7 7\nusemtl paper\n");
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let c = [j * n + i, j * n + i + 1, (j + 1) * n + i + 1, (j + 1) * n + i];
            let corner = |k: usize| format!("{}/{}", index[c[k]] + 1, c[k] + 1);
            text.push_str(&format!("f {} {} {} {}\n", corner(0), corner(1), corner(2), corner(3)));
        }
    }
    let input = dir.path().join("grid.obj");
    std::fs::write(&input, &text).unwrap();

    let mut doc = Document::open(&input, ShapeModel::EdgeSprings).unwrap();
    let left: Vec<u32> = (0..n).map(|j| index[j * n] as u32).collect();
    let right: Vec<u32> = (0..n).map(|j| index[j * n + n - 1] as u32).collect();
    fix(&mut doc, &left);
    let pulled = fix(&mut doc, &right);
    doc.apply(Command::MoveHandle { handle: pulled, delta: DVec3::new(0.0, 0.0, 0.5) }).unwrap();
    doc.solve(50).unwrap();

    // What the editor's Export… does.
    let output = dir.path().join("moved.obj");
    shapeup_core::io::write_mesh(&output, &doc.current_mesh()).unwrap();
    let written = std::fs::read_to_string(&output).unwrap();
    let (a, b): (Vec<&str>, Vec<&str>) = (text.lines().collect(), written.lines().collect());
    assert_eq!(a.len(), b.len(), "line for line");
    let mut moved = 0;
    for (x, y) in a.iter().zip(&b) {
        if x.starts_with("v ") {
            moved += usize::from(x != y);
        } else {
            assert_eq!(x, y, "only v lines change");
        }
    }
    assert!(moved >= n, "the pulled side moved ({moved} v lines changed)");
    let back = read_mesh(&output).unwrap().mesh;
    assert_eq!(back.num_vertices(), doc.num_vertices());
    for unused in [0, index[2 * n] - 1, v] {
        assert_eq!(back.positions[unused], doc.rest_positions()[unused], "unused vertex {unused} stays put");
    }
    assert_eq!(back.polygons, doc.rest_mesh().polygons, "quads stay quads");
}
