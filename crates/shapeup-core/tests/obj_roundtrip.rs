//! OBJ files in, the same OBJ files out: every line kept, only `v` coordinates and the used `vn`
//! normals rewritten; texture coordinates, corner indices and colours read back identical;
//! normals recomputed with the file's own indexing; bad indices named with file and line.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::Path;

use glam::{DMat3, DVec3};
use proptest::prelude::*;
use shapeup_core::Mesh;
use shapeup_core::geometry::indexed_normals;
use shapeup_core::io::obj::{ObjAttributes, ObjLine, read_obj, write_obj};
use shapeup_core::io::{AttributeKind, Attributes, NO_INDEX};
use shapeup_core::io::{IoError, read_mesh, write_mesh};
use shapeup_core::mesh::Polygons;
use shapeup_core::warnings::Warnings;

#[path = "common/file_mesh.rs"]
mod file_mesh;
use file_mesh::FileMesh;

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");
const BEETLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/beetle.obj");

// ---------------------------------------------------------------------------------------------
// Helpers

fn read(name: &str, bytes: &[u8]) -> FileMesh {
    read_obj(bytes, Path::new(name)).unwrap_or_else(|e| panic!("{e}")).into()
}

fn write(mesh: &FileMesh) -> (Vec<u8>, Warnings) {
    let mut out = Vec::new();
    let mut warnings = Warnings::new();
    write_obj(&mut out, mesh, &mesh.attributes, &mut warnings).unwrap();
    (out, warnings)
}

fn obj(mesh: &FileMesh) -> &ObjAttributes {
    obj_attributes(&mesh.attributes)
}

fn obj_attributes(attributes: &Attributes) -> &ObjAttributes {
    match attributes {
        Attributes::Obj(a) => a,
        other => panic!("expected OBJ attributes, found {other:?}"),
    }
}

fn bits(p: DVec3) -> [u64; 3] {
    p.to_array().map(f64::to_bits)
}

/// Positions bitwise, polygons, texture coordinates, corner indices and colours equal.
fn assert_same_mesh(a: &FileMesh, b: &FileMesh) {
    assert_eq!(a.positions.len(), b.positions.len(), "vertex count");
    for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
        assert_eq!(bits(*p), bits(*q), "vertex {i}: {p} vs {q}");
    }
    assert_eq!(a.polygons, b.polygons, "polygons");
    assert_eq!(a.triangles, b.triangles, "triangles");
    let (x, y) = (obj(a), obj(b));
    assert_eq!(x.texcoords, y.texcoords, "texture coordinates");
    assert_eq!(x.corner_texcoords, y.corner_texcoords, "corner vt indices");
    assert_eq!(x.corner_normals, y.corner_normals, "corner vn indices");
    assert_eq!(x.normals.len(), y.normals.len(), "normal count");
    assert_eq!(x.colors, y.colors, "colours");
    assert_eq!(a.attributes.texcoords(&a.polygons), b.attributes.texcoords(&b.polygons));
    assert_eq!(a.attributes.vertex_colors(), b.attributes.vertex_colors());
    assert_eq!(a.attributes.kinds(), b.attributes.kinds());
    assert_eq!((x.crlf, x.final_newline, x.bom, x.lines.len()), (y.crlf, y.final_newline, y.bom, y.lines.len()));
}

/// Physical lines, each with its `\r` if it had one.
fn physical_lines(bytes: &[u8]) -> Vec<&[u8]> {
    bytes.split(|&b| b == b'\n').collect()
}

/// The three numbers of a `v`/`vn` line and what follows the third, verbatim.
fn split_numbers<'a>(line: &'a str, keyword: &str) -> ([f64; 3], &'a str) {
    let mut rest = line.strip_prefix(keyword).unwrap_or_else(|| panic!("not a {keyword} line: {line:?}"));
    let mut xyz = [0.0; 3];
    for slot in &mut xyz {
        rest = rest.trim_start();
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        *slot = rest[..end].parse().unwrap_or_else(|_| panic!("bad number in {line:?}"));
        rest = &rest[end..];
    }
    (xyz, rest)
}

/// `output` is `input` line for line: the same number of lines and line endings, `v` lines with
/// the same three numbers and the same text after them, `vn` lines holding a unit vector (or
/// unchanged), every other line byte for byte.
fn assert_same_lines(input: &[u8], output: &[u8]) {
    let bom = b"\xEF\xBB\xBF";
    assert_eq!(input.starts_with(bom), output.starts_with(bom), "byte-order mark");
    let strip = |b: &[u8]| -> Vec<u8> { b.strip_prefix(bom).unwrap_or(b).to_vec() };
    let (input, output) = (strip(input), strip(output));
    let (a, b) = (physical_lines(&input), physical_lines(&output));
    assert_eq!(a.len(), b.len(), "number of lines");
    let mut v_lines = 0;
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        let (xs, ys) = (String::from_utf8_lossy(x), String::from_utf8_lossy(y));
        if xs.starts_with("v ") {
            let ((p, rest_in), (q, rest_out)) = (split_numbers(&xs, "v"), split_numbers(&ys, "v"));
            assert_eq!(p.map(f64::to_bits), q.map(f64::to_bits), "line {}: {xs:?} vs {ys:?}", k + 1);
            assert_eq!(rest_in, rest_out, "line {}: the text after z changed", k + 1);
            v_lines += 1;
        } else if xs.starts_with("vn ") && xs != ys {
            let (n, rest) = split_numbers(&ys, "vn");
            assert!((DVec3::from_array(n).length() - 1.0).abs() < 1e-12, "line {}: {ys:?}", k + 1);
            assert_eq!(rest.trim_end_matches('\r'), "", "line {}: {ys:?}", k + 1);
            assert_eq!(x.ends_with(b"\r"), y.ends_with(b"\r"), "line {}: line ending", k + 1);
        } else {
            assert_eq!(x, y, "line {} differs: {xs:?} vs {ys:?}", k + 1);
        }
    }
    assert!(v_lines > 0, "no v lines compared");
}

/// Reads `path`, writes it back unchanged (through [`write_mesh`]), checks the output line for
/// line and the mesh read back; returns the mesh, the output bytes and the write's warnings.
fn round_trip_file(path: &str) -> (FileMesh, Vec<u8>, Warnings) {
    let input = std::fs::read(path).unwrap();
    let mesh = FileMesh::from(read_mesh(Path::new(path)).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("out.obj");
    let warnings = write_mesh(&out_path, &mesh, &mesh.attributes).unwrap();
    let output = std::fs::read(&out_path).unwrap();
    assert_same_lines(&input, &output);
    let back = FileMesh::from(read_mesh(&out_path).unwrap());
    assert_same_mesh(&mesh, &back);
    // Written again, the file does not change any more (recomputed normals are a fixed point).
    let (again, _) = write(&back);
    assert!(again == output, "{:?}", String::from_utf8_lossy(&again));
    (mesh, output, warnings)
}

/// Number of distinct normals some corner uses.
fn used_normals(a: &ObjAttributes) -> usize {
    let mut used = vec![false; a.normals.len()];
    a.corner_normals.iter().filter(|&&n| n != NO_INDEX).for_each(|&n| used[n as usize] = true);
    used.iter().filter(|&&u| u).count()
}

/// Largest angle (degrees) between the file's normals and those recomputed by the writer for an
/// unchanged mesh.
fn worst_normal_angle(mesh: &FileMesh) -> f64 {
    let a = obj(mesh);
    let recomputed = indexed_normals(&mesh.positions, &mesh.polygons, &a.corner_normals, a.normals.len());
    a.normals
        .iter()
        .zip(&recomputed)
        .filter_map(|(n, r)| r.map(|r| n.normalize().dot(r).clamp(-1.0, 1.0).acos().to_degrees()))
        .fold(0.0, f64::max)
}

// ---------------------------------------------------------------------------------------------
// Bundled meshes

#[test]
fn spot_comes_back_line_for_line_with_its_texture_coordinates() {
    let (mesh, _, warnings) = round_trip_file(SPOT);
    let a = obj(&mesh);
    assert_eq!(a.texcoords.len(), 3225);
    assert_eq!(a.corner_texcoords.len(), 3 * 5856);
    assert!(a.corner_texcoords.iter().all(|&t| (t as usize) < a.texcoords.len()), "every corner has a vt");
    assert_eq!(mesh.attributes.kinds(), vec![AttributeKind::TexCoords]);
    assert!(warnings.is_empty(), "{warnings:?}");
}

#[test]
fn suzanne_keeps_its_quads_and_recomputes_its_normals() {
    let (mesh, output, warnings) = round_trip_file(SUZANNE);
    let input = std::fs::read_to_string(SUZANNE).unwrap();
    let faces =
        |text: &str| -> Vec<String> { text.lines().filter(|l| l.starts_with("f ")).map(str::to_owned).collect() };
    assert_eq!(faces(&input), faces(&String::from_utf8(output).unwrap()), "f lines identical");
    assert_eq!(mesh.polygons.iter().filter(|p| p.len() == 4).count(), 468);
    let a = obj(&mesh);
    assert_eq!(warnings.count("normals_recomputed"), used_normals(a));
    assert_eq!(used_normals(a), 507);
    // MeshLab weighted its smooth normals otherwise (up to 32° apart on the sharp features):
    // they agree in direction, not in value.
    let worst = worst_normal_angle(&mesh);
    assert!(worst < 45.0, "a recomputed normal is {worst}° off the file's");
}

#[test]
fn beetle_keeps_objects_smoothing_groups_and_materials() {
    let (mesh, _, warnings) = round_trip_file(BEETLE);
    let a = obj(&mesh);
    assert!(a.groups_and_materials);
    let kinds = mesh.attributes.kinds();
    assert!(kinds.contains(&AttributeKind::Normals), "{kinds:?}");
    assert!(kinds.iter().any(|k| matches!(k, AttributeKind::Other(s) if s.contains("materials"))), "{kinds:?}");
    assert_eq!(a.normals.len(), 1212);
    assert_eq!(warnings.count("normals_recomputed"), used_normals(a));
    let first = warnings.iter().find(|w| w.kind == "normals_recomputed").unwrap();
    let line = 1 + a.lines.iter().position(|l| matches!(l, ObjLine::Normal { .. })).unwrap();
    assert!(first.first.ends_with(&format!("(line {line})")), "{first}");
    // Blender wrote angle-weighted normals of this geometry (rounded to 6 digits) with this
    // indexing (smooth group, split at seams): the recomputed ones are the same.
    let worst = worst_normal_angle(&mesh);
    assert!(worst < 1.0, "a recomputed normal is {worst}° off the file's");
}

// ---------------------------------------------------------------------------------------------
// A hand-written file with every kind of line

/// CRLF, a byte-order mark, comments, an object, groups, a smoothing group, materials, a polyline,
/// a point, an unknown directive, a continued line, relative indices, a pentagon, a concave quad,
/// vertex colours (one with an inline comment), vertices used by no face at the start, in the
/// middle and at the end.
const HAND: &str = "\u{feff}# hand-written: every kind of line\r\n\
mtllib things.mtl\r\n\
o thing\r\n\
v 9 9 9 0.1 0.2 0.3\r\n\
v 0 0 0 1 0 0 # red\r\n\
v 2 0 0 0 1 0\r\n\
v 2 2 0 0 0 1\r\n\
v 0 2 0 1 1 0\r\n\
v 4 4 4 0.5 0.5 0.5\r\n\
v 0.5 0.5 0 0 1 1\r\n\
v 1 3 0 1 0 1\r\n\
vt 0 0\r\n\
vt 1 0\r\n\
vt 1 1 0\r\n\
vt 0 1\r\n\
vn 0 0 1\r\n\
vn 0 0 -1\r\n\
\r\n\
g front back\r\n\
s 1\r\n\
usemtl red\r\n\
# a triangle with relative indices\r\n\
f -7/-4/-2 -6/-3/-2 -5/-2/-2\r\n\
s off\r\n\
f 2/1 3/2 \\\r\n\
\x20 7/3 5/4\r\n\
f 2//1 3//1 4//1 8//1 5//1\r\n\
f 2 3 4\r\n\
l 2 3\r\n\
p 1\r\n\
frobnicate 1 2 3\r\n\
v 7 7 7 0 0 0\r\n";

#[test]
fn hand_written_file_is_read_completely() {
    let loaded = read_obj(HAND.as_bytes(), Path::new("hand.obj")).unwrap();
    let mesh = &FileMesh::from(loaded.clone());
    assert_eq!(mesh.num_vertices(), 9);
    assert_eq!(mesh.positions[0], DVec3::splat(9.0));
    assert_eq!(mesh.positions[8], DVec3::splat(7.0), "the v line after the faces");
    let polygons: Vec<&[u32]> = mesh.polygons.iter().collect();
    assert_eq!(polygons, [&[1, 2, 3][..], &[1, 2, 6, 4], &[1, 2, 3, 7, 4], &[1, 2, 3]]);
    assert_eq!(mesh.num_triangles(), 1 + 2 + 3 + 1);
    assert_eq!(loaded.warnings.count("polygons_triangulated"), 2);
    // The concave quad is cut at its reflex corner (vertex 6), not fanned from vertex 1.
    assert!(mesh.triangles[1..3].iter().all(|t| t.contains(&6)), "{:?}", &mesh.triangles[1..3]);

    let a = obj(mesh);
    let x = NO_INDEX;
    assert_eq!(a.texcoords, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
    assert_eq!(a.corner_texcoords, vec![0, 1, 2, 0, 1, 2, 3, x, x, x, x, x, x, x, x]);
    assert_eq!(a.corner_normals, vec![0, 0, 0, x, x, x, x, 0, 0, 0, 0, 0, x, x, x]);
    assert_eq!(a.normals, vec![DVec3::Z, DVec3::NEG_Z]);
    let colors = a.colors.clone().unwrap();
    assert_eq!(colors.len(), 9);
    assert_eq!(colors[1], [1.0, 0.0, 0.0], "an inline comment is not part of the colour");
    assert_eq!(colors[5], [0.5; 3]);
    assert_eq!(mesh.attributes.vertex_colors(), Some(colors));
    assert!(a.crlf && a.final_newline && a.bom);
    assert_eq!(a.lines.len(), HAND.matches('\n').count() - 1, "the continued f line is one line");
    assert_eq!(a.lines[4], ObjLine::Vertex { index: 1, rest: " 1 0 0 # red".into() });
    assert_eq!(a.lines[24], ObjLine::Other("f 2/1 3/2 \\\n  7/3 5/4".into()));
    assert_eq!(
        mesh.attributes.kinds(),
        vec![
            AttributeKind::TexCoords,
            AttributeKind::Normals,
            AttributeKind::VertexColors,
            AttributeKind::Other("OBJ objects, groups, smoothing groups and materials".into()),
        ]
    );
    let t = mesh.attributes.texcoords(&mesh.polygons).unwrap();
    assert_eq!((t.values, t.corners), (a.texcoords.clone(), a.corner_texcoords.clone()));
    assert!(mesh.attributes.has_normals());
}

#[test]
fn hand_written_file_comes_back_byte_for_byte_but_for_numbers() {
    let mesh = read("hand.obj", HAND.as_bytes());
    let (out, warnings) = write(&mesh);
    assert_same_lines(HAND.as_bytes(), &out);
    let text = String::from_utf8(out.clone()).unwrap();
    // The used normal is recomputed (+z, as every face lies in z = 0 counter-clockwise); the
    // unused one keeps its line.
    assert!(text.contains("\r\nvn 0.0 0.0 1.0\r\nvn 0 0 -1\r\n"), "{text}");
    assert!(text.contains("\r\nv 0.5 0.5 0.0 0 1 1\r\n"), "{text}");
    assert_eq!(warnings.count("normals_recomputed"), 1);
    assert_eq!(warnings.iter().next().unwrap().first, "vn 1 (line 16)");
    assert_same_mesh(&mesh, &read("hand.obj", &out));

    // Moved, only the v lines of the moved vertices change.
    let mut moved = mesh.positions.clone();
    moved[5] = DVec3::new(-1.5, 1e-300, 0.1);
    let (out2, _) = write(&mesh.with_positions(moved));
    let changed: Vec<usize> = physical_lines(&out)
        .iter()
        .zip(physical_lines(&out2))
        .enumerate()
        .filter(|(_, (a, b))| *a != b)
        .map(|(k, _)| k + 1)
        .collect();
    assert_eq!(changed, [9]);
    assert!(String::from_utf8(out2).unwrap().contains("\r\nv -1.5 1e-300 0.1 0.5 0.5 0.5\r\n"));
}

#[test]
fn lf_file_without_final_newline_keeps_both() {
    let text = "v 0 0 0 1\nv 1 0 0 0.5\nv 0 1 0 2\n\n# w, not colours\nf 1 2 3";
    let mesh = read("w.obj", text.as_bytes());
    let a = obj(&mesh);
    assert!(!a.crlf && !a.final_newline && !a.bom);
    assert_eq!(a.colors, None, "one value after x y z is w");
    assert!(mesh.attributes.kinds().is_empty());
    let (out, warnings) = write(&mesh);
    assert_eq!(
        String::from_utf8(out).unwrap(),
        "v 0.0 0.0 0.0 1\nv 1.0 0.0 0.0 0.5\nv 0.0 1.0 0.0 2\n\n# w, not colours\nf 1 2 3"
    );
    assert!(warnings.is_empty());
}

#[test]
fn non_utf8_text_comes_back_byte_for_byte() {
    // Latin-1 `é` (0xE9, not UTF-8) in comments, a material, a group, after a v line's z and in a
    // vn line no face uses (kept as it is).
    let input: &[u8] = b"# mod\xe8le caf\xe9\nmtllib mat\xe9riaux.mtl\nv 0 0 0\nv 1 2 3 # caf\xe9\nv 0 1 0\n\
                         vn 0 0 1 # \xe9\ng t\xeate\nusemtl mat\xe9riau\nf 1 2 3\n\xe9trange \xff\n";
    let mesh = read("latin1.obj", input);
    assert_eq!(mesh.positions[1], DVec3::new(1.0, 2.0, 3.0));
    let a = obj(&mesh);
    assert_eq!(a.lines[3], ObjLine::Vertex { index: 1, rest: b" # caf\xe9".to_vec() });
    assert_eq!(a.lines[7], ObjLine::Other(b"usemtl mat\xe9riau".to_vec()));
    assert!(a.groups_and_materials);

    let (out, warnings) = write(&mesh);
    let expected: &[u8] = b"# mod\xe8le caf\xe9\nmtllib mat\xe9riaux.mtl\nv 0.0 0.0 0.0\nv 1.0 2.0 3.0 # caf\xe9\n\
                            v 0.0 1.0 0.0\nvn 0 0 1 # \xe9\ng t\xeate\nusemtl mat\xe9riau\nf 1 2 3\n\xe9trange \xff\n";
    assert_eq!(String::from_utf8_lossy(&out), String::from_utf8_lossy(expected));
    assert!(out == expected, "the bytes that are not UTF-8 changed");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_same_lines(input, &out);

    // Moved, only that vertex's numbers change.
    let mut moved = mesh.positions.clone();
    moved[1] = DVec3::new(-4.0, 0.5, 2.0);
    let (out2, _) = write(&mesh.with_positions(moved));
    let (lines, lines2) = (physical_lines(&out), physical_lines(&out2));
    assert_eq!(lines.len(), lines2.len());
    for (k, (x, y)) in lines.iter().zip(&lines2).enumerate() {
        if k == 3 {
            assert_eq!(*y, b"v -4.0 0.5 2.0 # caf\xe9");
        } else {
            assert_eq!(x, y, "line {}", k + 1);
        }
    }
}

#[test]
fn faces_may_use_vt_and_vn_defined_after_them() {
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1 2/2/1 3/3/1\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n";
    let mesh = read("late.obj", text.as_bytes());
    assert_eq!(obj(&mesh).corner_texcoords, vec![0, 1, 2]);
    assert_eq!(obj(&mesh).corner_normals, vec![0, 0, 0]);
}

// ---------------------------------------------------------------------------------------------
// Normals follow the geometry

fn rotation() -> DMat3 {
    DMat3::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7)
}

/// Rotates the mesh, writes it and returns the normals read back from the output, with the
/// number of normals the writer reported as recomputed.
fn rotated_normals(mesh: &FileMesh) -> (Vec<DVec3>, usize) {
    let r = rotation();
    let moved = mesh.with_positions(mesh.positions.iter().map(|&p| r * p + DVec3::new(0.3, -2.0, 5.0)).collect());
    let (out, warnings) = write(&moved);
    let back = read("rotated.obj", &out);
    for (p, q) in back.positions.iter().zip(&moved.positions) {
        assert_eq!(bits(*p), bits(*q));
    }
    (obj(&back).normals.clone(), warnings.count("normals_recomputed"))
}

/// A box 2 × 1 × 0.5 as 8 vertices and 6 quads (outward, counter-clockwise), `f` corners `v//n`
/// with `normal(face, vertex)` as the normal index.
fn box_obj(normals: &[DVec3], normal: impl Fn(usize, u32) -> usize) -> String {
    let mut text = String::from("# a box\n");
    for i in 0..8 {
        let p = DVec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -0.5 } else { 0.5 },
            if i & 4 == 0 { -0.25 } else { 0.25 },
        );
        text += &format!("v {:?} {:?} {:?}\n", p.x, p.y, p.z);
    }
    for n in normals {
        text += &format!("vn {:?} {:?} {:?}\n", n.x, n.y, n.z);
    }
    let faces: [[u32; 4]; 6] = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    for (f, face) in faces.iter().enumerate() {
        text += "f";
        for &v in face {
            text += &format!(" {}//{}", v + 1, normal(f, v) + 1);
        }
        text += "\n";
    }
    text
}

#[test]
fn smooth_normals_rotate_with_the_mesh() {
    // At each corner of a box three faces meet at right angles, so the angle-weighted normal is
    // the diagonal (±1, ±1, ±1)/√3 whatever the side lengths (an area-weighted one would not be).
    let normals: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { -1.0 } else { 1.0 },
                if i & 2 == 0 { -1.0 } else { 1.0 },
                if i & 4 == 0 { -1.0 } else { 1.0 },
            )
            .normalize()
        })
        .collect();
    let mesh = read("box.obj", box_obj(&normals, |_, v| v as usize).as_bytes());
    let (back, recomputed) = rotated_normals(&mesh);
    assert_eq!(recomputed, 8);
    for (j, (n, original)) in back.iter().zip(&normals).enumerate() {
        let expected = rotation() * *original;
        assert!((*n - expected).length() < 1e-9, "vn {}: {n} vs {expected}", j + 1);
    }
}

#[test]
fn hard_normals_stay_hard_after_rotation() {
    // A cube-like box whose corners use their face's normal (a hard edge everywhere).
    let normals = [DVec3::NEG_Z, DVec3::Z, DVec3::NEG_Y, DVec3::Y, DVec3::NEG_X, DVec3::X];
    let mesh = read("hard.obj", box_obj(&normals, |f, _| f).as_bytes());
    let (back, recomputed) = rotated_normals(&mesh);
    assert_eq!(recomputed, 6);
    for (j, (n, original)) in back.iter().zip(&normals).enumerate() {
        let expected = rotation() * *original;
        assert!((*n - expected).length() < 1e-9, "vn {}: {n} vs {expected}", j + 1);
    }
}

// ---------------------------------------------------------------------------------------------
// Meshes without (matching) OBJ lines

#[test]
fn changed_vertex_count_writes_a_new_file_keeping_texcoords_and_normals() {
    let mesh = read("hand.obj", HAND.as_bytes());
    let mut grown = mesh.clone();
    grown.positions.push(DVec3::new(3.0, 3.0, 3.0));
    let (out, warnings) = write(&grown);
    let text = String::from_utf8(out.clone()).unwrap();
    assert!(text.starts_with("# written by shapeup: 10 vertices, 4 faces\n"), "{text}");
    assert_eq!(warnings.count("obj_lines_not_kept"), 1);
    // 9 colours for 10 vertices cannot be written; groups and materials have no place either.
    assert_eq!(warnings.count("attributes_dropped"), 2, "{warnings:?}");
    let dropped = warnings.iter().find(|w| w.kind == "attributes_dropped").unwrap();
    assert_eq!(dropped.first, "vertex colours");
    assert_eq!(warnings.count("normals_recomputed"), 6, "one per vertex some face uses");
    let faces: Vec<&str> = text.lines().filter(|l| l.starts_with("f ")).collect();
    assert_eq!(
        faces,
        ["f 2/1/1 3/2/2 4/3/3", "f 2/1/1 3/2/2 7/3/5 5/4/4", "f 2//1 3//2 4//3 8//6 5//4", "f 2//1 3//2 4//3"]
    );
    let back = read("new.obj", &out);
    assert_eq!(back.polygons, mesh.polygons);
    for (p, q) in back.positions.iter().zip(&grown.positions) {
        assert_eq!(bits(*p), bits(*q));
    }
    assert_eq!(back.attributes.texcoords(&back.polygons), mesh.attributes.texcoords(&mesh.polygons));
    assert_eq!(back.attributes.vertex_colors(), None);
    for n in &obj(&back).normals {
        assert!((*n - DVec3::Z).length() < 1e-12, "{n}");
    }
}

#[test]
fn changed_faces_write_a_new_file_keeping_colours_and_normals() {
    let mesh = read("hand.obj", HAND.as_bytes());
    let triangles = vec![[1, 2, 3], [3, 4, 1]];
    let mut changed = mesh.clone();
    changed.polygons = Polygons::from_triangles(&triangles);
    changed.triangle_polygon = vec![0, 1];
    changed.triangles = triangles.clone();
    let (out, warnings) = write(&changed);
    assert_eq!(warnings.count("obj_lines_not_kept"), 1);
    let kinds: Vec<String> =
        warnings.iter().filter(|w| w.kind == "attributes_dropped").map(|w| w.first.clone()).collect();
    assert_eq!(kinds, ["texture coordinates"], "the vt indices belonged to the old faces");
    let back = read("new.obj", &out);
    assert_eq!(back.triangles, triangles);
    assert_eq!(back.attributes.vertex_colors(), mesh.attributes.vertex_colors());
    assert_eq!(obj(&back).corner_normals, vec![0, 1, 2, 2, 3, 0]);
    assert!(obj(&back).normals.iter().all(|n| (*n - DVec3::Z).length() < 1e-12));
}

#[test]
fn generated_mesh_with_tetrahedra_writes_its_surface_polygons() {
    let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    let surface = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let mesh = FileMesh::from(Mesh::with_tetrahedra(positions, surface.clone(), vec![[0, 1, 2, 3]]).unwrap());
    let (out, warnings) = write(&mesh);
    assert!(warnings.is_empty(), "{warnings:?}");
    let text = String::from_utf8(out.clone()).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 4);
    assert!(!text.contains("vn") && !text.contains("vt"), "{text}");
    let back = read("tet.obj", &out);
    assert_eq!(back.triangles, surface);
    assert!(back.tetrahedra.is_empty());
}

// ---------------------------------------------------------------------------------------------
// Bad input

const TRIANGLE: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n";

fn bad(name: &str, text: &str, needles: &[&str]) {
    let err = read_obj(text.as_bytes(), Path::new(name)).expect_err("malformed input must be an error");
    assert!(matches!(err, IoError::Parse { .. }), "{err:?}");
    let message = err.to_string();
    assert!(message.starts_with(&format!("{name}: line ")), "{message}");
    assert!(!message.contains('\n'), "{message}");
    for needle in needles {
        assert!(message.contains(needle), "{message} lacks {needle:?}");
    }
}

#[test]
fn bad_texture_coordinate_and_normal_indices_name_file_and_line() {
    let t = TRIANGLE;
    bad("vt.obj", &format!("{t}f 1/1 2/2 3/3\n"), &["line 7", "texture coordinate (vt) index 3", "2 texture"]);
    bad("vt0.obj", &format!("{t}f 1/0 2/1 3/2\n"), &["line 7", "texture coordinate (vt) index 0", "start at 1"]);
    bad("vtrel.obj", &format!("{t}f 1/-1 2/-2 3/-3\n"), &["line 7", "relative", "-3", "only 2 texture"]);
    bad("vn.obj", &format!("{t}# x\nf 1//1 2//1 3//2\n"), &["line 8", "normal (vn) index 2", "1 normals"]);
    bad("vn0.obj", &format!("{t}f 1//1 2//0 3//1\n"), &["line 7", "normal (vn) index 0"]);
    bad("vnrel.obj", &format!("{t}f 1//-2 2//-1 3//-1\n"), &["line 7", "relative normal (vn) index -2", "only 1"]);
    bad("vnword.obj", &format!("{t}f 1//a 2//1 3//1\n"), &["line 7", "'a'", "not an integer"]);
    bad("novt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", &["line 4", "index 1", "has 0 texture coordinates"]);
    // The relative index counts what is defined before the face, not the whole file.
    bad("late.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/-1 2/-1 3/-1\nvt 0 0\n", &["line 4", "only 0 texture"]);
}

#[test]
fn mixed_corner_forms_name_file_and_line() {
    let t = TRIANGLE;
    bad("mixt.obj", &format!("{t}f 1/1 2/2 3\n"), &["line 7", "vt count mismatch", "'3'"]);
    bad("mixn.obj", &format!("{t}\nf 1 2//1 3\n"), &["line 8", "vn count mismatch", "'2//1'"]);
    bad("mixtn.obj", &format!("{t}f 1/1/1 2/2 3/1/1\n"), &["line 7", "vn count mismatch"]);
}

#[test]
fn non_numeric_values_name_file_and_line() {
    bad("vt.obj", "v 0 0 0\nvt 0.5 abc\n", &["line 2", "'abc'", "not a number"]);
    bad("vtu.obj", "v 0 0 0\nvt\n", &["line 2", "no u"]);
    bad("vn.obj", "v 0 0 0\nvn 0 x 1\n", &["line 2", "'x'", "not a number"]);
    bad("vnz.obj", "v 0 0 0\nvn 0 1\n", &["line 2", "no z"]);
    bad("v.obj", "v 0 0 0\nv 1 0 zz 1 1 1\n", &["line 2", "'zz'"]);
}

// ---------------------------------------------------------------------------------------------
// Random meshes

/// A random OBJ file, as text, with what reading it must give.
#[derive(Debug, Clone)]
struct Case {
    text: String,
    positions: Vec<DVec3>,
    polygons: Polygons,
    texcoords: Vec<[f64; 2]>,
    corner_texcoords: Vec<u32>,
    corner_normals: Vec<u32>,
    colors: Option<Vec<[f64; 3]>>,
}

/// One face: its distinct vertices and, per corner, optional vt and vn choices (in 0..1000,
/// taken modulo the counts) and whether each index is written relative.
type Face = (Vec<u32>, Option<Vec<u32>>, Option<Vec<u32>>, Vec<bool>);

fn case() -> impl Strategy<Value = Case> {
    (6u32..12).prop_flat_map(|n| {
        let coordinate = prop_oneof![-1e3..1e3f64, Just(0.0), Just(-0.0), Just(1e-300), Just(0.1)];
        let positions = prop::collection::vec([coordinate.clone(), coordinate.clone(), coordinate], n as usize);
        let face = (3usize..=6, Just((0..n).collect::<Vec<u32>>()).prop_shuffle()).prop_flat_map(|(k, order)| {
            let vertices = order[..k].to_vec();
            let indices = prop::option::of(prop::collection::vec(0u32..1000, k));
            (Just(vertices), indices.clone(), indices, prop::collection::vec(any::<bool>(), k))
        });
        let faces = prop::collection::vec(face, 1..8);
        let texcoords = prop::collection::vec([-2.0..2.0f64, -2.0..2.0f64], 1..6);
        let normals = prop::collection::vec([-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64], 1..6);
        let colors = prop::option::of(prop::collection::vec([0.0..1.0f64, 0.0..1.0f64, 0.0..1.0f64], n as usize));
        (positions, faces, texcoords, normals, colors, any::<bool>(), any::<bool>())
            .prop_map(|(p, f, t, nn, c, crlf, final_newline)| build_case(p, f, t, nn, c, crlf, final_newline))
    })
}

fn build_case(
    positions: Vec<[f64; 3]>,
    faces: Vec<Face>,
    texcoords: Vec<[f64; 2]>,
    normals: Vec<[f64; 3]>,
    colors: Option<Vec<[f64; 3]>>,
    crlf: bool,
    final_newline: bool,
) -> Case {
    let mut lines = vec!["# random".to_owned()];
    for (i, p) in positions.iter().enumerate() {
        let mut line = format!("v {:?} {:?} {:?}", p[0], p[1], p[2]);
        if let Some(c) = &colors {
            line += &format!(" {:?} {:?} {:?}", c[i][0], c[i][1], c[i][2]);
        }
        lines.push(line);
    }
    lines.extend(texcoords.iter().map(|t| format!("vt {:?} {:?}", t[0], t[1])));
    lines.extend(normals.iter().map(|n| format!("vn {:?} {:?} {:?}", n[0], n[1], n[2])));
    lines.push("g faces".to_owned());
    let (nv, nt, nn) = (positions.len(), texcoords.len(), normals.len());
    let index = |i: u32, count: usize, relative: bool| -> String {
        if relative { (i64::from(i) - count as i64).to_string() } else { (i + 1).to_string() }
    };
    let (mut polygons, mut corner_texcoords, mut corner_normals) = (Polygons::new(), Vec::new(), Vec::new());
    for (vertices, t, n, relative) in &faces {
        let mut line = String::from("f");
        for (k, &v) in vertices.iter().enumerate() {
            let t = t.as_ref().map(|t| t[k] % nt as u32);
            let n = n.as_ref().map(|n| n[k] % nn as u32);
            line += &format!(" {}", index(v, nv, relative[k]));
            match (t, n) {
                (None, None) => {}
                (Some(t), None) => line += &format!("/{}", index(t, nt, relative[k])),
                (None, Some(n)) => line += &format!("//{}", index(n, nn, !relative[k])),
                (Some(t), Some(n)) => line += &format!("/{}/{}", index(t, nt, relative[k]), index(n, nn, !relative[k])),
            }
            corner_texcoords.push(t.unwrap_or(NO_INDEX));
            corner_normals.push(n.unwrap_or(NO_INDEX));
        }
        polygons.push(vertices);
        lines.push(line);
    }
    let newline = if crlf { "\r\n" } else { "\n" };
    let mut text = lines.join(newline);
    if final_newline {
        text += newline;
    }
    Case {
        text,
        positions: positions.into_iter().map(DVec3::from_array).collect(),
        polygons,
        texcoords,
        corner_texcoords,
        corner_normals,
        colors,
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn random_meshes_round_trip(case in case()) {
        let first = read("random.obj", case.text.as_bytes());
        prop_assert_eq!(first.positions.iter().map(|p| bits(*p)).collect::<Vec<_>>(),
            case.positions.iter().map(|p| bits(*p)).collect::<Vec<_>>());
        prop_assert_eq!(&first.polygons, &case.polygons);
        let a = obj(&first);
        prop_assert_eq!(&a.texcoords, &case.texcoords);
        prop_assert_eq!(&a.corner_texcoords, &case.corner_texcoords);
        prop_assert_eq!(&a.corner_normals, &case.corner_normals);
        prop_assert_eq!(&a.colors, &case.colors);

        let (out, _) = write(&first);
        assert_same_lines(case.text.as_bytes(), &out);
        let second = read("random.obj", &out);
        assert_same_mesh(&first, &second);
        // Each used normal is the angle-weighted one of the geometry, exactly as written; the
        // others are the file's.
        let b = obj(&second);
        let expected = indexed_normals(&first.positions, &first.polygons, &a.corner_normals, a.normals.len());
        for (j, (n, e)) in b.normals.iter().zip(&expected).enumerate() {
            prop_assert_eq!(bits(*n), bits(e.unwrap_or(a.normals[j])), "vn {}", j + 1);
        }
    }
}
