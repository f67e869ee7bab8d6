//! The scene targets: parse, then load against a folder of tiny meshes so that mesh reading,
//! selections and constraint building run too.

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};
use std::sync::OnceLock;

use shapeup_core::scene::{Scene, SceneFormat};

use crate::{check_message, expect_valid};

/// Largest generated mesh (vertices) a fuzzed scene is loaded with: bigger ones take long to
/// build and would slow the fuzzer down; the cap on generated sizes has its own tests.
pub const MAX_LOADED_VERTICES: f64 = 20_000.0;

/// The unit cube: 8 vertices, 6 outward quads (0-based).
const CUBE: [[f64; 3]; 8] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [1.0, 1.0, 1.0],
    [0.0, 1.0, 1.0],
];
const QUADS: [[usize; 4]; 6] = [[0, 3, 2, 1], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]];
/// The cube as 5 tetrahedra (oriented when written).
const TETS: [[usize; 4]; 5] = [[0, 1, 3, 4], [1, 2, 3, 6], [1, 4, 5, 6], [3, 4, 6, 7], [1, 3, 4, 6]];

/// The scene's folder (`base_dir`): it holds `mesh.obj`, `.ply`, `.off`, `.stl`, `.msh`,
/// `.node`/`.ele`, and `../data/` the meshes the example scenes name, all tiny.
pub fn scene_dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let root = std::env::var_os("SHAPEUP_FUZZ_MESHES")
            .map_or_else(|| std::env::temp_dir().join("shapeup-fuzz-meshes-v2"), PathBuf::from);
        let scenes = root.join("scenes");
        let data = root.join("data");
        let mut files: Vec<(PathBuf, String)> = vec![
            (scenes.join("mesh.obj"), cube_obj()),
            (scenes.join("mesh.ply"), cube_ply()),
            (scenes.join("mesh.off"), cube_off()),
            (scenes.join("mesh.stl"), cube_stl()),
            (scenes.join("mesh.msh"), cube_msh()),
            (scenes.join("mesh.node"), cube_node()),
            (scenes.join("mesh.ele"), cube_ele()),
        ];
        let stand_in = split_cube_obj();
        for name in ["stanford-bunny", "roof-quads", "spot", "suzanne", "cow", "beetle"] {
            files.push((data.join(format!("{name}.obj")), stand_in.clone()));
        }
        for (path, text) in files {
            write_if_changed(&path, &text);
        }
        scenes
    })
}

/// Writes `text` unless the file already holds it, through a temp file renamed into place (fuzz
/// processes running in parallel share the folder).
fn write_if_changed(path: &Path, text: &str) {
    if std::fs::read_to_string(path).is_ok_and(|t| t == text) {
        return;
    }
    let dir = path.parent().unwrap_or(Path::new("."));
    let temp = dir.join(format!(".tmp-{}", std::process::id()));
    let written = std::fs::create_dir_all(dir)
        .and_then(|()| std::fs::write(&temp, text))
        .and_then(|()| std::fs::rename(&temp, path));
    if let Err(e) = written {
        panic!("cannot write the fuzz meshes in {}: {e} (set SHAPEUP_FUZZ_MESHES to a writable folder)", dir.display());
    }
}

fn cube_obj() -> String {
    let mut s = String::from("# unit cube, quads with texture coordinates\n");
    for [x, y, z] in CUBE {
        let _ = writeln!(s, "v {x} {y} {z}");
    }
    s.push_str("vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    for q in QUADS {
        let _ = writeln!(s, "f {}/1 {}/2 {}/3 {}/4", q[0] + 1, q[1] + 1, q[2] + 1, q[3] + 1);
    }
    s
}

/// The cube [-1, 1]³ with each face split in 2 × 2 quads (26 vertices), the stand-in for the
/// meshes the example scenes name: their boxes (in the input frame) select some of it.
fn split_cube_obj() -> String {
    let mut s = String::from("# the cube [-1, 1]^3, each face 2 x 2 quads\n");
    let mut index = std::collections::HashMap::new();
    let mut vertex = |p: [i32; 3], s: &mut String| -> usize {
        let n = index.len();
        *index.entry(p).or_insert_with(|| {
            let _ = writeln!(s, "v {} {} {}", p[0], p[1], p[2]);
            n + 1
        })
    };
    let mut faces = Vec::new();
    for axis in 0..3 {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [-1, 1] {
            for u in -1..1 {
                for v in -1..1 {
                    let mut quad = [(u, v), (u + 1, v), (u + 1, v + 1), (u, v + 1)].map(|(i, j)| {
                        let mut p = [0; 3];
                        (p[axis], p[b], p[c]) = (side, i, j);
                        vertex(p, &mut s)
                    });
                    // e_b × e_c = e_axis: counter-clockwise seen from +axis.
                    if side < 0 {
                        quad.reverse();
                    }
                    faces.push(quad);
                }
            }
        }
    }
    for [a, b, c, d] in faces {
        let _ = writeln!(s, "f {a} {b} {c} {d}");
    }
    s
}

fn cube_ply() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\nproperty float z\n\
         property float quality\nelement face 6\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for (i, [x, y, z]) in CUBE.iter().enumerate() {
        let _ = writeln!(s, "{x} {y} {z} {i}");
    }
    for q in QUADS {
        let _ = writeln!(s, "4 {} {} {} {}", q[0], q[1], q[2], q[3]);
    }
    s
}

fn cube_off() -> String {
    let mut s = String::from("OFF\n8 6 12\n");
    for [x, y, z] in CUBE {
        let _ = writeln!(s, "{x} {y} {z}");
    }
    for q in QUADS {
        let _ = writeln!(s, "4 {} {} {} {}", q[0], q[1], q[2], q[3]);
    }
    s
}

fn cube_stl() -> String {
    let mut s = String::from("solid cube\n");
    for q in QUADS {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            s.push_str(" facet normal 0 0 0\n  outer loop\n");
            for v in t {
                let [x, y, z] = CUBE[v];
                let _ = writeln!(s, "   vertex {x} {y} {z}");
            }
            s.push_str("  endloop\n endfacet\n");
        }
    }
    s.push_str("endsolid cube\n");
    s
}

/// The tetrahedra with positive volume.
fn oriented_tets() -> Vec<[usize; 4]> {
    TETS.iter()
        .map(|&[a, b, c, d]| {
            let sub = |i: usize, j: usize| [0, 1, 2].map(|k| CUBE[i][k] - CUBE[j][k]);
            let (u, v, w) = (sub(b, a), sub(c, a), sub(d, a));
            let det = u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0])
                + u[2] * (v[0] * w[1] - v[1] * w[0]);
            if det > 0.0 { [a, b, c, d] } else { [a, c, b, d] }
        })
        .collect()
}

fn cube_msh() -> String {
    // A physical group "solid" of every tetrahedron, for scenes' `physical = "solid"`.
    let mut s = String::from(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"solid\"\n$EndPhysicalNames\n$Nodes\n8\n",
    );
    for (i, [x, y, z]) in CUBE.iter().enumerate() {
        let _ = writeln!(s, "{} {x} {y} {z}", i + 1);
    }
    s.push_str("$EndNodes\n$Elements\n5\n");
    for (i, t) in oriented_tets().iter().enumerate() {
        let _ = writeln!(s, "{} 4 2 1 1 {} {} {} {}", i + 1, t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
    }
    s.push_str("$EndElements\n");
    s
}

fn cube_node() -> String {
    let mut s = String::from("8 3 0 0\n");
    for (i, [x, y, z]) in CUBE.iter().enumerate() {
        let _ = writeln!(s, "{} {x} {y} {z}", i + 1);
    }
    s
}

fn cube_ele() -> String {
    let mut s = String::from("5 4 0\n");
    for (i, t) in oriented_tets().iter().enumerate() {
        let _ = writeln!(s, "{} {} {} {} {}", i + 1, t[0] + 1, t[1] + 1, t[2] + 1, t[3] + 1);
    }
    s
}

/// Whether loading `scene` stays quick and inside the meshes folder: a generated mesh of at most
/// [`MAX_LOADED_VERTICES`], or a relative mesh path that goes up at most once (`../data/…`).
pub fn worth_loading(scene: &Scene) -> bool {
    if let Some(generated) = &scene.mesh.generate {
        // The library's own count, for every kind (cloth, sphere, tet_box).
        return generated.element_counts()[0] <= MAX_LOADED_VERTICES;
    }
    let mut ups = 0;
    for (i, component) in scene.mesh.path.components().enumerate() {
        match component {
            Component::Normal(_) => {}
            Component::ParentDir if i == 0 => ups += 1,
            _ => return false,
        }
    }
    ups <= 1
}

/// Parses `data` as a scene in `format` (named `name` in messages) and, when it parses and
/// [`worth_loading`], loads it. Every error must be one line naming the scene file.
///
/// # Panics
/// On a panic inside, or a message that is not one line naming the file: a finding.
pub fn fuzz_scene(data: &[u8], format: SceneFormat, name: &str) {
    // `Scene::from_file` reads UTF-8 text; other bytes never reach the parser.
    let Ok(text) = std::str::from_utf8(data) else {
        assert!(!expect_valid(), "SHAPEUP_FUZZ_EXPECT_VALID: this scene is not UTF-8");
        return;
    };
    let base_dir = scene_dir().to_path_buf();
    let scene = match Scene::parse(text, format, Path::new(name), base_dir) {
        Ok(scene) => scene,
        Err(e) if expect_valid() => panic!("SHAPEUP_FUZZ_EXPECT_VALID: this scene does not parse: {e}"),
        Err(e) => return check_message(&e.to_string(), &[name]),
    };
    if !worth_loading(&scene) {
        assert!(
            !expect_valid(),
            "SHAPEUP_FUZZ_EXPECT_VALID: this scene is not loaded (too large, or its mesh outside)"
        );
        return;
    }
    match scene.load() {
        Ok(_) => {}
        Err(e) if expect_valid() => panic!("SHAPEUP_FUZZ_EXPECT_VALID: this scene does not load: {e}"),
        Err(e) => check_message(&e.to_string(), &[name]),
    }
}
