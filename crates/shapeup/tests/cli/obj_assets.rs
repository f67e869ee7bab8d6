//! Real OBJ assets through `shapeup deform`: the output is the input file line for line, with
//! only vertex coordinates (and recomputed normals) changed — texture coordinates, faces
//! (quads stay quads), objects, smoothing groups, materials and comments come out unchanged.

use std::path::PathBuf;
use std::process::Command;

use glam::DVec3;

const SPOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/spot.obj");
const SUZANNE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");
const BEETLE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/beetle.obj");

/// Runs `shapeup deform SCENE -o OUT` in a fresh temp dir for a scene on `mesh` with `body`
/// after `[mesh]`; returns the output file's text and the process's stderr.
fn deform(mesh: &str, body: &str) -> (String, String) {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(&scene, format!("[mesh]\npath = '{mesh}'\n\n{body}")).unwrap();
    let output: PathBuf = dir.path().join("out.obj");
    let out = Command::new(env!("CARGO_BIN_EXE_shapeup"))
        .arg("deform")
        .arg(&scene)
        .arg("-o")
        .arg(&output)
        .output()
        .expect("cannot run the shapeup binary");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "shapeup deform failed\n{stderr}");
    (std::fs::read_to_string(&output).unwrap(), stderr)
}

/// Edge springs on the whole mesh, a `position` handle on `handle` moved by `translate` and a
/// fixed group on `fixed`.
fn scene_body(handle: &[usize], translate: [f64; 3], fixed: &[usize]) -> String {
    format!(
        "[solver]\niterations = 20\n\n[[constraints]]\ntype = \"edge_spring\"\n\n\
         [[constraints]]\ntype = \"position\"\nname = \"handle\"\nvertices = {handle:?}\ntranslate = {translate:?}\n\n\
         [[constraints]]\ntype = \"position\"\nname = \"fixed\"\nvertices = {fixed:?}\n"
    )
}

/// The x y z of a `v`/`vn` line and the text after them.
fn numbers<'a>(line: &'a str, keyword: &str) -> (DVec3, &'a str) {
    let mut rest = line.strip_prefix(keyword).unwrap_or_else(|| panic!("not a {keyword} line: {line:?}"));
    let mut xyz = [0.0; 3];
    for slot in &mut xyz {
        rest = rest.trim_start();
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        *slot = rest[..end].parse().unwrap_or_else(|_| panic!("bad number in {line:?}"));
        rest = &rest[end..];
    }
    (DVec3::from_array(xyz), rest)
}

fn positions(text: &str) -> Vec<DVec3> {
    text.lines().filter(|l| l.starts_with("v ")).map(|l| numbers(l, "v").0).collect()
}

fn diagonal(points: &[DVec3]) -> f64 {
    let lo = points.iter().fold(DVec3::splat(f64::INFINITY), |a, p| a.min(*p));
    let hi = points.iter().fold(DVec3::splat(f64::NEG_INFINITY), |a, p| a.max(*p));
    (hi - lo).length()
}

/// What differs between the input and output files, line by line (asserting the same number of
/// lines, the same line endings and every line other than `v` and `vn` byte for byte): the
/// largest vertex displacement, and how many `vn` lines changed.
fn compare(input: &str, output: &str) -> (f64, usize) {
    let (a, b): (Vec<&str>, Vec<&str>) = (input.split('\n').collect(), output.split('\n').collect());
    assert_eq!(a.len(), b.len(), "number of lines");
    let (mut moved, mut normals) = (0.0f64, 0);
    for (k, (x, y)) in a.iter().zip(&b).enumerate() {
        if x.starts_with("v ") {
            let ((p, rest_in), (q, rest_out)) = (numbers(x, "v"), numbers(y, "v"));
            assert_eq!(rest_in, rest_out, "line {}: the text after z changed", k + 1);
            moved = moved.max((p - q).length());
        } else if x.starts_with("vn ") && x != y {
            let (n, rest) = numbers(y, "vn");
            assert!((n.length() - 1.0).abs() < 1e-12 && rest.is_empty(), "line {}: {y:?}", k + 1);
            normals += 1;
        } else {
            assert_eq!(x, y, "line {} differs", k + 1);
        }
    }
    (moved, normals)
}

/// A zero displacement of `mesh` (handle and fixed group on disjoint vertex ranges) writes the
/// input back: `v` lines equal up to 1e-9 of the bounding-box diagonal, every other line but
/// `vn` identical. Returns the input, the output and stderr.
/// `extra` is appended to the scene.
fn zero_displacement(mesh: &str, extra: &str) -> (String, String, String) {
    let input = std::fs::read_to_string(mesh).unwrap();
    let handle: Vec<usize> = (0..20).collect();
    let fixed: Vec<usize> = (100..130).collect();
    let (output, stderr) = deform(mesh, &(scene_body(&handle, [0.0, 0.0, 0.0], &fixed) + extra));
    let (moved, _) = compare(&input, &output);
    let d = diagonal(&positions(&input));
    assert!(moved <= 1e-9 * d, "a vertex moved by {moved} (diagonal {d})");
    (input, output, stderr)
}

#[test]
fn spot_at_rest_comes_back_unchanged() {
    let (_, _, stderr) = zero_displacement(SPOT, "");
    assert!(!stderr.contains("normals recomputed"), "spot has no vn lines\n{stderr}");
}

#[test]
fn beetle_at_rest_keeps_its_objects_materials_and_normals() {
    // The beetle has loose parts (headlights): a weak anchor on every vertex holds them.
    let anchor = "\n[[constraints]]\ntype = \"position\"\nname = \"anchor\"\nweight = 0.01\n";
    let (input, output, stderr) = zero_displacement(BEETLE, anchor);
    let (_, normals) = compare(&input, &output);
    assert!(normals > 1000, "only {normals} vn lines were rewritten");
    assert!(stderr.contains("normals recomputed"), "{stderr}");
    // Blender wrote angle-weighted normals of this geometry: at rest the recomputed ones are the
    // file's up to its 6 digits.
    for (x, y) in input.lines().zip(output.lines()).filter(|(x, _)| x.starts_with("vn ")) {
        let (n, m) = (numbers(x, "vn").0.normalize(), numbers(y, "vn").0);
        assert!(n.dot(m) > 0.9999, "{x:?} became {y:?}");
    }
    for keep in ["mtllib VWBugMesh002.mtl", "o VWBUG", "usemtl None", "s 1"] {
        assert!(output.lines().any(|l| l == keep), "{keep:?} lost");
    }
}

#[test]
fn suzanne_at_rest_keeps_its_quads() {
    let (input, output, _) = zero_displacement(SUZANNE, "");
    let faces =
        |text: &str| -> Vec<String> { text.lines().filter(|l| l.starts_with("f ")).map(str::to_owned).collect() };
    let (a, b) = (faces(&input), faces(&output));
    assert_eq!(a, b);
    assert_eq!(b.iter().filter(|f| f.split_whitespace().count() == 5).count(), 468, "quads");
}

#[test]
fn deformed_spot_keeps_every_texture_coordinate_and_face() {
    let input = std::fs::read_to_string(SPOT).unwrap();
    let rest = positions(&input);
    // The head (z ≥ 0.8) pulled up, a slab at the back held.
    let head: Vec<usize> = (0..rest.len()).filter(|&i| rest[i].z >= 0.8).collect();
    let back: Vec<usize> = (0..rest.len()).filter(|&i| (-0.2..=-0.1).contains(&rest[i].z)).collect();
    assert!(head.len() > 10 && back.len() > 10);
    let t = DVec3::new(0.0, 0.2, 0.1);
    let (output, _) = deform(SPOT, &scene_body(&head, t.to_array(), &back));
    let (moved, _) = compare(&input, &output);
    assert!(moved > 0.5 * t.length(), "nothing moved (at most {moved})");
    let kept = |text: &str| -> Vec<String> {
        text.lines().filter(|l| l.starts_with("vt ") || l.starts_with("f ")).map(str::to_owned).collect()
    };
    assert_eq!(kept(&input), kept(&output), "vt and f lines identical");
    let out = positions(&output);
    let shift = head.iter().map(|&i| out[i] - rest[i]).sum::<DVec3>() / head.len() as f64;
    assert!((shift - t).length() < 0.05 * t.length(), "the head moved by {shift}, expected {t}");
    let held = back.iter().map(|&i| (out[i] - rest[i]).length()).fold(0.0, f64::max);
    assert!(held < 0.05 * t.length(), "the held slab moved by {held}");
}
