//! The nearest triangle of a surface to a point, through parry3d's BVH: which triangle an
//! `attachment` follows, and how far a piece lies from the body (the editor's attach test);
//! and the one conversion between glam's points and parry's, which contact uses too. Beneath
//! the constraints and contact.

use glam::DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{TriMesh, TriMeshFlags};

/// glam's point as parry's.
#[inline]
pub(crate) fn to_parry(p: DVec3) -> parry3d_f64::math::Vector {
    parry3d_f64::math::Vector::new(p.x, p.y, p.z)
}

/// parry's point as glam's.
#[inline]
pub(crate) fn from_parry(p: parry3d_f64::math::Vector) -> DVec3 {
    DVec3::new(p.x, p.y, p.z)
}

/// A surface of triangles answering nearest-triangle queries.
pub struct NearestTriangle {
    triangles: Vec<[u32; 3]>,
    mesh: TriMesh,
}

impl std::fmt::Debug for NearestTriangle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NearestTriangle").field("triangles", &self.triangles.len()).finish()
    }
}

impl NearestTriangle {
    /// The surface of `triangles` over `positions` (indices must be in range); `None` when
    /// there are no triangles or parry3d refuses them.
    pub fn new(positions: &[DVec3], triangles: Vec<[u32; 3]>) -> Option<Self> {
        if triangles.is_empty() || triangles.iter().flatten().any(|&v| v as usize >= positions.len()) {
            return None;
        }
        let vertices = positions.iter().map(|p| to_parry(*p)).collect();
        let mesh = TriMesh::with_flags(vertices, triangles.clone(), TriMeshFlags::empty()).ok()?;
        Some(NearestTriangle { triangles, mesh })
    }

    /// The triangle nearest to `x` (ties: parry's choice) and the distance to its closest
    /// point.
    pub fn nearest(&self, x: DVec3) -> ([u32; 3], f64) {
        let (projection, (face, _)) = self.mesh.project_local_point_and_get_location(to_parry(x), false);
        (self.triangles[face as usize], (x - from_parry(projection.point)).length())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    #[test]
    fn finds_the_triangle_under_a_point_and_its_distance() {
        let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0), DVec3::new(5.0, 5.0, 5.0)];
        let surface = NearestTriangle::new(&p, vec![[0, 1, 2], [1, 3, 2]]).unwrap();
        assert_eq!(surface.nearest(DVec3::new(0.2, 0.2, 0.5)), ([0, 1, 2], 0.5));
        let (t, d) = surface.nearest(DVec3::new(0.9, 0.8, -0.25));
        assert_eq!(t, [1, 3, 2]);
        assert!((d - 0.25).abs() < 1e-15);
        // Beyond a corner: the distance to the corner.
        let (_, d) = surface.nearest(DVec3::new(2.0, 1.0, 0.0));
        assert!((d - 1.0).abs() < 1e-15);
        assert!(NearestTriangle::new(&p, vec![]).is_none());
        assert!(NearestTriangle::new(&p, vec![[0, 1, 9]]).is_none());
    }
}
