//! Object File Format (`.off`).
//!
//! Read: a header `OFF` (or `COFF`, `NOFF`, `CNOFF`, `STOFF`, …), counts `nv nf [ne]` (on the
//! header line or the next), `nv` vertex lines `x y z …`, then `nf` face lines
//! `k i₀ … i_{k−1} [colour…]` with 0-based indices. `#` starts a comment; blank lines are
//! skipped. Binary OFF and the 4-D / n-D variants are refused.
//!
//! Kept ([`OffAttributes`]): the keyword and, verbatim, the values after each vertex's x y z
//! (normal, colour, texture coordinates, as the keyword's prefixes announce) and after each
//! face's indices (a colour). Written back as OFF, only x y z change and `N` normals are
//! recomputed; comment lines are not written (counted in a warning).

use std::io::{self, BufRead, Write};
use std::path::Path;

use glam::DVec3;

use super::{IoError, Lines, LoadedMesh, bounded_vec, build_mesh, parse_coordinate, write_xyz};
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
    let mut comments = 0;
    // The next non-blank line without its comment, split into tokens, or `None` at the end.
    let mut next_tokens = |lines: &mut Lines<_>| -> Result<Option<(usize, Vec<String>)>, IoError> {
        loop {
            let Some((number, text)) =
                lines.next_line().map_err(|source| IoError::Read { path: path.to_path_buf(), source })?
            else {
                return Ok(None);
            };
            if text.contains('#') {
                comments += 1;
            }
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

    let layout = VertexLayout::of(&keyword);
    let mut positions = bounded_vec(nv);
    let mut vertex_extra: Vec<String> = bounded_vec(nv);
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
        let extra = &tokens[3..];
        if let Some(bad) = extra.iter().find(|t| t.parse::<f64>().is_err()) {
            return Err(parse_error(line, format!("vertex {i}: '{bad}' after the coordinates is not a number")));
        }
        if layout.normal && extra.len() < 3 {
            return Err(parse_error(
                line,
                format!("vertex {i} has {} values after x y z, but {keyword} needs a normal (3)", extra.len()),
            ));
        }
        vertex_extra.push(extra.join(" "));
    }

    let mut faces: Vec<Vec<u32>> = bounded_vec(nf);
    let mut face_extra: Vec<String> = bounded_vec(nf);
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
        // Whatever follows the indices (a colour) is kept as it is.
        let extra: Vec<&str> = tokens.map(String::as_str).collect();
        if let Some(bad) = extra.iter().find(|t| t.parse::<f64>().is_err()) {
            return Err(parse_error(line, format!("face {f}: '{bad}' after the vertex indices is not a colour value")));
        }
        face_extra.push(extra.join(" "));
        faces.push(face);
    }
    if let Some((line, _)) = next_tokens(&mut lines)? {
        return Err(parse_error(
            line,
            format!("content after the last face (the counts line {counts_line} says {nv} vertices and {nf} faces)"),
        ));
    }
    let mut loaded = build_mesh(path, positions, faces.iter().map(Vec::as_slice).collect())?;
    let attributes = OffAttributes { keyword, layout, vertex_extra, face_extra, comments };
    if !attributes.is_plain() {
        loaded.mesh.attributes = crate::attributes::Attributes::Off(Box::new(attributes));
    }
    Ok(loaded)
}

/// What each vertex line holds after x y z, from the header keyword's prefixes (Geomview's
/// order: `[ST][C][N]OFF`, per vertex `x y z [nx ny nz] [r g b [a]] [s t]`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct VertexLayout {
    /// `N`: a normal follows the coordinates.
    pub normal: bool,
    /// `C`: a colour follows (3 or 4 values).
    pub color: bool,
    /// `ST`: texture coordinates come last.
    pub texture: bool,
}

impl VertexLayout {
    fn of(keyword: &str) -> Self {
        let prefix = keyword.strip_suffix("OFF").unwrap_or("");
        VertexLayout { texture: prefix.starts_with("ST"), color: prefix.contains('C'), normal: prefix.ends_with('N') }
    }
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

/// Everything an OFF file holds besides positions and faces (see [`crate::attributes`]): the
/// header keyword and, verbatim, the values after each vertex's x y z and after each face's
/// indices (colours, normals, texture coordinates).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OffAttributes {
    /// `OFF`, `COFF`, `NOFF`, `STCNOFF`, …
    pub keyword: String,
    /// What the vertex values hold.
    pub layout: VertexLayout,
    /// Per vertex, the tokens after x y z (joined by single spaces).
    pub vertex_extra: Vec<String>,
    /// Per face, the tokens after its indices (a colour), joined by single spaces.
    pub face_extra: Vec<String>,
    /// Lines with a `#` comment (not kept on output).
    pub comments: usize,
}

impl OffAttributes {
    /// The same with `comments` comment lines (what a file written from these holds: none).
    pub fn with_comments(mut self, comments: usize) -> Self {
        self.comments = comments;
        self
    }

    /// Whether there is nothing beyond a plain `OFF` (then the mesh carries no attributes).
    fn is_plain(&self) -> bool {
        self.keyword == "OFF"
            && self.comments == 0
            && self.vertex_extra.iter().all(String::is_empty)
            && self.face_extra.iter().all(String::is_empty)
    }

    /// The numbers after x y z of vertex `i` (unparsable tokens as NaN).
    fn vertex_values(&self, i: usize) -> Vec<f64> {
        self.vertex_extra
            .get(i)
            .map(|e| e.split_whitespace().map(|t| t.parse().unwrap_or(f64::NAN)).collect())
            .unwrap_or_default()
    }

    /// Texture coordinates per corner: each vertex's `s t` (`ST` prefix).
    pub fn texcoords(&self, polygons: &crate::mesh::Polygons) -> Option<crate::attributes::TexCoords> {
        if !self.layout.texture {
            return None;
        }
        let values: Option<Vec<[f64; 2]>> = (0..self.vertex_extra.len())
            .map(|i| {
                let v = self.vertex_values(i);
                (v.len() >= 2).then(|| [v[v.len() - 2], v[v.len() - 1]])
            })
            .collect();
        Some(crate::attributes::TexCoords { values: values?, corners: polygons.indices().to_vec() })
    }

    /// Per-vertex colours (`C` prefix), integers over 1 taken as 0–255.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        if !self.layout.color {
            return None;
        }
        let start = if self.layout.normal { 3 } else { 0 };
        let colors: Option<Vec<[f64; 3]>> = (0..self.vertex_extra.len())
            .map(|i| {
                let v = self.vertex_values(i);
                let c = v.get(start..start + 3)?;
                let scale = if c.iter().any(|&x| x > 1.0) { 255.0 } else { 1.0 };
                Some([c[0] / scale, c[1] / scale, c[2] / scale])
            })
            .collect();
        colors
    }

    /// Whether the vertices have normals (`N` prefix).
    pub fn has_normals(&self) -> bool {
        self.layout.normal
    }

    /// Every kind of attribute held.
    pub fn kinds(&self) -> Vec<crate::attributes::AttributeKind> {
        use crate::attributes::AttributeKind;
        let mut kinds = Vec::new();
        if self.layout.texture {
            kinds.push(AttributeKind::TexCoords);
        }
        if self.layout.normal {
            kinds.push(AttributeKind::Normals);
        }
        if self.layout.color {
            kinds.push(AttributeKind::VertexColors);
        }
        if self.face_extra.iter().any(|e| !e.is_empty()) {
            kinds.push(AttributeKind::Other("OFF face colours".into()));
        }
        kinds
    }
}

/// Writes `mesh` as ASCII OFF with exactly round-tripping coordinates. Tetrahedra are not
/// written.
///
/// # Errors
/// Any error of `w`.
pub fn write_off(w: &mut dyn Write, mesh: &Mesh, warnings: &mut crate::warnings::Warnings) -> io::Result<()> {
    let own = match &mesh.attributes {
        crate::attributes::Attributes::Off(a)
            if a.vertex_extra.len() == mesh.num_vertices() && a.face_extra.len() == mesh.num_polygons() =>
        {
            Some(a.as_ref())
        }
        _ => {
            super::report_dropped(mesh, &[], "OFF", warnings);
            None
        }
    };
    let keyword = own.map_or("OFF", |a| a.keyword.as_str());
    writeln!(w, "{keyword}\n{} {} 0", mesh.num_vertices(), mesh.num_polygons())?;
    let normals = match own {
        Some(a) if a.layout.normal => super::recompute_vertex_normals(mesh, warnings),
        _ => Vec::new(),
    };
    if let Some(a) = own {
        warnings.add_many("comments_dropped", "OFF comment lines not written", a.comments, String::new);
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        let extra = own.and_then(|a| a.vertex_extra.get(i)).map_or("", String::as_str);
        write_xyz(w, *p)?;
        let mut rest = extra.split_whitespace();
        if let Some(normal) = normals.get(i) {
            // NOFF: the three values after x y z are the normal; the rest stays as read.
            let old: Vec<&str> = rest.by_ref().take(3).collect();
            match normal {
                Some(n) => {
                    w.write_all(b" ")?;
                    write_xyz(w, *n)?;
                }
                None => write!(w, " {}", old.join(" "))?,
            }
        }
        for t in rest {
            write!(w, " {t}")?;
        }
        w.write_all(b"\n")?;
    }
    for (f, poly) in mesh.polygons.iter().enumerate() {
        write!(w, "{}", poly.len())?;
        for v in poly {
            write!(w, " {v}")?;
        }
        match own.and_then(|a| a.face_extra.get(f)).filter(|e| !e.is_empty()) {
            Some(extra) => writeln!(w, " {extra}")?,
            None => w.write_all(b"\n")?,
        }
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
