//! Mesh I/O: round trips of every writable format, each reader on hand-written bytes, malformed
//! inputs (an error naming the file and the line or element, never a panic) and atomic writes.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};

use glam::DVec3;
use shapeup_core::Mesh;
use shapeup_core::io::{
    Attributes, IoError, LoadedMesh, PlyEncoding, WriteFormat, obj, off, ply, read_mesh, stl, write_atomic, write_mesh,
    write_mesh_with,
};

#[path = "common/file_mesh.rs"]
mod file_mesh;
use file_mesh::FileMesh;

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/stanford-bunny.obj");
const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");

// ---------------------------------------------------------------------------------------------
// Helpers

/// Five vertices, the last used by no triangle, with coordinates that stress exact round trips.
fn small_mesh() -> FileMesh {
    let positions = vec![
        DVec3::new(0.1, -1.0 / 3.0, 1e-300),
        DVec3::new(1.0, 0.0, -0.0),
        DVec3::new(123_456.789_012_345_67, 2.5e10, -7.0),
        DVec3::new(-0.2, 0.7, 1.0 / 7.0),
        DVec3::new(9.0, 9.0, 9.0), // unreferenced
    ];
    Mesh::new(positions, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]]).unwrap().into()
}

fn spot() -> FileMesh {
    read_mesh(Path::new(SPOT)).unwrap().into()
}

fn assert_bitwise_equal(a: &Mesh, b: &Mesh) {
    assert_eq!(a.positions.len(), b.positions.len(), "vertex count");
    for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
        assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits), "vertex {i}: {p} vs {q}");
    }
    assert_eq!(a.triangles, b.triangles);
}

/// Writes with `format` into a temp dir under `name` and reads back by extension.
fn round_trip(mesh: &FileMesh, name: &str, format: Option<WriteFormat>) -> LoadedMesh {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    match format {
        Some(format) => write_mesh_with(&path, mesh, &mesh.attributes, format).unwrap(),
        None => write_mesh(&path, mesh, &mesh.attributes).unwrap(),
    };
    let loaded = read_mesh(&path).unwrap();
    assert_eq!(fs::read_dir(dir.path()).unwrap().count(), 1, "no temp file left behind");
    loaded
}

/// What reading back a binary STL of `mesh` must give: corners rounded to f32, equal ones merged,
/// numbered by first use (the documented STL behaviour).
fn expected_stl(mesh: &Mesh) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions = Vec::new();
    let triangles = mesh
        .triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                let p = mesh.positions[v as usize].as_vec3() + glam::Vec3::ZERO;
                *index.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                    positions.push(p.as_dvec3());
                    positions.len() as u32 - 1
                })
            })
        })
        .collect();
    (positions, triangles)
}

/// Writes `bytes` to `name` in a fresh temp dir and reads it with `read_mesh`.
fn read_bytes(name: &str, bytes: &[u8]) -> Result<LoadedMesh, IoError> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    fs::write(&path, bytes).unwrap();
    read_mesh(&path)
}

/// Reads malformed `bytes` as `name`; asserts an error whose message names the file and contains
/// every one of `needles`; returns the error.
fn malformed(name: &str, bytes: &[u8], needles: &[&str]) -> IoError {
    let err = read_bytes(name, bytes).expect_err("malformed input must be an error");
    let message = err.to_string();
    assert!(message.contains(name), "message does not name the file: {message}");
    assert!(!message.contains('\n'), "message is not one line: {message}");
    for needle in needles {
        assert!(message.contains(needle), "message lacks {needle:?}: {message}");
    }
    err
}

fn ply_header(format: &str, body: &str) -> Vec<u8> {
    format!("ply\nformat {format} 1.0\n{body}end_header\n").into_bytes()
}

// ---------------------------------------------------------------------------------------------
// Round trips

#[test]
fn obj_round_trip_is_exact_and_keeps_unreferenced_vertex() {
    let mesh = small_mesh();
    let loaded = round_trip(&mesh, "small.obj", None);
    assert_bitwise_equal(&loaded.mesh, &mesh);
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
}

#[test]
fn ply_round_trips_are_exact_in_every_encoding() {
    let mesh = small_mesh();
    assert_bitwise_equal(&round_trip(&mesh, "small.ply", None).mesh, &mesh);
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
        assert_bitwise_equal(&round_trip(&mesh, "small.ply", Some(WriteFormat::Ply(Some(encoding)))).mesh, &mesh);
    }
}

#[test]
fn default_ply_is_binary_little_endian_with_double_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.PLY");
    write_mesh(&path, &small_mesh(), &Attributes::None).unwrap();
    let bytes = fs::read(&path).unwrap();
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.starts_with("ply\nformat binary_little_endian 1.0\n"), "{text}");
    assert!(text.contains("property double x\n") && text.contains("property list uchar int vertex_indices\n"));
}

#[test]
fn off_round_trip_is_exact() {
    let mesh = small_mesh();
    assert_bitwise_equal(&round_trip(&mesh, "small.off", Some(WriteFormat::Off)).mesh, &mesh);
    assert_bitwise_equal(&round_trip(&mesh, "small.off", None).mesh, &mesh);
}

#[test]
fn stl_round_trip_drops_unreferenced_vertices_and_rounds_to_f32() {
    let mesh = small_mesh();
    let loaded = round_trip(&mesh, "small.stl", None);
    let (positions, triangles) = expected_stl(&mesh);
    assert_eq!(positions.len(), 4, "the unreferenced vertex cannot be stored in STL");
    assert_eq!(loaded.mesh.positions, positions);
    assert_eq!(loaded.mesh.triangles, triangles);
    // This mesh's triangles first use its vertices in order, so connectivity is unchanged.
    assert_eq!(loaded.mesh.triangles, mesh.triangles);
    for (p, q) in loaded.mesh.positions.iter().zip(&mesh.positions) {
        assert!((*p - *q).abs().max_element() <= q.abs().max_element() * f64::from(f32::EPSILON), "{p} vs {q}");
    }
}

#[test]
fn spot_round_trips_in_every_format() {
    let mesh = spot();
    assert_eq!(mesh.num_vertices(), 2930);
    assert_eq!(mesh.num_triangles(), 5856);
    for (name, format) in [
        ("spot.obj", WriteFormat::Obj),
        ("spot.ply", WriteFormat::Ply(Some(PlyEncoding::BinaryLittleEndian))),
        ("spot.ply", WriteFormat::Ply(Some(PlyEncoding::BinaryBigEndian))),
        ("spot.ply", WriteFormat::Ply(Some(PlyEncoding::Ascii))),
        ("spot.off", WriteFormat::Off),
    ] {
        let loaded = round_trip(&mesh, name, Some(format));
        assert_bitwise_equal(&loaded.mesh, &mesh);
    }
    let loaded = round_trip(&mesh, "spot.stl", Some(WriteFormat::StlBinary));
    let (positions, triangles) = expected_stl(&mesh);
    assert_eq!(loaded.mesh.positions, positions);
    assert_eq!(loaded.mesh.triangles, triangles);
    assert_eq!(loaded.mesh.num_triangles(), mesh.num_triangles());
}

// ---------------------------------------------------------------------------------------------
// Bundled meshes

#[test]
fn bunny_keeps_every_vertex_in_file_order() {
    let loaded = read_mesh(Path::new(BUNNY)).unwrap();
    assert_eq!(loaded.mesh.num_vertices(), 35_947, "unreferenced vertices are kept");
    assert_eq!(loaded.mesh.num_triangles(), 69_451);
    assert_eq!(loaded.mesh.positions[0], DVec3::new(-0.037830, 0.127940, 0.004475));
    assert_eq!(loaded.mesh.positions[35_946], DVec3::new(-0.040044, 0.153620, -0.008167));
    let mut used = vec![false; 35_947];
    for t in &loaded.mesh.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    assert_eq!(used.iter().filter(|&&u| u).count(), 34_834);
}

#[test]
fn suzanne_quads_are_triangulated() {
    let text = fs::read_to_string(SUZANNE).unwrap();
    let corners: Vec<usize> =
        text.lines().filter(|l| l.starts_with("f ")).map(|l| l.split_whitespace().count() - 1).collect();
    let expected: usize = corners.iter().map(|k| k - 2).sum();
    let loaded = read_mesh(Path::new(SUZANNE)).unwrap();
    assert_eq!(loaded.mesh.num_triangles(), expected);
    assert_eq!(loaded.warnings.count("polygons_triangulated"), corners.iter().filter(|&&k| k > 3).count());
    assert!(loaded.warnings.count("polygons_triangulated") > 0);
    assert_eq!(loaded.mesh.num_vertices(), text.lines().filter(|l| l.starts_with("v ")).count());
}

// ---------------------------------------------------------------------------------------------
// Each reader on hand-written bytes

#[test]
fn obj_corner_forms_negative_indices_and_pentagon() {
    let text = "# test\r\nmtllib a.mtl\r\no thing\r\nv 0 0 0\r\nv 1 0 0 1.0\r\nv 1 1 0 0.5 0.5 0.5\r\nv 0 1 0\r\n\
                v 0.5 1.5 0\r\nvt 0 0\r\nvt 1 0\r\nvt 1 1\r\nvt 0 1\r\nvt 0 2\r\nvn 0 0 1\r\nvn 0 0 1\r\nvn 0 0 1\r\n\
                vn 0 0 1\r\nvn 0 0 1\r\ng grp\r\ns off\r\nusemtl m\r\n\r\nf 1/2/3 2/3/4 3/4/5\r\nf 1//1 3//3 4//4\r\n\
                f -5/1 -3/2 -1/3\r\nf 1 2 3 5 4\r\nl 1 2\r\n";
    let loaded = obj::read_obj(text.as_bytes(), Path::new("forms.obj")).unwrap();
    assert_eq!(loaded.mesh.num_vertices(), 5);
    assert_eq!(loaded.mesh.positions[1], DVec3::X, "w is ignored");
    assert_eq!(loaded.mesh.positions[2], DVec3::new(1.0, 1.0, 0.0), "vertex colours are ignored");
    assert_eq!(
        loaded.mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [0, 2, 4], [0, 1, 2], [0, 2, 4], [0, 4, 3]],
        "pentagon fanned from its first corner"
    );
    assert_eq!(loaded.warnings.count("polygons_triangulated"), 1);
}

#[test]
fn ply_ascii_with_extra_vertex_properties_and_edge_element() {
    let mut bytes = ply_header(
        "ascii",
        "comment made by hand\nobj_info nothing\nelement vertex 4\nproperty float nx\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element edge 2\nproperty int vertex1\nproperty int vertex2\nelement face 2\n\
         property list uchar int vertex_indices\nproperty int flags\n",
    );
    bytes.extend_from_slice(
        b"0.5 0 0 0 255 0 0\r\n0.5 1 0 0 0 255 0\n\n0.5 1 1 0 0 0 255\n0.5 0 1 0.5 1 2 3\n0 1\n1 2\n3 0 1 2 7\n4 0 1 2 3 8\n",
    );
    let loaded = read_bytes("extra.ply", &bytes).unwrap();
    assert_eq!(
        loaded.mesh.positions,
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 0.5)]
    );
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2], [0, 1, 2], [0, 2, 3]]);
}

#[test]
fn ply_binary_big_endian_float_and_uchar_int_lists() {
    let mut bytes = ply_header(
        "binary_big_endian",
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty uchar alpha\n\
         element material 1\nproperty list uint8 float32 values\nproperty int16 id\n\
         element face 1\nproperty uchar flags\nproperty list uchar int vertex_indices\n",
    );
    for p in [[0.0f32, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, -2.25, 3.0]] {
        for x in p {
            bytes.extend_from_slice(&x.to_be_bytes());
        }
        bytes.push(200);
    }
    // material: a 2-item float list and a short, skipped.
    bytes.push(2);
    bytes.extend_from_slice(&1.0f32.to_be_bytes());
    bytes.extend_from_slice(&2.0f32.to_be_bytes());
    bytes.extend_from_slice(&(-3i16).to_be_bytes());
    // face
    bytes.push(9);
    bytes.push(3);
    for v in [2i32, 0, 1] {
        bytes.extend_from_slice(&v.to_be_bytes());
    }
    let loaded = read_bytes("be.ply", &bytes).unwrap();
    assert_eq!(loaded.mesh.positions, vec![DVec3::ZERO, DVec3::new(1.5, 0.0, 0.0), DVec3::new(0.0, -2.25, 3.0)]);
    assert_eq!(loaded.mesh.triangles, vec![[2, 0, 1]]);
}

#[test]
fn ply_binary_little_endian_double_and_vertex_index_name() {
    let mut bytes = ply_header(
        "binary_little_endian",
        "element vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
         element face 1\nproperty list ushort uint vertex_index\n",
    );
    let coords = [[0.1, 0.2, 0.3], [1.0 / 3.0, 0.0, 0.0], [0.0, 1e-300, 0.0], [5.0, 5.0, 5.0]];
    for p in coords {
        for x in p {
            bytes.extend_from_slice(&f64::to_le_bytes(x));
        }
    }
    bytes.extend_from_slice(&4u16.to_le_bytes());
    for v in [0u32, 1, 2, 3] {
        bytes.extend_from_slice(&v.to_le_bytes());
    }
    let loaded = ply::read_ply(&bytes[..], Path::new("le.ply")).unwrap();
    assert_eq!(loaded.mesh.positions, coords.map(DVec3::from_array).to_vec());
    assert_eq!(loaded.mesh.polygons.get(0), Some(&[0, 1, 2, 3][..]));
    assert_eq!(loaded.mesh.triangles.len(), 2, "a quad is two triangles");
    assert_eq!(loaded.warnings.count("polygons_triangulated"), 1);
}

#[test]
fn ply_without_faces_is_a_point_cloud() {
    let mut bytes = ply_header("ascii", "element vertex 2\nproperty int x\nproperty int y\nproperty int z\n");
    bytes.extend_from_slice(b"1 2 3\n-4 5 6\n");
    let loaded = read_bytes("points.ply", &bytes).unwrap();
    assert_eq!(loaded.mesh.positions, vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(-4.0, 5.0, 6.0)]);
    assert!(loaded.mesh.triangles.is_empty());
}

#[test]
fn stl_ascii_merges_shared_corners_in_first_occurrence_order() {
    let text = "solid two\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n\
                \x20     vertex 1 1 0\n    endloop\n  endfacet\n  facet normal 0 0 1\n    outer loop\n\
                \x20     vertex 0 0 0\n      vertex 1 1 0\n      vertex 0 1 0.5e0\n    endloop\n  endfacet\n\
                endsolid two\n";
    let loaded = read_bytes("two.stl", text.as_bytes()).unwrap();
    assert_eq!(
        loaded.mesh.positions,
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.0, 1.0, 0.5)]
    );
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
}

fn binary_stl(header: &[u8], count: u32, triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut bytes = vec![0u8; 80];
    bytes[..header.len()].copy_from_slice(header);
    bytes.extend_from_slice(&count.to_le_bytes());
    for t in triangles {
        bytes.extend_from_slice(&[0u8; 12]);
        for p in t {
            for x in p {
                bytes.extend_from_slice(&x.to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    bytes
}

#[test]
fn stl_binary_whose_header_starts_with_solid() {
    let tris =
        [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]]];
    let bytes = binary_stl(b"solid exported by some CAD tool", 2, &tris);
    assert!(bytes.starts_with(b"solid"));
    let loaded = stl::parse_stl(&bytes, Path::new("cad.stl")).unwrap();
    assert_eq!(loaded.mesh.num_vertices(), 4);
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2], [1, 3, 2]]);
    // And through a file, with an upper-case extension.
    assert_eq!(read_bytes("cad.STL", &bytes).unwrap(), loaded);
}

#[test]
fn stl_degenerate_triangle_is_dropped_and_reported() {
    let tris =
        [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [[0.0, 0.0, 0.0], [-0.0, 0.0, 0.0], [0.0, 1.0, 0.0]]];
    let loaded = read_bytes("deg.stl", &binary_stl(b"x", 2, &tris)).unwrap();
    assert_eq!(loaded.mesh.num_triangles(), 1);
    assert_eq!(loaded.warnings.count("faces_not_triangulated"), 1);
}

#[test]
fn off_with_comments_and_a_quad() {
    let text = "# a quad and a triangle\nOFF\n\n5 2 0 # counts\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n# apex\n0.5 0.5 1\n\
                4 0 1 2 3\n3 0 1 4 255 0 0\n";
    let loaded = off::read_off(text.as_bytes(), Path::new("q.off")).unwrap();
    assert_eq!(loaded.mesh.num_vertices(), 5);
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]]);
    assert_eq!(loaded.warnings.count("polygons_triangulated"), 1);
    assert_eq!(read_bytes("q.off", text.as_bytes()).unwrap().mesh, loaded.mesh);
}

// ---------------------------------------------------------------------------------------------
// Malformed inputs

const TRIANGLE_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

#[test]
fn obj_non_numeric_coordinate() {
    malformed("bad.obj", b"v 0 0 0\nv 1 abc 0\n", &["line 2", "'abc'", "not a number"]);
    malformed("few.obj", b"v 0 0 0\n\nv 1 2\n", &["line 3", "no z coordinate"]);
}

#[test]
fn obj_face_index_zero() {
    malformed("zero.obj", format!("{TRIANGLE_OBJ}f 0 1 2\n").as_bytes(), &["line 4", "index 0", "start at 1"]);
}

#[test]
fn obj_index_out_of_range() {
    malformed("range.obj", format!("{TRIANGLE_OBJ}f 1 2 3\nf 1 2 9\n").as_bytes(), &["line 5", "9", "3 vertices"]);
    malformed("rel.obj", format!("{TRIANGLE_OBJ}f -1 -2 -4\n").as_bytes(), &["line 4", "-4", "only 3 vertices"]);
    malformed("word.obj", format!("{TRIANGLE_OBJ}f 1 b 3\n").as_bytes(), &["line 4", "'b'"]);
}

#[test]
fn obj_face_with_two_vertices() {
    malformed("two.obj", format!("{TRIANGLE_OBJ}f 1 2\n").as_bytes(), &["line 4", "2 vertices", "at least 3"]);
}

#[test]
fn empty_files_are_errors_in_every_format() {
    malformed("empty.obj", b"", &["no vertices"]);
    malformed("faces_only.obj", b"# nothing\nf 1 2 3\n", &["no vertices"]);
    malformed("empty.ply", b"", &["line 1", "'ply'"]);
    malformed("empty.stl", b"", &["too short"]);
    malformed("empty.off", b"", &["line 1", "OFF"]);
    malformed("solid.stl", b"solid nothing\nendsolid nothing\n", &["no triangles"]);
    let zero = ply_header("ascii", "element vertex 0\nproperty float x\nproperty float y\nproperty float z\n");
    malformed("zero.ply", &zero, &["no vertices"]);
    malformed("zero.stl", &binary_stl(b"", 0, &[]), &["no triangles"]);
}

#[test]
fn ply_truncated_binary() {
    let mut bytes = ply_header(
        "binary_little_endian",
        "element vertex 100\nproperty float x\nproperty float y\nproperty float z\n",
    );
    let header_len = bytes.len();
    bytes.extend(std::iter::repeat_n(0u8, 12 * 10 + 5));
    let offset = format!("byte offset {}", header_len + 12 * 10 + 4);
    malformed("trunc.ply", &bytes, &[&offset, "element 'vertex' 10 of 100"]);

    // Ending inside a face's index list.
    let mut bytes = ply_header(
        "binary_big_endian",
        "element vertex 3\nproperty uchar x\nproperty uchar y\nproperty uchar z\nelement face 2\n\
         property list uchar int vertex_indices\n",
    );
    bytes.extend_from_slice(&[0, 0, 0, 1, 0, 0, 0, 1, 0, 3, 0, 0, 0, 0, 0, 0]);
    malformed("trunc_face.ply", &bytes, &["byte offset", "element 'face' 0 of 2"]);
}

#[test]
fn ply_truncated_ascii() {
    let mut bytes = ply_header("ascii", "element vertex 100\nproperty float x\nproperty float y\nproperty float z\n");
    bytes.extend_from_slice(b"0 0 0\n1 0 0\n");
    malformed("trunc_ascii.ply", &bytes, &["line 10", "element 'vertex' 2 of 100"]);
    let mut bytes = ply_header("ascii", "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n");
    bytes.extend_from_slice(b"0 0 0\n1 0\n");
    malformed("short_line.ply", &bytes, &["line 9", "element 'vertex' 1", "'z' is missing"]);
    let mut bytes = ply_header("ascii", "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n");
    bytes.extend_from_slice(b"0 0 0 7\n");
    malformed("long_line.ply", &bytes, &["line 8", "1 more values"]);
}

#[test]
fn ply_huge_count_does_not_allocate_or_panic() {
    let bytes = ply_header(
        "binary_little_endian",
        "element vertex 18446744073709551615\nproperty double x\nproperty double y\nproperty double z\n",
    );
    malformed("huge.ply", &bytes, &["element 'vertex' 0 of 18446744073709551615"]);
}

#[test]
fn ply_header_errors() {
    malformed(
        "no_end.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        &["line 5", "no 'end_header'"],
    );
    malformed(
        "no_end_data.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n0.5\n",
        &["line 5", "'0.5'", "end_header' missing"],
    );
    malformed(
        "type.ply",
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\nend_header\n",
        &["line 4", "unknown property type 'flaot'"],
    );
    malformed("format.ply", b"ply\nelement vertex 0\nend_header\n", &["line 3", "no 'format'"]);
    malformed("fmt.ply", b"ply\nformat binary 1.0\n", &["line 2", "unknown format 'binary'"]);
    malformed("magic.ply", b"PLY\n", &["line 1", "'ply'"]);
    malformed(
        "noface.ply",
        b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
          element face 0\nproperty int vertex_indices\nend_header\n",
        &["line 7", "vertex_indices"],
    );
    malformed("novertex.ply", b"ply\nformat ascii 1.0\nend_header\n", &["line 3", "no 'vertex' element"]);
}

#[test]
fn ply_face_index_out_of_range_names_the_face() {
    let mut bytes = ply_header(
        "ascii",
        "element vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 2\n\
         property list uchar int vertex_indices\n",
    );
    bytes.extend_from_slice(b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n");
    let err = malformed("range.ply", &bytes, &["face 1 refers to vertex 3", "3 vertices"]);
    assert!(matches!(err, IoError::Parse { line: 14, .. }), "{err:?}");
}

#[test]
fn stl_binary_truncated() {
    let tris = [[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]; 2];
    let mut bytes = binary_stl(b"binary", 5, &tris);
    bytes.extend_from_slice(&[1, 2, 3]);
    malformed("trunc.stl", &bytes, &["byte offset 184", "triangle 2 of 5"]);
    // Also when the header starts with "solid": the binary content gives it away.
    let bytes = binary_stl(b"solid but binary", 5, &tris);
    malformed("trunc_solid.stl", &bytes, &["byte offset 184", "triangle 2 of 5"]);
}

#[test]
fn stl_ascii_garbage() {
    malformed("coord.stl", b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 zz\n", &["line 4", "'zz'", "facet 0"]);
    malformed("keyword.stl", b"solid x\n  hello world\n", &["line 2", "expected 'facet' or 'endsolid'", "'hello'"]);
    malformed(
        "corners.stl",
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\n",
        &["line 6", "facet 0 has 2 vertices"],
    );
}

#[test]
fn off_truncated() {
    malformed("trunc.off", b"OFF\n4 1 0\n0 0 0\n1 0 0\n0 1 0\n", &["line 6", "3 of 4 vertices"]);
    malformed("trunc_faces.off", b"OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", &["line 7", "1 of 2 faces"]);
    malformed("trunc_face.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1\n", &["line 6", "face 0 lists 2 of its 3"]);
}

#[test]
fn off_bad_counts_and_data() {
    malformed("counts.off", b"OFF\n3 x 0\n", &["line 2", "bad counts"]);
    malformed("counts2.off", b"OFF\n3\n", &["line 2", "bad counts"]);
    malformed("header.off", b"PLY\n3 1 0\n", &["line 1", "'OFF'"]);
    malformed("coord.off", b"OFF\n3 1 0\n0 0 0\n1 q 0\n0 1 0\n3 0 1 2\n", &["line 4", "vertex 1 y", "'q'"]);
    malformed("range.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", &["line 6", "'3' is not in 0..3"]);
    malformed("two.off", b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", &["line 6", "2 vertices"]);
}

#[test]
fn unsupported_extension_and_missing_file() {
    let err = malformed("mesh.dae", b"whatever", &["unsupported", "'.dae'", ".obj, .ply, .stl, .off"]);
    assert!(matches!(err, IoError::UnsupportedFormat { ref extension, .. } if extension == "dae"));
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("absent.obj");
    let err = read_mesh(&missing).unwrap_err();
    assert!(matches!(err, IoError::Open { .. }));
    assert!(err.to_string().contains("absent.obj") && err.to_string().starts_with("cannot open"), "{err}");
}

#[test]
fn nan_and_inf_coordinates_are_mesh_errors_naming_the_file() {
    for (name, bytes) in [
        ("nan.obj", b"v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".to_vec()),
        ("inf.off", b"OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n".to_vec()),
        ("nan.ply", {
            let mut b = ply_header("ascii", "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n");
            b.extend_from_slice(b"0 NaN 0\n");
            b
        }),
        ("nan.stl", binary_stl(b"", 1, &[[[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]]])),
    ] {
        let err = malformed(name, &bytes, &["non-finite"]);
        assert!(matches!(err, IoError::Mesh { .. }), "{name}: {err:?}");
    }
}

/// Every prefix of a valid file of every format reads as `Ok` or `Err`, never a panic.
#[test]
fn every_truncation_of_every_format_is_an_error_not_a_panic() {
    let mesh = small_mesh();
    let dir = tempfile::tempdir().unwrap();
    for (name, format) in [
        ("t.obj", WriteFormat::Obj),
        ("t.off", WriteFormat::Off),
        ("t.ply", WriteFormat::Ply(Some(PlyEncoding::Ascii))),
        ("t.ply", WriteFormat::Ply(Some(PlyEncoding::BinaryLittleEndian))),
        ("t.ply", WriteFormat::Ply(Some(PlyEncoding::BinaryBigEndian))),
        ("t.stl", WriteFormat::StlBinary),
    ] {
        let path = dir.path().join(name);
        write_mesh_with(&path, &mesh, &mesh.attributes, format).unwrap();
        let bytes = fs::read(&path).unwrap();
        let read = |prefix: &[u8]| match name {
            "t.obj" => obj::read_obj(prefix, Path::new(name)),
            "t.off" => off::read_off(prefix, Path::new(name)),
            "t.ply" => ply::read_ply(prefix, Path::new(name)),
            _ => stl::parse_stl(prefix, Path::new(name)),
        };
        let full = read(&bytes).unwrap().mesh;
        if format != WriteFormat::StlBinary {
            assert_eq!(
                (&full.positions, &full.polygons, &full.triangles),
                (&mesh.positions, &mesh.polygons, &mesh.triangles)
            );
        }
        for len in 0..bytes.len() {
            if let Err(err) = read(&bytes[..len]) {
                assert!(err.to_string().contains(name), "{err}");
            }
        }
        // Binary files cannot lose their last byte unnoticed.
        if !matches!(format, WriteFormat::Obj | WriteFormat::Off | WriteFormat::Ply(Some(PlyEncoding::Ascii))) {
            assert!(read(&bytes[..bytes.len() - 1]).is_err(), "{format:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Atomic writes

fn dir_entries(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    entries
}

#[test]
fn writing_into_a_missing_directory_fails_and_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("missing").join("out.obj");
    let err = write_mesh(&target, &small_mesh(), &Attributes::None).unwrap_err();
    assert!(matches!(err, IoError::Write { .. }));
    assert!(err.to_string().contains("out.obj"), "{err}");
    assert!(dir_entries(dir.path()).is_empty());
}

#[test]
fn failing_writer_leaves_target_unchanged_and_no_temp_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("keep.txt");
    fs::write(&target, "old contents").unwrap();
    let err = write_atomic(&target, |w| {
        w.write_all(b"half of the new cont")?;
        Err(std::io::Error::other("disk on fire"))
    })
    .unwrap_err();
    assert!(err.to_string().contains("keep.txt") && err.to_string().contains("disk on fire"), "{err}");
    assert_eq!(fs::read_to_string(&target).unwrap(), "old contents");
    assert_eq!(dir_entries(dir.path()), vec![target]);
}

#[test]
fn atomic_write_replaces_the_target() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("report.json");
    fs::write(&target, "old").unwrap();
    write_atomic(&target, |w| w.write_all(b"{\"new\": true}")).unwrap();
    assert_eq!(fs::read_to_string(&target).unwrap(), "{\"new\": true}");
    assert_eq!(dir_entries(dir.path()), vec![target]);
}

#[test]
fn invalid_mesh_is_not_written() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("bad.obj");
    let mut mesh = Mesh::new(vec![DVec3::ZERO], vec![]).unwrap();
    mesh.triangles.push([0, 0, 5]);
    mesh.triangle_polygon.push(0);
    let err = write_mesh(&target, &mesh, &Attributes::None).unwrap_err();
    assert!(matches!(err, IoError::Mesh { .. }) && err.to_string().contains("bad.obj"), "{err}");
    assert!(dir_entries(dir.path()).is_empty());
    let err = write_mesh(&dir.path().join("x.dae"), &small_mesh(), &Attributes::None).unwrap_err();
    assert!(matches!(err, IoError::UnsupportedFormat { .. }));
}
