//! Meshes: positions, polygons with their triangulation, optional tetrahedra.
//!
//! A [`Mesh`] is plain data: `n×3` positions in `f64`, the file's faces as [`Polygons`], their
//! triangulation as `[u32; 3]` (each triangle knowing its polygon) and tetrahedra as `[u32; 4]`
//! indexing into the positions. What a file carries besides (texture coordinates, colours…) is not
//! part of it: readers return it beside the mesh ([`crate::io::LoadedMesh`]). Every constructor
//! validates indices, so code that receives a `Mesh` may index positions with them without checks.
//!
//! Polygons get their triangles from [`triangulate_polygon`] (ear clipping, in `triangulate.rs`).

mod triangulate;

use glam::DVec3;

use crate::warnings::Warnings;

pub use triangulate::{
    PolygonProblem, PolygonTriangulation, TRIANGULATION_WORK_FLOOR, TRIANGULATION_WORK_PER_CORNER,
    TriangulationScratch, triangulate_polygon, triangulation_work_budget,
};

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
        /// Index of the element (0-based).
        index: usize,
        /// The offending vertex index (0-based).
        vertex: u64,
        /// Number of vertices of the mesh.
        num_vertices: usize,
    },
    /// The triangle → polygon map does not match the triangles, or names a missing polygon.
    #[error("the triangle-to-polygon map is inconsistent ({triangles} triangles, {polygons} polygons)")]
    TrianglePolygonMap {
        /// Number of triangles.
        triangles: usize,
        /// Number of polygons.
        polygons: usize,
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

/// Faces as polygons of any size, in file order, stored flat (compressed rows): polygon `i` has
/// the corners `indices[offsets[i]..offsets[i + 1]]`. A corner's position in `indices` is its
/// *corner index*, which per-corner attributes (texture coordinates, normal indices) follow.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Polygons {
    offsets: Vec<usize>,
    indices: Vec<u32>,
}

impl Default for Polygons {
    fn default() -> Self {
        Polygons { offsets: vec![0], indices: Vec::new() }
    }
}

impl Polygons {
    /// No polygons.
    pub fn new() -> Self {
        Self::default()
    }

    /// One polygon per triangle.
    pub fn from_triangles(triangles: &[[u32; 3]]) -> Self {
        let mut p = Polygons { offsets: Vec::with_capacity(triangles.len() + 1), indices: Vec::new() };
        p.offsets.push(0);
        p.indices.reserve(3 * triangles.len());
        for t in triangles {
            p.push(t);
        }
        p
    }

    /// Appends a polygon (its vertex indices, in order).
    pub fn push(&mut self, corners: &[u32]) {
        self.indices.extend_from_slice(corners);
        self.offsets.push(self.indices.len());
    }

    /// Number of polygons.
    pub fn len(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Whether there are no polygons.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The corners of polygon `i`, or `None` past the end.
    pub fn get(&self, i: usize) -> Option<&[u32]> {
        let (start, end) = (*self.offsets.get(i)?, *self.offsets.get(i + 1)?);
        self.indices.get(start..end)
    }

    /// The corner indices of polygon `i` (a range into [`Polygons::indices`]).
    pub fn corner_range(&self, i: usize) -> std::ops::Range<usize> {
        match (self.offsets.get(i), self.offsets.get(i + 1)) {
            (Some(&a), Some(&b)) => a..b,
            _ => 0..0,
        }
    }

    /// Every polygon's corners, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.offsets.windows(2).map(|w| &self.indices[w[0]..w[1]])
    }

    /// All corners, polygon after polygon (the vertex of each corner index).
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// Start of each polygon in [`Polygons::indices`], and the total corner count last.
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// Total number of corners.
    pub fn num_corners(&self) -> usize {
        self.indices.len()
    }
}

impl<'a> FromIterator<&'a [u32]> for Polygons {
    fn from_iter<I: IntoIterator<Item = &'a [u32]>>(iter: I) -> Self {
        let mut p = Polygons::new();
        for poly in iter {
            p.push(poly);
        }
        p
    }
}

/// A mesh: positions, the file's faces as polygons, their triangulation (which triangle
/// constraints, cotan weights and rendering use) and optional tetrahedra.
#[derive(Debug, Clone, PartialEq)]
pub struct Mesh {
    /// `n×3` vertex positions, in file order (vertices no element uses are kept).
    pub positions: Vec<DVec3>,
    /// The faces as read (n-gons in file order, also those left out of the triangulation); the
    /// boundary triangles for a mesh read from tetrahedra.
    pub polygons: Polygons,
    /// `m×3` triangles, counter-clockwise seen from outside: each polygon's ear-clipping
    /// triangulation ([`triangulate_polygon`]), polygon after polygon.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the polygon it comes from (index into [`Mesh::polygons`]).
    pub triangle_polygon: Vec<u32>,
    /// `t×4` tetrahedra; empty for a surface mesh.
    pub tetrahedra: Vec<[u32; 4]>,
}

impl Default for Mesh {
    fn default() -> Self {
        Mesh {
            positions: Vec::new(),
            polygons: Polygons::new(),
            triangles: Vec::new(),
            triangle_polygon: Vec::new(),
            tetrahedra: Vec::new(),
        }
    }
}

impl Mesh {
    /// Why a mesh with faces has no triangles, to follow "has no faces" in an error message: the
    /// first face that cannot be triangulated and its [`PolygonProblem`] (`": its only face,
    /// face 0 (vertices 0 1 1), cannot be triangulated: fewer than 3 distinct corners"`), or an
    /// empty string when every face can be (or there is none).
    pub fn why_no_triangles(&self) -> String {
        let mut scratch = TriangulationScratch::default();
        let first = self.polygons.iter().enumerate().find_map(|(index, poly)| {
            triangulate_polygon(&self.positions, poly, &mut scratch, &mut Vec::new()).err().map(|e| (index, poly, e))
        });
        let Some((index, poly, problem)) = first else { return String::new() };
        let shown: Vec<String> = poly.iter().take(8).map(u32::to_string).collect();
        let more = if poly.len() > 8 { " …" } else { "" };
        let face = format!("face {index} (vertices {}{more})", shown.join(" "));
        match self.num_polygons() {
            1 => format!(": its only face, {face}, cannot be triangulated: {problem}"),
            n => format!(": none of its {n} faces can be triangulated (the first, {face}: {problem})"),
        }
    }

    /// A triangle mesh from positions and triangles (each triangle is also a polygon).
    ///
    /// # Errors
    /// [`MeshError`] if there are no vertices, an index is out of range or a coordinate is not finite.
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        Self::with_tetrahedra(positions, triangles, Vec::new())
    }

    /// A mesh with triangles (each also a polygon) and tetrahedra.
    ///
    /// # Errors
    /// As [`Mesh::new`].
    pub fn with_tetrahedra(
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        tetrahedra: Vec<[u32; 4]>,
    ) -> Result<Self, MeshError> {
        let mesh = Self::from_parts_unchecked(positions, triangles, tetrahedra);
        mesh.validate()?;
        Ok(mesh)
    }

    /// Like [`Mesh::with_tetrahedra`] without validation, for generators whose indices are
    /// correct by construction.
    pub(crate) fn from_parts_unchecked(
        positions: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
        tetrahedra: Vec<[u32; 4]>,
    ) -> Self {
        let polygons = Polygons::from_triangles(&triangles);
        let triangle_polygon = (0..triangles.len() as u32).collect();
        Mesh { positions, polygons, triangles, triangle_polygon, tetrahedra }
    }

    /// A mesh from polygons of any size, kept as they are; the triangulation is each
    /// polygon's [`triangulate_polygon`] (a hole joined by a bridge edge, which repeats two
    /// corners, included). A polygon that cannot be triangulated ([`PolygonProblem`]: fewer
    /// than three distinct corners, an edge run twice the same way, no area) stays in
    /// [`Mesh::polygons`] (and so in outputs) but gets no triangles. The returned warnings
    /// count polygons triangulated, polygons left out (`faces_not_triangulated`, the first
    /// named with its reason) and polygons whose ear clipping ran out of work and ended in a
    /// fan (`polygons_fanned`).
    ///
    /// # Errors
    /// As [`Mesh::new`]; indices are checked before anything else, so an out-of-range index
    /// names the face as it stands in `polygons` (0-based).
    pub fn from_polygons(positions: Vec<DVec3>, polygons: Polygons) -> Result<(Self, Warnings), MeshError> {
        let n = positions.len();
        for (index, poly) in polygons.iter().enumerate() {
            if let Some(&v) = poly.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::IndexOutOfRange { element: "face", index, vertex: v as u64, num_vertices: n });
            }
        }
        let mut warnings = Warnings::new();
        let mut triangles = Vec::with_capacity(polygons.num_corners().saturating_sub(2 * polygons.len()));
        let mut triangle_polygon = Vec::with_capacity(triangles.capacity());
        let mut scratch = TriangulationScratch::default();
        for (index, poly) in polygons.iter().enumerate() {
            let before = triangles.len();
            match triangulate_polygon(&positions, poly, &mut scratch, &mut triangles) {
                Err(problem) => {
                    warnings.add(
                        "faces_not_triangulated",
                        "faces that cannot be triangulated left out of the solver (outputs keep them)",
                        || format!("face {index} ({}): {problem}", join_corners(poly)),
                    );
                    continue;
                }
                Ok(done) if done.fan_fallback => warnings.add(
                    "polygons_fanned",
                    "polygons too tangled to ear-clip within the work budget, the rest of each fanned from one corner (triangles may overlap)",
                    || format!("face {index} ({} corners)", poly.len()),
                ),
                Ok(_) => {}
            }
            if poly.len() > 3 {
                warnings.add(
                    "polygons_triangulated",
                    "polygons with more than 3 corners triangulated for the solver (outputs keep the polygons)",
                    || format!("face {index} ({} corners)", poly.len()),
                );
            }
            triangle_polygon.resize(triangles.len(), index as u32);
            debug_assert!(triangles.len() > before);
        }
        let duplicates = duplicate_faces(&polygons);
        warnings.add_many(
            "duplicate_faces",
            "face(s) on the same vertices as an earlier face (in any order or orientation): kept as given, so constraints on faces act on each such place twice",
            duplicates.len(),
            || duplicates.first().map(|(f, earlier)| format!("face {f}, as face {earlier}")).unwrap_or_default(),
        );
        let mesh = Mesh { positions, polygons, triangles, triangle_polygon, tetrahedra: Vec::new() };
        mesh.validate()?;
        Ok((mesh, warnings))
    }

    /// The same mesh (faces, tetrahedra) at other positions: what every output writes.
    ///
    /// # Panics
    /// Never; a wrong length is caught by [`Mesh::validate`] when written.
    pub fn with_positions(&self, positions: Vec<DVec3>) -> Mesh {
        Mesh {
            positions,
            polygons: self.polygons.clone(),
            triangles: self.triangles.clone(),
            triangle_polygon: self.triangle_polygon.clone(),
            tetrahedra: self.tetrahedra.clone(),
        }
    }

    /// Replaces the faces by `triangles`, each its own polygon (the boundary of a tetrahedral
    /// mesh, or any triangle soup); attributes tied to the old faces no longer apply.
    pub fn set_triangles(&mut self, triangles: Vec<[u32; 3]>) {
        self.polygons = Polygons::from_triangles(&triangles);
        self.triangle_polygon = (0..triangles.len() as u32).collect();
        self.triangles = triangles;
    }

    /// Number of vertices n.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangles m.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// Number of polygons (faces as read).
    pub fn num_polygons(&self) -> usize {
        self.polygons.len()
    }

    /// Number of tetrahedra t.
    pub fn num_tetrahedra(&self) -> usize {
        self.tetrahedra.len()
    }

    /// Checks indices, finiteness, non-emptiness and the triangle → polygon map. [O(n + m + t)]
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
        for (index, poly) in self.polygons.iter().enumerate() {
            if let Some(&v) = poly.iter().find(|&&v| v as usize >= n) {
                return Err(MeshError::IndexOutOfRange { element: "face", index, vertex: v as u64, num_vertices: n });
            }
        }
        check_indices("triangle", &self.triangles, n)?;
        check_indices("tetrahedron", &self.tetrahedra, n)?;
        let polygons = self.polygons.len();
        if self.triangle_polygon.len() != self.triangles.len()
            || self.triangle_polygon.iter().any(|&p| p as usize >= polygons)
        {
            return Err(MeshError::TrianglePolygonMap { triangles: self.triangles.len(), polygons });
        }
        Ok(())
    }

    /// Axis-aligned bounding box (min, max) of all vertices.
    pub fn bounding_box(&self) -> (DVec3, DVec3) {
        self.positions.iter().fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
    }
}

fn join_corners(poly: &[u32]) -> String {
    let shown: Vec<String> = poly.iter().take(8).map(u32::to_string).collect();
    let more = if poly.len() > 8 { " …" } else { "" };
    format!("vertices {}{more}", shown.join(" "))
}

fn check_indices<const K: usize>(element: &'static str, elements: &[[u32; K]], n: usize) -> Result<(), MeshError> {
    for (index, e) in elements.iter().enumerate() {
        if let Some(&v) = e.iter().find(|&&v| v as usize >= n) {
            return Err(MeshError::IndexOutOfRange { element, index, vertex: v as u64, num_vertices: n });
        }
    }
    Ok(())
}

/// The faces on the same set of vertices as an earlier face (in any order or orientation; a
/// repeated corner counts once), each with the first such face: `(face, earlier)`, by face.
/// Faces are sorted by an order-free hash of their vertices; only faces of equal hash are
/// compared.
pub fn duplicate_faces(polygons: &Polygons) -> Vec<(usize, usize)> {
    // splitmix64's finalizer: summed over a face's distinct vertices, any order hashes alike.
    let mix = |v: u32| {
        let mut z = u64::from(v).wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    };
    let vertex_set = |corners: &[u32]| {
        let mut set = corners.to_vec();
        set.sort_unstable();
        set.dedup();
        set
    };
    let mut keys: Vec<(u64, usize)> = polygons
        .iter()
        .enumerate()
        .map(|(f, corners)| (vertex_set(corners).iter().fold(0u64, |h, &v| h.wrapping_add(mix(v))), f))
        .collect();
    keys.sort_unstable();
    let mut duplicates = Vec::new();
    for run in keys.chunk_by(|a, b| a.0 == b.0).filter(|run| run.len() > 1) {
        let mut distinct: Vec<(Vec<u32>, usize)> = Vec::new();
        for &(_, f) in run {
            let set = vertex_set(polygons.get(f).unwrap_or_default());
            match distinct.iter().find(|(other, _)| *other == set) {
                Some(&(_, earlier)) => duplicates.push((f, earlier)),
                None => distinct.push((set, f)),
            }
        }
    }
    duplicates.sort_unstable();
    duplicates
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn quad_positions() -> Vec<DVec3> {
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]
    }

    fn polys(list: &[&[u32]]) -> Polygons {
        list.iter().copied().collect()
    }

    #[test]
    fn convex_polygons_become_fans_from_first_vertex_and_stay_polygons() {
        let (mesh, warnings) = Mesh::from_polygons(quad_positions(), polys(&[&[0, 1, 2, 3]])).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(mesh.triangle_polygon, vec![0, 0]);
        assert_eq!(mesh.polygons.get(0), Some(&[0, 1, 2, 3][..]));
        assert_eq!(warnings.count("polygons_triangulated"), 1);
    }

    #[test]
    fn faces_repeating_a_vertex_are_kept_as_polygons_without_triangles() {
        let (mesh, warnings) =
            Mesh::from_polygons(quad_positions(), polys(&[&[0, 1, 1], &[0, 1, 2], &[0, 1, 2], &[0, 1, 2, 2]])).unwrap();
        assert_eq!(mesh.polygons.len(), 4, "every face is kept");
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 1, 2], [0, 1, 2]], "duplicates kept, a b c c merged");
        assert_eq!(mesh.triangle_polygon, vec![1, 2, 3]);
        assert_eq!(warnings.count("faces_not_triangulated"), 1);
        assert!(warnings.iter().any(|w| w.first.contains("face 0")));
    }

    /// A face on the same vertices as an earlier one, in any order or orientation, is counted
    /// once with the earlier face; faces sharing only some vertices are not.
    #[test]
    fn duplicate_faces_are_counted_with_the_earlier_face() {
        let faces = polys(&[&[0, 1, 2], &[1, 3, 2], &[2, 1, 0], &[0, 1, 2, 3], &[1, 2, 0], &[3, 2, 1, 0], &[0, 1, 3]]);
        assert_eq!(duplicate_faces(&faces), [(2, 0), (4, 0), (5, 3)]);
        let (_, warnings) = Mesh::from_polygons(quad_positions(), faces).unwrap();
        let w = warnings.iter().find(|w| w.kind == "duplicate_faces").unwrap();
        assert_eq!((w.count, w.first.as_str()), (3, "face 2, as face 0"));
        let (_, warnings) = Mesh::from_polygons(quad_positions(), polys(&[&[0, 1, 2], &[0, 2, 3]])).unwrap();
        assert_eq!(warnings.count("duplicate_faces"), 0);
    }

    #[test]
    fn out_of_range_index_names_the_face() {
        let err = Mesh::from_polygons(quad_positions(), polys(&[&[0, 1, 2], &[0, 9, 2]])).unwrap_err();
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
