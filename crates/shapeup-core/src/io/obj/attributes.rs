//! What an OBJ file holds besides positions and faces ([`ObjAttributes`]): its lines in order
//! and the values parsed from them, with the format-neutral views writers of other formats use.

use std::hash::{DefaultHasher, Hash, Hasher};

use glam::DVec3;

use crate::io::attributes::{AttributeKind, TexCoords};
use crate::mesh::{Mesh, Polygons};

/// A hash of the faces as read, so that the writer reproduces `f` lines only for the same faces.
pub(super) fn fingerprint(polygons: &Polygons) -> u64 {
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

/// Everything an OBJ file holds besides positions and faces (see [`Attributes`](crate::io::Attributes) and the
/// [module docs](super)): its lines in order and the values parsed from them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjAttributes {
    /// Every logical line of the file, in order.
    pub lines: Vec<ObjLine>,
    /// The `vt` lines' (u, v) in order (v = 0 when the line has none; w stays in the line).
    pub texcoords: Vec<[f64; 2]>,
    /// The `vn` lines' vectors in order, as read (not normalized).
    pub normals: Vec<DVec3>,
    /// Per polygon corner (see [`crate::mesh::Polygons`]): its index into
    /// [`ObjAttributes::texcoords`], or [`NO_INDEX`](crate::io::NO_INDEX).
    pub corner_texcoords: Vec<u32>,
    /// Per polygon corner: its index into [`ObjAttributes::normals`], or [`NO_INDEX`](crate::io::NO_INDEX).
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
    pub(super) polygons_fingerprint: u64,
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
    pub(super) fn mismatch(&self, mesh: &Mesh) -> Option<String> {
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
