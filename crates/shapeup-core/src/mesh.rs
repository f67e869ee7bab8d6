//! Meshes: positions, triangles and optional tetrahedra.
//!
//! A [`Mesh`] is plain data: `n×3` positions in `f64`, triangles as `[u32; 3]` and tetrahedra as
//! `[u32; 4]` indexing into the positions. Every constructor validates indices, so code that
//! receives a `Mesh` may index positions with them without checks.

use glam::DVec3;

/// An error in the elements of a mesh (bad index, empty mesh, non-finite coordinate).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// The mesh has no vertices, or no elements at all.
    #[error("the mesh is empty ({0})")]
    Empty(&'static str),
    /// An element refers to a vertex that does not exist.
    #[error(
        "{element} {index} refers to vertex {vertex}, but the mesh has {num_vertices} vertices (valid: 0..{num_vertices})"
    )]
    IndexOutOfRange {
        /// "triangle" or "tetrahedron".
        element: &'static str,
        /// Index of the element (0-based, after fan triangulation).
        index: usize,
        /// The offending vertex index (0-based).
        vertex: u64,
        /// Number of vertices of the mesh.
        num_vertices: usize,
    },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate {value:?}")]
    NonFinite {
        /// Index of the vertex (0-based).
        vertex: usize,
        /// Its coordinates.
        value: [f64; 3],
    },
}

/// What [`Mesh::from_polygons`] changed while building a triangle mesh.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PolygonReport {
    /// Polygons with more than three corners, split into fans.
    pub polygons_split: usize,
    /// Faces dropped because they repeat a vertex (or have fewer than three corners).
    pub faces_dropped: usize,
}

/// A triangle mesh, optionally with tetrahedra (a volume mesh whose surface is the triangles).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Mesh {
    /// `n×3` vertex positions, in file order (vertices no element uses are kept).
    pub positions: Vec<DVec3>,
    /// `m×3` triangles, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// `t×4` tetrahedra; empty for a surface mesh.
    pub tetrahedra: Vec<[u32; 4]>,
}

impl Mesh {
    /// A triangle mesh from positions and triangles.
    ///
    /// # Errors
    /// [`MeshError`] if there are no vertices, an index is out of range or a coordinate is not finite.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::with_tetrahedra(positions, triangles, Vec::new())
    }

    /// A mesh with triangles and tetrahedra.
    ///
    /// # Errors
    /// As [`Mesh::new`].
    pub fn with_tetrahedra(
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        tetrahedra: Vec<[u32; 4]>,
    ) -> Result<Self, MeshError> {
        let mesh = Mesh { positions, triangles, tetrahedra };
        mesh.validate()?;
        Ok(mesh)
    }

    /// A triangle mesh from polygons of any size: a polygon (v₀, v₁, …, v_k) becomes the fan
    /// (v₀, v_i, v_{i+1}), i = 1…k−1; a face that repeats a vertex, or has fewer than three
    /// corners, is dropped and counted in the report.
    ///
    /// # Errors
    /// As [`Mesh::new`]; indices are checked before any face is dropped, so an out-of-range
    /// index names the face as it stands in `polygons` (0-based).
    pub fn from_polygons(positions: Vec<DVec3>, polygons: &[Vec<u32>]) -> Result<(Self, PolygonReport), MeshError> {
        let n = positions.len();
        let mut report = PolygonReport::default();
        let mut triangles = Vec::with_capacity(polygons.len());
        for (index, poly) in polygons.iter().enumerate() {
            if let Some(&v) = poly.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::IndexOutOfRange { element: "face", index, vertex: v as u64, num_vertices: n });
            }
            if poly.len() < 3 || has_repeat(poly) {
                report.faces_dropped += 1;
                continue;
            }
            if poly.len() > 3 {
                report.polygons_split += 1;
            }
            for i in 1..poly.len() - 1 {
                triangles.push([poly[0], poly[i], poly[i + 1]]);
            }
        }
        Ok((Mesh::new(positions, triangles)?, report))
    }

    /// Number of vertices n.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles m.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Number of tetrahedra t.
    pub fn num_tetrahedra(&self) -> usize {
        self.tetrahedra.len()
    }

    /// Checks indices, finiteness and non-emptiness. [O(n + m + t)]
    ///
    /// # Errors
    /// The first problem found, as a [`MeshError`].
    pub fn validate(&self) -> Result<(), MeshError> {
        let n = self.positions.len();
        if n == 0 {
            return Err(MeshError::Empty("no vertices"));
        }
        if let Some((vertex, p)) = self.positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFinite { vertex, value: p.to_array() });
        }
        check_indices("triangle", &self.triangles, n)?;
        check_indices("tetrahedron", &self.tetrahedra, n)?;
        Ok(())
    }

    /// Axis-aligned bounding box (min, max) of all vertices.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
    }
}

fn has_repeat(poly: &[u32]) -> bool {
    poly.iter().enumerate().any(|(i, v)| poly[i + 1..].contains(v))
}

fn check_indices<const K: usize>(element: &'static str, elements: &[[u32; K]], n: usize) -> Result<(), MeshError> {
    for (index, e) in elements.iter().enumerate() {
        if let Some(&v) = e.iter().find(|&&v| v as usize >= n) {
            return Err(MeshError::IndexOutOfRange { element, index, vertex: v as u64, num_vertices: n });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad_positions() -> Vec<DVec3> {
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]
    }

    #[test]
    fn polygons_become_fans_from_first_vertex() {
        let (mesh, report) = Mesh::from_polygons(quad_positions(), &[vec![0, 1, 2, 3]]).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(report, PolygonReport { polygons_split: 1, faces_dropped: 0 });
    }

    #[test]
    fn faces_repeating_a_vertex_are_dropped_and_counted() {
        let polys = [vec![0, 1, 1], vec![0, 1, 2], vec![0, 1, 2]];
        let (mesh, report) = Mesh::from_polygons(quad_positions(), &polys).unwrap();
        assert_eq!(mesh.triangles.len(), 2, "duplicate faces are kept");
        assert_eq!(report.faces_dropped, 1);
    }

    #[test]
    fn out_of_range_index_names_the_face() {
        let err = Mesh::from_polygons(quad_positions(), &[vec![0, 1, 2], vec![0, 9, 2]]).unwrap_err();
        assert_eq!(err, MeshError::IndexOutOfRange { element: "face", index: 1, vertex: 9, num_vertices: 4 });
        assert!(err.to_string().contains("face 1 refers to vertex 9"));
    }

    #[test]
    fn empty_and_non_finite_are_errors() {
        assert_eq!(Mesh::new(vec![], vec![]).unwrap_err(), MeshError::Empty("no vertices"));
        let err = Mesh::new(vec![DVec3::new(0.0, f64::NAN, 0.0)], vec![]).unwrap_err();
        assert!(matches!(err, MeshError::NonFinite { vertex: 0, .. }));
    }
}
