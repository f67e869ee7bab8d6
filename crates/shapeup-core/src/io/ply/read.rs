//! Reading a PLY file: the header, then every element instance in ascii (one line each) or
//! binary (little or big endian), each checked as it arrives, then the mesh from the `vertex`,
//! `face` and `tristrips` elements.

use std::io::{self, BufRead, Read};
use std::path::Path;

use glam::DVec3;

use super::attributes::{Plan, PlyAttributes, PlyElement, PlyType, decode_strip};
use super::header::{Header, parse_header, plan, reserve};
use super::scalar::{PlyEncoding, PlyScalar};
use crate::io::{Attributes, IoError, Lines, LoadedMesh, build_mesh, decode_text, read_error, shown, utf16_encoding};
use crate::mesh::Polygons;
use crate::warnings::Warnings;

/// Reads a PLY file from `reader`; `path` only names it in errors. The mesh's attributes are
/// the whole file ([`Attributes::Ply`]).
///
/// # Errors
/// [`IoError::Parse`] with the line for a malformed header (no `ply`/`format`/`end_header`,
/// unknown type or keyword, no `vertex` element with `x y z`) or malformed ascii data (too few
/// or too many values on an instance's line, a value not of its type, a vertex index out of
/// range, a face with fewer than 3 indices, a strip with fewer than 3 indices, a non-blank line
/// after the last element); [`IoError::Binary`] with the byte offset and element index for
/// truncated binary data and the same face, index and strip errors, or with the offset of any
/// bytes after the last element, or for malformed UTF-16 text; [`IoError::Parse`] also for a
/// binary `format` in a UTF-16 file; [`IoError::Invalid`] for zero vertices; [`IoError::Mesh`]
/// for a non-finite coordinate; [`IoError::Read`] if reading fails.
pub fn read_ply(mut reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let utf16 = utf16_encoding(reader.fill_buf().map_err(|e| read_error(path, e))?);
    // An ascii file in UTF-16 is transcoded; other files pass through byte for byte.
    let reader = decode_text(reader).map_err(|e| read_error(path, e))?;
    let mut lines = Lines::new(reader);
    let Header { encoding, lines: header, mut elements, declared, end_line } = parse_header(&mut lines, path, utf16)?;
    reserve(&mut elements);
    let plan = plan(&elements, &declared, end_line, path)?;
    let num_vertices = elements.get(plan.vertex.0).map_or(0, |v| v.count);
    let checks = Checks { plan: &plan, num_vertices };
    match encoding {
        PlyEncoding::Ascii => read_ascii_body(&mut lines, &mut elements, &checks, path)?,
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let offset = lines.consumed;
            let mut body =
                Binary { reader: lines.into_inner(), offset, big_endian: encoding == PlyEncoding::BinaryBigEndian };
            read_binary_body(&mut body, &mut elements, &checks, path)?;
        }
    }
    let (positions, polygons, warnings) = mesh_parts(&elements, &plan);
    if positions.is_empty() {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "the PLY file has no vertices".to_owned() });
    }
    let mut loaded = build_mesh(path, positions, polygons)?;
    loaded.warnings.extend(warnings.for_file(path));
    loaded.attributes = Attributes::Ply(Box::new(PlyAttributes { encoding, header, elements, plan }));
    Ok(loaded)
}

/// Positions and polygons from the elements read (indices checked while reading), and the
/// strip triangles skipped.
fn mesh_parts(elements: &[PlyElement], plan: &Plan) -> (Vec<DVec3>, Polygons, Warnings) {
    let property = |(e, p): (usize, usize)| elements.get(e).and_then(|e| e.properties.get(p));
    let [x, y, z] = plan.vertex.1.map(|p| property((plan.vertex.0, p)).map_or(&[][..], |p| &p.values));
    let positions = x.iter().zip(y).zip(z).map(|((&x, &y), &z)| DVec3::new(x, y, z)).collect();
    let mut polygons = Polygons::new();
    if let Some(faces) = plan.face.and_then(property) {
        let mut corners = Vec::new();
        for i in 0..faces.len() {
            corners.clear();
            corners.extend(faces.list(i).unwrap_or(&[]).iter().map(|&v| v as u32));
            polygons.push(&corners);
        }
    }
    let mut warnings = Warnings::new();
    if let Some(strips) = plan.strips.and_then(property) {
        let mut triangles = Vec::new();
        for i in 0..strips.len() {
            let skipped = decode_strip(strips.list(i).unwrap_or(&[]), &mut triangles);
            warnings.add_many(
                "strip_triangles_skipped",
                "triangles of triangle strips that repeat a vertex skipped (strips use them to join)",
                skipped,
                || format!("tristrips {i}"),
            );
        }
        for t in &triangles {
            polygons.push(t);
        }
    }
    (positions, polygons, warnings)
}

/// What is checked of each instance as it is read.
struct Checks<'a> {
    plan: &'a Plan,
    num_vertices: usize,
}

impl Checks<'_> {
    /// What is wrong with instance `i` of element `e` (just read): a face of fewer than 3
    /// indices, a face or strip index that is no vertex, a strip too short.
    fn instance(&self, e: usize, element: &PlyElement, i: usize) -> Result<(), InstanceError> {
        let n = self.num_vertices;
        // Only errors spell the name out (cut short: it may be a long word).
        let name = || shown(&element.name).into_owned();
        let list = |p: usize| element.properties.get(p).and_then(|p| p.list(i)).unwrap_or(&[]);
        let out_of_range = |vertex: f64| InstanceError::OutOfRange { element: name(), i, vertex, vertices: n };
        if let Some((_, p)) = self.plan.face.filter(|(fe, _)| *fe == e) {
            let k = list(p).len();
            if k < 3 {
                return Err(InstanceError::TooFewIndices { element: name(), i, indices: k });
            }
            for &v in list(p) {
                if !(v >= 0.0 && v.fract() == 0.0) {
                    return Err(InstanceError::BadFaceIndex { element: name(), i, vertex: v });
                }
                if v >= n as f64 {
                    return Err(out_of_range(v));
                }
            }
        }
        if let Some((_, p)) = self.plan.strips.filter(|(se, _)| *se == e) {
            let items = list(p);
            for &v in items {
                if !(v == -1.0 || (v >= 0.0 && v.fract() == 0.0)) {
                    return Err(InstanceError::BadStripIndex { element: name(), i, vertex: v });
                }
                if v >= n as f64 {
                    return Err(out_of_range(v));
                }
            }
            let mut runs = items.split(|&v| v < 0.0).map(<[f64]>::len);
            if let Some(short) = runs.clone().find(|&k| k == 1 || k == 2) {
                return Err(InstanceError::ShortStrip { element: name(), i, indices: short });
            }
            if runs.all(|k| k < 3) {
                return Err(InstanceError::NoStrip { element: name(), i });
            }
        }
        Ok(())
    }
}

/// What is wrong with one element instance (`element` names it, cut short; `i` is its index):
/// a value that is missing, extra or not of its type (ascii), or a face or strip that makes no
/// polygon. The readers place it at its line (ascii) or byte offset (binary).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
enum InstanceError {
    /// A face of fewer than 3 corners.
    #[error("{element} {i} has {indices} vertex indices, expected at least 3")]
    TooFewIndices { element: String, i: usize, indices: usize },
    /// A face index that is not a whole number ≥ 0.
    #[error("element '{element}' {i}: vertex index {vertex} is not a valid index (expected an integer ≥ 0)")]
    BadFaceIndex { element: String, i: usize, vertex: f64 },
    /// A strip index that is neither a whole number ≥ 0 nor −1.
    #[error(
        "element '{element}' {i}: vertex index {vertex} is not a valid index (expected an integer ≥ 0, or -1 to restart the strip)"
    )]
    BadStripIndex { element: String, i: usize, vertex: f64 },
    /// A face or strip index past the last vertex.
    #[error("{element} {i} refers to vertex {vertex}, but the file has {vertices} vertices (valid: 0..{vertices})")]
    OutOfRange { element: String, i: usize, vertex: f64, vertices: usize },
    /// A strip run of 1 or 2 indices.
    #[error("element '{element}' {i}: a strip of {indices} indices (a triangle needs 3)")]
    ShortStrip { element: String, i: usize, indices: usize },
    /// A strip without any run of 3 indices.
    #[error("element '{element}' {i}: a strip with fewer than 3 indices")]
    NoStrip { element: String, i: usize },
    /// An ascii line that ends before a value (`what` names the value).
    #[error("element '{element}' {i} has too few values: {what} is missing")]
    TooFewValues { element: String, i: usize, what: String },
    /// An ascii number that its integer type does not hold.
    #[error("element '{element}' {i}: {what} '{token}' is not a {ty} (an integer in its range)")]
    OutOfType { element: String, i: usize, what: String, token: String, ty: &'static str },
    /// An ascii token that is not a number.
    #[error("element '{element}' {i}: {what} '{token}' is not a number")]
    NotANumber { element: String, i: usize, what: String, token: String },
    /// A list whose length is negative.
    #[error("element '{element}' {i}: property '{property}' has a negative length {length}")]
    NegativeLength { element: String, i: usize, property: String, length: f64 },
    /// An ascii line with values left over.
    #[error("element '{element}' {i} has {extra} more values than its properties declare")]
    TooManyValues { element: String, i: usize, extra: usize },
}

fn read_ascii_body<R: BufRead>(
    lines: &mut Lines<R>,
    elements: &mut [PlyElement],
    checks: &Checks,
    path: &Path,
) -> Result<(), IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    for (e, element) in elements.iter_mut().enumerate() {
        // Instances without properties occupy no data: do not loop over a huge count for nothing.
        if element.properties.is_empty() {
            continue;
        }
        for i in 0..element.count {
            loop {
                let Some((line, text)) = lines.next_line().map_err(|source| read_error(path, source))? else {
                    let count = element.count;
                    return Err(parse_error(
                        lines.number + 1,
                        format!(
                            "file ends before element '{}' {i} of {count} (the header declares {count})",
                            shown(&element.name)
                        ),
                    ));
                };
                if text.trim().is_empty() {
                    continue;
                }
                parse_ascii_instance(text, element, i).map_err(|m| parse_error(line, m.to_string()))?;
                checks.instance(e, element, i).map_err(|m| parse_error(line, m.to_string()))?;
                break;
            }
        }
    }
    // Content after the last instance means the header's counts disagree with the data.
    while let Some((line, text)) = lines.next_line().map_err(|source| read_error(path, source))? {
        if !text.trim().is_empty() {
            return Err(parse_error(
                line,
                format!(
                    "content after the last element: '{}' (the header's counts disagree with the data)",
                    shown(text.trim())
                ),
            ));
        }
    }
    Ok(())
}

/// Reads instance `i` of `element` from its line's `text` into its properties.
fn parse_ascii_instance(text: &str, element: &mut PlyElement, i: usize) -> Result<(), InstanceError> {
    let PlyElement { name, properties, .. } = element;
    let name = &*name;
    // Only errors spell the name out (cut short: it may be a long word).
    let element = || shown(name).into_owned();
    let mut tokens = text.split_whitespace();
    let mut next_value = |ty: PlyScalar, what: &dyn Fn() -> String| -> Result<f64, InstanceError> {
        let token = tokens.next().ok_or_else(|| InstanceError::TooFewValues { element: element(), i, what: what() })?;
        ty.parse_ascii(token).ok_or_else(|| {
            let (element, what, token) = (element(), what(), shown(token).into_owned());
            if ty.is_integer() && token.parse::<f64>().is_ok() {
                InstanceError::OutOfType { element, i, what, token, ty: ty.name() }
            } else {
                InstanceError::NotANumber { element, i, what, token }
            }
        })
    };
    for property in properties.iter_mut() {
        // Spelled out (cut short) only in errors.
        let pname = &property.name;
        match property.ty {
            PlyType::Scalar(ty) => {
                let v = next_value(ty, &|| format!("property '{}'", shown(pname)))?;
                property.values.push(v);
            }
            PlyType::List { count, item } => {
                let len = next_value(count, &|| format!("the length of property '{}'", shown(pname)))?;
                if len < 0.0 {
                    let property = shown(pname).into_owned();
                    return Err(InstanceError::NegativeLength { element: element(), i, property, length: len });
                }
                // An integer in 0..=u32::MAX (parse_ascii checked the count type's range).
                let len = len as usize;
                for _ in 0..len {
                    let v = next_value(item, &|| format!("an item of property '{}'", shown(pname)))?;
                    property.values.push(v);
                }
                property.offsets.push(property.values.len());
            }
        }
    }
    let extra = tokens.count();
    if extra > 0 {
        return Err(InstanceError::TooManyValues { element: element(), i, extra });
    }
    Ok(())
}

/// Binary data after the header, tracking the byte offset for errors.
struct Binary<R> {
    reader: R,
    offset: u64,
    big_endian: bool,
}

enum BinaryError {
    Eof,
    Io(io::Error),
}

impl<R: Read> Binary<R> {
    fn read(&mut self, ty: PlyScalar) -> Result<f64, BinaryError> {
        let mut buf = [0u8; 8];
        let bytes = buf.get_mut(..ty.size()).unwrap_or(&mut []);
        self.reader.read_exact(bytes).map_err(|e| match e.kind() {
            io::ErrorKind::UnexpectedEof => BinaryError::Eof,
            _ => BinaryError::Io(e),
        })?;
        self.offset += ty.size() as u64;
        Ok(ty.decode(bytes, self.big_endian))
    }
}

fn read_binary_body<R: Read>(
    body: &mut Binary<R>,
    elements: &mut [PlyElement],
    checks: &Checks,
    path: &Path,
) -> Result<(), IoError> {
    for (e, element) in elements.iter_mut().enumerate() {
        // Instances without properties occupy no data: do not loop over a huge count for nothing.
        if element.properties.is_empty() {
            continue;
        }
        let count = element.count;
        for i in 0..count {
            let start = body.offset;
            let name = &element.name;
            let error = |offset: u64, message: String| IoError::Binary { path: path.to_path_buf(), offset, message };
            let map = |err: BinaryError, offset: u64| match err {
                BinaryError::Eof => error(
                    offset,
                    format!("file ends inside element '{}' {i} of {count} (the header declares {count})", shown(name)),
                ),
                BinaryError::Io(source) => IoError::Read { path: path.to_path_buf(), source },
            };
            for property in &mut element.properties {
                match property.ty {
                    PlyType::Scalar(ty) => {
                        let v = body.read(ty).map_err(|err| map(err, body.offset))?;
                        property.values.push(v);
                    }
                    PlyType::List { count: count_type, item } => {
                        let len = body.read(count_type).map_err(|err| map(err, body.offset))?;
                        if len < 0.0 {
                            let message = format!("element '{}' {i}: list length {len} is negative", shown(name));
                            return Err(error(start, message));
                        }
                        // A u32 at most: items are only stored as they arrive.
                        for _ in 0..len as usize {
                            let v = body.read(item).map_err(|err| map(err, body.offset))?;
                            property.values.push(v);
                        }
                        property.offsets.push(property.values.len());
                    }
                }
            }
            checks.instance(e, element, i).map_err(|m| error(start, m.to_string()))?;
        }
    }
    // One byte more shows trailing data; the rest is only counted, never held.
    let read_error = |source| IoError::Read { path: path.to_path_buf(), source };
    let mut byte = [0u8; 1];
    let extra = loop {
        match body.reader.read(&mut byte) {
            Ok(n) => break n,
            Err(err) if err.kind() == io::ErrorKind::Interrupted => {}
            Err(err) => return Err(read_error(err)),
        }
    };
    if extra > 0 {
        let rest = io::copy(&mut body.reader, &mut io::sink()).map_err(read_error)?;
        return Err(IoError::Binary {
            path: path.to_path_buf(),
            offset: body.offset,
            message: format!(
                "{} bytes after the last element (the header's counts or a list length disagree with the data)",
                rest + 1
            ),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn non_integer_and_negative_face_indices_are_errors() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("n.ply: line 13") && err.contains("face' 0") && err.contains("-1"), "{err}");
        let text = text.replace("int vertex_indices", "float vertex_indices").replace("3 0 -1 2", "3 0 1.5 2");
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("n.ply: line 13") && err.contains("face' 0") && err.contains("1.5"), "{err}");
    }
}
