//! Plane (planarity): the corners of each polygon face, or a whole vertex set, kept coplanar.
//!
//! Term: ω Σ_i ‖(q_i − q̄) − p_i‖² over the k corners of a face (k ≥ 4), or over all the
//! selected vertices (k ≥ 3) with `whole_selection = true`; q̄ = (1/k) Σ_j q_j. The k rows of C
//! are mean-centred as in ShapeOp, C = I − 11ᵀ/k, so the set is that of the centred coplanar
//! configurations P = {p : Σ_i p_i = 0, n·p_i = 0 for a unit n}.
//!
//! Projection (exact): with d_i = q_i − q̄ the rows of C q, the nearest point of P is the best
//! rank-two approximation of the k×3 matrix D (Eckart–Young): n = the principal axis of the d_i
//! of smallest singular value (the smallest eigenvector of the covariance DᵀD), and
//! p_i = (d_i − d̄) − ((d_i − d̄)·n) n (d̄ = 0 up to rounding; taking it off keeps Σ p_i = 0
//! exactly). Its distance is σ₃, the set's residual below.
//!
//! ω = 1: the term is already the squared distance (length²) of the corners from the set; as
//! in ShapeOp, and in ShapeUp where every face's planarity projection counts alike, the weight
//! of planarity against the other terms is the group multiplier. Default multiplier 10 (as
//! edge springs: one of the shape's terms, strong against a closeness of 1).
//!
//! Sources: ShapeUp (Bouaziz et al. 2012, §4 "planarity": each polygon face of a mesh projected
//! on its best-fit plane, by PCA) and ShapeOp's `PlaneConstraint` (Deuss et al. 2015:
//! mean-centred rows, the smallest singular vector of the centred points as normal, by Eigen's
//! JacobiSVD). We compute the normal the same way (one-sided Jacobi on D,
//! [`sets::principal_axes`]; an eigensolver on the covariance DᵀD would square the condition
//! number). Choice left open: the elements. One constraint per polygon face of the input as
//! read (its quads and n-gons, not their triangles, which are always planar; faces that are
//! triangles are skipped), or one over the whole selection.

use crate::constraints::contract::{BuildContext, Constraint, ConstraintType, TypeInfo};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::sets;
use crate::constraints::kit::point_set::{PointSet, Primitive, faces_or_set};
use crate::constraints::kit::vertex_set::centred_view;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;
use crate::constraints::kit::faces::WHOLE_SELECTION;

/// Name in scene files.
const KIND: &str = "plane";


/// The plane constraint on a face's corners or a vertex set (k ≥ 3, distinct):
/// [`PointSet::new`] keeps them coplanar, `None` with fewer than 3.
pub type Plane = PointSet<Coplanar>;

/// The plane's primitive: centred coplanar configurations, projected by PCA.
#[derive(Debug, Clone, Copy)]
pub struct Coplanar;

impl Primitive for Coplanar {
    const KIND: &'static str = KIND;
    const MIN_VERTICES: usize = 3;

    fn project(d: &[DVec3], out: &mut [DVec3]) {
        let (mean, _, axes) = sets::principal_axes(d);
        let n = axes[2];
        for (o, &x) in out.iter_mut().zip(d) {
            let y = x - mean;
            *o = y - y.dot(n) * n;
        }
    }
    /// √(‖Σ p_i‖²/k + σ₃²), σ₃ the smallest singular value of p about its centroid: the exact
    /// distance of p from the centred coplanar configurations.
    fn set_residual(p: &[DVec3]) -> f64 {
        let p = centred_view(p);
        let (_, sigma, _) = sets::principal_axes(&p);
        (sets::centroid_offset(&p).powi(2) + sigma[2] * sigma[2]).sqrt()
    }
    /// The planarity error: the largest distance of a corner of C q from the best-fit plane,
    /// max_i |(d_i − d̄)·n| (ShapeUp §6 and the architectural literature report this, over the
    /// mean edge length).
    fn violation(cq: &[DVec3]) -> f64 {
        let (mean, _, axes) = sets::principal_axes(cq);
        cq.iter().map(|&d| (d - mean).dot(axes[2]).abs()).fold(0.0, f64::max)
    }
}

/// Builds a [`Plane`] on every selected polygon face of 4 or more corners, or one over all
/// the selected vertices (at least 3) with `whole_selection = true`. Default multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct PlaneType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "plane: the corners of each polygon face (or the whole selection) stay coplanar",
    options: &[WHOLE_SELECTION],
    element: Element::Face { min: 4, max: usize::MAX },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for PlaneType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        faces_or_set::<Coplanar>(ctx, params, "three points always lie on a plane", "which are always planar")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2, project};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::mesh::{Mesh, Polygons};

    /// Smallest singular value of the centred points, by nalgebra.
    fn nalgebra_smallest(p: &[DVec3]) -> f64 {
        let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let m = nalgebra::DMatrix::from_fn(p.len(), 3, |i, j| (p[i] - mean)[j]);
        if p.len() < 3 { 0.0 } else { m.singular_values().iter().copied().fold(f64::INFINITY, f64::min) }
    }

    #[test]
    fn projection_is_coplanar_centred_and_no_sampled_plane_is_closer() {
        let mut rng = Rng(17);
        for trial in 0..40 {
            let k = 3 + trial % 8;
            let c = Plane::new((0..k as u32).collect()).unwrap();
            let (a, n0) = (rng.vec3(), rng.vec3().normalize());
            let noise = [0.01, 0.1, 1.0][trial % 3];
            let q: Vec<DVec3> = (0..k)
                .map(|_| {
                    let x = rng.vec3();
                    a + x - x.dot(n0) * n0 + noise * rng.vec3()
                })
                .collect();
            let cq = c.apply(&q);
            let p = project(&c, &q);
            // On the set, by the definition: σ₃ = 0 about the centroid, centred.
            assert!(nalgebra_smallest(&p) < 1e-13, "σ₃ = {}", nalgebra_smallest(&p));
            assert!(sets::centroid_offset(&p) < 1e-13);
            assert!(c.set_residual(&p) < 1e-13);
            // The distance moved is the input's σ₃ (Eckart–Young), as the residual says.
            let d = dist2(&cq, &p);
            assert!((d.sqrt() - nalgebra_smallest(&cq)).abs() < 1e-12);
            assert!((c.set_residual(&cq) - d.sqrt()).abs() < 1e-12);
            // No sampled plane through the origin is closer (each with its nearest points).
            let normal = (p[0] - p[1]).cross(p[2] - p[1]).normalize_or(n0);
            for j in 0..200 {
                let w = if j % 2 == 0 { (normal + 0.05 * rng.vec3()).normalize() } else { rng.vec3().normalize() };
                let sample: Vec<DVec3> = cq.iter().map(|&x| x - x.dot(w) * w).collect();
                assert!(d <= dist2(&cq, &sample) + 1e-13, "trial {trial}");
            }
        }
    }

    #[test]
    fn residual_is_zero_exactly_on_coplanar_points() {
        let c = Plane::new(vec![0, 1, 2, 3]).unwrap();
        let (u, v) = (DVec3::new(1.0, 2.0, 0.5).normalize(), DVec3::new(-2.0, 1.0, 0.0).normalize());
        let on = [u + v, -u, 2.0 * v - u, -v];
        let mean = on.iter().copied().sum::<DVec3>() / 4.0;
        let on = on.map(|x| x - mean);
        assert!(c.set_residual(&on) < 1e-14);
        let n = u.cross(v).normalize();
        let off = [on[0] + 0.1 * n, on[1] - 0.1 * n, on[2] + 0.1 * n, on[3] - 0.1 * n];
        // At most the 0.2 the offsets moved it (a nearer plane may exist), and clearly off.
        let r = c.set_residual(&off);
        assert!(r > 1e-2 && r <= 0.2 + 1e-12, "{r}");
    }

    fn quad_strip() -> Mesh {
        let positions: Vec<DVec3> =
            (0..6).map(|i| DVec3::new((i / 2) as f64, (i % 2) as f64, 0.1 * (i * i) as f64)).collect();
        let mut polygons = Polygons::new();
        polygons.push(&[0, 2, 3, 1]);
        polygons.push(&[2, 4, 5, 3]);
        polygons.push(&[0, 1, 4]);
        Mesh::from_polygons(positions, polygons).unwrap().0
    }

    #[test]
    fn violation_is_the_largest_corner_distance_from_the_best_fit_plane() {
        // A unit square whose corners alternate ±ε off z = 0: the best-fit plane is z = 0 by
        // symmetry, every corner is ε from it; σ₃ (the residual) is 2ε.
        let eps = 1e-3;
        let c = Plane::new(vec![0, 1, 2, 3]).unwrap();
        let q = [
            DVec3::new(0.0, 0.0, eps),
            DVec3::new(1.0, 0.0, -eps),
            DVec3::new(1.0, 1.0, eps),
            DVec3::new(0.0, 1.0, -eps),
        ];
        let cq = c.apply(&q);
        assert!((c.violation(&cq) - eps).abs() < 1e-15);
        assert!((c.set_residual(&cq) - 2.0 * eps).abs() < 1e-15);
    }

    #[test]
    fn build_makes_one_per_selected_face_or_one_over_the_selection() {
        let mesh = quad_strip();
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let frame = WorkingFrame::IDENTITY;
        let ctx = |selection| BuildContext { rest: &rest, selection, frame: &frame };
        let all = build_constraints(KIND, &ctx(&Selection::All), Params::default()).unwrap();
        assert_eq!(all.len(), 2, "the two quads, not the triangle");
        assert_eq!(all[1].vertices(), &[2, 4, 5, 3]);
        let one = Selection::from_faces(6, &rest.faces, &[1]);
        assert_eq!(build_constraints(KIND, &ctx(&one), Params::default()).unwrap().len(), 1);
        let by_vertices = Selection::from_indices(6, &[0, 1, 2, 3]);
        assert_eq!(
            build_constraints(KIND, &ctx(&by_vertices), Params::default()).unwrap()[0].vertices(),
            &[0, 2, 3, 1]
        );
        let whole =
            build_constraints(KIND, &ctx(&Selection::All), Params::default().with("whole_selection", true)).unwrap();
        assert_eq!(whole.len(), 1);
        assert_eq!(whole[0].num_rows(), 6);
        let two = Selection::from_indices(6, &[0, 5]);
        let err = build_constraints(KIND, &ctx(&two), Params::default().with("whole_selection", true)).unwrap_err();
        assert!(err.to_string().contains("has 2"), "{err}");
        let err =
            build_constraints(KIND, &ctx(&Selection::All), Params::default().with("whole_selection", 1)).unwrap_err();
        assert!(err.to_string().contains("whole_selection"), "{err}");
        let none = Selection::from_indices(6, &[0]);
        let err = build_constraints(KIND, &ctx(&none), Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }

    #[test]
    fn a_triangle_only_mesh_is_refused_with_the_reason() {
        let rest =
            RestGeometry::new(vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ONE], vec![[0, 1, 2], [1, 3, 2]], vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, ConstraintError::Invalid { .. }), "{text}");
        assert!(
            text.starts_with("plane: the mesh has no polygon faces of 4 or more corners (")
                && text.contains("triangles"),
            "{text}"
        );
        assert_eq!(build_constraints(KIND, &ctx, Params::default().with("whole_selection", true)).unwrap().len(), 1);
    }
}
