//! Binary Gmsh `.msh` (4.1 with `size_t` of 8 and 4 bytes, 2.2; little and big endian): files
//! written here exactly per the MSH specification read identically to the ASCII file of the same
//! mesh, files written by Gmsh itself (tests/data/gmsh_box_*, see gmsh_box.geo) likewise, a
//! file cut at every byte ends in one line naming the byte offset, and malformed data is an error
//! naming its byte offset.

use std::path::Path;

use shapeup_core::io::{IoError, LoadedMesh, msh};

// ---------------------------------------------------------------------------------------------
// A test-only MSH writer: one mesh description, written as ASCII or binary 4.1 and 2.2.

/// A block of nodes of one entity; `params` per node when parametric (`dim` values each).
struct NodeBlock {
    dim: i32,
    entity: i32,
    tags: Vec<u64>,
    coords: Vec<[f64; 3]>,
    params: Option<Vec<Vec<f64>>>,
}

/// A block of elements of one type: (element tag, node tags).
struct ElementBlock {
    dim: i32,
    entity: i32,
    kind: i32,
    elements: Vec<(u64, Vec<u64>)>,
}

struct Model {
    nodes: Vec<NodeBlock>,
    elements: Vec<ElementBlock>,
}

/// Sparse node tags in no order over two blocks (one parametric), and points, lines, a
/// triangle, two tetrahedra (one negatively oriented) and a second-order tetrahedron.
fn model() -> Model {
    Model {
        nodes: vec![
            NodeBlock {
                dim: 0,
                entity: 1,
                tags: vec![100, 7, 42],
                coords: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
                params: None,
            },
            NodeBlock {
                dim: 2,
                entity: 1,
                tags: vec![3, 55, 9],
                coords: vec![[0.0, 0.0, 1.0], [1.0, 1.0, 1.0], [0.1, 1.0 / 3.0, -2.5e-300]],
                params: Some(vec![vec![0.25, 0.5], vec![0.75, 0.5], vec![1.0, 2.0]]),
            },
        ],
        elements: vec![
            ElementBlock { dim: 0, entity: 1, kind: 15, elements: vec![(1, vec![100])] },
            ElementBlock { dim: 1, entity: 1, kind: 1, elements: vec![(2, vec![100, 7]), (3, vec![7, 42])] },
            ElementBlock { dim: 2, entity: 1, kind: 2, elements: vec![(4, vec![100, 7, 42])] },
            ElementBlock {
                dim: 3,
                entity: 1,
                kind: 4,
                elements: vec![(10, vec![100, 7, 42, 3]), (20, vec![7, 3, 42, 55]), (30, vec![9, 7, 42, 3])],
            },
            ElementBlock {
                dim: 3,
                entity: 1,
                kind: 11,
                elements: vec![(60, vec![100, 7, 42, 3, 100, 7, 42, 3, 100, 7])],
            },
        ],
    }
}

const PHYSICAL_NAMES: &str = "$PhysicalNames\n2\n3 1 \"volume\"\n2 2 \"skin\"\n$EndPhysicalNames\n";

fn num_nodes(m: &Model) -> usize {
    m.nodes.iter().map(|b| b.tags.len()).sum()
}

fn num_elements(m: &Model) -> usize {
    m.elements.iter().map(|b| b.elements.len()).sum()
}

fn node_tags(m: &Model) -> impl Iterator<Item = u64> + '_ {
    m.nodes.iter().flat_map(|b| b.tags.iter().copied())
}

/// MSH 4.1 ASCII, with `$Entities` and `$NodeData` to skip.
fn ascii_41(m: &Model) -> String {
    let mut s = String::from("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    s += PHYSICAL_NAMES;
    s += "$Entities\n1 1 0 1\n1 0 0 0 1 5\n1 0 0 0 1 1 1 0 2 1 -1\n1 0 0 0 1 1 1 1 1 1 2\n$EndEntities\n";
    let (min, max) = (node_tags(m).min().unwrap(), node_tags(m).max().unwrap());
    s += &format!("$Nodes\n{} {} {min} {max}\n", m.nodes.len(), num_nodes(m));
    for b in &m.nodes {
        s += &format!("{} {} {} {}\n", b.dim, b.entity, u8::from(b.params.is_some()), b.tags.len());
        for t in &b.tags {
            s += &format!("{t}\n");
        }
        for (k, c) in b.coords.iter().enumerate() {
            s += &format!("{:?} {:?} {:?}", c[0], c[1], c[2]);
            for p in b.params.as_ref().map_or(&[][..], |p| &p[k]) {
                s += &format!(" {p:?}");
            }
            s += "\n";
        }
    }
    s += "$EndNodes\n";
    s += &format!("$Elements\n{} {} 1 60\n", m.elements.len(), num_elements(m));
    for b in &m.elements {
        s += &format!("{} {} {} {}\n", b.dim, b.entity, b.kind, b.elements.len());
        for (tag, nodes) in &b.elements {
            let nodes: Vec<String> = nodes.iter().map(u64::to_string).collect();
            s += &format!("{tag} {}\n", nodes.join(" "));
        }
    }
    s += "$EndElements\n$NodeData\n1\n\"t\"\n1\n0.0\n3\n0\n1\n1\n100 3.5\n$EndNodeData\n";
    s
}

/// Binary values in one byte order.
struct Out {
    bytes: Vec<u8>,
    big: bool,
    size_t: usize,
}

impl Out {
    fn text(&mut self, s: &str) {
        self.bytes.extend_from_slice(s.as_bytes());
    }
    fn ordered(&mut self, le: &[u8]) {
        let mut b = le.to_vec();
        if self.big {
            b.reverse();
        }
        self.bytes.extend_from_slice(&b);
    }
    fn int(&mut self, v: i32) {
        self.ordered(&v.to_le_bytes());
    }
    fn size(&mut self, v: u64) {
        if self.size_t == 4 {
            self.ordered(&u32::try_from(v).unwrap().to_le_bytes());
        } else {
            self.ordered(&v.to_le_bytes());
        }
    }
    fn double(&mut self, v: f64) {
        self.ordered(&v.to_le_bytes());
    }
}

/// MSH 4.1 binary as the specification lays it out (and Gmsh writes it): the `int` 1 after the
/// version line, `$Entities` in binary, a line break after each section's binary data, and the
/// `$NodeData` values (an `int` tag and a `double` each) in binary after their ASCII header.
fn binary_41(m: &Model, big: bool, size_t: usize) -> Vec<u8> {
    let mut o = Out { bytes: Vec::new(), big, size_t };
    o.text(&format!("$MeshFormat\n4.1 1 {size_t}\n"));
    o.int(1);
    o.text("\n$EndMeshFormat\n");
    o.text(PHYSICAL_NAMES);
    // One point, one curve (bounded by two points), no surface, one volume (bounded by one).
    o.text("$Entities\n");
    for count in [1, 1, 0, 1] {
        o.size(count);
    }
    o.int(1);
    for x in [0.0, 0.0, 0.0] {
        o.double(x);
    }
    o.size(1);
    o.int(5);
    for (tag, bounds) in [(1, vec![1, -1]), (1, vec![2])] {
        o.int(tag);
        for x in [0.0, 0.0, 0.0, 1.0, 1.0, 1.0] {
            o.double(x);
        }
        o.size(1);
        o.int(1);
        o.size(bounds.len() as u64);
        for b in bounds {
            o.int(b);
        }
    }
    o.text("\n$EndEntities\n$Nodes\n");
    for v in [m.nodes.len() as u64, num_nodes(m) as u64, node_tags(m).min().unwrap(), node_tags(m).max().unwrap()] {
        o.size(v);
    }
    for b in &m.nodes {
        o.int(b.dim);
        o.int(b.entity);
        o.int(i32::from(b.params.is_some()));
        o.size(b.tags.len() as u64);
        for &t in &b.tags {
            o.size(t);
        }
        for (k, c) in b.coords.iter().enumerate() {
            for &x in c {
                o.double(x);
            }
            for &p in b.params.as_ref().map_or(&[][..], |p| &p[k]) {
                o.double(p);
            }
        }
    }
    o.text("\n$EndNodes\n$Elements\n");
    for v in [m.elements.len() as u64, num_elements(m) as u64, 1, 60] {
        o.size(v);
    }
    for b in &m.elements {
        o.int(b.dim);
        o.int(b.entity);
        o.int(b.kind);
        o.size(b.elements.len() as u64);
        for (tag, nodes) in &b.elements {
            o.size(*tag);
            for &n in nodes {
                o.size(n);
            }
        }
    }
    o.text("\n$EndElements\n$NodeData\n1\n\"t\"\n1\n0.0\n3\n0\n1\n1\n");
    o.int(100);
    o.double(3.5);
    o.text("\n$EndNodeData\n");
    o.bytes
}

/// MSH 2.2 ASCII: `tag type 2 physical elementary nodes…`.
fn ascii_22(m: &Model) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
    s += PHYSICAL_NAMES;
    s += &format!("$Nodes\n{}\n", num_nodes(m));
    for b in &m.nodes {
        for (t, c) in b.tags.iter().zip(&b.coords) {
            s += &format!("{t} {:?} {:?} {:?}\n", c[0], c[1], c[2]);
        }
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", num_elements(m));
    for b in &m.elements {
        for (tag, nodes) in &b.elements {
            let nodes: Vec<String> = nodes.iter().map(u64::to_string).collect();
            s += &format!("{tag} {} 2 {} {} {}\n", b.kind, b.dim, b.entity, nodes.join(" "));
        }
    }
    s += "$EndElements\n";
    s
}

/// MSH 2.2 binary: `int` node tags, then per block of one type the header `type following
/// tags` and per element `number physical elementary nodes…`, all `int`s.
fn binary_22(m: &Model, big: bool) -> Vec<u8> {
    let mut o = Out { bytes: Vec::new(), big, size_t: 8 };
    o.text("$MeshFormat\n2.2 1 8\n");
    o.int(1);
    o.text("\n$EndMeshFormat\n");
    o.text(PHYSICAL_NAMES);
    o.text(&format!("$Nodes\n{}\n", num_nodes(m)));
    for b in &m.nodes {
        for (&t, c) in b.tags.iter().zip(&b.coords) {
            o.int(i32::try_from(t).unwrap());
            for &x in c {
                o.double(x);
            }
        }
    }
    o.text(&format!("\n$EndNodes\n$Elements\n{}\n", num_elements(m)));
    for b in &m.elements {
        o.int(b.kind);
        o.int(b.elements.len() as i32);
        o.int(2);
        for (tag, nodes) in &b.elements {
            for v in [i32::try_from(*tag).unwrap(), b.dim, b.entity] {
                o.int(v);
            }
            for &n in nodes {
                o.int(i32::try_from(n).unwrap());
            }
        }
    }
    o.text("\n$EndElements\n");
    o.bytes
}

fn read(bytes: &[u8], name: &str) -> Result<LoadedMesh, IoError> {
    msh::read_msh(bytes, Path::new(name))
}

/// What two reads of one mesh share whatever their encoding: the mesh, its tetrahedra's file
/// order and warnings (an ASCII file's source text is its own).
fn same(
    loaded: &LoadedMesh,
) -> (&shapeup_core::Mesh, Option<&shapeup_core::io::TetrahedronOrder>, &shapeup_core::warnings::Warnings) {
    (&loaded.mesh, loaded.attributes.tetrahedron_order(), &loaded.warnings)
}

fn data(name: &str) -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name)).unwrap()
}

/// The error reading `bytes`, which must be one line naming the file and `byte offset N`; N.
fn offset_error(bytes: &[u8], name: &str) -> (u64, String) {
    let err = read(bytes, name).expect_err("a malformed file").to_string();
    assert!(!err.contains('\n') && err.starts_with(&format!("{name}: byte offset ")), "{err}");
    let offset = err[name.len() + 14..].split(':').next().unwrap().parse().unwrap();
    (offset, err)
}

// ---------------------------------------------------------------------------------------------
// Binary reads as ASCII

#[test]
fn binary_41_reads_as_its_ascii_twin_in_both_byte_orders_and_sizes() {
    let m = model();
    let ascii = read(ascii_41(&m).as_bytes(), "a.msh").unwrap();
    assert_eq!(ascii.mesh.num_vertices(), 6);
    assert_eq!(ascii.mesh.num_tetrahedra(), 3, "types 15, 1, 2 and 11 skipped");
    assert_eq!(ascii.mesh.positions[5].z, -2.5e-300, "coordinates exact");
    for big in [false, true] {
        for size_t in [8, 4] {
            let bytes = binary_41(&m, big, size_t);
            let binary = read(&bytes, "b.msh").unwrap_or_else(|e| panic!("big {big} size_t {size_t}: {e}"));
            assert_eq!(same(&binary), same(&ascii), "big endian {big}, size_t {size_t}");
        }
    }
}

#[test]
fn binary_22_reads_as_its_ascii_twin_in_both_byte_orders() {
    let m = model();
    let ascii = read(ascii_22(&m).as_bytes(), "a.msh").unwrap();
    assert_eq!(same(&ascii), same(&read(ascii_41(&m).as_bytes(), "a.msh").unwrap()), "2.2 and 4.1 hold the same mesh");
    for big in [false, true] {
        assert_eq!(same(&read(&binary_22(&m, big), "b.msh").unwrap()), same(&ascii), "big endian {big}");
    }
}

#[test]
fn triangles_only_binary_is_a_surface_mesh() {
    let mut m = model();
    m.elements.retain(|b| b.kind != 4);
    let ascii = read(ascii_41(&m).as_bytes(), "a.msh").unwrap();
    assert_eq!((ascii.mesh.num_tetrahedra(), ascii.mesh.num_triangles()), (0, 1));
    assert_eq!(same(&read(&binary_41(&m, false, 8), "b.msh").unwrap()), same(&ascii));
    assert_eq!(same(&read(&binary_22(&m, true), "b.msh").unwrap()), same(&ascii));
}

/// `binary` and `ascii` hold the same mesh; Gmsh writes ASCII coordinates with 16 significant
/// digits (`%.16g`), which is not always enough to read back the binary `double` exactly.
fn same_up_to_ascii_digits(binary: &LoadedMesh, ascii: &LoadedMesh) {
    let (b, a) = (&binary.mesh, &ascii.mesh);
    assert_eq!(b.tetrahedra, a.tetrahedra);
    assert_eq!(b.triangles, a.triangles);
    assert_eq!(b.polygons, a.polygons);
    assert_eq!(b.positions.len(), a.positions.len());
    for (p, q) in b.positions.iter().zip(&a.positions) {
        assert!((*p - *q).abs().max_element() <= 1e-15, "{p} vs {q}");
    }
}

#[test]
fn files_written_by_gmsh_read_as_their_ascii_twins() {
    let ascii_41 = read(&data("gmsh_box_41_ascii.msh"), "gmsh_box_41_ascii.msh").unwrap();
    let binary_41 = read(&data("gmsh_box_41_binary.msh"), "gmsh_box_41_binary.msh").unwrap();
    same_up_to_ascii_digits(&binary_41, &ascii_41);
    assert!(ascii_41.mesh.num_tetrahedra() > 50 && ascii_41.mesh.num_vertices() > 50);
    let ascii_22 = read(&data("gmsh_box_22_ascii.msh"), "gmsh_box_22_ascii.msh").unwrap();
    let binary_22 = read(&data("gmsh_box_22_binary.msh"), "gmsh_box_22_binary.msh").unwrap();
    same_up_to_ascii_digits(&binary_22, &ascii_22);
    assert_eq!(same(&binary_22), same(&binary_41), "Gmsh's 2.2 and 4.1 binary files hold the same mesh");
    let groups = |m: &LoadedMesh| m.attributes.physical_groups().to_vec();
    assert_eq!(groups(&binary_22), groups(&binary_41), "and the same physical groups");
    assert_eq!(groups(&binary_41).len(), 4);
    // The box [0, 1] × [0, 0.5] × [0, 0.25] filled: its volume from the tetrahedra.
    let p = &binary_41.mesh.positions;
    let volume: f64 = binary_41
        .mesh
        .tetrahedra
        .iter()
        .map(|t| {
            let [a, b, c, d] = t.map(|v| p[v as usize]);
            (b - a).dot((c - a).cross(d - a)) / 6.0
        })
        .sum();
    assert!((volume - 0.125).abs() < 1e-12, "{volume}");
}

// ---------------------------------------------------------------------------------------------
// Truncated and malformed

/// Each prefix of `bytes` fails with one line naming the byte offset (or a line of the two text
/// lines before the file says it is binary), or, cut just after an `$End…` line, reads as a
/// file without the sections after it (a point cloud, or "no nodes").
fn every_cut_fails_cleanly(bytes: &[u8], name: &str) {
    let version_end = find(bytes, b" 1 ") + 5;
    for cut in 0..bytes.len() {
        let prefix = &bytes[..cut];
        let text = String::from_utf8_lossy(prefix);
        let last = text.trim_end().rsplit('\n').next().unwrap_or("").to_owned();
        let result = read(prefix, name);
        if let Err(err) = &result {
            let message = err.to_string();
            assert!(!message.contains('\n') && message.starts_with(name), "cut at {cut}: {message}");
        }
        match result {
            Err(IoError::Binary { offset, .. }) => assert!(offset <= cut as u64, "cut at {cut}: offset {offset}"),
            Err(IoError::Parse { line, .. }) => assert!(cut < version_end && line <= 2, "cut at {cut}: line {line}"),
            Ok(_) | Err(IoError::Invalid { .. }) => assert!(last.starts_with("$End"), "cut at {cut} after '{last}'"),
            Err(other) => panic!("cut at {cut}: {other}"),
        }
    }
}

#[test]
fn truncated_binary_files_name_the_byte_offset_at_every_cut() {
    let m = model();
    every_cut_fails_cleanly(&binary_41(&m, false, 8), "t.msh");
    every_cut_fails_cleanly(&binary_41(&m, true, 4), "t.msh");
    every_cut_fails_cleanly(&binary_22(&m, true), "t.msh");
    every_cut_fails_cleanly(&data("gmsh_box_41_binary.msh"), "gmsh_box_41_binary.msh");
}

/// The offset of the first occurrence of `needle` in `haystack`.
fn find(haystack: &[u8], needle: &[u8]) -> usize {
    haystack.windows(needle.len()).position(|w| w == needle).unwrap()
}

#[test]
fn malformed_binary_data_is_named_by_its_byte_offset() {
    let m = model();
    let good = binary_41(&m, false, 8);
    let nodes = find(&good, b"$Nodes\n") + 7;
    let elements = find(&good, b"$Elements\n") + 10;

    // Endianness mark other than 1.
    let mut bytes = good.clone();
    bytes[20] = 2;
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == 20 && err.contains("byte order"), "{err}");

    // A node tag defined twice: the second tag of the first block becomes 100.
    let mut bytes = good.clone();
    let second_tag = nodes + 32 + 20 + 8;
    bytes[second_tag..second_tag + 8].copy_from_slice(&100u64.to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == second_tag as u64 && err.contains("node tag 100 is defined twice"), "{err}");

    // An element type that is not Gmsh's: the first block's type becomes 1234.
    let mut bytes = good.clone();
    bytes[elements + 32 + 8..elements + 32 + 12].copy_from_slice(&1234i32.to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == (elements + 40) as u64 && err.contains("element type 1234"), "{err}");

    // A tetrahedron's node that is not defined (the first tetrahedron's last node: tag 3 → 4).
    let tet_block = find(&good[elements..], &[3, 0, 0, 0, 1, 0, 0, 0, 4, 0, 0, 0]) + elements;
    let first_tet = tet_block + 20;
    let mut bytes = good.clone();
    bytes[first_tet + 32..first_tet + 40].copy_from_slice(&4u64.to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == first_tet as u64 && err.contains("element 10: node tag 4 is not defined"), "{err}");

    // A flat tetrahedron, named at its offset: node 55 moved into the plane of 7, 3, 42.
    let mut flat = model();
    flat.nodes[1].coords[1] = [0.5, 0.5, 0.0];
    flat.nodes[1].coords[0] = [0.0, 0.0, 0.0];
    flat.nodes[0].coords[0] = [0.0, 0.0, -1.0];
    let bytes = binary_41(&flat, false, 8);
    let (offset, err) = offset_error(&bytes, "m.msh");
    let second_tet = find(&bytes, &[20, 0, 0, 0, 0, 0, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0]);
    assert!(offset == second_tet as u64 && err.contains("element 20 is flat"), "{err}");

    // Counts that disagree with the blocks.
    let mut bytes = good.clone();
    bytes[nodes + 8..nodes + 16].copy_from_slice(&7u64.to_le_bytes());
    let (_, err) = offset_error(&bytes, "m.msh");
    assert!(err.contains("says 7 nodes, but its blocks hold 6"), "{err}");

    // A parametric flag of 2.
    let mut bytes = good.clone();
    bytes[nodes + 32 + 8..nodes + 32 + 12].copy_from_slice(&2i32.to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == (nodes + 40) as u64 && err.contains("parametric flag 2"), "{err}");

    // Data-size other than 8 or 4, a 2.2 binary file with data-size 4.
    let err = read(b"$MeshFormat\n4.1 1 2\n\x01\0\0\0\n$EndMeshFormat\n", "m.msh").unwrap_err().to_string();
    assert!(err.contains("m.msh: line 2") && err.contains("data-size '2'"), "{err}");
    let err = read(b"$MeshFormat\n2.2 1 4\n\x01\0\0\0\n$EndMeshFormat\n", "m.msh").unwrap_err().to_string();
    assert!(err.contains("m.msh: line 2") && err.contains("data-size '4'"), "{err}");

    // A section that is never closed.
    let cut = &good[..find(&good, b"$EndNodeData")];
    let (offset, err) = offset_error(cut, "m.msh");
    assert!(offset == cut.len() as u64 && err.contains("'$EndNodeData'"), "{err}");

    // Garbage where a section should start.
    let mut bytes = good.clone();
    bytes.extend_from_slice(b"hello\n");
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == good.len() as u64 && err.contains("'hello'"), "{err}");
}

#[test]
fn malformed_binary_22_is_named_by_its_byte_offset() {
    let m = model();
    let good = binary_22(&m, false);
    let elements = find(&good, b"$Elements\n8\n") + 12;
    // More elements announced in a block header than are left.
    let mut bytes = good.clone();
    bytes[elements + 4..elements + 8].copy_from_slice(&9i32.to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == (elements + 4) as u64 && err.contains("9 elements follow, expected 1 to the 8 left"), "{err}");
    // A negative node tag.
    let nodes = find(&good, b"$Nodes\n6\n") + 9;
    let mut bytes = good.clone();
    bytes[nodes..nodes + 4].copy_from_slice(&(-5i32).to_le_bytes());
    let (offset, err) = offset_error(&bytes, "m.msh");
    assert!(offset == nodes as u64 && err.contains("node tag -5"), "{err}");
}

#[test]
fn utf16_text_is_decoded_and_utf16_binary_refused() {
    let m = model();
    let ascii = ascii_41(&m);
    for big in [false, true] {
        let mut bytes = if big { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
        for unit in ascii.encode_utf16() {
            bytes.extend_from_slice(&if big { unit.to_be_bytes() } else { unit.to_le_bytes() });
        }
        let (utf16, utf8) = (read(&bytes, "u.msh").unwrap(), read(ascii.as_bytes(), "u.msh").unwrap());
        assert_eq!(same(&utf16), same(&utf8));
        assert_eq!(utf16.attributes.physical_groups(), utf8.attributes.physical_groups());
    }
    let mut bytes = vec![0xFF, 0xFE];
    for unit in "$MeshFormat\n4.1 1 8\n".encode_utf16() {
        bytes.extend_from_slice(&unit.to_le_bytes());
    }
    let err = read(&bytes, "u.msh").unwrap_err().to_string();
    assert!(err.contains("u.msh: line 2") && err.contains("UTF-16 little endian"), "{err}");
}
