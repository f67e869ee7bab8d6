//! Line: a set of vertices kept collinear.
//!
//! Term: ω Σ_i ‖(q_i − q̄) − p_i‖² over the k ≥ 2 selected vertices, q̄ = (1/k) Σ_j q_j. The
//! k rows of C are mean-centred as in ShapeOp: C = I − 11ᵀ/k (row i: q_i − q̄), so the term is
//! translation-invariant and the set is that of the *centred* collinear configurations,
//! L = {p : Σ_i p_i = 0, p_i = t_i u for a unit u and reals t_i}.
//!
//! Projection (exact): with d_i = q_i − q̄ the rows of C q, the nearest point of L is the best
//! rank-one approximation of the k×3 matrix D (Eckart–Young): u = the principal axis of the
//! d_i of largest singular value (PCA), p_i = ((d_i − d̄)·u) u (d̄ = 0 up to rounding; taking it
//! off keeps Σ p_i = 0 exactly). Its distance is √(σ₂² + σ₃²), the set's residual below.
//!
//! ω = 1: the term is already the squared distance (length²) of the k points from the set,
//! which grows with the set's size and number of points; as in ShapeOp (and ShapeUp's
//! shape-space projections, where each set counts alike) how much it matters is left to the
//! group multiplier. Default multiplier 10 (as edge springs: one of the shape's terms, strong
//! against a closeness of 1).
//!
//! Sources: ShapeUp (Bouaziz et al. 2012, §4: lines among the shape-space constraints
//! projected by PCA) and ShapeOp's `LineConstraint` (Deuss et al. 2015: mean-centred rows,
//! projection on the dominant singular vector of the centred points, by Eigen's JacobiSVD).
//! We do the same: the axis from the singular vectors of D itself (one-sided Jacobi,
//! [`sets::principal_axes`]), not from an eigensolver on the covariance DᵀD, which would square
//! the condition number and blur the small singular values the residual reads. Left open by
//! both and decided here: a set of coincident points (D = 0) projects to itself.
//!
//! What line, plane, circle and sphere share (the mean-centred rows, the projection's frame,
//! the builds) is [`PointSet`](crate::constraints::kit::point_set::PointSet).

use crate::constraints::contract::{BuildContext, Constraint, ConstraintType, TypeInfo};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::sets;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;
use crate::constraints::kit::point_set::{PointSet, Primitive, one_set};
use crate::constraints::kit::vertex_set::centred_view;

/// Name in scene files.
const KIND: &str = "line";


/// The line constraint on a set of vertices (k ≥ 2, distinct): [`PointSet::new`] keeps them
/// collinear, `None` with fewer than 2.
pub type Line = PointSet<Collinear>;

/// The line's primitive: centred collinear configurations, projected by PCA.
#[derive(Debug, Clone, Copy)]
pub struct Collinear;

impl Primitive for Collinear {
    const KIND: &'static str = KIND;
    const MIN_VERTICES: usize = 2;

    fn project(d: &[DVec3], out: &mut [DVec3]) {
        let (mean, _, axes) = sets::principal_axes(d);
        let u = axes[0];
        for (o, &x) in out.iter_mut().zip(d) {
            *o = (x - mean).dot(u) * u;
        }
    }
    /// √(‖Σ p_i‖²/k + σ₂² + σ₃²), σ the singular values of p about its centroid: the exact
    /// distance of p from the centred collinear configurations.
    fn set_residual(p: &[DVec3]) -> f64 {
        let p = centred_view(p);
        let (_, sigma, _) = sets::principal_axes(&p);
        (sets::centroid_offset(&p).powi(2) + sigma[1] * sigma[1] + sigma[2] * sigma[2]).sqrt()
    }
}

/// Builds one [`Line`] over all the selected vertices (at least 2). No options. Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct LineType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "line: the selected vertices stay collinear",
    options: &[],
    element: Element::VertexSet { min: 2 },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for LineType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        one_set::<Collinear>(ctx, "a line needs two points")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::contract::RowSink;
    use crate::constraints::kit::vertex_set::DENSE_SET_MAX;
    use crate::constraints::kit::test_util::{Rng, dist2, project};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};

    /// Singular values of the centred points by nalgebra (descending).
    fn nalgebra_sigma(p: &[DVec3]) -> Vec<f64> {
        let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let m = nalgebra::DMatrix::from_fn(p.len(), 3, |i, j| (p[i] - mean)[j]);
        let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s.resize(3, 0.0);
        s
    }

    #[test]
    fn large_sets_have_diagonal_rows_the_centred_energy_and_translate_with_q() {
        // Line, plane, circle, sphere, similarity over more than DENSE_SET_MAX vertices: rows
        // are the vertices, the projection lies on the set, E is that of the centred rows (the
        // projection's distance to q equals the centred one), and translating q translates p.
        use crate::constraints::{Circle, Plane, Similarity, Sphere};
        let mut rng = Rng(211);
        let k = DENSE_SET_MAX + 21;
        let all: Vec<u32> = (0..k as u32).collect();
        let rest: Vec<DVec3> = (0..k).map(|_| rng.vec3()).collect();
        let constraints: Vec<Box<dyn Constraint>> = vec![
            Box::new(Line::new(all.clone()).unwrap()),
            Box::new(Plane::new(all.clone()).unwrap()),
            Box::new(Circle::new(all.clone()).unwrap()),
            Box::new(Sphere::new(all.clone()).unwrap()),
            Box::new(Similarity::new(all.clone(), &rest).unwrap()),
        ];
        let q: Vec<DVec3> = (0..k).map(|_| rng.vec3() + DVec3::new(5.0, -2.0, 1.0)).collect();
        let shift = DVec3::new(0.3, 0.7, -1.1);
        let moved: Vec<DVec3> = q.iter().map(|x| *x + shift).collect();
        for c in &constraints {
            let mut sink = RowSink::default();
            c.rows(&mut sink);
            assert_eq!(sink.entries.len(), k, "{}: one entry per row", c.kind());
            let p = project(c.as_ref(), &q);
            assert!(c.set_residual(&p) < 1e-9, "{}: off the set by {}", c.kind(), c.set_residual(&p));
            // The same projection about the centroid, as centred rows would give it.
            let mean = q.iter().copied().sum::<DVec3>() / k as f64;
            let d: Vec<DVec3> = q.iter().map(|x| *x - mean).collect();
            let pc: Vec<DVec3> = p.iter().map(|x| *x - mean).collect();
            assert!((dist2(&q, &p) - dist2(&d, &pc)).abs() < 1e-9);
            assert!(sets::centroid_offset(&pc) < 1e-9, "{}: p sits at q's centroid", c.kind());
            let pm = project(c.as_ref(), &moved);
            let back: Vec<DVec3> = pm.iter().map(|x| *x - shift).collect();
            assert!(dist2(&back, &p) < 1e-18, "{}: translating q translates p", c.kind());
        }
    }

    #[test]
    fn rows_are_mean_centred() {
        let c = Line::new(vec![3, 0, 2]).unwrap();
        let mut rng = Rng(5);
        let q: Vec<DVec3> = (0..4).map(|_| rng.vec3()).collect();
        let mean = (q[3] + q[0] + q[2]) / 3.0;
        let want = [q[3] - mean, q[0] - mean, q[2] - mean];
        assert!(dist2(&c.apply(&q), &want) < 1e-28);
        assert_eq!(c.element_weight(), 1.0);
        let shifted: Vec<DVec3> = q.iter().map(|&x| x + DVec3::new(1.0, -2.0, 3.0)).collect();
        assert!(dist2(&c.apply(&q), &c.apply(&shifted)) < 1e-26, "translation-invariant rows");
    }

    #[test]
    fn projection_is_collinear_centred_and_no_sampled_line_is_closer() {
        let mut rng = Rng(11);
        for trial in 0..40 {
            let k = 2 + trial % 7;
            let c = Line::new((0..k as u32).collect()).unwrap();
            let (a, u) = (rng.vec3(), rng.vec3().normalize());
            let noise = [0.01, 0.1, 1.0][trial % 3];
            let q: Vec<DVec3> = (0..k).map(|_| a + 2.0 * rng.uniform() * u + noise * rng.vec3()).collect();
            let cq = c.apply(&q);
            let p = project(&c, &q);
            // On the set, by the definition: rank ≤ 1 about the centroid, and centred.
            let s = nalgebra_sigma(&p);
            assert!(s[1] < 1e-13, "σ₂ = {}", s[1]);
            assert!(sets::centroid_offset(&p) < 1e-13);
            assert!(c.set_residual(&p) < 1e-13);
            // The residual is the distance to the set: for C q, the projection's distance.
            let sq = nalgebra_sigma(&cq);
            let d = dist2(&cq, &p);
            assert!((c.set_residual(&cq) - d.sqrt()).abs() < 1e-12, "{} vs {}", c.set_residual(&cq), d.sqrt());
            assert!((d - sq[1] * sq[1] - sq[2] * sq[2]).abs() < 1e-12);
            // No sampled centred collinear configuration is closer: random lines near the
            // fitted one and random ones, each with its best parameters t_i = d_i·w.
            let fitted = p.iter().copied().max_by(|x, y| x.length().total_cmp(&y.length())).unwrap().normalize_or(u);
            for j in 0..200 {
                let w = if j % 2 == 0 { (fitted + 0.05 * rng.vec3()).normalize() } else { rng.vec3().normalize() };
                let sample: Vec<DVec3> = cq.iter().map(|&x| x.dot(w) * w).collect();
                assert!(d <= dist2(&cq, &sample) + 1e-13);
                let jitter: Vec<DVec3> = p.iter().map(|&x| x + 1e-3 * rng.uniform() * fitted).collect();
                assert!(d <= dist2(&cq, &jitter) + 1e-13);
            }
        }
    }

    #[test]
    fn residual_is_zero_exactly_on_collinear_points() {
        let c = Line::new(vec![0, 1, 2, 3]).unwrap();
        let on = [DVec3::new(-1.5, -3.0, 1.5), DVec3::new(0.5, 1.0, -0.5), DVec3::new(1.0, 2.0, -1.0), DVec3::ZERO];
        assert!(c.set_residual(&on) < 1e-14);
        let off = [on[0], on[1], on[2] + DVec3::new(0.0, 0.0, 0.1), on[3]];
        assert!(c.set_residual(&off) > 1e-3);
        let shifted: Vec<DVec3> = on.iter().map(|&x| x + DVec3::X).collect();
        assert!((c.set_residual(&shifted) - 2.0).abs() < 1e-12, "an off-centre set is √k·|shift| away");
    }

    #[test]
    fn coincident_points_stay_finite() {
        let c = Line::new(vec![0, 1, 2]).unwrap();
        let p = project(&c, &[DVec3::ONE; 3]);
        assert!(p.iter().all(|x| *x == DVec3::ZERO));
    }

    #[test]
    fn build_takes_the_selection_and_refuses_one_vertex() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ONE];
        let rest = RestGeometry::new(p, vec![[0, 1, 2], [1, 3, 2]], vec![]);
        let frame = WorkingFrame::IDENTITY;
        let built = build_constraints(
            KIND,
            &BuildContext { rest: &rest, selection: &Selection::All, frame: &frame },
            Params::default(),
        )
        .unwrap();
        assert_eq!(built.len(), 1);
        assert_eq!(built[0].vertices(), &[0, 1, 2, 3]);
        let one = Selection::from_indices(4, &[2]);
        let err =
            build_constraints(KIND, &BuildContext { rest: &rest, selection: &one, frame: &frame }, Params::default())
                .unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }) && err.to_string().contains("has 1"), "{err}");
        let none = Selection::from_indices(4, &[]);
        let err =
            build_constraints(KIND, &BuildContext { rest: &rest, selection: &none, frame: &frame }, Params::default())
                .unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
