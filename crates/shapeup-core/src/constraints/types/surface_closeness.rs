//! Surface closeness: each vertex kept on the input surface's tangent plane at its rest
//! position, free to slide along the surface; a boundary vertex slides along the boundary's
//! tangent line, a boundary corner stays.
//!
//! Term: ω ‖q_i − p‖² with p = q_i − Σ_k ((q_i − x⁰_i)·n_k) n_k, the nearest point of the affine
//! set through the rest position x⁰_i orthogonal to the unit vectors n_k:
//! - interior vertex: one n, the normalized sum of the unit normals of the triangles around i
//!   at rest (the set is the tangent plane);
//! - boundary vertex with two boundary edges turning by at most [`CORNER_ANGLE`]: n and t × n,
//!   t the boundary's tangent (the bisector of the two edge directions), so the set is the
//!   tangent line of the boundary curve and the boundary cannot slide off the design's edge;
//! - a boundary corner (a sharper turn, or not two boundary edges): all three axes (the set is
//!   x⁰_i itself, as a `position`).
//!
//! ω = 1, as for `position` (closeness).
//!
//! Why beside `position`: a design's quad mesh whose edges do not follow a conjugate net cannot
//! be made planar without moving its vertices by more than the planarity defect, and point
//! closeness charges the tangential part of that motion, which leaves the surface where it
//! was. Charging only the normal part lets the net slide towards planar faces while the
//! surface stays (ShapeUp, Bouaziz et al. 2012, §6, planar and circular meshes kept close to
//! the reference surface; the tangent-plane linearization of the distance to the reference
//! surface is that of Liu et al. 2006, "Geometric modeling with conical meshes and developable
//! surfaces", §3). The plane is the linearization at x⁰_i: for a slide s along a surface of
//! curvature κ it misses the surface by about κ s²/2 (a slide of one mean edge length h on a
//! surface meshed at h κ ≈ 0.05 misses it by 2.5 % of h). Give a weak `position` group beside it
//! so the net cannot slide without bound.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::{RestGeometry, vertex_normals};
use crate::topology::boundary_edges;
use glam::DVec3;

/// Name in scene files.
const KIND: &str = "surface_closeness";

/// Boundary turn (radians) above which a boundary vertex counts as a corner and stays: 30°.
pub const CORNER_ANGLE: f64 = std::f64::consts::FRAC_PI_6;

/// One vertex kept on an affine set through its rest position: a plane, a line or the point.
#[derive(Debug, Clone)]
pub struct SurfaceCloseness {
    vertex: [u32; 1],
    origin: DVec3,
    /// Orthonormal directions the vertex may not move along (1: plane, 2: line, 3: point).
    normals: Vec<DVec3>,
}

impl SurfaceCloseness {
    /// Keeps vertex `i` on the plane through `origin` with normal `normal` (normalized here);
    /// `None` when the normal is zero or anything is not finite.
    pub fn new(i: u32, origin: DVec3, normal: DVec3) -> Option<Self> {
        let normal = normal.try_normalize()?;
        origin.is_finite().then(|| SurfaceCloseness { vertex: [i], origin, normals: vec![normal] })
    }

    /// Keeps vertex `i` on the line through `origin` along `tangent`; `normal` (the surface's)
    /// picks the first orthogonal axis. `None` when the tangent is zero or not finite; a normal
    /// parallel to the tangent is replaced by any orthogonal direction.
    pub fn on_line(i: u32, origin: DVec3, tangent: DVec3, normal: DVec3) -> Option<Self> {
        let t = tangent.try_normalize()?;
        let n = (normal - normal.dot(t) * t).try_normalize().unwrap_or_else(|| t.any_orthonormal_vector());
        origin.is_finite().then(|| SurfaceCloseness { vertex: [i], origin, normals: vec![n, t.cross(n)] })
    }

    /// Keeps vertex `i` at `origin`; `None` when it is not finite.
    pub fn at_point(i: u32, origin: DVec3) -> Option<Self> {
        origin.is_finite().then(|| SurfaceCloseness {
            vertex: [i],
            origin,
            normals: vec![DVec3::X, DVec3::Y, DVec3::Z],
        })
    }

    /// The dimension of the set: 2 (plane), 1 (line) or 0 (point).
    pub fn dimension(&self) -> usize {
        3 - self.normals.len()
    }
}

impl Constraint for SurfaceCloseness {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertex
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        sink.push(0, self.vertex[0], 1.0);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let x = q[self.vertex[0] as usize];
        let d = x - self.origin;
        out[0] = self.normals.iter().fold(x, |p, &n| p - d.dot(n) * n);
    }
    /// √Σ_k ((p − x⁰)·n_k)²: the distance of p from the set.
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let d = p[0] - self.origin;
        self.normals.iter().map(|&n| d.dot(n).powi(2)).sum::<f64>().sqrt()
    }
}

/// Builds a [`SurfaceCloseness`] on every selected vertex of a triangle (or polygon) with a
/// defined normal; no options.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceClosenessType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "surface closeness: vertices stay on the input surface (its rest tangent planes) and may slide along it",
    options: &[],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    // Tied to the rest surface, as `position` is to the rest positions.
    rigidly_invariant: false,
};

impl ConstraintType for SurfaceClosenessType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        let x = &rest.positions;
        let normals = vertex_normals(x, &rest.triangles);
        let along_boundary = boundary_neighbours(rest);
        per_selected_vertex(ctx, KIND, "vertices of a triangle or polygon", |i| {
            let v = i as u32;
            if !rest.topology.in_triangle[i] {
                return None;
            }
            if !rest.topology.boundary[i] {
                return SurfaceCloseness::new(v, x[i], normals[i]);
            }
            let line = match along_boundary[i].as_slice() {
                &[a, b] => {
                    let into = (x[i] - x[a as usize]).normalize_or_zero();
                    let out = (x[b as usize] - x[i]).normalize_or_zero();
                    (into.dot(out) >= CORNER_ANGLE.cos())
                        .then(|| SurfaceCloseness::on_line(v, x[i], into + out, normals[i]))
                        .flatten()
                }
                _ => None,
            };
            line.or_else(|| SurfaceCloseness::at_point(v, x[i]))
        })
    }
}

/// For each vertex, the other ends of its boundary edges, in edge order.
fn boundary_neighbours(rest: &RestGeometry) -> Vec<Vec<u32>> {
    let topology = &rest.topology;
    let mut out = vec![Vec::new(); rest.num_vertices()];
    for [a, b] in boundary_edges(&topology.edges, &topology.edge_triangle_count) {
        out[a as usize].push(b);
        out[b as usize].push(a);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::kit::test_util::Rng;

    /// p(q) of a one-row constraint.
    fn proj(c: &dyn Constraint, q: &[DVec3]) -> DVec3 {
        let mut out = [DVec3::ZERO];
        c.project(q, &mut out);
        out[0]
    }

    #[test]
    fn projection_is_the_nearest_point_of_the_tangent_plane() {
        let mut rng = Rng(7);
        for _ in 0..50 {
            let origin = rng.vec3();
            let c = SurfaceCloseness::new(0, origin, rng.vec3()).unwrap();
            let q = [rng.vec3() * 3.0];
            let p = [proj(&c, &q)];
            assert!(c.set_residual(&p) < 1e-14, "on the plane");
            let d = (p[0] - q[0]).length();
            // Sampled points of the plane: p plus tangent offsets; none is closer.
            let n = c.normals[0];
            for _ in 0..100 {
                let t = rng.vec3();
                let s = p[0] + (t - t.dot(n) * n);
                assert!(c.set_residual(&[s]) < 1e-12);
                assert!((s - q[0]).length() >= d - 1e-12);
            }
            // A point already on the plane is its own projection (sliding is free).
            let on = [p[0] + n.any_orthonormal_vector() * 2.0];
            assert!((proj(&c, &on) - on[0]).length() < 1e-12);
        }
    }

    #[test]
    fn line_and_point_projections_are_nearest_points() {
        let mut rng = Rng(11);
        for _ in 0..50 {
            let (origin, tangent) = (rng.vec3(), rng.vec3());
            let line = SurfaceCloseness::on_line(0, origin, tangent, rng.vec3()).unwrap();
            assert_eq!(line.dimension(), 1);
            let q = [rng.vec3() * 3.0];
            let p = [proj(&line, &q)];
            assert!(line.set_residual(&p) < 1e-12, "on the line");
            let d = (p[0] - q[0]).length();
            for _ in 0..100 {
                let s = origin + tangent * rng.uniform() * 5.0;
                assert!(line.set_residual(&[s]) < 1e-12);
                assert!((s - q[0]).length() >= d - 1e-12);
            }
            let point = SurfaceCloseness::at_point(0, origin).unwrap();
            assert_eq!(point.dimension(), 0);
            assert!((proj(&point, &q) - origin).length() < 1e-15);
        }
    }

    #[test]
    fn a_grid_gets_planes_inside_lines_on_its_edges_and_points_at_its_corners() {
        // A 3×3 grid of unit squares in z = 0, triangulated.
        let n = 4u32;
        let positions = (0..n * n).map(|k| DVec3::new((k % n) as f64, (k / n) as f64, 0.0)).collect();
        let mut triangles = Vec::new();
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                let a = j * n + i;
                triangles.push([a, a + 1, a + n + 1]);
                triangles.push([a, a + n + 1, a + n]);
            }
        }
        let rest = RestGeometry::new(positions, triangles, vec![]);
        let ctx = BuildContext {
            rest: &rest,
            selection: &crate::constraints::Selection::All,
            frame: &crate::geometry::WorkingFrame::IDENTITY,
        };
        let built = SurfaceClosenessType.build(&ctx, &mut Params::default()).unwrap();
        let q: Vec<DVec3> = rest.positions.iter().map(|p| *p + DVec3::new(0.3, 0.2, 0.1)).collect();
        for c in &built {
            let v = c.vertices()[0];
            let (i, j) = (v % n, v / n);
            let p = proj(c.as_ref(), &q);
            let moved = p - rest.positions[v as usize];
            let corner = (i == 0 || i == n - 1) && (j == 0 || j == n - 1);
            let edge = !corner && (i == 0 || i == n - 1 || j == 0 || j == n - 1);
            if corner {
                assert!(moved.length() < 1e-12, "corner {v} stays");
            } else if edge {
                // Slides along the boundary only.
                let along = if i == 0 || i == n - 1 { DVec3::new(0.0, 0.2, 0.0) } else { DVec3::new(0.3, 0.0, 0.0) };
                assert!((moved - along).length() < 1e-12, "edge vertex {v} moved {moved}");
            } else {
                assert!((moved - DVec3::new(0.3, 0.2, 0.0)).length() < 1e-12, "interior {v} slides in the plane");
            }
        }
    }

    #[test]
    fn a_zero_normal_builds_nothing() {
        assert!(SurfaceCloseness::new(0, DVec3::ZERO, DVec3::ZERO).is_none());
        assert!(SurfaceCloseness::new(0, DVec3::NAN, DVec3::Z).is_none());
    }
}
