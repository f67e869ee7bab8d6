//! `.vtu` and `.pvd` output, read back independently of the writer's crate: the XML with
//! quick-xml, each inline binary array decoded by hand (base64 of a little-endian `UInt64` byte
//! count followed by the little-endian values), as VTK's reader does.

use base64::Engine;
use glam::DVec3;
use quick_xml::events::{BytesStart, Event};
use shapeup_core::Mesh;
use shapeup_core::generate::tet_box;
use shapeup_core::io::vtu::{PointVectors, write_pvd, write_vtu};
use shapeup_core::io::{AttributeKind, Attributes, read_mesh, write_mesh};
use shapeup_core::mesh::Polygons;
use shapeup_core::warnings::Warnings;
use std::collections::HashMap;

use crate::file_mesh::FileMesh;
use std::io::ErrorKind;

/// One `<DataArray>`: its attributes, the element it sits in and its text.
#[derive(Debug)]
struct Array {
    parent: String,
    attributes: HashMap<String, String>,
    text: String,
}

impl Array {
    fn attribute(&self, key: &str) -> &str {
        self.attributes.get(key).map_or("", String::as_str)
    }

    fn components(&self) -> usize {
        self.attributes.get("NumberOfComponents").map_or(1, |c| c.parse().unwrap())
    }

    /// The decoded bytes after checking the byte-count header.
    fn bytes(&self) -> Vec<u8> {
        assert_eq!(self.attribute("format"), "binary", "inline base64");
        let raw = base64::engine::general_purpose::STANDARD.decode(self.text.trim()).unwrap();
        let count = u64::from_le_bytes(raw[..8].try_into().unwrap());
        assert_eq!(count as usize, raw.len() - 8, "the UInt64 header counts the bytes that follow");
        raw[8..].to_vec()
    }

    fn floats(&self) -> Vec<f64> {
        assert_eq!(self.attribute("type"), "Float64");
        self.bytes().chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect()
    }

    fn integers(&self) -> Vec<u64> {
        match self.attribute("type") {
            "UInt8" => self.bytes().into_iter().map(u64::from).collect(),
            "UInt64" | "Int64" => {
                self.bytes().chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().unwrap())).collect()
            }
            "Int32" | "UInt32" => {
                self.bytes().chunks_exact(4).map(|c| u64::from(u32::from_le_bytes(c.try_into().unwrap()))).collect()
            }
            other => panic!("unexpected integer type {other}"),
        }
    }
}

/// A parsed `.vtu`: the attributes of `<VTKFile>`, `<Piece>` and `<PointData>`, and every array.
#[derive(Debug, Default)]
struct Vtu {
    file: HashMap<String, String>,
    grid: bool,
    piece: HashMap<String, String>,
    point_data: HashMap<String, String>,
    arrays: Vec<Array>,
}

impl Vtu {
    fn array(&self, parent: &str, name: &str) -> &Array {
        self.arrays
            .iter()
            .find(|a| a.parent == parent && a.attribute("Name") == name)
            .unwrap_or_else(|| panic!("no {parent}/{name} array in {:?}", self.arrays))
    }

    /// The points, as written.
    fn points(&self) -> Vec<DVec3> {
        let points: Vec<&Array> = self.arrays.iter().filter(|a| a.parent == "Points").collect();
        assert_eq!(points.len(), 1);
        assert_eq!(points[0].components(), 3);
        points[0].floats().chunks_exact(3).map(DVec3::from_slice).collect()
    }

    fn point_arrays(&self) -> Vec<&str> {
        self.arrays.iter().filter(|a| a.parent == "PointData").map(|a| a.attribute("Name")).collect()
    }

    fn count(&self, key: &str) -> usize {
        self.piece[key].parse().unwrap()
    }
}

fn attributes(e: &BytesStart<'_>) -> HashMap<String, String> {
    e.attributes()
        .map(|a| {
            let a = a.unwrap();
            (String::from_utf8(a.key.as_ref().to_vec()).unwrap(), a.unescape_value().unwrap().into_owned())
        })
        .collect()
}

fn parse_vtu(xml: &str) -> Vtu {
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut vtu = Vtu::default();
    let mut stack: Vec<String> = Vec::new();
    let mut current: Option<Array> = None;
    loop {
        match reader.read_event().unwrap() {
            Event::Start(e) if e.name().as_ref() == b"DataArray" => {
                let parent = stack.last().cloned().unwrap_or_default();
                current = Some(Array { parent, attributes: attributes(&e), text: String::new() });
            }
            Event::Text(t) => {
                if let Some(a) = &mut current {
                    a.text.push_str(&t.unescape().unwrap());
                }
            }
            Event::End(e) if e.name().as_ref() == b"DataArray" => vtu.arrays.extend(current.take()),
            Event::Start(e) => {
                let name = String::from_utf8(e.name().as_ref().to_vec()).unwrap();
                match name.as_str() {
                    "VTKFile" => vtu.file = attributes(&e),
                    "UnstructuredGrid" => vtu.grid = true,
                    "Piece" => vtu.piece = attributes(&e),
                    "PointData" => vtu.point_data = attributes(&e),
                    _ => {}
                }
                stack.push(name);
            }
            Event::End(_) => {
                stack.pop();
            }
            Event::Empty(e) => assert_ne!(e.name().as_ref(), b"DataArray", "an array without data"),
            Event::Eof => break,
            _ => {}
        }
    }
    vtu
}

fn vtu_of(mesh: &Mesh, attributes: &Attributes, vectors: &[PointVectors<'_>]) -> (Vtu, Warnings) {
    let mut out = Vec::new();
    let mut warnings = Warnings::new();
    write_vtu(&mut out, mesh, attributes, vectors, &mut warnings).unwrap();
    (parse_vtu(&String::from_utf8(out).unwrap()), warnings)
}

/// The cells' connectivity of the VTU file written from `mesh` with `attributes`.
pub(crate) fn connectivity_of(mesh: &Mesh, attributes: &Attributes) -> Vec<u64> {
    vtu_of(mesh, attributes, &[]).0.array("Cells", "connectivity").integers()
}

fn assert_same_bits(a: &[DVec3], b: &[DVec3]) {
    assert_eq!(a.len(), b.len());
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits), "point {i}: {p} vs {q}");
    }
}

#[test]
fn tet_box_is_written_as_tetrahedra_with_exact_points_and_vectors() {
    let mut mesh = FileMesh::from(tet_box([2, 1, 1], DVec3::new(2.0, 1.0, 1.0)));
    // Coordinates that a short decimal would not keep.
    for p in &mut mesh.positions {
        *p = *p * (1.0 / 3.0) + DVec3::new(1e-17, -2.5e10, 0.1);
    }
    let velocity: Vec<DVec3> = (0..mesh.positions.len()).map(|i| DVec3::new(i as f64 / 7.0, -9.81, 1e300)).collect();
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[PointVectors { name: "velocity", values: &velocity }]);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert!(vtu.grid, "an UnstructuredGrid");
    assert_eq!(vtu.file["type"], "UnstructuredGrid");
    assert_eq!(vtu.file["version"], "1.0", "UInt64 headers need format 1.0");
    assert_eq!(vtu.file["header_type"], "UInt64");
    assert_eq!(vtu.file["byte_order"], "LittleEndian");
    assert_eq!(vtu.count("NumberOfPoints"), 12);
    assert_eq!(vtu.count("NumberOfCells"), 12);
    assert_same_bits(&vtu.points(), &mesh.positions);

    let connectivity = vtu.array("Cells", "connectivity").integers();
    let expected: Vec<u64> = mesh.tetrahedra.iter().flatten().map(|&v| u64::from(v)).collect();
    assert_eq!(connectivity, expected);
    assert_eq!(vtu.array("Cells", "offsets").integers(), (1..=12).map(|i| 4 * i).collect::<Vec<u64>>());
    assert_eq!(vtu.array("Cells", "types").integers(), vec![10; 12], "VTK_TETRA");

    assert_eq!(vtu.point_arrays(), ["velocity"]);
    assert_eq!(vtu.point_data.get("Vectors").map(String::as_str), Some("velocity"));
    let v = vtu.array("PointData", "velocity");
    assert_eq!(v.components(), 3);
    let back: Vec<DVec3> = v.floats().chunks_exact(3).map(DVec3::from_slice).collect();
    assert_same_bits(&back, &velocity);
}

#[test]
fn polygons_keep_their_corner_counts_and_unreferenced_points() {
    // A triangle, a quad and a pentagon sharing edges, and a vertex in no face at the end.
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.5, 1.0, 0.0),
        DVec3::new(2.0, 0.0, 0.1),
        DVec3::new(1.5, 1.0, -0.1),
        DVec3::new(3.0, 0.0, 0.0),
        DVec3::new(3.5, 1.0, 0.0),
        DVec3::new(2.5, 2.0, 0.0),
        DVec3::new(0.1, 0.2, 1.0 / 3.0),
    ];
    let polygons: Polygons = [&[0u32, 1, 2][..], &[1, 3, 4, 2], &[3, 5, 6, 7, 4]].into_iter().collect();
    let mesh = FileMesh::from(Mesh::from_polygons(positions.clone(), polygons).unwrap().0);
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[]);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(vtu.count("NumberOfPoints"), 9, "the vertex in no face too");
    assert_eq!(vtu.count("NumberOfCells"), 3, "one cell per polygon, not per triangle");
    assert_same_bits(&vtu.points(), &positions);
    assert_eq!(vtu.array("Cells", "connectivity").integers(), [0, 1, 2, 1, 3, 4, 2, 3, 5, 6, 7, 4]);
    assert_eq!(vtu.array("Cells", "offsets").integers(), [3, 7, 12]);
    assert_eq!(vtu.array("Cells", "types").integers(), [5, 9, 7], "VTK_TRIANGLE, VTK_QUAD, VTK_POLYGON");
    assert!(vtu.point_arrays().is_empty());
}

#[test]
fn write_mesh_writes_vtu_atomically_by_extension() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("box.vtu");
    let mesh = tet_box([1, 1, 1], DVec3::ONE);
    let warnings = write_mesh(&path, &mesh, &Attributes::None).unwrap();
    assert!(warnings.is_empty());
    let vtu = parse_vtu(&std::fs::read_to_string(&path).unwrap());
    assert_eq!((vtu.count("NumberOfPoints"), vtu.count("NumberOfCells")), (8, 6));
    let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "no temp file left: {names:?}");
}

/// An OFF file with normals, colours and texture coordinates per vertex and a colour per face:
/// the first three become point arrays (normals recomputed from the geometry), the face colours
/// are reported as dropped.
#[test]
fn attributes_become_point_arrays_and_the_rest_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let off = dir.path().join("square.off");
    std::fs::write(
        &off,
        "STCNOFF\n5 1 0\n\
         0 0 0  1 0 0  1 0 0 1  0 0\n\
         1 0 0  1 0 0  0 1 0 1  1 0\n\
         1 1 0  1 0 0  0 0 1 1  1 1\n\
         0 1 0  1 0 0  0.25 0.5 0.75 1  0 1\n\
         5 5 5  1 0 0  1 1 1 1  0.5 0.5\n\
         4 0 1 2 3  1 0 0\n",
    )
    .unwrap();
    let mesh = FileMesh::from(read_mesh(&off).unwrap());
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[]);
    assert_eq!(vtu.point_arrays(), ["normals", "color", "texcoords"]);
    assert_eq!(vtu.point_data.get("Normals").map(String::as_str), Some("normals"));
    assert_eq!(vtu.point_data.get("TCoords").map(String::as_str), Some("texcoords"));
    let normals = vtu.array("PointData", "normals").floats();
    let up = [0.0, 0.0, 1.0];
    assert_eq!(normals, [up, up, up, up, [0.0; 3]].concat(), "recomputed (not the file's 1 0 0); zero in no face");
    let colors = vtu.array("PointData", "color");
    assert_eq!(colors.components(), 3);
    assert_eq!(
        colors.floats(),
        [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.25, 0.5, 0.75, 1.0, 1.0, 1.0],
        "r g b per vertex"
    );
    let uv = vtu.array("PointData", "texcoords");
    assert_eq!(uv.components(), 2);
    assert_eq!(uv.floats(), [0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0], "(0, 0) for the vertex in no face");
    assert_eq!(warnings.count("attributes_dropped"), 1, "{warnings:?}");
    let dropped: Vec<&str> = warnings.iter().map(|w| w.first.as_str()).collect();
    for kept in [AttributeKind::Normals, AttributeKind::VertexColors, AttributeKind::TexCoords] {
        assert!(!dropped.contains(&kept.describe().as_str()), "{dropped:?}");
    }
}

/// Per-vertex PLY properties become scalar arrays under their own names.
#[test]
fn ply_vertex_properties_become_scalar_arrays() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("t.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\nproperty double z\n\
         property float confidence\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0 0.5\n1 0 0 0.25\n0 1 0 -2\n3 0 1 2\n",
    )
    .unwrap();
    let mesh = FileMesh::from(read_mesh(&ply).unwrap());
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[]);
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(vtu.point_arrays(), ["confidence"]);
    assert_eq!(vtu.point_data.get("Scalars").map(String::as_str), Some("confidence"));
    assert_eq!(vtu.array("PointData", "confidence").floats(), [0.5, 0.25, -2.0]);

    // A property named like the caller's array gives way to it, with a warning.
    std::fs::write(&ply, std::fs::read_to_string(&ply).unwrap().replace("confidence", "velocity")).unwrap();
    let mesh = FileMesh::from(read_mesh(&ply).unwrap());
    let velocity = vec![DVec3::X; 3];
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[PointVectors { name: "velocity", values: &velocity }]);
    assert_eq!(vtu.point_arrays(), ["velocity"]);
    assert_eq!(vtu.array("PointData", "velocity").components(), 3);
    assert_eq!(warnings.count("point_data_dropped"), 1, "{warnings:?}");
}

#[test]
fn bad_point_data_is_refused_before_anything_is_written() {
    let mesh = tet_box([1, 1, 1], DVec3::ONE);
    let short = vec![DVec3::ZERO; 3];
    let mut out = Vec::new();
    let err = write_vtu(
        &mut out,
        &mesh,
        &Attributes::None,
        &[PointVectors { name: "velocity", values: &short }],
        &mut Warnings::new(),
    )
    .unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidInput);
    assert!(err.to_string().contains("velocity"), "{err}");
    let full = vec![DVec3::ZERO; 8];
    let twice = [PointVectors { name: "v", values: &full }, PointVectors { name: "v", values: &full }];
    let err = write_vtu(&mut out, &mesh, &Attributes::None, &twice, &mut Warnings::new()).unwrap_err();
    assert_eq!(err.kind(), ErrorKind::InvalidInput);
    assert!(out.is_empty());
}

#[test]
fn pvd_lists_the_frames_with_their_times() {
    let entries = [(0.0, "frame_0000.vtu"), (0.1, "frame_0006.vtu"), (1.0 / 3.0, "frame_0020.vtu"), (2.5, "a&b.vtu")];
    let mut out = Vec::new();
    write_pvd(&mut out, &entries).unwrap();
    let text = String::from_utf8(out).unwrap();
    let mut reader = quick_xml::Reader::from_str(&text);
    let (mut collection, mut root, mut listed) = (false, HashMap::new(), Vec::new());
    loop {
        match reader.read_event().unwrap() {
            Event::Start(e) if e.name().as_ref() == b"VTKFile" => root = attributes(&e),
            Event::Start(e) if e.name().as_ref() == b"Collection" => collection = true,
            Event::Empty(e) if e.name().as_ref() == b"DataSet" => {
                assert!(collection, "DataSet inside Collection");
                let a = attributes(&e);
                listed.push((a["timestep"].parse::<f64>().unwrap(), a["file"].clone()));
            }
            Event::Eof => break,
            _ => {}
        }
    }
    assert_eq!(root["type"], "Collection");
    let expected: Vec<(f64, String)> = entries.iter().map(|(t, f)| (*t, (*f).to_owned())).collect();
    assert_eq!(listed, expected, "times exact, names unescaped");
}

/// Texture coordinates that differ between the corners of a vertex (a seam) cannot be point
/// data; they and the OBJ groups are reported as dropped.
#[test]
fn per_corner_texture_coordinates_and_groups_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("seam.obj");
    std::fs::write(
        &obj,
        "g square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.5\n\
         f 1/1 2/2 3/3\nf 1/4 3/3 4/4\n",
    )
    .unwrap();
    let mesh = FileMesh::from(read_mesh(&obj).unwrap());
    let (vtu, warnings) = vtu_of(&mesh, &mesh.attributes, &[]);
    assert!(vtu.point_arrays().is_empty(), "{:?}", vtu.point_arrays());
    assert_eq!(warnings.count("attributes_dropped"), 2, "{warnings:?}");
    let texture = AttributeKind::TexCoords.describe();
    assert!(warnings.iter().any(|w| w.first == texture), "{warnings:?}");
}
