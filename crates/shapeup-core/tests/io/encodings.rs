//! UTF-16 text files (byte-order mark FF FE or FE FF) read exactly as their UTF-8 copies: OBJ,
//! OFF, ascii STL, TetGen pairs and scene files, in both byte orders, with LF and CRLF line
//! endings; malformed UTF-16 is refused in one line naming the file, the encoding and the byte
//! offset; a binary STL whose header starts with FF FE stays binary.

use std::fs;
use std::path::{Path, PathBuf};

use shapeup_core::io::{IoError, LoadedMesh, read_mesh};
use shapeup_core::scene::{Scene, SceneError};

/// `text` as UTF-16 with its byte-order mark, little or big endian.
fn utf16(text: &str, big_endian: bool) -> Vec<u8> {
    let mut bytes = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
    for unit in text.encode_utf16() {
        bytes.extend_from_slice(&if big_endian { unit.to_be_bytes() } else { unit.to_le_bytes() });
    }
    bytes
}

const ENCODINGS: [(&str, bool); 2] = [("le", false), ("be", true)];

/// The text with CRLF line endings.
fn crlf(text: &str) -> String {
    text.replace('\n', "\r\n")
}

/// A loaded mesh with the file's path taken out of its warnings, to compare files of different
/// names.
fn comparable(loaded: LoadedMesh, path: &Path) -> (shapeup_core::mesh::Mesh, String) {
    let warnings = format!("{:?}", loaded.warnings).replace(&path.display().to_string(), "FILE");
    (loaded.mesh, warnings)
}

/// Writes `files` (name, bytes) into a fresh folder and reads the mesh named by the first.
fn read_files(files: &[(&str, Vec<u8>)]) -> Result<(shapeup_core::mesh::Mesh, String), IoError> {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        fs::write(dir.path().join(name), bytes).unwrap();
    }
    let path = dir.path().join(files[0].0);
    read_mesh(&path).map(|loaded| comparable(loaded, &path))
}

/// Every UTF-16 form (both byte orders, LF and CRLF) of each text file reads as the UTF-8 file
/// with the same line endings.
fn reads_as_utf8(files: &[(&str, &str)]) {
    for ending in [false, true] {
        let texts: Vec<(&str, String)> =
            files.iter().map(|(name, text)| (*name, if ending { crlf(text) } else { (*text).to_owned() })).collect();
        let utf8: Vec<(&str, Vec<u8>)> = texts.iter().map(|(n, t)| (*n, t.as_bytes().to_vec())).collect();
        let expected = read_files(&utf8).unwrap_or_else(|e| panic!("UTF-8 {}: {e}", files[0].0));
        for (label, big) in ENCODINGS {
            let encoded: Vec<(&str, Vec<u8>)> = texts.iter().map(|(n, t)| (*n, utf16(t, big))).collect();
            let got = read_files(&encoded).unwrap_or_else(|e| panic!("UTF-16 {label} {}: {e}", files[0].0));
            assert_eq!(got, expected, "UTF-16 {label}, CRLF {ending}: {}", files[0].0);
        }
        // Only one of the TetGen pair in UTF-16 reads the same too.
        if files.len() == 2 {
            let mixed = vec![(texts[0].0, utf16(&texts[0].1, true)), (texts[1].0, texts[1].1.as_bytes().to_vec())];
            assert_eq!(read_files(&mixed).unwrap(), expected, "{}", files[0].0);
        }
    }
}

#[test]
fn utf16_obj_reads_as_its_utf8_copy() {
    let text = "# caf\u{e9} \u{1D11E} (a character outside the BMP: a surrogate pair)\nmtllib m.mtl\n\
                v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nvt 0 0\nvt 1 1\nvn 0 0 1\n\
                g quad \u{e9}t\u{e9}\nf 1/1/1 2/2/1 3/1/1 \\\n 4/2/1\n";
    reads_as_utf8(&[("m.obj", text)]);
    // The mesh is really there (the report was "no vertices").
    let (mesh, _) = read_files(&[("m.obj", utf16(text, false))]).unwrap();
    assert_eq!((mesh.num_vertices(), mesh.num_polygons()), (4, 1));
}

#[test]
fn utf16_off_reads_as_its_utf8_copy() {
    let text = "COFF\n# colours \u{e9}\n4 2 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 9 9 9\n\
                3 0 1 2\n3 0 2 3 0.5 0.5 0.5\n";
    reads_as_utf8(&[("m.off", text)]);
}

#[test]
fn utf16_ascii_stl_reads_as_its_utf8_copy() {
    let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n\
                endfacet\nfacet normal 0 0 1\nouter loop\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\n\
                endfacet\nendsolid t\n";
    reads_as_utf8(&[("t.stl", text)]);
    // It was taken for binary ("triangle 2 of 7471205").
    let (mesh, _) = read_files(&[("t.stl", utf16(text, false))]).unwrap();
    assert_eq!(mesh.triangles.len(), 2);
}

#[test]
fn utf16_tetgen_pair_reads_as_its_utf8_copy() {
    let node = "# points \u{e9}\n5 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n5 1 1 1\n";
    let ele = "2 4 0\n1 1 2 3 4\n2 2 3 4 5\n";
    reads_as_utf8(&[("m.node", node), ("m.ele", ele)]);
    reads_as_utf8(&[("m.ele", ele), ("m.node", node)]);
}

#[test]
fn binary_stl_whose_header_starts_like_utf16_stays_binary() {
    let mut bytes = vec![b' '; 80];
    bytes[..4].copy_from_slice(&[0xFF, 0xFE, b's', 0]);
    bytes.extend_from_slice(&1u32.to_le_bytes());
    for v in [[0.0f32, 0.0, 1.0], [0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    bytes.extend_from_slice(&[0, 0]);
    for mark in [[0xFF, 0xFE], [0xFE, 0xFF]] {
        bytes[..2].copy_from_slice(&mark);
        let (mesh, _) = read_files(&[("b.stl", bytes.clone())]).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
        assert_eq!(mesh.positions[1].x, 1.0);
    }
    // Truncated, it is still reported as binary STL, not as text.
    let err = read_files(&[("b.stl", bytes[..bytes.len() - 10].to_vec())]).unwrap_err().to_string();
    assert!(err.contains("b.stl") && err.contains("triangle 0 of 1"), "{err}");
}

/// The error of reading `bytes` as `name`, checked to be one line naming the file, the encoding
/// and `offset`.
fn refused(name: &str, bytes: Vec<u8>, encoding: &str, offset: usize) {
    let err = read_files(&[(name, bytes)]).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, IoError::Binary { offset: o, .. } if o as usize == offset), "{name}: {message}");
    assert!(
        message.contains(name) && message.contains(encoding) && message.contains(&format!("byte offset {offset}")),
        "{name}: {message}"
    );
    assert!(!message.contains('\n'), "{message}");
}

#[test]
fn malformed_utf16_is_refused_naming_the_encoding_and_offset() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    // An odd number of bytes: the last one is half a unit.
    let mut odd = utf16(obj, false);
    let len = odd.len();
    odd.push(b'x');
    refused("odd.obj", odd, "UTF-16 little endian", len);
    // An unpaired high surrogate before 'f' (byte offset 2 + 2 × units before it).
    let before = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let mut lone = utf16(before, true);
    lone.extend_from_slice(&[0xD8, 0x00]);
    lone.extend_from_slice(&utf16("f 1 2 3\n", true)[2..]);
    refused("lone.obj", lone.clone(), "UTF-16 big endian", 2 + 2 * before.len());
    // A lone low surrogate in each other text format.
    let lone_low = |text: &str, at: usize| {
        let mut bytes = utf16(&text[..at], false);
        bytes.extend_from_slice(&[0x00, 0xDC]);
        bytes.extend_from_slice(&utf16(&text[at..], false)[2..]);
        (bytes, 2 + 2 * at)
    };
    let off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let (bytes, offset) = lone_low(off, 20);
    refused("lone.off", bytes, "UTF-16 little endian", offset);
    let stl = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\n\
               endfacet\nendsolid t\n";
    let (bytes, offset) = lone_low(stl, 30);
    refused("lone.stl", bytes, "UTF-16 little endian", offset);
    let node = "4 3 0 0\n1 0 0 0\n2 1 0 0\n3 0 1 0\n4 0 0 1\n";
    let ele = "1 4 0\n1 1 2 3 4\n";
    let (bytes, offset) = lone_low(node, 12);
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("m.node"), bytes).unwrap();
    fs::write(dir.path().join("m.ele"), ele).unwrap();
    let err = read_mesh(&dir.path().join("m.ele")).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, IoError::Binary { .. }), "{message}");
    assert!(
        message.contains("m.node") && message.contains("UTF-16") && message.contains(&format!("byte offset {offset}")),
        "{message}"
    );
    let (bytes, offset) = lone_low(ele, 8);
    fs::write(dir.path().join("m.node"), node).unwrap();
    fs::write(dir.path().join("m.ele"), bytes).unwrap();
    let message = read_mesh(&dir.path().join("m.node")).unwrap_err().to_string();
    assert!(message.contains("m.ele") && message.contains(&format!("byte offset {offset}")), "{message}");
}

fn scene_dir() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("m.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let path = dir.path().to_path_buf();
    (dir, path)
}

#[test]
fn utf16_scene_files_parse_as_their_utf8_copies() {
    let (_keep, dir) = scene_dir();
    let toml = "# caf\u{e9}\n[mesh]\npath = \"m.obj\"\n\n[solver]\niterations = 7\n\n[[constraints]]\n\
                type = \"edge_strain\"\nname = \"\u{e9}l\u{e8}ve\"\nweight = 2.0\n";
    let json = "{\n  \"mesh\": {\"path\": \"m.obj\"},\n  \"solver\": {\"iterations\": 7},\n  \"constraints\": \
                [{\"type\": \"edge_strain\", \"name\": \"\u{e9}l\u{e8}ve\", \"weight\": 2.0}]\n}\n";
    for (ext, text) in [("toml", toml), ("json", json)] {
        for ending in [false, true] {
            let text = if ending { crlf(text) } else { text.to_owned() };
            let utf8 = dir.join(format!("s.{ext}"));
            fs::write(&utf8, &text).unwrap();
            let expected = Scene::from_file(&utf8).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(expected.solver.iterations, 7);
            for (label, big) in ENCODINGS {
                let path = dir.join(format!("s_{label}.{ext}"));
                fs::write(&path, utf16(&text, big)).unwrap();
                let mut scene = Scene::from_file(&path).unwrap_or_else(|e| panic!("{label} {ext}: {e}"));
                assert_eq!(scene.file, path);
                scene.file = utf8.clone();
                assert_eq!(scene, expected, "{label} {ext} CRLF {ending}");
            }
        }
    }
}

#[test]
fn malformed_scene_text_is_a_parse_error_naming_the_encoding() {
    let (_keep, dir) = scene_dir();
    let mut bytes = utf16("[mesh]\npath = \"m.obj\"\n", false);
    bytes.push(b'\n');
    let path = dir.join("odd.toml");
    fs::write(&path, &bytes).unwrap();
    let err = Scene::from_file(&path).unwrap_err();
    let message = err.to_string();
    assert!(matches!(err, SceneError::Parse { .. }), "{message}");
    assert!(
        message.contains("odd.toml")
            && message.contains("UTF-16 little endian")
            && message.contains(&format!("byte offset {}", bytes.len() - 1)),
        "{message}"
    );
    // Invalid UTF-8 says where, too (it was "stream did not contain valid UTF-8").
    let path = dir.join("latin1.toml");
    fs::write(&path, b"[mesh]\npath = \"caf\xe9.obj\"\n").unwrap();
    let message = Scene::from_file(&path).unwrap_err().to_string();
    assert!(
        message.contains("latin1.toml") && message.contains("UTF-8") && message.contains("byte offset 18"),
        "{message}"
    );
}
