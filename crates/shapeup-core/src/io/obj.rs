//! Wavefront OBJ: `v` and `f` lines.
//!
//! Hand-written rather than `tobj`, which drops unreferenced vertices and reorders them when it
//! merges position/normal/texture indices: here vertex *i* of the mesh is the *i*-th `v` line.
//!
//! Read: `v x y z [w | r g b]` (extra values ignored); `f` with `i`, `i/t`, `i//n` or `i/t/n`
//! corners, 1-based or negative (relative to the last `v`), any number of corners (fanned by
//! [`Mesh::from_polygons`](crate::mesh::Mesh::from_polygons)); `#` comments, `\` line
//! continuations and `\r\n` endings. All other directives (`vn vt vp o g s usemtl mtllib l p`, and
//! unknown ones) are ignored.

use std::io::{self, BufRead, Write};
use std::path::Path;

use glam::DVec3;

use super::{IoError, Lines, LoadedMesh, build_mesh, parse_coordinate, write_point};
use crate::mesh::Mesh;

/// Reads an OBJ file from `reader`; `path` only names it in errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a non-numeric or missing coordinate, an index that is 0,
/// not an integer or out of range, or a face with fewer than three corners;
/// [`IoError::Invalid`] when there are no vertices; [`IoError::Mesh`] for a non-finite
/// coordinate; [`IoError::Read`] if reading fails.
pub fn read_obj(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let mut lines = Lines::new(reader);
    let mut positions: Vec<DVec3> = Vec::new();
    let mut faces: Vec<Vec<u32>> = Vec::new();
    // Line of each face, to report indices that turn out out of range once all `v` are read.
    let mut face_lines: Vec<usize> = Vec::new();
    let mut logical = String::new();

    loop {
        // Assemble one logical line (joining `\` continuations), numbered by its first line.
        logical.clear();
        let mut first_line = 0;
        let mut at_end = false;
        loop {
            match lines.next_line().map_err(|source| IoError::Read { path: path.to_path_buf(), source })? {
                None => {
                    at_end = true;
                    break;
                }
                Some((number, text)) => {
                    if first_line == 0 {
                        first_line = number;
                    }
                    let text = text.trim_end();
                    match text.strip_suffix('\\') {
                        Some(head) => {
                            logical.push_str(head);
                            logical.push(' ');
                        }
                        None => {
                            logical.push_str(text);
                            break;
                        }
                    }
                }
            }
        }
        if at_end && first_line == 0 {
            break;
        }
        let content = logical.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let mut xyz = [0.0; 3];
                for (axis, slot) in ["x", "y", "z"].iter().zip(&mut xyz) {
                    let token = tokens.next().ok_or_else(|| {
                        parse_error(first_line, format!("vertex has no {axis} coordinate (expected 'v x y z')"))
                    })?;
                    *slot = parse_coordinate(token, &format!("vertex {axis} coordinate"))
                        .map_err(|m| parse_error(first_line, m))?;
                }
                positions.push(DVec3::from_array(xyz));
            }
            Some("f") => {
                let mut face = Vec::with_capacity(4);
                for token in tokens {
                    let index = parse_index(token, positions.len()).map_err(|m| parse_error(first_line, m))?;
                    face.push(index);
                }
                if face.len() < 3 {
                    return Err(parse_error(
                        first_line,
                        format!("face has {} vertices, expected at least 3", face.len()),
                    ));
                }
                faces.push(face);
                face_lines.push(first_line);
            }
            // Normals, texture coordinates, groups, materials, lines, points, unknown: not needed.
            _ => {}
        }
        if at_end {
            break;
        }
    }

    if positions.is_empty() {
        return Err(IoError::Invalid {
            path: path.to_path_buf(),
            message: "no vertices (expected 'v x y z' lines)".to_owned(),
        });
    }
    let n = positions.len();
    for (face, &line) in faces.iter().zip(&face_lines) {
        if let Some(&v) = face.iter().find(|&&v| v as usize >= n) {
            return Err(parse_error(
                line,
                format!(
                    "vertex index {} is out of range: the file has {n} vertices (valid: 1..={n})",
                    u64::from(v) + 1
                ),
            ));
        }
    }
    build_mesh(path, positions, faces.iter().map(Vec::as_slice).collect())
}

/// Parses a face corner `i`, `i/t`, `i//n` or `i/t/n` into a 0-based vertex index; negative `i`
/// counts back from the last of the `defined` vertices read so far.
fn parse_index(token: &str, defined: usize) -> Result<u32, String> {
    let vertex = token.split('/').next().unwrap_or("");
    let i: i64 =
        vertex.parse().map_err(|_| format!("face corner '{token}' does not start with an integer vertex index"))?;
    let zero_based = match i {
        0 => return Err(format!("vertex index 0 in '{token}' is invalid (OBJ indices start at 1)")),
        i if i > 0 => i - 1,
        i => {
            let resolved = i64::try_from(defined).unwrap_or(i64::MAX).saturating_add(i);
            if resolved < 0 {
                return Err(format!(
                    "relative vertex index {i} is out of range: only {defined} vertices are defined before this face"
                ));
            }
            resolved
        }
    };
    u32::try_from(zero_based).map_err(|_| format!("vertex index {i} is too large (at most {})", u32::MAX))
}

/// Everything an OBJ file holds besides positions and faces (see [`crate::attributes`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjAttributes {}

impl ObjAttributes {
    /// Texture coordinates per corner.
    pub fn texcoords(&self, _polygons: &crate::mesh::Polygons) -> Option<crate::attributes::TexCoords> {
        None
    }

    /// Per-vertex colours.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        None
    }

    /// Whether the file has `vn` lines.
    pub fn has_normals(&self) -> bool {
        false
    }

    /// Every kind of attribute held.
    pub fn kinds(&self) -> Vec<crate::attributes::AttributeKind> {
        Vec::new()
    }
}

/// Writes `mesh` as OBJ: one `v` line per vertex (shortest decimal that reads back exactly), one
/// 1-based `f` line per polygon. Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`.
pub fn write_obj(w: &mut dyn Write, mesh: &Mesh, _warnings: &mut crate::warnings::Warnings) -> io::Result<()> {
    writeln!(w, "# written by shapeup: {} vertices, {} faces", mesh.num_vertices(), mesh.num_polygons())?;
    for p in &mesh.positions {
        w.write_all(b"v ")?;
        write_point(w, *p)?;
    }
    for poly in mesh.polygons.iter() {
        w.write_all(b"f")?;
        for v in poly {
            write!(w, " {}", u64::from(*v) + 1)?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn read(text: &str) -> Result<LoadedMesh, IoError> {
        read_obj(text.as_bytes(), Path::new("mem.obj"))
    }

    #[test]
    fn corner_forms_and_relative_indices() {
        assert_eq!(parse_index("3", 5), Ok(2));
        assert_eq!(parse_index("3/1", 5), Ok(2));
        assert_eq!(parse_index("3//7", 5), Ok(2));
        assert_eq!(parse_index("3/1/7", 5), Ok(2));
        assert_eq!(parse_index("-1", 5), Ok(4));
        assert_eq!(parse_index("-5/2", 5), Ok(0));
        assert!(parse_index("-6", 5).unwrap_err().contains("only 5 vertices"));
        assert!(parse_index("0", 5).unwrap_err().contains("index 0"));
        assert!(parse_index("a", 5).is_err());
        assert!(parse_index("/1", 5).is_err());
        assert!(parse_index("99999999999", 5).unwrap_err().contains("too large"));
    }

    #[test]
    fn continuation_comments_and_unknown_directives() {
        let text = "# c\nv 0 0 0 # inline\nv 1 0 0\r\nv 0 \\\n 1 0\nvn 0 0 1\nfoo bar\nf 1 2 \\\n3\n";
        let loaded = read(text).unwrap();
        assert_eq!(loaded.mesh.positions[2], DVec3::Y);
        assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn error_on_continued_line_names_its_first_line() {
        let err = read("v 0 0 0\nv 1 \\\n x 0\n").unwrap_err().to_string();
        assert!(err.contains("mem.obj: line 2:") && err.contains("'x'"), "{err}");
    }

    #[test]
    fn file_without_trailing_newline_and_backslash_at_end() {
        let loaded = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \\").unwrap();
        assert_eq!(loaded.mesh.triangles.len(), 1);
    }

    #[test]
    fn writes_one_based_faces() {
        let mesh = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
        let mut out = Vec::new();
        write_obj(&mut out, &mesh, &mut crate::warnings::Warnings::new()).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.contains("v 1.0 0.0 0.0\n") && text.ends_with("f 1 2 3\n"), "{text}");
    }
}
