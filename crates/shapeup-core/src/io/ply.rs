//! Stanford PLY: ascii, binary little endian and binary big endian, kept whole.
//!
//! **Read.** The header (`format`, `comment`, `obj_info`, `element NAME COUNT`,
//! `property TYPE NAME`, `property list COUNT_TYPE ITEM_TYPE NAME`, with the types
//! `char uchar short ushort int uint float double` or `int8 … float64`) and every element with
//! every property are kept in [`PlyAttributes`] (the mesh's [`Attributes::Ply`]): the header
//! lines verbatim and in order, each property's declared type and its values, exactly (every
//! PLY type converts exactly to `f64`; an ascii value is read as its declared type holds it, so
//! an ascii file and a binary one with the same header hold the same values). The mesh is built
//! from the `vertex` element's scalar `x y z` (vertices in file order, also those no face uses),
//! one polygon per instance of the `face` element's list `vertex_indices` (or `vertex_index`),
//! then the triangles of a `tristrips` element's list `vertex_indices`: −1 restarts a strip,
//! every other triangle is flipped so that all turn the same way (OpenGL's order), and a
//! triangle that repeats a vertex (strips use them to join) is skipped and counted. In ascii,
//! each element instance is one line. A file must start with `ply`; an ascii one saved as UTF-16
//! (byte-order mark `FF FE` or `FE FF`) is decoded, a binary one cannot be UTF-16 text and is
//! refused naming the encoding.
//!
//! **Hostile sizes.** Header counts reserve at most [`MAX_PREALLOCATION`] values in all, however
//! many elements and properties the header declares; the rest grows as data actually arrives, and
//! every instance, list item and strip index is read (and checked) once, so a file of a few KB
//! that claims 2³¹ elements or lists of 4·10⁹ items fails at its end, in time and memory
//! proportional to its size, and a face of any number of corners reads in linear time. Text
//! quoted in errors (names, values, header lines) is cut to 60 characters.
//!
//! **Written** ([`write_ply`]), a mesh read from PLY gets its header back line for line (only
//! `format` changes when the encoding does) and every element and property with its type; only
//! `x y z` (the mesh's positions, in their declared type) and, when the vertices have
//! `nx ny nz`, the normals (recomputed, angle-weighted per vertex) change. Any other mesh gets
//! `double` x y z, `float` nx ny nz, `uchar` red green blue, faces as
//! `list uchar int vertex_indices` and MeshLab's per-corner `list uchar float texcoord`, as far
//! as its attributes have them; the rest is reported.
//!
//! Hand-written rather than `ply-rs-bw`, to report where a file is malformed (the line, or the
//! byte offset and element index) and to bound what header counts allocate.

use std::io::{self, BufRead, Read, Write};
use std::path::Path;

use glam::DVec3;

use super::Attributes;
use super::attributes::{AttributeKind, NO_INDEX, TexCoords, VertexScalar};
use super::{
    IoError, Lines, LoadedMesh, MAX_PREALLOCATION, build_mesh, decode_text, read_error, report_dropped, shown,
    utf16_encoding, write_f64,
};
use crate::mesh::{Mesh, Polygons};
use crate::warnings::Warnings;

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

impl PlyEncoding {
    /// The word after `format` in the header.
    pub fn keyword(self) -> &'static str {
        match self {
            Self::Ascii => "ascii",
            Self::BinaryLittleEndian => "binary_little_endian",
            Self::BinaryBigEndian => "binary_big_endian",
        }
    }
}

/// A PLY number type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlyScalar {
    /// `char` or `int8`.
    Char,
    /// `uchar` or `uint8`.
    UChar,
    /// `short` or `int16`.
    Short,
    /// `ushort` or `uint16`.
    UShort,
    /// `int` or `int32`.
    Int,
    /// `uint` or `uint32`.
    UInt,
    /// `float` or `float32`.
    Float,
    /// `double` or `float64`.
    Double,
}

const TYPE_NAMES: &str = "char, uchar, short, ushort, int, uint, float, double, int8, uint8, int16, uint16, int32, uint32, float32 or float64";

impl PlyScalar {
    /// Every type, smallest first.
    pub const ALL: [PlyScalar; 8] =
        [Self::Char, Self::UChar, Self::Short, Self::UShort, Self::Int, Self::UInt, Self::Float, Self::Double];

    /// The type a header names (`uchar` or `uint8`, …).
    pub fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::Char,
            "uchar" | "uint8" => Self::UChar,
            "short" | "int16" => Self::Short,
            "ushort" | "uint16" => Self::UShort,
            "int" | "int32" => Self::Int,
            "uint" | "uint32" => Self::UInt,
            "float" | "float32" => Self::Float,
            "double" | "float64" => Self::Double,
            _ => return None,
        })
    }

    /// The type's classic name (`uchar`, `float`, …).
    pub fn name(self) -> &'static str {
        match self {
            Self::Char => "char",
            Self::UChar => "uchar",
            Self::Short => "short",
            Self::UShort => "ushort",
            Self::Int => "int",
            Self::UInt => "uint",
            Self::Float => "float",
            Self::Double => "double",
        }
    }

    /// Bytes per value in a binary file.
    pub fn size(self) -> usize {
        match self {
            Self::Char | Self::UChar => 1,
            Self::Short | Self::UShort => 2,
            Self::Int | Self::UInt | Self::Float => 4,
            Self::Double => 8,
        }
    }

    /// Whether it is one of the integer types.
    pub fn is_integer(self) -> bool {
        !matches!(self, Self::Float | Self::Double)
    }

    /// The smallest and largest value of an integer type (of `f64` for the float types).
    fn range(self) -> (f64, f64) {
        match self {
            Self::Char => (i8::MIN.into(), i8::MAX.into()),
            Self::UChar => (0.0, u8::MAX.into()),
            Self::Short => (i16::MIN.into(), i16::MAX.into()),
            Self::UShort => (0.0, u16::MAX.into()),
            Self::Int => (i32::MIN.into(), i32::MAX.into()),
            Self::UInt => (0.0, u32::MAX.into()),
            Self::Float | Self::Double => (f64::MIN, f64::MAX),
        }
    }

    /// `v` as this type holds it: rounded to the nearest integer and clamped to the type's
    /// range (NaN: 0) for the integer types, rounded to `f32` for `float`, as is for `double`.
    pub fn coerce(self, v: f64) -> f64 {
        match self {
            Self::Float => f64::from(v as f32),
            Self::Double => v,
            _ if v.is_nan() => 0.0,
            _ => {
                let (lo, hi) = self.range();
                // `+ 0.0` turns −0 into 0, which is what an integer holds.
                v.round().clamp(lo, hi) + 0.0
            }
        }
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
            Self::Char => f64::from(i8::from_le_bytes(take(bytes, big_endian))),
            Self::UChar => f64::from(u8::from_le_bytes(take(bytes, big_endian))),
            Self::Short => f64::from(i16::from_le_bytes(take(bytes, big_endian))),
            Self::UShort => f64::from(u16::from_le_bytes(take(bytes, big_endian))),
            Self::Int => f64::from(i32::from_le_bytes(take(bytes, big_endian))),
            Self::UInt => f64::from(u32::from_le_bytes(take(bytes, big_endian))),
            Self::Float => f64::from(f32::from_le_bytes(take(bytes, big_endian))),
            Self::Double => f64::from_le_bytes(take(bytes, big_endian)),
        }
    }

    /// Appends `v`, [coerced](Self::coerce) to this type, in binary.
    fn encode(self, v: f64, big_endian: bool, out: &mut Vec<u8>) {
        fn order<const N: usize>(mut le: [u8; N], big_endian: bool) -> [u8; N] {
            if big_endian {
                le.reverse();
            }
            le
        }
        let v = self.coerce(v);
        // The casts are exact: `v` is an integer within the type's range, or an f32 value.
        match self {
            Self::Char => out.extend_from_slice(&order((v as i8).to_le_bytes(), big_endian)),
            Self::UChar => out.extend_from_slice(&order((v as u8).to_le_bytes(), big_endian)),
            Self::Short => out.extend_from_slice(&order((v as i16).to_le_bytes(), big_endian)),
            Self::UShort => out.extend_from_slice(&order((v as u16).to_le_bytes(), big_endian)),
            Self::Int => out.extend_from_slice(&order((v as i32).to_le_bytes(), big_endian)),
            Self::UInt => out.extend_from_slice(&order((v as u32).to_le_bytes(), big_endian)),
            Self::Float => out.extend_from_slice(&order((v as f32).to_le_bytes(), big_endian)),
            Self::Double => out.extend_from_slice(&order(v.to_le_bytes(), big_endian)),
        }
    }

    /// Appends `v`, [coerced](Self::coerce) to this type, as ascii: integers as integers,
    /// `float` as the shortest text that reads back as the same `f32`, `double` likewise.
    fn write_ascii(self, v: f64, out: &mut Vec<u8>) -> io::Result<()> {
        let v = self.coerce(v);
        match self {
            Self::Float => write!(out, "{:?}", v as f32),
            Self::Double => write_f64(out, v),
            _ => write!(out, "{}", v as i64),
        }
    }

    /// The value an ascii token stands for, as this type holds it; `None` if it is not a
    /// number, or for an integer type not an integer in its range.
    fn parse_ascii(self, token: &str) -> Option<f64> {
        match self {
            // Parsed as f32 directly: rounding through f64 first could round twice.
            Self::Float => token.parse::<f32>().ok().map(f64::from),
            Self::Double => token.parse::<f64>().ok(),
            _ => {
                let v = token.parse::<i64>().map(|i| i as f64).or_else(|_| token.parse::<f64>()).ok()?;
                let (lo, hi) = self.range();
                (v.fract() == 0.0 && v >= lo && v <= hi).then_some(v + 0.0)
            }
        }
    }
}

/// A property's declared type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum PlyType {
    /// `property TYPE NAME`: one value per element instance.
    Scalar(PlyScalar),
    /// `property list COUNT ITEM NAME`: a list per instance, its length stored as `count`.
    List {
        /// The type of the length.
        count: PlyScalar,
        /// The type of the items.
        item: PlyScalar,
    },
}

/// One property of an element, with the values of every instance read.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyProperty {
    name: String,
    ty: PlyType,
    /// Scalar: one value per instance. List: the items of every instance, one after the other.
    values: Vec<f64>,
    /// List: where each instance's items start in `values`, and the total last (instances + 1
    /// entries). Empty for a scalar.
    offsets: Vec<usize>,
}

impl PlyProperty {
    fn new(name: &str, ty: PlyType) -> Self {
        let offsets = if matches!(ty, PlyType::List { .. }) { vec![0] } else { Vec::new() };
        PlyProperty { name: name.to_owned(), ty, values: Vec::new(), offsets }
    }

    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its declared type.
    pub fn ty(&self) -> PlyType {
        self.ty
    }

    /// Number of instances held (the element's count once read).
    pub fn len(&self) -> usize {
        match self.ty {
            PlyType::Scalar(_) => self.values.len(),
            PlyType::List { .. } => self.offsets.len().saturating_sub(1),
        }
    }

    /// Whether no instance is held.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Instance `i`'s value of a scalar property (`None` for a list, or past the end).
    pub fn scalar(&self, i: usize) -> Option<f64> {
        match self.ty {
            PlyType::Scalar(_) => self.values.get(i).copied(),
            PlyType::List { .. } => None,
        }
    }

    /// Instance `i`'s items of a list property (`None` for a scalar, or past the end).
    pub fn list(&self, i: usize) -> Option<&[f64]> {
        let (start, end) = (*self.offsets.get(i)?, *self.offsets.get(i + 1)?);
        self.values.get(start..end)
    }

    /// Every value (scalar) or item (list), instance after instance.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// For a list, where each instance's items start in [`Self::values`], then their total;
    /// empty for a scalar.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    fn is_index_list(&self) -> bool {
        matches!(self.ty, PlyType::List { .. }) && (self.name == "vertex_indices" || self.name == "vertex_index")
    }
}

/// One element (`vertex`, `face`, `material`, …) with its properties.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyElement {
    name: String,
    count: usize,
    properties: Vec<PlyProperty>,
}

impl PlyElement {
    /// Its name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Its number of instances, as the header declares it.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Its properties, in header order.
    pub fn properties(&self) -> &[PlyProperty] {
        &self.properties
    }

    /// The property called `name`, if any.
    pub fn property(&self, name: &str) -> Option<&PlyProperty> {
        self.properties.iter().find(|p| p.name == name)
    }

    fn scalar_index(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name && matches!(p.ty, PlyType::Scalar(_)))
    }
}

/// Which elements and properties the mesh is built from.
#[derive(Debug, Clone, PartialEq)]
struct Plan {
    /// Element index of `vertex` and property indices of x, y, z.
    vertex: (usize, [usize; 3]),
    /// Element and property index of the face index lists.
    face: Option<(usize, usize)>,
    /// Element and property index of the triangle strips.
    strips: Option<(usize, usize)>,
}

/// Everything a PLY file holds: its encoding, header lines, and every element and property with
/// its type and values (see the [module docs](self) and [`super::Attributes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PlyAttributes {
    encoding: PlyEncoding,
    /// The lines between `ply` and `end_header`, verbatim.
    header: Vec<String>,
    elements: Vec<PlyElement>,
    plan: Plan,
}

/// Vertex colour property names, most common first.
const COLOR_NAMES: [[&str; 3]; 3] =
    [["red", "green", "blue"], ["r", "g", "b"], ["diffuse_red", "diffuse_green", "diffuse_blue"]];
/// Per-vertex texture coordinate property names, most common first.
const UV_NAMES: [[&str; 2]; 4] = [["u", "v"], ["s", "t"], ["texture_u", "texture_v"], ["texture_s", "texture_t"]];
const NORMAL_NAMES: [&str; 3] = ["nx", "ny", "nz"];

impl PlyAttributes {
    /// The file's encoding.
    pub fn encoding(&self) -> PlyEncoding {
        self.encoding
    }

    /// The header lines between `ply` and `end_header`, verbatim (without line endings).
    pub fn header_lines(&self) -> &[String] {
        &self.header
    }

    /// Every element, in file order.
    pub fn elements(&self) -> &[PlyElement] {
        &self.elements
    }

    /// The element called `name`, if any.
    pub fn element(&self, name: &str) -> Option<&PlyElement> {
        self.elements.iter().find(|e| e.name == name)
    }

    fn vertex(&self) -> Option<&PlyElement> {
        self.elements.get(self.plan.vertex.0)
    }

    fn face(&self) -> Option<&PlyElement> {
        self.plan.face.and_then(|(e, _)| self.elements.get(e))
    }

    fn vertex_triple(&self, names: [&str; 3]) -> Option<[usize; 3]> {
        let vertex = self.vertex()?;
        let [a, b, c] = names.map(|n| vertex.scalar_index(n));
        Some([a?, b?, c?])
    }

    /// Property indices of the vertex colours.
    fn color_properties(&self) -> Option<[usize; 3]> {
        COLOR_NAMES.iter().find_map(|&names| self.vertex_triple(names))
    }

    /// Property indices of the per-vertex texture coordinates.
    fn uv_properties(&self) -> Option<[usize; 2]> {
        let vertex = self.vertex()?;
        UV_NAMES.iter().find_map(|names| {
            let [u, v] = names.map(|n| vertex.scalar_index(n));
            Some([u?, v?])
        })
    }

    /// Property indices of the vertex normals.
    fn normal_properties(&self) -> Option<[usize; 3]> {
        self.vertex_triple(NORMAL_NAMES)
    }

    /// The face element's per-corner `texcoord` list.
    fn face_texcoords(&self) -> Option<&PlyProperty> {
        self.face()?.properties.iter().find(|p| p.name == "texcoord" && matches!(p.ty, PlyType::List { .. }))
    }

    /// Vertex scalar properties that no view above covers.
    fn other_vertex_scalars(&self) -> impl Iterator<Item = &PlyProperty> {
        let mut covered: Vec<usize> = self.plan.vertex.1.to_vec();
        covered.extend(self.normal_properties().into_iter().flatten());
        covered.extend(self.color_properties().into_iter().flatten());
        covered.extend(self.uv_properties().into_iter().flatten());
        let properties = self.vertex().map_or(&[][..], |v| &v.properties);
        properties
            .iter()
            .enumerate()
            .filter(move |(p, prop)| matches!(prop.ty, PlyType::Scalar(_)) && !covered.contains(p))
            .map(|(_, prop)| prop)
    }

    /// Texture coordinates per corner of `polygons`: per vertex from `u v` (or `s t`,
    /// `texture_u texture_v`, `texture_s texture_t`), else per corner from the faces' `texcoord`
    /// lists (u v per corner; a face whose list does not have two values per corner, or a
    /// polygon that is no face, gets [`NO_INDEX`]).
    pub fn texcoords(&self, polygons: &Polygons) -> Option<TexCoords> {
        if let (Some([u, v]), Some(vertex)) = (self.uv_properties(), self.vertex()) {
            let (u, v) = (vertex.properties.get(u)?, vertex.properties.get(v)?);
            let values = u.values.iter().zip(&v.values).map(|(&u, &v)| [u, v]).collect();
            return Some(TexCoords { values, corners: polygons.indices().to_vec() });
        }
        let lists = self.face_texcoords()?;
        let mut values = Vec::new();
        let mut corners = Vec::with_capacity(polygons.num_corners());
        for (f, poly) in polygons.iter().enumerate() {
            match lists.list(f) {
                Some(items) if items.len() == 2 * poly.len() => {
                    for pair in items.chunks_exact(2) {
                        corners.push(u32::try_from(values.len()).unwrap_or(NO_INDEX));
                        values.push([pair[0], pair[1]]);
                    }
                }
                _ => corners.extend(std::iter::repeat_n(NO_INDEX, poly.len())),
            }
        }
        Some(TexCoords { values, corners })
    }

    /// Per-vertex colours in [0, 1] from `red green blue` (or `r g b`, `diffuse_red …`): integer
    /// types divided by 255 (`ushort` by 65535), float types as they are.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        let vertex = self.vertex()?;
        let channels = self.color_properties()?.map(|p| vertex.properties.get(p));
        let [Some(r), Some(g), Some(b)] = channels else { return None };
        let scale = |p: &PlyProperty| match p.ty {
            PlyType::Scalar(PlyScalar::Float | PlyScalar::Double) => 1.0,
            PlyType::Scalar(PlyScalar::UShort) => f64::from(u16::MAX),
            _ => f64::from(u8::MAX),
        };
        let [sr, sg, sb] = [r, g, b].map(scale);
        Some(r.values.iter().zip(&g.values).zip(&b.values).map(|((&r, &g), &b)| [r / sr, g / sg, b / sb]).collect())
    }

    /// Whether the vertices have `nx ny nz`.
    pub fn has_normals(&self) -> bool {
        self.normal_properties().is_some()
    }

    /// Every vertex scalar property other than x y z, the normals, the colours and the texture
    /// coordinates.
    pub fn vertex_scalars(&self) -> Vec<VertexScalar> {
        self.other_vertex_scalars().map(|p| VertexScalar { name: p.name.clone(), values: p.values.clone() }).collect()
    }

    /// Every kind of attribute held, for writers of other formats to say what they drop.
    pub fn kinds(&self) -> Vec<AttributeKind> {
        let mut kinds = Vec::new();
        if self.uv_properties().is_some() || self.face_texcoords().is_some() {
            kinds.push(AttributeKind::TexCoords);
        }
        if self.has_normals() {
            kinds.push(AttributeKind::Normals);
        }
        if self.color_properties().is_some() {
            kinds.push(AttributeKind::VertexColors);
        }
        if self.other_vertex_scalars().next().is_some() {
            kinds.push(AttributeKind::VertexScalars);
        }
        if self.vertex().is_some_and(|v| v.properties.iter().any(|p| matches!(p.ty, PlyType::List { .. }))) {
            kinds.push(AttributeKind::Other("PLY vertex list properties".into()));
        }
        let roles = [(self.plan.face, "face"), (self.plan.strips, "tristrips")];
        for (e, element) in self.elements.iter().enumerate() {
            if e == self.plan.vertex.0 {
                continue;
            }
            match roles.iter().find(|(role, _)| role.is_some_and(|(re, _)| re == e)) {
                Some(&(Some((_, list)), what)) => {
                    let extra = element
                        .properties
                        .iter()
                        .enumerate()
                        .any(|(p, prop)| p != list && !(what == "face" && prop.name == "texcoord"));
                    if extra {
                        kinds.push(AttributeKind::Other(format!("PLY {what} properties")));
                    }
                }
                _ => kinds.push(AttributeKind::Other(format!("PLY element '{}'", shown(&element.name)))),
            }
        }
        if self.header.iter().any(|l| matches!(l.split_whitespace().next(), Some("comment" | "obj_info"))) {
            kinds.push(AttributeKind::Other("PLY header comments".into()));
        }
        kinds
    }

    /// Why these attributes do not describe `mesh` (another vertex count, other faces), or
    /// `None` when they do and can be written back.
    fn mismatch(&self, mesh: &Mesh) -> Option<String> {
        let vertices = self.vertex().map_or(0, |v| v.count);
        if vertices != mesh.num_vertices() {
            return Some(format!("the file has {vertices} vertices, the mesh {}", mesh.num_vertices()));
        }
        for element in &self.elements {
            if let Some(p) = element.properties.iter().find(|p| p.len() != element.count) {
                return Some(format!(
                    "property '{}' of element '{}' is incomplete",
                    shown(&p.name),
                    shown(&element.name)
                ));
            }
        }
        let mut polygons = mesh.polygons.iter().enumerate();
        let mut differs = |expected: &[f64]| match polygons.next() {
            Some((i, poly)) => {
                let same = poly.len() == expected.len() && poly.iter().zip(expected).all(|(&a, &b)| f64::from(a) == b);
                (!same).then(|| format!("polygon {i} is not the file's"))
            }
            None => Some("the mesh has fewer polygons than the file".to_owned()),
        };
        if let Some(faces) = self.plan.face.and_then(|(e, p)| self.elements.get(e)?.properties.get(p)) {
            for i in 0..faces.len() {
                if let Some(why) = differs(faces.list(i).unwrap_or(&[])) {
                    return Some(why);
                }
            }
        }
        if let Some(strips) = self.plan.strips.and_then(|(e, p)| self.elements.get(e)?.properties.get(p)) {
            let mut triangles = Vec::new();
            for i in 0..strips.len() {
                decode_strip(strips.list(i).unwrap_or(&[]), &mut triangles);
            }
            for t in triangles {
                if let Some(why) = differs(&t.map(f64::from)) {
                    return Some(why);
                }
            }
        }
        polygons.next().map(|(i, _)| format!("polygon {i} is not in the file"))
    }
}

/// Appends the triangles of one strip (its items, −1 restarting) to `out`, flipping every other
/// one so that all turn like the first; returns how many repeat a vertex and were skipped.
fn decode_strip(items: &[f64], out: &mut Vec<[u32; 3]>) -> usize {
    let mut skipped = 0;
    for run in items.split(|&v| v < 0.0) {
        for (j, w) in run.windows(3).enumerate() {
            let [a, b, c] = [w[0], w[1], w[2]].map(|v| v as u32);
            if a == b || b == c || a == c {
                skipped += 1;
            } else {
                out.push(if j % 2 == 0 { [a, b, c] } else { [b, a, c] });
            }
        }
    }
    skipped
}

/// What the header says.
struct Header {
    encoding: PlyEncoding,
    lines: Vec<String>,
    elements: Vec<PlyElement>,
    /// The header line declaring each element, for errors.
    declared: Vec<usize>,
    end_line: usize,
}

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

/// Room in every property for the instances its element announces, within one shared bound
/// ([`MAX_PREALLOCATION`] values in all, however many properties a header declares); lists
/// and anything beyond grow as data arrives.
fn reserve(elements: &mut [PlyElement]) {
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

fn parse_header<R: BufRead>(lines: &mut Lines<R>, path: &Path, utf16: Option<&'static str>) -> Result<Header, IoError> {
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
        header.push(text.to_owned());
    }
}

fn plan(elements: &[PlyElement], declared: &[usize], end_line: usize, path: &Path) -> Result<Plan, IoError> {
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

/// What is checked of each instance as it is read.
struct Checks<'a> {
    plan: &'a Plan,
    num_vertices: usize,
}

impl Checks<'_> {
    /// What is wrong with instance `i` of element `e` (just read): a face of fewer than 3
    /// indices, a face or strip index that is no vertex, a strip too short.
    fn instance(&self, e: usize, element: &PlyElement, i: usize) -> Result<(), String> {
        let n = self.num_vertices;
        // Only errors spell the name out (cut short: it may be a long word).
        let name = || shown(&element.name);
        let list = |p: usize| element.properties.get(p).and_then(|p| p.list(i)).unwrap_or(&[]);
        let out_of_range =
            |v: f64| format!("{} {i} refers to vertex {v}, but the file has {n} vertices (valid: 0..{n})", name());
        if let Some((_, p)) = self.plan.face.filter(|(fe, _)| *fe == e) {
            let k = list(p).len();
            if k < 3 {
                return Err(format!("{} {i} has {k} vertex indices, expected at least 3", name()));
            }
            for &v in list(p) {
                if !(v >= 0.0 && v.fract() == 0.0) {
                    return Err(format!(
                        "element '{}' {i}: vertex index {v} is not a valid index (expected an integer ≥ 0)",
                        name()
                    ));
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
                    return Err(format!(
                        "element '{}' {i}: vertex index {v} is not a valid index (expected an integer ≥ 0, or -1 to restart the strip)",
                        name()
                    ));
                }
                if v >= n as f64 {
                    return Err(out_of_range(v));
                }
            }
            let mut runs = items.split(|&v| v < 0.0).map(<[f64]>::len);
            if let Some(short) = runs.clone().find(|&k| k == 1 || k == 2) {
                return Err(format!("element '{}' {i}: a strip of {short} indices (a triangle needs 3)", name()));
            }
            if runs.all(|k| k < 3) {
                return Err(format!("element '{}' {i}: a strip with fewer than 3 indices", name()));
            }
        }
        Ok(())
    }
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
                parse_ascii_instance(text, element, i).map_err(|m| parse_error(line, m))?;
                checks.instance(e, element, i).map_err(|m| parse_error(line, m))?;
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
fn parse_ascii_instance(text: &str, element: &mut PlyElement, i: usize) -> Result<(), String> {
    let PlyElement { name, properties, .. } = element;
    let name = &*name;
    let mut tokens = text.split_whitespace();
    let mut next_value = |ty: PlyScalar, what: &dyn Fn() -> String| -> Result<f64, String> {
        let token = tokens
            .next()
            .ok_or_else(|| format!("element '{}' {i} has too few values: {} is missing", shown(name), what()))?;
        ty.parse_ascii(token).ok_or_else(|| {
            let (name, token) = (shown(name), shown(token));
            if ty.is_integer() && token.parse::<f64>().is_ok() {
                format!("element '{name}' {i}: {} '{token}' is not a {} (an integer in its range)", what(), ty.name())
            } else {
                format!("element '{name}' {i}: {} '{token}' is not a number", what())
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
                    return Err(format!(
                        "element '{}' {i}: property '{}' has a negative length {len}",
                        shown(name),
                        shown(pname)
                    ));
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
        return Err(format!("element '{}' {i} has {extra} more values than its properties declare", shown(name)));
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
            checks.instance(e, element, i).map_err(|m| error(start, m))?;
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

/// Writes `mesh` as PLY in `encoding` (`None`: the input's own, else binary little endian).
///
/// A mesh read from PLY whose vertex count and polygons are still the file's gets the file back
/// (see the [module docs](self)): every element and property with its type, only x y z and any
/// `nx ny nz` (recomputed, counted as `normals_recomputed`) changed. Otherwise: `double` x y z,
/// `float` nx ny nz if the attributes have normals (recomputed), `uchar` red green blue if they
/// have vertex colours (a warning when a colour is not a multiple of 1/255), the polygons as
/// `list uchar int vertex_indices` (a wider count type for polygons of more than 255 corners),
/// per-corner `list uchar float texcoord` when every corner has texture coordinates, and a
/// warning for what else the attributes hold. Tetrahedra are not written.
///
/// # Errors
/// Any error of `w`; [`io::ErrorKind::InvalidInput`] for more than `i32::MAX` vertices in a new
/// file (the indices are `int`).
pub fn write_ply(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    encoding: Option<PlyEncoding>,
    warnings: &mut Warnings,
) -> io::Result<()> {
    if let Attributes::Ply(own) = attributes {
        let encoding = encoding.unwrap_or(own.encoding);
        match own.mismatch(mesh) {
            None => return write_own(w, mesh, own, encoding, warnings),
            Some(why) => {
                warnings.add(
                    "ply_layout_not_kept",
                    "PLY inputs that no longer match the mesh, written with its positions, faces and common attributes only",
                    || why,
                );
                return write_generic(w, mesh, attributes, encoding, warnings);
            }
        }
    }
    write_generic(w, mesh, attributes, encoding.unwrap_or(PlyEncoding::BinaryLittleEndian), warnings)
}

/// Appends one value of type `ty` to an instance being encoded.
fn put(out: &mut Vec<u8>, ty: PlyScalar, v: f64, encoding: PlyEncoding) -> io::Result<()> {
    match encoding {
        PlyEncoding::Ascii => {
            if !out.is_empty() {
                out.push(b' ');
            }
            ty.write_ascii(v, out)
        }
        PlyEncoding::BinaryLittleEndian => {
            ty.encode(v, false, out);
            Ok(())
        }
        PlyEncoding::BinaryBigEndian => {
            ty.encode(v, true, out);
            Ok(())
        }
    }
}

/// Writes the file `own` describes, with `mesh`'s positions and recomputed normals.
fn write_own(
    w: &mut dyn Write,
    mesh: &Mesh,
    own: &PlyAttributes,
    encoding: PlyEncoding,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let mut head = String::from("ply\n");
    for line in &own.header {
        let mut tokens = line.split_whitespace();
        if encoding != own.encoding && tokens.next() == Some("format") {
            let version = tokens.nth(1).unwrap_or("1.0");
            head.push_str(&format!("format {} {version}", encoding.keyword()));
        } else {
            head.push_str(line);
        }
        head.push('\n');
    }
    head.push_str("end_header\n");
    w.write_all(head.as_bytes())?;

    let (vertex_element, xyz) = own.plan.vertex;
    let normal_properties = own.normal_properties();
    let normals = match normal_properties {
        Some(_) => super::recompute_vertex_normals(mesh, warnings),
        None => Vec::new(),
    };
    let mut rounded = 0;
    let mut first_rounded = None;
    let mut out = Vec::new();
    for (e, element) in own.elements.iter().enumerate() {
        if element.properties.is_empty() {
            continue;
        }
        for i in 0..element.count {
            out.clear();
            for (p, property) in element.properties.iter().enumerate() {
                match property.ty {
                    PlyType::Scalar(ty) => {
                        let mut v = property.scalar(i).unwrap_or(0.0);
                        if e == vertex_element {
                            if let Some(axis) = xyz.iter().position(|&q| q == p) {
                                v = mesh.positions.get(i).and_then(|q| q.to_array().get(axis).copied()).unwrap_or(v);
                                // Only integer types lose more than their declared precision.
                                if ty.is_integer() && ty.coerce(v) != v {
                                    rounded += 1;
                                    first_rounded.get_or_insert(i);
                                }
                            } else if let Some(axis) = normal_properties.and_then(|n| n.iter().position(|&q| q == p))
                                && let Some(Some(normal)) = normals.get(i)
                            {
                                v = normal.to_array().get(axis).copied().unwrap_or(v);
                            }
                        }
                        put(&mut out, ty, v, encoding)?;
                    }
                    PlyType::List { count, item } => {
                        let items = property.list(i).unwrap_or(&[]);
                        put(&mut out, count, items.len() as f64, encoding)?;
                        for &v in items {
                            put(&mut out, item, v, encoding)?;
                        }
                    }
                }
            }
            if encoding == PlyEncoding::Ascii {
                out.push(b'\n');
            }
            w.write_all(&out)?;
        }
    }
    if let Some(first) = first_rounded {
        warnings.add_many(
            "coordinates_rounded",
            "coordinates rounded to the file's integer coordinate types",
            rounded,
            || format!("vertex {first}"),
        );
    }
    Ok(())
}

/// The smallest integer type that holds `n`.
fn count_type(n: usize) -> PlyScalar {
    if n <= usize::from(u8::MAX) {
        PlyScalar::UChar
    } else if n <= usize::from(u16::MAX) {
        PlyScalar::UShort
    } else {
        PlyScalar::UInt
    }
}

/// Writes `mesh` in the layout shapeup chooses (see [`write_ply`]).
fn write_generic(
    w: &mut dyn Write,
    mesh: &Mesh,
    attributes: &Attributes,
    encoding: PlyEncoding,
    warnings: &mut Warnings,
) -> io::Result<()> {
    let n = mesh.num_vertices();
    if i32::try_from(n).is_err() {
        return Err(io::Error::new(io::ErrorKind::InvalidInput, "PLY 'int' indices allow at most i32::MAX vertices"));
    }
    let mut kept = Vec::new();
    if attributes.has_normals() {
        kept.push(AttributeKind::Normals);
    }
    let colors = attributes.vertex_colors().filter(|c| c.len() == n);
    if colors.is_some() {
        kept.push(AttributeKind::VertexColors);
    }
    let texcoords = attributes.texcoords(&mesh.polygons).filter(|t| {
        t.corners.len() == mesh.polygons.num_corners() && t.corners.iter().all(|&c| (c as usize) < t.values.len())
    });
    if texcoords.is_some() {
        kept.push(AttributeKind::TexCoords);
    }
    report_dropped(attributes, &kept, "PLY", warnings);
    let normals = attributes.has_normals().then(|| super::recompute_vertex_normals(mesh, warnings));
    let colors: Option<Vec<[f64; 3]>> = colors.map(|colors| {
        let mut rounded = colors.iter().enumerate().filter(|(_, c)| {
            c.iter().any(|&c| {
                let byte = PlyScalar::UChar.coerce(c * 255.0);
                byte / 255.0 != c
            })
        });
        if let Some((first, _)) = rounded.next() {
            warnings.add_many("colors_rounded", "vertex colours rounded to 8 bits", 1 + rounded.count(), || {
                format!("vertex {first}")
            });
        }
        colors.iter().map(|c| c.map(|c| c * 255.0)).collect()
    });

    let max_corners = mesh.polygons.iter().map(<[u32]>::len).max().unwrap_or(0);
    let index_count = count_type(max_corners);
    let texcoord_count = count_type(2 * max_corners);
    let mut head = format!(
        "ply\nformat {} 1.0\ncomment written by shapeup\nelement vertex {n}\nproperty double x\nproperty double y\nproperty double z\n",
        encoding.keyword()
    );
    if normals.is_some() {
        head.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if colors.is_some() {
        head.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    head.push_str(&format!(
        "element face {}\nproperty list {} int vertex_indices\n",
        mesh.num_polygons(),
        index_count.name()
    ));
    if texcoords.is_some() {
        head.push_str(&format!("property list {} float texcoord\n", texcoord_count.name()));
    }
    head.push_str("end_header\n");
    w.write_all(head.as_bytes())?;

    let mut out = Vec::new();
    for (i, p) in mesh.positions.iter().enumerate() {
        out.clear();
        for x in p.to_array() {
            put(&mut out, PlyScalar::Double, x, encoding)?;
        }
        if let Some(normals) = &normals {
            let normal = normals.get(i).copied().flatten().unwrap_or(DVec3::ZERO);
            for x in normal.to_array() {
                put(&mut out, PlyScalar::Float, x, encoding)?;
            }
        }
        if let Some(colors) = &colors {
            for x in colors.get(i).copied().unwrap_or_default() {
                put(&mut out, PlyScalar::UChar, x, encoding)?;
            }
        }
        if encoding == PlyEncoding::Ascii {
            out.push(b'\n');
        }
        w.write_all(&out)?;
    }
    for (f, poly) in mesh.polygons.iter().enumerate() {
        out.clear();
        put(&mut out, index_count, poly.len() as f64, encoding)?;
        for &v in poly {
            put(&mut out, PlyScalar::Int, f64::from(v), encoding)?;
        }
        if let Some(t) = &texcoords {
            let corners = t.corners.get(mesh.polygons.corner_range(f)).unwrap_or(&[]);
            put(&mut out, texcoord_count, 2.0 * corners.len() as f64, encoding)?;
            for &c in corners {
                for x in t.values.get(c as usize).copied().unwrap_or_default() {
                    put(&mut out, PlyScalar::Float, x, encoding)?;
                }
            }
        }
        if encoding == PlyEncoding::Ascii {
            out.push(b'\n');
        }
        w.write_all(&out)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn decodes_every_type_in_both_endians() {
        assert_eq!(PlyScalar::Char.decode(&[0xff], false), -1.0);
        assert_eq!(PlyScalar::UChar.decode(&[0xff], true), 255.0);
        assert_eq!(PlyScalar::Short.decode(&[0xfe, 0xff], false), -2.0);
        assert_eq!(PlyScalar::Short.decode(&[0xff, 0xfe], true), -2.0);
        assert_eq!(PlyScalar::UShort.decode(&[0x01, 0x02], true), 258.0);
        assert_eq!(PlyScalar::Int.decode(&(-7i32).to_be_bytes(), true), -7.0);
        assert_eq!(PlyScalar::UInt.decode(&u32::MAX.to_le_bytes(), false), f64::from(u32::MAX));
        assert_eq!(PlyScalar::Float.decode(&1.5f32.to_be_bytes(), true), 1.5);
        assert_eq!(PlyScalar::Double.decode(&0.1f64.to_le_bytes(), false), 0.1);
        for (name, ty) in [
            ("float32", PlyScalar::Float),
            ("uint8", PlyScalar::UChar),
            ("int", PlyScalar::Int),
            ("double", PlyScalar::Double),
        ] {
            assert_eq!(PlyScalar::parse(name), Some(ty));
        }
        assert_eq!(PlyScalar::parse("float16"), None);
    }

    #[test]
    fn encode_then_decode_is_exact_at_the_ends_of_every_range() {
        for ty in PlyScalar::ALL {
            let (lo, hi) = ty.range();
            let samples = match ty {
                PlyScalar::Float => vec![f64::from(f32::MIN), f64::from(f32::MIN_POSITIVE), 0.1f32.into(), -0.0],
                PlyScalar::Double => vec![f64::MIN, 5e-324, 0.1, -0.0],
                _ => vec![lo, hi, 0.0, (lo + hi).div_euclid(2.0)],
            };
            for v in samples {
                for big in [false, true] {
                    let mut bytes = Vec::new();
                    ty.encode(v, big, &mut bytes);
                    assert_eq!(bytes.len(), ty.size());
                    assert_eq!(ty.decode(&bytes, big).to_bits(), v.to_bits(), "{ty:?} {v} big {big}");
                }
                let mut text = Vec::new();
                ty.write_ascii(v, &mut text).unwrap();
                let text = String::from_utf8(text).unwrap();
                assert_eq!(ty.parse_ascii(&text).map(f64::to_bits), Some(v.to_bits()), "{ty:?} {text}");
            }
        }
    }

    #[test]
    fn ascii_values_are_read_as_their_type_holds_them() {
        assert_eq!(PlyScalar::Float.parse_ascii("0.1"), Some(f64::from(0.1f32)));
        assert_eq!(PlyScalar::Double.parse_ascii("0.1"), Some(0.1));
        assert_eq!(PlyScalar::UChar.parse_ascii("255.0"), Some(255.0));
        assert_eq!(PlyScalar::UChar.parse_ascii("256"), None);
        assert_eq!(PlyScalar::UChar.parse_ascii("-1"), None);
        assert_eq!(PlyScalar::Int.parse_ascii("1.5"), None);
        assert_eq!(PlyScalar::Char.parse_ascii("-0").map(f64::to_bits), Some(0f64.to_bits()));
        assert_eq!(PlyScalar::Short.coerce(1e9), f64::from(i16::MAX));
        assert_eq!(PlyScalar::UInt.coerce(-2.6), 0.0);
        assert_eq!(PlyScalar::Int.coerce(-2.5), -3.0);
    }

    #[test]
    fn strips_alternate_their_winding_and_restart_at_minus_one() {
        let mut out = Vec::new();
        let skipped = decode_strip(&[0.0, 1.0, 2.0, 3.0, 3.0, 4.0, -1.0, 5.0, 6.0, 7.0], &mut out);
        // Windows of 0 1 2 3 3 4: 0 1 2, 1 2 3 (second: flipped), 2 3 3 and 3 3 4 (skipped); then 5 6 7.
        assert_eq!(out, vec![[0, 1, 2], [2, 1, 3], [5, 6, 7]]);
        assert_eq!(skipped, 2, "2 3 3 and 3 3 4 repeat a vertex");
    }

    #[test]
    fn non_integer_and_negative_face_indices_are_errors() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("n.ply: line 13") && err.contains("face' 0") && err.contains("-1"), "{err}");
        let text = text.replace("int vertex_indices", "float vertex_indices").replace("3 0 -1 2", "3 0 1.5 2");
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("n.ply: line 13") && err.contains("face' 0") && err.contains("1.5"), "{err}");
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
            // And it is written back as it was: declared, without data.
            let mut out = Vec::new();
            write_ply(&mut out, &loaded.mesh, &loaded.attributes, None, &mut Warnings::new()).unwrap();
            assert_eq!(out, bytes);
        }
    }

    #[test]
    fn missing_vertex_coordinate_property() {
        let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n";
        let err = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap_err().to_string();
        assert!(err.contains("line 3") && err.contains("'z'"), "{err}");
    }

    #[test]
    fn integer_coordinates_are_rounded_with_a_warning() {
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty short x\nproperty short y\nproperty short z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
        let loaded = read_ply(text.as_bytes(), Path::new("n.ply")).unwrap();
        let moved = loaded.mesh.with_positions(vec![DVec3::new(0.4, 0.0, 0.0), DVec3::new(7.0, 0.0, 0.0), DVec3::Y]);
        let mut out = Vec::new();
        let mut warnings = Warnings::new();
        write_ply(&mut out, &moved, &loaded.attributes, None, &mut warnings).unwrap();
        let back = read_ply(&out[..], Path::new("n.ply")).unwrap();
        assert_eq!(back.mesh.positions, vec![DVec3::ZERO, DVec3::new(7.0, 0.0, 0.0), DVec3::Y]);
        assert_eq!(warnings.count("coordinates_rounded"), 1);
    }
}
