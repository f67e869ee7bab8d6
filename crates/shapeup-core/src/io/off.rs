//! Object File Format (`.off`).
//!
//! Read: a header `OFF` (or `COFF`, `NOFF`, `CNOFF`, `STOFF`, …), counts `nv nf [ne]` (on the
//! header line, glued to the keyword as in `OFF8 6 12`, or on the next line), then `nv` vertices
//! `x y z …` and `nf` faces `k i₀ … i_{k−1} [colour…]` with 0-based indices. After the counts the
//! file is whitespace-separated numbers, as Geomview reads it: a vertex's coordinates and a
//! face's indices may continue over several lines; what follows the last of them on its line
//! (a vertex's normal, colour or texture coordinates, a face's colour) belongs to that element.
//! `#` starts a comment anywhere; blank lines are skipped. Binary OFF and the 4-D / n-D variants
//! are refused. A UTF-16 file (byte-order mark) is decoded ([`super`]).
//!
//! Kept ([`OffAttributes`]): the keyword and, verbatim, the values after each vertex's x y z
//! (normal, colour, texture coordinates, as the keyword's prefixes announce) and after each
//! face's indices (a colour). Written back as OFF, only x y z change and `N` normals are
//! recomputed; comment lines are not written (counted in a warning).

use std::io::{self, BufRead, Write};
use std::path::Path;

use glam::DVec3;

use super::{
    IoError, Lines, LoadedMesh, TextReader, bounded_vec, build_mesh, decode_text, parse_coordinate, read_error, shown,
    write_xyz,
};
use crate::mesh::{Mesh, Polygons};

/// Reads an OFF file from `reader`; `path` only names it in errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a bad header or counts, a non-numeric coordinate, a bad
/// or out-of-range index, a face with fewer than three corners, or a file that ends before the
/// counts say; [`IoError::Invalid`] for zero vertices; [`IoError::Mesh`] for a non-finite
/// coordinate; [`IoError::Binary`] for malformed UTF-16; [`IoError::Read`] if reading fails.
pub fn read_off(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let reader = decode_text(reader).map_err(|e| read_error(path, e))?;
    let mut tokens = Tokens::new(reader, path);
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };

    let Some((header_line, first)) = tokens.next_token()? else {
        return Err(parse_error(1, "empty file (expected an 'OFF' header)".to_owned()));
    };
    // `OFF`, or the keyword glued to the vertex count (`OFF8 6 12`, as some exporters write).
    let (keyword, glued) = split_keyword(first)
        .ok_or_else(|| parse_error(header_line, format!("expected an 'OFF' header, found '{}'", shown(first))))?;
    let (keyword, glued) = (keyword.to_owned(), glued.to_owned());
    let mut counts: Vec<String> = Vec::new();
    if !glued.is_empty() {
        counts.push(glued);
    }
    let rest = tokens.rest_of_line();
    if rest.split_whitespace().next().is_some_and(|t| t.eq_ignore_ascii_case("BINARY")) {
        return Err(parse_error(header_line, "binary OFF is not supported (only ASCII OFF)".to_owned()));
    }
    counts.extend(rest.split_whitespace().map(str::to_owned));
    // Counts may follow the keyword on the same line, else they are the next line.
    let counts_line = if counts.is_empty() {
        let Some((line, first)) = tokens.next_token()? else {
            return Err(parse_error(
                tokens.end_line(),
                "file ends before the counts line 'vertices faces edges'".to_owned(),
            ));
        };
        counts.push(first.to_owned());
        counts.extend(tokens.rest_of_line().split_whitespace().map(str::to_owned));
        line
    } else {
        header_line
    };
    let bad_counts = || {
        parse_error(
            counts_line,
            format!("bad counts line '{}' (expected 'vertices faces edges')", shown(&counts.join(" "))),
        )
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
    let truncated = |line: usize, what: String| {
        parse_error(
            line,
            format!("file ends early: {what} (counts line {counts_line} says {nv} vertices and {nf} faces)"),
        )
    };

    let layout = VertexLayout::of(&keyword);
    // Grown as vertices and faces arrive: the counts are a claim (see MAX_PREALLOCATION).
    let mut positions = bounded_vec(nv);
    let mut vertex_extra: Vec<String> = Vec::new();
    for i in 0..nv {
        let mut xyz = [0.0; 3];
        for (axis, slot) in ["x", "y", "z"].iter().zip(&mut xyz) {
            let Some((line, token)) = tokens.next_token()? else {
                let found = if *axis == "x" {
                    format!("found {i} of {nv} vertices")
                } else {
                    format!("vertex {i} has no {axis} coordinate")
                };
                return Err(truncated(tokens.end_line(), found));
            };
            *slot = parse_coordinate(token, &format!("vertex {i} {axis} coordinate"))
                .map_err(|e| parse_error(line, e.to_string()))?;
        }
        positions.push(DVec3::from_array(xyz));
        let line = tokens.line();
        let extra = tokens.rest_of_line();
        if let Some(bad) = extra.split_whitespace().find(|t| t.parse::<f64>().is_err()) {
            return Err(parse_error(
                line,
                format!("vertex {i}: '{}' after the coordinates is not a number", shown(bad)),
            ));
        }
        let values = extra.split_whitespace().count();
        if values < layout.min_values() {
            return Err(parse_error(
                line,
                format!("vertex {i} has {values} values after x y z, but {keyword} needs {}", layout.describe()),
            ));
        }
        vertex_extra.push(extra);
    }

    let mut polygons = Polygons::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut face_extra: Vec<String> = Vec::new();
    for f in 0..nf {
        let Some((face_line, k_token)) = tokens.next_token()? else {
            return Err(truncated(tokens.end_line(), format!("found {f} of {nf} faces")));
        };
        let k: usize = k_token
            .parse()
            .map_err(|_| parse_error(face_line, format!("face {f}: '{}' is not a vertex count", shown(k_token))))?;
        if k < 3 {
            return Err(parse_error(face_line, format!("face {f} has {k} vertices, expected at least 3")));
        }
        corners.clear();
        for corner in 0..k {
            let Some((line, token)) = tokens.next_token()? else {
                return Err(parse_error(
                    face_line,
                    format!("face {f} lists {corner} of its {k} vertex indices before the file ends"),
                ));
            };
            let index = token.parse::<u32>().ok().filter(|&v| (v as usize) < nv).ok_or_else(|| {
                parse_error(line, format!("face {f}: vertex index '{}' is not in 0..{nv}", shown(token)))
            })?;
            corners.push(index);
        }
        // Whatever follows the indices on their line (a colour) is kept as it is.
        let line = tokens.line();
        let extra = tokens.rest_of_line();
        if let Some(bad) = extra.split_whitespace().find(|t| t.parse::<f64>().is_err()) {
            return Err(parse_error(
                line,
                format!("face {f}: '{}' after the vertex indices is not a colour value", shown(bad)),
            ));
        }
        face_extra.push(extra);
        polygons.push(&corners);
    }
    if let Some((line, _)) = tokens.next_token()? {
        return Err(parse_error(
            line,
            format!("content after the last face (the counts line {counts_line} says {nv} vertices and {nf} faces)"),
        ));
    }
    let comments = tokens.comments;
    let mut loaded = build_mesh(path, positions, polygons)?;
    let attributes = OffAttributes { keyword, layout, vertex_extra, face_extra, comments };
    if !attributes.is_plain() {
        loaded.attributes = super::Attributes::Off(Box::new(attributes));
    }
    Ok(loaded)
}

/// The header keyword and the digits glued to it (`OFF8` → `OFF`, `8`), or `None` when the token
/// is not an OFF keyword (see [`is_off_keyword`]).
fn split_keyword(token: &str) -> Option<(&str, &str)> {
    let end = token.find("OFF")? + "OFF".len();
    let (keyword, glued) = token.split_at(end);
    (is_off_keyword(keyword) && glued.bytes().all(|b| b.is_ascii_digit())).then_some((keyword, glued))
}

/// The whitespace-separated tokens of an OFF file, each with its line; `#` comments and blank
/// lines skipped.
struct Tokens<'p, R> {
    lines: Lines<TextReader<R>>,
    path: &'p Path,
    /// The current line up to any comment, and its tokens' byte ranges.
    text: String,
    spans: Vec<(usize, usize)>,
    /// Tokens of the current line already taken.
    taken: usize,
    /// Number of the current line.
    line: usize,
    /// Lines with a `#` comment so far.
    comments: usize,
}

impl<'p, R: BufRead> Tokens<'p, R> {
    fn new(reader: TextReader<R>, path: &'p Path) -> Self {
        Self { lines: Lines::new(reader), path, text: String::new(), spans: Vec::new(), taken: 0, line: 0, comments: 0 }
    }

    /// Moves to the next line with a token; `false` at the end of the file.
    fn load(&mut self) -> Result<bool, IoError> {
        loop {
            let Some((number, text)) = self.lines.next_line().map_err(|e| read_error(self.path, e))? else {
                return Ok(false);
            };
            if text.contains('#') {
                self.comments += 1;
            }
            let content = text.split('#').next().unwrap_or("");
            self.text.clear();
            self.text.push_str(content);
            self.spans.clear();
            let base = self.text.as_ptr() as usize;
            self.spans.extend(self.text.split_whitespace().map(|t| {
                let start = t.as_ptr() as usize - base;
                (start, start + t.len())
            }));
            self.taken = 0;
            if !self.spans.is_empty() {
                self.line = number;
                return Ok(true);
            }
        }
    }

    /// The next token and its line (continuing on the next lines when this one is used up), or
    /// `None` at the end of the file.
    fn next_token(&mut self) -> Result<Option<(usize, &str)>, IoError> {
        if self.taken == self.spans.len() && !self.load()? {
            return Ok(None);
        }
        let (start, end) = self.spans[self.taken];
        self.taken += 1;
        Ok(Some((self.line, &self.text[start..end])))
    }

    /// The tokens of the current line not taken yet, joined by single spaces; the next token
    /// comes from a later line.
    fn rest_of_line(&mut self) -> String {
        let mut rest = String::new();
        for &(start, end) in &self.spans[self.taken..] {
            if !rest.is_empty() {
                rest.push(' ');
            }
            rest.push_str(&self.text[start..end]);
        }
        self.taken = self.spans.len();
        rest
    }

    /// The line of the last token taken.
    fn line(&self) -> usize {
        self.line
    }

    /// The line after the last one: where an element that is missing would have been.
    fn end_line(&self) -> usize {
        self.lines.number + 1
    }
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

    /// Fewest values a vertex line holds after x y z: a normal (3), a colour (3, or 4 with
    /// alpha), texture coordinates (2). Fewer would put `s t` or the colour on the wrong values.
    fn min_values(self) -> usize {
        3 * usize::from(self.normal) + 3 * usize::from(self.color) + 2 * usize::from(self.texture)
    }

    /// What [`VertexLayout::min_values`] counts, for messages.
    fn describe(self) -> String {
        let parts: Vec<&str> =
            [(self.normal, "a normal (3)"), (self.color, "a colour (3 or 4)"), (self.texture, "s t (2)")]
                .into_iter()
                .filter_map(|(has, what)| has.then_some(what))
                .collect();
        parts.join(", ")
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

/// Everything an OFF file holds besides positions and faces (see [`super::Attributes`]): the
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
    pub fn texcoords(&self, polygons: &crate::mesh::Polygons) -> Option<super::attributes::TexCoords> {
        if !self.layout.texture {
            return None;
        }
        let values: Option<Vec<[f64; 2]>> = (0..self.vertex_extra.len())
            .map(|i| {
                let v = self.vertex_values(i);
                (v.len() >= 2).then(|| [v[v.len() - 2], v[v.len() - 1]])
            })
            .collect();
        Some(super::attributes::TexCoords { values: values?, corners: polygons.indices().to_vec() })
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
    pub fn kinds(&self) -> Vec<super::attributes::AttributeKind> {
        use super::attributes::AttributeKind;
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
pub fn write_off(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &super::Attributes,
    warnings: &mut crate::warnings::Warnings,
) -> io::Result<()> {
    let own = match attributes {
        super::Attributes::Off(a)
            if a.vertex_extra.len() == mesh.num_vertices() && a.face_extra.len() == mesh.num_polygons() =>
        {
            Some(a.as_ref())
        }
        _ => {
            super::report_dropped(attributes, &[], "OFF", warnings);
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
    fn keyword_glued_to_the_counts() {
        assert_eq!(split_keyword("OFF8"), Some(("OFF", "8")));
        assert_eq!(split_keyword("COFF12"), Some(("COFF", "12")));
        assert_eq!(split_keyword("OFF"), Some(("OFF", "")));
        assert_eq!(split_keyword("OFFx"), None);
        assert_eq!(split_keyword("4OFF8"), None);
        let plain = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";
        let expected = read_off(plain.as_bytes(), Path::new("m.off")).unwrap().mesh;
        for glued in ["OFF4 2 0\n", "OFF4 2\n", "OFF4\n2 0\n"] {
            let text = plain.replacen("OFF\n4 2 0\n", glued, 1);
            let result = read_off(text.as_bytes(), Path::new("m.off"));
            if glued == "OFF4\n2 0\n" {
                // The counts are one line: a count alone on the header line is not all of them.
                let err = result.unwrap_err().to_string();
                assert!(err.contains("line 1") && err.contains("bad counts"), "{err}");
            } else {
                assert_eq!(result.unwrap().mesh, expected, "{glued:?}");
            }
        }
        let coff = "COFF4 2 0\n0 0 0 1 0 0\n1 0 0 1 0 0\n1 1 0 1 0 0\n0 1 0 1 0 0\n3 0 1 2\n3 0 2 3\n";
        let loaded = read_off(coff.as_bytes(), Path::new("m.off")).unwrap();
        assert_eq!(loaded.mesh.triangles, expected.triangles);
        assert_eq!(loaded.attributes.vertex_colors().unwrap()[2], [1.0, 0.0, 0.0]);
    }

    #[test]
    fn indices_continue_over_lines_and_comments_go_anywhere() {
        let text = "OFF # header\n# counts next\n5 1 0\n0 0 0\n1 0 # half a vertex\n 0\n1 1 0\n0 1\n0\n0.5 1.5 0\n\
                    5 0 1\n# between corners\n2 3\n\n 4 0.2 0.3 0.4 # a colour after the last index\n";
        let loaded = read_off(text.as_bytes(), Path::new("m.off")).unwrap();
        assert_eq!(loaded.mesh.polygons.get(0), Some(&[0, 1, 2, 3, 4][..]));
        assert_eq!(loaded.mesh.positions[1], DVec3::X);
        assert_eq!(loaded.mesh.positions[3], DVec3::Y);
        let crate::io::Attributes::Off(a) = &loaded.attributes else { panic!("no OFF attributes") };
        assert_eq!(a.face_extra, ["0.2 0.3 0.4"]);
        assert_eq!(a.comments, 5);
        // Errors name the line of the token at fault.
        let bad = text.replace("2 3\n", "2 x\n");
        let err = read_off(bad.as_bytes(), Path::new("m.off")).unwrap_err().to_string();
        assert!(err.contains("line 13") && err.contains("'x'"), "{err}");
        let short = &text[..text.find("\n 4").unwrap()];
        let err = read_off(short.as_bytes(), Path::new("m.off")).unwrap_err().to_string();
        assert!(err.contains("line 11") && err.contains("lists 4 of its 5"), "{err}");
    }

    #[test]
    fn binary_off_is_refused() {
        let err = read_off(&b"OFF BINARY\n"[..], Path::new("m.off")).unwrap_err().to_string();
        assert!(err.contains("line 1") && err.contains("binary"), "{err}");
    }
}
