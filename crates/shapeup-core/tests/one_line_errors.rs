//! Findings of the fuzz targets (fuzz/), each with its minimized input: every error is one line
//! (a file's carriage returns, escape sequences and newlines, also those a scene's TOML or JSON
//! escapes spell, are quoted escaped), and OFF vertex lines too short for their keyword's
//! layout are refused instead of having their texture coordinates taken from other values.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use shapeup_core::io::{msh, obj, off, ply, stl, tetgen};
use shapeup_core::scene::Scene;

/// Asserts `message` is one line without control characters, naming `name` and holding `needle`.
fn one_line(message: &str, name: &str, needle: &str) {
    assert!(!message.contains(char::is_control), "not one clean line: {message:?}");
    assert!(message.contains(name), "does not name {name}: {message}");
    assert!(message.contains(needle), "no {needle:?} in: {message}");
}

#[test]
fn readers_quote_control_characters_escaped() {
    let e = obj::read_obj(&b"v 0 0 0\nf 1\x1b[2J 2 3\n"[..], Path::new("esc.obj")).unwrap_err();
    one_line(&e.to_string(), "esc.obj", "\\u{1b}[2J");

    let e = off::read_off(&b"OFF\n3 1 0\n0 0 0\n1 0\r0 0\n"[..], Path::new("cr.off")).unwrap_err();
    one_line(&e.to_string(), "cr.off", "cr.off");

    // A PLY element name with an escape byte, then quoted by the count error and the warning.
    let e = ply::read_ply(&b"ply\nformat ascii 1.0\nelement ve\x1brtex x\n"[..], Path::new("e.ply")).unwrap_err();
    one_line(&e.to_string(), "e.ply", "\\u{1b}");

    let e = stl::read_stl(&b"solid\x07 a\n  fac\x1bet normal 0 0 1\n"[..], Path::new("bell.stl")).unwrap_err();
    one_line(&e.to_string(), "bell.stl", "solid\\u{7}");
    let e = stl::read_stl(&b"solid a\n  fac\x1bet normal 0 0 1\n"[..], Path::new("esc.stl")).unwrap_err();
    one_line(&e.to_string(), "esc.stl", "fac\\u{1b}et");

    let e = tetgen::read_tetgen(
        &b"4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n"[..],
        Path::new("a.node"),
        &b"1 4 0\n1 1 2 3 4\n\x1b]0;pwned\x07\n"[..],
        Path::new("a.ele"),
    )
    .unwrap_err();
    one_line(&e.to_string(), "a.ele", "\\u{1b}]0;pwned\\u{7}");
}

#[test]
fn a_carriage_return_inside_a_line_is_quoted_escaped() {
    // The fuzzer's first finding: readers that quote a whole line (Gmsh, TetGen) gave a lone
    // `\r` back raw, so a terminal showed the end of the message over its start.
    let e = msh::read_msh(&b"$Mesh\rFormat\n4.1 0 8\n$EndMeshFormat\n"[..], Path::new("r.msh")).unwrap_err();
    one_line(&e.to_string(), "r.msh", "$Mesh\\rFormat");
    let e = obj::read_obj(&b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\x1b3\n"[..], Path::new("r.obj")).unwrap_err();
    one_line(&e.to_string(), "r.obj", "x\\u{1b}3");
}

/// The error of loading `text` as `name` (a scene beside a one-triangle `m.obj`).
fn scene(text: &str, name: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    match Scene::from_file(&path) {
        Ok(scene) => scene.load().map(|_| ()).unwrap_err().to_string(),
        Err(e) => e.to_string(),
    }
}

#[test]
fn scene_keys_types_names_and_paths_spelled_with_escapes_stay_on_one_line() {
    // TOML and JSON spell a newline inside a string as `\n`: the parsed key, type or name holds a
    // real one, and messages quote it.
    let toml = "[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge\\nspring\"\n";
    one_line(&scene(toml, "t.toml"), "t.toml", "edge\\nspring");

    let toml = "[mesh]\npath = \"m.obj\"\n[[constraints]]\ntype = \"edge_spring\"\n\"we\\u001bight\" = 1\n";
    one_line(&scene(toml, "k.toml"), "k.toml", "we\\u{1b}ight");

    let json = r#"{"mesh": {"path": "m.obj"}, "constraints": [{"type": "nope", "name": "a\r\nb"}]}"#;
    one_line(&scene(json, "n.json"), "n.json", "a\\r\\nb");

    let json = r#"{"mesh": {"path": "m.obj"}, "constraints": [{"type": "edge_spring", "weight": "x\ny"}]}"#;
    one_line(&scene(json, "w.json"), "w.json", "w.json");

    let json = r#"{"mesh": {"path": "m.obj"}, "solver": {"mode": "sta\ntic"}}"#;
    one_line(&scene(json, "m.json"), "m.json", "m.json");

    // A mesh path with a newline: the load error quotes it escaped.
    one_line(&scene("[mesh]\npath = \"no\\nsuch.obj\"\n", "p.toml"), "p.toml", "no\\nsuch.obj");
}

#[test]
fn off_vertex_lines_shorter_than_their_layout_are_refused() {
    // `STNOFF` needs a normal and s t after x y z: a vertex with 3 values had its normal's y and
    // z taken as texture coordinates, which a round trip then wrote as a different file.
    let text = "STNOFF\n3 1 0\n0 0 0 0 0 1 0.5 0.5\n1 0 0 0 0 1\n0 1 0 0 0 1 1 1\n3 0 1 2\n";
    let e = off::read_off(text.as_bytes(), Path::new("st.off")).unwrap_err();
    one_line(&e.to_string(), "st.off", "vertex 1 has 3 values after x y z");
    assert!(e.to_string().contains("a normal (3), s t (2)"), "{e}");

    let e = off::read_off(&b"COFF\n3 1 0\n0 0 0 1 0 0\n1 0 0 0 1 0\n0 1 0 0 0\n3 0 1 2\n"[..], Path::new("c.off"))
        .unwrap_err();
    one_line(&e.to_string(), "c.off", "line 5: vertex 2 has 2 values after x y z");

    // Enough values (an alpha included) still read, with s t the last two.
    let text = "STCOFF\n3 1 0\n0 0 0 1 0 0 1 0.25 0.75\n1 0 0 0 1 0 1 0 0\n0 1 0 0 0 1 1 1 1\n3 0 1 2\n";
    let loaded = off::read_off(text.as_bytes(), Path::new("ok.off")).unwrap();
    let uv = loaded.attributes.texcoords(&loaded.mesh.polygons).unwrap();
    assert_eq!(uv.values[0], [0.25, 0.75]);
}
