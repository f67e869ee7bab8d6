//! Hostile inputs for the text readers (OBJ, OFF, STL ascii and binary, TetGen): files under
//! 10 KB that claim huge element counts, very long lines and repeated continuation lines are
//! refused, or read, in time and memory in proportion to their real size; per-element work is
//! linear (a face of 150,000 corners, a line of two million backslashes).
//!
//! Memory is measured with a counting global allocator, so this file holds only these tests and
//! runs them one at a time; each runs on its own thread under a 60 s watchdog (a hang check, far
//! above the real time, not a timing assertion).

use std::fmt::Write as _;
use std::path::Path;
use std::sync::atomic::Ordering;

use crate::{CURRENT, PEAK, SERIAL};
use std::time::Duration;

use shapeup_core::io::{IoError, LoadedMesh, obj, off, stl, tetgen};

const MB: usize = 1 << 20;

/// Runs `f` on its own thread, failing after 60 s (a hang), and returns its result and the peak
/// bytes allocated above what was allocated before.
fn measured<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> (T, usize) {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let base = CURRENT.load(Ordering::Relaxed);
    PEAK.store(base, Ordering::Relaxed);
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = send.send(f());
    });
    let value = receive.recv_timeout(Duration::from_secs(60)).expect("no answer within 60 s (a hang)");
    (value, PEAK.load(Ordering::Relaxed).saturating_sub(base))
}

type Reader = fn(&[u8], &Path) -> Result<LoadedMesh, IoError>;

fn read_obj(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    obj::read_obj(bytes, path)
}

fn read_off(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    off::read_off(bytes, path)
}

fn read_stl(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    stl::read_stl(bytes, path)
}

/// Reads `bytes` as `name` with `read` under the watchdog, checking that the peak allocation
/// stays under `limit`; returns the result (errors as their one line).
fn run(read: Reader, name: &'static str, bytes: Vec<u8>, limit: usize) -> Result<LoadedMesh, String> {
    let len = bytes.len();
    let (result, peak) = measured(move || read(&bytes, Path::new(name)).map_err(|e| e.to_string()));
    assert!(peak < limit, "{name} ({len} bytes) took {} MB at the peak (limit {} MB)", peak / MB, limit / MB);
    if let Err(message) = &result {
        assert!(message.contains(name) && !message.contains('\n'), "{message}");
    }
    result
}

/// What a small input may take: on a header's claim a reader reserves one vector of at most
/// 16 MiB up front (TetGen's `.node` then `.ele`: one each, the first freed), and grows past
/// that only as data arrives. (Before, an OFF file claiming 10⁹ faces reserved 48 MB.)
const SMALL_INPUT_LIMIT: usize = 32 * MB;

/// A small input (under 10 KB) that must be refused within [`SMALL_INPUT_LIMIT`]; returns its
/// error.
fn refused(read: Reader, name: &'static str, text: &[u8], needles: &[&str]) -> String {
    assert!(text.len() < 10 * 1024, "{name}: a hostile input is under 10 KB");
    let message = run(read, name, text.to_vec(), SMALL_INPUT_LIMIT).expect_err(name);
    for needle in needles {
        assert!(message.contains(needle), "{name}: {message} (expected '{needle}')");
    }
    message
}

#[test]
fn off_claiming_huge_counts_is_refused_in_small_memory() {
    let _whole_test = crate::whole_test();
    refused(read_off, "huge.off", b"OFF\n1000000000 1000000000 0\n0 0 0\n", &["line 4", "1 of 1000000000 vertices"]);
    refused(read_off, "glued.off", b"OFF1000000000 1000000000 0\n", &["line 2", "0 of 1000000000 vertices"]);
    let faces = b"OFF\n3 4000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    refused(read_off, "faces.off", faces, &["line 7", "1 of 4000000000 faces"]);
    // A face claiming 4e9 corners, its indices continuing over lines until the file ends.
    let mut corners = String::from("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000000\n");
    for _ in 0..1000 {
        corners.push_str("0 1 2\n");
    }
    refused(read_off, "corners.off", corners.as_bytes(), &["line 6", "lists 3000 of its 4000000000"]);
    refused(read_off, "overflow.off", b"OFF\n99999999999999999999999 1 0\n", &["line 2", "bad counts"]);
}

#[test]
fn stl_claiming_huge_counts_is_refused_in_small_memory() {
    let _whole_test = crate::whole_test();
    let mut binary = vec![b' '; 80];
    binary.extend_from_slice(&4_000_000_000u32.to_le_bytes());
    binary.extend_from_slice(&[0; 50 * 3]);
    refused(read_stl, "huge.stl", &binary, &["triangle 3 of 4000000000"]);
    // The same bytes with a header that says "solid": still binary (NUL bytes), still refused.
    binary[..5].copy_from_slice(b"solid");
    refused(read_stl, "solid.stl", &binary, &["4000000000"]);
    // An ascii facet of 500 vertices ends where the file does.
    let mut ascii = String::from("solid x\nfacet normal 0 0 1\nouter loop\n");
    for i in 0..500 {
        writeln!(ascii, "vertex {i} 0 0").unwrap();
    }
    refused(read_stl, "open.stl", ascii.as_bytes(), &["line 504", "file ends inside facet 0"]);
}

fn read_pair(node: &'static str, ele: &'static str) -> Result<LoadedMesh, String> {
    let (result, peak) = measured(move || {
        tetgen::read_tetgen(node.as_bytes(), Path::new("h.node"), ele.as_bytes(), Path::new("h.ele"))
            .map_err(|e| e.to_string())
    });
    assert!(peak < SMALL_INPUT_LIMIT, "{node:?} / {ele:?}: {} MB at the peak", peak / MB);
    result
}

#[test]
fn tetgen_claiming_huge_counts_is_refused_in_small_memory() {
    let _whole_test = crate::whole_test();
    const NODE: &str = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    const ELE: &str = "1 4 0\n1 1 2 3 4\n";
    assert!(read_pair(NODE, ELE).is_ok());
    for (node, ele, needles) in [
        ("2147483648 3 0 0\n1 0 0 0\n", ELE, &["h.node: line 3", "point 2 of 2147483648"][..]),
        ("4294967296 3 0 0\n", ELE, &["h.node: line 1", "more than a mesh can index"]),
        ("99999999999999999999999 3\n", ELE, &["h.node: line 1", "bad header"]),
        (NODE, "1099511627776 4 0\n1 1 2 3 4\n", &["h.ele: line 3", "tetrahedron 2 of 1099511627776"]),
        (NODE, "1 4294967295 0\n1 1 2 3 4\n", &["h.ele: line 1", "4294967295 nodes per tetrahedron"]),
        (NODE, "1 18446744073709551615 0\n1 1 2 3 4\n", &["h.ele: line 1", "nodes per tetrahedron"]),
    ] {
        let message = read_pair(node, ele).expect_err(node);
        for needle in needles {
            assert!(message.contains(needle), "{message} (expected '{needle}')");
        }
    }
    // Attribute and marker counts are claims too: the points carry none, and read as they are.
    let loaded = read_pair("4 3 4294967295 4294967295\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n", ELE).unwrap();
    assert_eq!(loaded.mesh.num_tetrahedra(), 1);
}

#[test]
fn obj_continuation_lines_join_in_linear_time() {
    let _whole_test = crate::whole_test();
    // Thousands of continuation lines make one logical line, a face of 3,000 corners.
    let mut text = String::new();
    for i in 0..3000 {
        writeln!(text, "v {i} {} 0", i % 7).unwrap();
    }
    text.push('f');
    for i in 1..=3000 {
        writeln!(text, " {i} \\").unwrap();
    }
    text.push('\n');
    let loaded = run(read_obj, "joined.obj", text.into_bytes(), SMALL_INPUT_LIMIT).unwrap();
    assert_eq!(loaded.mesh.polygons.get(0).map(<[u32]>::len), Some(3000));
    // A file of nothing but continuations is one (empty) logical line: no vertices.
    let only = "\\\n".repeat(4000);
    let message = run(read_obj, "only.obj", only.into_bytes(), SMALL_INPUT_LIMIT).unwrap_err();
    assert!(message.contains("no vertices"), "{message}");
    // Two million backslashes on one line, none of them a continuation but the last: each was
    // looked at up to the end of its line (quadratic, minutes).
    let mut line = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng");
    line.push_str(&" \\".repeat(2_000_000));
    line.push_str(" x \\\n y\n");
    let len = line.len();
    let loaded = run(read_obj, "backslashes.obj", line.into_bytes(), 40 * len).unwrap();
    assert_eq!(loaded.mesh.num_vertices(), 3);
}

#[test]
fn long_lines_are_read_in_proportion() {
    let _whole_test = crate::whole_test();
    let comment = format!("# {}\n", "x".repeat(4 * MB));
    let obj = format!("{comment}v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let len = obj.len();
    assert!(run(read_obj, "long.obj", obj.into_bytes(), 8 * len).is_ok());
    let off = format!("OFF\n{comment}3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    assert!(run(read_off, "long.off", off.into_bytes(), 8 * len).is_ok());
    let stl = format!("solid {}\nendsolid\n", "x".repeat(4 * MB));
    let message = run(read_stl, "long.stl", stl.into_bytes(), 8 * len).unwrap_err();
    assert!(message.contains("no triangles"), "{message}");
    // One huge token where a count belongs.
    let off = format!("OFF\n{} 1 0\n", "9".repeat(4 * MB));
    let message = run(read_off, "digits.off", off.into_bytes(), 8 * len).unwrap_err();
    assert!(message.contains("bad counts"), "{}", &message[..message.len().min(200)]);
}

/// A 150,000-corner convex face (its corners on a circle), the indices on one `f` line or, in
/// OFF, one face record.
#[test]
fn a_face_of_150000_corners_reads_in_linear_time() {
    let _whole_test = crate::whole_test();
    const N: usize = 150_000;
    let point = |i: usize| {
        let t = i as f64 / N as f64 * std::f64::consts::TAU;
        (t.cos(), t.sin())
    };
    let mut obj = String::new();
    let mut off = format!("OFF\n{N} 1 0\n");
    for i in 0..N {
        let (x, y) = point(i);
        writeln!(obj, "v {x} {y} 0").unwrap();
        writeln!(off, "{x} {y} 0").unwrap();
    }
    obj.push('f');
    write!(off, "{N}").unwrap();
    for i in 0..N {
        write!(obj, " {}", i + 1).unwrap();
        write!(off, " {i}").unwrap();
    }
    obj.push('\n');
    off.push('\n');
    let limit = 40 * obj.len();
    let loaded = run(read_obj, "big_face.obj", obj.into_bytes(), limit).unwrap();
    assert_eq!(loaded.mesh.polygons.get(0).map(<[u32]>::len), Some(N));
    let loaded = run(read_off, "big_face.off", off.into_bytes(), limit).unwrap();
    assert_eq!(loaded.mesh.polygons.get(0).map(<[u32]>::len), Some(N));
}
