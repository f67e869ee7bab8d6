//! Collider shapes at rest and their one query: the closest surface point of a point, the
//! outward normal there and the signed distance (negative inside).
//!
//! Plane, sphere, capsule and box are closed-form; a mesh is a parry3d `TriMesh` (its own BVH),
//! whose inside/outside test uses angle-weighted pseudo-normals (Bærentzen and Aanæs, "Signed
//! distance computation using the angle weighted pseudonormal", IEEE TVCG 2005): robust at
//! edges and vertices of a closed, consistently oriented mesh. An open mesh is one-sided: its
//! front is where the faces' normals point, and a point behind it counts as inside only
//! within the mesh's `thickness` (deeper, it is free: it came from behind). Its rim (the
//! edges on one face, and their vertices) is rounded: a point whose closest point is on the
//! rim is outside, whichever side of the faces' planes it is on (a cloth hanging over the
//! edge of a roof is beside the roof, not behind it).

use super::boxes::{from_parry, to_parry};
use glam::{DMat3, DQuat, DVec3};
use parry3d_f64::query::{PointQueryWithLocation, Ray, RayCast};
use parry3d_f64::shape::{TriMesh, TriMeshFlags, TrianglePointLocation};

/// What a query finds: the closest point on the surface, the outward unit normal there and
/// the signed distance of the query point (negative inside, +∞ when nothing answers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proximity {
    /// Closest point on the surface.
    pub point: DVec3,
    /// Outward unit normal at `point` (towards the query point when it is outside).
    pub normal: DVec3,
    /// Signed distance: ‖x − point‖ outside, −‖x − point‖ inside.
    pub distance: f64,
}

/// A collider's shape in its rest pose (working frame).
#[derive(Debug, Clone)]
pub enum Shape {
    /// The half-space n·(x − point) ≤ 0 is inside; `normal` is unit.
    Plane {
        /// A point on the plane.
        point: DVec3,
        /// Unit outward normal.
        normal: DVec3,
    },
    /// A ball.
    Sphere {
        /// Centre.
        center: DVec3,
        /// Radius > 0.
        radius: f64,
    },
    /// The points within `radius` of the segment ab.
    Capsule {
        /// One end of the axis.
        a: DVec3,
        /// The other end (≠ a).
        b: DVec3,
        /// Radius > 0.
        radius: f64,
    },
    /// An oriented box: centre, half extents along its own axes, and its orientation.
    Box {
        /// Centre.
        center: DVec3,
        /// Half extents ≥ 0 along the box's axes.
        half: DVec3,
        /// Box axes to world.
        rotation: DQuat,
    },
    /// A triangle mesh.
    Mesh(Box<MeshShape>),
}

/// A triangle-mesh collider: parry3d's `TriMesh` (BVH, pseudo-normals) and whether it is
/// closed.
#[derive(Debug, Clone)]
pub struct MeshShape {
    mesh: TriMesh,
    /// A closed, oriented mesh: inside is inside. Open: one-sided with `thickness`.
    pub closed: bool,
    /// Open meshes: how deep behind the front a point still counts as inside (working units).
    pub thickness: f64,
    /// The triangles of zero area ([`MeshShape::degenerate_triangles`]).
    degenerate: Vec<usize>,
    /// Open meshes, per triangle (a, b, c): whether its edges ab, bc, ca are on one face only
    /// (empty for a closed mesh); and per vertex, whether it is on such an edge.
    rim_edges: Vec<[bool; 3]>,
    rim_vertices: Vec<bool>,
}

/// Why a mesh cannot be a collider.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshShapeError {
    /// No triangles, or parry3d refused the index buffer.
    #[error("{0}")]
    Build(String),
}

impl MeshShape {
    /// A mesh collider of `positions` and `triangles` (working frame).
    ///
    /// # Errors
    /// No triangles, or triangles parry3d refuses.
    pub fn new(
        positions: &[DVec3],
        triangles: &[[u32; 3]],
        closed: bool,
        thickness: f64,
    ) -> Result<Self, MeshShapeError> {
        if triangles.is_empty() {
            return Err(MeshShapeError::Build("the mesh has no triangles".into()));
        }
        let vertices = positions.iter().map(|p| to_parry(*p)).collect();
        let mesh = TriMesh::with_flags(vertices, triangles.to_vec(), TriMeshFlags::ORIENTED)
            .map_err(|e| MeshShapeError::Build(e.to_string()))?;
        // Relative to the triangle's own size only: a collider is not in the working frame's
        // unit size, so an absolute area bound would count small ordinary triangles.
        let corner = |v: u32| positions.get(v as usize).copied().unwrap_or(DVec3::NAN);
        let degenerate = triangles
            .iter()
            .enumerate()
            .filter(|(_, t)| {
                let (a, b, c) = (corner(t[0]), corner(t[1]), corner(t[2]));
                let longest2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
                let (area, bound) =
                    (0.5 * (b - a).cross(c - a).length(), crate::geometry::MIN_RELATIVE_AREA * longest2);
                // A NaN corner counts as degenerate.
                area.is_nan() || bound.is_nan() || area <= bound
            })
            .map(|(i, _)| i)
            .collect::<Vec<_>>();
        // Only zero-area triangles: no face has a normal, there is nothing to be outside of.
        if degenerate.len() == triangles.len() {
            return Err(MeshShapeError::Build(format!(
                "all {} of its triangles have zero area (points or segments): no face to collide with",
                triangles.len()
            )));
        }
        let (rim_edges, rim_vertices) = if closed {
            (Vec::new(), Vec::new())
        } else {
            let (edges, counts, triangle_edges) = crate::topology::indexed_edges(mesh.indices());
            let on_one = |e: u32| counts[e as usize] == 1;
            let rim_edges = triangle_edges.iter().map(|t| t.map(on_one)).collect();
            (rim_edges, crate::topology::boundary_vertices(positions.len(), &edges, &counts))
        };
        Ok(MeshShape { mesh, closed, thickness, degenerate, rim_edges, rim_vertices })
    }

    /// The indices of the triangles of zero area (to round-off: A ≤ 1e-12 ℓ², ℓ the longest
    /// edge; a point or a segment): they have no normal of their own, which a scene warns of.
    pub fn degenerate_triangles(&self) -> &[usize] {
        &self.degenerate
    }

    fn closest(&self, x: DVec3) -> Proximity {
        let (projection, (face, location)) = self.mesh.project_local_point_and_get_location(to_parry(x), false);
        let point = from_parry(projection.point);
        let offset = x - point;
        let length = offset.length();
        let inside = projection.is_inside && !self.on_rim(face, location);
        // The direction from the surface to the point, turned outward; on the surface, the
        // face's normal.
        let normal = if length > 1e-12 {
            if inside { -offset / length } else { offset / length }
        } else {
            let face = self.mesh.triangle(projection.subshape);
            face.normal().map(from_parry).unwrap_or(DVec3::Y)
        };
        let distance = if inside { -length } else { length };
        if !self.closed && inside && length > self.thickness {
            // Deeper behind an open surface than its thickness: not touching it.
            return Proximity { point, normal, distance: f64::INFINITY };
        }
        Proximity { point, normal, distance }
    }

    /// Whether a closest point on `face` at `location` lies on the rim of an open mesh.
    fn on_rim(&self, face: u32, location: TrianglePointLocation) -> bool {
        let Some(rim) = self.rim_edges.get(face as usize) else { return false };
        match location {
            TrianglePointLocation::OnVertex(i) => self
                .mesh
                .indices()
                .get(face as usize)
                .and_then(|t| t.get(i as usize))
                .is_some_and(|&v| self.rim_vertices[v as usize]),
            // parry's edges 0, 1, 2 are AB, BC and AC: ours in the same order.
            TrianglePointLocation::OnEdge(i, _) => rim.get(i as usize).copied().unwrap_or(false),
            TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => false,
        }
    }

    /// The first time t ∈ [0, 1] at which x0 + t (x1 − x0) meets the surface, with the
    /// surface's normal there, if it does.
    fn segment_hit(&self, x0: DVec3, x1: DVec3) -> Option<(f64, DVec3)> {
        let d = x1 - x0;
        let ray = Ray::new(to_parry(x0), to_parry(d));
        self.mesh
            .cast_local_ray_and_get_normal(&ray, 1.0, false)
            .map(|hit| (hit.time_of_impact, from_parry(hit.normal)))
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.mesh.indices().len()
    }

    /// The ridges of the mesh (rest pose): its edges on one face only (an open mesh's rim),
    /// on more than two, or between two faces that meet at a convex dihedral angle over
    /// [`RIDGE_ANGLE_DEG`]; and the vertices at their ends. Only these can cut into a surface
    /// whose vertices are kept out of the mesh: a concave or flat edge lies behind its faces.
    pub fn ridges(&self) -> (Vec<DVec3>, Vec<[DVec3; 2]>) {
        let vertices: Vec<DVec3> = self.mesh.vertices().iter().map(|p| from_parry(*p)).collect();
        let triangles = self.mesh.indices();
        let normal = |t: &[u32; 3]| {
            let [a, b, c] = t.map(|v| vertices[v as usize]);
            (b - a).cross(c - a).try_normalize()
        };
        // Per edge (sorted ends): the faces on it, with the vertex opposite it in each.
        let mut faces: std::collections::HashMap<(u32, u32), Vec<(usize, u32)>> = std::collections::HashMap::new();
        for (f, t) in triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b, o) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                faces.entry((a.min(b), a.max(b))).or_default().push((f, o));
            }
        }
        let cos_ridge = RIDGE_ANGLE_DEG.to_radians().cos();
        let mut keep = vec![false; vertices.len()];
        let mut segments = Vec::new();
        let mut edges: Vec<_> = faces.into_iter().collect();
        edges.sort_unstable_by_key(|(e, _)| *e);
        for ((a, b), on) in edges {
            let ridge = match on[..] {
                [(f, _), (g, o)] => match (normal(&triangles[f]), normal(&triangles[g])) {
                    // Convex: g's far vertex lies behind f's plane.
                    (Some(nf), Some(ng)) => {
                        nf.dot(ng) < cos_ridge && nf.dot(vertices[o as usize] - vertices[a as usize]) < 0.0
                    }
                    _ => false,
                },
                _ => true,
            };
            if ridge {
                keep[a as usize] = true;
                keep[b as usize] = true;
                segments.push([vertices[a as usize], vertices[b as usize]]);
            }
        }
        let points = vertices.iter().zip(&keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
        (points, segments)
    }
}

/// The dihedral angle (between the faces' normals) over which a convex edge of a mesh
/// collider is a ridge: a surface edge of length ℓ whose ends are kept at the thickness t from
/// the faces of a flatter edge passes over it within about ℓ/2 · tan(5°) − t, which is below
/// 0 for t ≥ 0.044 ℓ (the default thickness is 0.25 of the mean edge length).
pub const RIDGE_ANGLE_DEG: f64 = 10.0;

impl Shape {
    /// The closest surface point of `x`, the outward normal and the signed distance (see
    /// [`Proximity`]).
    pub fn closest(&self, x: DVec3) -> Proximity {
        match self {
            Shape::Plane { point, normal } => {
                let distance = normal.dot(x - *point);
                Proximity { point: x - distance * *normal, normal: *normal, distance }
            }
            Shape::Sphere { center, radius } => round(*center, x, *radius),
            Shape::Capsule { a, b, radius } => {
                let ab = *b - *a;
                // An axis whose length squared underflows (scenes refuse one under 1e-150, but
                // the working frame scales it) is a sphere at `a`, not 0/0.
                let length2 = ab.length_squared();
                let t = if length2 > 0.0 { ((x - *a).dot(ab) / length2).clamp(0.0, 1.0) } else { 0.0 };
                round(*a + t * ab, x, *radius)
            }
            Shape::Box { center, half, rotation } => {
                let local = rotation.inverse() * (x - *center);
                let (point, normal, distance) = box_closest(local, *half);
                Proximity { point: *center + *rotation * point, normal: *rotation * normal, distance }
            }
            Shape::Mesh(mesh) => mesh.closest(x),
        }
    }

    /// Where the segment x0 → x1 first enters the shape from outside: the parameter t ∈ [0, 1]
    /// and the outward normal there (continuous collision detection against a thin collider,
    /// which a point can cross within one step). `None` when it does not cross the surface
    /// inward, or starts inside.
    pub fn segment_entry(&self, x0: DVec3, x1: DVec3) -> Option<(f64, DVec3)> {
        match self {
            Shape::Mesh(mesh) => {
                let start = mesh.closest(x0);
                if start.distance < 0.0 {
                    return None;
                }
                let (t, normal) = mesh.segment_hit(x0, x1)?;
                // Enters from the front: the segment runs against the face's normal.
                let normal = if normal.dot(x1 - x0) > 0.0 { -normal } else { normal };
                Some((t, normal))
            }
            _ => {
                // Closed primitives: an exact ray cast (parry3d's) in the shape's own frame.
                // A point that does not move enters nothing (parry's ball answers 0/0 for it).
                if x1 == x0 || self.closest(x0).distance < 0.0 {
                    return None;
                }
                let (origin, direction, turn) = match self {
                    Shape::Box { center, rotation, .. } => {
                        (rotation.inverse() * (x0 - *center), rotation.inverse() * (x1 - x0), *rotation)
                    }
                    _ => (x0, x1 - x0, DQuat::IDENTITY),
                };
                let ray = Ray::new(to_parry(origin), to_parry(direction));
                let hit = match self {
                    Shape::Plane { point, normal } => {
                        let shape = parry3d_f64::shape::HalfSpace::new(to_parry(*normal));
                        let ray = Ray::new(to_parry(origin - *point), to_parry(direction));
                        shape.cast_local_ray_and_get_normal(&ray, 1.0, true)
                    }
                    Shape::Sphere { center, radius } => {
                        let ray = Ray::new(to_parry(origin - *center), to_parry(direction));
                        parry3d_f64::shape::Ball::new(*radius).cast_local_ray_and_get_normal(&ray, 1.0, true)
                    }
                    Shape::Capsule { a, b, radius } => {
                        parry3d_f64::shape::Capsule::new(to_parry(*a), to_parry(*b), *radius)
                            .cast_local_ray_and_get_normal(&ray, 1.0, true)
                    }
                    Shape::Box { half, .. } => {
                        parry3d_f64::shape::Cuboid::new(to_parry(*half)).cast_local_ray_and_get_normal(&ray, 1.0, true)
                    }
                    Shape::Mesh(_) => None,
                }?;
                let normal = turn * from_parry(hit.normal);
                (hit.time_of_impact.is_finite() && normal.is_finite()).then_some((hit.time_of_impact, normal))
            }
        }
    }
}

/// The points within `radius` of `core`: closest point, normal and signed distance of `x`.
fn round(core: DVec3, x: DVec3, radius: f64) -> Proximity {
    let offset = x - core;
    let length = offset.length();
    // At the very centre any direction is closest: take +y.
    let normal = if length > 0.0 { offset / length } else { DVec3::Y };
    Proximity { point: core + radius * normal, normal, distance: length - radius }
}

/// Closest surface point, outward normal and signed distance of `x` to the box |x_k| ≤ h_k
/// (box coordinates).
fn box_closest(x: DVec3, h: DVec3) -> (DVec3, DVec3, f64) {
    let q = x.abs() - h;
    if q.max_element() > 0.0 {
        // Outside: the clamped point.
        let point = x.clamp(-h, h);
        let offset = x - point;
        let length = offset.length();
        return (point, offset / length, length);
    }
    // Inside: out through the nearest face.
    let axis = if q.x >= q.y && q.x >= q.z {
        0
    } else if q.y >= q.z {
        1
    } else {
        2
    };
    let mut normal = DVec3::ZERO;
    normal[axis] = if x[axis] >= 0.0 { 1.0 } else { -1.0 };
    let mut point = x;
    point[axis] = normal[axis] * h[axis];
    (point, normal, q[axis])
}

/// The rotation of `angle_deg` degrees about unit `axis`.
pub(crate) fn rotation(axis: DVec3, angle_deg: f64) -> DQuat {
    DQuat::from_axis_angle(axis, angle_deg.to_radians())
}

/// Whether `rotation` is (numerically) the identity, for messages and tests.
#[allow(dead_code)]
pub(crate) fn is_identity(rotation: DQuat) -> bool {
    (DMat3::from_quat(rotation) - DMat3::IDENTITY).to_cols_array().iter().all(|v| v.abs() < 1e-12)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    fn random_point(seed: &mut u64) -> DVec3 {
        DVec3::new(rng(seed), rng(seed), rng(seed)) * 2.0
    }

    /// Brute-force check of a query against samples of the surface: the point found is on it,
    /// no sample is closer, the sign agrees with `inside`.
    fn check(shape: &Shape, surface: &[DVec3], inside: impl Fn(DVec3) -> bool) {
        let mut seed = 7;
        for _ in 0..300 {
            let x = random_point(&mut seed);
            let p = shape.closest(x);
            let nearest = surface.iter().map(|s| (*s - x).length()).fold(f64::INFINITY, f64::min);
            assert!(p.distance.abs() <= nearest + 1e-9, "{x:?}: |d| {} > nearest sample {nearest}", p.distance);
            assert!(p.distance.abs() >= nearest - 0.05, "{x:?}: |d| {} ≪ nearest sample {nearest}", p.distance);
            assert!(((x - p.point).length() - p.distance.abs()).abs() < 1e-9);
            assert_eq!(p.distance < 0.0, inside(x), "{x:?}: sign");
            assert!((p.normal.length() - 1.0).abs() < 1e-12);
            if p.distance.abs() > 1e-6 {
                assert!((x - p.point).normalize().dot(p.normal) * p.distance.signum() > 1.0 - 1e-9, "normal");
            }
        }
    }

    fn sphere_samples(center: DVec3, r: f64, n: usize) -> Vec<DVec3> {
        let mut out = Vec::new();
        for i in 0..n {
            let theta = std::f64::consts::PI * (i as f64 + 0.5) / n as f64;
            for j in 0..2 * n {
                let phi = std::f64::consts::PI * j as f64 / n as f64;
                out.push(center + r * DVec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
            }
        }
        out
    }

    #[test]
    fn sphere_against_samples() {
        let c = DVec3::new(0.1, -0.2, 0.3);
        check(&Shape::Sphere { center: c, radius: 0.7 }, &sphere_samples(c, 0.7, 80), |x| (x - c).length() < 0.7);
    }

    #[test]
    fn a_point_that_does_not_move_enters_no_primitive() {
        // parry's ball ray cast with a zero direction is 0/0: a vertex the step left where it
        // was got a NaN entry point.
        let x = DVec3::new(0.0, 0.31, 0.0);
        for shape in [
            Shape::Sphere { center: DVec3::ZERO, radius: 0.3 },
            Shape::Capsule { a: DVec3::new(-1.0, 0.0, 0.0), b: DVec3::new(1.0, 0.0, 0.0), radius: 0.3 },
            Shape::Box { center: DVec3::ZERO, half: DVec3::splat(0.3), rotation: DQuat::IDENTITY },
            Shape::Plane { point: DVec3::new(0.0, 0.3, 0.0), normal: DVec3::Y },
        ] {
            assert_eq!(shape.segment_entry(x, x), None, "{shape:?}");
            let (t, n) = shape.segment_entry(x, x - DVec3::Y).expect("a fall through it enters it");
            assert!(t.is_finite() && n.is_finite() && t > 0.0 && t < 0.1, "{shape:?}: {t} {n}");
        }
    }

    #[test]
    fn capsule_against_samples() {
        let (a, b) = (DVec3::new(-0.5, 0.0, 0.0), DVec3::new(0.5, 0.2, 0.0));
        // Samples of the capsule's surface: the cylinder, then the two hemispherical caps.
        let axis = (b - a).normalize();
        let u = axis.cross(DVec3::Z).normalize();
        let w = axis.cross(u);
        let mut surface = Vec::new();
        for k in 0..=100 {
            let c = a + (b - a) * (k as f64 / 100.0);
            for j in 0..200 {
                let phi = std::f64::consts::TAU * j as f64 / 200.0;
                surface.push(c + 0.4 * (phi.cos() * u + phi.sin() * w));
            }
        }
        for s in sphere_samples(a, 0.4, 80) {
            if (s - a).dot(axis) <= 0.0 {
                surface.push(s);
            }
        }
        for s in sphere_samples(b, 0.4, 80) {
            if (s - b).dot(axis) >= 0.0 {
                surface.push(s);
            }
        }
        let shape = Shape::Capsule { a, b, radius: 0.4 };
        let core = |x: DVec3| {
            let t = ((x - a).dot(b - a) / (b - a).length_squared()).clamp(0.0, 1.0);
            (x - (a + t * (b - a))).length()
        };
        check(&shape, &surface, |x| core(x) < 0.4);
    }

    #[test]
    fn box_against_samples() {
        let rotation = rotation(DVec3::new(1.0, 2.0, 0.5).normalize(), 30.0);
        let (center, half) = (DVec3::new(0.2, 0.1, -0.1), DVec3::new(0.6, 0.3, 0.9));
        let mut surface = Vec::new();
        let n = 60;
        for i in 0..=n {
            for j in 0..=n {
                let (u, v) = (2.0 * i as f64 / n as f64 - 1.0, 2.0 * j as f64 / n as f64 - 1.0);
                for s in [-1.0, 1.0] {
                    for local in [DVec3::new(s, u, v), DVec3::new(u, s, v), DVec3::new(u, v, s)] {
                        surface.push(center + rotation * (local * half));
                    }
                }
            }
        }
        let shape = Shape::Box { center, half, rotation };
        check(&shape, &surface, |x| {
            let l = rotation.inverse() * (x - center);
            l.abs().cmplt(half).all()
        });
    }

    /// A cube's 12 triangles, outward, over corners k = (x, y, z) bits (x the lowest).
    const CUBE: [[u32; 3]; 12] = [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];

    #[test]
    fn a_cube_has_12_ridges_a_flat_or_gently_bent_sheet_only_its_rim() {
        let p: Vec<DVec3> =
            (0..8).map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64)).collect();
        let (points, segments) = MeshShape::new(&p, &CUBE, true, 0.0).unwrap().ridges();
        // The 6 face diagonals are flat; the 12 cube edges are convex at 90°.
        assert_eq!((points.len(), segments.len()), (8, 12));
        assert!(segments.iter().all(|[a, b]| ((*a - *b).length() - 1.0).abs() < 1e-12));
        // A 4 × 4 grid of squares bent along x = 2 by `angle` (y = 0 for x ≤ 2, rising after),
        // faces up: below the ridge angle only its 16 rim edges are ridges; above it the fold
        // line's 4 edges too, once convex (bent down), never when concave (bent up).
        let sheet = |angle_deg: f64| {
            let slope = angle_deg.to_radians().tan();
            let p: Vec<DVec3> = (0..25)
                .map(|k| {
                    let (x, z) = ((k / 5) as f64, (k % 5) as f64);
                    DVec3::new(x, slope * (x - 2.0).max(0.0), z)
                })
                .collect();
            let mut t = Vec::new();
            for i in 0..4u32 {
                for j in 0..4u32 {
                    let v = |a: u32, b: u32| a * 5 + b;
                    t.push([v(i, j), v(i, j + 1), v(i + 1, j)]);
                    t.push([v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)]);
                }
            }
            MeshShape::new(&p, &t, false, 0.1).unwrap().ridges().1.len()
        };
        assert_eq!(sheet(0.0), 16);
        assert_eq!(sheet(5.0), 16);
        assert_eq!(sheet(-20.0), 20, "bent down by 20°: a convex fold");
        assert_eq!(sheet(20.0), 16, "bent up by 20°: a concave fold cannot cut anything");
    }

    #[test]
    fn closed_mesh_inside_outside_and_distance() {
        // A closed mesh: the cube's 12 triangles against the exact box.
        let p: Vec<DVec3> = (0..8)
            .map(|i| {
                DVec3::new(
                    if i & 1 == 0 { -0.5 } else { 0.5 },
                    if i & 2 == 0 { -0.5 } else { 0.5 },
                    if i & 4 == 0 { -0.5 } else { 0.5 },
                )
            })
            .collect();
        let mesh = Shape::Mesh(Box::new(MeshShape::new(&p, &CUBE, true, 0.0).expect("a cube")));
        let exact = Shape::Box { center: DVec3::ZERO, half: DVec3::splat(0.5), rotation: DQuat::IDENTITY };
        let mut seed = 3;
        for _ in 0..500 {
            let x = random_point(&mut seed);
            let (a, b) = (mesh.closest(x), exact.closest(x));
            assert!((a.distance - b.distance).abs() < 1e-9, "{x:?}: mesh {} box {}", a.distance, b.distance);
        }
    }

    #[test]
    fn open_mesh_is_one_sided_with_thickness() {
        let p = vec![
            DVec3::new(-1.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, -1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(-1.0, 0.0, 1.0),
        ];
        // Faces turned to +y.
        let t = vec![[0, 2, 1], [0, 3, 2]];
        let mesh = MeshShape::new(&p, &t, false, 0.1).expect("a square");
        let shape = Shape::Mesh(Box::new(mesh));
        let above = shape.closest(DVec3::new(0.2, 0.3, 0.1));
        assert!((above.distance - 0.3).abs() < 1e-12 && above.normal.dot(DVec3::Y) > 0.999);
        let shallow = shape.closest(DVec3::new(0.2, -0.05, 0.1));
        assert!((shallow.distance + 0.05).abs() < 1e-12, "within the thickness behind: inside");
        assert!(shape.closest(DVec3::new(0.2, -0.5, 0.1)).distance.is_infinite(), "deep behind: free");
        // Beyond the rim, just below the plane: beside the square, outside, pointing away from
        // its edge (x = 1) or its corner (1, 0, 1).
        let beside = shape.closest(DVec3::new(1.03, -0.04, 0.1));
        assert!((beside.distance - 0.05).abs() < 1e-12, "{beside:?}");
        assert!((beside.normal - DVec3::new(0.6, -0.8, 0.0)).length() < 1e-12, "{beside:?}");
        let corner = shape.closest(DVec3::new(1.02, -0.01, 1.02));
        assert!((corner.distance - 0.03).abs() < 1e-12 && corner.normal.y < 0.0, "{corner:?}");
    }

    #[test]
    fn segment_entry_catches_a_thin_box() {
        let plate = Shape::Box { center: DVec3::ZERO, half: DVec3::new(1.0, 0.0005, 1.0), rotation: DQuat::IDENTITY };
        let (t, n) = plate.segment_entry(DVec3::new(0.1, 0.2, 0.0), DVec3::new(0.1, -0.3, 0.0)).expect("crosses");
        assert!((t - 0.1995 / 0.5).abs() < 1e-9, "t = {t}");
        assert!(n.dot(DVec3::Y) > 0.999);
        assert!(plate.segment_entry(DVec3::new(0.1, 0.2, 0.0), DVec3::new(0.1, 0.1, 0.0)).is_none());
    }
}
