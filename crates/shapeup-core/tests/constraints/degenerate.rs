//! Vertices that only degenerate (zero-area) triangles use follow their edge: after a large
//! deformation (static or dynamic) they end on the edge at their rest parameter (math
//! reference, "Edge cases").
#![allow(clippy::unwrap_used, clippy::expect_used)]

use glam::DVec3;
use shapeup_core::constraints::DEGENERATE_FACES_GROUP;
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{LoadedScene, Scene, SceneFormat};
use shapeup_core::warnings::Warnings;
use std::path::{Path, PathBuf};

/// Cells of the strip along x and y, and their size.
const NX: u32 = 12;
const NY: u32 = 3;
const CELL: f64 = 0.25;

/// A flat strip of NX × NY cells (3 × 0.75) in the plane z = 0, vertex (i, j) = j (NX + 1) + i.
fn strip() -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let id = |i: u32, j: u32| j * (NX + 1) + i;
    let positions = (0..=NY).flat_map(|j| (0..=NX).map(move |i| DVec3::new(i as f64 * CELL, j as f64 * CELL, 0.0)));
    let triangles = (0..NY)
        .flat_map(|j| {
            (0..NX).flat_map(move |i| {
                [[id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]]
            })
        })
        .collect();
    (positions.collect(), triangles)
}

/// The strip plus vertex v at parameter `t` on its bottom boundary edge (a, b) = (6, 7), used
/// only by the zero-area triangle (a, v, b). Returns the mesh and (v, a, b).
fn strip_with_sliver(t: f64) -> (Mesh, [usize; 3]) {
    let (mut p, mut tris) = strip();
    let (a, b) = (6u32, 7u32);
    let v = p.len() as u32;
    p.push(p[a as usize].lerp(p[b as usize], t));
    tris.push([a, v, b]);
    (Mesh::new(p, tris).unwrap(), [v as usize, a as usize, b as usize])
}

/// The left column fixed; the right one turned 90° about x and moved by (−1, 0.5, 1.5) (the
/// strip is 3 long): a large, non-rigid deformation of the middle where the sliver is.
const HANDLES: &str = r#"
[[constraints]]
type = "position"
name = "fixed"
box = { min = [-1, -1, -1], max = [0.01, 1, 1] }

[[constraints]]
type = "position"
name = "moved"
box = { min = [2.99, -1, -1], max = [4, 1, 1] }
translate = [-1.0, 0.5, 1.5]
rotate = { axis = [1, 0, 0], angle_deg = 90 }
"#;

fn scene(text: &str) -> Scene {
    let full = format!("[mesh]\npath = \"unused.obj\"\n{text}");
    Scene::parse(&full, SceneFormat::Toml, Path::new("degenerate.toml"), PathBuf::new()).unwrap()
}

fn load(mesh: &Mesh, shape: &str) -> LoadedScene {
    scene(&format!("[solver]\niterations = 300\n{shape}{HANDLES}")).build(mesh.clone(), Warnings::new(), 0.0).unwrap()
}

/// Distance of x to the line through a and b, and x's parameter along a → b.
fn on_line(x: DVec3, a: DVec3, b: DVec3) -> (f64, f64) {
    let ab = b - a;
    let s = (x - a).dot(ab) / ab.length_squared();
    ((x - a.lerp(b, s)).length(), s)
}

fn diagonal(mesh: &Mesh) -> f64 {
    let (lo, hi) = mesh.bounding_box();
    (hi - lo).length()
}

/// The static result in the input frame, with and without the attachments.
fn deform(loaded: &mut LoadedScene, with_rule: bool) -> Vec<DVec3> {
    if !with_rule {
        let id = loaded.system.groups().find(|(_, g)| g.name == DEGENERATE_FACES_GROUP).map(|(id, _)| id).unwrap();
        loaded.system.remove_group(id).unwrap();
    }
    let (q, _) = loaded.solve_static(None).unwrap();
    loaded.mesh_at(&q).positions
}

const SPRINGS: &str = "[[constraints]]\ntype = \"edge_spring\"\n";
const STRAIN_BENDING: &str = "[[constraints]]\ntype = \"triangle_strain\"\n[[constraints]]\ntype = \"bending\"\n";
const ISO: &str = "[[constraints]]\ntype = \"iso_one_ring\"\n";

#[test]
fn a_sliver_vertex_ends_on_its_edge_at_its_rest_parameter() {
    let t = 0.3;
    let (mesh, [v, a, b]) = strip_with_sliver(t);
    let d = diagonal(&mesh);
    let rest = &mesh.positions;
    // Only v's attachment touches it: it ends on its edge exactly, whatever the rest does.
    let mut loaded = load(&mesh, STRAIN_BENDING);
    assert_eq!(loaded.warnings.count("degenerate_vertices_attached"), 1);
    let q = deform(&mut loaded, true);
    let (off, s) = on_line(q[v], q[a], q[b]);
    assert!(off < 1e-9 * d, "v is {off} off its edge");
    assert!((s - t).abs() < 1e-9, "v's parameter {s}, rest {t}");
    assert!((q[v] - rest[v]).length() > 0.2 * d, "a large deformation moves v too");
    // Without the rule v stays where it was while its edge moves away.
    let q = deform(&mut load(&mesh, STRAIN_BENDING), false);
    assert_eq!(q[v], rest[v]);
    assert!(on_line(q[v], q[a], q[b]).0 > 0.2 * d, "the spike the rule removes");
}

#[test]
fn with_springs_or_one_rings_the_sliver_vertex_stays_near_its_edge() {
    // Here v is also in the sliver's edge springs, or in a's and b's one-rings, which do not
    // all want it at parameter t once edge ab stretches or turns unevenly: the attachment is one
    // term among them. v ends near its edge, much nearer than without the rule.
    let t = 0.3;
    let (mesh, [v, a, b]) = strip_with_sliver(t);
    let d = diagonal(&mesh);
    // (shape, bound on the distance to the line / d, on |s − t|, on the ratio with / without)
    for (shape, off_max, s_max, ratio_max) in [(SPRINGS, 1e-5, 1e-3, 0.01), (ISO, 3e-3, 5e-3, 0.5)] {
        let q = deform(&mut load(&mesh, shape), true);
        let (off, s) = on_line(q[v], q[a], q[b]);
        let free = deform(&mut load(&mesh, shape), false);
        let free_off = on_line(free[v], free[a], free[b]).0;
        assert!(off < off_max * d, "{shape}: v is {off} off its edge");
        assert!((s - t).abs() < s_max, "{shape}: v's parameter {s}, rest {t}");
        assert!(off < ratio_max * free_off, "{shape}: {off} off with the rule, {free_off} without");
        assert!((q[v] - mesh.positions[v]).length() > 0.2 * d, "{shape}: v follows the deformation");
    }
}

#[test]
fn a_chain_of_slivers_follows_the_edge() {
    // v at 0.3 on (a, b) in (a, v, b); w at 0.5 on (v, b) in (v, w, b): w's edge is solved only
    // through v's attachment.
    let (mesh, [v, a, b]) = strip_with_sliver(0.3);
    let (mut p, mut tris) = (mesh.positions.clone(), mesh.triangles.clone());
    let w = p.len();
    p.push(p[v].lerp(p[b], 0.5));
    tris.push([v as u32, w as u32, b as u32]);
    let mesh = Mesh::new(p, tris).unwrap();
    let d = diagonal(&mesh);
    let mut loaded = load(&mesh, STRAIN_BENDING);
    assert_eq!(loaded.warnings.count("degenerate_vertices_attached"), 2);
    assert_eq!(loaded.warnings.count("degenerate_vertices_stranded"), 0);
    let q = deform(&mut loaded, true);
    for (x, t) in [(q[v], 0.3), (q[w], 0.65)] {
        let (off, s) = on_line(x, q[a], q[b]);
        assert!(off < 1e-9 * d, "{off} off the edge");
        assert!((s - t).abs() < 1e-9, "parameter {s}, rest {t}");
    }
}

#[test]
fn in_dynamic_mode_the_sliver_vertex_stays_on_its_edge() {
    // The strip hangs from its left column and swings under gravity.
    let t = 0.3;
    let (mesh, [v, a, b]) = strip_with_sliver(t);
    let d = diagonal(&mesh);
    let text = format!(
        "[solver]\nmode = \"dynamic\"\n{STRAIN_BENDING}[[constraints]]\ntype = \"position\"\nbox = {{ min = [-1, -1, \
         -1], max = [0.01, 1, 1] }}\n"
    );
    let mut loaded = scene(&text).build(mesh.clone(), Warnings::new(), 0.0).unwrap();
    let m = loaded.masses()[v];
    assert!(m.is_finite() && m > 0.0, "a vertex of a zero-area triangle has a mass: {m}");
    let mut sim = loaded.start_simulation().unwrap();
    for _ in 0..40 {
        sim.step().unwrap();
    }
    let q = loaded.to_input(sim.positions());
    assert!(q.iter().all(|x| x.is_finite()));
    let (off, s) = on_line(q[v], q[a], q[b]);
    // Only v's tiny inertia (m = 1e-9) pulls against its attachment.
    assert!(off < 1e-9 * d, "v is {off} off its edge");
    assert!((s - t).abs() < 1e-9, "v's parameter {s}, rest {t}");
    assert!((q[v] - mesh.positions[v]).length() > 0.05 * d, "the strip swings: v moves with it");
}

#[test]
fn an_isolated_degenerate_triangle_gets_no_attachment_and_no_error() {
    // A collinear triangle away from the strip, which nothing else touches: it keeps its place.
    let (mut p, mut tris) = strip();
    let first = p.len() as u32;
    p.extend([DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.5, 2.0, 0.0), DVec3::new(1.0, 2.0, 0.0)]);
    tris.push([first, first + 1, first + 2]);
    let mesh = Mesh::new(p, tris).unwrap();
    let mut loaded = load(&mesh, STRAIN_BENDING);
    assert!(loaded.system.groups().all(|(_, g)| g.name != DEGENERATE_FACES_GROUP));
    assert_eq!(loaded.warnings.count("degenerate_vertices_attached"), 0);
    assert_eq!(loaded.warnings.count("degenerate_vertices_stranded"), 3);
    let (q, _) = loaded.solve_static(None).unwrap();
    let out = loaded.mesh_at(&q).positions;
    let isolated = first as usize..first as usize + 3;
    assert!(isolated.clone().all(|v| !loaded.system.is_solved(v)));
    assert_eq!(out[isolated.clone()], mesh.positions[isolated]);
}
