//! What a PLY file holds ([`PlyAttributes`]: header lines, elements, properties with their types
//! and values) and the format-neutral views of it (texture coordinates, colours, normals, other
//! vertex scalars) that writers of other formats use.

use super::{PlyEncoding, PlyScalar};
use crate::io::attributes::{AttributeKind, NO_INDEX, TexCoords, VertexScalar};
use crate::io::shown;
use crate::mesh::{Mesh, Polygons};

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
    pub(super) name: String,
    pub(super) ty: PlyType,
    /// Scalar: one value per instance. List: the items of every instance, one after the other.
    pub(super) values: Vec<f64>,
    /// List: where each instance's items start in `values`, and the total last (instances + 1
    /// entries). Empty for a scalar.
    pub(super) offsets: Vec<usize>,
}

impl PlyProperty {
    pub(super) fn new(name: &str, ty: PlyType) -> Self {
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

    pub(super) fn is_index_list(&self) -> bool {
        matches!(self.ty, PlyType::List { .. }) && (self.name == "vertex_indices" || self.name == "vertex_index")
    }
}

/// One element (`vertex`, `face`, `material`, …) with its properties.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyElement {
    pub(super) name: String,
    pub(super) count: usize,
    pub(super) properties: Vec<PlyProperty>,
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

    pub(super) fn scalar_index(&self, name: &str) -> Option<usize> {
        self.properties.iter().position(|p| p.name == name && matches!(p.ty, PlyType::Scalar(_)))
    }
}

/// Which elements and properties the mesh is built from.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Plan {
    /// Element index of `vertex` and property indices of x, y, z.
    pub(super) vertex: (usize, [usize; 3]),
    /// Element and property index of the face index lists.
    pub(super) face: Option<(usize, usize)>,
    /// Element and property index of the triangle strips.
    pub(super) strips: Option<(usize, usize)>,
}

/// Everything a PLY file holds: its encoding, header lines, and every element and property with
/// its type and values (see the [module docs](super) and [`Attributes`](crate::io::Attributes)).
#[derive(Debug, Clone, PartialEq)]
pub struct PlyAttributes {
    pub(super) encoding: PlyEncoding,
    /// The lines between `ply` and `end_header`, verbatim.
    pub(super) header: Vec<String>,
    pub(super) elements: Vec<PlyElement>,
    pub(super) plan: Plan,
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
    pub(super) fn normal_properties(&self) -> Option<[usize; 3]> {
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
    pub(super) fn mismatch(&self, mesh: &Mesh) -> Option<String> {
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
pub(super) fn decode_strip(items: &[f64], out: &mut Vec<[u32; 3]>) -> usize {
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    #[test]
    fn strips_alternate_their_winding_and_restart_at_minus_one() {
        let mut out = Vec::new();
        let skipped = decode_strip(&[0.0, 1.0, 2.0, 3.0, 3.0, 4.0, -1.0, 5.0, 6.0, 7.0], &mut out);
        // Windows of 0 1 2 3 3 4: 0 1 2, 1 2 3 (second: flipped), 2 3 3 and 3 3 4 (skipped); then 5 6 7.
        assert_eq!(out, vec![[0, 1, 2], [2, 1, 3], [5, 6, 7]]);
        assert_eq!(skipped, 2, "2 3 3 and 3 3 4 repeat a vertex");
    }
}
