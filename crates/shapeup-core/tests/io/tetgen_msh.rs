//! Tetrahedral mesh I/O: Gmsh `.msh` and TetGen `.node`/`.ele` round trips, hand-written files of
//! both MSH versions, the derived boundary surface, and malformed inputs (an error naming the file
//! and line, never a panic) and failed writes (nothing left behind).

use std::fs;
use std::path::{Path, PathBuf};

use glam::DVec3;
use shapeup_core::Mesh;
use shapeup_core::io::{Attributes, IoError, LoadedMesh, MeshFormat, WriteFormat, msh, read_mesh, tetgen, write_mesh};
use shapeup_core::topology::{tetrahedron_boundary, unique_edges};

// ---------------------------------------------------------------------------------------------
// Helpers

/// (b − a)·((c − a) × (d − a)) = 6 × the signed volume.
fn volume6(p: &[DVec3], t: [u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(|v| p[v as usize]);
    (b - a).dot((c - a).cross(d - a))
}

/// An `nx × ny × nz` grid of boxes, each split into six positively oriented tetrahedra around
/// its (0,0,0)–(1,1,1) diagonal (conforming across boxes); coordinates with long decimal
/// expansions so that round trips must be exact to pass. Triangles: the boundary.
fn grid(nx: u32, ny: u32, nz: u32) -> Mesh {
    let mut positions = Vec::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let (i, j, k) = (f64::from(i), f64::from(j), f64::from(k));
                positions.push(DVec3::new(0.1 * i + 1.0 / 3.0, j / 7.0 - 2.5e-3, 0.3 * k - 1e-5));
            }
        }
    }
    let index = |i: u32, j: u32, k: u32| i + (nx + 1) * (j + (ny + 1) * k);
    let mut tets = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let corner = |bits: u32| index(i + (bits & 1), j + ((bits >> 1) & 1), k + ((bits >> 2) & 1));
                for [p, q] in [[0, 1], [0, 2], [1, 0], [1, 2], [2, 0], [2, 1]] {
                    let mut tet = [corner(0), corner(1 << p), corner((1 << p) | (1 << q)), corner(7)];
                    if volume6(&positions, tet) < 0.0 {
                        tet.swap(2, 3);
                    }
                    tets.push(tet);
                }
            }
        }
    }
    let triangles = tetrahedron_boundary(&tets);
    Mesh::with_tetrahedra(positions, triangles, tets).unwrap()
}

fn assert_exact(a: &Mesh, b: &Mesh) {
    assert_eq!(a.positions.len(), b.positions.len(), "vertex count");
    for (i, (p, q)) in a.positions.iter().zip(&b.positions).enumerate() {
        assert_eq!(p.to_array().map(f64::to_bits), q.to_array().map(f64::to_bits), "vertex {i}: {p} vs {q}");
    }
    assert_eq!(a.tetrahedra, b.tetrahedra);
    assert_eq!(a.triangles, b.triangles);
}

/// Every boundary triangle faces away from the centroid (the meshes here are convex) and every
/// edge of the surface is in exactly two triangles.
fn assert_closed_and_outward(mesh: &Mesh) {
    let p = &mesh.positions;
    let centroid = p.iter().sum::<DVec3>() / p.len() as f64;
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|v| p[v as usize]);
        let normal = (b - a).cross(c - a);
        assert!(normal.dot((a + b + c) / 3.0 - centroid) > 0.0, "triangle {t:?} faces inward");
    }
    let (_, counts) = unique_edges(&mesh.triangles);
    assert!(counts.iter().all(|&c| c == 2), "surface is not closed: {counts:?}");
}

fn dir_entries(dir: &Path) -> Vec<PathBuf> {
    let mut entries: Vec<PathBuf> = fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    entries
}

/// Writes `files` (name, contents) into a fresh temp dir and reads `read` with `read_mesh`.
fn read_files(files: &[(&str, &str)], read: &str) -> Result<LoadedMesh, IoError> {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        fs::write(dir.path().join(name), text).unwrap();
    }
    read_mesh(&dir.path().join(read))
}

/// Asserts that reading `read` among `files` fails with a one-line message naming `names_file`
/// and containing every one of `needles`.
fn malformed(files: &[(&str, &str)], read: &str, names_file: &str, needles: &[&str]) -> IoError {
    let err = read_files(files, read).expect_err("malformed input must be an error");
    let message = err.to_string();
    assert!(message.contains(names_file), "message does not name {names_file}: {message}");
    assert!(!message.contains('\n'), "message is not one line: {message}");
    for needle in needles {
        assert!(message.contains(needle), "message lacks {needle:?}: {message}");
    }
    err
}

/// "line N" for the first line of `text` that contains `needle`.
fn line_of(text: &str, needle: &str) -> String {
    let at = text.find(needle).unwrap();
    format!("line {}", text[..at].matches('\n').count() + 1)
}

/// Five points: the unit corner tetrahedron and (1, 1, 1).
const FIVE: [[f64; 3]; 5] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 1.0, 1.0]];

/// What the hand-written files below hold: (0, 1, 2, 3) and (1, 3, 2, 4) written negatively,
/// read back with the last two vertices swapped.
fn two_tets_expected() -> Vec<[u32; 4]> {
    vec![[0, 1, 2, 3], [1, 3, 4, 2]]
}

fn assert_two_tets(loaded: &LoadedMesh) {
    let mesh = &loaded.mesh;
    assert_eq!(mesh.positions, FIVE.map(DVec3::from_array).to_vec(), "vertices in file order");
    assert_eq!(mesh.tetrahedra, two_tets_expected());
    assert!(mesh.tetrahedra.iter().all(|&t| volume6(&mesh.positions, t) > 0.0));
    assert_eq!(mesh.triangles, tetrahedron_boundary(&mesh.tetrahedra), "file triangles are ignored");
    assert_eq!(mesh.triangles.len(), 6);
    assert_closed_and_outward(mesh);
}

const MSH22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n\
$PhysicalNames\n1\n3 1 \"volume\"\n$EndPhysicalNames\n\
$Nodes\n5\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n$EndNodes\n\
$Elements\n6\n\
1 15 2 0 1 1\n\
2 1 2 0 1 1 2\n\
3 2 2 0 1 1 2 3\n\
4 4 2 1 1 1 2 3 4\n\
5 4 2 1 1 2 4 3 5\n\
6 11 2 1 1 1 2 3 4 1 2 3 4 1 2\n\
$EndElements\n";

/// Sparse tags in order 100, 7, 42, 3, 55 over two blocks (one parametric), $Entities and
/// $NodeData to skip, and points, lines, a triangle and a second-order tetrahedron to skip.
const MSH41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n\
$Entities\n1 0 0 1\n1 0 0 0 0\n1 0 0 0 1 1 1 0 1 -1\n$EndEntities\n\
$Nodes\n2 5 3 100\n0 1 0 3\n100\n7\n42\n0 0 0\n1 0 0\n0 1 0\n\
2 1 1 2\n3\n55\n0 0 1 0.25 0.5\n1 1 1 0.75 0.5\n$EndNodes\n\
$Elements\n5 6 1 60\n\
0 1 15 1\n1 100\n\
1 1 1 1\n2 100 7\n\
2 1 2 1\n3 100 7 42\n\
3 1 4 2\n10 100 7 42 3\n20 7 3 42 55\n\
3 1 11 1\n60 100 7 42 3 100 7 42 3 100 7\n\
$EndElements\n\
$NodeData\n1\n\"t\"\n1\n0.0\n3\n0\n1\n1\n100 3.5\n$EndNodeData\n";

const NODE_1: &str = "# five points, 1 attribute, boundary markers\n5 3 1 1\n\
1 0 0 0 0.5 1\n2 1 0 0 0.5 1\n\n3 0 1 0 0.5 1 # a comment\n4 0 0 1 0.5 0\n5 1 1 1 0.5 1\n";
const ELE_1: &str = "2 4 1\n1 1 2 3 4 7.0\n2 2 4 3 5 7.0\n# end\n";
const NODE_0: &str = "5 3\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n4 1 1 1\n";
const ELE_0: &str = "2\n0 0 1 2 3\n1 1 3 2 4\n";

// ---------------------------------------------------------------------------------------------
// Round trips

#[test]
fn msh_round_trip_is_exact() {
    for mesh in [grid(1, 1, 1), grid(3, 3, 3)] {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.msh");
        write_mesh(&path, &mesh, &Attributes::None).unwrap();
        assert_eq!(dir_entries(dir.path()), vec![path.clone()], "no temp file left behind");
        let text = fs::read_to_string(&path).unwrap();
        assert!(text.starts_with("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n"), "{}", &text[..40]);
        assert_exact(&read_mesh(&path).unwrap().mesh, &mesh);
    }
}

#[test]
fn tetgen_round_trip_is_exact_from_either_file() {
    for (mesh, written) in [(grid(1, 1, 1), "m.ele"), (grid(3, 3, 3), "m.node")] {
        let dir = tempfile::tempdir().unwrap();
        write_mesh(&dir.path().join(written), &mesh, &Attributes::None).unwrap();
        let (node, ele) = (dir.path().join("m.node"), dir.path().join("m.ele"));
        assert_eq!(dir_entries(dir.path()), vec![ele.clone(), node.clone()], "the pair and nothing else");
        assert_exact(&read_mesh(&node).unwrap().mesh, &mesh);
        assert_exact(&read_mesh(&ele).unwrap().mesh, &mesh);
    }
}

#[test]
fn left_handed_tetrahedra_are_written_back_as_the_file_lists_them() {
    // Each file lists its second tetrahedron (1, 3, 2, 4) left-handed; the solver's mesh has it
    // right-handed, every writer of tetrahedra as the file had it.
    let file_order: Vec<u64> = [0, 1, 2, 3, 1, 3, 2, 4].into();
    for files in [vec![("m.msh", MSH22)], vec![("m.msh", MSH41)], vec![("m.node", NODE_1), ("m.ele", ELE_1)]] {
        let loaded = read_files(&files, files[0].0).unwrap();
        assert_two_tets(&loaded);
        let info = shapeup_core::inspect::MeshInfo::of_loaded(&loaded);
        let left_handed = &info.volume.as_ref().unwrap().left_handed_tetrahedra;
        assert_eq!((left_handed.count, left_handed.first.clone()), (1, vec![1]), "{}", files[0].0);
        assert!(info.to_string().contains("left-handed tetrahedra in the file 1 (first: 1)"), "{info}");
        assert_eq!(shapeup_core::inspect::MeshInfo::of(&loaded.mesh).volume.unwrap().left_handed_tetrahedra.count, 0);
        let connectivity = super::vtu::connectivity_of(&loaded.mesh, &loaded.attributes);
        assert_eq!(connectivity, file_order, "VTU");
        // Without the file's attributes (another mesh) the solver's order is written.
        assert_ne!(super::vtu::connectivity_of(&loaded.mesh, &Attributes::None), file_order);
        for written in ["out.msh", "out.ele"] {
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(written);
            let warnings = write_mesh(&path, &loaded.mesh, &loaded.attributes).unwrap();
            // TetGen files cannot hold an MSH file's physical groups (and say so).
            let dropped_groups = written == "out.ele" && files[0].0 == "m.msh";
            assert!(
                warnings.iter().all(|w| dropped_groups && w.kind == "attributes_dropped"),
                "{written}: {warnings:?}"
            );
            let text = fs::read_to_string(&path).unwrap();
            let again = read_mesh(&path).unwrap();
            assert_eq!(again.mesh.tetrahedra, two_tets_expected(), "{written}");
            let order = again.attributes.tetrahedron_order();
            assert_eq!(
                order,
                loaded.attributes.tetrahedron_order(),
                "{written} lists the same tetrahedron left-handed"
            );
            if files[0].0 == "m.msh" && written == "out.msh" {
                // The file written back: its elements exactly as listed, with its own tags.
                let elements = |t: &str| t.split("$Elements").nth(1).map(str::to_owned);
                assert_eq!(elements(&text), elements(files[0].1), "{written}:\n{text}");
            } else {
                // One-based indices: the second tetrahedron as listed.
                assert!(text.lines().any(|l| l.trim_end().ends_with(" 2 4 3 5")), "{written}:\n{text}");
            }
        }
    }
}

#[test]
fn triangle_mesh_round_trips_through_msh() {
    let cube = grid(1, 1, 1);
    let surface = Mesh::new(cube.positions.clone(), cube.triangles.clone()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.msh");
    write_mesh(&path, &surface, &Attributes::None).unwrap();
    let loaded = read_mesh(&path).unwrap();
    assert_exact(&loaded.mesh, &surface);
    assert!(loaded.mesh.tetrahedra.is_empty());
}

#[test]
fn every_truncation_is_an_error_or_a_mesh_never_a_panic() {
    let mesh = grid(1, 1, 1);
    let mut msh_bytes = Vec::new();
    msh::write_msh(&mut msh_bytes, &mesh).unwrap();
    for len in 0..msh_bytes.len() {
        if let Err(err) = msh::read_msh(&msh_bytes[..len], Path::new("t.msh")) {
            assert!(err.to_string().contains("t.msh"), "{err}");
        }
    }
    let (mut node, mut ele) = (Vec::new(), Vec::new());
    tetgen::write_node(&mut node, &mesh).unwrap();
    tetgen::write_ele(&mut ele, &mesh).unwrap();
    let read = |n: &[u8], e: &[u8]| tetgen::read_tetgen(n, Path::new("t.node"), e, Path::new("t.ele"));
    assert_exact(&read(&node, &ele).unwrap().mesh, &mesh);
    for len in 0..node.len() {
        if let Err(err) = read(&node[..len], &ele) {
            assert!(err.to_string().contains("t.node"), "{err}");
        }
    }
    for len in 0..ele.len() {
        if let Err(err) = read(&node, &ele[..len]) {
            assert!(err.to_string().contains("t.ele"), "{err}");
        }
    }
}

/// Every line of every hand-written file replaced by hostile text reads as `Ok` or an error
/// naming the file, never a panic.
#[test]
fn every_corrupted_line_is_an_error_or_a_mesh_never_a_panic() {
    let hostile = ["", "x", "-1", "0", "18446744073709551616", "1 2 3 4 5 6 7 8 9 10 11 12", "$Nodes", "$EndElements"];
    for (name, text) in [("a.msh", MSH22), ("b.msh", MSH41), ("c.node", NODE_1), ("c.ele", ELE_1)] {
        let lines: Vec<&str> = text.lines().collect();
        for i in 0..lines.len() {
            for bad in hostile {
                let mut edited = lines.clone();
                edited[i] = bad;
                let edited = edited.join("\n");
                let path = Path::new(name);
                let result = match name {
                    "c.node" => tetgen::read_tetgen(edited.as_bytes(), path, ELE_1.as_bytes(), Path::new("c.ele")),
                    "c.ele" => tetgen::read_tetgen(NODE_1.as_bytes(), Path::new("c.node"), edited.as_bytes(), path),
                    _ => msh::read_msh(edited.as_bytes(), path),
                };
                if let Err(err) = result {
                    assert!(err.to_string().contains(name), "{err}");
                }
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Hand-written files and the boundary

#[test]
fn cube_boundary_is_twelve_outward_triangles_of_a_closed_surface() {
    let cube = grid(1, 1, 1);
    assert_eq!(cube.tetrahedra.len(), 6);
    assert_eq!(cube.triangles.len(), 12);
    assert_closed_and_outward(&cube);
    let big = grid(3, 3, 3);
    assert_eq!((big.positions.len(), big.tetrahedra.len(), big.triangles.len()), (64, 162, 108));
    assert_closed_and_outward(&big);
}

#[test]
fn hand_written_msh_2_2() {
    assert_two_tets(&read_files(&[("a.msh", MSH22)], "a.msh").unwrap());
}

#[test]
fn hand_written_msh_4_1_with_sparse_tags_and_other_elements() {
    assert_two_tets(&read_files(&[("b.msh", MSH41)], "b.msh").unwrap());
}

#[test]
fn msh_with_triangles_only_is_a_surface_mesh() {
    let text = MSH22
        .replace("$Elements\n6\n", "$Elements\n3\n")
        .replace(&MSH22[MSH22.find("4 4 2").unwrap()..MSH22.find("$EndElements").unwrap()], "");
    let loaded = read_files(&[("s.msh", &text)], "s.msh").unwrap();
    assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
    assert!(loaded.mesh.tetrahedra.is_empty());
}

#[test]
fn tetgen_one_based_with_attributes_markers_and_comments() {
    assert_two_tets(&read_files(&[("c.node", NODE_1), ("c.ele", ELE_1)], "c.node").unwrap());
}

#[test]
fn tetgen_zero_based() {
    assert_two_tets(&read_files(&[("d.node", NODE_0), ("d.ele", ELE_0)], "d.ele").unwrap());
}

#[test]
fn extensions_select_the_formats() {
    assert_eq!(MeshFormat::from_path(Path::new("a.MSH")).unwrap(), MeshFormat::Msh);
    assert_eq!(MeshFormat::from_path(Path::new("a.node")).unwrap(), MeshFormat::TetGen);
    assert_eq!(MeshFormat::from_path(Path::new("a.Ele")).unwrap(), MeshFormat::TetGen);
    assert_eq!(WriteFormat::from_path(Path::new("a.msh")).unwrap(), WriteFormat::Msh);
    assert_eq!(WriteFormat::from_path(Path::new("a.ele")).unwrap(), WriteFormat::TetGen);
    let err = MeshFormat::from_path(Path::new("a.vtk")).unwrap_err().to_string();
    assert!(err.contains(".msh, .node/.ele"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Malformed files

#[test]
fn msh_truncated_nodes() {
    let cut = &MSH41[..MSH41.find("1 0 0\n").unwrap()];
    let expected = format!("line {}", cut.matches('\n').count() + 1);
    malformed(&[("t.msh", cut)], "t.msh", "t.msh", &[&expected, "file ends early", "coordinates 2 of 3"]);
    let cut = &MSH22[..MSH22.find("4 0 0 1").unwrap()];
    malformed(&[("t.msh", cut)], "t.msh", "t.msh", &[&line_of(MSH22, "4 0 0 1"), "node 4 of 5"]);
}

#[test]
fn msh_truncated_elements() {
    let cut = &MSH41[..MSH41.find("20 7 3").unwrap()];
    malformed(&[("e.msh", cut)], "e.msh", "e.msh", &[&line_of(MSH41, "20 7 3"), "file ends early", "element 2 of 2"]);
    let cut = &MSH22[..MSH22.find("$EndElements").unwrap()];
    malformed(&[("e.msh", cut)], "e.msh", "e.msh", &[&line_of(MSH22, "$EndElements"), "'$EndElements'"]);
}

#[test]
fn msh_missing_end_nodes() {
    let text = MSH22.replace("$EndNodes\n", "");
    malformed(
        &[("n.msh", &text)],
        "n.msh",
        "n.msh",
        &[&line_of(&text, "$Elements"), "expected '$EndNodes'", "found '$Elements'"],
    );
}

#[test]
fn node_tag_out_of_range() {
    let text = MSH41.replace("20 7 3 42 55", "20 7 3 42 56");
    malformed(&[("r.msh", &text)], "r.msh", "r.msh", &[&line_of(&text, "20 7 3"), "node tag '56' is not defined"]);
    let text = MSH22.replace("5 4 2 1 1 2 4 3 5", "5 4 2 1 1 2 4 3 0");
    malformed(&[("r.msh", &text)], "r.msh", "r.msh", &[&line_of(&text, "5 4 2 1"), "element 5", "node tag '0'"]);
    let ele = ELE_1.replace("2 2 4 3 5", "2 2 4 3 6");
    malformed(
        &[("r.node", NODE_1), ("r.ele", &ele)],
        "r.node",
        "r.ele",
        &[&line_of(&ele, "2 2 4"), "'6' is out of range", "1..=5"],
    );
    let ele = ELE_1.replace("1 1 2 3 4", "1 0 2 3 4");
    malformed(&[("r.node", NODE_1), ("r.ele", &ele)], "r.ele", "r.ele", &["line 2", "'0' is out of range"]);
}

#[test]
fn non_numeric_coordinate() {
    let text = MSH22.replace("3 0 1 0", "3 0 abc 0");
    malformed(
        &[("c.msh", &text)],
        "c.msh",
        "c.msh",
        &[&line_of(&text, "abc"), "node 3: y coordinate 'abc' is not a number"],
    );
    let text = MSH41.replace("1 1 1 0.75", "1 1 1e9e9 0.75");
    malformed(&[("c.msh", &text)], "c.msh", "c.msh", &[&line_of(&text, "1e9e9"), "node 55: z coordinate"]);
    let node = NODE_0.replace("2 0 1 0", "2 0 1 z");
    malformed(&[("c.node", &node), ("c.ele", ELE_0)], "c.ele", "c.node", &["line 4", "point 2: z coordinate 'z'"]);
}

#[test]
fn flat_or_repeating_tetrahedron_names_the_element() {
    // Node 5 moved into the plane x + y + z = 1 of nodes 2, 3, 4.
    let text = MSH22.replace("5 1 1 1", "5 0.5 0.5 0");
    malformed(&[("z.msh", &text)], "z.msh", "z.msh", &[&line_of(&text, "5 4 2 1"), "element 5 is flat"]);
    let node = NODE_0.replace("4 1 1 1", "4 0.25 0.25 0.5");
    malformed(&[("z.node", &node), ("z.ele", ELE_0)], "z.node", "z.ele", &["line 3", "tetrahedron 1 is flat"]);
    let ele = ELE_0.replace("0 0 1 2 3", "0 0 1 2 1");
    malformed(&[("z.node", NODE_0), ("z.ele", &ele)], "z.node", "z.ele", &["line 2", "tetrahedron 0 repeats a vertex"]);
}

#[test]
fn binary_msh_with_garbage_after_the_byte_order_int_names_the_offset() {
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&[1, 0, 0, 0, 0xff, 0xfe, b'\n']);
    bytes.extend_from_slice(b"$EndMeshFormat\n");
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bin.msh");
    fs::write(&path, bytes).unwrap();
    let err = read_mesh(&path).unwrap_err().to_string();
    assert!(err.contains("bin.msh: byte offset 24") && err.contains("expected '$EndMeshFormat'"), "{err}");
}

#[test]
fn missing_partner_file_is_named() {
    malformed(&[("p.node", NODE_1)], "p.node", "p.ele", &["cannot open"]);
    malformed(&[("q.ele", ELE_1)], "q.ele", "q.node", &["cannot open"]);
}

#[test]
fn empty_files_and_empty_meshes() {
    malformed(&[("e.msh", "")], "e.msh", "e.msh", &["line 1", "empty file"]);
    malformed(&[("e.node", ""), ("e.ele", ELE_0)], "e.ele", "e.node", &["line 1", "empty file"]);
    malformed(&[("e.node", NODE_0), ("e.ele", "# nothing\n")], "e.ele", "e.ele", &["line 1", "empty file"]);
    let err = malformed(&[("e.node", "0 3 0 0\n"), ("e.ele", ELE_0)], "e.ele", "e.node", &["0 points"]);
    assert!(matches!(err, IoError::Invalid { .. }));
    let err = malformed(&[("e.node", NODE_0), ("e.ele", "0 4 0\n")], "e.ele", "e.ele", &["0 tetrahedra"]);
    assert!(matches!(err, IoError::Invalid { .. }));
    let no_nodes = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let err = malformed(&[("e.msh", no_nodes)], "e.msh", "e.msh", &["no nodes"]);
    assert!(matches!(err, IoError::Invalid { .. }));
    let lines_only = MSH41.replace("3 1 4 2\n10 100 7 42 3\n20 7 3 42 55\n", "").replace("2 1 2 1\n3 100 7 42\n", "");
    let lines_only = lines_only.replace("$Elements\n5 6 1 60", "$Elements\n3 3 1 60");
    let err = malformed(&[("l.msh", &lines_only)], "l.msh", "l.msh", &["no 4-node tetrahedra", "type 1, 11, 15"]);
    assert!(matches!(err, IoError::Invalid { .. }));
}

#[test]
fn huge_counts_do_not_allocate() {
    let huge = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 18446744073709551615 1 2\n\
                3 1 0 18446744073709551615\n1\n";
    malformed(&[("h.msh", huge)], "h.msh", "h.msh", &["line 8", "file ends early"]);
    let huge = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n99999999999999999\n1 0 0 0\n";
    malformed(&[("h.msh", huge)], "h.msh", "h.msh", &["line 7", "node 2 of 99999999999999999"]);
    malformed(&[("h.node", "4000000000 3 0 0\n1 0 0 0\n"), ("h.ele", ELE_1)], "h.ele", "h.node", &["line 3"]);
    malformed(&[("h.node", NODE_1), ("h.ele", "4000000000 4 0\n")], "h.ele", "h.ele", &["line 2"]);
}

#[test]
fn other_msh_errors() {
    let v4 = "$MeshFormat\n4 0 8\n$EndMeshFormat\n";
    malformed(&[("v.msh", v4)], "v.msh", "v.msh", &["line 2", "MSH version 4 is not supported"]);
    let text = MSH22.replace("3 0 1 0\n", "1 0 1 0\n");
    malformed(&[("d.msh", &text)], "d.msh", "d.msh", &[&line_of(&text, "1 0 1 0"), "node tag 1 is defined twice"]);
    let text = MSH41.replace("$Nodes\n2 5 3 100", "$Nodes\n2 6 3 100");
    malformed(&[("d.msh", &text)], "d.msh", "d.msh", &[&line_of(&text, "$EndNodes"), "says 6 nodes", "hold 5"]);
    let text = MSH41.replace("$EndNodeData\n", "");
    malformed(&[("d.msh", &text)], "d.msh", "d.msh", &["'$EndNodeData'", &line_of(&text, "$NodeData")]);
    let text = MSH22.replace("4 4 2 1 1 1 2 3 4", "4 4 2 1 1 1 2 3");
    malformed(&[("d.msh", &text)], "d.msh", "d.msh", &[&line_of(&text, "4 4 2 1"), "lists 3 nodes, expected 4"]);
    let text = MSH22.replace("4 4 2 1 1 1 2 3 4", "4 4 18446744073709551615 1 2 3 4");
    malformed(&[("d.msh", &text)], "d.msh", "d.msh", &[&line_of(&text, "4 4 1844"), "lists 0 nodes"]);
}

#[test]
fn nan_coordinate_is_a_mesh_error_naming_the_file() {
    let text = MSH22.replace("2 1 0 0", "2 NaN 0 0");
    let err = malformed(&[("n.msh", &text)], "n.msh", "n.msh", &["non-finite"]);
    assert!(matches!(err, IoError::Mesh { .. }));
    let node = NODE_0.replace("1 1 0 0", "1 inf 0 0");
    let err = malformed(&[("n.node", &node), ("n.ele", ELE_0)], "n.ele", "n.node", &["non-finite"]);
    assert!(matches!(err, IoError::Mesh { .. }));
}

// ---------------------------------------------------------------------------------------------
// Failed writes leave nothing

#[test]
fn tetgen_without_tetrahedra_writes_nothing() {
    let cube = grid(1, 1, 1);
    let surface = Mesh::new(cube.positions, cube.triangles).unwrap();
    let dir = tempfile::tempdir().unwrap();
    for name in ["s.node", "s.ele"] {
        let err = write_mesh(&dir.path().join(name), &surface, &Attributes::None).unwrap_err();
        assert!(matches!(err, IoError::Invalid { .. }), "{err}");
        assert!(err.to_string().contains(name) && err.to_string().contains("no"), "{err}");
    }
    assert!(dir_entries(dir.path()).is_empty());
}

#[test]
fn invalid_mesh_or_missing_directory_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = grid(1, 1, 1);
    bad.tetrahedra.push([0, 1, 2, 99]);
    for name in ["b.msh", "b.node"] {
        let err = write_mesh(&dir.path().join(name), &bad, &Attributes::None).unwrap_err();
        assert!(matches!(err, IoError::Mesh { .. }) && err.to_string().contains(name), "{err}");
    }
    let missing = dir.path().join("missing");
    for name in ["m.msh", "m.ele"] {
        let err = write_mesh(&missing.join(name), &grid(1, 1, 1), &Attributes::None).unwrap_err();
        assert!(matches!(err, IoError::Write { .. }), "{err}");
    }
    assert!(dir_entries(dir.path()).is_empty(), "no file and no temp file");
}

// ---------------------------------------------------------------------------------------------
// Gmsh in, Gmsh out: physical groups, tags and every element kept

/// A unit cube of five tetrahedra, MSH 4.1: node tags 10–80 in two blocks, physical groups
/// "fixed" (the two triangles of the face x = 0) and "solid" (the tetrahedra), and a line
/// element of no group.
const CUBE_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 \"fixed\"\n3 2 \"solid\"\n\
$EndPhysicalNames\n$Entities\n0 1 1 1\n1 0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 1 1 0\n1 0 0 0 1 1 1 1 2 0\n$EndEntities\n\
$Nodes\n2 8 10 80\n3 1 0 4\n10\n20\n30\n40\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 1 0 4\n50\n60\n70\n80\n0 0 1\n1 0 1\n\
1 1 1\n0 1 1\n$EndNodes\n$Elements\n3 8 100 107\n3 1 4 5\n100 10 20 40 50\n101 30 40 20 70\n102 60 50 70 20\n\
103 80 70 50 40\n104 20 40 50 70\n2 1 2 2\n105 10 40 80\n106 10 80 50\n1 1 1 1\n107 10 50\n$EndElements\n";

/// The same cube as MSH 2.2 (CRLF line endings): physical tags as each element's first tag.
const CUBE_22: &str = "$MeshFormat\r\n2.2 0 8\r\n$EndMeshFormat\r\n$PhysicalNames\r\n2\r\n2 1 \"fixed\"\r\n3 2 \"solid\"\r\n\
$EndPhysicalNames\r\n$Nodes\r\n8\r\n10 0 0 0\r\n20 1 0 0\r\n30 1 1 0\r\n40 0 1 0\r\n50 0 0 1\r\n60 1 0 1\r\n\
70 1 1 1\r\n80 0 1 1\r\n$EndNodes\r\n$Elements\r\n8\r\n100 4 2 2 1 10 20 40 50\r\n101 4 2 2 1 30 40 20 70\r\n\
102 4 2 2 1 60 50 70 20\r\n103 4 2 2 1 80 70 50 40\r\n104 4 2 2 1 20 40 50 70\r\n105 2 2 1 1 10 40 80\r\n\
106 2 2 1 1 10 80 50\r\n107 1 2 0 1 10 50\r\n$EndElements\r\n";

/// `.msh` → `.msh` keeps `$PhysicalNames`, `$Entities`, node and element tags, the file's own
/// triangles and lines and its line endings: only the coordinates change, and they read back
/// exactly. Other formats say once that they drop the groups and the other elements; a mesh
/// that is not the file's falls back to the plain writer and says so too.
#[test]
fn msh_comes_back_with_its_groups_tags_and_elements_moved() {
    for (name, text) in [("41", CUBE_41), ("22", CUBE_22)] {
        let loaded = read_files(&[("cube.msh", text)], "cube.msh").unwrap();
        let groups: Vec<(i32, i64, Option<String>, Vec<u32>)> = loaded
            .attributes
            .physical_groups()
            .iter()
            .map(|g| (g.dim, g.tag, g.name.clone(), g.vertices.clone()))
            .collect();
        // Vertex i is the i-th node: tags 10, 20, … 80 are vertices 0–7.
        let expected = vec![
            (2, 1, Some("fixed".to_string()), vec![0, 3, 4, 7]),
            (3, 2, Some("solid".to_string()), (0..8).collect()),
        ];
        assert_eq!(groups, expected, "{name}");
        let info = shapeup_core::inspect::MeshInfo::of_loaded(&loaded);
        assert!(
            info.to_string().contains(
                "physical groups: \"fixed\" (dimension 2, tag 1, 4 vertices), \"solid\" (dimension 3, tag 2, 8 vertices)"
            ),
            "{info}"
        );
        let moved: Vec<DVec3> =
            loaded.mesh.positions.iter().map(|&p| p * 1.5 + DVec3::new(1.0 / 3.0, -2e-7, 7.0)).collect();
        let mesh = loaded.mesh.with_positions(moved.clone());
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("out.msh");
        let warnings = write_mesh(&out, &mesh, &loaded.attributes).unwrap();
        assert!(warnings.is_empty(), "{name}: {warnings:?}");
        let written = fs::read_to_string(&out).unwrap();
        let (before, after): (Vec<&str>, Vec<&str>) =
            (text.split_inclusive('\n').collect(), written.split_inclusive('\n').collect());
        assert_eq!(before.len(), after.len(), "{name}: line for line");
        let changed: Vec<usize> = (0..before.len()).filter(|&i| before[i] != after[i]).collect();
        let coordinate_lines =
            if name == "41" { [21, 22, 23, 24, 30, 31, 32, 33] } else { [10, 11, 12, 13, 14, 15, 16, 17] };
        assert_eq!(changed, coordinate_lines, "{name}: only the coordinate lines change\n{written}");
        assert!(
            after.iter().all(|l| l.ends_with(if name == "22" { "\r\n" } else { "\n" })),
            "{name}: line endings kept"
        );
        let again = read_mesh(&out).unwrap();
        assert_eq!(again.mesh.positions, moved, "{name}: coordinates exact");
        assert_eq!(again.attributes.physical_groups(), loaded.attributes.physical_groups(), "{name}");
        // Another format drops the groups and the line element, and says so once.
        let warnings = write_mesh(&dir.path().join("out.obj"), &mesh, &loaded.attributes).unwrap();
        let dropped = warnings.iter().find(|w| w.kind == "attributes_dropped").unwrap();
        assert!(dropped.message.contains("Gmsh physical groups") && dropped.message.contains("other than tetrahedra"));
        // Another mesh (a vertex fewer) is written plainly, saying what it leaves out.
        let other = Mesh::with_tetrahedra(loaded.mesh.positions[..7].to_vec(), Vec::new(), vec![[0, 1, 3, 4]]).unwrap();
        let warnings = write_mesh(&out, &other, &loaded.attributes).unwrap();
        assert!(warnings.iter().any(|w| w.kind == "attributes_dropped"), "{name}: {warnings:?}");
    }
}

/// The points of each physical group of `loaded`, in the order of its groups.
fn group_points(loaded: &LoadedMesh) -> Vec<Vec<DVec3>> {
    let groups = loaded.attributes.physical_groups();
    groups.iter().map(|g| g.vertices.iter().map(|&v| loaded.mesh.positions[v as usize]).collect()).collect()
}

/// Gmsh's own files (4.8.4, `gmsh_box.geo`): the 4.1 (with parametric nodes) and 2.2 files,
/// ASCII and binary, name the same four physical groups (a point, a curve, a surface, the
/// volume) with the same vertices, and each comes back with only its node coordinates changed:
/// an ASCII file line for line (a 4.1 node keeps its parametric coordinates), a binary one
/// byte for byte but the nodes' `double`s.
#[test]
fn gmsh_files_keep_their_physical_groups_and_come_back_line_for_line() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let mut groups_of_each = Vec::new();
    for name in ["gmsh_box_41_binary.msh", "gmsh_box_22_binary.msh"] {
        let path = data.join(name);
        let loaded = read_mesh(&path).unwrap();
        let labels: Vec<String> = loaded.attributes.physical_groups().iter().map(|g| g.label()).collect();
        assert_eq!(labels, ["corner", "edge", "bottom", "solid"], "{name}");
        groups_of_each.push(group_points(&loaded));
        let moved: Vec<DVec3> =
            loaded.mesh.positions.iter().map(|&p| p * 2.0 - DVec3::new(0.0, 1.0 / 3.0, 0.0)).collect();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(name);
        write_mesh(&out, &loaded.mesh.with_positions(moved.clone()), &loaded.attributes).unwrap();
        let (before, after) = (fs::read(&path).unwrap(), fs::read(&out).unwrap());
        assert_eq!(before.len(), after.len(), "{name}");
        let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
        assert!(changed > 0 && changed <= 24 * loaded.mesh.num_vertices(), "{name}: {changed} bytes changed");
        assert_eq!(read_mesh(&out).unwrap().mesh.positions, moved, "{name}");
    }
    for name in ["gmsh_box_41_ascii.msh", "gmsh_box_22_ascii.msh"] {
        let path = data.join(name);
        let loaded = read_mesh(&path).unwrap();
        let groups: Vec<(String, i32, usize)> =
            loaded.attributes.physical_groups().iter().map(|g| (g.label(), g.dim, g.vertices.len())).collect();
        let labels: Vec<&str> = groups.iter().map(|g| g.0.as_str()).collect();
        assert_eq!(labels, ["corner", "edge", "bottom", "solid"], "{name}");
        assert_eq!(groups[0].2, 1, "{name}: a point");
        assert_eq!(groups[3].2, loaded.mesh.num_vertices(), "{name}: the volume has every node");
        groups_of_each.push(group_points(&loaded));
        let moved: Vec<DVec3> = loaded.mesh.positions.iter().map(|&p| p + DVec3::new(0.5, 0.0, -1.0)).collect();
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join(name);
        write_mesh(&out, &loaded.mesh.with_positions(moved.clone()), &loaded.attributes).unwrap();
        let (before, after) = (fs::read_to_string(&path).unwrap(), fs::read_to_string(&out).unwrap());
        let changed: Vec<(&str, &str)> = before.lines().zip(after.lines()).filter(|(a, b)| a != b).collect();
        assert_eq!(before.lines().count(), after.lines().count(), "{name}");
        assert_eq!(changed.len(), loaded.mesh.num_vertices(), "{name}: the node lines only");
        if name.contains("41") {
            let parametric = changed.iter().filter(|(a, _)| a.split_whitespace().count() > 3).count();
            assert!(parametric > 0, "{name}: has parametric nodes");
            for (a, b) in &changed {
                assert_eq!(
                    a.split_whitespace().skip(3).collect::<Vec<_>>(),
                    b.split_whitespace().skip(3).collect::<Vec<_>>()
                );
            }
        }
        assert_eq!(read_mesh(&out).unwrap().mesh.positions, moved, "{name}");
    }
    // Node order differs between the versions, and ASCII files round the last digit; the
    // groups hold the same points.
    let sorted = |sets: &Vec<Vec<DVec3>>| -> Vec<Vec<[i64; 3]>> {
        sets.iter()
            .map(|s| {
                let mut keys: Vec<[i64; 3]> =
                    s.iter().map(|p| p.to_array().map(|x| (x * 1e9).round() as i64)).collect();
                keys.sort_unstable();
                keys
            })
            .collect()
    };
    for other in &groups_of_each[1..] {
        assert_eq!(sorted(&groups_of_each[0]), sorted(other));
    }
}

/// A `$PhysicalNames` line must be `dimension tag "name"` with a dimension 0–3 and the name
/// quoted whole (or one word): an unterminated quote, words after the name or a dimension 7
/// are refused at their line, never read as odd names.
#[test]
fn malformed_physical_names_are_refused_at_their_line() {
    for bad in ["2 1 \"fixed", "2 1 \"fixed\" junk", "7 1 \"fixed\"", "2 1 two words", "x 1 \"fixed\""] {
        let text = CUBE_41.replace("2 1 \"fixed\"", bad);
        let err = malformed(&[("cube.msh", &text)], "cube.msh", "cube.msh", &["line 6", "dimension tag"]);
        assert!(err.to_string().contains(bad), "{bad}: {err}");
    }
    let twice = CUBE_41.replace("3 2 \"solid\"", "2 1 \"solid\"");
    malformed(&[("cube.msh", &twice)], "cube.msh", "cube.msh", &["line 7", "tag 1 is named twice (first \"fixed\")"]);
    // Also across sections: a second $PhysicalNames renaming a group.
    let again = CUBE_41.replace("$Entities\n", "$PhysicalNames\n1\n2 1 \"other\"\n$EndPhysicalNames\n$Entities\n");
    malformed(&[("cube.msh", &again)], "cube.msh", "cube.msh", &["line 11", "tag 1 is named twice (first \"fixed\")"]);
    let unquoted = read_files(&[("cube.msh", &CUBE_41.replace("\"fixed\"", "fixed"))], "cube.msh").unwrap();
    assert_eq!(unquoted.attributes.physical_groups()[0].label(), "fixed");
}
