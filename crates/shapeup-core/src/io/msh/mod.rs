//! Gmsh `.msh`: versions 4.1 and 2.2 (2.0 and 2.1 read as 2.2), ASCII and binary.
//!
//! Read: `$MeshFormat`, `$Nodes` and `$Elements`; in binary 4.1 files `$Entities` is parsed (its
//! layout is binary there) only to step over it; every other section (`$PhysicalNames`,
//! `$Entities` in ASCII files, `$NodeData`, `$Periodic`, …) is skipped up to its `$End…` line,
//! which binary files always put on a line of its own after their data. Node tags may be sparse
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
//! Write: MSH 4.1 ASCII without `$Entities` (Gmsh creates discrete entities for it): one node
//! block, one block of tetrahedra if there are any and one of the surface triangles.
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
mod write;

use std::io::BufRead;
use std::path::Path;

use super::records::Records;
use super::{IoError, LoadedMesh, decode_text, read_error, shown, utf16_encoding};
use ascii::{read_elements, read_nodes_2, read_nodes_41};
use binary::{Binary, read_binary};
use model::{Elements, Nodes, Place, finish};

pub(super) use model::{parse_point, tetrahedral_mesh};
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
    let utf16 = utf16_encoding(reader.fill_buf().map_err(|e| read_error(path, e))?);
    let reader = decode_text(reader).map_err(|e| read_error(path, e))?;
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
            return read_binary(&mut b, version_2);
        }
        _ => return Err(bad_version()),
    }
    r.expect_line("$EndMeshFormat", "")?;

    let mut nodes = Nodes::default();
    let mut elements = Elements::default();
    while r.advance()? {
        let section = r.text().to_owned();
        match section.as_str() {
            "$Nodes" if version_2 => read_nodes_2(&mut r, &mut nodes)?,
            "$Nodes" => read_nodes_41(&mut r, &mut nodes)?,
            "$Elements" => read_elements(&mut r, &nodes, &mut elements, version_2)?,
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
    finish(path, nodes, elements, Place::Line)
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
