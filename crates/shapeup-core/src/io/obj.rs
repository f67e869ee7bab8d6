//! Wavefront OBJ, kept line for line.
//!
//! Hand-written rather than `tobj`, which drops unreferenced vertices and reorders them when it
//! merges position/normal/texture indices, and keeps no lines: here vertex *i* of the mesh is the
//! *i*-th `v` line, and every line of the file is kept.
//!
//! **Read.** `v x y z [w | r g b [a]]`; `vt u [v [w]]`; `vn x y z`; `f` with `i`, `i/t`, `i//n`
//! or `i/t/n` corners (all corners of a face of one form), 1-based or negative (relative to the
//! last `v`, `vt` or `vn` read so far), any number of corners (triangulated by
//! [`Mesh::from_polygons`]); `#` comments, `\` line continuations, `\r\n` endings, a UTF-8
//! byte-order mark; UTF-16 files (byte-order mark) are decoded and read as their UTF-8 copy (and
//! written back as UTF-8). Values after a vertex's x y z are a colour when there are 3 or 4 of them,
//! all numbers (`r g b` or `r g b a`: colours come first, as MeshLab and tinyobjloader write and
//! read them); 1 (`w`), 2 or 5 and more are not. The file has vertex colours when every `v`
//! line has one.
//!
//! **Kept** ([`ObjAttributes`]): every logical line in order — for a `v` line the text after its
//! z coordinate (w, colour, comment) verbatim, for a `vn` line the line itself, every other line
//! (comments, blank lines, `vt`, `f`, `o`, `g`, `s`, `mtllib`, `usemtl`, `l`, `p`, unknown
//! directives) verbatim — with the parsed texture coordinates, normals, per-corner `vt` and `vn`
//! indices, colours, the line-ending style (that of the first line), whether the file ends with a
//! newline and whether it starts with a byte-order mark. Lines are kept as the file's bytes, so
//! text that is not UTF-8 (Latin-1 comments, group and material names of older files) comes back
//! unchanged and `usemtl` names still match the `.mtl` file; only numbers, indices and keywords
//! are parsed, and those are ASCII.
//!
//! **Written back** as OBJ the file comes out line for line, byte for byte, except that each `v`
//! line becomes `v x y z` (the new position, shortest exact decimals) followed by its original
//! rest, and each normal some face corner uses is recomputed from the new geometry with the
//! file's own corner→normal indexing (so hard edges and smoothing groups stay), angle-weighted
//! ([`indexed_normals`]); a `\` continuation inside a vertex's (or a recomputed normal's)
//! coordinates is joined. Material (`.mtl`) files are never touched. A mesh without OBJ lines (or
//! whose vertices or faces no longer match them) is written as a new file: a header comment, `v`
//! (with colours), `vt`, per-vertex `vn` and one `f` line per polygon.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::io::{self, BufRead, Write};
use std::ops::Range;
use std::path::Path;

use glam::DVec3;

use super::Attributes;
use super::attributes::{AttributeKind, NO_INDEX, TexCoords};
use super::{
    IoError, LoadedMesh, UTF8_BOM, build_mesh, decode_text, parse_coordinate, read_error, report_dropped, shown,
    write_f64, write_xyz,
};
use crate::geometry::indexed_normals;
use crate::mesh::{Mesh, Polygons};
use crate::warnings::Warnings;

/// Reads an OBJ file from `reader`; `path` only names it in errors. The mesh's attributes are
/// the file's [`ObjAttributes`].
///
/// # Errors
/// [`IoError::Parse`] with the line for a non-numeric or missing coordinate (`v`, `vt`, `vn`), a
/// `v`, `vt` or `vn` index that is 0, not an integer or out of range (relative ones against what
/// is defined before the face), a face whose corners mix forms (some with a `vt` or `vn` index,
/// some without), or a face with fewer than three corners; [`IoError::Invalid`] when there are no
/// vertices; [`IoError::Mesh`] for a non-finite coordinate; [`IoError::Binary`] for malformed
/// UTF-16; [`IoError::Read`] if reading fails.
pub fn read_obj(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let mut lines = RawLines::new(decode_text(reader).map_err(|e| read_error(path, e))?);
    let mut attributes = ObjAttributes::default();
    let mut positions: Vec<DVec3> = Vec::new();
    let mut colors: Vec<Option<[f64; 3]>> = Vec::new();
    let mut polygons = Polygons::new();
    // Line of each face, to report indices that turn out out of range once the whole file is read.
    let mut face_lines: Vec<usize> = Vec::new();

    loop {
        // One logical line: physical lines joined by `\n` while one ends in `\` (before trailing
        // blanks), numbered by its first line.
        let mut raw: Vec<u8> = Vec::new();
        let mut first_line = 0;
        let mut at_end = false;
        loop {
            match lines.next_line().map_err(|e| read_error(path, e))? {
                None => {
                    at_end = true;
                    break;
                }
                Some((number, text)) => {
                    if first_line == 0 {
                        first_line = number;
                    } else {
                        raw.push(b'\n');
                    }
                    raw.extend_from_slice(text);
                    if !text_view(text, &mut String::new()).trim_end().ends_with('\\') {
                        break;
                    }
                }
            }
        }
        if first_line == 0 {
            break;
        }
        // Parsed through a view with the same byte offsets (see `text_view`), kept as bytes.
        let mut replaced = String::new();
        let view = text_view(&raw, &mut replaced);
        let spans = token_spans(view);
        let tokens: Vec<&str> = spans.iter().map(|r| &view[r.clone()]).collect();
        let error = |message: String| parse_error(first_line, message);
        match tokens.first().copied() {
            Some("v") => {
                let xyz = parse_values(&tokens[1..], "vertex", "v x y z", &["x", "y", "z"]).map_err(error)?;
                let extra = &tokens[4.min(tokens.len())..];
                let color = match extra.len() {
                    3 | 4 => match (extra[0].parse(), extra[1].parse(), extra[2].parse()) {
                        (Ok(r), Ok(g), Ok(b)) if extra.get(3).is_none_or(|a| a.parse::<f64>().is_ok()) => {
                            Some([r, g, b])
                        }
                        _ => None,
                    },
                    _ => None,
                };
                let index = count_u32(positions.len(), "vertices").map_err(error)?;
                // The rest after z, verbatim (spans[3] exists: parse_values found x y z).
                let rest = spans.get(3).map_or(Vec::new(), |z| raw[z.end..].to_vec());
                attributes.lines.push(ObjLine::Vertex { index, rest });
                positions.push(DVec3::new(xyz[0], xyz[1], xyz[2]));
                colors.push(color);
            }
            Some("vt") => {
                // v and w are optional, but must be numbers when present.
                let present = tokens.len().clamp(2, 4) - 1;
                let uvw = parse_values(&tokens[1..], "texture coordinate", "vt u [v [w]]", &["u", "v", "w"][..present])
                    .map_err(error)?;
                attributes.texcoords.push([uvw[0], uvw.get(1).copied().unwrap_or(0.0)]);
                attributes.lines.push(ObjLine::Other(raw));
            }
            Some("vn") => {
                let xyz = parse_values(&tokens[1..], "normal", "vn x y z", &["x", "y", "z"]).map_err(error)?;
                let index = count_u32(attributes.normals.len(), "normals").map_err(error)?;
                attributes.normals.push(DVec3::new(xyz[0], xyz[1], xyz[2]));
                attributes.lines.push(ObjLine::Normal { index, text: raw });
            }
            Some("f") => {
                let defined = [positions.len(), attributes.texcoords.len(), attributes.normals.len()];
                let mut corners: Vec<(Corner, &str)> = Vec::with_capacity(tokens.len() - 1);
                for &token in &tokens[1..] {
                    let corner = parse_corner(token, defined).map_err(error)?;
                    if let Some(&(first, first_token)) = corners.first() {
                        let k = corners.len() + 1;
                        for (what, has, had) in [
                            ("vt", corner.t.is_some(), first.t.is_some()),
                            ("vn", corner.n.is_some(), first.n.is_some()),
                        ] {
                            if has != had {
                                let (with, without) = if had { (1, k) } else { (k, 1) };
                                let token_of = |c: usize| if c == 1 { first_token } else { token };
                                return Err(error(format!(
                                    "{what} count mismatch: corner {with} ('{}') has a {what} index but corner \
                                     {without} ('{}') has none (a face's corners must all have one, or none)",
                                    shown(token_of(with)),
                                    shown(token_of(without))
                                )));
                            }
                        }
                    }
                    corners.push((corner, token));
                }
                if corners.len() < 3 {
                    return Err(error(format!("face has {} vertices, expected at least 3", corners.len())));
                }
                let vertices: Vec<u32> = corners.iter().map(|(c, _)| c.v).collect();
                polygons.push(&vertices);
                attributes.corner_texcoords.extend(corners.iter().map(|(c, _)| c.t.unwrap_or(NO_INDEX)));
                attributes.corner_normals.extend(corners.iter().map(|(c, _)| c.n.unwrap_or(NO_INDEX)));
                face_lines.push(first_line);
                attributes.lines.push(ObjLine::Other(raw));
            }
            Some("o" | "g" | "s" | "usemtl" | "mtllib") => {
                attributes.groups_and_materials = true;
                attributes.lines.push(ObjLine::Other(raw));
            }
            // Comments, blank lines, `l`, `p`, `vp`, unknown directives: kept as they are.
            _ => attributes.lines.push(ObjLine::Other(raw)),
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
    let counts = [positions.len(), attributes.texcoords.len(), attributes.normals.len()];
    for (face, &line) in face_lines.iter().enumerate() {
        for c in polygons.corner_range(face) {
            let indices = [
                polygons.indices().get(c).copied(),
                attributes.corner_texcoords.get(c).copied().filter(|&t| t != NO_INDEX),
                attributes.corner_normals.get(c).copied().filter(|&n| n != NO_INDEX),
            ];
            for ((kind, index), &count) in INDEX_KINDS.iter().zip(indices).zip(&counts) {
                if let Some(i) = index.filter(|&i| i as usize >= count) {
                    let valid = if count == 0 { String::new() } else { format!(" (valid: 1..={count})") };
                    return Err(parse_error(
                        line,
                        format!(
                            "{} index {} is out of range: the file has {count} {}{valid}",
                            kind.name,
                            u64::from(i) + 1,
                            kind.plural
                        ),
                    ));
                }
            }
        }
    }
    if colors.iter().all(Option::is_some) {
        attributes.colors = Some(colors.into_iter().flatten().collect());
    }
    attributes.crlf = lines.crlf.unwrap_or(false);
    attributes.final_newline = lines.final_newline;
    attributes.bom = lines.bom;
    attributes.faces = face_lines.len();
    attributes.polygons_fingerprint = fingerprint(&polygons);
    let mut loaded = build_mesh(path, positions, polygons)?;
    loaded.attributes = Attributes::Obj(Box::new(attributes));
    Ok(loaded)
}

/// Physical lines of a file as bytes without their endings, remembering what the writer needs to
/// reproduce the file: a byte-order mark, the ending style and whether the last line has one.
struct RawLines<R> {
    reader: R,
    bytes: Vec<u8>,
    number: usize,
    bom: bool,
    /// Whether the first line ending is `\r\n` (`None` until a line ending was read).
    crlf: Option<bool>,
    final_newline: bool,
}

impl<R: BufRead> RawLines<R> {
    fn new(reader: R) -> Self {
        Self { reader, bytes: Vec::new(), number: 0, bom: false, crlf: None, final_newline: false }
    }

    /// The next line's 1-based number and bytes, or `None` at the end of the file.
    fn next_line(&mut self) -> io::Result<Option<(usize, &[u8])>> {
        self.bytes.clear();
        if self.reader.read_until(b'\n', &mut self.bytes)? == 0 {
            return Ok(None);
        }
        self.number += 1;
        if self.number == 1 && self.bytes.starts_with(UTF8_BOM) {
            self.bom = true;
            self.bytes.drain(..UTF8_BOM.len());
        }
        self.final_newline = self.bytes.last() == Some(&b'\n');
        if self.final_newline {
            self.bytes.pop();
            let cr = self.bytes.last() == Some(&b'\r');
            // Every `\r` before the `\n` is part of the line ending (files that went through
            // two CRLF conversions end lines in `\r\r\n`): the line is written back with the
            // file's one ending, so a kept `\r` would not read back the same.
            while self.bytes.last() == Some(&b'\r') {
                self.bytes.pop();
            }
            self.crlf.get_or_insert(cr);
        }
        Ok(Some((self.number, &self.bytes)))
    }
}

/// `bytes` as text to parse: themselves when they are UTF-8, else a copy in `replaced` with each
/// byte that is not part of a UTF-8 character replaced by `?`. Either way byte offsets are those
/// of `bytes` (so a token's range is also its range in the file's line), and the keywords,
/// numbers and indices that are parsed (ASCII) are unaffected.
fn text_view<'a>(bytes: &'a [u8], replaced: &'a mut String) -> &'a str {
    match std::str::from_utf8(bytes) {
        Ok(text) => text,
        Err(_) => {
            replaced.clear();
            for chunk in bytes.utf8_chunks() {
                replaced.push_str(chunk.valid());
                replaced.extend(std::iter::repeat_n('?', chunk.invalid().len()));
            }
            replaced
        }
    }
}

/// Byte ranges of the tokens of a logical line (physical lines joined by `\n`): runs of
/// characters between whitespace and continuation backslashes (a `\` with only blanks after it
/// on its physical line), up to a `#` comment. Ranges into the raw text let a `v` line keep what
/// follows its z coordinate exactly as written.
fn token_spans(raw: &str) -> Vec<Range<usize>> {
    let mut spans = Vec::new();
    let mut start = None;
    // Each physical line is looked at once for its continuation, so a line of many backslashes
    // stays linear.
    let mut continuation = continuation_at(raw, 0);
    for (i, c) in raw.char_indices() {
        if c == '\n' {
            continuation = continuation_at(raw, i + 1);
        }
        if c == '#' || c.is_whitespace() || (c == '\\' && continuation == Some(i)) {
            if let Some(s) = start.take() {
                spans.push(s..i);
            }
            if c == '#' {
                return spans;
            }
        } else if start.is_none() {
            start = Some(i);
        }
    }
    if let Some(s) = start {
        spans.push(s..raw.len());
    }
    spans
}

/// The byte offset of the continuation backslash of the physical line that starts at `from` in
/// `raw` (its last character before trailing blanks), if it ends in one.
fn continuation_at(raw: &str, from: usize) -> Option<usize> {
    let line = raw.get(from..)?.split('\n').next()?.trim_end();
    line.ends_with('\\').then(|| from + line.len() - 1)
}

/// Parses one number per name from `tokens` (extra tokens are ignored); `what` and `form` name
/// the directive in errors.
fn parse_values(tokens: &[&str], what: &str, form: &str, names: &[&str]) -> Result<Vec<f64>, String> {
    names
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let token = tokens.get(k).ok_or_else(|| format!("{what} has no {name} coordinate (expected '{form}')"))?;
            parse_coordinate(token, &format!("{what} {name} coordinate"))
        })
        .collect()
}

/// `count` as the index of the next element, refusing files with more than `u32::MAX`.
fn count_u32(count: usize, plural: &str) -> Result<u32, String> {
    u32::try_from(count)
        .ok()
        .filter(|&i| i != NO_INDEX)
        .ok_or_else(|| format!("too many {plural} (at most {})", NO_INDEX - 1))
}

/// One face corner, 0-based: its vertex, texture coordinate and normal (positive indices not yet
/// checked against the file's counts).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Corner {
    v: u32,
    t: Option<u32>,
    n: Option<u32>,
}

/// What a face index refers to, for messages.
struct IndexKind {
    name: &'static str,
    plural: &'static str,
}

const INDEX_KINDS: [IndexKind; 3] = [
    IndexKind { name: "vertex", plural: "vertices" },
    IndexKind { name: "texture coordinate (vt)", plural: "texture coordinates" },
    IndexKind { name: "normal (vn)", plural: "normals" },
];

/// Parses a face corner `i`, `i/t`, `i//n` or `i/t/n` (an empty `t` or `n` is none); negative
/// indices count back from the last of the `defined` vertices, texture coordinates and normals
/// read so far.
fn parse_corner(token: &str, defined: [usize; 3]) -> Result<Corner, String> {
    let mut parts = token.split('/');
    // Messages quote at most the start of a (hostile) long token.
    let token = &*shown(token);
    let vertex = parts.next().unwrap_or("");
    if vertex.parse::<i64>().is_err() {
        return Err(format!("face corner '{token}' does not start with an integer vertex index"));
    }
    let v = parse_index(vertex, token, &INDEX_KINDS[0], defined[0])?;
    let mut optional = |kind: usize| match parts.next() {
        None | Some("") => Ok(None),
        Some(text) => parse_index(text, token, &INDEX_KINDS[kind], defined[kind]).map(Some),
    };
    let t = optional(1)?;
    let n = optional(2)?;
    if parts.next().is_some() {
        return Err(format!("face corner '{token}' has more than 3 parts (expected i, i/t, i//n or i/t/n)"));
    }
    Ok(Corner { v, t, n })
}

/// Parses one index of a corner into a 0-based index.
fn parse_index(text: &str, token: &str, kind: &IndexKind, defined: usize) -> Result<u32, String> {
    let name = kind.name;
    let i: i64 = text
        .parse()
        .map_err(|_| format!("{name} index '{}' in face corner '{token}' is not an integer", shown(text)))?;
    let zero_based = match i {
        0 => return Err(format!("{name} index 0 in '{token}' is invalid (OBJ indices start at 1)")),
        i if i > 0 => i - 1,
        i => {
            let resolved = i64::try_from(defined).unwrap_or(i64::MAX).saturating_add(i);
            if resolved < 0 {
                return Err(format!(
                    "relative {name} index {i} in '{token}' is out of range: only {defined} {} are defined before \
                     this face",
                    kind.plural
                ));
            }
            resolved
        }
    };
    u32::try_from(zero_based)
        .ok()
        .filter(|&i| i != NO_INDEX)
        .ok_or_else(|| format!("{name} index {i} is too large (at most {})", NO_INDEX - 1))
}

/// A hash of the faces as read, so that the writer reproduces `f` lines only for the same faces.
fn fingerprint(polygons: &Polygons) -> u64 {
    let mut hasher = DefaultHasher::new();
    polygons.offsets().hash(&mut hasher);
    polygons.indices().hash(&mut hasher);
    hasher.finish()
}

/// One logical line of an OBJ file (physical lines joined by `\` continuations are one line, its
/// text holding `\n` between them; line endings are not part of it).
///
/// Text is the file's bytes, verbatim: they need not be UTF-8 (older files often have Latin-1
/// comments, group and material names), and are written back unchanged. Use
/// [`String::from_utf8_lossy`] to show them.
#[derive(Debug, Clone, PartialEq)]
pub enum ObjLine {
    /// A `v` line.
    Vertex {
        /// The vertex it defines (0-based).
        index: u32,
        /// Everything after the z coordinate, verbatim: `w`, a colour, blanks, a comment.
        rest: Vec<u8>,
    },
    /// A `vn` line.
    Normal {
        /// The normal it defines (0-based, as `vn` indices count from 1).
        index: u32,
        /// The whole line, verbatim (written back when the normal is not recomputed).
        text: Vec<u8>,
    },
    /// Any other line, verbatim: comments, blank lines, `vt`, `f`, `o`, `g`, `s`, `mtllib`,
    /// `usemtl`, `l`, `p`, unknown directives.
    Other(Vec<u8>),
}

/// Everything an OBJ file holds besides positions and faces (see [`super::Attributes`] and the
/// [module docs](self)): its lines in order and the values parsed from them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjAttributes {
    /// Every logical line of the file, in order.
    pub lines: Vec<ObjLine>,
    /// The `vt` lines' (u, v) in order (v = 0 when the line has none; w stays in the line).
    pub texcoords: Vec<[f64; 2]>,
    /// The `vn` lines' vectors in order, as read (not normalized).
    pub normals: Vec<DVec3>,
    /// Per polygon corner (see [`crate::mesh::Polygons`]): its index into
    /// [`ObjAttributes::texcoords`], or [`NO_INDEX`].
    pub corner_texcoords: Vec<u32>,
    /// Per polygon corner: its index into [`ObjAttributes::normals`], or [`NO_INDEX`].
    pub corner_normals: Vec<u32>,
    /// The colour of every vertex, as written (`r g b` after x y z), when every `v` line has one.
    pub colors: Option<Vec<[f64; 3]>>,
    /// Whether lines end with `\r\n` (the first line ending decides; else `\n`).
    pub crlf: bool,
    /// Whether the last line ends with a line ending.
    pub final_newline: bool,
    /// Whether the file starts with a UTF-8 byte-order mark.
    pub bom: bool,
    /// Whether the file has `o`, `g`, `s`, `usemtl` or `mtllib` lines.
    pub groups_and_materials: bool,
    /// Number of `f` lines.
    pub faces: usize,
    polygons_fingerprint: u64,
}

impl ObjAttributes {
    /// Texture coordinates per corner of `polygons` (the mesh's), if the file has `vt` lines and
    /// its faces have as many corners as `polygons`.
    pub fn texcoords(&self, polygons: &Polygons) -> Option<TexCoords> {
        if self.texcoords.is_empty() || self.corner_texcoords.len() != polygons.num_corners() {
            return None;
        }
        Some(TexCoords { values: self.texcoords.clone(), corners: self.corner_texcoords.clone() })
    }

    /// Per-vertex colours in [0, 1], when every `v` line has one: as written, or divided by 255
    /// when some component exceeds 1 (files that write 0–255 integers).
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        let colors = self.colors.as_ref()?;
        let scale = if colors.iter().flatten().any(|&c| c > 1.0) { 1.0 / 255.0 } else { 1.0 };
        Some(colors.iter().map(|c| c.map(|x| x * scale)).collect())
    }

    /// Whether the file has `vn` lines.
    pub fn has_normals(&self) -> bool {
        !self.normals.is_empty()
    }

    /// Every kind of attribute held.
    pub fn kinds(&self) -> Vec<AttributeKind> {
        let mut kinds = Vec::new();
        if !self.texcoords.is_empty() {
            kinds.push(AttributeKind::TexCoords);
        }
        if self.has_normals() {
            kinds.push(AttributeKind::Normals);
        }
        if self.colors.is_some() {
            kinds.push(AttributeKind::VertexColors);
        }
        if self.groups_and_materials {
            kinds.push(AttributeKind::Other("OBJ objects, groups, smoothing groups and materials".into()));
        }
        kinds
    }

    /// Why the lines cannot be written back for `mesh` (vertices or faces changed), or `None`.
    fn mismatch(&self, mesh: &Mesh) -> Option<String> {
        let mut vertex_lines = 0usize;
        for line in &self.lines {
            match line {
                ObjLine::Vertex { index, .. } => {
                    if *index as usize != vertex_lines {
                        return Some(format!("v line {} holds vertex {index}", vertex_lines + 1));
                    }
                    vertex_lines += 1;
                }
                ObjLine::Normal { index, .. } if *index as usize >= self.normals.len() => {
                    return Some(format!("vn line for normal {index} of {}", self.normals.len()));
                }
                _ => {}
            }
        }
        let corners = mesh.polygons.num_corners();
        if vertex_lines != mesh.num_vertices()
            || self.faces != mesh.num_polygons()
            || self.corner_texcoords.len() != corners
            || self.corner_normals.len() != corners
            || self.polygons_fingerprint != fingerprint(&mesh.polygons)
        {
            return Some(format!(
                "the file has {vertex_lines} v lines and {} f lines, the mesh {} vertices and {} polygons{}",
                self.faces,
                mesh.num_vertices(),
                mesh.num_polygons(),
                if vertex_lines == mesh.num_vertices() && self.faces == mesh.num_polygons() {
                    " with other corners"
                } else {
                    ""
                }
            ));
        }
        None
    }
}

/// Writes `mesh` as OBJ. A mesh read from OBJ whose vertices and faces still match the file
/// comes out line for line (see the [module docs](self)), its used normals recomputed (counted
/// in `warnings`); any other mesh as a new file: one `v` line per vertex (with its colour when
/// the attributes have colours), the texture coordinates, smooth per-vertex normals when the
/// attributes have normals, and one 1-based `f` line per polygon. Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`.
pub fn write_obj(w: &mut dyn Write, mesh: &Mesh, attributes: &Attributes, warnings: &mut Warnings) -> io::Result<()> {
    let mut same_faces = true;
    if let Attributes::Obj(obj) = attributes {
        match obj.mismatch(mesh) {
            None => return write_lines(w, mesh, obj, warnings),
            Some(reason) => warnings.add(
                "obj_lines_not_kept",
                "meshes whose vertices or faces no longer match their OBJ file's lines, written as new OBJ \
                 files (the file's comments, groups and layout are not kept)",
                || reason,
            ),
        }
        // Per-corner texture indices only mean something for the faces they were read with.
        same_faces = obj.polygons_fingerprint == fingerprint(&mesh.polygons);
    }
    write_new(w, mesh, attributes, same_faces, warnings)
}

/// Writes a kept line's bytes, which may span physical lines (`\n` inside), with the file's line
/// ending; returns how many physical lines they span.
fn write_text(w: &mut dyn Write, text: &[u8], newline: &[u8]) -> io::Result<usize> {
    let mut count = 0;
    for (k, part) in text.split(|&b| b == b'\n').enumerate() {
        if k > 0 {
            w.write_all(newline)?;
        }
        w.write_all(part)?;
        count += 1;
    }
    Ok(count)
}

/// The file's lines with the mesh's positions and recomputed normals.
fn write_lines(w: &mut dyn Write, mesh: &Mesh, obj: &ObjAttributes, warnings: &mut Warnings) -> io::Result<()> {
    let newline: &[u8] = if obj.crlf { b"\r\n" } else { b"\n" };
    let normals = if obj.normals.is_empty() {
        Vec::new()
    } else {
        indexed_normals(&mesh.positions, &mesh.polygons, &obj.corner_normals, obj.normals.len())
    };
    if obj.bom {
        w.write_all(UTF8_BOM)?;
    }
    let mut line_number = 1;
    let mut recomputed = 0;
    let mut first_recomputed = String::new();
    for (k, line) in obj.lines.iter().enumerate() {
        if k > 0 {
            w.write_all(newline)?;
        }
        match line {
            ObjLine::Vertex { index, rest } => {
                let p = mesh.positions.get(*index as usize).copied().unwrap_or_default();
                w.write_all(b"v ")?;
                write_xyz(w, p)?;
                line_number += write_text(w, rest, newline)?;
            }
            ObjLine::Normal { index, text } => match normals.get(*index as usize).copied().flatten() {
                Some(n) => {
                    if recomputed == 0 {
                        first_recomputed = format!("vn {} (line {line_number})", u64::from(*index) + 1);
                    }
                    recomputed += 1;
                    w.write_all(b"vn ")?;
                    write_xyz(w, n)?;
                    line_number += 1;
                }
                None => line_number += write_text(w, text, newline)?,
            },
            ObjLine::Other(text) => line_number += write_text(w, text, newline)?,
        }
    }
    if obj.final_newline {
        w.write_all(newline)?;
    }
    warnings
        .add_many("normals_recomputed", "normals recomputed from the moved geometry", recomputed, || first_recomputed);
    Ok(())
}

/// A new OBJ file for a mesh without (matching) OBJ lines; texture coordinates only when its
/// attributes belong to its faces (`same_faces`).
fn write_new(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    same_faces: bool,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let n = mesh.num_vertices();
    let polygons = &mesh.polygons;
    writeln!(w, "# written by shapeup: {n} vertices, {} faces", mesh.num_polygons())?;
    let colors = attributes.vertex_colors().filter(|c| c.len() == n);
    for (i, p) in mesh.positions.iter().enumerate() {
        w.write_all(b"v ")?;
        write_xyz(w, *p)?;
        if let Some(c) = colors.as_ref().and_then(|c| c.get(i)) {
            w.write_all(b" ")?;
            write_xyz(w, DVec3::from_array(*c))?;
        }
        w.write_all(b"\n")?;
    }
    let texcoords = attributes.texcoords(polygons).filter(|t| same_faces && t.corners.len() == polygons.num_corners());
    if let Some(t) = &texcoords {
        for [u, v] in &t.values {
            w.write_all(b"vt ")?;
            write_f64(w, *u)?;
            w.write_all(b" ")?;
            write_f64(w, *v)?;
            w.write_all(b"\n")?;
        }
    }
    // Smooth normals, one per vertex some polygon uses (`vn` k+1 for the vertex with index k).
    let mut normal_of_vertex = vec![NO_INDEX; if attributes.has_normals() { n } else { 0 }];
    if attributes.has_normals() {
        let mut written = 0u32;
        for (v, normal) in indexed_normals(&mesh.positions, polygons, polygons.indices(), n).iter().enumerate() {
            if let Some(normal) = normal {
                w.write_all(b"vn ")?;
                write_xyz(w, *normal)?;
                w.write_all(b"\n")?;
                normal_of_vertex[v] = written;
                written += 1;
            }
        }
        let vt_lines = texcoords.as_ref().map_or(0, |t| t.values.len());
        warnings.add_many("normals_recomputed", "normals recomputed from the moved geometry", written as usize, || {
            format!("vn 1 (line {})", 2 + n + vt_lines)
        });
    }
    for (face, poly) in polygons.iter().enumerate() {
        let range = polygons.corner_range(face);
        // A face's corners must all have a vt (vn) index or none: else the face goes without.
        let t_of = |c: usize| {
            texcoords.as_ref().and_then(|t| t.corners.get(c).copied().filter(|&i| (i as usize) < t.values.len()))
        };
        let n_of = |v: u32| normal_of_vertex.get(v as usize).copied().filter(|&i| i != NO_INDEX);
        let with_t = range.clone().all(|c| t_of(c).is_some());
        let with_n = !normal_of_vertex.is_empty() && poly.iter().all(|&v| n_of(v).is_some());
        w.write_all(b"f")?;
        for (c, &v) in range.zip(poly) {
            write!(w, " {}", u64::from(v) + 1)?;
            match (with_t, with_n) {
                (false, false) => {}
                (true, false) => write!(w, "/{}", t_of(c).map_or(0, |i| u64::from(i) + 1))?,
                (false, true) => write!(w, "//{}", n_of(v).map_or(0, |i| u64::from(i) + 1))?,
                (true, true) => write!(
                    w,
                    "/{}/{}",
                    t_of(c).map_or(0, |i| u64::from(i) + 1),
                    n_of(v).map_or(0, |i| u64::from(i) + 1)
                )?,
            }
        }
        w.write_all(b"\n")?;
    }
    let mut kept = Vec::new();
    if texcoords.is_some() {
        kept.push(AttributeKind::TexCoords);
    }
    if colors.is_some() {
        kept.push(AttributeKind::VertexColors);
    }
    if attributes.has_normals() {
        kept.push(AttributeKind::Normals);
    }
    report_dropped(attributes, &kept, "OBJ", warnings);
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn read(text: &str) -> Result<LoadedMesh, IoError> {
        read_obj(text.as_bytes(), Path::new("mem.obj"))
    }

    fn obj(attributes: &Attributes) -> &ObjAttributes {
        match attributes {
            Attributes::Obj(a) => a,
            other => panic!("not OBJ attributes: {other:?}"),
        }
    }

    fn write(mesh: &Mesh, attributes: &Attributes) -> (String, Warnings) {
        let mut out = Vec::new();
        let mut warnings = Warnings::new();
        write_obj(&mut out, mesh, attributes, &mut warnings).unwrap();
        (String::from_utf8(out).unwrap(), warnings)
    }

    #[test]
    fn corner_forms_and_relative_indices() {
        let corner = |v, t, n| Ok(Corner { v, t, n });
        assert_eq!(parse_corner("3", [5, 2, 8]), corner(2, None, None));
        assert_eq!(parse_corner("3/1", [5, 2, 8]), corner(2, Some(0), None));
        assert_eq!(parse_corner("3//7", [5, 2, 8]), corner(2, None, Some(6)));
        assert_eq!(parse_corner("3/1/7", [5, 2, 8]), corner(2, Some(0), Some(6)));
        assert_eq!(parse_corner("-1/-1/-2", [5, 2, 8]), corner(4, Some(1), Some(6)));
        assert_eq!(parse_corner("-5/-2", [5, 2, 8]), corner(0, Some(0), None));
        assert!(parse_corner("-6", [5, 2, 8]).unwrap_err().contains("only 5 vertices"));
        assert!(parse_corner("1/-3", [5, 2, 8]).unwrap_err().contains("only 2 texture coordinates"));
        assert!(parse_corner("1//-9", [5, 2, 8]).unwrap_err().contains("only 8 normals"));
        assert!(parse_corner("0", [5, 2, 8]).unwrap_err().contains("vertex index 0"));
        assert!(parse_corner("1/0", [5, 2, 8]).unwrap_err().contains("texture coordinate (vt) index 0"));
        assert!(parse_corner("1//0", [5, 2, 8]).unwrap_err().contains("normal (vn) index 0"));
        assert!(parse_corner("1/x", [5, 2, 8]).unwrap_err().contains("'x'"));
        assert!(parse_corner("1/1/1/1", [5, 2, 8]).unwrap_err().contains("more than 3 parts"));
        assert!(parse_corner("a", [5, 2, 8]).is_err());
        assert!(parse_corner("/1", [5, 2, 8]).is_err());
        assert!(parse_corner("99999999999", [5, 2, 8]).unwrap_err().contains("too large"));
    }

    #[test]
    fn tokens_split_at_blanks_continuations_and_comments() {
        let raw = "v 1\t2 \\\n 3 0.5# c \\ d";
        let tokens: Vec<&str> = token_spans(raw).into_iter().map(|r| &raw[r]).collect();
        assert_eq!(tokens, ["v", "1", "2", "3", "0.5"]);
        let raw = "f a\\b \\\\  ";
        let tokens: Vec<&str> = token_spans(raw).into_iter().map(|r| &raw[r]).collect();
        assert_eq!(tokens, ["f", "a\\b", "\\"], "only a backslash ending its line continues it");
    }

    #[test]
    fn text_view_keeps_byte_offsets() {
        let mut replaced = String::new();
        assert_eq!(text_view("v 1 é".as_bytes(), &mut replaced), "v 1 é");
        let bytes = b"g caf\xe9 \xff\xfe x";
        let view = text_view(bytes, &mut replaced);
        assert_eq!(view, "g caf? ?? x");
        assert_eq!(view.len(), bytes.len());
    }

    #[test]
    fn continuation_comments_and_unknown_directives() {
        let text = "# c\nv 0 0 0 # inline\nv 1 0 0\r\nv 0 \\\n 1 0\nvn 0 0 1\nfoo bar\nf 1 2 \\\n3\n";
        let loaded = read(text).unwrap();
        assert_eq!(loaded.mesh.positions[2], DVec3::Y);
        assert_eq!(loaded.mesh.triangles, vec![[0, 1, 2]]);
        let a = obj(&loaded.attributes);
        assert_eq!(a.lines[1], ObjLine::Vertex { index: 0, rest: " # inline".into() });
        assert_eq!(a.lines[6], ObjLine::Other("f 1 2 \\\n3".into()));
        assert!(!a.crlf && a.final_newline && !a.bom);
    }

    #[test]
    fn error_on_continued_line_names_its_first_line() {
        let err = read("v 0 0 0\nv 1 \\\n x 0\n").unwrap_err().to_string();
        assert!(err.contains("mem.obj: line 2:") && err.contains("'x'"), "{err}");
    }

    #[test]
    fn file_without_trailing_newline_and_backslash_at_end() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 \\";
        let loaded = read(text).unwrap();
        assert_eq!(loaded.mesh.triangles.len(), 1);
        assert!(!obj(&loaded.attributes).final_newline);
        assert_eq!(
            write(&loaded.mesh, &loaded.attributes).0,
            "v 0.0 0.0 0.0\nv 1.0 0.0 0.0\nv 0.0 1.0 0.0\nf 1 2 3 \\"
        );
    }

    #[test]
    fn w_and_colours_are_told_apart_by_count() {
        let colors = |rest: &str| {
            let text = format!("v 0 0 0{rest}\nv 1 0 0{rest}\nv 0 1 0{rest}\nf 1 2 3\n");
            obj(&read(&text).unwrap().attributes).colors.clone()
        };
        assert_eq!(colors(" 1"), None, "w");
        assert_eq!(colors(" 0.5 0.25"), None);
        assert_eq!(colors(" 0.5 0.25 1"), Some(vec![[0.5, 0.25, 1.0]; 3]));
        assert_eq!(colors(" 0.5 0.25 1 0.9"), Some(vec![[0.5, 0.25, 1.0]; 3]), "r g b a");
        assert_eq!(colors(" 1 0.5 0.25 1 0.9"), None);
        assert_eq!(colors(" red green blue"), None);
        // Only when every vertex has one.
        let loaded = read("v 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0 0 0 1\nf 1 2 3\n").unwrap();
        assert_eq!(loaded.attributes.vertex_colors(), None);
        // 0–255 colours are scaled into [0, 1].
        let loaded = read("v 0 0 0 255 0 51\nv 1 0 0 0 255 0\nv 0 1 0 0 0 255\nf 1 2 3\n").unwrap();
        assert_eq!(loaded.attributes.vertex_colors().unwrap()[0], [1.0, 0.0, 0.2]);
    }

    #[test]
    fn mixed_corner_forms_are_errors() {
        let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\n";
        let err = read(&format!("{base}f 1/1 2 3/1\n")).unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("vt count mismatch") && err.contains("'2'"), "{err}");
        let err = read(&format!("{base}f 1//1 2//1 3\n")).unwrap_err().to_string();
        assert!(err.contains("line 6") && err.contains("vn count mismatch") && err.contains("'3'"), "{err}");
    }

    #[test]
    fn writes_one_based_faces() {
        let mesh = Mesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y], vec![[0, 1, 2]]).unwrap();
        let (text, warnings) = write(&mesh, &Attributes::None);
        assert!(text.contains("v 1.0 0.0 0.0\n") && text.ends_with("f 1 2 3\n"), "{text}");
        assert!(warnings.is_empty());
    }

    #[test]
    fn unchanged_file_is_reproduced_and_moved_vertices_keep_their_rest() {
        let text = "\u{feff}# hi\r\nv 0 0 0 1 0 0 # red\r\nv 1 0 0 0 1 0\r\nv 0 1 0 0 0 1\r\nvt 0 0\r\n\r\n\
                    vn 0 0 1\r\nvn 1 0 0\r\ng a\r\nf 1/1/1 2/1/1 3/1/1\r\n";
        let loaded = read(text).unwrap();
        let mut moved = loaded.mesh.clone();
        moved.positions[1] = DVec3::new(2.0, 0.0, 0.0);
        let (out, warnings) = write(&moved, &loaded.attributes);
        let expected = "\u{feff}# hi\r\nv 0.0 0.0 0.0 1 0 0 # red\r\nv 2.0 0.0 0.0 0 1 0\r\nv 0.0 1.0 0.0 0 0 1\r\n\
                        vt 0 0\r\n\r\nvn 0.0 0.0 1.0\r\nvn 1 0 0\r\ng a\r\nf 1/1/1 2/1/1 3/1/1\r\n";
        assert_eq!(out, expected, "the unused vn 2 keeps its line");
        assert_eq!(warnings.count("normals_recomputed"), 1);
        assert_eq!(warnings.iter().next().unwrap().first, "vn 1 (line 7)");
    }

    #[test]
    fn changed_faces_fall_back_to_a_new_file_with_a_warning() {
        let loaded = read("o x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\n").unwrap();
        let mut changed = loaded.mesh.clone();
        changed.polygons = Polygons::from_triangles(&[[1, 3, 2]]);
        changed.triangles = vec![[1, 3, 2]];
        let (out, warnings) = write(&changed, &loaded.attributes);
        assert!(out.starts_with("# written by shapeup") && out.ends_with("f 2 4 3\n"), "{out}");
        assert_eq!(warnings.count("obj_lines_not_kept"), 1);
        // The texture coordinates belonged to the old faces; both they and the groups are dropped.
        assert_eq!(warnings.count("attributes_dropped"), 2, "{warnings:?}");
    }
}
