//! Meshes: positions, polygons with their triangulation, optional tetrahedra, and attributes.
//!
//! A [`Mesh`] is plain data: `n×3` positions in `f64`, the file's faces as [`Polygons`], their
//! triangulation as `[u32; 3]` (each triangle knowing its polygon) and tetrahedra as `[u32; 4]`
//! indexing into the positions, plus the file's [`Attributes`]. Every constructor validates indices, so code that
//! receives a `Mesh` may index positions with them without checks.

use glam::DVec3;

use crate::attributes::Attributes;
use crate::warnings::Warnings;

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

    /// Whether every polygon is a triangle.
    pub fn all_triangles(&self) -> bool {
        self.offsets.windows(2).all(|w| w[1] - w[0] == 3)
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
/// constraints, cotan weights and rendering use), optional tetrahedra, and the attributes the
/// file carried (texture coordinates, normals, colours, properties…) so that writing it back
/// loses nothing.
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
    /// What the file carried besides positions and faces, kept for writing.
    pub attributes: Attributes,
}

impl Default for Mesh {
    fn default() -> Self {
        Mesh {
            positions: Vec::new(),
            polygons: Polygons::new(),
            triangles: Vec::new(),
            triangle_polygon: Vec::new(),
            tetrahedra: Vec::new(),
            attributes: Attributes::None,
        }
    }
}

impl Mesh {
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
        Mesh { positions, polygons, triangles, triangle_polygon, tetrahedra, attributes: Attributes::None }
    }

    /// A mesh from polygons of any size, kept as they are; the triangulation is each
    /// polygon's [`triangulate_polygon`]. A polygon that still repeats a vertex after repeated
    /// neighbouring corners are merged, or has fewer than three distinct corners, stays in
    /// [`Mesh::polygons`] (and so in outputs) but gets no triangles. Both facts are counted in
    /// the returned warnings.
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
        let mut corners = Vec::new();
        for (index, poly) in polygons.iter().enumerate() {
            let before = triangles.len();
            if !triangulate_polygon(&positions, poly, &mut corners, &mut triangles) {
                warnings.add(
                    "faces_not_triangulated",
                    "faces that repeat a vertex (or have fewer than 3 distinct corners) left out of the solver (outputs keep them)",
                    || format!("face {index} ({})", join_corners(poly)),
                );
                continue;
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
        let mesh = Mesh {
            positions,
            polygons,
            triangles,
            triangle_polygon,
            tetrahedra: Vec::new(),
            attributes: Attributes::None,
        };
        mesh.validate()?;
        Ok((mesh, warnings))
    }

    /// The same mesh (faces, attributes) at other positions: what every output writes.
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
            attributes: self.attributes.clone(),
        }
    }

    /// Replaces the faces by `triangles`, each its own polygon (the boundary of a tetrahedral
    /// mesh, or any triangle soup); attributes tied to the old faces are dropped.
    pub fn set_triangles(&mut self, triangles: Vec<[u32; 3]>) {
        self.polygons = Polygons::from_triangles(&triangles);
        self.triangle_polygon = (0..triangles.len() as u32).collect();
        self.triangles = triangles;
        self.attributes = Attributes::None;
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

/// Triangulates one polygon by ear clipping in its best-fit plane, appending its triangles
/// (same winding as the polygon) to `out`; `scratch` is reused between calls.
///
/// Repeated neighbouring corners (`a b b c`, also across the end) are merged first. Returns
/// `false`, and appends nothing, when fewer than 3 corners remain or a vertex still repeats.
///
/// The plane's normal is Newell's, n = Σ_i (p_i − p_{i+1}) × … (the area vector of the polygon,
/// Newell 1972), which follows the polygon's winding; corners are projected onto the plane and
/// an *ear* — a convex corner whose triangle with its two neighbours contains no other
/// remaining corner — is cut off until a triangle is left (Meisters 1975). The search starts at
/// the second remaining corner, so a convex polygon (v₀, …, v_k) gives exactly the fan
/// (v₀, v_i, v_{i+1}). No triangle of a simple polygon folds over; for a self-intersecting or
/// degenerate polygon (no ear exists) the corner with the largest convex turn, or else the
/// next corner, is cut, so the result always has k − 2 triangles.
pub fn triangulate_polygon(
    positions: &[DVec3],
    polygon: &[u32],
    scratch: &mut Vec<u32>,
    out: &mut Vec<[u32; 3]>,
) -> bool {
    scratch.clear();
    for &v in polygon {
        if scratch.last() != Some(&v) {
            scratch.push(v);
        }
    }
    while scratch.len() > 1 && scratch.first() == scratch.last() {
        scratch.pop();
    }
    if scratch.len() < 3 || has_repeat(scratch) {
        return false;
    }
    if scratch.len() == 3 {
        out.push([scratch[0], scratch[1], scratch[2]]);
        return true;
    }
    // Best-fit plane: Newell's normal and a basis (u, w) with u × w = n.
    let p = |v: u32| positions[v as usize];
    let mut normal = DVec3::ZERO;
    for (i, &a) in scratch.iter().enumerate() {
        let b = scratch[(i + 1) % scratch.len()];
        normal += p(a).cross(p(b));
    }
    let normal = normal.normalize_or_zero();
    if normal == DVec3::ZERO {
        // No plane at all (every corner on one line, or the area cancels out): a fan.
        for i in 1..scratch.len() - 1 {
            out.push([scratch[0], scratch[i], scratch[i + 1]]);
        }
        return true;
    }
    let u = normal.any_orthonormal_vector();
    let w = normal.cross(u);
    let origin = p(scratch[0]);
    let flat = |v: u32| {
        let d = p(v) - origin;
        glam::DVec2::new(d.dot(u), d.dot(w))
    };
    let mut ring: Vec<(u32, glam::DVec2)> = scratch.iter().map(|&v| (v, flat(v))).collect();
    // Relative tolerance for "convex" and "inside": the polygon's scale squared.
    let extent = ring.iter().map(|(_, q)| q.length_squared()).fold(0.0, f64::max);
    let eps = 1e-14 * extent.max(f64::MIN_POSITIVE);
    let turn = |a: glam::DVec2, b: glam::DVec2, c: glam::DVec2| (b - a).perp_dot(c - b);
    while ring.len() > 3 {
        let k = ring.len();
        let corner = |i: usize| (ring[(i + k - 1) % k].1, ring[i].1, ring[(i + 1) % k].1);
        let is_ear = |i: usize| {
            let (a, b, c) = corner(i);
            if turn(a, b, c) <= eps {
                return false;
            }
            (0..k).filter(|&j| j != i && j != (i + k - 1) % k && j != (i + 1) % k).all(|j| {
                let q = ring[j].1;
                // Strictly outside one edge (points on an edge of the ear block it only when
                // they are inside the other two).
                turn(a, b, q) < -eps || turn(b, c, q) < -eps || turn(c, a, q) < -eps
            })
        };
        let ear = (1..=k).map(|i| i % k).find(|&i| is_ear(i)).unwrap_or_else(|| {
            (0..k)
                .map(|i| {
                    let (a, b, c) = corner(i);
                    (i, turn(a, b, c))
                })
                .fold((1 % k, f64::NEG_INFINITY), |best, (i, t)| if t > best.1 { (i, t) } else { best })
                .0
        });
        out.push([ring[(ear + k - 1) % k].0, ring[ear].0, ring[(ear + 1) % k].0]);
        ring.remove(ear);
    }
    out.push([ring[0].0, ring[1].0, ring[2].0]);
    true
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
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn quad_positions() -> Vec<DVec3> {
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y]
    }

    fn polys(list: &[&[u32]]) -> Polygons {
        list.iter().copied().collect()
    }

    fn area_vector(positions: &[DVec3], t: [u32; 3]) -> DVec3 {
        let p = t.map(|v| positions[v as usize]);
        0.5 * (p[1] - p[0]).cross(p[2] - p[0])
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
    fn concave_quad_is_cut_along_its_inner_diagonal() {
        // An arrowhead: corner 3 points inwards, so the fan from 0 (diagonal 0–2) would fold over.
        let positions =
            vec![DVec3::ZERO, DVec3::new(2.0, 1.0, 0.0), DVec3::new(0.0, 2.0, 0.0), DVec3::new(0.5, 1.0, 0.0)];
        let (mesh, _) = Mesh::from_polygons(positions.clone(), polys(&[&[0, 1, 2, 3]])).unwrap();
        let total: DVec3 = mesh.triangles.iter().map(|&t| area_vector(&positions, t)).sum();
        assert!((total.z - 1.5).abs() < 1e-12, "area {total}");
        for &t in &mesh.triangles {
            assert!(area_vector(&positions, t).z > 0.0, "triangle {t:?} folds over");
        }
    }

    #[test]
    fn l_shaped_hexagon_in_a_tilted_plane_has_no_folded_triangle() {
        let flat = [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (1.0, 2.0), (0.0, 2.0)];
        let turn = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let positions: Vec<DVec3> = flat.iter().map(|&(x, y)| turn * DVec3::new(x, y, 0.0)).collect();
        // Start the polygon at the reflex corner's neighbour so that a fan would fold.
        let (mesh, _) = Mesh::from_polygons(positions.clone(), polys(&[&[4, 5, 0, 1, 2, 3]])).unwrap();
        assert_eq!(mesh.triangles.len(), 4);
        let normal = turn * DVec3::Z;
        let mut area = 0.0;
        for &t in &mesh.triangles {
            let a = area_vector(&positions, t);
            assert!(a.dot(normal) > 1e-9, "triangle {t:?} folds over or is degenerate");
            area += a.dot(normal);
        }
        assert!((area - 3.0).abs() < 1e-12, "the triangles tile the polygon: area {area}");
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

    #[test]
    fn random_simple_polygons_triangulate_without_folds() {
        // Star-shaped polygons with random radii are simple; every ear-clipped triangle must
        // turn the same way as the polygon and the areas must add up.
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for k in 4..40 {
            let positions: Vec<DVec3> = (0..k)
                .map(|i| {
                    let a = std::f64::consts::TAU * i as f64 / k as f64;
                    let r = 0.2 + next();
                    DVec3::new(r * a.cos(), r * a.sin(), 0.0)
                })
                .collect();
            let area: f64 =
                (0..k).map(|i| positions[i].truncate().perp_dot(positions[(i + 1) % k].truncate())).sum::<f64>() / 2.0;
            let poly: Vec<u32> = (0..k as u32).collect();
            let mut out = Vec::new();
            assert!(triangulate_polygon(&positions, &poly, &mut Vec::new(), &mut out));
            assert_eq!(out.len(), k - 2);
            let sum: f64 = out.iter().map(|&t| area_vector(&positions, t).z).sum();
            assert!(out.iter().all(|&t| area_vector(&positions, t).z > 0.0), "k = {k}: a triangle folds");
            assert!((sum - area).abs() < 1e-12 * area.abs().max(1.0), "k = {k}: {sum} vs {area}");
        }
    }
}
