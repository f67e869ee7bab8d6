//! Rest geometry: areas, volumes, cotan weights, normals, lumped masses and the working frame.
//!
//! Each routine is one small function whose doc states its formula (see the math reference,
//! `docs/math.md`, "Notation"). [`RestGeometry`] bundles what the constraints need, computed
//! once from the rest positions.

use crate::topology::Topology;
use glam::DVec3;

/// Smallest vertex area: A_i is floored here so that 1/A_i stays finite.
pub const MIN_VERTEX_AREA: f64 = 1e-12;

/// Area of triangle (a, b, c): A = ½‖(b − a) × (c − a)‖.
pub fn triangle_area(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    0.5 * (b - a).cross(c - a).length()
}

/// Area of every triangle, A_t.
pub fn triangle_areas(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<f64> {
    triangles
        .iter()
        .map(|t| triangle_area(positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]))
        .collect()
}

/// Barycentric vertex areas: A_i = max(Σ_{t ∋ i} A_t / 3, 1e-12).
pub fn vertex_areas(n: usize, triangles: &[[u32; 3]], triangle_areas: &[f64]) -> Vec<f64> {
    let mut areas = vec![0.0; n];
    for (t, &a) in triangles.iter().zip(triangle_areas) {
        for &v in t {
            areas[v as usize] += a / 3.0;
        }
    }
    areas.iter_mut().for_each(|a| *a = a.max(MIN_VERTEX_AREA));
    areas
}

/// Cotangent of the angle at `c` opposite edge (a, b): cot = (a−c)·(b−c) / ‖(a−c)×(b−c)‖.
/// `None` for a degenerate (zero-area) corner.
pub fn cotangent(a: DVec3, b: DVec3, c: DVec3) -> Option<f64> {
    let (u, v) = (a - c, b - c);
    let sin = u.cross(v).length();
    (sin > 1e-300).then(|| u.dot(v) / sin)
}

/// Cotan weight of every edge of `topology.edges`: c_ij = ½ Σ cot θ over the angles θ opposite
/// the edge in each of its triangles (one term on a boundary edge, all of them on an edge of
/// three or more). A zero-area triangle ([`is_degenerate_triangle`]) adds no term.
pub fn cotan_weights(positions: &[DVec3], triangles: &[[u32; 3]], topology: &Topology) -> Vec<f64> {
    let mut weights = vec![0.0; topology.edges.len()];
    for (t, edges) in triangles.iter().zip(&topology.triangle_edges) {
        let p = t.map(|v| positions[v as usize]);
        if is_degenerate_triangle(p[0], p[1], p[2]) {
            continue;
        }
        for k in 0..3 {
            // Edge k joins corners k and k + 1; the angle opposite it is at corner k + 2.
            if let Some(cot) = cotangent(p[k], p[(k + 1) % 3], p[(k + 2) % 3]) {
                weights[edges[k] as usize] += 0.5 * cot;
            }
        }
    }
    weights
}

/// Smallest rest triangle area that counts (working frame): smaller triangles add no cotan
/// terms and no strain constraint (math reference, "Edge cases").
pub const MIN_TRIANGLE_AREA: f64 = 1e-12;

/// Smallest rest triangle area that counts relative to its longest edge ℓ, A/ℓ² (the sine of
/// its smallest angle is about 2A/ℓ²): below it the triangle is flat to round-off at any scale.
pub const MIN_RELATIVE_AREA: f64 = 1e-12;

/// Whether a triangle has zero area for the solver: A ≤ 1e-12, or A ≤ 1e-12 ℓ² with ℓ its
/// longest edge (flat to round-off: its rest frame, cotangents and inverse shape matrix would be
/// round-off too). In the working frame (radius 0.5, so ℓ ≤ 1) the second bound adds nothing; it
/// keeps meshes that are not normalized, 1e6 across, from slivers with infinite coefficients.
/// A NaN corner counts as degenerate.
pub fn is_degenerate_triangle(a: DVec3, b: DVec3, c: DVec3) -> bool {
    let area = triangle_area(a, b, c);
    let longest2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    !(area > MIN_TRIANGLE_AREA && area > MIN_RELATIVE_AREA * longest2)
}

/// Signed volume of tetrahedron (a, b, c, d): V = (b − a) · ((c − a) × (d − a)) / 6
/// (positive when (b−a, c−a, d−a) is right-handed).
pub fn tet_volume(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> f64 {
    (b - a).dot((c - a).cross(d - a)) / 6.0
}

/// Unit normal of triangle (a, b, c): (b − a) × (c − a) normalized; zero if degenerate.
pub fn triangle_normal(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

/// Per-vertex normals n̄_i: the normalized sum of the unit normals of the triangles around i
/// (zero for a vertex in no triangle).
pub fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut normals = vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let n = triangle_normal(positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
        for &v in t {
            normals[v as usize] += n;
        }
    }
    normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    normals
}

/// Angle-weighted normal contribution of every polygon corner: θ_c n_f, with n_f the unit
/// Newell normal of the corner's polygon (n_f ∝ Σ_i p_i × p_{i+1}) and θ_c the angle between
/// the corner's two edges (Thürmer & Wüthrich 1998, "Computing vertex normals from polygonal
/// facets"). Summing these over the corners that share a normal and normalizing gives that
/// normal; zero for a degenerate corner or polygon.
pub fn corner_normal_weights(positions: &[DVec3], polygons: &crate::mesh::Polygons) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(polygons.num_corners());
    for poly in polygons.iter() {
        let k = poly.len();
        let p = |i: usize| positions[poly[i % k] as usize];
        let mut newell = DVec3::ZERO;
        for i in 0..k {
            newell += p(i).cross(p(i + 1));
        }
        let n = newell.normalize_or_zero();
        for i in 0..k {
            let (a, b) = (p(i + k - 1) - p(i), p(i + 1) - p(i));
            let angle = a.cross(b).length().atan2(a.dot(b));
            out.push(if angle.is_finite() { angle * n } else { DVec3::ZERO });
        }
    }
    out
}

/// Normals as a file indexes them: normal `j` is the normalized sum of
/// [`corner_normal_weights`] over the corners c with `corner_index[c] == j` (corners with
/// [`crate::io::attributes::NO_INDEX`] count for none). `None` for a normal no corner uses, or
/// whose sum vanishes (the caller keeps the file's value). Indexing per vertex
/// (`corner_index = polygons.indices()`) gives smooth vertex normals; a file's own indexing
/// keeps its hard edges and smoothing groups.
pub fn indexed_normals(
    positions: &[DVec3],
    polygons: &crate::mesh::Polygons,
    corner_index: &[u32],
    count: usize,
) -> Vec<Option<DVec3>> {
    let mut sums = vec![DVec3::ZERO; count];
    for (w, &j) in corner_normal_weights(positions, polygons).iter().zip(corner_index) {
        if let Some(s) = sums.get_mut(j as usize) {
            *s += *w;
        }
    }
    sums.into_iter().map(|s| s.try_normalize()).collect()
}

/// Mean length of the mesh's edges: of its polygon faces as read (a quad's diagonal, which
/// triangulation adds, is no edge of the mesh), else of its triangles, else of its tetrahedra;
/// 0 for none.
pub fn mean_edge_length(rest: &RestGeometry) -> f64 {
    let mut edges = crate::topology::polygon_edges(rest.faces.iter());
    if edges.is_empty() {
        edges = if rest.topology.edges.is_empty() {
            crate::topology::tetrahedron_edges(&rest.tetrahedra)
        } else {
            rest.topology.edges.clone()
        };
    }
    let p = &rest.positions;
    let total: f64 = edges.iter().map(|e| (p[e[1] as usize] - p[e[0] as usize]).length()).sum();
    if edges.is_empty() { 0.0 } else { total / edges.len() as f64 }
}

/// The diagonal of the axis-aligned bounding box of the rest positions (0 for none).
pub fn bounding_box_diagonal(rest: &RestGeometry) -> f64 {
    points_diagonal(&rest.positions)
}

/// The diagonal of the axis-aligned bounding box of `points` (0 for none).
pub fn points_diagonal(points: &[DVec3]) -> f64 {
    let Some(&first) = points.first() else { return 0.0 };
    let (lo, hi) = points.iter().fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length()
}

/// Lumped masses of a surface: m_i = max(ρ Σ_{t ∋ i} A_t / 3, 1e-9).
pub fn lumped_masses_surface(n: usize, triangles: &[[u32; 3]], triangle_areas: &[f64], density: f64) -> Vec<f64> {
    let mut m = vec![0.0; n];
    for (t, &a) in triangles.iter().zip(triangle_areas) {
        for &v in t {
            m[v as usize] += density * a / 3.0;
        }
    }
    m.iter_mut().for_each(|x| *x = x.max(1e-9));
    m
}

/// Lumped masses of a volume: m_i = max(ρ Σ_{T ∋ i} |V_T| / 4, 1e-9).
pub fn lumped_masses_volume(positions: &[DVec3], tetrahedra: &[[u32; 4]], density: f64) -> Vec<f64> {
    let mut m = vec![0.0; positions.len()];
    for t in tetrahedra {
        let p = t.map(|v| positions[v as usize]);
        let v = tet_volume(p[0], p[1], p[2], p[3]).abs();
        for &i in t {
            m[i as usize] += density * v / 4.0;
        }
    }
    m.iter_mut().for_each(|x| *x = x.max(1e-9));
    m
}

/// The normalized frame the solver works in: x_work = (x_input − center) · scale.
///
/// [`WorkingFrame::fit`] puts the centroid of all vertices (referenced or not) at the origin and
/// the farthest vertex at distance 0.5, so weights, lengths and areas mean the same for a mesh
/// in millimetres or metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorkingFrame {
    /// Translation: the input-frame point that maps to the origin.
    pub center: DVec3,
    /// Scale factor from input units to working units.
    pub scale: f64,
    /// True for a scene with a material, whose working frame is metres: loads are then
    /// physical (forces in newtons, pressures in pascals) and not scaled with lengths
    /// ([`WorkingFrame::force_to_working`]).
    pub physical: bool,
}

impl Default for WorkingFrame {
    fn default() -> Self {
        WorkingFrame::IDENTITY
    }
}

impl WorkingFrame {
    /// The identity frame (`normalize = false`).
    pub const IDENTITY: WorkingFrame = WorkingFrame { center: DVec3::ZERO, scale: 1.0, physical: false };

    /// The frame of a scene with a material: metres, `metres` per input unit, no translation.
    pub fn metres(metres: f64) -> Self {
        WorkingFrame { center: DVec3::ZERO, scale: metres, physical: true }
    }

    /// center = (1/n) Σ x_i; scale = 0.5 / max_i ‖x_i − center‖ (identity scale if all
    /// vertices coincide).
    pub fn fit(positions: &[DVec3]) -> Self {
        if positions.is_empty() {
            return Self::IDENTITY;
        }
        let center = positions.iter().copied().sum::<DVec3>() / positions.len() as f64;
        let radius = positions.iter().map(|p| (*p - center).length()).fold(0.0, f64::max);
        let scale = if radius > 0.0 { 0.5 / radius } else { 1.0 };
        WorkingFrame { center, scale, physical: false }
    }

    /// A point from the input frame to the working frame.
    pub fn to_working(&self, p: DVec3) -> DVec3 {
        (p - self.center) * self.scale
    }

    /// A point from the working frame back to the input frame.
    pub fn to_input(&self, p: DVec3) -> DVec3 {
        p / self.scale + self.center
    }

    /// A displacement or direction (no translation) from the input frame to the working frame.
    pub fn vector_to_working(&self, v: DVec3) -> DVec3 {
        v * self.scale
    }

    /// A force from the scene to the working frame: in newtons with a material (`physical`,
    /// unchanged); otherwise scaled like a length ([`WorkingFrame::vector_to_working`]), so
    /// that a scene means the same in millimetres or metres (the `force` type's docs say why).
    pub fn force_to_working(&self, f: DVec3) -> DVec3 {
        if self.physical { f } else { self.vector_to_working(f) }
    }

    /// A pressure (force per area) from the scene to the working frame: in pascals with a
    /// material (unchanged); otherwise forces scale like lengths and areas like squared
    /// lengths, so p / scale.
    pub fn pressure_to_working(&self, p: f64) -> f64 {
        if self.physical { p } else { p / self.scale }
    }
}

/// Everything about the rest shape that constraints need, computed once.
#[derive(Debug, Clone, Default)]
pub struct RestGeometry {
    /// Rest positions x⁰ (working frame).
    pub positions: Vec<DVec3>,
    /// Triangles of the mesh.
    pub triangles: Vec<[u32; 3]>,
    /// Tetrahedra of the mesh (empty for a surface).
    pub tetrahedra: Vec<[u32; 4]>,
    /// The input's polygon faces as read (n-gons, not their triangles): what face constraints
    /// (plane, circle, rectangle…) act on. The triangles themselves when built with
    /// [`RestGeometry::new`].
    pub faces: crate::mesh::Polygons,
    /// Connectivity.
    pub topology: Topology,
    /// Rest triangle areas A_t.
    pub triangle_areas: Vec<f64>,
    /// Rest vertex areas A_i (barycentric, floored at 1e-12).
    pub vertex_areas: Vec<f64>,
    /// Rest cotan weight c_ij of each edge of `topology.edges`.
    pub cotan_weights: Vec<f64>,
    /// Connected piece of each vertex (joined by triangles or tetrahedra; 0-based, in order of
    /// each piece's smallest vertex), and the number of pieces ([`crate::topology::connected_pieces`]).
    pub pieces: (Vec<u32>, usize),
}

impl RestGeometry {
    /// Computes topology, areas and cotan weights of rest positions (already in the working frame).
    pub fn new(positions: Vec<DVec3>, triangles: Vec<[u32; 3]>, tetrahedra: Vec<[u32; 4]>) -> Self {
        let topology = Topology::new(positions.len(), &triangles);
        let triangle_areas = triangle_areas(&positions, &triangles);
        let vertex_areas = vertex_areas(positions.len(), &triangles, &triangle_areas);
        let cotan_weights = cotan_weights(&positions, &triangles, &topology);
        let faces = crate::mesh::Polygons::from_triangles(&triangles);
        let links = triangles.iter().map(|t| &t[..]).chain(tetrahedra.iter().map(|t| &t[..]));
        let pieces = crate::topology::connected_pieces(positions.len(), links);
        RestGeometry {
            positions,
            triangles,
            tetrahedra,
            faces,
            topology,
            triangle_areas,
            vertex_areas,
            cotan_weights,
            pieces,
        }
    }

    /// The rest geometry of `mesh` at `positions` (its vertices in the working frame), with
    /// the mesh's polygon faces.
    pub fn of_mesh(positions: Vec<DVec3>, mesh: &crate::mesh::Mesh) -> Self {
        let mut rest = RestGeometry::new(positions, mesh.triangles.clone(), mesh.tetrahedra.clone());
        rest.faces = mesh.polygons.clone();
        rest
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// The discrete Laplacian stencil of vertex i: pairs (j, c_ij / A_i) over its one-ring, so
    /// that H(q) = Σ_j (c_ij / A_i)(q_i − q_j).
    pub fn laplacian_stencil(&self, i: usize) -> Vec<(u32, f64)> {
        let ai = self.vertex_areas[i];
        self.topology.one_rings[i]
            .iter()
            .filter_map(|&j| self.topology.edge_index(i as u32, j).map(|e| (j, self.cotan_weights[e] / ai)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn right_triangle_area_and_cotangents() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!((triangle_area(a, b, c) - 0.5).abs() < 1e-15);
        // angle at a (opposite edge bc) is 90°: cot = 0; angles at b and c are 45°: cot = 1.
        assert!(cotangent(b, c, a).unwrap().abs() < 1e-15);
        assert!((cotangent(a, c, b).unwrap() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn cotan_laplacian_of_flat_fan_vanishes_at_centre() {
        // Linear precision: on a flat mesh Σ_j c_ij (x_i − x_j) = 0 at an interior vertex.
        let mut p = vec![DVec3::new(0.1, -0.05, 0.0)];
        for k in 0..7 {
            let t = k as f64 / 7.0 * std::f64::consts::TAU;
            p.push(DVec3::new(t.cos() * (1.0 + 0.2 * (k % 2) as f64), t.sin(), 0.0));
        }
        let tris: Vec<[u32; 3]> = (0..7).map(|k| [0, 1 + k, 1 + (k + 1) % 7]).collect();
        let rest = RestGeometry::new(p.clone(), tris, vec![]);
        let h: DVec3 = rest.laplacian_stencil(0).iter().map(|&(j, w)| w * (p[0] - p[j as usize])).sum();
        assert!(h.length() < 1e-12, "{h}");
    }

    #[test]
    fn working_frame_maps_farthest_vertex_to_half() {
        let p = vec![DVec3::new(10.0, 0.0, 0.0), DVec3::new(14.0, 0.0, 0.0), DVec3::new(12.0, 1.0, 0.0)];
        let f = WorkingFrame::fit(&p);
        let w: Vec<DVec3> = p.iter().map(|&x| f.to_working(x)).collect();
        let c = w.iter().copied().sum::<DVec3>() / 3.0;
        assert!(c.length() < 1e-12);
        let r = w.iter().map(|x| x.length()).fold(0.0, f64::max);
        assert!((r - 0.5).abs() < 1e-12);
        assert!((f.to_input(w[1]) - p[1]).length() < 1e-12);
    }

    #[test]
    fn tet_volume_sign() {
        let v = tet_volume(DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z);
        assert!((v - 1.0 / 6.0).abs() < 1e-15);
        assert!(tet_volume(DVec3::ZERO, DVec3::Y, DVec3::X, DVec3::Z) < 0.0);
    }
}
