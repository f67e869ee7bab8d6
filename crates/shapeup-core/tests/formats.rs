//! Every text reader skips a UTF-8 byte-order mark; OFF keeps its colours, normals and texture
//! coordinates; writers say what a format cannot hold.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::fs;
use std::path::{Path, PathBuf};

use glam::{DQuat, DVec3};
use shapeup_core::Mesh;
use shapeup_core::io::{Attributes, LoadedMesh, read_mesh, write_mesh};
use shapeup_core::scene::Scene;

const BOM: &str = "\u{feff}";

/// Writes `files` (name, text) into a temp dir and reads the first by extension.
fn read_files(files: &[(&str, &str)]) -> (tempfile::TempDir, LoadedMesh) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        fs::write(dir.path().join(name), text).unwrap();
    }
    let loaded = read_mesh(&dir.path().join(files[0].0)).unwrap_or_else(|e| panic!("{}: {e}", files[0].0));
    (dir, loaded)
}

/// The same mesh read with and without a byte-order mark before the first line.
fn same_with_bom(files: &[(&str, &str)]) -> LoadedMesh {
    let (_d, plain) = read_files(files);
    let mut marked: Vec<(&str, String)> = files.iter().map(|(n, t)| (*n, t.to_string())).collect();
    for (_, text) in &mut marked {
        text.insert_str(0, BOM);
    }
    let marked: Vec<(&str, &str)> = marked.iter().map(|(n, t)| (*n, t.as_str())).collect();
    let (_d, with_bom) = read_files(&marked);
    assert_eq!(with_bom.mesh.positions, plain.mesh.positions, "{}: positions", files[0].0);
    assert_eq!(with_bom.mesh.polygons, plain.mesh.polygons, "{}: faces", files[0].0);
    assert_eq!(with_bom.mesh.tetrahedra, plain.mesh.tetrahedra, "{}: tetrahedra", files[0].0);
    with_bom
}

#[test]
fn a_byte_order_mark_is_skipped_by_every_text_reader() {
    let obj = same_with_bom(&[("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")]);
    assert_eq!(obj.mesh.positions[0], DVec3::ZERO, "the first vertex is not lost");
    same_with_bom(&[(
        "m.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )]);
    same_with_bom(&[("m.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")]);
    let stl = same_with_bom(&[(
        "m.stl",
        "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n",
    )]);
    assert_eq!(stl.mesh.num_triangles(), 1, "ascii STL with a mark is not taken for binary");
    same_with_bom(&[(
        "m.msh",
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\
         $EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n",
    )]);
    let node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    let ele = "1 4 0\n1 1 2 3 4\n";
    // Each of the pair may carry the mark.
    same_with_bom(&[("m.node", node), ("m.ele", ele)]);
}

#[test]
fn scene_files_with_a_byte_order_mark_parse() {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in [
        ("s.toml", "[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge_spring\"\n"),
        ("s.json", r#"{"mesh": {"path": "m.obj"}, "constraints": [{"type": "edge_spring"}]}"#),
    ] {
        let path = dir.path().join(name);
        fs::write(&path, format!("{BOM}{text}")).unwrap();
        let scene = Scene::from_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.groups.len(), 1);
    }
}

// ---------------------------------------------------------------------------------------------
// OFF

fn write_read(
    mesh: &Mesh,
    attributes: &Attributes,
    name: &str,
) -> (PathBuf, String, LoadedMesh, shapeup_core::warnings::Warnings) {
    let dir = tempfile::tempdir().unwrap().keep();
    let path = dir.join(name);
    let warnings = write_mesh(&path, mesh, attributes).unwrap();
    let text = fs::read_to_string(&path).unwrap_or_default();
    let back = read_mesh(&path).unwrap();
    (path, text, back, warnings)
}

#[test]
fn off_keeps_colours_face_colours_and_polygons_and_moves_positions() {
    let text = "# coloured\nCOFF\n5 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n1 1 0 0 0 255 255\n0 1 0 9 9 9 255\n\
                7 7 7 1 2 3 4\n4 0 1 2 3 10 20 30\n3 0 1 2\n";
    let (_d, loaded) = read_files(&[("c.off", text)]);
    let Attributes::Off(off) = &loaded.attributes else { panic!("COFF attributes kept") };
    assert_eq!(off.vertex_extra[4], "1 2 3 4", "unreferenced vertex keeps its values");
    assert_eq!(loaded.attributes.vertex_colors().unwrap()[1], [0.0, 1.0, 0.0]);
    let moved = loaded.mesh.with_positions(loaded.mesh.positions.iter().map(|&p| p + DVec3::X).collect());
    let (_p, written, back, warnings) = write_read(&moved, &loaded.attributes, "moved.off");
    assert!(written.starts_with("COFF\n5 2 0\n"), "{written}");
    assert!(written.contains("\n4 0 1 2 3 10 20 30\n") && written.contains("\n3 0 1 2\n"), "{written}");
    assert_eq!(back.mesh.positions, moved.positions);
    assert_eq!(back.mesh.polygons, loaded.mesh.polygons, "the quad stays a quad");
    assert_eq!(back.attributes, loaded.attributes.clone().with_comments(0));
    assert_eq!(warnings.count("comments_dropped"), 1);
}

#[test]
fn noff_normals_are_recomputed_for_the_moved_shape() {
    // A unit square with the right normals; turned by a rotation, the normals turn with it.
    let text = "NOFF\n4 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n1 1 0 0 0 1\n0 1 0 0 0 1\n4 0 1 2 3\n";
    let (_d, loaded) = read_files(&[("n.off", text)]);
    let turn = DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), 1.0);
    let moved = loaded.mesh.with_positions(loaded.mesh.positions.iter().map(|&p| turn * p).collect());
    let (_p, written, _back, warnings) = write_read(&moved, &loaded.attributes, "n.off");
    assert_eq!(warnings.count("normals_recomputed"), 4);
    let expected = turn * DVec3::Z;
    for line in written.lines().skip(2).take(4) {
        let v: Vec<f64> = line.split_whitespace().map(|t| t.parse().unwrap()).collect();
        assert!((DVec3::new(v[3], v[4], v[5]) - expected).length() < 1e-12, "{line}");
    }
}

#[test]
fn stl_output_says_what_it_cannot_keep() {
    let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 5 5 5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n";
    let (_d, loaded) = read_files(&[("q.obj", text)]);
    let (_p, _text, back, warnings) = write_read(&loaded.mesh, &loaded.attributes, "q.stl");
    assert_eq!(back.mesh.num_vertices(), 4, "the unused vertex is lost, and said");
    assert_eq!(warnings.count("vertices_not_kept"), 5);
    assert_eq!(warnings.count("polygons_split"), 1);
    assert_eq!(warnings.count("attributes_dropped"), 1, "{warnings:?}");
    let line = warnings.iter().map(ToString::to_string).collect::<Vec<_>>().join("\n");
    assert!(line.contains("q.stl") && line.contains("texture coordinates"), "{line}");
}

#[test]
fn every_output_format_keeps_vertex_count_and_order() {
    // Unreferenced vertices at the start, in the middle and at the end.
    let positions: Vec<DVec3> =
        (0..7).map(|i| DVec3::new(i as f64, (i * i) as f64 * 0.5, 1.0 / (i + 1) as f64)).collect();
    let mesh = Mesh::new(positions.clone(), vec![[1, 2, 4], [2, 5, 4]]).unwrap();
    for name in ["m.obj", "m.ply", "m.off", "m.msh"] {
        let (_p, _t, back, _w) = write_read(&mesh, &Attributes::None, name);
        assert_eq!(back.mesh.positions, positions, "{name}");
        assert_eq!(back.mesh.triangles, mesh.triangles, "{name}");
    }
    let _ = Path::new("");
}

#[test]
fn malformed_off_values_name_the_line() {
    for (text, line, needle) in [
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2 junk\n", "line 6", "junk"),
        ("NOFF\n3 1 0\n0 0 0 0 0\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n", "line 3", "normal"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "line 7", "after the last face"),
        ("COFF\n3 1 0\n0 0 0 red\n1 0 0\n0 1 0\n3 0 1 2\n", "line 3", "red"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.off");
        fs::write(&path, text).unwrap();
        let err = read_mesh(&path).unwrap_err().to_string();
        assert!(err.contains("bad.off") && err.contains(line) && err.contains(needle), "{text:?}: {err}");
    }
}
