//! Shared helpers of the types' unit tests: row distances, projections, random numbers, a
//! closed mesh.

use crate::constraints::contract::Constraint;
use crate::geometry::RestGeometry;
use glam::DVec3;

pub(crate) use crate::linalg::test_rng::Rng;

/// `‖a − b‖_F²` of two row lists.
pub fn dist2(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).length_squared()).sum()
}

/// `c`'s projection of `q` (its `num_rows()` rows).
pub fn project(c: &dyn Constraint, q: &[DVec3]) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; c.num_rows()];
    c.project(q, &mut out);
    out
}

/// A closed octahedron-like bumpy mesh: every vertex interior, nonzero curvature.
pub fn octahedron() -> RestGeometry {
    let p = vec![DVec3::X, -DVec3::X, DVec3::Y, -DVec3::Y, DVec3::Z * 1.3, -DVec3::Z * 0.8];
    let t = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    RestGeometry::new(p, t, vec![])
}
