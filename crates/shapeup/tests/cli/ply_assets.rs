//! Real PLY assets through `shapeup deform`: a coloured binary file with custom properties
//! comes out with every element, property, type, header line and its encoding; only the
//! coordinates of what moved change.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::DVec3;
use shapeup_core::Mesh;
use shapeup_core::attributes::Attributes;
use shapeup_core::io::ply::{PlyAttributes, PlyEncoding, PlyType};
use shapeup_core::io::read_mesh;

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");

/// Writes spot's positions (as `float`) and faces as a big-endian binary PLY with colours, a
/// `float confidence`, an `int segment`, a `material` element and a face property.
fn coloured_spot(path: &Path) {
    let spot = read_mesh(Path::new(SPOT)).unwrap().mesh;
    let n = spot.num_vertices();
    let mut bytes = format!(
        "ply\nformat binary_big_endian 1.0\ncomment spot, coloured by hand\nobj_info test asset\n\
         element vertex {n}\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nproperty float confidence\n\
         property int segment\nelement material 1\nproperty list uchar uchar name\n\
         element face {}\nproperty list uchar int vertex_indices\nproperty ushort part\nend_header\n",
        spot.num_polygons()
    )
    .into_bytes();
    for (i, p) in spot.positions.iter().enumerate() {
        for x in p.to_array() {
            bytes.extend_from_slice(&(x as f32).to_be_bytes());
        }
        bytes.extend_from_slice(&[(i % 256) as u8, (i * 7 % 256) as u8, 255 - (i % 256) as u8]);
        bytes.extend_from_slice(&(i as f32 / n as f32).to_be_bytes());
        bytes.extend_from_slice(&(i as i32 - 1000).to_be_bytes());
    }
    bytes.push(4);
    bytes.extend_from_slice(b"skin");
    for (f, poly) in spot.polygons.iter().enumerate() {
        bytes.push(poly.len() as u8);
        for &v in poly {
            bytes.extend_from_slice(&(v as i32).to_be_bytes());
        }
        bytes.extend_from_slice(&((f % 5) as u16).to_be_bytes());
    }
    std::fs::write(path, bytes).unwrap();
}

/// A scene on `mesh`: edge springs, the slab −0.2 ≤ z ≤ −0.1 fixed, the head (z ≥ 0.8) moved
/// by `translate`.
fn scene(dir: &Path, mesh: &Path, translate: [f64; 3]) -> PathBuf {
    let [tx, ty, tz] = translate;
    let text = format!(
        r#"[mesh]
path = '{}'

[solver]
iterations = 20

[[constraints]]
type = "edge_spring"
weight = 10.0

[[constraints]]
type = "position"
name = "fixed"
weight = 100.0
box = {{ min = [-2, -2, -0.2], max = [2, 2, -0.1] }}

[[constraints]]
type = "position"
name = "moved"
weight = 100.0
box = {{ min = [-2, -2, 0.8], max = [2, 2, 2] }}
translate = [{tx:?}, {ty:?}, {tz:?}]
"#,
        mesh.display()
    );
    let path = dir.join(format!("scene-{tx}-{ty}-{tz}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `shapeup deform SCENE -o OUTPUT` and reads the output back.
fn deform(scene: &Path, output: &Path) -> Mesh {
    let out = Command::new(env!("CARGO_BIN_EXE_shapeup"))
        .args(["deform".as_ref(), scene.as_os_str(), "-o".as_ref(), output.as_os_str()])
        .output()
        .expect("cannot run the shapeup binary");
    assert!(
        out.status.success(),
        "shapeup deform failed:\n{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    read_mesh(output).unwrap_or_else(|e| panic!("cannot read back {}: {e}", output.display())).mesh
}

/// The PLY attributes of the file at `path`.
fn attributes(path: &Path) -> Box<PlyAttributes> {
    match read_mesh(path).unwrap().attributes {
        Attributes::Ply(a) => a,
        other => panic!("the output is not read as PLY: {other:?}"),
    }
}

fn is_coordinate(element: &str, property: &str) -> bool {
    element == "vertex" && ["x", "y", "z"].contains(&property)
}

/// Asserts that every element and property (but x y z), with its type and values bit for bit,
/// every header line and the encoding are the same.
fn assert_same_but_coordinates(input: &PlyAttributes, output: &PlyAttributes) {
    assert_eq!(output.encoding(), input.encoding());
    assert_eq!(output.header_lines(), input.header_lines());
    assert_eq!(output.elements().len(), input.elements().len());
    for (a, b) in input.elements().iter().zip(output.elements()) {
        assert_eq!((a.name(), a.count()), (b.name(), b.count()));
        for (p, q) in a.properties().iter().zip(b.properties()) {
            assert_eq!((p.name(), p.ty()), (q.name(), q.ty()), "element {}", a.name());
            if is_coordinate(a.name(), p.name()) {
                continue;
            }
            let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert!(bits(p.values()) == bits(q.values()), "{} property {} changed", a.name(), p.name());
            assert_eq!(p.offsets(), q.offsets());
        }
    }
}

#[test]
fn deform_with_a_zero_translation_gives_the_input_back() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spot-coloured.ply");
    coloured_spot(&input);
    let rest = read_mesh(&input).unwrap().mesh;
    let output = dir.path().join("out.ply");
    let result = deform(&scene(dir.path(), &input, [0.0; 3]), &output);
    let (a, b) = (attributes(&input), attributes(&output));
    assert_eq!(b.encoding(), PlyEncoding::BinaryBigEndian);
    assert_same_but_coordinates(&a, &b);
    assert_eq!(
        b.element("vertex").unwrap().property("x").unwrap().ty(),
        PlyType::Scalar(shapeup_core::io::ply::PlyScalar::Float)
    );
    // At rest the solver returns the input up to its round-off, which f32 keeps only near 0.
    let worst = rest.positions.iter().zip(&result.positions).map(|(p, q)| (*p - *q).length()).fold(0.0, f64::max);
    let (lo, hi) = rest.bounding_box();
    assert!(worst <= 1e-9 * (hi - lo).length(), "positions moved by up to {worst}");
    // Same layout: as many bytes.
    assert_eq!(std::fs::metadata(&output).unwrap().len(), std::fs::metadata(&input).unwrap().len());
}

#[test]
fn deform_with_a_translation_changes_only_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("spot-coloured.ply");
    coloured_spot(&input);
    let rest = read_mesh(&input).unwrap().mesh;
    let output = dir.path().join("out.ply");
    let t = DVec3::new(0.0, 0.2, 0.1);
    let result = deform(&scene(dir.path(), &input, t.to_array()), &output);
    assert_same_but_coordinates(&attributes(&input), &attributes(&output));
    assert_eq!(result.polygons, rest.polygons);
    // The head followed its handle; the fixed slab stayed (to the solver's accuracy, in f32).
    let mut moved = 0;
    for (p, q) in rest.positions.iter().zip(&result.positions) {
        if p.z >= 0.8 {
            assert!((*q - *p - t).length() < 0.01 * t.length(), "{p} → {q}");
            moved += 1;
        } else if (-0.2..=-0.1).contains(&p.z) {
            assert!((*q - *p).length() < 0.01 * t.length(), "{p} → {q}");
        }
    }
    assert!(moved > 10);
    assert!(rest.positions.iter().zip(&result.positions).any(|(p, q)| p != q));
}
