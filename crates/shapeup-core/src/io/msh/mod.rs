//! Gmsh `.msh`: versions 4.1 and 2.2 (2.0 and 2.1 read as 2.2), ASCII and binary.
//!
//! Read: `$MeshFormat`, `$Nodes`, `$Elements`, `$PhysicalNames` and (4.1) `$Entities`, for the
//! physical groups ([`PhysicalGroup`]: the nodes of every element, of any type, whose physical
//! tag is the group's: 2.2's first element tag, 4.1's entity's physical tags), which scenes
//! select (`physical = "NAME"`). Every other section (`$NodeData`, `$Periodic`, …) is skipped
//! up to its `$End…` line, which binary files always put on a line of its own after their data. Node tags may be sparse
//! and in any order: vertex *i* of the mesh is the *i*-th node of the file. Element type 4 (4-node
//! tetrahedron) and type 2 (3-node triangle) are read; every other type (points, lines, quads,
//! second-order elements, …) is skipped (in binary files by its number of nodes, from Gmsh's table
//! of element types: an unknown type is an error there). With tetrahedra, the mesh's triangles
//! are their boundary ([`tetrahedron_boundary`](crate::topology::tetrahedron_boundary)) and the file's triangles are ignored; without,
//! the file's triangles are the mesh. Tetrahedra of negative volume (left-handed) are reoriented
//! for the solver by swapping their last two vertices (so scene vertex indices stay valid, only
//! the corner order changes) and listed in the attributes
//! ([`TetrahedronOrder`](crate::io::TetrahedronOrder)), so that every writer of tetrahedra puts
//! them back in the file's order; flat ones (|volume| ≤ 1e-12 × the product of the edge lengths from the first
//! corner) and ones that repeat a vertex are an error naming the element and its line (ASCII) or
//! byte offset (binary).
//!
//! Binary files (`4.1 1 8` or `4.1 1 4`: `size_t` of 8 or 4 bytes; `2.2 1 8`) are little or big
//! endian, as the integer 1 after the version line says; every error in them names the byte
//! offset. An ASCII file in UTF-16 (byte-order mark `FF FE` or `FE FF`) is decoded; a binary one
//! cannot be UTF-16 text and is refused naming the encoding. Counts in headers never size an
//! allocation beyond [`super::MAX_PREALLOCATION`], and every count is checked against the data
//! that actually follows, so a short file claiming 2⁶⁰ nodes fails quickly at its end.
//!
//! Write: a mesh read from a `.msh` file, with the same nodes and elements, is written as that
//! file with only its node coordinates replaced ([`MshSource`]; ASCII or binary, in the file's
//! byte order): `$PhysicalNames`, `$Entities`, node and element tags, every element of every
//! type, parametric coordinates and line endings come back as read (a UTF-16 file keeps its
//! groups but is written anew). Any other mesh is written as MSH 4.1 ASCII without
//! `$Entities` (Gmsh creates discrete entities for it): one node block, one block of tetrahedra
//! if there are any and one of the surface triangles, saying what of the source it drops.
//!
//! Hand-written rather than the `mshio` crate: mshio 0.4 (nom 5) reserves vectors of the sizes a
//! header claims (`count(parser, n)` calls `Vec::with_capacity(n)`, so a 1 KB file claiming 2⁶⁰
//! nodes aborts), reports errors as a parser backtrace into the byte slice rather than a byte
//! offset, needs the whole file in memory, and reads neither version 2.2 nor parametric nodes.
//!
//! Laid out by phase: `model.rs` holds what is read (nodes, elements) and makes the mesh,
//! `ascii.rs` and `binary.rs` read the sections, `write.rs` writes.

mod ascii;
mod binary;
mod model;
mod source;
mod write;

use std::io::BufRead;
use std::path::Path;

use super::records::Records;
use super::{IoError, LoadedMesh, decode_text, read_error, shown, utf16_encoding};
use std::collections::HashMap;

use super::Attributes;
use ascii::{PhysicalName, read_elements, read_entities, read_nodes_2, read_nodes_41, read_physical_names};
use binary::{Binary, read_binary};
use model::{Elements, Nodes, Place, finish};

pub(super) use model::{parse_point, tetrahedral_mesh};
pub use source::{Layout, MshSource, PhysicalGroup};
pub use write::write_msh;

/// Gmsh element type of a 3-node triangle.
const TRIANGLE: usize = 2;

/// Gmsh element type of a 4-node tetrahedron.
const TETRAHEDRON: usize = 4;

/// Reads a Gmsh `.msh` file (4.1 or 2.2, ASCII or binary) from `reader`; `path` only names it in
/// errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a missing `$MeshFormat`, an unsupported version, and, in
/// ASCII files, a malformed or truncated section, a duplicate or undefined node tag, a
/// non-numeric coordinate, or a flat tetrahedron; [`IoError::Binary`] with the byte offset for
/// the same in binary files (and for an unknown element type, a bad endianness mark, a binary
/// file in UTF-16, or malformed UTF-16); [`IoError::Invalid`] for no nodes, or elements none of
/// which is a tetrahedron or triangle; [`IoError::Mesh`] for a non-finite coordinate;
/// [`IoError::Read`] if reading fails.
pub fn read_msh(mut reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    // Whole, so that an ASCII file can be written back with only its coordinates changed.
    let mut raw = Vec::new();
    reader.read_to_end(&mut raw).map_err(|e| read_error(path, e))?;
    let utf16 = utf16_encoding(&raw);
    let mut loaded = read_msh_text(&raw, path, utf16)?;
    if let Some(source) = loaded.1.take() {
        let order = match std::mem::take(&mut loaded.0.attributes) {
            Attributes::Tetrahedra(order) => Some(*order),
            _ => None,
        };
        // A UTF-16 file's lines are not its bytes: it keeps its groups, not its text.
        let text = if utf16.is_none() { raw } else { Vec::new() };
        loaded.0.attributes = Attributes::Msh(Box::new(MshSource { text, order, ..source }));
    }
    Ok(loaded.0)
}

/// [`read_msh`] of the bytes `raw`; for an ASCII file also what its source keeps (all but the
/// text and the tetrahedra's order).
fn read_msh_text(
    raw: &[u8],
    path: &Path,
    utf16: Option<&'static str>,
) -> Result<(LoadedMesh, Option<MshSource>), IoError> {
    let reader = decode_text(std::io::Cursor::new(raw)).map_err(|e| read_error(path, e))?;
    let mut r = Records::new(reader, path, None);
    if !r.advance()? {
        return Err(r.error_at(1, "empty file (expected '$MeshFormat')"));
    }
    if r.text() != "$MeshFormat" {
        return Err(r.error(format!("not a Gmsh file: expected '$MeshFormat', found '{}'", shown(r.text()))));
    }
    r.require_line(|| "the version line 'version file-type data-size'".to_owned())?;
    let fields: Vec<&str> = r.tokens().take(4).collect();
    let version_2 = match fields.first().copied().unwrap_or("") {
        "4.1" => false,
        "2" | "2.0" | "2.1" | "2.2" => true,
        v => {
            return Err(
                r.error(format!("MSH version {} is not supported (only 4.1 and 2.2, ASCII or binary)", shown(v)))
            );
        }
    };
    let bad_version = || r.error(format!("bad version line '{}' (expected e.g. '4.1 0 8')", shown(r.text())));
    match fields.get(1).copied() {
        Some("0") => {}
        Some("1") => {
            if let Some(encoding) = utf16 {
                return Err(r.error(format!(
                    "a binary .msh file cannot be {encoding} text (the file starts with its byte-order mark)"
                )));
            }
            let size_t = match (version_2, fields.get(2).copied()) {
                (_, Some("8")) => 8,
                (false, Some("4")) => 4,
                (_, size) => {
                    let expected = if version_2 { "8 (sizeof(double))" } else { "8 or 4 (sizeof(size_t))" };
                    return Err(r.error(format!(
                        "data-size '{}' is not supported in a binary file (expected {expected})",
                        shown(size.unwrap_or(""))
                    )));
                }
            };
            let offset = r.lines.consumed;
            let mut b = Binary { reader: r.lines.into_inner(), offset, path, big_endian: false, size_t };
            let (nodes, elements, names) = read_binary(&mut b, version_2)?;
            return with_source(
                path,
                nodes,
                elements,
                names,
                Layout::Binary { big_endian: b.big_endian },
                Place::Offset,
            );
        }
        _ => return Err(bad_version()),
    }
    r.expect_line("$EndMeshFormat", "")?;

    let mut nodes = Nodes::default();
    let mut elements = Elements::default();
    let mut names = Vec::new();
    let mut entities = HashMap::new();
    while r.advance()? {
        let section = r.text().to_owned();
        match section.as_str() {
            "$Nodes" if version_2 => read_nodes_2(&mut r, &mut nodes)?,
            "$Nodes" => read_nodes_41(&mut r, &mut nodes)?,
            "$Elements" => read_elements(&mut r, &nodes, &mut elements, version_2, &entities)?,
            "$PhysicalNames" => read_physical_names(&mut r, &mut names)?,
            "$Entities" if !version_2 => entities = read_entities(&mut r)?,
            s if is_section(s) => {
                // A section we do not need: skip it whole.
                let end = format!("$End{}", &s[1..]);
                let start = r.line;
                while r.text() != end {
                    if !r.advance()? {
                        return Err(r.eof_error(format!("'{end}' (closing '{s}' of line {start})")));
                    }
                }
            }
            s => return Err(r.error(format!("expected a section such as '$Nodes', found '{}'", shown(s)))),
        }
    }
    let layout = if version_2 { Layout::Text22 } else { Layout::Text41 };
    with_source(path, nodes, elements, names, layout, Place::Line)
}

/// The mesh of `nodes` and `elements`, and what its source keeps but its text (which
/// [`read_msh`] adds) and the tetrahedra's order (in the mesh's attributes).
fn with_source(
    path: &Path,
    mut nodes: Nodes,
    mut elements: Elements,
    names: Vec<PhysicalName>,
    layout: Layout,
    place: Place,
) -> Result<(LoadedMesh, Option<MshSource>), IoError> {
    let node_origins = std::mem::take(&mut nodes.origins);
    let counts = (elements.tets.len(), elements.triangles.len());
    let other_elements = elements.other;
    let physical_groups = physical_groups(std::mem::take(&mut elements.physical), names);
    let loaded = finish(path, nodes, elements, place)?;
    let source = MshSource {
        text: Vec::new(),
        node_origins,
        layout,
        elements: counts,
        other_elements,
        order: None,
        physical_groups,
    };
    Ok((loaded, Some(source)))
}

/// The physical groups from the vertices of their elements and `$PhysicalNames`, by dimension
/// and tag (a named group without elements has no vertices).
fn physical_groups(mut vertices: HashMap<(i32, i64), Vec<u32>>, names: Vec<PhysicalName>) -> Vec<PhysicalGroup> {
    // Each (dimension, tag) once: the readers refuse a second name (`add_physical_name`).
    let mut named: HashMap<(i32, i64), String> = names.into_iter().collect();
    let keys: std::collections::BTreeSet<(i32, i64)> = vertices.keys().chain(named.keys()).copied().collect();
    keys.into_iter()
        .map(|(dim, tag)| {
            let mut list = vertices.remove(&(dim, tag)).unwrap_or_default();
            list.sort_unstable();
            list.dedup();
            PhysicalGroup { dim, tag, name: named.remove(&(dim, tag)), vertices: list }
        })
        .collect()
}

/// Whether `text` opens a section (`$Name`, one word, not `$End…`).
fn is_section(text: &str) -> bool {
    text.starts_with('$') && !text.starts_with("$End") && text.len() > 1 && !text.contains(char::is_whitespace)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::tetrahedron_boundary;

    const TET_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 4 1 4\n3 1 0 4\n1\n2\n3\n4\n\
                          0 0 0\n1 0 0\n0 1 0\n0 0 1\n$EndNodes\n$Elements\n1 1 1 1\n3 1 4 1\n1 1 2 3 4\n$EndElements\n";

    #[test]
    fn one_tetrahedron_and_its_boundary() {
        let loaded = read_msh(TET_41.as_bytes(), Path::new("t.msh")).unwrap();
        assert_eq!(loaded.mesh.tetrahedra, vec![[0, 1, 2, 3]]);
        assert_eq!(loaded.mesh.triangles, tetrahedron_boundary(&[[0, 1, 2, 3]]));
    }

    #[test]
    fn written_file_reads_back() {
        let mesh = read_msh(TET_41.as_bytes(), Path::new("t.msh")).unwrap().mesh;
        let mut out = Vec::new();
        write_msh(&mut out, &mesh).unwrap();
        assert_eq!(read_msh(&out[..], Path::new("u.msh")).unwrap().mesh, mesh);
    }

    #[test]
    fn header_errors_name_the_line() {
        let err = read_msh(&b"$MeshFormat\n4.0 0 8\n"[..], Path::new("a.msh")).unwrap_err().to_string();
        assert!(err.contains("a.msh: line 2") && err.contains("4.0"), "{err}");
        let err = read_msh(&b"hello\n"[..], Path::new("a.msh")).unwrap_err().to_string();
        assert!(err.contains("line 1") && err.contains("$MeshFormat"), "{err}");
        let err = read_msh(&b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Comments\nhi\n"[..], Path::new("a.msh"));
        let err = err.unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("$EndComments"), "{err}");
    }
}
