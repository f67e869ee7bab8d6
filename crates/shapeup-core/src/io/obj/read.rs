//! Reading OBJ: `v`, `vt`, `vn` and `f` lines parsed, every line kept.

use std::io::BufRead;
use std::path::Path;

use glam::DVec3;

use super::attributes::{ObjAttributes, ObjLine, fingerprint};
use super::lines::{RawLines, text_view, token_spans};
use crate::io::{
    Attributes, IoError, LoadedMesh, NO_INDEX, NotANumber, build_mesh, decode_text, parse_coordinate, read_error, shown,
};
use crate::mesh::Polygons;

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
        let line_error = |e: LineError| error(e.to_string());
        match tokens.first().copied() {
            Some("v") => {
                let xyz = parse_values(&tokens[1..], "vertex", "v x y z", &["x", "y", "z"]).map_err(line_error)?;
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
                let index = count_u32(positions.len(), "vertices").map_err(line_error)?;
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
                    .map_err(line_error)?;
                attributes.texcoords.push([uvw[0], uvw.get(1).copied().unwrap_or(0.0)]);
                attributes.lines.push(ObjLine::Other(raw));
            }
            Some("vn") => {
                let xyz = parse_values(&tokens[1..], "normal", "vn x y z", &["x", "y", "z"]).map_err(line_error)?;
                let index = count_u32(attributes.normals.len(), "normals").map_err(line_error)?;
                attributes.normals.push(DVec3::new(xyz[0], xyz[1], xyz[2]));
                attributes.lines.push(ObjLine::Normal { index, text: raw });
            }
            Some("f") => {
                let defined = [positions.len(), attributes.texcoords.len(), attributes.normals.len()];
                let mut corners: Vec<(Corner, &str)> = Vec::with_capacity(tokens.len() - 1);
                for &token in &tokens[1..] {
                    let corner = parse_corner(token, defined).map_err(line_error)?;
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

/// What is wrong with a `v`, `vt`, `vn` or `f` line; [`read_obj`] places it at its line
/// ([`IoError::Parse`]). Quoted tokens are cut short ([`shown`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
enum LineError {
    /// A coordinate is missing.
    #[error("{what} has no {name} coordinate (expected '{form}')")]
    MissingCoordinate { what: &'static str, name: &'static str, form: &'static str },
    /// A coordinate is not a number.
    #[error(transparent)]
    NotANumber(#[from] NotANumber),
    /// More elements of a kind than a `u32` index holds.
    #[error("too many {plural} (at most {})", NO_INDEX - 1)]
    TooMany { plural: &'static str },
    /// A face corner without an integer vertex index first.
    #[error("face corner '{token}' does not start with an integer vertex index")]
    NoVertexIndex { token: String },
    /// A face corner of more than `i/t/n`.
    #[error("face corner '{token}' has more than 3 parts (expected i, i/t, i//n or i/t/n)")]
    TooManyParts { token: String },
    /// An index of a face corner that is not an integer.
    #[error("{name} index '{text}' in face corner '{token}' is not an integer")]
    NotAnInteger { name: &'static str, text: String, token: String },
    /// Index 0 (OBJ counts from 1).
    #[error("{name} index 0 in '{token}' is invalid (OBJ indices start at 1)")]
    Zero { name: &'static str, token: String },
    /// A negative index reaching back past the first element defined.
    #[error(
        "relative {name} index {index} in '{token}' is out of range: only {defined} {plural} are defined before this face"
    )]
    RelativeOutOfRange { name: &'static str, index: i64, token: String, defined: usize, plural: &'static str },
    /// An index past what a `u32` holds.
    #[error("{name} index {index} is too large (at most {})", NO_INDEX - 1)]
    TooLarge { name: &'static str, index: i64 },
}

/// Parses one number per name from `tokens` (extra tokens are ignored); `what` and `form` name
/// the directive in errors.
fn parse_values(
    tokens: &[&str],
    what: &'static str,
    form: &'static str,
    names: &[&'static str],
) -> Result<Vec<f64>, LineError> {
    names
        .iter()
        .enumerate()
        .map(|(k, &name)| {
            let token = tokens.get(k).ok_or(LineError::MissingCoordinate { what, name, form })?;
            Ok(parse_coordinate(token, &format!("{what} {name} coordinate"))?)
        })
        .collect()
}

/// `count` as the index of the next element, refusing files with more than `u32::MAX`.
fn count_u32(count: usize, plural: &'static str) -> Result<u32, LineError> {
    u32::try_from(count).ok().filter(|&i| i != NO_INDEX).ok_or(LineError::TooMany { plural })
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
fn parse_corner(token: &str, defined: [usize; 3]) -> Result<Corner, LineError> {
    let mut parts = token.split('/');
    // Messages quote at most the start of a (hostile) long token.
    let token = &*shown(token);
    let vertex = parts.next().unwrap_or("");
    if vertex.parse::<i64>().is_err() {
        return Err(LineError::NoVertexIndex { token: token.to_owned() });
    }
    let v = parse_index(vertex, token, &INDEX_KINDS[0], defined[0])?;
    let mut optional = |kind: usize| match parts.next() {
        None | Some("") => Ok(None),
        Some(text) => parse_index(text, token, &INDEX_KINDS[kind], defined[kind]).map(Some),
    };
    let t = optional(1)?;
    let n = optional(2)?;
    if parts.next().is_some() {
        return Err(LineError::TooManyParts { token: token.to_owned() });
    }
    Ok(Corner { v, t, n })
}

/// Parses one index of a corner into a 0-based index.
fn parse_index(text: &str, token: &str, kind: &IndexKind, defined: usize) -> Result<u32, LineError> {
    let name = kind.name;
    let i: i64 = text.parse().map_err(|_| LineError::NotAnInteger {
        name,
        text: shown(text).into_owned(),
        token: token.to_owned(),
    })?;
    let zero_based = match i {
        0 => return Err(LineError::Zero { name, token: token.to_owned() }),
        i if i > 0 => i - 1,
        i => {
            let resolved = i64::try_from(defined).unwrap_or(i64::MAX).saturating_add(i);
            if resolved < 0 {
                return Err(LineError::RelativeOutOfRange {
                    name,
                    index: i,
                    token: token.to_owned(),
                    defined,
                    plural: kind.plural,
                });
            }
            resolved
        }
    };
    u32::try_from(zero_based).ok().filter(|&i| i != NO_INDEX).ok_or(LineError::TooLarge { name, index: i })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn corner_forms_and_relative_indices() {
        let corner = |v, t, n| Ok(Corner { v, t, n });
        assert_eq!(parse_corner("3", [5, 2, 8]), corner(2, None, None));
        assert_eq!(parse_corner("3/1", [5, 2, 8]), corner(2, Some(0), None));
        assert_eq!(parse_corner("3//7", [5, 2, 8]), corner(2, None, Some(6)));
        assert_eq!(parse_corner("3/1/7", [5, 2, 8]), corner(2, Some(0), Some(6)));
        assert_eq!(parse_corner("-1/-1/-2", [5, 2, 8]), corner(4, Some(1), Some(6)));
        assert_eq!(parse_corner("-5/-2", [5, 2, 8]), corner(0, Some(0), None));
        assert!(parse_corner("-6", [5, 2, 8]).unwrap_err().to_string().contains("only 5 vertices"));
        assert!(parse_corner("1/-3", [5, 2, 8]).unwrap_err().to_string().contains("only 2 texture coordinates"));
        assert!(parse_corner("1//-9", [5, 2, 8]).unwrap_err().to_string().contains("only 8 normals"));
        assert!(parse_corner("0", [5, 2, 8]).unwrap_err().to_string().contains("vertex index 0"));
        assert!(parse_corner("1/0", [5, 2, 8]).unwrap_err().to_string().contains("texture coordinate (vt) index 0"));
        assert!(parse_corner("1//0", [5, 2, 8]).unwrap_err().to_string().contains("normal (vn) index 0"));
        assert!(parse_corner("1/x", [5, 2, 8]).unwrap_err().to_string().contains("'x'"));
        assert!(parse_corner("1/1/1/1", [5, 2, 8]).unwrap_err().to_string().contains("more than 3 parts"));
        assert!(parse_corner("a", [5, 2, 8]).is_err());
        assert!(parse_corner("/1", [5, 2, 8]).is_err());
        assert!(parse_corner("99999999999", [5, 2, 8]).unwrap_err().to_string().contains("too large"));
    }
}
