//! End-to-end tests of `shapeup simulate --format`: every frame keeps the input's vertices, VTU
//! frames carry velocities and a ParaView time series, MSH frames keep the tetrahedra, and a bad
//! format is refused before anything is written.

use glam::DVec3;
use shapeup_core::Mesh;
use shapeup_core::io::read_mesh;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};


use crate::common::{Output, shapeup_in};

const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../examples");

/// `shapeup simulate SCENE -o DIR EXTRA…`.
fn simulate<S: AsRef<OsStr>>(scene: &Path, dir: &Path, extra: &[S]) -> Output {
    let mut args: Vec<&OsStr> = vec![OsStr::new("simulate"), scene.as_os_str(), OsStr::new("-o"), dir.as_os_str()];
    args.extend(extra.iter().map(AsRef::as_ref));
    shapeup_in(None, args)
}

fn read(path: &Path) -> Mesh {
    read_mesh(path).unwrap_or_else(|e| panic!("cannot read back {}: {e}", path.display())).mesh
}

fn write(path: &Path, text: &str) -> PathBuf {
    std::fs::write(path, text).unwrap();
    path.to_path_buf()
}

/// The sorted file names in `dir`.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

/// A dynamic scene on `mesh` with `body` after `[solver]`'s mode.
fn dynamic_scene(path: &Path, mesh: &str, body: &str) -> PathBuf {
    write(path, &format!("[mesh]\n{mesh}\n[solver]\nmode = \"dynamic\"\n{body}"))
}

// ---- reading VTU and PVD by hand (the CLI crate depends on no XML library) ----

/// Standard base64 (with padding), whitespace ignored.
fn base64_decode(text: &str) -> Vec<u8> {
    let value = |c: u8| -> u32 {
        match c {
            b'A'..=b'Z' => u32::from(c - b'A'),
            b'a'..=b'z' => u32::from(c - b'a') + 26,
            b'0'..=b'9' => u32::from(c - b'0') + 52,
            b'+' => 62,
            b'/' => 63,
            b'=' => 0,
            _ => panic!("not base64: {:?}", c as char),
        }
    };
    let bytes: Vec<u8> = text.bytes().filter(|c| !c.is_ascii_whitespace()).collect();
    assert_eq!(bytes.len() % 4, 0, "padded base64");
    let mut out = Vec::with_capacity(bytes.len() / 4 * 3);
    for chunk in bytes.chunks(4) {
        let n = chunk.iter().fold(0u32, |n, &c| (n << 6) | value(c));
        let pad = chunk.iter().filter(|&&c| c == b'=').count();
        out.extend_from_slice(&[(n >> 16) as u8, (n >> 8) as u8, n as u8][..3 - pad]);
    }
    out
}

/// The opening tag and the text of the first `<DataArray` at or after `from` in `xml`.
fn data_array_at(xml: &str, from: usize) -> (&str, &str) {
    let start = from + xml[from..].find("<DataArray").expect("a DataArray");
    let open_end = start + xml[start..].find('>').unwrap();
    let close = open_end + xml[open_end..].find("</DataArray>").unwrap();
    (&xml[start..=open_end], &xml[open_end + 1..close])
}

/// The `Float64` 3-vectors of a binary inline array (a `UInt64` byte count, then the values).
fn vectors(tag: &str, text: &str) -> Vec<DVec3> {
    assert!(tag.contains("type=\"Float64\"") && tag.contains("NumberOfComponents=\"3\""), "{tag}");
    let bytes = base64_decode(text);
    let count = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    assert_eq!(count, bytes.len() - 8, "{tag}");
    let values: Vec<f64> = bytes[8..].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
    values.chunks_exact(3).map(DVec3::from_slice).collect()
}

/// A `.vtu` frame: its points and its `velocity` point data.
fn read_vtu(path: &Path) -> (Vec<DVec3>, Vec<DVec3>, String) {
    let xml = std::fs::read_to_string(path).unwrap();
    assert!(xml.contains("<UnstructuredGrid>"), "{}", path.display());
    let points_at = xml.find("<Points>").expect("Points");
    let (tag, text) = data_array_at(&xml, points_at);
    let points = vectors(tag, text);
    let name_at = xml.find("Name=\"velocity\"").expect("a velocity array");
    let tag_at = xml[..name_at].rfind("<DataArray").unwrap();
    let (open, close) = (xml.find("<PointData").expect("PointData"), xml.find("</PointData>").unwrap());
    assert!(open < tag_at && tag_at < close, "velocity is point data");
    let (tag, text) = data_array_at(&xml, tag_at);
    let velocity = vectors(tag, text);
    (points, velocity, xml)
}

/// The `(timestep, file)` of each `<DataSet>` of a `.pvd`.
fn read_pvd(path: &Path) -> Vec<(f64, String)> {
    let xml = std::fs::read_to_string(path).unwrap();
    assert!(xml.contains("type=\"Collection\""), "{xml}");
    let attribute = |tag: &str, key: &str| -> String {
        let start = tag.find(&format!(" {key}=\"")).unwrap_or_else(|| panic!("no {key} in {tag}")) + key.len() + 3;
        tag[start..start + tag[start..].find('"').unwrap()].to_owned()
    };
    xml.split("<DataSet ")
        .skip(1)
        .map(|rest| {
            let tag = format!(" {}", &rest[..rest.find("/>").unwrap()]);
            (attribute(&tag, "timestep").parse().unwrap(), attribute(&tag, "file"))
        })
        .collect()
}

// ---- tests ----

/// One triangle (falling freely) among vertices no face uses, at the end, the start and in the
/// middle of the file: every OBJ and PLY frame has the input's vertex count and order, and the
/// unused vertices keep their input coordinates bit for bit.
#[test]
fn every_frame_keeps_the_input_vertices_and_unused_ones_stay() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("end.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0.3 0.7 2.9\nf 1 2 3\n", vec![3]),
        (
            "start-middle.obj",
            "v -0.1 9.7 3.3\nv 0 0 0\nv 0.1 5.3 -7.7\nv 0.2 0.4 1.9\nv 1 0 0\nv 0 1 0\nf 2 5 6\n",
            vec![0, 2, 3],
        ),
    ];
    for (name, text, unused) in cases {
        let input = read(&write(&dir.path().join(name), text));
        let scene = dynamic_scene(
            &dir.path().join(format!("{name}.toml")),
            &format!("path = '{name}'"),
            "time_step = 0.01\ngravity = [0.0, -10.0, 0.0]\n",
        );
        for format in ["obj", "ply"] {
            let out_dir = dir.path().join(format!("{name}-{format}"));
            simulate(&scene, &out_dir, &["--frames", "3", "--format", format]).success();
            let expected: Vec<String> = (0..=3).map(|k| format!("frame_000{k}.{format}")).collect();
            assert_eq!(entries(&out_dir), expected);
            for file in &expected {
                let frame = read(&out_dir.join(file));
                assert_eq!(frame.num_vertices(), input.num_vertices(), "{name} {file}");
                for &v in &unused {
                    assert_eq!(
                        frame.positions[v].to_array().map(f64::to_bits),
                        input.positions[v].to_array().map(f64::to_bits),
                        "{name} {file}: unused vertex {v} moved: {} -> {}",
                        input.positions[v],
                        frame.positions[v]
                    );
                }
            }
            // The triangle itself falls (so the frames are not all the input).
            let last = read(&out_dir.join(&expected[3]));
            let used = (0..input.num_vertices()).find(|v| !unused.contains(v)).unwrap();
            assert!(last.positions[used].y < input.positions[used].y - 1e-3, "{name}: the triangle did not fall");
        }
    }
}

/// A free fall written as VTU: the velocity of frame k is g t_k in input units, and matches the
/// finite difference of the positions of frames k − 1 and k; `frames.pvd` lists every frame
/// with its time.
#[test]
fn vtu_frames_carry_the_velocity_and_a_time_series() {
    let dir = tempfile::tempdir().unwrap();
    let (h, g) = (0.01, -10.0);
    // 2 m wide and normalized: the working frame's scale is not 1, so the velocity must be
    // mapped back to input units.
    let scene = dynamic_scene(
        &dir.path().join("fall.toml"),
        "generate = { kind = \"cloth\", vertices = [3, 3], size = [2.0, 2.0] }\nnormalize = true",
        &format!("time_step = {h}\ngravity = [0.0, {g:?}, 0.0]\n"),
    );
    let out_dir = dir.path().join("frames");
    simulate(&scene, &out_dir, &["--frames", "5", "--format", "vtu"]).success();
    let mut expected: Vec<String> = (0..=5).map(|k| format!("frame_000{k}.vtu")).collect();
    expected.push("frames.pvd".into());
    assert_eq!(entries(&out_dir), expected);

    let frames: Vec<(Vec<DVec3>, Vec<DVec3>, String)> =
        (0..=5).map(|k| read_vtu(&out_dir.join(format!("frame_000{k}.vtu")))).collect();
    let relative = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(frames[0].1.iter().all(|v| *v == DVec3::ZERO), "at rest at t = 0");
    for k in 1..=5 {
        let ((previous, _, _), (points, velocity, xml)) = (&frames[k - 1], &frames[k]);
        assert!(xml.contains("NumberOfPoints=\"9\""), "frame {k}");
        assert_eq!(velocity.len(), 9);
        let t = k as f64 * h;
        for (i, v) in velocity.iter().enumerate() {
            assert!(relative(v.y, g * t) < 1e-9, "frame {k} vertex {i}: v = {v}, g t = {}", g * t);
            assert!(v.x.abs() < 1e-12 && v.z.abs() < 1e-12, "frame {k} vertex {i}: v = {v}");
            let difference = (points[i] - previous[i]) / h;
            assert!(
                relative(difference.y, v.y) < 1e-9,
                "frame {k} vertex {i}: (x_k − x_(k−1))/h = {difference}, v = {v}"
            );
        }
    }

    let listed = read_pvd(&out_dir.join("frames.pvd"));
    assert_eq!(listed.len(), 6);
    for (k, (time, file)) in listed.iter().enumerate() {
        assert_eq!(file, &format!("frame_000{k}.vtu"));
        assert!((time - k as f64 * h).abs() < 1e-15, "frame {k} at {time} s");
    }
}

/// `--format msh` (and `vtu`) write the whole bar of the bar-twist example with its tetrahedra.
#[test]
fn msh_and_vtu_frames_keep_the_tetrahedra() {
    let dir = tempfile::tempdir().unwrap();
    let scene = Path::new(EXAMPLES).join("bar-twist.toml");
    let msh_dir = dir.path().join("msh");
    simulate(&scene, &msh_dir, &["--frames", "2", "--format", "msh"]).success();
    assert_eq!(entries(&msh_dir), ["frame_0000.msh", "frame_0001.msh", "frame_0002.msh"]);
    let (rest, last) = (read(&msh_dir.join("frame_0000.msh")), read(&msh_dir.join("frame_0002.msh")));
    // 16 × 4 × 4 cubes of 6 tetrahedra, 17 × 5 × 5 vertices.
    for frame in [&rest, &last] {
        assert_eq!(frame.num_tetrahedra(), 16 * 4 * 4 * 6);
        assert_eq!(frame.num_vertices(), 17 * 5 * 5);
    }
    assert_eq!(rest.tetrahedra, last.tetrahedra);
    assert!(rest.positions.iter().zip(&last.positions).any(|(a, b)| a != b), "the turning end moved");

    let vtu_dir = dir.path().join("vtu");
    simulate(&scene, &vtu_dir, &["--frames", "1", "--format", "vtu"]).success();
    let (points, velocity, xml) = read_vtu(&vtu_dir.join("frame_0001.vtu"));
    assert_eq!((points.len(), velocity.len()), (425, 425));
    assert!(xml.contains(&format!("NumberOfCells=\"{}\"", 16 * 4 * 4 * 6)), "one cell per tetrahedron");
}

/// What writing frames drops is said once (from the first frame), after the load warnings, on
/// stderr and in the report.
#[test]
fn frame_warnings_are_printed_once_and_reported() {
    let dir = tempfile::tempdir().unwrap();
    // A group, texture coordinates with a seam (per corner) and a quad (triangulated on load).
    write(
        &dir.path().join("seam.obj"),
        "g square\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 2 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0.5 0.5\n\
         f 1/1 2/2 3/3\nf 1/4 3/3 4/4\nf 2 5 6 3\n",
    );
    let scene = dynamic_scene(&dir.path().join("s.toml"), "path = 'seam.obj'", "");
    let (out_dir, report) = (dir.path().join("frames"), dir.path().join("r.json"));
    let out = simulate(
        &scene,
        &out_dir,
        &[
            OsStr::new("--frames"),
            OsStr::new("4"),
            OsStr::new("--format"),
            OsStr::new("vtu"),
            OsStr::new("--report"),
            report.as_os_str(),
        ],
    )
    .success();
    let lines: Vec<&str> = out.stderr.lines().filter(|l| l.starts_with("shapeup: warning: ")).collect();
    let dropped: Vec<&&str> = lines.iter().filter(|l| l.contains("VTU")).collect();
    assert_eq!(dropped.len(), 1, "once, not once per frame\n{}", out.stderr);
    assert!(dropped[0].contains("frame_0000.vtu") && dropped[0].contains("texture coordinates"), "{}", dropped[0]);
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    let warnings = report["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), lines.len(), "the same warnings in the report\n{report:#}");
    assert!(warnings.iter().any(|w| w["kind"] == "attributes_dropped" && w["count"] == 2), "{report:#}");
    let load = warnings.iter().filter(|w| w["file"].as_str().is_some_and(|f| f.ends_with("seam.obj"))).count();
    assert!(load >= 1, "the load warnings come first and stay\n{report:#}");
}

/// A bad `--format` is one line of error, a non-zero exit and no output at all.
#[test]
fn bad_format_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dynamic_scene(
        &dir.path().join("s.toml"),
        "generate = { kind = \"cloth\", vertices = [3, 3], size = [1.0, 1.0] }",
        "",
    );
    let out_dir = dir.path().join("frames");
    let report = dir.path().join("r.json");
    for bad in ["gltf", "", "frame.obj"] {
        let out = simulate(
            &scene,
            &out_dir,
            &[
                OsStr::new("--frames"),
                OsStr::new("2"),
                OsStr::new("--format"),
                OsStr::new(bad),
                OsStr::new("--report"),
                report.as_os_str(),
            ],
        );
        assert_eq!(out.code, Some(1), "{}", out.describe());
        let lines: Vec<&str> = out.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(lines.len(), 1, "{}", out.describe());
        assert!(lines[0].contains("--format") && lines[0].contains(&format!("\"{bad}\"")), "{}", lines[0]);
        assert!(lines[0].contains("obj, ply, off, stl, vtu, msh"), "{}", lines[0]);
        assert!(!out_dir.exists() && !report.exists(), "nothing written for --format {bad:?}");
    }
    // Upper case names the same formats.
    simulate(&scene, &out_dir, &["--frames", "1", "--format", "OBJ"]).success();
    assert_eq!(entries(&out_dir), ["frame_0000.obj", "frame_0001.obj"]);
}
