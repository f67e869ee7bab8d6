//! Object File Format (`.off`).
//!
//! Read: a header `OFF` (or `COFF`, `NOFF`, `CNOFF`, `STOFF`, …: the extra per-vertex values
//! those announce are ignored), counts `nv nf [ne]` (on the header line or the next), `nv` vertex
//! lines `x y z …`, then `nf` face lines `k i₀ … i_{k−1} [colour…]` with 0-based indices. `#`
//! starts a comment; blank lines are skipped. Binary OFF and the 4-D / n-D variants are refused.

use std::io::{self, BufRead, Write};
use std::path::Path;

use glam::DVec3;

use super::{IoError, Lines, LoadedMesh, bounded_vec, build_mesh, parse_coordinate, write_point};
use crate::mesh::Mesh;

/// Reads an OFF file from `reader`; `path` only names it in errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a bad header or counts, a non-numeric coordinate, a bad
/// or out-of-range index, a face with fewer than three corners, or a file that ends before the
/// counts say; [`IoError::Invalid`] for zero vertices; [`IoError::Mesh`] for a non-finite
/// coordinate; [`IoError::Read`] if reading fails.
pub fn read_off(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let mut lines = Lines::new(reader);
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    // The next non-blank line without its comment, split into tokens, or `None` at the end.
    let next_tokens = |lines: &mut Lines<_>| -> Result<Option<(usize, Vec<String>)>, IoError> {
        loop {
            let Some((number, text)) =
                lines.next_line().map_err(|source| IoError::Read { path: path.to_path_buf(), source })?
            else {
                return Ok(None);
            };
            let content = text.split('#').next().unwrap_or("");
            let tokens: Vec<String> = content.split_whitespace().map(str::to_owned).collect();
            if !tokens.is_empty() {
                return Ok(Some((number, tokens)));
            }
        }
    };

    let (header_line, mut header) =
        next_tokens(&mut lines)?.ok_or_else(|| parse_error(1, "empty file (expected an 'OFF' header)".to_owned()))?;
    let keyword = header.remove(0);
    if !is_off_keyword(&keyword) {
        return Err(parse_error(header_line, format!("expected an 'OFF' header, found '{keyword}'")));
    }
    if header.first().is_some_and(|t| t.eq_ignore_ascii_case("BINARY")) {
        return Err(parse_error(header_line, "binary OFF is not supported (only ASCII OFF)".to_owned()));
    }
    // Counts may follow the keyword on the same line.
    let (counts_line, counts) = if header.is_empty() {
        next_tokens(&mut lines)?.ok_or_else(|| {
            parse_error(lines.number + 1, "file ends before the counts line 'vertices faces edges'".to_owned())
        })?
    } else {
        (header_line, header)
    };
    let bad_counts = || {
        parse_error(counts_line, format!("bad counts line '{}' (expected 'vertices faces edges')", counts.join(" ")))
    };
    if counts.len() < 2 || counts.len() > 3 {
        return Err(bad_counts());
    }
    let mut numbers = counts.iter().map(|t| t.parse::<usize>());
    let (Some(Ok(nv)), Some(Ok(nf))) = (numbers.next(), numbers.next()) else {
        return Err(bad_counts());
    };
    if numbers.next().is_some_and(|r| r.is_err()) {
        return Err(bad_counts());
    }
    if nv == 0 {
        return Err(IoError::Invalid {
            path: path.to_path_buf(),
            message: "the counts line says 0 vertices".to_owned(),
        });
    }
    let truncated = |lines: &Lines<_>, what: String| {
        parse_error(
            lines.number + 1,
            format!("file ends early: {what} (counts line {counts_line} says {nv} vertices and {nf} faces)"),
        )
    };

    let mut positions = bounded_vec(nv);
    for i in 0..nv {
        let (line, tokens) =
            next_tokens(&mut lines)?.ok_or_else(|| truncated(&lines, format!("found {i} of {nv} vertices")))?;
        if tokens.len() < 3 {
            return Err(parse_error(line, format!("vertex {i} has {} coordinates, expected 3", tokens.len())));
        }
        let mut xyz = [0.0; 3];
        for ((axis, token), slot) in ["x", "y", "z"].iter().zip(&tokens).zip(&mut xyz) {
            *slot =
                parse_coordinate(token, &format!("vertex {i} {axis} coordinate")).map_err(|m| parse_error(line, m))?;
        }
        positions.push(DVec3::from_array(xyz));
    }

    let mut faces: Vec<Vec<u32>> = bounded_vec(nf);
    for f in 0..nf {
        let (line, tokens) =
            next_tokens(&mut lines)?.ok_or_else(|| truncated(&lines, format!("found {f} of {nf} faces")))?;
        let mut tokens = tokens.iter();
        let k_token = tokens.next().map_or("", String::as_str);
        let k: usize =
            k_token.parse().map_err(|_| parse_error(line, format!("face {f}: '{k_token}' is not a vertex count")))?;
        if k < 3 {
            return Err(parse_error(line, format!("face {f} has {k} vertices, expected at least 3")));
        }
        let mut face = Vec::with_capacity(k.min(64));
        for corner in 0..k {
            let token = tokens
                .next()
                .ok_or_else(|| parse_error(line, format!("face {f} lists {corner} of its {k} vertex indices")))?;
            let index = token
                .parse::<u32>()
                .ok()
                .filter(|&v| (v as usize) < nv)
                .ok_or_else(|| parse_error(line, format!("face {f}: vertex index '{token}' is not in 0..{nv}")))?;
            face.push(index);
        }
        // Whatever follows the indices (a colour) is ignored.
        faces.push(face);
    }
    build_mesh(path, positions, faces.iter().map(Vec::as_slice).collect())
}

/// `OFF` with any of the optional prefixes `ST`, `C`, `N`, `4`, `n`… that only add per-vertex
/// values; the 4-D and n-D variants (`4OFF`, `nOFF`) change the vertex layout and are refused.
fn is_off_keyword(keyword: &str) -> bool {
    let Some(prefix) = keyword.strip_suffix("OFF") else { return false };
    let prefix = prefix.strip_prefix("ST").unwrap_or(prefix);
    let prefix = prefix.strip_prefix('C').unwrap_or(prefix);
    let prefix = prefix.strip_prefix('N').unwrap_or(prefix);
    prefix.is_empty()
}

/// Everything an OFF file holds besides positions and faces (see [`crate::attributes`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OffAttributes {}

impl OffAttributes {
    /// Texture coordinates per corner.
    pub fn texcoords(&self, _polygons: &crate::mesh::Polygons) -> Option<crate::attributes::TexCoords> {
        None
    }

    /// Per-vertex colours.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        None
    }

    /// Whether the vertices have normals (`NOFF`).
    pub fn has_normals(&self) -> bool {
        false
    }

    /// Every kind of attribute held.
    pub fn kinds(&self) -> Vec<crate::attributes::AttributeKind> {
        Vec::new()
    }
}

/// Writes `mesh` as ASCII OFF with exactly round-tripping coordinates. Tetrahedra are not
/// written.
///
/// # Errors
/// Any error of `w`.
pub fn write_off(w: &mut dyn Write, mesh: &Mesh, warnings: &mut crate::warnings::Warnings) -> io::Result<()> {
    super::report_dropped(mesh, &[], "OFF", warnings);
    writeln!(w, "OFF\n{} {} 0", mesh.num_vertices(), mesh.num_polygons())?;
    for p in &mesh.positions {
        write_point(w, *p)?;
    }
    for poly in mesh.polygons.iter() {
        write!(w, "{}", poly.len())?;
        for v in poly {
            write!(w, " {v}")?;
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn header_variants() {
        for ok in ["OFF", "COFF", "NOFF", "CNOFF", "STOFF", "STCNOFF"] {
            assert!(is_off_keyword(ok), "{ok}");
        }
        for bad in ["4OFF", "nOFF", "OF", "PLY", "off"] {
            assert!(!is_off_keyword(bad), "{bad}");
        }
    }

    #[test]
    fn counts_on_header_line_and_colour_values() {
        let text = "COFF 3 1 0\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n0 1 0 255 0 0 255\n3 0 1 2 0.5 0.5 0.5\n";
        let loaded = read_off(text.as_bytes(), Path::new("m.off")).unwrap();
        assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn binary_off_is_refused() {
        let err = read_off(&b"OFF BINARY\n"[..], Path::new("m.off")).unwrap_err().to_string();
        assert!(err.contains("line 1") && err.contains("binary"), "{err}");
    }
}
