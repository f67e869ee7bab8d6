//! The format-neutral words for what a mesh file carries besides positions and faces: texture
//! coordinates, per-vertex scalars, the kinds a writer reports as dropped.
//!
//! Per-corner data follows [`Polygons`](crate::mesh::Polygons)' corner indices: corner `c` of
//! the mesh is `polygons.indices()[c]`.

/// Marks a corner without a value in per-corner index arrays.
pub const NO_INDEX: u32 = u32::MAX;

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
