//! STL, ascii and binary.
//!
//! STL stores each triangle with its own three corners, so there are no shared vertices to keep
//! in order: readers merge corners with exactly equal coordinates (`-0.0` equals `0.0`) into one
//! vertex, numbered in order of first occurrence. An STL file written by [`write_stl_binary`]
//! therefore reads back with the same triangles, except that
//! - vertices no triangle uses are lost (STL cannot store them), and vertices are renumbered in
//!   order of first use by the triangles;
//! - coordinates are rounded to `f32`, and distinct vertices that round (or already were) equal
//!   become one.
//!
//! Hand-written rather than `stl_io`: that crate detects ascii by trying to parse it (a binary
//! file whose header starts with `solid` trips it), and its errors do not say which facet or
//! byte is wrong. Here a file is binary when `84 + 50·count` equals its length (whatever its
//! header says, even `solid` or a UTF-16 byte-order mark), otherwise ascii when it starts with
//! `solid` and holds no NUL byte, or when it is UTF-16 text (byte-order mark `FF FE` or `FE FF`)
//! that does, otherwise binary (and then truncated or with trailing bytes, which are ignored).
//! Facet normals are ignored on reading.

use std::collections::HashMap;
use std::io::{self, Read, Write};
use std::path::Path;

use glam::{DVec3, Vec3};

use super::{IoError, Lines, LoadedMesh, bounded_vec, build_mesh, decode_text, parse_coordinate, read_error, shown};
use crate::mesh::Mesh;

const HEADER_LEN: usize = 80;
const TRIANGLE_LEN: usize = 50;
/// The header of the files we write; it must not start with `solid`.
const HEADER_TEXT: &[u8] = b"binary STL written by shapeup";

/// Reads an ascii or binary STL file from `reader` (whole, into memory); `path` only names it in
/// errors.
///
/// # Errors
/// [`IoError::Binary`] for a truncated binary file (naming the triangle), [`IoError::Parse`] with
/// the line for malformed ascii, [`IoError::Invalid`] when there are no triangles,
/// [`IoError::Mesh`] for a non-finite coordinate, [`IoError::Binary`] for malformed UTF-16 text,
/// [`IoError::Read`] if reading fails.
pub fn read_stl(mut reader: impl Read, path: &Path) -> Result<LoadedMesh, IoError> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(|source| IoError::Read { path: path.to_path_buf(), source })?;
    parse_stl(&bytes, path)
}

/// Parses STL from bytes; see [`read_stl`].
///
/// # Errors
/// As [`read_stl`].
pub fn parse_stl(bytes: &[u8], path: &Path) -> Result<LoadedMesh, IoError> {
    let count = bytes.get(HEADER_LEN..HEADER_LEN + 4).and_then(|b| <[u8; 4]>::try_from(b).ok()).map(u32::from_le_bytes);
    if let Some(count) = count
        && binary_len(count) == bytes.len() as u64
    {
        return parse_binary(bytes, count, path);
    }
    // An ascii file, also after a UTF-8 byte-order mark (the line reader skips the mark) or
    // encoded as UTF-16 (decoded on the way, malformed UTF-16 refused with its offset).
    if looks_ascii(bytes) || bytes.strip_prefix(super::UTF8_BOM).is_some_and(looks_ascii) || utf16_ascii(bytes) {
        let text = decode_text(bytes).map_err(|e| read_error(path, e))?;
        return parse_ascii(text, path);
    }
    match count {
        Some(count) => parse_binary(bytes, count, path),
        None => Err(IoError::Binary {
            path: path.to_path_buf(),
            offset: bytes.len() as u64,
            message: format!(
                "file ends after {} bytes: too short for binary STL (84-byte header) and not ascii STL (no 'solid' at the start)",
                bytes.len()
            ),
        }),
    }
}

fn binary_len(count: u32) -> u64 {
    (HEADER_LEN as u64 + 4) + TRIANGLE_LEN as u64 * u64::from(count)
}

fn looks_ascii(bytes: &[u8]) -> bool {
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    let head = bytes.get(start..start + 5).unwrap_or(&[]);
    head.eq_ignore_ascii_case(b"solid") && !bytes.contains(&0)
}

/// Whether `bytes` are UTF-16 text (a byte-order mark) that reads as ascii STL: `solid` at the
/// start, no NUL character (malformed units count as characters here; the reader refuses them).
fn utf16_ascii(bytes: &[u8]) -> bool {
    let Some(encoding) = encoding_rs::Encoding::for_bom(bytes).map(|(e, _)| e).filter(|e| *e != encoding_rs::UTF_8)
    else {
        return false;
    };
    let (text, _) = encoding.decode_without_bom_handling(bytes.get(2..).unwrap_or(&[]));
    looks_ascii(text.as_bytes())
}

/// Gives each distinct position one index, in order of first occurrence.
#[derive(Default)]
struct Merger {
    positions: Vec<DVec3>,
    index: HashMap<[u64; 3], u32>,
}

impl Merger {
    fn with_capacity(corners: usize) -> Self {
        Self { positions: bounded_vec(corners), index: HashMap::with_capacity(corners.min(super::MAX_PREALLOCATION)) }
    }

    fn insert(&mut self, p: DVec3) -> Option<u32> {
        // `+ 0.0` turns -0.0 into 0.0, so the two (equal) zeros share a vertex.
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        if let Some(&i) = self.index.get(&key) {
            return Some(i);
        }
        let i = u32::try_from(self.positions.len()).ok()?;
        self.positions.push(p);
        self.index.insert(key, i);
        Some(i)
    }
}

fn too_many_vertices(path: &Path) -> IoError {
    IoError::Invalid { path: path.to_path_buf(), message: format!("more than {} distinct vertices", u32::MAX) }
}

fn finish(merger: Merger, faces: &[Vec<u32>], path: &Path) -> Result<LoadedMesh, IoError> {
    if faces.is_empty() {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "the STL file has no triangles".to_owned() });
    }
    build_mesh(path, merger.positions, faces.iter().map(Vec::as_slice).collect())
}

fn parse_binary(bytes: &[u8], count: u32, path: &Path) -> Result<LoadedMesh, IoError> {
    let count_usize = count as usize;
    let body = bytes.get(HEADER_LEN + 4..).unwrap_or(&[]);
    let complete = body.len() / TRIANGLE_LEN;
    if complete < count_usize {
        return Err(IoError::Binary {
            path: path.to_path_buf(),
            offset: (HEADER_LEN + 4 + complete * TRIANGLE_LEN) as u64,
            message: format!(
                "file ends inside triangle {complete} of {count} (the header says {count} triangles, {} bytes; the file has {})",
                binary_len(count),
                bytes.len()
            ),
        });
    }
    let mut merger = Merger::with_capacity(count_usize.saturating_mul(3));
    let mut faces = bounded_vec(count_usize);
    for chunk in body.chunks_exact(TRIANGLE_LEN).take(count_usize) {
        let mut face = Vec::with_capacity(3);
        // Bytes 0..12 are the normal, 12..48 the corners, 48..50 an attribute: both ignored.
        for corner in chunk.get(12..48).unwrap_or(&[]).chunks_exact(12) {
            let mut xyz = [0.0; 3];
            for (slot, b) in xyz.iter_mut().zip(corner.chunks_exact(4)) {
                *slot = f64::from(f32::from_le_bytes(<[u8; 4]>::try_from(b).unwrap_or_default()));
            }
            face.push(merger.insert(DVec3::from_array(xyz)).ok_or_else(|| too_many_vertices(path))?);
        }
        faces.push(face);
    }
    finish(merger, &faces, path)
}

#[derive(Clone, Copy, PartialEq)]
enum State {
    /// Before `solid` or after `endsolid`.
    Outside,
    /// Expecting `facet` or `endsolid`.
    Solid,
    /// After `facet`, expecting `outer loop`.
    Facet,
    /// Inside `outer loop`, expecting `vertex` or `endloop`.
    Loop,
    /// After `endloop`, expecting `endfacet`.
    EndLoop,
}

fn parse_ascii(text: impl io::BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let mut lines = Lines::new(text);
    let mut state = State::Outside;
    let mut merger = Merger::default();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    let mut corners: Vec<u32> = Vec::with_capacity(3);
    while let Some((line, text)) = lines.next_line().map_err(|e| read_error(path, e))? {
        let mut tokens = text.split_whitespace();
        let Some(keyword) = tokens.next() else { continue };
        let facet = faces.len();
        let keyword = keyword.to_ascii_lowercase();
        state = match (state, keyword.as_str()) {
            (State::Outside, "solid") => State::Solid,
            (State::Outside, _) => {
                return Err(parse_error(line, format!("expected 'solid', found '{}'", shown(&keyword))));
            }
            (State::Solid, "facet") => State::Facet,
            (State::Solid, "endsolid") => State::Outside,
            (State::Solid, _) => {
                return Err(parse_error(line, format!("expected 'facet' or 'endsolid', found '{}'", shown(&keyword))));
            }
            (State::Facet, "outer") if tokens.next().is_some_and(|t| t.eq_ignore_ascii_case("loop")) => {
                corners.clear();
                State::Loop
            }
            (State::Facet, _) => {
                return Err(parse_error(
                    line,
                    format!("facet {facet}: expected 'outer loop', found '{}'", shown(text)),
                ));
            }
            (State::Loop, "vertex") => {
                let mut xyz = [0.0; 3];
                for (axis, slot) in ["x", "y", "z"].iter().zip(&mut xyz) {
                    let token = tokens.next().ok_or_else(|| {
                        parse_error(
                            line,
                            format!("facet {facet}: vertex has no {axis} coordinate (expected 'vertex x y z')"),
                        )
                    })?;
                    *slot = parse_coordinate(token, &format!("facet {facet}: vertex {axis} coordinate"))
                        .map_err(|e| parse_error(line, e.to_string()))?;
                }
                corners.push(merger.insert(DVec3::from_array(xyz)).ok_or_else(|| too_many_vertices(path))?);
                State::Loop
            }
            (State::Loop, "endloop") if corners.len() >= 3 => State::EndLoop,
            (State::Loop, "endloop") => {
                return Err(parse_error(line, format!("facet {facet} has {} vertices, expected 3", corners.len())));
            }
            (State::Loop, _) => {
                return Err(parse_error(
                    line,
                    format!("facet {facet}: expected 'vertex x y z' or 'endloop', found '{}'", shown(&keyword)),
                ));
            }
            (State::EndLoop, "endfacet") => {
                faces.push(std::mem::take(&mut corners));
                State::Solid
            }
            (State::EndLoop, _) => {
                return Err(parse_error(
                    line,
                    format!("facet {facet}: expected 'endfacet', found '{}'", shown(&keyword)),
                ));
            }
        };
    }
    if matches!(state, State::Facet | State::Loop | State::EndLoop) {
        return Err(parse_error(
            lines.number + 1,
            format!("file ends inside facet {} (expected 'endloop' and 'endfacet')", faces.len()),
        ));
    }
    // A missing final `endsolid` is tolerated: some exporters omit it.
    finish(merger, &faces, path)
}

/// Writes `mesh` as binary STL: an 80-byte header (not starting with `solid`), the triangle
/// count, then per triangle its unit normal (zero when degenerate) and corners as `f32`.
/// Unreferenced vertices and tetrahedra are not written (see the [module docs](self)).
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] for more than `u32::MAX` triangles.
pub fn write_stl_binary(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &super::Attributes,
    warnings: &mut crate::warnings::Warnings,
) -> io::Result<()> {
    super::report_dropped(attributes, &[], "STL", warnings);
    super::report_polygons_split(mesh, "STL", warnings);
    warnings.add_many(
        "vertices_not_kept",
        "vertices not kept as such: STL stores separate triangles, so the output's vertex count and order are not the input's (use OBJ, PLY or OFF to keep them)",
        mesh.num_vertices(),
        String::new,
    );
    let count = u32::try_from(mesh.num_triangles())
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "binary STL holds at most u32::MAX triangles"))?;
    let mut header = [b' '; HEADER_LEN];
    for (slot, b) in header.iter_mut().zip(HEADER_TEXT) {
        *slot = *b;
    }
    w.write_all(&header)?;
    w.write_all(&count.to_le_bytes())?;
    let corner = |i: u32| mesh.positions.get(i as usize).copied().unwrap_or_default();
    for &[a, b, c] in &mesh.triangles {
        let (pa, pb, pc) = (corner(a), corner(b), corner(c));
        let normal = (pb - pa).cross(pc - pa).normalize_or_zero().as_vec3();
        let mut record = [0u8; TRIANGLE_LEN];
        let values: [Vec3; 4] = [normal, pa.as_vec3(), pb.as_vec3(), pc.as_vec3()];
        for (slot, x) in record.chunks_exact_mut(4).zip(values.iter().flat_map(|v| v.to_array())) {
            slot.copy_from_slice(&x.to_le_bytes());
        }
        w.write_all(&record)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn signed_zeros_merge() {
        let mut m = Merger::default();
        assert_eq!(m.insert(DVec3::new(0.0, 1.0, 2.0)), Some(0));
        assert_eq!(m.insert(DVec3::new(-0.0, 1.0, 2.0)), Some(0));
        assert_eq!(m.insert(DVec3::new(0.0, 1.0, 2.5)), Some(1));
    }

    #[test]
    fn written_header_is_not_ascii_and_sizes_match() {
        let mesh = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
        let mut out = Vec::new();
        write_stl_binary(&mut out, &mesh, &crate::io::Attributes::None, &mut crate::warnings::Warnings::new()).unwrap();
        assert_eq!(out.len(), 84 + 50);
        assert!(!out.starts_with(b"solid"));
        // The normal of a counter-clockwise triangle in the xy plane is +z.
        assert_eq!(&out[84..96], &[0.0f32, 0.0, 1.0].map(f32::to_le_bytes).concat()[..]);
    }

    #[test]
    fn short_garbage_is_an_error() {
        let err = parse_stl(b"hello", Path::new("g.stl")).unwrap_err().to_string();
        assert!(err.contains("g.stl") && err.contains("too short"), "{err}");
        let err = parse_stl(b"", Path::new("g.stl")).unwrap_err().to_string();
        assert!(err.contains("g.stl"), "{err}");
    }

    #[test]
    fn missing_endsolid_is_tolerated_but_open_facet_is_not() {
        let facet =
            "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
        assert_eq!(parse_stl(facet.as_bytes(), Path::new("t.stl")).unwrap().mesh.triangles, vec![[0, 1, 2]]);
        let open = &facet[..facet.len() - "endloop\nendfacet\n".len()];
        let err = parse_stl(open.as_bytes(), Path::new("t.stl")).unwrap_err().to_string();
        assert!(err.contains("line 7") && err.contains("facet 0"), "{err}");
    }
}
