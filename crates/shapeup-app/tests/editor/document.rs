//! The editor model driven by commands, as the GUI will: select → fix → drag → solve, undo,
//! and the scene round trip through `shapeup deform`'s code path.

use crate::max_distance;
use glam::DVec3;
use shapeup_app::document::{GroupRole, WEIGHT_RANGE};
use shapeup_app::{Command, Document, EditorError, SelectMode, ShapeModel};
use shapeup_core::io::{Attributes, read_mesh};
use shapeup_core::scene::{Scene, SceneFormat};
use shapeup_core::solver::Acceleration;
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

/// What `shapeup deform SCENE` computes: the saved scene replayed from the rest shape.
/// The saved scene solved as `shapeup deform` does it: the shape and its final energy.
fn replay(scene_path: &Path) -> (Vec<DVec3>, f64) {
    let scene = Scene::from_file(scene_path).unwrap();
    let mut loaded = scene.load().unwrap();
    let (q, report) = loaded.solve_static(None).unwrap();
    (loaded.mesh_at(&q).positions, report.energies.last().copied().unwrap_or(report.initial_energy))
}

fn diagonal(doc: &Document) -> f64 {
    let (lo, hi) = doc.rest_mesh().bounding_box();
    (hi - lo).length()
}

/// A flat (n+1)×(n+1) grid in the XY plane, offset by `origin` (z up to `bump` so that bending
/// has something to keep).
fn grid(n: u32, origin: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            let (u, v) = (f64::from(x) / f64::from(n), f64::from(y) / f64::from(n));
            positions.push(origin + DVec3::new(u, v, 0.1 * (3.0 * u).sin() * (2.0 * v).cos()));
        }
    }
    let mut triangles = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let v = y * (n + 1) + x;
            triangles.push([v, v + 1, v + n + 2]);
            triangles.push([v, v + n + 2, v + n + 1]);
        }
    }
    (positions, triangles)
}

/// Scripted editing sessions (drags of several moves, a rotation, smoothing, weights, Make rest
/// shape) converge in the editor's model; the saved scene replayed as `shapeup deform` does it
/// gives the editor's converged shape to 1e-6 of the bounding-box diagonal.
#[test]
fn saved_scenes_replay_what_the_editor_converged_to() {
    let dir = tempfile::tempdir().unwrap();
    let (positions, triangles) = grid(10, DVec3::ZERO);
    let mesh_path = dir.path().join("sheet.obj");
    let mesh = shapeup_core::mesh::Mesh::new(positions, triangles).unwrap();
    shapeup_core::io::write_mesh(&mesh_path, &mesh, &Attributes::None).unwrap();

    for (session, model) in
        [ShapeModel::StrainBending, ShapeModel::EdgeSprings, ShapeModel::IsoOneRing].into_iter().enumerate()
    {
        let mut doc = Document::open(&mesh_path, model).unwrap();
        doc.apply(Command::SetTolerance(1e-13)).unwrap();
        assert_eq!(doc.acceleration(), Acceleration::Lbfgs, "on by default");
        if session == 1 {
            // The plain iteration, saved and replayed as such (and undoable).
            doc.apply(Command::SetAcceleration(Acceleration::None)).unwrap();
            doc.apply(Command::Undo).unwrap();
            assert_eq!(doc.acceleration(), Acceleration::Lbfgs);
            doc.apply(Command::Redo).unwrap();
            assert_eq!(doc.acceleration(), Acceleration::None);
        }
        if session == 2 {
            // Anderson acceleration, saved and replayed as such.
            doc.apply(Command::SetAcceleration(Acceleration::Anderson)).unwrap();
        }
        if session == 2 {
            // Anderson acceleration, saved and replayed as such.
            doc.apply(Command::SetAcceleration(Acceleration::Anderson)).unwrap();
        }
        let left: Vec<u32> = (0..11).map(|y| y * 11).collect();
        let right: Vec<u32> = (0..11).map(|y| y * 11 + 10).collect();
        fix(&mut doc, &left);
        let pulled = fix(&mut doc, &right);
        // A drag: many small moves, each followed by a partial solve as the worker would do.
        doc.begin_drag();
        for k in 0..12u32 {
            let delta = DVec3::new(0.01, 0.004 * f64::from(k % 3), 0.02);
            doc.apply(Command::MoveHandle { handle: pulled, delta }).unwrap();
            doc.solve(1 + k as usize % 4).unwrap();
        }
        doc.end_drag();
        doc.apply(Command::RotateHandle { handle: pulled, axis: DVec3::X, angle: 0.2 }).unwrap();
        if session == 0 {
            doc.apply(Command::Select { vertices: (40..80).collect(), mode: SelectMode::Replace }).unwrap();
            doc.apply(Command::AddSmoothing).unwrap();
            let smoothing = doc.groups().last().unwrap().key;
            doc.apply(Command::SetWeight { group: smoothing, weight: 0.05 }).unwrap();
        }
        let converged = doc.converge().unwrap();
        let editor_energy = *converged.energies.last().unwrap();

        let scene_path = dir.path().join(format!("session-{session}.toml"));
        let saved = doc.save_scene_with_mesh(&scene_path).unwrap();
        assert_eq!(saved.rest_mesh, None, "the rest shape is the opened mesh");
        let text = std::fs::read_to_string(&scene_path).unwrap();
        let expected = ["acceleration = \"lbfgs\"", "acceleration = \"none\"", "acceleration = \"anderson\""][session];
        assert!(text.contains(expected), "{text}");
        let d = diagonal(&doc);
        let (replayed, replay_energy) = replay(&scene_path);
        let worst = max_distance(&replayed, doc.positions());
        // Strain + bending on a nearly flat sheet has nearby local minima (bending's energy has
        // a kink where the mean curvature vanishes): the replay starts from the shape on screen
        // (`[mesh] start`), so it stays in the editor's.
        assert!(saved.start_mesh.is_some(), "the shape on screen is saved as the start");
        assert!(
            replay_energy <= editor_energy * (1.0 + 1e-9),
            "session {session}: E {replay_energy} vs {editor_energy}"
        );
        assert!(worst < 1e-6 * d, "session {session}: replay differs by {:.3e} of the diagonal", worst / d);

        // Make rest shape, drag again: the saved scene carries the new rest mesh.
        doc.apply(Command::MakeRest).unwrap();
        doc.apply(Command::MoveHandle { handle: pulled, delta: DVec3::new(0.0, 0.1, -0.05) }).unwrap();
        let after = doc.converge().unwrap();
        let scene_path = dir.path().join(format!("rest-{session}.toml"));
        let saved = doc.save_scene_with_mesh(&scene_path).unwrap();
        let rest_file = saved.rest_mesh.expect("the new rest mesh is written beside the scene");
        assert_eq!(rest_file, dir.path().join(format!("rest-{session}.rest.obj")));
        assert_eq!(read_mesh(&rest_file).unwrap().mesh.positions, doc.rest_positions());
        let start = read_mesh(&saved.start_mesh.clone().unwrap()).unwrap().mesh.positions;
        assert_eq!(start, doc.positions(), "the start shape is the shape on screen, bit for bit");
        let (replayed, replay_energy) = replay(&scene_path);
        let worst = max_distance(&replayed, doc.positions());
        if after.energies.len() < doc.iterations() {
            assert!(worst < 1e-6 * d, "session {session} after Make rest: replay differs by {:.3e}", worst / d);
        } else {
            // Plain iterations stopped at the cap, still converging: the replay goes on from
            // there (as the editor says when such a shape is saved), never to a higher energy.
            assert!(replay_energy <= *after.energies.last().unwrap(), "session {session}: E rose in the replay");
        }
        assert!(!doc.is_modified(), "saving clears the modified flag");
    }
}

#[test]
fn convergence_stops_at_the_tolerance_or_the_cap() {
    // A sheet held on one side and pulled on the other (plain local-global iterations converge
    // slowly on large meshes: see issue 10; a small one reaches 1e-6 well within the cap).
    let dir = tempfile::tempdir().unwrap();
    let (positions, triangles) = grid(10, DVec3::ZERO);
    let mesh_path = dir.path().join("sheet.obj");
    shapeup_core::io::write_mesh(
        &mesh_path,
        &shapeup_core::mesh::Mesh::new(positions, triangles).unwrap(),
        &Attributes::None,
    )
    .unwrap();
    let mut doc = Document::open(&mesh_path, ShapeModel::EdgeSprings).unwrap();
    assert_eq!(doc.tolerance(), shapeup_app::document::DEFAULT_TOLERANCE);
    let left: Vec<u32> = (0..11).map(|y| y * 11).collect();
    let right: Vec<u32> = (0..11).map(|y| y * 11 + 10).collect();
    fix(&mut doc, &left);
    let head = fix(&mut doc, &right);
    for (k, acceleration) in [Acceleration::None, Acceleration::Anderson, Acceleration::Lbfgs].into_iter().enumerate() {
        doc.apply(Command::SetAcceleration(acceleration)).unwrap();
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        doc.apply(Command::MoveHandle { handle: head, delta: DVec3::new(0.1, 0.1, 0.2) * sign }).unwrap();
        let report = doc.converge().unwrap();
        let e = &report.energies;
        let n = e.len();
        assert!(n >= 2 && n < doc.iterations(), "{acceleration:?}: {n} iterations");
        let last_change = (e[n - 2] - e[n - 1]).abs() / e[n - 2];
        assert!(last_change <= 1e-6, "{acceleration:?}: stopped at a relative change of {last_change:e}");
        // Plain: the one before was still above it, so it did not stop early. (Accelerated,
        // a mixed step below the tolerance is confirmed by one plain iteration first.)
        if n >= 3 && acceleration == Acceleration::None {
            assert!((e[n - 3] - e[n - 2]).abs() / e[n - 3] > 1e-6);
        }
    }
    // Both handles moved alike: the sheet moves rigidly, E is round-off (about 1e-30) and
    // converges at once although its relative change stays large.
    let mut sheet = Document::open(&mesh_path, ShapeModel::StrainBending).unwrap();
    fix(&mut sheet, &left);
    fix(&mut sheet, &right);
    let handles: Vec<_> = sheet.handles().map(|h| h.key).collect();
    for handle in handles {
        sheet.apply(Command::MoveHandle { handle, delta: DVec3::new(0.3, -0.2, 0.1) }).unwrap();
    }
    let rigid = sheet.converge().unwrap();
    assert!(
        rigid.energies.len() <= 3,
        "{} iterations for a rigid motion: {:?}",
        rigid.energies.len(),
        &rigid.energies[..3]
    );
    // The cap.
    doc.apply(Command::SetIterations(3)).unwrap();
    doc.apply(Command::MoveHandle { handle: head, delta: DVec3::new(0.0, 0.1, 0.0) }).unwrap();
    assert_eq!(doc.converge().unwrap().energies.len(), 3);
    assert!(doc.apply(Command::SetTolerance(0.0)).is_err());
    assert!(doc.apply(Command::SetTolerance(f64::NAN)).is_err());
}

#[test]
fn fix_selection_makes_one_handle_at_the_current_positions() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let key = fix(&mut doc, &[7, 3, 11]);
    let handles: Vec<_> = doc.handles().collect();
    assert_eq!(handles.len(), 1);
    let handle = handles[0];
    assert_eq!((handle.key, handle.role, handle.spec.weight), (key, GroupRole::Handle, 1.0));
    assert_eq!(handle.vertices(), Some(&[3, 7, 11][..]));
    let expected: Vec<DVec3> = [3, 7, 11].iter().map(|&v| doc.positions()[v]).collect();
    assert_eq!(handle.targets(), expected);
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
    assert_eq!(doc.group(key).unwrap().targets()[0], doc.rest_positions()[1]);
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
    let target = doc.group(key).unwrap().targets()[0];
    assert!((target - doc.rest_positions()[5] - DVec3::new(0.1, 0.0, 0.0)).length() < 1e-12);
    assert!(doc.undo());
    assert_eq!(doc.state(), &before, "one undo step undoes the whole drag");
    assert!(doc.undo(), "the fixes before it are separate steps");
}

#[test]
fn undo_during_a_drag_does_nothing_and_the_drag_stays_one_step() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let key = fix(&mut doc, &[5]);
    let before = doc.state().clone();
    let step = Command::MoveHandle { handle: key, delta: DVec3::new(0.01, 0.0, 0.0) };
    doc.begin_drag();
    doc.apply(step.clone()).unwrap();
    // ctrl+z (and ctrl+shift+z) with the button still held: ignored, the drag goes on.
    assert!(!doc.apply(Command::Undo).unwrap());
    assert!(!doc.apply(Command::Redo).unwrap());
    assert!(!doc.undo());
    assert!(doc.is_dragging());
    for _ in 0..6 {
        doc.apply(step.clone()).unwrap();
    }
    doc.end_drag();
    let target = doc.group(key).unwrap().targets()[0];
    assert!((target - doc.rest_positions()[5] - DVec3::new(0.07, 0.0, 0.0)).length() < 1e-12);
    assert!(doc.undo());
    assert_eq!(doc.state(), &before, "one undo undoes the whole drag, the moves after ctrl+z too");
}

#[test]
fn apply_says_whether_there_is_something_new_to_solve() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    assert!(!doc.apply(Command::Undo).unwrap(), "nothing to undo");
    assert!(!doc.apply(Command::Redo).unwrap(), "nothing to redo");
    assert!(!doc.apply(Command::ResetShape).unwrap(), "already at rest");
    assert!(!doc.apply(Command::Select { vertices: vec![1, 2], mode: SelectMode::Replace }).unwrap());
    let key = fix(&mut doc, &[5]);
    let weight = doc.group(key).unwrap().spec.weight;
    assert!(!doc.apply(Command::SetWeight { group: key, weight }).unwrap(), "the same weight");
    assert!(doc.apply(Command::SetWeight { group: key, weight: weight * 2.0 }).unwrap());
    assert!(doc.apply(Command::MoveHandle { handle: key, delta: DVec3::X * 0.1 }).unwrap());
    assert!(doc.apply(Command::Undo).unwrap());
    assert!(doc.apply(Command::Redo).unwrap());
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
            doc.groups().iter().filter(|g| g.role == GroupRole::Shape).map(|g| g.spec.kind.as_str()).collect();
        let expected: Vec<&str> = model.groups().iter().map(|(k, _)| *k).collect();
        assert_eq!(kinds, expected);
        for (g, (_, w)) in doc.groups().iter().zip(model.groups().iter()) {
            assert_eq!(g.spec.weight, *w, "default weight of {}", g.spec.kind);
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
        assert_eq!(doc.group(key).unwrap().spec.weight, expected);
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
    assert_eq!(doc.group(b).unwrap().spec.name, "feet");
    // Names stay unique, so that the session saves as a scene that opens again.
    let taken = doc.apply(Command::RenameHandle { handle: a, name: "feet".into() }).unwrap_err();
    assert_eq!(taken, EditorError::NameTaken("feet".into()));
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
        hard = true
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
    assert_eq!(doc.groups()[0].spec.weight, 5.0);
    let top = doc.groups()[1].clone();
    let mesh = read_mesh(Path::new(SPOT)).unwrap().mesh;
    for (&v, t) in top.vertices().unwrap().iter().zip(&top.targets()) {
        assert!(mesh.positions[v].y >= 0.6);
        assert_eq!(*t, mesh.positions[v] + DVec3::new(0.0, 0.1, 0.0));
    }
    doc.solve(5).unwrap();
    // The hard handle holds its vertices exactly.
    for (&v, t) in top.vertices().unwrap().iter().zip(&top.targets()) {
        assert!((doc.positions()[v] - *t).length() < 1e-12);
    }
    // The floor keeps its option when saved, the handle its `hard`.
    let saved = doc.to_scene(SPOT);
    assert_eq!(saved.groups[2].options.get("height").and_then(|h| h.as_f64()), Some(-0.5));
    assert_eq!(saved.groups[1].options.get("hard").and_then(|h| h.as_bool()), Some(true));
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
    shapeup_core::io::write_mesh(&output, &doc.current_mesh(), doc.attributes()).unwrap();
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

/// Separate sheets, `grid(n, origin)` each, in one mesh, and the first vertex of each.
fn sheets(parts: &[(u32, DVec3)]) -> (shapeup_core::mesh::Mesh, Vec<u32>) {
    let (mut positions, mut triangles, mut offsets) = (Vec::new(), Vec::new(), Vec::new());
    for &(n, origin) in parts {
        let (p, t) = grid(n, origin);
        let offset = positions.len() as u32;
        offsets.push(offset);
        positions.extend(p);
        triangles.extend(t.iter().map(|t| t.map(|v| v + offset)));
    }
    (shapeup_core::mesh::Mesh::new(positions, triangles).unwrap(), offsets)
}

/// Two separate sheets: the free one is counted, makes the solve fail without changing the
/// shape, and "Pin free pieces" makes it solvable; a piece is selected from one vertex.
#[test]
fn pieces_without_handles() {
    let (mesh, offsets) = sheets(&[(4, DVec3::ZERO), (4, DVec3::new(2.0, 0.0, 0.0)), (2, DVec3::new(0.0, 2.0, 0.0))]);
    let (offset, offset3) = (offsets[1], offsets[2]);
    let mut doc = Document::new(mesh, ShapeModel::StrainBending).unwrap();
    assert_eq!(doc.pieces().count, 3);
    assert_eq!(doc.num_free_pieces(), 3);

    // Select the second sheet from one of its vertices.
    doc.apply(Command::SelectPiece { vertex: offset + 7, mode: SelectMode::Replace }).unwrap();
    assert_eq!(doc.selected_vertices(), (offset..offset3).collect::<Vec<_>>());
    doc.apply(Command::SelectPiece { vertex: 99_999, mode: SelectMode::Add }).unwrap();
    assert_eq!(doc.num_selected(), (offset3 - offset) as usize);

    // A handle on the first sheet only: two pieces are free and the system is singular.
    let handle = fix(&mut doc, &[0, 1, 2]);
    assert_eq!(doc.num_selected(), 0, "fixed vertices leave the selection");
    assert_eq!(doc.num_free_pieces(), 2);
    doc.apply(Command::MoveHandle { handle, delta: DVec3::Z * 0.3 }).unwrap();
    let before = doc.positions().to_vec();
    let error = doc.converge().unwrap_err();
    assert!(matches!(error, EditorError::Solve(_)), "{error}");
    assert_eq!(doc.positions(), &before[..], "a failed solve leaves the last good shape");

    doc.apply(Command::PinFreePieces).unwrap();
    assert_eq!(doc.num_free_pieces(), 0);
    let pins = doc.handles().last().unwrap().clone();
    assert_eq!(pins.spec.name, "free pieces");
    assert_eq!(pins.spec.weight, shapeup_app::document::FREE_PIECE_WEIGHT);
    assert_eq!(pins.vertices().unwrap(), (offset as usize..doc.num_vertices()).collect::<Vec<_>>());
    assert_eq!(doc.handles().count(), 2, "one group for every free piece");
    doc.converge().unwrap();
    // The pinned sheets stay at rest (nothing pulls them); the held sheet followed its handle.
    for v in offset..doc.num_vertices() as u32 {
        assert!((doc.positions()[v as usize] - doc.rest_positions()[v as usize]).length() < 1e-9);
    }
    assert!((doc.positions()[0].z - 0.3).abs() < 1e-3);
    // Nothing left to pin: a no-op, no undo step.
    let undo_before = doc.can_undo();
    doc.apply(Command::PinFreePieces).unwrap();
    assert_eq!(doc.handles().count(), 2);
    assert_eq!(doc.can_undo(), undo_before);
}

/// Pieces far apart are not attached when opened; Attach free pieces attaches every free
/// one to the held piece, however far, and then the system solves; nothing left free is an
/// error that changes nothing.
#[test]
fn attach_free_pieces_attaches_every_free_piece_to_the_held_ones() {
    let (mesh, offsets) = sheets(&[(4, DVec3::ZERO), (4, DVec3::new(2.0, 0.0, 0.0))]);
    let offset = offsets[1];
    let mut doc = Document::new(mesh, ShapeModel::IsoOneRing).unwrap();
    assert_eq!((doc.num_attached_pieces(), doc.num_free_pieces()), (0, 2), "1 apart: not attached when opened");
    let handle = fix(&mut doc, &[0, 1, 2, 5]);
    doc.apply(Command::AttachFreePieces).unwrap();
    assert_eq!((doc.num_attached_pieces(), doc.num_free_pieces()), (1, 0));
    doc.apply(Command::MoveHandle { handle, delta: DVec3::Z * 0.2 }).unwrap();
    doc.converge().unwrap();
    let moved = (doc.positions()[offset as usize] - doc.rest_positions()[offset as usize]).length();
    assert!(moved > 0.05, "the attached sheet went with the held one ({moved})");
    let groups = doc.groups().len();
    let error = doc.apply(Command::AttachFreePieces).unwrap_err();
    assert!(error.to_string().contains("no free piece"), "{error}");
    assert_eq!(doc.groups().len(), groups);
}

/// Undo brings back the shape that was on screen: after a drag (one step however many
/// moves), Reset shape, Make rest shape and a dynamics run (a checkpoint).
#[test]
fn undo_steps_restore_what_was_seen() {
    let mut doc = spot(ShapeModel::EdgeSprings);
    let (top, bottom) = extremes(&doc, 4);
    let head = fix(&mut doc, &top);
    fix(&mut doc, &bottom);
    doc.converge().unwrap();
    let at_rest = doc.positions().to_vec();

    doc.begin_drag();
    for _ in 0..10 {
        doc.apply(Command::MoveHandle { handle: head, delta: DVec3::Y * 0.01 }).unwrap();
        doc.solve(2).unwrap();
    }
    doc.end_drag();
    doc.converge().unwrap();
    let dragged = doc.positions().to_vec();
    assert!(max_distance(&dragged, &at_rest) > 0.05);

    // Reset shape is one undoable step.
    doc.apply(Command::ResetShape).unwrap();
    assert_eq!(doc.positions(), doc.rest_positions());
    assert!(doc.undo());
    assert_eq!(doc.positions(), &dragged[..], "undo of Reset shape brings the shape back");

    // Make rest shape: undo restores the rest and the shape.
    let rest = doc.rest_positions().to_vec();
    doc.apply(Command::MakeRest).unwrap();
    assert_eq!(doc.rest_positions(), &dragged[..]);
    assert!(doc.undo());
    assert_eq!(doc.rest_positions(), &rest[..]);
    assert_eq!(doc.positions(), &dragged[..]);
    assert!(doc.redo());
    assert_eq!(doc.rest_positions(), &dragged[..]);
    assert!(doc.undo());

    // A dynamics run: a checkpoint, then the simulation moves the shape.
    doc.checkpoint();
    let mut fallen = dragged.clone();
    fallen.iter_mut().for_each(|p| p.y -= 0.2);
    assert!(doc.accept_positions(doc.epoch(), &fallen));
    assert!(doc.undo());
    assert_eq!(doc.positions(), &dragged[..], "undo of a dynamics run");
    assert!(doc.redo());
    assert_eq!(doc.positions(), &fallen[..], "redo of a dynamics run");

    // The whole drag is one step: undo it (after undoing the checkpoint) and the handle is
    // back where it started.
    assert!(doc.undo());
    let targets = doc.group(head).unwrap().targets();
    assert!(doc.undo());
    let back = doc.group(head).unwrap().targets();
    assert!((targets[0].y - back[0].y - 0.1).abs() < 1e-12, "one step undid all ten moves");
    assert_eq!(doc.positions(), &at_rest[..]);
}

/// The issue's sessions on a real mesh: Spot with each shape model, its lowest vertices and its
/// head fixed, the head dragged a modest way in steps with partial solves (as the worker does),
/// converged, saved, replayed by the library from the saved start shape.
#[test]
fn a_saved_scene_replays_the_converged_shape_of_each_shape_model() {
    const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
    const COW: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/cow.obj");
    let dir = tempfile::tempdir().unwrap();
    // Spot with each model, and the issue's cow with edge springs (its belly folded the other
    // way in a replay from rest, 5 % of the diagonal off).
    let runs = ShapeModel::ALL.map(|m| (SPOT, m)).into_iter().chain([(COW, ShapeModel::EdgeSprings)]);
    for (mesh, model) in runs {
        let mut doc = Document::open(Path::new(mesh), model).unwrap();
        let mut order: Vec<u32> = (0..doc.num_vertices() as u32).collect();
        order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
        fix(&mut doc, &order[..40]);
        let head = fix(&mut doc, &order[order.len() - 40..]);
        doc.begin_drag();
        for k in 0..8 {
            doc.apply(Command::MoveHandle { handle: head, delta: DVec3::new(0.02, -0.03, 0.01) }).unwrap();
            doc.solve(1 + k % 3).unwrap();
        }
        doc.end_drag();
        let converged = doc.converge().unwrap();
        assert!(converged.energies.len() < doc.iterations(), "{model:?} converged within the cap");
        let name = Path::new(mesh).file_stem().unwrap().to_string_lossy();
        let scene_path = dir.path().join(format!("{name}-{model:?}.toml"));
        doc.save_scene_with_mesh(&scene_path).unwrap();
        let (replayed, replay_energy) = replay(&scene_path);
        let d = diagonal(&doc);
        let worst = max_distance(&replayed, doc.positions()) / d;
        let energy = *converged.energies.last().unwrap();
        // The saved shape meets the tolerance, so the replay keeps it: measured 9e-17 of the
        // diagonal (the working frame's round trip) for every model. Before the replay kept a
        // converged start, its restarted L-BFGS went one step on: springs 5e-8, strain +
        // bending 1.8e-6, one-rings 2.3e-6; from rest these replays landed in other minima, up
        // to 5 % of the diagonal away.
        assert!(worst < 1e-6, "{model:?}: the replay is {worst:.3e} of the diagonal away");
        assert!(replay_energy <= energy * (1.0 + 1e-9), "{model:?}: E {replay_energy} vs {energy}");
        // Reopened, the editor starts from the saved shape.
        let reopened = Document::from_scene(&Scene::from_file(&scene_path).unwrap()).unwrap();
        assert_eq!(reopened.positions(), doc.positions());
    }
}

/// A scene that spells out a preset's options at their defaults is that preset: its model is
/// selected and its groups are the model's (no remove button); other values keep them apart.
#[test]
fn a_scene_spelling_out_a_presets_defaults_selects_that_preset() {
    const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
    let open = |prevent_flips: bool| {
        let text = format!(
            "[mesh]\npath = '{SPOT}'\n[[constraints]]\ntype = \"triangle_strain\"\n\
             [[constraints]]\ntype = \"bending\"\nprevent_flips = {prevent_flips}\n\
             [[constraints]]\ntype = \"position\"\nvertices = [0, 1, 2]\n"
        );
        let scene = Scene::parse(&text, SceneFormat::Toml, Path::new("p.toml"), std::path::PathBuf::new()).unwrap();
        Document::from_scene(&scene).unwrap()
    };
    let doc = open(false);
    assert_eq!(doc.shape_model(), Some(ShapeModel::StrainBending));
    assert!(doc.groups()[..2].iter().all(|g| g.role == GroupRole::Shape));
    let doc = open(true);
    assert_eq!(doc.shape_model(), None, "prevent_flips = true is not the preset");
    assert_eq!(doc.groups()[1].role, GroupRole::Other);
}

const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");

/// Per vertex of `piece`, how far it has moved away from the surface of the other pieces
/// (now versus at rest): 0 for a piece that follows the body, its whole drift for one left
/// behind.
fn drift_from_body(doc: &Document, piece: &[u32]) -> f64 {
    let body = |positions: &[DVec3]| {
        let triangles = doc.triangles().iter().filter(|t| !piece.contains(&t[0])).copied().collect::<Vec<[u32; 3]>>();
        shapeup_core::nearest::NearestTriangle::new(positions, triangles).unwrap()
    };
    let (rest, now) = (body(doc.rest_positions()), body(doc.positions()));
    piece
        .iter()
        .map(|&v| {
            let v = v as usize;
            (now.nearest(doc.positions()[v]).1 - rest.nearest(doc.rest_positions()[v]).1).abs()
        })
        .fold(0.0, f64::max)
}

/// The largest relative change of an edge length of `piece`.
fn stretch(doc: &Document, piece: &[u32]) -> f64 {
    let (q, x) = (doc.positions(), doc.rest_positions());
    doc.triangles()
        .iter()
        .filter(|t| piece.contains(&t[0]))
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| {
            let (a, b) = (a as usize, b as usize);
            ((q[a] - q[b]).length() / (x[a] - x[b]).length() - 1.0).abs()
        })
        .fold(0.0, f64::max)
}

/// The head's vertices around `piece` at rest: within twice its radius of its centroid.
fn around(doc: &Document, piece: &[u32], others: &[u32]) -> Vec<u32> {
    let x = doc.rest_positions();
    let centre = piece.iter().map(|&v| x[v as usize]).sum::<DVec3>() / piece.len() as f64;
    let radius = piece.iter().map(|&v| (x[v as usize] - centre).length()).fold(0.0, f64::max);
    others.iter().copied().filter(|&v| (x[v as usize] - centre).length() < 2.0 * radius).collect()
}

/// How far `piece` lags behind the vertices `around` it: the distance between their mean
/// displacements from rest, relative to the surroundings' (0: it went along, 1: it stayed).
fn lag(doc: &Document, piece: &[u32], around: &[u32]) -> f64 {
    let mean = |set: &[u32]| {
        set.iter().map(|&v| doc.positions()[v as usize] - doc.rest_positions()[v as usize]).sum::<DVec3>()
            / set.len() as f64
    };
    let (moved, went) = (mean(around), mean(piece));
    (went - moved).length() / moved.length()
}

/// Suzanne is a head and two eyes, separate pieces sitting in the eye sockets. Opened, the
/// eyes are attached to the head (one "attachment" group, nothing free but the head); posing
/// the head carries them along without tearing, where pinned eyes stay behind; the gizmo's
/// handle is not replaced; the saved scene replays the pose with the eyes in place.
#[test]
fn pieces_that_sit_on_the_body_follow_it() {
    let mut doc = Document::open(Path::new(SUZANNE), ShapeModel::EdgeSprings).unwrap();
    assert_eq!(doc.pieces().count, 3);
    assert_eq!(doc.num_attached_pieces(), 2, "both eyes attached when opened");
    assert_eq!(doc.num_free_pieces(), 1, "only the head needs a handle");
    let attached = doc.groups().iter().find(|g| g.spec.kind == "attachment").unwrap();
    assert_eq!((attached.spec.name.as_str(), attached.role), ("attached pieces", GroupRole::Other));
    let eyes: Vec<u32> = attached.vertices().unwrap().iter().map(|&v| v as u32).collect();
    let head: Vec<u32> = (0..doc.num_vertices() as u32).filter(|v| !eyes.contains(v)).collect();
    assert_eq!(head.len(), 441, "the eyes are every vertex but the head's (441 of 507)");
    assert!(head.iter().all(|&v| doc.pieces().of_vertex[v as usize] == doc.pieces().of_vertex[head[0] as usize]));
    let eye = |k: u32| -> Vec<u32> {
        let piece = doc.pieces().of_vertex[eyes[0] as usize];
        eyes.iter().copied().filter(|&v| (doc.pieces().of_vertex[v as usize] == piece) == (k == 0)).collect()
    };
    let (left, right) = (eye(0), eye(1));

    // Hold the chin, turn and lift the top of the head.
    let by_y = |count: usize, top: bool| {
        let mut order = head.clone();
        order.sort_by(|&a, &b| doc.positions()[a as usize].y.total_cmp(&doc.positions()[b as usize].y));
        if top { order[order.len() - count..].to_vec() } else { order[..count].to_vec() }
    };
    let (top, chin) = (by_y(12, true), by_y(12, false));
    fix(&mut doc, &chin);
    let crown = fix(&mut doc, &top);
    let size = diagonal(&doc);
    doc.apply(Command::MoveHandle { handle: crown, delta: DVec3::new(0.125, 0.05, 0.05) * size }).unwrap();
    doc.apply(Command::RotateHandle { handle: crown, axis: DVec3::Z, angle: 0.25 }).unwrap();
    assert_eq!(doc.num_free_pieces(), 0);
    doc.converge().unwrap();
    let moved = doc.positions().iter().zip(doc.rest_positions()).map(|(q, x)| (*q - *x).length());
    let eye_moved = left.iter().map(|&v| (doc.positions()[v as usize] - doc.rest_positions()[v as usize]).length());
    let (head_moved, eye_moved) = (moved.fold(0.0, f64::max), eye_moved.fold(0.0, f64::max));
    let (drift, strain) = (drift_from_body(&doc, &left).max(drift_from_body(&doc, &right)), stretch(&doc, &eyes));
    let socket = around(&doc, &left, &head);
    let socket_strain = doc
        .triangles()
        .iter()
        .filter(|t| t.iter().all(|v| socket.contains(v)))
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| {
            let (q, x) = (doc.positions(), doc.rest_positions());
            let (a, b) = (a as usize, b as usize);
            ((q[a] - q[b]).length() / (x[a] - x[b]).length() - 1.0).abs()
        })
        .fold(0.0, f64::max);
    // Measured: the head moves 0.27 of the diagonal, an eye 0.14; the eye's mean motion is
    // 9 % off its surroundings' (pinned: 100 %), it stays within 0.8 % of the diagonal of its
    // socket (pinned: 4.3 %), and its edges change by 25 % where the head's around it change
    // by 72 % (the default springs crumple Suzanne's head under this pose).
    let followed = lag(&doc, &left, &socket).max(lag(&doc, &right, &around(&doc, &right, &head)));
    assert!(followed < 0.2, "the eyes went with the head around them (lag {followed:.2})");
    assert!(head_moved > 0.2 * size);
    assert!(eye_moved > 0.05 * size, "the eyes went with the head ({:.3} of the diagonal)", eye_moved / size);
    assert!(drift < 0.02 * size, "the eyes stayed in their sockets: drift {:.2e} of the diagonal", drift / size);
    assert!(
        strain < 0.5 * socket_strain,
        "the eyes deform less than the head around them: {:.1} % (the head {:.1} %)",
        100.0 * strain,
        100.0 * socket_strain
    );

    let saved = doc.positions().to_vec();
    // Saved and replayed as `shapeup deform` does: the eyes are in the same place.
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("suzanne-posed.toml");
    doc.save_scene_with_mesh(&scene).unwrap();
    let text = std::fs::read_to_string(&scene).unwrap();
    assert!(text.contains("type = \"attachment\""), "{text}");
    let (replayed, _) = replay(&scene);
    let off = max_distance(&replayed, &saved);
    assert!(off < 1e-6 * size, "the replay is {:.2e} of the diagonal away", off / size);

    // The same pose with the eyes pinned at rest instead: they stay behind.
    let key = doc.groups().iter().find(|g| g.spec.kind == "attachment").unwrap().key;
    doc.apply(Command::RemoveGroup(key)).unwrap();
    assert_eq!(doc.num_free_pieces(), 2);
    doc.apply(Command::PinFreePieces).unwrap();
    doc.converge().unwrap();
    let (left_behind, stayed) = (drift_from_body(&doc, &left), lag(&doc, &left, &socket));
    assert!(
        stayed > 0.9 && left_behind > 3.0 * drift,
        "pinned eyes stay behind (lag {stayed:.2}, drift {left_behind:.3})"
    );
}

/// The cow with its hooves held and its head dragged by 0.11 of the diagonal, converged with
/// `model`: the 99th percentile and the largest change of a dihedral angle (degrees), the 99th
/// percentile edge stretch, and how far the handle is from its target (fraction of the drag).
fn cow_drag(model: ShapeModel) -> (f64, f64, f64, f64) {
    let mut doc = Document::open(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/cow.obj")), model).unwrap();
    let n = doc.num_vertices();
    let sorted = |axis: fn(DVec3) -> f64| {
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_by(|&a, &b| axis(doc.positions()[a as usize]).total_cmp(&axis(doc.positions()[b as usize])));
        order
    };
    let (by_y, by_x) = (sorted(|p| p.y), sorted(|p| p.x));
    fix(&mut doc, &by_y[..n / 20]);
    let head = fix(&mut doc, &by_x[n - n / 30..]);
    let drag = DVec3::new(0.0, 0.1, 0.05) * diagonal(&doc);
    doc.apply(Command::MoveHandle { handle: head, delta: drag }).unwrap();
    doc.converge().unwrap();
    let (q, x) = (doc.positions(), doc.rest_positions());
    let triangles = doc.triangles().to_vec();
    let normal = |p: &[DVec3], t: [u32; 3]| {
        let [a, b, c] = t.map(|v| p[v as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    };
    let mut faces_of_edge: std::collections::BTreeMap<(u32, u32), Vec<usize>> = Default::default();
    for (i, t) in triangles.iter().enumerate() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            faces_of_edge.entry((a.min(b), a.max(b))).or_default().push(i);
        }
    }
    let percentile = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() * 99 / 100], v[v.len() - 1])
    };
    let dihedral = faces_of_edge.values().filter(|f| f.len() == 2).map(|f| {
        let angle = |p: &[DVec3]| normal(p, triangles[f[0]]).dot(normal(p, triangles[f[1]])).clamp(-1.0, 1.0).acos();
        (angle(q) - angle(x)).abs().to_degrees()
    });
    let (bend99, bend_max) = percentile(dihedral.collect());
    let stretch = faces_of_edge.keys().map(|&(a, b)| {
        let (a, b) = (a as usize, b as usize);
        ((q[a] - q[b]).length() / (x[a] - x[b]).length() - 1.0).abs()
    });
    let (stretch99, _) = percentile(stretch.collect());
    let held = doc.group(head).unwrap().vertices().unwrap();
    let lag = held.iter().map(|&v| (q[v] - x[v] - drag).length()).fold(0.0, f64::max) / drag.length();
    (bend99, bend_max, stretch99, lag)
}

/// The editor's default shape model holds a real mesh's shape on a modest drag and reaches
/// the handle; edge springs, the old default, fold the cow's edges (figures in
/// `DEFAULT_SHAPE_MODEL`'s doc).
#[test]
fn the_default_shape_model_holds_the_cow_on_a_modest_drag() {
    assert_eq!(shapeup_app::group::DEFAULT_SHAPE_MODEL, ShapeModel::IsoOneRing);
    let (bend99, bend_max, stretch99, lag) = cow_drag(shapeup_app::group::DEFAULT_SHAPE_MODEL);
    assert!(bend99 < 15.0 && bend_max < 45.0, "dihedral angles change by {bend99:.1}° (p99), {bend_max:.1}° at most");
    assert!(stretch99 < 0.3, "edges stretch by {:.0} % (p99)", 100.0 * stretch99);
    assert!(lag < 0.01, "the handle is {:.1} % of the drag from its target", 100.0 * lag);
    let (springs99, springs_max, _, _) = cow_drag(ShapeModel::EdgeSprings);
    assert!(springs99 > 45.0 && springs_max > 150.0, "springs fold: {springs99:.1}° (p99), {springs_max:.1}°");
}

/// A scene the editor cannot keep whole (a `[material]`, `[loads]`) is refused in one line
/// naming the table, rather than opened and then saved without it.
#[test]
fn a_scene_with_a_material_or_loads_is_refused_not_truncated() {
    const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
    for (table, text) in [
        (
            "[material]",
            "[material]\nmodel = \"stvk\"\nyoungs_modulus = 1e6\npoisson_ratio = 0.3\ndensity = 1000.0\nthickness = 0.001\n",
        ),
        ("[loads]", "[loads]\npressure = 10.0\n"),
    ] {
        let text = format!("[mesh]\npath = '{SPOT}'\n{text}[[constraints]]\ntype = \"edge_spring\"\n");
        let scene = Scene::parse(&text, SceneFormat::Toml, Path::new("m.toml"), std::path::PathBuf::new()).unwrap();
        let e = Document::from_scene(&scene).unwrap_err().to_string();
        assert!(e.contains(table) && e.contains("shapeup deform"), "{e}");
    }
}
