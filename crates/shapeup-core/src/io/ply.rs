//! Stanford PLY: ascii, binary little endian and binary big endian.
//!
//! Read: a `vertex` element with scalar `x`, `y`, `z` of any numeric type (`char uchar short
//! ushort int uint float double` or `int8 … float64`), any other vertex properties (normals,
//! colours, …) ignored; an optional `face` element with a list property `vertex_indices` (or
//! `vertex_index`) of any count and index types, other face properties ignored; any other
//! element (`edge`, `material`, …) is read past and ignored, in binary too. Faces with fewer than
//! three corners or a repeated corner are dropped and counted in the report. `comment` and
//! `obj_info` lines are skipped. In ascii, each element instance is one line.
//!
//! Hand-written rather than `ply-rs-bw`, to report where (line, or byte offset and element index)
//! a file is malformed and to bound what header counts allocate.

use std::io::{self, BufRead, Read, Write};
use std::path::{Path, PathBuf};

use glam::DVec3;

use super::{IoError, Lines, LoadedMesh, bounded_vec, build_mesh, write_point};
use crate::mesh::Mesh;

/// How a PLY file encodes its elements.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyEncoding {
    /// `format ascii 1.0`.
    Ascii,
    /// `format binary_little_endian 1.0`.
    BinaryLittleEndian,
    /// `format binary_big_endian 1.0`.
    BinaryBigEndian,
}

/// A scalar property type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

const TYPE_NAMES: &str = "char, uchar, short, ushort, int, uint, float, double, int8, uint8, int16, uint16, int32, uint32, float32 or float64";

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    /// Decodes `bytes` (exactly [`Self::size`] long; shorter slices are zero-padded). Every PLY
    /// type converts to `f64` exactly.
    fn decode(self, bytes: &[u8], big_endian: bool) -> f64 {
        fn take<const N: usize>(bytes: &[u8], big_endian: bool) -> [u8; N] {
            let mut out = [0; N];
            for (o, b) in out.iter_mut().zip(bytes) {
                *o = *b;
            }
            // Normalise to little endian so one `from_le_bytes` serves both.
            if big_endian {
                out.reverse();
            }
            out
        }
        match self {
            Self::I8 => f64::from(i8::from_le_bytes(take(bytes, big_endian))),
            Self::U8 => f64::from(u8::from_le_bytes(take(bytes, big_endian))),
            Self::I16 => f64::from(i16::from_le_bytes(take(bytes, big_endian))),
            Self::U16 => f64::from(u16::from_le_bytes(take(bytes, big_endian))),
            Self::I32 => f64::from(i32::from_le_bytes(take(bytes, big_endian))),
            Self::U32 => f64::from(u32::from_le_bytes(take(bytes, big_endian))),
            Self::F32 => f64::from(f32::from_le_bytes(take(bytes, big_endian))),
            Self::F64 => f64::from_le_bytes(take(bytes, big_endian)),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    properties: Vec<Property>,
    /// Header line declaring it, for errors.
    line: usize,
}

/// Which properties of which elements the mesh is built from.
struct Plan {
    /// Element index of `vertex` and property indices of x, y, z.
    vertex: (usize, [usize; 3]),
    /// Element index of `face` and property index of its index list.
    face: Option<(usize, usize)>,
}

/// Reads a PLY file from `reader`; `path` only names it in errors.
///
/// # Errors
/// [`IoError::Parse`] with the line for a malformed header (no `ply`/`format`/`end_header`,
/// unknown type or keyword, no `vertex` element with `x y z`) or malformed ascii data;
/// [`IoError::Binary`] with the byte offset and element index for truncated binary data;
/// [`IoError::Invalid`] for zero vertices; [`IoError::Mesh`] for an out-of-range index or a
/// non-finite coordinate; [`IoError::Read`] if reading fails.
pub fn read_ply(reader: impl BufRead, path: &Path) -> Result<LoadedMesh, IoError> {
    let mut lines = Lines::new(reader);
    let (encoding, elements, end_line) = parse_header(&mut lines, path)?;
    let plan = plan(&elements, end_line, path)?;
    let mut sink =
        Sink { plan, positions: Vec::new(), faces: Vec::new(), corner: Vec::new(), path: path.to_path_buf() };
    if let Some(vertex) = elements.get(sink.plan.vertex.0) {
        sink.positions = bounded_vec(vertex.count);
    }
    if let Some(face) = sink.plan.face.and_then(|(e, _)| elements.get(e)) {
        sink.faces = bounded_vec(face.count);
    }
    match encoding {
        PlyEncoding::Ascii => read_ascii_body(&mut lines, &elements, &mut sink)?,
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let offset = lines.consumed;
            let mut body =
                Binary { reader: lines.into_inner(), offset, big_endian: encoding == PlyEncoding::BinaryBigEndian };
            read_binary_body(&mut body, &elements, &mut sink)?;
        }
    }
    if sink.positions.is_empty() {
        return Err(IoError::Invalid { path: path.to_path_buf(), message: "the PLY file has no vertices".to_owned() });
    }
    build_mesh(path, sink.positions, sink.faces.iter().map(Vec::as_slice).collect())
}

fn parse_header<R: BufRead>(lines: &mut Lines<R>, path: &Path) -> Result<(PlyEncoding, Vec<Element>, usize), IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let read_error = |source| IoError::Read { path: path.to_path_buf(), source };
    match lines.next_line().map_err(read_error)? {
        Some((_, first)) if first.trim() == "ply" => {}
        Some((_, first)) => {
            let shown: String = first.chars().take(40).collect();
            return Err(parse_error(1, format!("not a PLY file: expected 'ply' on the first line, found '{shown}'")));
        }
        None => return Err(parse_error(1, "empty file (expected 'ply' on the first line)".to_owned())),
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some((line, text)) = lines.next_line().map_err(read_error)? else {
            return Err(parse_error(
                lines.number + 1,
                "the header has no 'end_header' line (the file ends inside the header)".to_owned(),
            ));
        };
        let tokens: Vec<&str> = text.split_whitespace().collect();
        match tokens.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", format, ..] => {
                encoding = Some(match *format {
                    "ascii" => PlyEncoding::Ascii,
                    "binary_little_endian" => PlyEncoding::BinaryLittleEndian,
                    "binary_big_endian" => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(parse_error(
                            line,
                            format!(
                                "unknown format '{other}' (expected ascii, binary_little_endian or binary_big_endian)"
                            ),
                        ));
                    }
                });
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    parse_error(line, format!("element '{name}' has count '{count}', expected a non-negative integer"))
                })?;
                elements.push(Element { name: (*name).to_owned(), count, properties: Vec::new(), line });
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return Err(parse_error(line, "'property' before any 'element'".to_owned()));
                };
                let scalar = |name: &str| {
                    Scalar::parse(name).ok_or_else(|| {
                        parse_error(line, format!("unknown property type '{name}' (expected {TYPE_NAMES})"))
                    })
                };
                let (kind, name) = match rest {
                    ["list", count, item, name] => {
                        let count_type = scalar(count)?;
                        if !count_type.is_integer() {
                            return Err(parse_error(
                                line,
                                format!("list count type '{count}' must be an integer type"),
                            ));
                        }
                        (Kind::List { count: count_type, item: scalar(item)? }, name)
                    }
                    [ty, name] if *ty != "list" => (Kind::Scalar(scalar(ty)?), name),
                    _ => {
                        return Err(parse_error(
                            line,
                            format!(
                                "malformed property '{text}' (expected 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME')"
                            ),
                        ));
                    }
                };
                element.properties.push(Property { name: (*name).to_owned(), kind });
            }
            ["end_header"] => {
                let encoding =
                    encoding.ok_or_else(|| parse_error(line, "no 'format' line before 'end_header'".to_owned()))?;
                return Ok((encoding, elements, line));
            }
            [keyword, ..] => {
                let shown: String = keyword.chars().take(40).collect();
                let hint = if elements.is_empty() { "" } else { "; is 'end_header' missing?" };
                return Err(parse_error(
                    line,
                    format!(
                        "unexpected header line starting with '{shown}' (expected format, element, property, comment, obj_info or end_header{hint})"
                    ),
                ));
            }
        }
    }
}

fn plan(elements: &[Element], end_line: usize, path: &Path) -> Result<Plan, IoError> {
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.to_path_buf(), line, message };
    let find = |name: &str| -> Result<Option<usize>, IoError> {
        let mut found = elements.iter().enumerate().filter(|(_, e)| e.name == name);
        let first = found.next().map(|(i, _)| i);
        if let Some((_, second)) = found.next() {
            return Err(parse_error(second.line, format!("a second '{name}' element")));
        }
        Ok(first)
    };
    let vertex_index =
        find("vertex")?.ok_or_else(|| parse_error(end_line, "the header declares no 'vertex' element".to_owned()))?;
    let vertex = elements.get(vertex_index).ok_or_else(|| parse_error(end_line, "no 'vertex' element".to_owned()))?;
    let mut xyz = [0; 3];
    for (axis, slot) in ["x", "y", "z"].iter().zip(&mut xyz) {
        *slot = vertex
            .properties
            .iter()
            .position(|p| p.name == *axis && matches!(p.kind, Kind::Scalar(_)))
            .ok_or_else(|| parse_error(vertex.line, format!("element 'vertex' has no scalar property '{axis}'")))?;
    }
    let face = match find("face")? {
        None => None,
        Some(face_index) => {
            let face = elements.get(face_index).ok_or_else(|| parse_error(end_line, "no 'face' element".to_owned()))?;
            let list = face
                .properties
                .iter()
                .position(|p| {
                    matches!(p.kind, Kind::List { .. }) && (p.name == "vertex_indices" || p.name == "vertex_index")
                })
                .ok_or_else(|| {
                    parse_error(
                        face.line,
                        "element 'face' has no list property 'vertex_indices' (or 'vertex_index')".to_owned(),
                    )
                })?;
            Some((face_index, list))
        }
    };
    Ok(Plan { vertex: (vertex_index, xyz), face })
}

/// Collects positions and faces as element instances are decoded.
struct Sink {
    plan: Plan,
    positions: Vec<DVec3>,
    faces: Vec<Vec<u32>>,
    /// The instance being decoded: its scalar values (vertex) or list items (face).
    corner: Vec<f64>,
    path: PathBuf,
}

/// What an element's properties are needed for.
#[derive(Clone, Copy, PartialEq)]
enum Role {
    Vertex,
    Face,
    Skip,
}

impl Sink {
    fn role(&self, element: usize) -> Role {
        if element == self.plan.vertex.0 {
            Role::Vertex
        } else if self.plan.face.is_some_and(|(e, _)| e == element) {
            Role::Face
        } else {
            Role::Skip
        }
    }

    /// Whether list property `property` of an element with `role` holds the face's indices.
    fn is_face_list(&self, role: Role, property: usize) -> bool {
        role == Role::Face && self.plan.face.is_some_and(|(_, p)| p == property)
    }

    /// Stores the instance just decoded into `self.corner` (vertex: one value per property;
    /// face: the list items). `Err` says what is wrong with a face index.
    fn finish_instance(&mut self, role: Role) -> Result<(), String> {
        match role {
            Role::Vertex => {
                let [x, y, z] = self.plan.vertex.1.map(|p| self.corner.get(p).copied().unwrap_or(f64::NAN));
                self.positions.push(DVec3::new(x, y, z));
            }
            Role::Face => {
                let mut face = Vec::with_capacity(self.corner.len());
                for &v in &self.corner {
                    if !(v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0) {
                        return Err(format!("vertex index {v} is not a valid index (expected an integer ≥ 0)"));
                    }
                    face.push(v as u32);
                }
                self.faces.push(face);
            }
            Role::Skip => {}
        }
        Ok(())
    }
}

/// A list length as a count, if it is one.
fn list_len(v: f64) -> Option<usize> {
    (v >= 0.0 && v <= f64::from(u32::MAX) && v.fract() == 0.0).then_some(v as usize)
}

fn read_ascii_body<R: BufRead>(lines: &mut Lines<R>, elements: &[Element], sink: &mut Sink) -> Result<(), IoError> {
    let path = sink.path.clone();
    let parse_error = |line: usize, message: String| IoError::Parse { path: path.clone(), line, message };
    for (e, element) in elements.iter().enumerate() {
        // Instances without properties occupy no data: do not loop over a huge count for nothing.
        if element.properties.is_empty() {
            continue;
        }
        let role = sink.role(e);
        let name = &element.name;
        for i in 0..element.count {
            let (line, tokens) = loop {
                match lines.next_line().map_err(|source| IoError::Read { path: path.clone(), source })? {
                    None => {
                        return Err(parse_error(
                            lines.number + 1,
                            format!(
                                "file ends before element '{name}' {i} of {} (the header declares {})",
                                element.count, element.count
                            ),
                        ));
                    }
                    Some((line, text)) => {
                        let tokens: Vec<String> = text.split_whitespace().map(str::to_owned).collect();
                        if !tokens.is_empty() {
                            break (line, tokens);
                        }
                    }
                }
            };
            let mut tokens = tokens.iter();
            let mut next_value = |what: &str| -> Result<f64, IoError> {
                let token = tokens.next().ok_or_else(|| {
                    parse_error(line, format!("element '{name}' {i} has too few values: {what} is missing"))
                })?;
                token
                    .parse::<f64>()
                    .map_err(|_| parse_error(line, format!("element '{name}' {i}: {what} '{token}' is not a number")))
            };
            sink.corner.clear();
            for (p, property) in element.properties.iter().enumerate() {
                let what = format!("property '{}'", property.name);
                match property.kind {
                    Kind::Scalar(_) => {
                        let v = next_value(&what)?;
                        if role == Role::Vertex {
                            sink.corner.push(v);
                        }
                    }
                    Kind::List { .. } => {
                        let len = next_value(&format!("the length of {what}"))?;
                        let len = list_len(len).ok_or_else(|| {
                            parse_error(line, format!("element '{name}' {i}: list length {len} is not a count"))
                        })?;
                        let keep = sink.is_face_list(role, p);
                        for _ in 0..len {
                            let v = next_value(&format!("an item of {what}"))?;
                            if keep {
                                sink.corner.push(v);
                            }
                        }
                    }
                }
            }
            let extra = tokens.len();
            if extra > 0 {
                return Err(parse_error(
                    line,
                    format!("element '{name}' {i} has {extra} more values than its properties declare"),
                ));
            }
            sink.finish_instance(role).map_err(|m| parse_error(line, format!("element '{name}' {i}: {m}")))?;
        }
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
    fn read(&mut self, ty: Scalar) -> Result<f64, BinaryError> {
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

fn read_binary_body<R: Read>(body: &mut Binary<R>, elements: &[Element], sink: &mut Sink) -> Result<(), IoError> {
    let path = sink.path.clone();
    for (e, element) in elements.iter().enumerate() {
        // Instances without properties occupy no data: do not loop over a huge count for nothing.
        if element.properties.is_empty() {
            continue;
        }
        let role = sink.role(e);
        let name = &element.name;
        for i in 0..element.count {
            let start = body.offset;
            let error = |offset: u64, message: String| IoError::Binary { path: path.clone(), offset, message };
            let map = |err: BinaryError, offset: u64| match err {
                BinaryError::Eof => error(
                    offset,
                    format!(
                        "file ends inside element '{name}' {i} of {} (the header declares {})",
                        element.count, element.count
                    ),
                ),
                BinaryError::Io(source) => IoError::Read { path: path.clone(), source },
            };
            sink.corner.clear();
            for (p, property) in element.properties.iter().enumerate() {
                match property.kind {
                    Kind::Scalar(ty) => {
                        let v = body.read(ty).map_err(|err| map(err, body.offset))?;
                        if role == Role::Vertex {
                            sink.corner.push(v);
                        }
                    }
                    Kind::List { count, item } => {
                        let len = body.read(count).map_err(|err| map(err, body.offset))?;
                        let len = list_len(len).ok_or_else(|| {
                            error(start, format!("element '{name}' {i}: list length {len} is not a count"))
                        })?;
                        let keep = sink.is_face_list(role, p);
                        for _ in 0..len {
                            let v = body.read(item).map_err(|err| map(err, body.offset))?;
                            if keep {
                                sink.corner.push(v);
                            }
                        }
                    }
                }
            }
            sink.finish_instance(role).map_err(|m| error(start, format!("element '{name}' {i}: {m}")))?;
        }
    }
    Ok(())
}

/// Everything a PLY file holds besides positions and faces (see [`crate::attributes`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlyAttributes {}

impl PlyAttributes {
    /// Texture coordinates per corner.
    pub fn texcoords(&self, _polygons: &crate::mesh::Polygons) -> Option<crate::attributes::TexCoords> {
        None
    }

    /// Per-vertex colours.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        None
    }

    /// Whether the vertices have `nx ny nz`.
    pub fn has_normals(&self) -> bool {
        false
    }

    /// Per-vertex scalar properties other than positions, normals and colours.
    pub fn vertex_scalars(&self) -> Vec<crate::attributes::VertexScalar> {
        Vec::new()
    }

    /// Every kind of attribute held.
    pub fn kinds(&self) -> Vec<crate::attributes::AttributeKind> {
        Vec::new()
    }
}

/// Writes `mesh` as PLY: `double` x, y, z and faces as `list uchar int vertex_indices`.
/// Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] for more than `i32::MAX` vertices (the
/// indices are `int`).
pub fn write_ply(
    w: &mut dyn Write,
    mesh: &Mesh,
    encoding: Option<PlyEncoding>,
    _warnings: &mut crate::warnings::Warnings,
) -> io::Result<()> {
    let encoding = encoding.unwrap_or(PlyEncoding::BinaryLittleEndian);
    if i32::try_from(mesh.num_vertices()).is_err() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, "PLY 'int' indices allow at most i32::MAX vertices"));
    }
    let format = match encoding {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    write!(
        w,
        "ply\nformat {format} 1.0\ncomment written by shapeup\nelement vertex {}\nproperty double x\nproperty double y\nproperty double z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
        mesh.num_vertices(),
        mesh.num_polygons()
    )?;
    match encoding {
        PlyEncoding::Ascii => {
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
        }
        PlyEncoding::BinaryLittleEndian | PlyEncoding::BinaryBigEndian => {
            let big = encoding == PlyEncoding::BinaryBigEndian;
            for p in &mesh.positions {
                for x in p.to_array() {
                    w.write_all(&if big { x.to_be_bytes() } else { x.to_le_bytes() })?;
                }
            }
            for poly in mesh.polygons.iter() {
                w.write_all(&[u8::try_from(poly.len()).unwrap_or(u8::MAX)])?;
                for &v in poly {
                    // In range: indices are below num_vertices ≤ i32::MAX (checked above).
                    let v = i32::try_from(v).unwrap_or(i32::MAX);
                    w.write_all(&if big { v.to_be_bytes() } else { v.to_le_bytes() })?;
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn decodes_every_type_in_both_endians() {
        assert_eq!(Scalar::I8.decode(&[0xff], false), -1.0);
        assert_eq!(Scalar::U8.decode(&[0xff], true), 255.0);
        assert_eq!(Scalar::I16.decode(&[0xfe, 0xff], false), -2.0);
        assert_eq!(Scalar::I16.decode(&[0xff, 0xfe], true), -2.0);
        assert_eq!(Scalar::U16.decode(&[0x01, 0x02], true), 258.0);
        assert_eq!(Scalar::I32.decode(&(-7i32).to_be_bytes(), true), -7.0);
        assert_eq!(Scalar::U32.decode(&u32::MAX.to_le_bytes(), false), f64::from(u32::MAX));
        assert_eq!(Scalar::F32.decode(&1.5f32.to_be_bytes(), true), 1.5);
        assert_eq!(Scalar::F64.decode(&0.1f64.to_le_bytes(), false), 0.1);
        for (name, ty) in
            [("float32", Scalar::F32), ("uint8", Scalar::U8), ("int", Scalar::I32), ("double", Scalar::F64)]
        {
            assert_eq!(Scalar::parse(name), Some(ty));
        }
        assert_eq!(Scalar::parse("float16"), None);
    }

    #[test]
    fn non_integer_and_negative_face_indices_are_errors() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("n.ply: line 13") && err.contains("face' 0") && err.contains("-1"), "{err}");
    }

    #[test]
    fn float_list_count_type_is_refused() {
        let text = "ply\nformat ascii 1.0\nelement face 0\nproperty list float int vertex_indices\nend_header\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("line 4") && err.contains("integer type"), "{err}");
    }

    #[test]
    fn huge_element_without_properties_is_skipped_at_once() {
        for format in ["ascii", "binary_little_endian"] {
            let text = format!(
                "ply\nformat {format} 1.0\nelement nothing 18446744073709551615\nelement vertex 1\nproperty uchar x\nproperty uchar y\nproperty uchar z\nend_header\n"
            );
            let mut bytes = text.into_bytes();
            bytes.extend_from_slice(if format == "ascii" { b"1 2 3\n" } else { &[1, 2, 3] });
            let loaded = read_ply(&bytes[..], Path::new("n.ply")).unwrap();
            assert_eq!(loaded.mesh.positions, vec![DVec3::new(1.0, 2.0, 3.0)]);
        }
    }

    #[test]
    fn missing_vertex_coordinate_property() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("line 3") && err.contains("'z'"), "{err}");
    }
}
