//! What a mesh file carries besides positions and faces, kept so that outputs lose nothing.
//!
//! [`Attributes`] holds the data of the format a mesh was read from, complete: written back in
//! the same format it reproduces the file (OBJ line for line, PLY property by property with
//! their types, OFF value by value), with only positions (and normals, recomputed from the
//! moved geometry) changed. Written to another format, the writer keeps what that format can
//! hold through the format-neutral views below ([`Attributes::texcoords`],
//! [`Attributes::vertex_colors`], [`Attributes::has_normals`], [`Attributes::vertex_scalars`])
//! and reports the rest ([`Attributes::kinds`]) as a warning.
//!
//! Per-corner data follows [`Polygons`]' corner indices: corner `c` of the mesh is
//! `polygons.indices()[c]`.

use crate::io::obj::ObjAttributes;
use crate::io::off::OffAttributes;
use crate::io::ply::PlyAttributes;
use crate::mesh::Polygons;

/// Marks a corner without a value in per-corner index arrays.
pub const NO_INDEX: u32 = u32::MAX;

/// The attributes of a mesh, as the format it was read from holds them.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Attributes {
    /// Nothing besides positions and faces (generated meshes, STL, MSH, TetGen files).
    #[default]
    None,
    /// Everything an OBJ file held: its lines in order, texture coordinates, normals.
    Obj(Box<ObjAttributes>),
    /// Everything a PLY file held: header, every element and property with its type.
    Ply(Box<PlyAttributes>),
    /// Everything an OFF file held: its header keyword and the values after each vertex and face.
    Off(Box<OffAttributes>),
}

/// Texture coordinates per polygon corner: `corners[c]` indexes `values` ([`NO_INDEX`] for a
/// corner without one).
#[derive(Debug, Clone, PartialEq)]
pub struct TexCoords {
    /// (u, v) pairs.
    pub values: Vec<[f64; 2]>,
    /// One index per polygon corner.
    pub corners: Vec<u32>,
}

/// A per-vertex scalar (a PLY vertex property such as `confidence`, or a colour channel).
#[derive(Debug, Clone, PartialEq)]
pub struct VertexScalar {
    /// The property's name.
    pub name: String,
    /// One value per vertex.
    pub values: Vec<f64>,
}

/// A kind of attribute, for the writers to say what they cannot keep.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum AttributeKind {
    /// Texture coordinates.
    TexCoords,
    /// Vertex normals (recomputed on output).
    Normals,
    /// Per-vertex colours.
    VertexColors,
    /// Per-vertex scalar properties other than the above.
    VertexScalars,
    /// Anything else, named ("OBJ groups and materials", "PLY element 'material'").
    Other(String),
}

impl AttributeKind {
    /// A plural noun phrase for warnings.
    pub fn describe(&self) -> String {
        match self {
            AttributeKind::TexCoords => "texture coordinates".into(),
            AttributeKind::Normals => "normals".into(),
            AttributeKind::VertexColors => "vertex colours".into(),
            AttributeKind::VertexScalars => "per-vertex properties".into(),
            AttributeKind::Other(name) => name.clone(),
        }
    }
}

impl Attributes {
    /// The same attributes as a file written from them holds them (OFF drops comment lines).
    pub fn with_comments(self, comments: usize) -> Self {
        match self {
            Attributes::Off(a) => Attributes::Off(Box::new(a.with_comments(comments))),
            other => other,
        }
    }

    /// Texture coordinates per corner, if the file has any.
    pub fn texcoords(&self, polygons: &Polygons) -> Option<TexCoords> {
        match self {
            Attributes::None => None,
            Attributes::Obj(a) => a.texcoords(polygons),
            Attributes::Ply(a) => a.texcoords(polygons),
            Attributes::Off(a) => a.texcoords(polygons),
        }
    }

    /// Per-vertex colours (r, g, b in [0, 1]), if the file has them for every vertex.
    pub fn vertex_colors(&self) -> Option<Vec<[f64; 3]>> {
        match self {
            Attributes::None => None,
            Attributes::Obj(a) => a.vertex_colors(),
            Attributes::Ply(a) => a.vertex_colors(),
            Attributes::Off(a) => a.vertex_colors(),
        }
    }

    /// Whether the file stores vertex normals (outputs then write recomputed ones).
    pub fn has_normals(&self) -> bool {
        match self {
            Attributes::None => false,
            Attributes::Obj(a) => a.has_normals(),
            Attributes::Ply(a) => a.has_normals(),
            Attributes::Off(a) => a.has_normals(),
        }
    }

    /// Per-vertex scalar properties other than positions, normals and colours (PLY).
    pub fn vertex_scalars(&self) -> Vec<VertexScalar> {
        match self {
            Attributes::Ply(a) => a.vertex_scalars(),
            _ => Vec::new(),
        }
    }

    /// Every kind of attribute the file carries, for writers of another format to say what
    /// they drop.
    pub fn kinds(&self) -> Vec<AttributeKind> {
        match self {
            Attributes::None => Vec::new(),
            Attributes::Obj(a) => a.kinds(),
            Attributes::Ply(a) => a.kinds(),
            Attributes::Off(a) => a.kinds(),
        }
    }
}
