//! What a group applies to: the chosen vertices or faces ([`Selection`]) and the kind of
//! element a type builds one constraint on ([`Element`]).

use crate::geometry::RestGeometry;

/// The elements a constraint type builds one constraint on: what its selection picks, what
/// the editor offers it for, and which meshes the shared tests run it on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Element {
    /// One constraint per selected vertex.
    Vertex,
    /// One constraint over all the selected vertices together (at least `min` of them).
    VertexSet {
        /// Fewest vertices the set needs.
        min: usize,
    },
    /// One per edge whose two vertices are selected.
    Edge,
    /// One per polygon face of the input (as read, not its triangles) with between `min` and
    /// `max` corners.
    Face {
        /// Fewest corners.
        min: usize,
        /// Most corners.
        max: usize,
    },
    /// One per triangle of the triangulation.
    Triangle,
    /// One per tetrahedron.
    Tetrahedron,
    /// One per selected vertex, with a triangle of a piece that holds no selected vertex to
    /// follow (the mesh needs two pieces or more).
    PieceVertex,
}

impl Element {
    /// Whether the element is a polygon face (selections may name faces).
    pub fn is_face(self) -> bool {
        matches!(self, Element::Face { .. })
    }

    /// Plural noun for messages ("quad faces", "vertices").
    pub fn plural(self) -> String {
        match self {
            Element::Vertex | Element::VertexSet { .. } => "vertices".into(),
            Element::PieceVertex => "vertices of pieces that follow others".into(),
            Element::Edge => "edges".into(),
            Element::Face { min: 4, max: 4 } => "quad faces".into(),
            Element::Face { min, max } if max == usize::MAX => format!("faces of {min} or more corners"),
            Element::Face { min, max } => format!("faces of {min} to {max} corners"),
            Element::Triangle => "triangles".into(),
            Element::Tetrahedron => "tetrahedra".into(),
        }
    }
}

/// Which vertices (or polygon faces) a constraint group applies to.
///
/// Per-vertex and vertex-set constraints take the chosen vertices; edge, face, triangle and
/// tetrahedron constraints take the elements all of whose vertices are chosen, and face
/// constraints the chosen faces of a face selection ([`Element`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Selection {
    /// Every vertex and face.
    All,
    /// `chosen[i]` for each vertex i.
    Vertices(Vec<bool>),
    /// Polygon faces by index (into the input's faces), and the vertices they use.
    Faces {
        /// `faces[f]`: face f is chosen.
        faces: Vec<bool>,
        /// `vertices[i]`: vertex i is a corner of a chosen face.
        vertices: Vec<bool>,
    },
}

impl Selection {
    /// A selection of the listed vertex indices out of `n` (indices must be `< n`).
    pub fn from_indices(n: usize, indices: &[usize]) -> Self {
        let mut chosen = vec![false; n];
        for &i in indices {
            if let Some(c) = chosen.get_mut(i) {
                *c = true;
            }
        }
        Selection::Vertices(chosen)
    }

    /// A selection of the listed faces of `faces` and their corners (indices must be
    /// `< faces.len()`; others are ignored), over `n` vertices.
    pub fn from_faces(n: usize, faces: &crate::mesh::Polygons, indices: &[usize]) -> Self {
        let mut chosen = vec![false; faces.len()];
        let mut vertices = vec![false; n];
        for &f in indices {
            if let (Some(c), Some(corners)) = (chosen.get_mut(f), faces.get(f)) {
                *c = true;
                for &v in corners {
                    if let Some(x) = vertices.get_mut(v as usize) {
                        *x = true;
                    }
                }
            }
        }
        Selection::Faces { faces: chosen, vertices }
    }

    /// Whether vertex `v` is chosen (a corner of a chosen face, for a face selection).
    pub fn contains(&self, v: u32) -> bool {
        match self {
            Selection::All => true,
            Selection::Vertices(chosen) | Selection::Faces { vertices: chosen, .. } => {
                chosen.get(v as usize).copied().unwrap_or(false)
            }
        }
    }

    /// Whether polygon face `f` with these corners is chosen: every face for
    /// [`Selection::All`], a face whose corners are all chosen for a vertex selection, a listed
    /// face for a face selection.
    pub fn contains_face(&self, f: usize, corners: &[u32]) -> bool {
        match self {
            Selection::Faces { faces, .. } => faces.get(f).copied().unwrap_or(false),
            _ => self.contains_all(corners),
        }
    }

    /// The chosen vertices in ascending order, out of `n`.
    pub fn vertex_list(&self, n: usize) -> Vec<u32> {
        (0..n as u32).filter(|&v| self.contains(v)).collect()
    }

    /// Whether every vertex of an element is chosen.
    pub fn contains_all(&self, element: &[u32]) -> bool {
        element.iter().all(|&v| self.contains(v))
    }
}

/// Whether `selection` picks at least one element of this kind on `rest` (for menus: the
/// editor offers a type only when it fits the selection).
pub fn selects_any(element: Element, rest: &RestGeometry, selection: &Selection) -> bool {
    let n = rest.num_vertices() as u32;
    match element {
        Element::Vertex => (0..n).any(|v| selection.contains(v)),
        Element::VertexSet { min } => (0..n).filter(|&v| selection.contains(v)).take(min).count() >= min.max(1),
        Element::Edge => rest.topology.edges.iter().any(|e| selection.contains_all(&e[..])),
        Element::Face { min, max } => rest
            .faces
            .iter()
            .enumerate()
            .any(|(f, corners)| (min..=max).contains(&corners.len()) && selection.contains_face(f, corners)),
        Element::Triangle => rest.triangles.iter().any(|t| selection.contains_all(&t[..])),
        Element::Tetrahedron => rest.tetrahedra.iter().any(|t| selection.contains_all(&t[..])),
        Element::PieceVertex => {
            (0..n).any(|v| selection.contains(v))
                && crate::constraints::kit::pieces::unselected_piece_triangles(rest, |v| selection.contains(v))
                    .next()
                    .is_some()
        }
    }
}
