//! The editor builds groups of any registered type on the selection, vertices or polygon faces,
//! through the library's one route, and saves them so that `shapeup deform` replays them.

use shapeup_app::document::GroupRole;
use shapeup_app::{Command, Document, EditorError, SelectMode, ShapeModel};
use shapeup_core::constraints::{Element, registry};
use shapeup_core::scene::Scene;
use std::path::Path;

const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");

fn suzanne() -> Document {
    Document::open(Path::new(SUZANNE), ShapeModel::EdgeSprings).unwrap()
}

/// The quads among Suzanne's first faces.
fn some_quads(doc: &Document, count: usize) -> Vec<u32> {
    let mesh = doc.rest_mesh();
    (0..mesh.polygons.len() as u32).filter(|&f| mesh.polygons.get(f as usize).unwrap().len() == 4).take(count).collect()
}

#[test]
fn the_add_menu_offers_the_registered_types_that_fit_the_selection() {
    let mut doc = suzanne();
    assert!(doc.fitting_types().is_empty(), "nothing selected, nothing fits");
    doc.apply(Command::Select { vertices: vec![0], mode: SelectMode::Replace }).unwrap();
    let names: Vec<&str> = doc.fitting_types().iter().map(|t| t.name()).collect();
    assert!(names.contains(&"position") && names.contains(&"smoothing"), "{names:?}");
    assert!(doc.fitting_types().iter().all(|t| !t.element().is_face()), "one vertex is no face: {names:?}");
    doc.apply(Command::SelectFaces { faces: some_quads(&doc, 12), mode: SelectMode::Replace }).unwrap();
    let fitting = doc.fitting_types();
    let names: Vec<&str> = fitting.iter().map(|t| t.name()).collect();
    for ty in registry().iter().filter(|t| matches!(t.element(), Element::Face { min, .. } if min <= 4)) {
        assert!(names.contains(&ty.name()), "{} fits twelve quads: {names:?}", ty.name());
    }
    assert!(!names.contains(&"tet_strain"), "no tetrahedra: {names:?}");
}

#[test]
fn a_face_group_is_built_on_the_selected_faces_solved_and_replayed() {
    let mut doc = suzanne();
    let quads = some_quads(&doc, 40);
    doc.apply(Command::SelectFaces { faces: quads.clone(), mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::AddConstraint { kind: "parallelogram".into(), options: Default::default() }).unwrap();
    let group = doc.groups().last().unwrap().clone();
    assert_eq!((group.spec.kind.as_str(), group.role), ("parallelogram", GroupRole::Other));
    // The group keeps face indices as a scene lists them.
    let quad_faces: Vec<usize> = quads.iter().map(|&f| f as usize).collect();
    assert_eq!(group.faces(), Some(&quad_faces[..]));
    // A handle: every vertex held softly where it is.
    doc.apply(Command::Select { vertices: (0..doc.num_vertices() as u32).collect(), mode: SelectMode::Replace })
        .unwrap();
    doc.apply(Command::FixSelection).unwrap();
    doc.converge().unwrap();

    let dir = tempfile::tempdir().unwrap();
    let scene_path = dir.path().join("faces.toml");
    doc.save_scene_with_mesh(&scene_path).unwrap();
    let text = std::fs::read_to_string(&scene_path).unwrap();
    assert!(text.contains("faces = ["), "{text}");
    let scene = Scene::from_file(&scene_path).unwrap();
    let mut loaded = scene.load().unwrap();
    let (q, report) = loaded.solve_static(None).unwrap();
    assert!(report.energies.is_empty(), "the saved shape meets the tolerance: kept as it is");
    let replayed = loaded.mesh_at(&q).positions;
    let worst = replayed.iter().zip(doc.positions()).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    let (lo, hi) = doc.rest_mesh().bounding_box();
    // The saved start already meets the tolerance: the replay is the shape on screen.
    assert!(worst <= 1e-12 * (hi - lo).length(), "the replay is off the editor's shape by {worst}");
    // And the scene reopens in the editor with its face group.
    let reopened = Document::from_scene(&scene).unwrap();
    assert_eq!(
        reopened.groups().iter().find(|g| g.spec.kind == "parallelogram").unwrap().faces(),
        Some(&quad_faces[..])
    );
}

#[test]
fn options_from_the_widgets_reach_the_group_and_bad_ones_are_refused_by_name() {
    let mut doc = suzanne();
    doc.apply(Command::Select { vertices: (0..50).collect(), mode: SelectMode::Replace }).unwrap();
    let before = doc.groups().len();
    let mut options = serde_json::Map::new();
    options.insert("strain_freedom".into(), serde_json::Value::from(-1.0));
    let e = doc.apply(Command::AddConstraint { kind: "triangle_strain".into(), options }).unwrap_err();
    assert!(matches!(e, EditorError::Constraint(_)) && e.to_string().contains("strain_freedom"), "{e}");
    assert_eq!(doc.groups().len(), before, "nothing added");
    let mut options = serde_json::Map::new();
    options.insert("strain_freedom".into(), serde_json::Value::from(0.2));
    doc.apply(Command::AddConstraint { kind: "triangle_strain".into(), options }).unwrap();
    assert_eq!(doc.groups().last().unwrap().spec.options.get("strain_freedom"), Some(&serde_json::Value::from(0.2)));
    // A type with targets becomes a handle at the current positions.
    doc.apply(Command::AddConstraint { kind: "position".into(), options: Default::default() }).unwrap();
    let handle = doc.groups().last().unwrap();
    assert_eq!(handle.role, GroupRole::Handle);
    assert_eq!(handle.targets().len(), 50);
}
