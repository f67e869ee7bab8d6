//! PLY kept whole: every element, property, type and header line survives read → write → read
//! in every encoding; only positions (and normals, recomputed) change; triangle strips decode
//! consistently oriented; malformed files are one-line errors with their position.

use std::fs;
use std::path::Path;

use glam::{DQuat, DVec3};
use proptest::prelude::*;
use shapeup_core::Mesh;
use shapeup_core::io::ply::{self, PlyAttributes, PlyScalar, PlyType};
use shapeup_core::io::{
    AttributeKind, Attributes, IoError, NO_INDEX, PlyEncoding, WriteFormat, read_mesh, write_mesh_with,
};
use shapeup_core::mesh::Polygons;
use shapeup_core::warnings::Warnings;

use crate::file_mesh::FileMesh;

const ENCODINGS: [PlyEncoding; 3] = [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian];

// ---------------------------------------------------------------------------------------------
// A reference PLY encoder: files described as data, written independently of the library.

/// A property with the values of every instance (one for a scalar, the items for a list).
#[derive(Debug, Clone)]
struct Prop {
    name: String,
    ty: PlyType,
    data: Vec<Vec<f64>>,
}

#[derive(Debug, Clone)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

/// A PLY file: comment lines and elements.
#[derive(Debug, Clone)]
struct File {
    comments: Vec<String>,
    elements: Vec<Element>,
}

fn scalar(name: &str, ty: PlyScalar, values: &[f64]) -> Prop {
    Prop { name: name.into(), ty: PlyType::Scalar(ty), data: values.iter().map(|&v| vec![v]).collect() }
}

fn list(name: &str, count: PlyScalar, item: PlyScalar, lists: &[&[f64]]) -> Prop {
    Prop { name: name.into(), ty: PlyType::List { count, item }, data: lists.iter().map(|l| l.to_vec()).collect() }
}

fn element(name: &str, props: Vec<Prop>) -> Element {
    let count = props.first().map_or(0, |p| p.data.len());
    Element { name: name.into(), count, props }
}

fn header_of(file: &File, encoding: PlyEncoding) -> String {
    let mut h = format!("ply\nformat {} 1.0\n", encoding.keyword());
    for c in &file.comments {
        h.push_str(&format!("comment {c}\n"));
    }
    for e in &file.elements {
        h.push_str(&format!("element {} {}\n", e.name, e.count));
        for p in &e.props {
            match p.ty {
                PlyType::Scalar(t) => h.push_str(&format!("property {} {}\n", t.name(), p.name)),
                PlyType::List { count, item } => {
                    h.push_str(&format!("property list {} {} {}\n", count.name(), item.name(), p.name))
                }
            }
        }
    }
    h.push_str("end_header\n");
    h
}

fn ascii_value(ty: PlyScalar, v: f64) -> String {
    match ty {
        PlyScalar::Float => format!("{:?}", v as f32),
        PlyScalar::Double => format!("{v:?}"),
        _ => format!("{}", v as i64),
    }
}

fn binary_value(ty: PlyScalar, v: f64, big: bool, out: &mut Vec<u8>) {
    let mut bytes: Vec<u8> = match ty {
        PlyScalar::Char => (v as i8).to_le_bytes().to_vec(),
        PlyScalar::UChar => (v as u8).to_le_bytes().to_vec(),
        PlyScalar::Short => (v as i16).to_le_bytes().to_vec(),
        PlyScalar::UShort => (v as u16).to_le_bytes().to_vec(),
        PlyScalar::Int => (v as i32).to_le_bytes().to_vec(),
        PlyScalar::UInt => (v as u32).to_le_bytes().to_vec(),
        PlyScalar::Float => (v as f32).to_le_bytes().to_vec(),
        PlyScalar::Double => v.to_le_bytes().to_vec(),
    };
    if big {
        bytes.reverse();
    }
    out.extend_from_slice(&bytes);
}

fn encode(file: &File, encoding: PlyEncoding) -> Vec<u8> {
    let mut out = header_of(file, encoding).into_bytes();
    let big = encoding == PlyEncoding::BinaryBigEndian;
    for e in &file.elements {
        for i in 0..e.count {
            let mut values: Vec<(PlyScalar, f64)> = Vec::new();
            for p in &e.props {
                match p.ty {
                    PlyType::Scalar(t) => values.push((t, p.data[i][0])),
                    PlyType::List { count, item } => {
                        values.push((count, p.data[i].len() as f64));
                        values.extend(p.data[i].iter().map(|&v| (item, v)));
                    }
                }
            }
            if encoding == PlyEncoding::Ascii {
                let line: Vec<String> = values.iter().map(|&(t, v)| ascii_value(t, v)).collect();
                out.extend_from_slice(line.join(" ").as_bytes());
                out.push(b'\n');
            } else {
                for (t, v) in values {
                    binary_value(t, v, big, &mut out);
                }
            }
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Helpers

/// What reading a file gave: the mesh with its attributes, and the warnings.
struct Loaded {
    mesh: FileMesh,
    warnings: Warnings,
}

fn read(name: &str, bytes: &[u8]) -> Loaded {
    let loaded = ply::read_ply(bytes, Path::new(name)).unwrap_or_else(|e| panic!("{e}"));
    Loaded { mesh: FileMesh { mesh: loaded.mesh, attributes: loaded.attributes }, warnings: loaded.warnings }
}

fn attributes(mesh: &FileMesh) -> &PlyAttributes {
    match &mesh.attributes {
        Attributes::Ply(a) => a,
        other => panic!("not PLY attributes: {other:?}"),
    }
}

/// Writes through the public API (`write_mesh_with`, a real file) and returns the bytes.
fn write(mesh: &FileMesh, encoding: Option<PlyEncoding>) -> (Vec<u8>, Warnings) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.ply");
    let warnings = write_mesh_with(&path, mesh, &mesh.attributes, WriteFormat::Ply(encoding)).unwrap();
    (fs::read(&path).unwrap(), warnings)
}

/// Asserts that `a` holds exactly what `file` describes: element names and counts, property
/// names, types and every value bit for bit, and the comments in the header.
fn assert_holds(a: &PlyAttributes, file: &File) {
    let comments: Vec<&str> = a.header_lines().iter().filter_map(|l| l.strip_prefix("comment ")).collect();
    assert_eq!(comments, file.comments.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(a.elements().len(), file.elements.len());
    for (got, want) in a.elements().iter().zip(&file.elements) {
        assert_eq!(got.name(), want.name);
        assert_eq!(got.count(), want.count, "element {}", want.name);
        assert_eq!(got.properties().len(), want.props.len(), "element {}", want.name);
        for (gp, wp) in got.properties().iter().zip(&want.props) {
            assert_eq!((gp.name(), gp.ty()), (wp.name.as_str(), wp.ty), "element {}", want.name);
            assert_eq!(gp.len(), wp.data.len());
            for (i, values) in wp.data.iter().enumerate() {
                let got_values = match gp.ty() {
                    PlyType::Scalar(_) => vec![gp.scalar(i).unwrap()],
                    PlyType::List { .. } => gp.list(i).unwrap().to_vec(),
                };
                assert_eq!(
                    got_values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "{} {i} property {}: {got_values:?} vs {values:?}",
                    want.name,
                    wp.name
                );
            }
        }
    }
}

/// Asserts that two files read hold the same elements, properties, types and values (bit for
/// bit) and header lines, but for the `format` line when the encodings differ.
fn assert_same_content(a: &PlyAttributes, b: &PlyAttributes) {
    assert_eq!(a.elements(), b.elements(), "elements differ");
    for (x, y) in a.elements().iter().zip(b.elements()) {
        for (p, q) in x.properties().iter().zip(y.properties()) {
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(p.values()), bits(q.values()), "property {}", p.name());
            assert_eq!(p.offsets(), q.offsets());
        }
    }
    let lines = |a: &PlyAttributes| -> Vec<String> {
        a.header_lines().iter().filter(|l| !l.starts_with("format ")).cloned().collect()
    };
    assert_eq!(lines(a), lines(b));
    let format = b.header_lines().iter().find(|l| l.starts_with("format ")).unwrap();
    assert_eq!(format, &format!("format {} 1.0", b.encoding().keyword()));
}

fn bits(p: &[DVec3]) -> Vec<[u64; 3]> {
    p.iter().map(|p| p.to_array().map(f64::to_bits)).collect()
}

fn f32_of(v: f64) -> f64 {
    f64::from(v as f32)
}

// ---------------------------------------------------------------------------------------------
// A rich asset: colours, a float and an int property, a material element of names, face
// properties, a triangle, a quad and a pentagon, unreferenced vertices at start, middle and end.

const RICH_POSITIONS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0], // unreferenced
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [1.0, 1.0, 0.0],
    [9.0, 9.0, 9.0], // unreferenced
    [0.0, 1.0, 0.0],
    [0.5, 1.5, 0.25],
    [0.125, -3.5, 100.0], // unreferenced
];
const RICH_FACES: [&[f64]; 4] = [&[1.0, 2.0, 3.0], &[1.0, 3.0, 6.0, 5.0], &[1.0, 2.0, 3.0, 6.0, 5.0], &[5.0, 6.0, 3.0]];

fn rich() -> File {
    let column = |axis: usize| RICH_POSITIONS.map(|p| f32_of(p[axis]));
    let n = RICH_POSITIONS.len();
    let texcoords: Vec<Vec<f64>> =
        RICH_FACES.iter().map(|f| (0..2 * f.len()).map(|k| k as f64 * 0.125).collect()).collect();
    let texcoord_lists: Vec<&[f64]> = texcoords.iter().map(Vec::as_slice).collect();
    File {
        comments: vec!["made by hand".into(), "second comment".into()],
        elements: vec![
            element(
                "vertex",
                vec![
                    scalar("x", PlyScalar::Float, &column(0)),
                    scalar("y", PlyScalar::Float, &column(1)),
                    scalar("z", PlyScalar::Float, &column(2)),
                    scalar("red", PlyScalar::UChar, &(0..n).map(|i| (i * 30) as f64).collect::<Vec<_>>()),
                    scalar("green", PlyScalar::UChar, &(0..n).map(|i| 255.0 - i as f64).collect::<Vec<_>>()),
                    scalar("blue", PlyScalar::UChar, &[0.0, 1.0, 2.0, 3.0, 254.0, 255.0, 128.0, 7.0]),
                    scalar("confidence", PlyScalar::Float, &(0..n).map(|i| f32_of(0.1 * i as f64)).collect::<Vec<_>>()),
                    scalar(
                        "label",
                        PlyScalar::Int,
                        &[-7.0, 0.0, 2_000_000_000.0, 1.0, -2_000_000_000.0, 5.0, 6.0, 7.0],
                    ),
                ],
            ),
            element(
                "material",
                vec![
                    list(
                        "name",
                        PlyScalar::UChar,
                        PlyScalar::UChar,
                        &[&b"red".map(f64::from), &b"skin".map(f64::from)],
                    ),
                    scalar("shininess", PlyScalar::Float, &[0.5, 32.0]),
                ],
            ),
            element(
                "face",
                vec![
                    list("vertex_indices", PlyScalar::UChar, PlyScalar::Int, &RICH_FACES),
                    scalar("flags", PlyScalar::UChar, &[0.0, 1.0, 2.0, 255.0]),
                    list("texcoord", PlyScalar::UChar, PlyScalar::Float, &texcoord_lists),
                ],
            ),
        ],
    }
}

#[test]
fn rich_files_are_read_whole_in_every_encoding() {
    let file = rich();
    for encoding in ENCODINGS {
        let loaded = read("rich.ply", &encode(&file, encoding));
        let a = attributes(&loaded.mesh);
        assert_eq!(a.encoding(), encoding);
        assert_holds(a, &file);
        assert!(a.header_lines().contains(&"comment made by hand".to_owned()));
        let mesh = &loaded.mesh;
        assert_eq!(mesh.num_vertices(), 8, "unreferenced vertices are kept");
        let expected: Vec<DVec3> = RICH_POSITIONS.iter().map(|p| DVec3::from_array(p.map(f32_of))).collect();
        assert_eq!(mesh.positions, expected);
        let polygons: Vec<Vec<u32>> = mesh.polygons.iter().map(<[u32]>::to_vec).collect();
        let want: Vec<Vec<u32>> = RICH_FACES.iter().map(|f| f.iter().map(|&v| v as u32).collect()).collect();
        assert_eq!(polygons, want, "faces become the polygons, in file order");
        let name = a.element("material").unwrap().property("name").unwrap();
        assert_eq!(name.list(1).unwrap(), b"skin".map(f64::from));
    }
}

#[test]
fn rich_files_come_back_byte_for_byte_in_their_own_encoding() {
    let file = rich();
    for encoding in ENCODINGS {
        let bytes = encode(&file, encoding);
        let loaded = read("rich.ply", &bytes);
        let (written, warnings) = write(&loaded.mesh, None);
        assert_eq!(
            String::from_utf8_lossy(&written),
            String::from_utf8_lossy(&bytes),
            "{encoding:?}: the file changed on its way through"
        );
        assert!(warnings.is_empty(), "{warnings:?}");
        let back = read("rich.ply", &written);
        assert_same_content(attributes(&loaded.mesh), attributes(&back.mesh));
        assert_eq!(bits(&back.mesh.positions), bits(&loaded.mesh.positions));
        assert_eq!(back.mesh.polygons, loaded.mesh.polygons);
    }
}

#[test]
fn changing_the_encoding_keeps_every_value() {
    let file = rich();
    for from in ENCODINGS {
        let loaded = read("rich.ply", &encode(&file, from));
        for to in ENCODINGS {
            let (written, _) = write(&loaded.mesh, Some(to));
            assert_eq!(written, encode(&file, to), "{from:?} → {to:?}");
            let back = read("rich.ply", &written);
            assert_eq!(attributes(&back.mesh).encoding(), to);
            assert_same_content(attributes(&loaded.mesh), attributes(&back.mesh));
            assert_holds(attributes(&back.mesh), &file);
        }
    }
}

#[test]
fn views_of_a_rich_file() {
    let loaded = read("rich.ply", &encode(&rich(), PlyEncoding::BinaryLittleEndian));
    let attrs = &loaded.mesh.attributes;
    let colors = attrs.vertex_colors().unwrap();
    assert_eq!(colors.len(), 8);
    assert_eq!(colors[1], [30.0 / 255.0, 254.0 / 255.0, 1.0 / 255.0]);
    assert!(!attrs.has_normals());
    let scalars = attrs.vertex_scalars();
    let names: Vec<&str> = scalars.iter().map(|s| s.name.as_str()).collect();
    assert_eq!(names, ["confidence", "label"]);
    assert_eq!(scalars[1].values[2], 2_000_000_000.0);
    let tex = attrs.texcoords(&loaded.mesh.polygons).unwrap();
    assert_eq!(tex.corners.len(), loaded.mesh.polygons.num_corners());
    // Corner 1 of face 1 (corner index 3 + 1): its u v are items 2 and 3 of that face's list.
    assert_eq!(tex.values[tex.corners[4] as usize], [0.25, 0.375]);
    let kinds = attrs.kinds();
    for kind in [
        AttributeKind::TexCoords,
        AttributeKind::VertexColors,
        AttributeKind::VertexScalars,
        AttributeKind::Other("PLY element 'material'".into()),
        AttributeKind::Other("PLY face properties".into()),
    ] {
        assert!(kinds.contains(&kind), "{kind:?} missing from {kinds:?}");
    }
    assert!(!kinds.contains(&AttributeKind::Normals));
}

#[test]
fn per_vertex_uv_and_float_colours_are_views_too() {
    let file = File {
        comments: vec![],
        elements: vec![
            element(
                "vertex",
                vec![
                    scalar("x", PlyScalar::Double, &[0.0, 1.0, 0.0]),
                    scalar("y", PlyScalar::Double, &[0.0, 0.0, 1.0]),
                    scalar("z", PlyScalar::Double, &[0.0, 0.0, 0.0]),
                    scalar("s", PlyScalar::Float, &[0.0, 1.0, 0.5]),
                    scalar("t", PlyScalar::Float, &[0.25, 0.75, 1.0]),
                    scalar("r", PlyScalar::Float, &[0.5, 1.0, 0.0]),
                    scalar("g", PlyScalar::Float, &[0.5, 1.0, 0.0]),
                    scalar("b", PlyScalar::Float, &[0.5, 1.0, 0.0]),
                    scalar("alpha", PlyScalar::UChar, &[255.0, 255.0, 0.0]),
                ],
            ),
            element("face", vec![list("vertex_index", PlyScalar::UChar, PlyScalar::UInt, &[&[2.0, 0.0, 1.0]])]),
        ],
    };
    let loaded = read("uv.ply", &encode(&file, PlyEncoding::Ascii));
    let attrs = &loaded.mesh.attributes;
    let tex = attrs.texcoords(&loaded.mesh.polygons).unwrap();
    assert_eq!(tex.corners, vec![2, 0, 1], "per vertex: corners index by vertex");
    assert_eq!(tex.values, vec![[0.0, 0.25], [1.0, 0.75], [0.5, 1.0]]);
    assert_eq!(attrs.vertex_colors().unwrap()[0], [0.5, 0.5, 0.5], "float colours as they are");
    let names: Vec<String> = attrs.vertex_scalars().into_iter().map(|s| s.name).collect();
    assert_eq!(names, ["alpha"]);
}

// ---------------------------------------------------------------------------------------------
// Moved positions, recomputed normals

#[test]
fn moved_positions_are_written_in_their_type_and_nothing_else_changes() {
    let file = rich();
    for encoding in ENCODINGS {
        let loaded = read("rich.ply", &encode(&file, encoding));
        let moved: Vec<DVec3> =
            loaded.mesh.positions.iter().map(|p| *p * 1.1 + DVec3::new(0.3, -0.2, 1.0 / 3.0)).collect();
        let (written, warnings) = write(&loaded.mesh.with_positions(moved.clone()), None);
        assert!(warnings.is_empty(), "{warnings:?}");
        let back = read("rich.ply", &written);
        // Declared float: written as the nearest f32.
        let expected: Vec<DVec3> = moved.iter().map(|p| DVec3::from_array(p.to_array().map(f32_of))).collect();
        assert_eq!(bits(&back.mesh.positions), bits(&expected));
        assert_ne!(back.mesh.positions, loaded.mesh.positions);
        let (a, b) = (attributes(&loaded.mesh), attributes(&back.mesh));
        assert_eq!(a.header_lines(), b.header_lines());
        for (x, y) in a.elements().iter().zip(b.elements()) {
            for (p, q) in x.properties().iter().zip(y.properties()) {
                assert_eq!(p.ty(), q.ty());
                if x.name() == "vertex" && ["x", "y", "z"].contains(&p.name()) {
                    continue;
                }
                assert_eq!(p, q, "property {} of {} changed", p.name(), x.name());
            }
        }
    }
}

/// A regular octahedron: each vertex's angle-weighted normal is its own direction, exactly.
fn octahedron_file(positions: &[DVec3], normals: &[DVec3]) -> File {
    let col = |v: &[DVec3], axis: usize| v.iter().map(|p| p[axis]).collect::<Vec<_>>();
    let faces: [&[f64]; 8] = [
        &[0.0, 2.0, 4.0],
        &[2.0, 1.0, 4.0],
        &[1.0, 3.0, 4.0],
        &[3.0, 0.0, 4.0],
        &[2.0, 0.0, 5.0],
        &[1.0, 2.0, 5.0],
        &[3.0, 1.0, 5.0],
        &[0.0, 3.0, 5.0],
    ];
    File {
        comments: vec!["octahedron with exact normals".into()],
        elements: vec![
            element(
                "vertex",
                vec![
                    scalar("x", PlyScalar::Double, &col(positions, 0)),
                    scalar("y", PlyScalar::Double, &col(positions, 1)),
                    scalar("z", PlyScalar::Double, &col(positions, 2)),
                    scalar("nx", PlyScalar::Double, &col(normals, 0)),
                    scalar("ny", PlyScalar::Double, &col(normals, 1)),
                    scalar("nz", PlyScalar::Double, &col(normals, 2)),
                    scalar("quality", PlyScalar::UShort, &[1.0, 2.0, 3.0, 4.0, 5.0, 65535.0]),
                ],
            ),
            element("face", vec![list("vertex_indices", PlyScalar::UChar, PlyScalar::Int, &faces)]),
        ],
    }
}

#[test]
fn normals_are_recomputed_for_a_rotated_mesh() {
    let rest = [DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z, -DVec3::Z];
    let file = octahedron_file(&rest, &rest);
    for encoding in ENCODINGS {
        let loaded = read("octa.ply", &encode(&file, encoding));
        assert!(loaded.mesh.attributes.has_normals());
        let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let rotated: Vec<DVec3> = rest.iter().map(|&p| turn * p).collect();
        let (written, warnings) = write(&loaded.mesh.with_positions(rotated.clone()), None);
        assert_eq!(warnings.count("normals_recomputed"), 6);
        let back = read("octa.ply", &written);
        assert_eq!(bits(&back.mesh.positions), bits(&rotated), "double coordinates are exact");
        let vertex = attributes(&back.mesh).element("vertex").unwrap();
        for (i, want) in rotated.iter().enumerate() {
            let got = DVec3::new(
                vertex.property("nx").unwrap().scalar(i).unwrap(),
                vertex.property("ny").unwrap().scalar(i).unwrap(),
                vertex.property("nz").unwrap().scalar(i).unwrap(),
            );
            assert!((got - *want).length() < 1e-12, "vertex {i}: normal {got} vs rotated {want}");
        }
        assert_eq!(vertex.property("quality"), attributes(&loaded.mesh).element("vertex").unwrap().property("quality"));
    }
}

// ---------------------------------------------------------------------------------------------
// Triangle strips

/// A 2 × 4 grid in the plane z = 0: bottom vertex i is 2i, top vertex i is 2i + 1.
fn grid_vertex() -> Element {
    let xs: Vec<f64> = (0..8).map(|v| (v / 2) as f64).collect();
    let ys: Vec<f64> = (0..8).map(|v| (v % 2) as f64).collect();
    element(
        "vertex",
        vec![
            scalar("x", PlyScalar::Float, &xs),
            scalar("y", PlyScalar::Float, &ys),
            scalar("z", PlyScalar::Float, &[0.0; 8]),
        ],
    )
}

fn strips_file(strips: &[&[f64]]) -> File {
    File {
        comments: vec![],
        elements: vec![
            grid_vertex(),
            element("tristrips", vec![list("vertex_indices", PlyScalar::Int, PlyScalar::Int, strips)]),
        ],
    }
}

#[test]
fn triangle_strips_decode_consistently_oriented() {
    // One strip over the first two cells, a restart, one over the third cell.
    let file = strips_file(&[&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0, -1.0, 4.0, 5.0, 6.0, 7.0]]);
    for encoding in ENCODINGS {
        let loaded = read("strips.ply", &encode(&file, encoding));
        let triangles: Vec<Vec<u32>> = loaded.mesh.polygons.iter().map(<[u32]>::to_vec).collect();
        // OpenGL's order: triangle k of a strip is (v_k, v_k+1, v_k+2) for even k, (v_k+1, v_k, v_k+2) for odd k.
        let reference = [[0, 1, 2], [2, 1, 3], [2, 3, 4], [4, 3, 5], [4, 5, 6], [6, 5, 7]];
        assert_eq!(triangles, reference.map(|t| t.to_vec()).to_vec());
        for t in &reference {
            let p = t.map(|v| loaded.mesh.positions[v as usize]);
            let normal = (p[1] - p[0]).cross(p[2] - p[0]);
            assert_eq!(normal, DVec3::new(0.0, 0.0, -1.0), "triangle {t:?} turns the other way");
        }
        assert_eq!(loaded.mesh.triangles.len(), 6);
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        // Written back, the strips stay strips.
        let (written, _) = write(&loaded.mesh, None);
        assert_eq!(written, encode(&file, encoding));
    }
}

#[test]
fn strip_triangles_repeating_a_vertex_are_skipped_and_counted() {
    // 2 2 joins two strips: its triangles repeat a vertex; parity runs on through them.
    let file = strips_file(&[&[0.0, 1.0, 2.0, 2.0, 4.0, 5.0, 6.0], &[3.0, 5.0, 7.0]]);
    let loaded = read("strips.ply", &encode(&file, PlyEncoding::BinaryLittleEndian));
    let triangles: Vec<Vec<u32>> = loaded.mesh.polygons.iter().map(<[u32]>::to_vec).collect();
    // Windows 0 1 2 | 1 2 2 (skip) | 2 2 4 (skip) | 2 4 5 (odd: 4 2 5) | 4 5 6 (even); then 3 5 7.
    assert_eq!(triangles, vec![vec![0, 1, 2], vec![4, 2, 5], vec![4, 5, 6], vec![3, 5, 7]]);
    assert_eq!(loaded.warnings.count("strip_triangles_skipped"), 2);
}

#[test]
fn faces_and_strips_together_faces_first() {
    let mut file = strips_file(&[&[4.0, 5.0, 6.0, 7.0]]);
    file.elements.insert(
        1,
        element("face", vec![list("vertex_indices", PlyScalar::UChar, PlyScalar::Int, &[&[0.0, 2.0, 3.0, 1.0]])]),
    );
    let loaded = read("both.ply", &encode(&file, PlyEncoding::Ascii));
    let polygons: Vec<Vec<u32>> = loaded.mesh.polygons.iter().map(<[u32]>::to_vec).collect();
    assert_eq!(polygons, vec![vec![0, 2, 3, 1], vec![4, 5, 6], vec![6, 5, 7]]);
    let (written, _) = write(&loaded.mesh, Some(PlyEncoding::BinaryBigEndian));
    assert_eq!(written, encode(&file, PlyEncoding::BinaryBigEndian));
}

#[test]
fn a_strip_with_fewer_than_three_indices_is_an_error() {
    for strips in
        [&[&[0.0, 1.0, 2.0][..], &[3.0, 5.0][..]], &[&[0.0, 1.0, 2.0][..], &[0.0, 1.0, 2.0, -1.0, 5.0, 7.0][..]]]
    {
        let file = strips_file(strips);
        let bytes = encode(&file, PlyEncoding::Ascii);
        let err = ply::read_ply(&bytes[..], Path::new("short.ply")).unwrap_err();
        let message = err.to_string();
        assert!(matches!(err, IoError::Parse { line: 19, .. }), "{message}");
        assert!(message.contains("short.ply") && message.contains("'tristrips' 1"), "{message}");
        let bytes = encode(&file, PlyEncoding::BinaryLittleEndian);
        let header = header_of(&file, PlyEncoding::BinaryLittleEndian).len();
        let strip_1 = header + 8 * 12 + 4 + 3 * 4;
        let err = ply::read_ply(&bytes[..], Path::new("short.ply")).unwrap_err();
        let message = err.to_string();
        assert!(message.contains(&format!("byte offset {strip_1}")) && message.contains("'tristrips' 1"), "{message}");
    }
}

// ---------------------------------------------------------------------------------------------
// Malformed files and a byte-order mark

#[test]
fn a_byte_order_mark_before_ply_is_skipped() {
    let bytes = encode(&rich(), PlyEncoding::BinaryBigEndian);
    let mut marked = b"\xEF\xBB\xBF".to_vec();
    marked.extend_from_slice(&bytes);
    let (plain, with_mark) = (read("m.ply", &bytes), read("m.ply", &marked));
    assert_eq!(with_mark.mesh, plain.mesh);
    // Written back without the mark (and otherwise the same).
    assert_eq!(write(&with_mark.mesh, None).0, bytes);
}

fn malformed(name: &str, bytes: &[u8], needles: &[&str]) -> IoError {
    let err = ply::read_ply(bytes, Path::new(name)).expect_err("malformed input must be an error");
    let message = err.to_string();
    assert!(message.contains(name) && !message.contains('\n'), "{message}");
    for needle in needles {
        assert!(message.contains(needle), "message lacks {needle:?}: {message}");
    }
    err
}

fn triangle_file(faces: &[&[f64]]) -> File {
    File {
        comments: vec![],
        elements: vec![
            element(
                "vertex",
                vec![
                    scalar("x", PlyScalar::Float, &[0.0, 1.0, 0.0]),
                    scalar("y", PlyScalar::Float, &[0.0, 0.0, 1.0]),
                    scalar("z", PlyScalar::Float, &[0.0, 0.0, 0.0]),
                ],
            ),
            element(
                "face",
                vec![
                    list("vertex_indices", PlyScalar::UChar, PlyScalar::Int, faces),
                    scalar("flags", PlyScalar::UChar, &vec![0.0; faces.len()]),
                ],
            ),
        ],
    }
}

#[test]
fn list_lengths_that_disagree_with_the_data_are_errors_with_their_position() {
    let file = triangle_file(&[&[0.0, 1.0, 2.0], &[0.0, 2.0, 1.0]]);
    let text = String::from_utf8(encode(&file, PlyEncoding::Ascii)).unwrap();
    // Line 15 is face 1 "3 0 2 1 0": claim 4 corners (then `flags` is missing) or 2 (one value too many).
    assert!(text.contains("\n3 0 2 1 0\n"));
    let err = malformed(
        "few.ply",
        text.replace("\n3 0 2 1 0\n", "\n4 0 2 1 0\n").as_bytes(),
        &["line 15", "face' 1", "'flags' is missing"],
    );
    assert!(matches!(err, IoError::Parse { line: 15, .. }));
    malformed(
        "many.ply",
        text.replace("\n3 0 2 1 0\n", "\n2 0 2 1 0\n").as_bytes(),
        &["line 15", "face' 1", "1 more values"],
    );

    let bytes = encode(&file, PlyEncoding::BinaryLittleEndian);
    // The last face claims one more corner than the file holds.
    let header = header_of(&file, PlyEncoding::BinaryLittleEndian).len();
    let face_1 = header + 3 * 12 + (1 + 12 + 1);
    let mut longer = bytes.clone();
    longer[face_1] = 4;
    let err = malformed("long.ply", &longer, &["byte offset", "element 'face' 1 of 2"]);
    assert!(matches!(err, IoError::Binary { offset, .. } if offset as usize == bytes.len() - 1), "{err}");
    malformed("cut.ply", &bytes[..bytes.len() - 2], &["byte offset", "element 'face' 1 of 2"]);
}

/// A binary little-endian file of 4 float vertices and faces given as raw `uchar int` lists.
fn four_vertex_binary(faces: usize, data: &[&[u32]]) -> Vec<u8> {
    let mut out = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nelement face {faces}\nproperty list uchar int vertex_indices\nend_header\n"
    )
    .into_bytes();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        v.iter().for_each(|c| out.extend_from_slice(&c.to_le_bytes()));
    }
    for face in data {
        out.push(face[0] as u8);
        face[1..].iter().for_each(|v| out.extend_from_slice(&v.to_le_bytes()));
    }
    out
}

#[test]
fn data_after_the_last_element_is_an_error() {
    // Face 0 claims 4 indices but holds 3: it swallows face 1's bytes, which must not pass.
    let swallowing = four_vertex_binary(2, &[&[4, 0, 1, 2], &[3, 0, 2, 3]]);
    malformed("swallow.ply", &swallowing, &["byte offset"]);
    // The header declares one face fewer than the data holds.
    let bytes = four_vertex_binary(1, &[&[3, 0, 1, 2], &[3, 0, 2, 3]]);
    let face_1 = bytes.len() - 13;
    let err = malformed(
        "extra.ply",
        &bytes,
        &[&format!("byte offset {face_1}"), "13 bytes after the last element", "disagree with the data"],
    );
    assert!(matches!(err, IoError::Binary { offset, .. } if offset as usize == face_1), "{err}");
    // The same file with the right count reads.
    read("right.ply", &four_vertex_binary(2, &[&[3, 0, 1, 2], &[3, 0, 2, 3]]));

    let file = triangle_file(&[&[0.0, 1.0, 2.0]]);
    let text = String::from_utf8(encode(&file, PlyEncoding::Ascii)).unwrap();
    // Blank lines at the end are fine; a line with content is not.
    read("blank.ply", format!("{text}\n  \n").as_bytes());
    let err = malformed(
        "extra.ply",
        format!("{text}\n3 0 2 1 0\n").as_bytes(),
        &["line 16", "content after the last element", "'3 0 2 1 0'"],
    );
    assert!(matches!(err, IoError::Parse { line: 16, .. }), "{err}");
}

#[test]
fn faces_with_fewer_than_three_indices_are_errors() {
    for k in 0..3 {
        let short: Vec<f64> = (0..k).map(f64::from).collect();
        let file = triangle_file(&[&[0.0, 1.0, 2.0], &short]);
        let expected = format!("face 1 has {k} vertex indices, expected at least 3");
        let err = malformed("short.ply", &encode(&file, PlyEncoding::Ascii), &["line 15", &expected]);
        assert!(matches!(err, IoError::Parse { line: 15, .. }), "{err}");
        for encoding in [PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
            let face_1 = header_of(&file, encoding).len() + 3 * 12 + (1 + 12 + 1);
            let err = malformed("short.ply", &encode(&file, encoding), &[&format!("byte offset {face_1}"), &expected]);
            assert!(matches!(err, IoError::Binary { .. }), "{err}");
        }
    }
}

#[test]
fn an_index_out_of_range_names_the_line_or_byte_offset_and_face() {
    let file = triangle_file(&[&[0.0, 1.0, 2.0], &[0.0, 9.0, 1.0]]);
    let err = malformed("range.ply", &encode(&file, PlyEncoding::Ascii), &["face 1 refers to vertex 9", "3 vertices"]);
    assert!(matches!(err, IoError::Parse { line: 15, .. }), "{err}");
    let bytes = encode(&file, PlyEncoding::BinaryBigEndian);
    let face_1 = header_of(&file, PlyEncoding::BinaryBigEndian).len() + 3 * 12 + (1 + 12 + 1);
    let err = malformed("range.ply", &bytes, &[&format!("byte offset {face_1}"), "face 1 refers to vertex 9"]);
    assert!(matches!(err, IoError::Binary { .. }));
}

#[test]
fn ascii_values_must_fit_their_type() {
    let file = triangle_file(&[&[0.0, 1.0, 2.0]]);
    let text = String::from_utf8(encode(&file, PlyEncoding::Ascii)).unwrap();
    assert!(text.ends_with("\n3 0 1 2 0\n"));
    let bad = text.replace("\n3 0 1 2 0\n", "\n3 0 1 2 256\n");
    malformed("type.ply", bad.as_bytes(), &["line 14", "face' 0", "'flags' '256' is not a uchar"]);
    let bad = text.replace("\n3 0 1 2 0\n", "\n3 0 1 2 x\n");
    malformed("word.ply", bad.as_bytes(), &["line 14", "'x' is not a number"]);
}

// ---------------------------------------------------------------------------------------------
// The generic writer: meshes that are not (or no longer) the file they were read from

#[test]
fn a_new_mesh_gets_double_coordinates_and_wider_counts_for_big_polygons() {
    let k = 300;
    let positions: Vec<DVec3> = (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            DVec3::new(a.cos(), a.sin(), 0.1)
        })
        .collect();
    let corners: Vec<u32> = (0..k as u32).collect();
    let (mesh, _) = Mesh::from_polygons(positions.clone(), [&corners[..]].into_iter().collect()).unwrap();
    for encoding in ENCODINGS {
        let (written, warnings) = write(&mesh.clone().into(), Some(encoding));
        assert!(warnings.is_empty(), "{warnings:?}");
        let back = read("big.ply", &written);
        assert_eq!(bits(&back.mesh.positions), bits(&positions));
        assert_eq!(back.mesh.polygons, mesh.polygons);
        let face = attributes(&back.mesh).element("face").unwrap();
        assert_eq!(
            face.property("vertex_indices").unwrap().ty(),
            PlyType::List { count: PlyScalar::UShort, item: PlyScalar::Int }
        );
    }
}

/// `mesh` with its polygons replaced by `triangles`, so that its PLY attributes no longer match.
fn with_other_faces(mesh: &FileMesh, triangles: &[[u32; 3]]) -> FileMesh {
    let mut other = mesh.clone();
    other.polygons = Polygons::from_triangles(triangles);
    other.triangles = triangles.to_vec();
    other.triangle_polygon = (0..triangles.len() as u32).collect();
    other
}

#[test]
fn a_mesh_whose_faces_changed_keeps_colours_and_reports_the_rest() {
    let loaded = read("rich.ply", &encode(&rich(), PlyEncoding::Ascii));
    let mesh = with_other_faces(&loaded.mesh, &[[1, 2, 3], [3, 5, 6]]);
    let (written, warnings) = write(&mesh, None);
    assert_eq!(warnings.count("ply_layout_not_kept"), 1, "{warnings:?}");
    assert_eq!(warnings.count("colors_rounded"), 0, "uchar colours are exact");
    let dropped: Vec<String> =
        warnings.iter().filter(|w| w.kind == "attributes_dropped").map(|w| w.to_string()).collect();
    // Texture coordinates (the old faces' do not fit the new ones), confidence and label, the
    // material element, the face flags, the header comments.
    assert_eq!(warnings.count("attributes_dropped"), 5, "{dropped:?}");
    assert!(dropped[0].contains("(first: texture coordinates)"), "{dropped:?}");
    let text = String::from_utf8_lossy(&written);
    assert!(text.starts_with("ply\nformat ascii 1.0\n"), "the input's encoding: {text}");
    let back = read("changed.ply", &written);
    assert_eq!(back.mesh.attributes.vertex_colors(), loaded.mesh.attributes.vertex_colors());
    assert_eq!(back.mesh.polygons, mesh.polygons);
    assert_eq!(bits(&back.mesh.positions), bits(&loaded.mesh.positions));
    // The old faces' texture coordinates do not fit the new faces: not written, and said.
    assert!(back.mesh.attributes.texcoords(&back.mesh.polygons).is_none());
}

#[test]
fn generic_output_rounds_float_colours_with_a_warning_and_writes_per_corner_uv() {
    let file = File {
        comments: vec![],
        elements: vec![
            element(
                "vertex",
                vec![
                    scalar("x", PlyScalar::Double, &[0.0, 1.0, 0.0, 1.0]),
                    scalar("y", PlyScalar::Double, &[0.0, 0.0, 1.0, 1.0]),
                    scalar("z", PlyScalar::Double, &[0.0; 4]),
                    scalar("u", PlyScalar::Float, &[0.0, 1.0, 0.0, 1.0]),
                    scalar("v", PlyScalar::Float, &[0.0, 0.0, 1.0, 0.5]),
                    scalar("red", PlyScalar::Float, &[0.3, 0.0, 1.0, 0.5].map(f32_of)),
                    scalar("green", PlyScalar::Float, &[0.0, 0.0, 1.0, 0.0]),
                    scalar("blue", PlyScalar::Float, &[0.0, 0.0, 1.0, 0.0]),
                ],
            ),
            element("face", vec![list("vertex_indices", PlyScalar::UChar, PlyScalar::Int, &[&[0.0, 1.0, 3.0, 2.0]])]),
        ],
    };
    let loaded = read("float.ply", &encode(&file, PlyEncoding::Ascii));
    let mesh = with_other_faces(&loaded.mesh, &[[0, 1, 3], [0, 3, 2]]);
    let (written, warnings) = write(&mesh, Some(PlyEncoding::BinaryLittleEndian));
    assert_eq!(warnings.count("colors_rounded"), 2, "0.3 and 0.5 are no multiples of 1/255: {warnings:?}");
    let back = read("float.ply", &written);
    let colors = back.mesh.attributes.vertex_colors().unwrap();
    assert_eq!(colors[0], [77.0 / 255.0, 0.0, 0.0]);
    assert_eq!(colors[3], [128.0 / 255.0, 0.0, 0.0]);
    let tex = back.mesh.attributes.texcoords(&back.mesh.polygons).unwrap();
    let per_corner: Vec<[f64; 2]> = tex.corners.iter().map(|&c| tex.values[c as usize]).collect();
    assert_eq!(per_corner, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 0.5], [0.0, 0.0], [1.0, 0.5], [0.0, 1.0]]);
    assert!(tex.corners.iter().all(|&c| c != NO_INDEX));
}

// ---------------------------------------------------------------------------------------------
// Random files

fn any_scalar() -> impl Strategy<Value = PlyScalar> {
    prop::sample::select(PlyScalar::ALL.to_vec())
}

fn int_scalar() -> impl Strategy<Value = PlyScalar> {
    prop::sample::select(PlyScalar::ALL.iter().copied().filter(|t| t.is_integer()).collect::<Vec<_>>())
}

/// Any finite value of type `ty`, sampled so that the ends of each range, zero, −0 and tiny
/// floats all come up.
fn value_of(ty: PlyScalar) -> BoxedStrategy<f64> {
    match ty {
        PlyScalar::Float => prop_oneof![
            any::<u32>().prop_map(f32::from_bits),
            Just(-0.0f32),
            Just(f32::MIN_POSITIVE / 4.0),
            -10.0f32..10.0
        ]
        .prop_filter("finite", |v| v.is_finite())
        .prop_map(f64::from)
        .boxed(),
        PlyScalar::Double => prop_oneof![any::<u64>().prop_map(f64::from_bits), Just(-0.0), Just(5e-324), -10.0..10.0]
            .prop_filter("finite", |v| v.is_finite())
            .boxed(),
        _ => {
            let (lo, hi) = match ty {
                PlyScalar::Char => (i64::from(i8::MIN), i64::from(i8::MAX)),
                PlyScalar::UChar => (0, i64::from(u8::MAX)),
                PlyScalar::Short => (i64::from(i16::MIN), i64::from(i16::MAX)),
                PlyScalar::UShort => (0, i64::from(u16::MAX)),
                PlyScalar::Int => (i64::from(i32::MIN), i64::from(i32::MAX)),
                _ => (0, i64::from(u32::MAX)),
            };
            prop_oneof![Just(lo), Just(hi), lo..=hi].prop_map(|v| v as f64).boxed()
        }
    }
}

/// A property named `name` of random type with `count` instances.
fn random_prop(name: String, count: usize, lists: bool) -> BoxedStrategy<Prop> {
    let scalar_name = name.clone();
    let scalar_prop = any_scalar()
        .prop_flat_map(move |ty| {
            let name = scalar_name.clone();
            prop::collection::vec(value_of(ty), count).prop_map(move |v| Prop {
                name: name.clone(),
                ty: PlyType::Scalar(ty),
                data: v.into_iter().map(|v| vec![v]).collect(),
            })
        })
        .boxed();
    if !lists {
        return scalar_prop;
    }
    let list_prop = (int_scalar(), any_scalar())
        .prop_flat_map(move |(c, item)| {
            let name = name.clone();
            // Short lists: every count type holds their lengths.
            prop::collection::vec(prop::collection::vec(value_of(item), 0..5), count).prop_map(move |data| Prop {
                name: name.clone(),
                ty: PlyType::List { count: c, item },
                data,
            })
        })
        .boxed();
    prop_oneof![scalar_prop, list_prop].boxed()
}

fn random_file() -> impl Strategy<Value = File> {
    (
        1usize..8,
        0usize..5,
        0usize..4,
        0usize..3,
        0usize..4,
        prop::sample::select(vec![PlyScalar::Float, PlyScalar::Double, PlyScalar::Short, PlyScalar::UChar]),
    )
        .prop_flat_map(|(n, faces, extra_vertex, extra_face, extra_count, xyz)| {
            let coordinates = prop::collection::vec(value_of(xyz), 3 * n);
            let polygons = prop::collection::vec(prop::collection::vec(0..n as u32, 3..7), faces);
            let index_types = (
                int_scalar(),
                prop::sample::select(vec![
                    PlyScalar::Char,
                    PlyScalar::UChar,
                    PlyScalar::Int,
                    PlyScalar::UInt,
                    PlyScalar::UShort,
                ]),
            );
            let vertex_props: Vec<_> = (0..extra_vertex).map(|k| random_prop(format!("p{k}"), n, false)).collect();
            let face_props: Vec<_> = (0..extra_face).map(|k| random_prop(format!("f{k}"), faces, true)).collect();
            let extra_props: Vec<_> = (0..2).map(|k| random_prop(format!("e{k}"), extra_count, true)).collect();
            let comment = "[a-z ]{0,12}";
            (Just((n, xyz)), coordinates, polygons, index_types, vertex_props, face_props, extra_props, comment)
        })
        .prop_map(
            |((n, xyz), coordinates, polygons, (count, item), vertex_props, face_props, extra_props, comment)| {
                let axis = |a: usize| (0..n).map(|i| coordinates[3 * i + a]).collect::<Vec<_>>();
                let mut vertex =
                    vec![scalar("x", xyz, &axis(0)), scalar("y", xyz, &axis(1)), scalar("z", xyz, &axis(2))];
                // Extra properties before, between and after the coordinates: interleave.
                for (k, p) in vertex_props.into_iter().enumerate() {
                    vertex.insert((2 * k) % (vertex.len() + 1), p);
                }
                let lists: Vec<Vec<f64>> = polygons.iter().map(|p| p.iter().map(|&v| f64::from(v)).collect()).collect();
                let mut face =
                    vec![Prop { name: "vertex_indices".into(), ty: PlyType::List { count, item }, data: lists }];
                face.extend(face_props);
                let extra_count = extra_props.first().map_or(0, |p| p.data.len());
                File {
                    comments: vec![comment],
                    elements: vec![
                        Element { name: "extra".into(), count: extra_count, props: extra_props },
                        Element { name: "vertex".into(), count: n, props: vertex },
                        Element { name: "face".into(), count: polygons.len(), props: face },
                    ],
                }
            },
        )
}

fn any_encoding() -> impl Strategy<Value = PlyEncoding> {
    prop::sample::select(ENCODINGS.to_vec())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn random_files_round_trip_exactly(file in random_file(), encoding in any_encoding(), other in any_encoding()) {
        let bytes = encode(&file, encoding);
        let first = read("random.ply", &bytes);
        assert_holds(attributes(&first.mesh), &file);
        // In its own encoding: the same bytes, so reading them again is the identity.
        let mut same = Vec::new();
        ply::write_ply(&mut same, &first.mesh, &first.mesh.attributes, None, &mut Warnings::new()).unwrap();
        prop_assert_eq!(&same, &bytes);
        // In another: the same content.
        let mut converted = Vec::new();
        ply::write_ply(&mut converted, &first.mesh, &first.mesh.attributes, Some(other), &mut Warnings::new()).unwrap();
        prop_assert_eq!(&converted, &encode(&file, other));
        let back = read("random.ply", &converted);
        assert_same_content(attributes(&first.mesh), attributes(&back.mesh));
        prop_assert_eq!(bits(&back.mesh.positions), bits(&first.mesh.positions));
        prop_assert_eq!(&back.mesh.polygons, &first.mesh.polygons);
    }
}

#[test]
fn read_mesh_on_a_written_rich_file_gives_the_same_mesh() {
    // Through the file system and the extension dispatch, too.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rich.ply");
    fs::write(&path, encode(&rich(), PlyEncoding::BinaryLittleEndian)).unwrap();
    let loaded = read_mesh(&path).unwrap();
    let again = dir.path().join("again.ply");
    write_mesh_with(&again, &loaded.mesh, &loaded.attributes, WriteFormat::Ply(None)).unwrap();
    assert_eq!(fs::read(&again).unwrap(), fs::read(&path).unwrap());
}

#[test]
fn a_stray_carriage_return_before_a_keyword_reads_back_the_same() {
    // Found by the attribute_roundtrip fuzz target: "ply\n\rformat ..." was read (the keyword
    // is found between whitespace), kept raw and written back raw, and the copy read as a
    // header without its format line.
    let text = b"ply\n\rformat ascii 1.0\ncomment  two spaces kept \nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let first = read("cr.ply", text);
    let (bytes, _) = write(&first.mesh, None);
    let second = read("copy.ply", &bytes);
    let (a, b) = (attributes(&first.mesh), attributes(&second.mesh));
    assert_eq!(a.header_lines(), b.header_lines());
    assert_eq!(a.header_lines()[0], "format ascii 1.0");
    assert_eq!(a.header_lines()[1], "comment  two spaces kept ");
}
