//! Hostile sizes for the PLY and Gmsh readers: inputs of a few KB that claim 2³¹ elements, lists
//! of 4·10⁹ items, 2⁶⁰ nodes or blocks, hundreds of properties, or lines of many KB are refused
//! in time and memory proportional to their real size (a counting allocator bounds the peak, a
//! watchdog catches hangs), with one line naming the file and the line or byte offset. Also
//! UTF-16 PLY files: an ascii one is decoded, a binary one refused naming the encoding.

use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::mpsc;

use crate::{CURRENT as LIVE, PEAK, SERIAL as ONE_AT_A_TIME};
use std::time::Duration;

use shapeup_core::io::{IoError, LoadedMesh, msh, ply};

/// Most bytes a hostile input of a few KB may have live at once while it is read.
const PEAK_LIMIT: usize = 64 << 20;
/// A read that takes longer has hung (the inputs take milliseconds).
const WATCHDOG: Duration = Duration::from_secs(30);

type Reader = fn(&[u8], &Path) -> Result<LoadedMesh, IoError>;

fn read_ply(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    ply::read_ply(bytes, path)
}

fn read_msh(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    msh::read_msh(bytes, path)
}

/// Reads `bytes` with `reader` on a watched thread; returns the result and the peak of the
/// bytes allocated above what was live before.
fn watched(reader: Reader, bytes: Vec<u8>, name: &'static str) -> (Result<LoadedMesh, IoError>, usize) {
    let base = LIVE.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        let result = reader(&bytes, Path::new(name));
        // The receiver may have given up (a hang already reported).
        let _ = send.send(result);
    });
    let result = receive.recv_timeout(WATCHDOG).unwrap_or_else(|_| panic!("{name}: no answer in {WATCHDOG:?}"));
    (result, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

/// Each input must be under 10 KB and be refused with one line naming `name` and containing
/// every one of its `expected` strings, within the peak limit.
fn refused(reader: Reader, name: &'static str, cases: Vec<(Vec<u8>, Vec<&str>)>) {
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    for (i, (bytes, expected)) in cases.into_iter().enumerate() {
        assert!(bytes.len() < 10_000, "{name} case {i} is {} bytes", bytes.len());
        let (result, peak) = watched(reader, bytes, name);
        let err = result.err().unwrap_or_else(|| panic!("{name} case {i} was read")).to_string();
        assert!(!err.contains('\n') && err.starts_with(name) && err.len() < 400, "{name} case {i}: {err}");
        for e in expected {
            assert!(err.contains(e), "{name} case {i}: '{e}' not in: {err}");
        }
        assert!(peak < PEAK_LIMIT, "{name} case {i}: peak {peak} bytes ({err})");
    }
}

const PLY_VERTEX: &str = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n";

fn ascii_ply(header: &str, body: &str) -> Vec<u8> {
    format!("ply\nformat ascii 1.0\n{header}end_header\n{body}").into_bytes()
}

fn binary_ply(header: &str, body: &[u8]) -> Vec<u8> {
    let mut bytes = format!("ply\nformat binary_little_endian 1.0\n{header}end_header\n").into_bytes();
    bytes.extend_from_slice(body);
    bytes
}

/// Three vertices as three little-endian `float`s each.
fn le_vertices() -> Vec<u8> {
    [0f32, 0., 0., 1., 0., 0., 0., 1., 0.].iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// `n` properties `uchar pK` (a header of about 20 bytes each).
fn many_properties(n: usize) -> String {
    (0..n).map(|k| format!("property uchar p{k}\n")).collect()
}

/// `n` elements, each claiming `count` instances of one `uchar` property.
fn many_elements(n: usize, count: &str) -> String {
    (0..n).map(|k| format!("element e{k} {count}\nproperty uchar v\n")).collect()
}

#[test]
fn ascii_ply_with_hostile_sizes_is_refused_in_proportion() {
    let _whole_test = crate::whole_test();
    let faces = "element face 1\nproperty list uint int vertex_indices\n";
    let strips = "element tristrips 1\nproperty list uint int vertex_indices\n";
    let long_word = "w".repeat(9000);
    refused(
        read_ply,
        "a.ply",
        vec![
            // 2³¹ vertices claimed, one given.
            (ascii_ply(&PLY_VERTEX.replace(" 3\n", " 2147483648\n"), "0 0 0\n"), vec!["line 9", "vertex' 1 of"]),
            // A face and a strip of 4·10⁹ items, three given.
            (
                ascii_ply(&format!("{PLY_VERTEX}{faces}"), "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"),
                vec!["line 13", "too few values"],
            ),
            (
                ascii_ply(&format!("{PLY_VERTEX}{strips}"), "0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n"),
                vec!["line 13", "too few values"],
            ),
            // 400 properties of an element claiming 2³¹ instances.
            (
                ascii_ply(
                    &format!("{PLY_VERTEX}element many 2147483648\n{}", many_properties(400)),
                    "0 0 0\n1 0 0\n0 1 0\n",
                ),
                vec!["line 412", "file ends before element 'many' 0 of 2147483648"],
            ),
            // 180 elements each claiming 2⁴⁰ instances.
            (
                ascii_ply(&format!("{}{PLY_VERTEX}", many_elements(180, "1099511627776")), "0\n"),
                vec!["file ends before element 'e0' 1 of 1099511627776"],
            ),
            // A header line of 9000 characters: its word is cut short in the message.
            (
                ascii_ply(&format!("{PLY_VERTEX}property float {long_word} x\n"), ""),
                vec!["line 7", "malformed property", "…"],
            ),
            (ascii_ply(&format!("{PLY_VERTEX}{long_word}\n"), ""), vec!["line 7", "unexpected header line"]),
        ],
    );
}

#[test]
fn binary_ply_with_hostile_sizes_is_refused_in_proportion() {
    let _whole_test = crate::whole_test();
    let faces = "element face 1\nproperty list uint int vertex_indices\n";
    let strips = "element tristrips 1\nproperty list uint int vertex_indices\n";
    let mut claim_4e9 = le_vertices();
    claim_4e9.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    claim_4e9.extend(std::iter::repeat_n(0u8, 64));
    refused(
        read_ply,
        "b.ply",
        vec![
            (
                binary_ply(&PLY_VERTEX.replace(" 3\n", " 2147483648\n"), &le_vertices()),
                vec!["byte offset", "file ends inside element 'vertex' 3 of 2147483648"],
            ),
            (
                binary_ply(&format!("{PLY_VERTEX}{faces}"), &claim_4e9),
                vec!["byte offset", "file ends inside element 'face' 0"],
            ),
            (binary_ply(&format!("{PLY_VERTEX}{strips}"), &claim_4e9), vec!["byte offset", "'tristrips' 0"]),
            (
                binary_ply(&format!("{PLY_VERTEX}element many 2147483648\n{}", many_properties(400)), &le_vertices()),
                vec!["byte offset", "file ends inside element 'many' 0"],
            ),
            (
                binary_ply(&format!("{}{PLY_VERTEX}", many_elements(180, "1099511627776")), &[7; 100]),
                vec!["byte offset", "file ends inside element 'e0' 100"],
            ),
        ],
    );
}

#[test]
fn a_face_of_150000_corners_reads_in_a_1_mb_ply() {
    let _whole_test = crate::whole_test();
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    // A convex polygon: its triangulation is simple, so only the reading is measured.
    let n = 150_000;
    let mut body = String::new();
    for k in 0..n {
        let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
        body += &format!("{:.6} {:.6} 0\n", a.cos(), a.sin());
    }
    body += &format!("{n}");
    for k in 0..n {
        body += &format!(" {k}");
    }
    body += "\n";
    let header = format!(
        "element vertex {n}\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uint int vertex_indices\n"
    );
    let bytes = ascii_ply(&header, &body);
    assert!(bytes.len() < 5 << 20);
    let (result, _) = watched(read_ply, bytes, "big.ply");
    let mesh = result.unwrap().mesh;
    assert_eq!((mesh.num_vertices(), mesh.num_polygons()), (n as usize, 1));
    assert_eq!(mesh.polygons.iter().next().unwrap().len(), n as usize);
}

const HUGE: &str = "1152921504606846976"; // 2⁶⁰

#[test]
fn ascii_msh_with_hostile_sizes_is_refused_in_proportion() {
    let _whole_test = crate::whole_test();
    let head = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n";
    let nodes = "$Nodes\n1 3 1 3\n0 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n";
    let case = |s: String| s.into_bytes();
    refused(
        read_msh,
        "a.msh",
        vec![
            (
                case(format!("{head}$Nodes\n1 {HUGE} 1 3\n0 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n")),
                vec!["line 13", "says 1152921504606846976 nodes"],
            ),
            (
                case(format!("{head}$Nodes\n{HUGE} 3 1 3\n0 1 0 3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n")),
                vec!["line 13", "node block 2 of"],
            ),
            (case(format!("{head}$Nodes\n1 3 1 3\n0 1 0 {HUGE}\n1\n2\n3\n")), vec!["line 10", "tag 4 of"]),
            (
                case(format!("{head}{nodes}$Elements\n1 {HUGE} 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n")),
                vec!["says 1152921504606846976 elements"],
            ),
            (case(format!("{head}{nodes}$Elements\n{HUGE} 1 1 1\n2 1 2 1\n1 1 2 3\n")), vec!["element block 2 of"]),
            (case(format!("{head}{nodes}$Elements\n1 1 1 1\n2 1 2 {HUGE}\n1 1 2 3\n")), vec!["element 2 of"]),
            (
                case(format!("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n{HUGE}\n1 0 0 0\n")),
                vec!["line 7", "node 2 of"],
            ),
            (
                case(format!("{head}{nodes}$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 {}\n$EndElements\n", "9".repeat(8000))),
                vec!["node tag '99999", "…"],
            ),
        ],
    );
}

/// A binary MSH 4.1 file (little endian, `size_t` of 8 bytes): the text before its sections.
fn binary_msh_head() -> Vec<u8> {
    let mut bytes = b"$MeshFormat\n4.1 1 8\n".to_vec();
    bytes.extend_from_slice(&1i32.to_le_bytes());
    bytes.extend_from_slice(b"\n$EndMeshFormat\n");
    bytes
}

fn sizes(values: &[u64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn ints(values: &[i32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// One node block of nodes 1, 2, 3 (header counts `blocks` and `count`), closed.
fn binary_nodes(blocks: u64, count: u64, in_block: u64) -> Vec<u8> {
    let mut b = b"$Nodes\n".to_vec();
    b.extend(sizes(&[blocks, count, 1, 3]));
    b.extend(ints(&[0, 1, 0]));
    b.extend(sizes(&[in_block, 1, 2, 3]));
    // Distinct and non-zero, so that a block claiming more nodes takes them for tags.
    for k in 0..9 {
        b.extend((0.5 + 0.25 * f64::from(k)).to_le_bytes());
    }
    b.extend(b"\n$EndNodes\n");
    b
}

#[test]
fn binary_msh_with_hostile_sizes_is_refused_in_proportion() {
    let _whole_test = crate::whole_test();
    let huge = 1u64 << 60;
    let join = |parts: &[&[u8]]| parts.concat();
    let head = binary_msh_head();
    let nodes = binary_nodes(1, 3, 3);
    let elements = |blocks: u64, count: u64, kind: i32, n: u64| {
        let mut b = b"$Elements\n".to_vec();
        b.extend(sizes(&[blocks, count, 1, 1]));
        b.extend(ints(&[2, 1, kind]));
        b.extend(sizes(&[n, 1, 1, 2, 3]));
        b.extend(b"\n$EndElements\n");
        b
    };
    let mut entities = b"$Entities\n".to_vec();
    entities.extend(sizes(&[huge, 0, 0, 0]));
    entities.extend(ints(&[1]));
    entities.extend(sizes(&[0, 0, 0, 0]));
    let mut physical = b"$Entities\n".to_vec();
    physical.extend(sizes(&[1, 0, 0, 0]));
    physical.extend(ints(&[1]));
    physical.extend(sizes(&[0, 0, 0, huge, 1]));
    let mut v22 = b"$MeshFormat\n2.2 1 8\n".to_vec();
    v22.extend(ints(&[1]));
    v22.extend(b"\n$EndMeshFormat\n$Nodes\n");
    let mut v22_nodes = v22.clone();
    v22_nodes.extend(format!("{HUGE}\n").bytes());
    v22_nodes.extend(ints(&[1]));
    v22_nodes.extend(sizes(&[0, 0, 0]));
    let mut v22_elements = v22;
    v22_elements.extend(b"1\n");
    v22_elements.extend(ints(&[1]));
    v22_elements.extend(sizes(&[0, 0, 0]));
    v22_elements.extend(format!("\n$EndNodes\n$Elements\n{HUGE}\n").bytes());
    v22_elements.extend(ints(&[15, 1 << 30, 0, 1, 1]));
    refused(
        read_msh,
        "b.msh",
        vec![
            (join(&[&head, &binary_nodes(1, huge, 3)]), vec!["byte offset", "says 1152921504606846976 nodes"]),
            (join(&[&head, &binary_nodes(huge, 3, 3)]), vec!["byte offset", "node block 2 of 1152921504606846976"]),
            (join(&[&head, &binary_nodes(1, 3, huge)]), vec!["byte offset", "tag 14 of 1152921504606846976"]),
            (join(&[&head, &nodes, &elements(1, huge, 2, 1)]), vec!["says 1152921504606846976 elements"]),
            (join(&[&head, &nodes, &elements(huge, 1, 2, 1)]), vec!["element block 2 of 1152921504606846976"]),
            (join(&[&head, &nodes, &elements(1, huge, 2, huge)]), vec!["element 2 of 1152921504606846976"]),
            // Skipped types: their size is computed, never looped over.
            (join(&[&head, &nodes, &elements(1, huge, 1, huge)]), vec!["more bytes than a file can hold"]),
            (join(&[&head, &nodes, &elements(1, huge, 15, huge / 2)]), vec!["file ends inside element block 1"]),
            (join(&[&head, &entities]), vec!["byte offset", "point entity 2 of 1152921504606846976"]),
            (join(&[&head, &physical]), vec!["byte offset", "point entity 1 of 1"]),
            (v22_nodes, vec!["byte offset", "node 2 of 1152921504606846976"]),
            (v22_elements, vec!["byte offset", "elements 1 to 1073741824"]),
        ],
    );
}

#[test]
fn utf16_ply_is_decoded_when_ascii_and_refused_when_binary() {
    let _whole_test = crate::whole_test();
    let _guard = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let text = String::from_utf8(ascii_ply(
        &format!("{PLY_VERTEX}element face 1\nproperty list uchar int vertex_indices\n"),
        "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    ))
    .unwrap();
    let utf8 = ply::read_ply(text.as_bytes(), Path::new("u.ply")).unwrap();
    for big in [false, true] {
        let mut bytes = if big { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
        for unit in text.encode_utf16() {
            bytes.extend_from_slice(&if big { unit.to_be_bytes() } else { unit.to_le_bytes() });
        }
        assert_eq!(ply::read_ply(&bytes[..], Path::new("u.ply")).unwrap(), utf8, "big endian {big}");
    }
    let mut bytes = vec![0xFF, 0xFE];
    for unit in "ply\nformat binary_little_endian 1.0\n".encode_utf16() {
        bytes.extend_from_slice(&unit.to_le_bytes());
    }
    let err = ply::read_ply(&bytes[..], Path::new("u.ply")).unwrap_err().to_string();
    assert!(err.contains("u.ply: line 2") && err.contains("UTF-16 little endian"), "{err}");
    // Malformed UTF-16 (an unpaired surrogate) is named by its byte offset.
    let mut bytes = vec![0xFF, 0xFE];
    for unit in "ply\nformat ascii 1.0\n".encode_utf16() {
        bytes.extend_from_slice(&unit.to_le_bytes());
    }
    bytes.extend_from_slice(&0xD800u16.to_le_bytes());
    bytes.extend_from_slice(&u16::from(b'x').to_le_bytes());
    let err = ply::read_ply(&bytes[..], Path::new("u.ply")).unwrap_err().to_string();
    assert!(err.contains("u.ply: byte offset 44") && err.contains("UTF-16"), "{err}");
}
