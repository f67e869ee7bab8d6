//! The PLY header: `ply`, `format`, `element`, `property`, `comment`/`obj_info` and `end_header`
//! lines into elements and properties ([`parse_header`]), which of them make the mesh
//! ([`plan`]), and the room reserved for them ([`reserve`]).

use std::io::BufRead;
use std::path::Path;

use super::attributes::{Plan, PlyElement, PlyProperty, PlyType};
use super::scalar::{PlyEncoding, PlyScalar, TYPE_NAMES};
use crate::io::{IoError, Lines, MAX_PREALLOCATION, read_error, shown};

/// What the header says.
pub(super) struct Header {
    pub(super) encoding: PlyEncoding,
    pub(super) lines: Vec<String>,
    pub(super) elements: Vec<PlyElement>,
    /// The header line declaring each element, for errors.
    pub(super) declared: Vec<usize>,
    pub(super) end_line: usize,
}

/// Room in every property for the instances its element announces, within one shared bound
/// ([`MAX_PREALLOCATION`] values in all, however many properties a header declares); lists
/// and anything beyond grow as data arrives.
pub(super) fn reserve(elements: &mut [PlyElement]) {
    let vectors: usize = elements
        .iter()
        .flat_map(|e| &e.properties)
        .map(|p| if matches!(p.ty, PlyType::List { .. }) { 2 } else { 1 })
        .sum();
    let share = MAX_PREALLOCATION / vectors.max(1);
    for element in elements {
        let room = element.count.min(share);
        for property in &mut element.properties {
            property.values.reserve(room);
            if matches!(property.ty, PlyType::List { .. }) {
                property.offsets.reserve(room);
            }
        }
    }
}

pub(super) fn parse_header<R: BufRead>(
    lines: &mut Lines<R>,
    path: &Path,
    utf16: Option<&'static str>,
) -> Result<Header, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let read_error = |source| read_error(path, source);
    match lines.next_line().map_err(read_error)? {
        Some((_, first)) if first.trim() == "ply" => {}
        Some((_, first)) => {
            return Err(parse_error(
                1,
                format!("not a PLY file: expected 'ply' on the first line, found '{}'", shown(first)),
            ));
        }
        None => return Err(parse_error(1, "empty file (expected 'ply' on the first line)".to_owned())),
    }
    let mut encoding = None;
    let mut header = Vec::new();
    let mut elements: Vec<PlyElement> = Vec::new();
    let mut declared = Vec::new();
    loop {
        let Some((line, text)) = lines.next_line().map_err(read_error)? else {
            return Err(parse_error(
                lines.number + 1,
                "the header has no 'end_header' line (the file ends inside the header)".to_owned(),
            ));
        };
        // No header line has more than 5 words but comments, which are kept whole: a sixth word
        // is enough to tell a malformed line, without collecting a huge line's every word.
        let tokens: Vec<&str> = text.split_whitespace().take(6).collect();
        match tokens.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", format, ..] => {
                encoding = Some(match *format {
                    "ascii" => PlyEncoding::Ascii,
                    "binary_little_endian" | "binary_big_endian" if utf16.is_some() => {
                        return Err(parse_error(
                            line,
                            format!(
                                "a {format} file cannot be {} text (the file starts with its byte-order mark)",
                                utf16.unwrap_or_default()
                            ),
                        ));
                    }
                    "binary_little_endian" => PlyEncoding::BinaryLittleEndian,
                    "binary_big_endian" => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(parse_error(
                            line,
                            format!(
                                "unknown format '{}' (expected ascii, binary_little_endian or binary_big_endian)",
                                shown(other)
                            ),
                        ));
                    }
                });
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    parse_error(
                        line,
                        format!(
                            "element '{}' has count '{}', expected a non-negative integer",
                            shown(name),
                            shown(count)
                        ),
                    )
                })?;
                elements.push(PlyElement { name: (*name).to_owned(), count, properties: Vec::new() });
                declared.push(line);
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return Err(parse_error(line, "'property' before any 'element'".to_owned()));
                };
                let scalar = |name: &str| {
                    PlyScalar::parse(name).ok_or_else(|| {
                        parse_error(line, format!("unknown property type '{}' (expected {TYPE_NAMES})", shown(name)))
                    })
                };
                let (ty, name) = match rest {
                    ["list", count, item, name] => {
                        let count_type = scalar(count)?;
                        if !count_type.is_integer() {
                            return Err(parse_error(
                                line,
                                format!("list count type '{}' must be an integer type", shown(count)),
                            ));
                        }
                        (PlyType::List { count: count_type, item: scalar(item)? }, name)
                    }
                    [ty, name] if *ty != "list" => (PlyType::Scalar(scalar(ty)?), name),
                    _ => {
                        return Err(parse_error(
                            line,
                            format!(
                                "malformed property '{}' (expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME')",
                                shown(text)
                            ),
                        ));
                    }
                };
                element.properties.push(PlyProperty::new(name, ty));
            }
            ["end_header"] => {
                let encoding =
                    encoding.ok_or_else(|| parse_error(line, "no 'format' line before 'end_header'".to_owned()))?;
                return Ok(Header { encoding, lines: header, elements, declared, end_line: line });
            }
            [keyword, ..] => {
                let hint = if elements.is_empty() { "" } else { "; is 'end_header' missing?" };
                return Err(parse_error(
                    line,
                    format!(
                        "unexpected header line starting with '{}' (expected format, element, property, comment, obj_info or end_header{hint})",
                        shown(keyword)
                    ),
                ));
            }
        }
        // Kept as read less the whitespace before its keyword (a comment's own spaces stay): a
        // stray carriage return before `format`, written back raw, read as no format line.
        header.push(text.trim_start().to_owned());
    }
}

pub(super) fn plan(elements: &[PlyElement], declared: &[usize], end_line: usize, path: &Path) -> Result<Plan, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let line_of = |e: usize| declared.get(e).copied().unwrap_or(end_line);
    let find = |name: &str| -> Result<Option<usize>, IoError> {
        let mut found = elements.iter().enumerate().filter(|(_, e)| e.name == name).map(|(i, _)| i);
        let first = found.next();
        if let Some(second) = found.next() {
            return Err(parse_error(line_of(second), format!("a second '{}' element", shown(name))));
        }
        Ok(first)
    };
    let vertex_index =
        find("vertex")?.ok_or_else(|| parse_error(end_line, "the header declares no 'vertex' element".to_owned()))?;
    let vertex = elements.get(vertex_index).ok_or_else(|| parse_error(end_line, "no 'vertex' element".to_owned()))?;
    let mut xyz = [0; 3];
    for (axis, slot) in ["x", "y", "z"].iter().zip(&mut xyz) {
        *slot = vertex.scalar_index(axis).ok_or_else(|| {
            parse_error(line_of(vertex_index), format!("element 'vertex' has no scalar property '{axis}'"))
        })?;
    }
    let face = match find("face")? {
        None => None,
        Some(e) => {
            let list = elements.get(e).and_then(|f| f.properties.iter().position(PlyProperty::is_index_list));
            let list = list.ok_or_else(|| {
                parse_error(
                    line_of(e),
                    "element 'face' has no list property 'vertex_indices' (or 'vertex_index')".to_owned(),
                )
            })?;
            Some((e, list))
        }
    };
    // A `tristrips` element without an index list is some other data: kept, not decoded.
    let strips = find("tristrips")?.and_then(|e| {
        let list = elements.get(e)?.properties.iter().position(|p| p.is_index_list() && p.name == "vertex_indices")?;
        Some((e, list))
    });
    Ok(Plan { vertex: (vertex_index, xyz), face, strips })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use std::path::Path;

    use crate::io::ply::read_ply;

    #[test]
    fn float_list_count_type_is_refused() {
        let text = "ply\nformat ascii 1.0\nelement face 0\nproperty list float int vertex_indices\nend_header\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("line 4") && err.contains("integer type"), "{err}");
    }

    #[test]
    fn missing_vertex_coordinate_property() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("line 3") && err.contains("'z'"), "{err}");
    }
}
