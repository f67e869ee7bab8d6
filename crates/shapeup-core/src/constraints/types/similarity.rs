//! Similarity: the selected vertices move as one rigid body that may also scale uniformly.
//!
//! Term: ω Σ_i ‖(q_i − c) − s R d⁰_i‖² over the k ≥ 2 selected vertices, c = (1/k) Σ_j q_j,
//! d⁰_i = x⁰_i − c⁰ the centred rest shape, minimized over rotations R and scales s ≥ 0.
//!
//! - Rows of C (k, translation-invariant as in ShapeOp): q_i − (1/k) Σ_j q_j, as rigid.
//! - Set: {s R d⁰_i : R ∈ SO(3), s ≥ 0} (s = 0, the shape collapsed to its centroid, included
//!   so that the set is closed).
//! - Projection (Umeyama 1991): S = Σ_i (q_i − c) d⁰_iᵀ, R = [`nearest_rotation3`]`(S)` as for
//!   rigid (for any s > 0 the best R maximizes tr(RᵀS) whatever s is), then the best scale
//!   s = tr(RᵀS) / Σ_i ‖d⁰_i‖² (the minimizer of the quadratic in s; it is ≥ 0 since
//!   tr(RᵀS) = σ₁ + σ₂ ± σ₃ ≥ 0), p_i = s R d⁰_i: the exact nearest point. With a rest shape
//!   collapsed to one point (Σ‖d⁰‖² = 0) the set is the origin and p = 0.
//! - ω = 1 (per constraint). Default multiplier 100, as rigid.
//! - Residual (direct): with s² = Σ‖p_i‖² / Σ‖d⁰_i‖² (what s must be if p is on the set),
//!   max_ij |p_i·p_j − s² d⁰_i·d⁰_j| and the orientation of a spanning triple against s³ times
//!   the rest one, in length units (as rigid).
//!
//! Sources: ShapeOp's SimilarityConstraint (Deuss et al. 2015), ShapeUp (Bouaziz et al. 2012),
//! Umeyama 1991 "Least-squares estimation of transformation parameters between two point
//! patterns".
//!
//! Choices left open: no options, as ShapeOp. A scale band [s_min, s_max] would stay exact
//! (clamp s: R does not depend on s, and the energy is a parabola in s) but is left out until a
//! scene needs it. Vertices weigh equally and ω = 1, as rigid.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::vertex_set::{ShapeMatch, centre_into, centred_view, push_centred_rows, to_row_frame};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::nearest_rotation3;
use glam::{DMat3, DVec3};

/// Name in scene files.
const KIND: &str = "similarity";

/// A similarity group: its selected vertices move as one rigid body with a uniform scale.
#[derive(Debug, Clone)]
pub struct Similarity {
    shape: ShapeMatch,
}

impl Similarity {
    /// A similarity group of `vertices` (at least 2, indices into `rest`) at their rest
    /// positions; `None` with fewer than 2.
    pub fn new(vertices: Vec<u32>, rest: &[DVec3]) -> Option<Self> {
        (vertices.len() >= 2).then(|| Similarity { shape: ShapeMatch::new(vertices, rest) })
    }

    /// The best-fit rotation and scale (R, s) of centred rows `e`.
    fn fit_centred(&self, e: &[DVec3]) -> (DMat3, f64) {
        let s_mat = self.shape.covariance(e);
        let r = nearest_rotation3(s_mat);
        if self.shape.rest_norm2 <= 0.0 {
            return (r, 0.0);
        }
        // tr(RᵀS) = Σ_i e_i · R d⁰_i.
        let trace: f64 = e.iter().zip(self.shape.rest.iter()).map(|(e, d0)| e.dot(r * *d0)).sum();
        (r, (trace / self.shape.rest_norm2).max(0.0))
    }

    /// The best-fit rotation and scale (R, s) of the current positions.
    pub fn fit(&self, q: &[DVec3]) -> (DMat3, f64) {
        let mut e = vec![DVec3::ZERO; self.shape.vertices.len()];
        centre_into(q, &self.shape.vertices, &mut e);
        self.fit_centred(&e)
    }
}

impl Constraint for Similarity {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.shape.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        self.shape.vertices.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        push_centred_rows(&self.shape.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        centre_into(q, &self.shape.vertices, out);
        let (r, s) = self.fit_centred(out);
        let sr = r * s;
        for (o, d0) in out.iter_mut().zip(self.shape.rest.iter()) {
            *o = sr * *d0;
        }
        to_row_frame(&self.shape.vertices, q, out);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let p = &*centred_view(p);
        let s = if self.shape.rest_norm2 > 0.0 {
            (p.iter().map(|x| x.length_squared()).sum::<f64>() / self.shape.rest_norm2).sqrt()
        } else {
            0.0
        };
        self.shape.residual(p, s)
    }
}

/// Builds one [`Similarity`] over all the selected vertices (at least 2). No options. Default
/// multiplier 100.
#[derive(Debug, Clone, Copy)]
pub struct SimilarityType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "similarity: the selected vertices move as one rigid body that may scale uniformly",
    options: &[],
    element: Element::VertexSet { min: 2 },
    default_multiplier: 100.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for SimilarityType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let vertices = ShapeMatch::selected(ctx, KIND)?;
        Ok(Similarity::new(vertices, &ctx.rest.positions)
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .into_iter()
            .collect())
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use glam::DQuat;

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    fn cloud(rng: &mut Rng, k: usize) -> Vec<DVec3> {
        (0..k).map(|_| rng.vec3() * DVec3::new(1.0, 0.7, 0.4)).collect()
    }

    fn project(c: &Similarity, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; c.num_rows()];
        c.project(q, &mut out);
        out
    }

    #[test]
    fn a_scaled_rotated_rest_shape_projects_to_itself() {
        let mut rng = Rng(201);
        let x = cloud(&mut rng, 6);
        let c = Similarity::new((0..6).collect(), &x).unwrap();
        for s in [0.3, 1.0, 2.5] {
            let (r, t) = (rotation(&mut rng), rng.vec3());
            let q: Vec<DVec3> = x.iter().map(|p| s * (r * *p) + t).collect();
            assert!(c.energy(&q) < 1e-24, "s = {s}");
            let (fr, fs) = c.fit(&q);
            assert!((fs - s).abs() < 1e-12);
            assert!((fr - r).abs().to_cols_array().iter().all(|e| *e < 1e-12));
        }
    }

    #[test]
    fn projection_is_on_the_set_and_no_sampled_similar_copy_is_closer() {
        let mut rng = Rng(203);
        for k in [2, 3, 5, 9] {
            let x = cloud(&mut rng, k);
            let c = Similarity::new((0..k as u32).collect(), &x).unwrap();
            for trial in 0..40 {
                let q: Vec<DVec3> = match trial % 3 {
                    0 => {
                        let (r, s) = (rotation(&mut rng), 1.0 + 0.8 * rng.uniform());
                        x.iter().map(|p| s * (r * (*p + 0.3 * rng.vec3()))).collect()
                    }
                    1 => x.iter().map(|p| DVec3::new(p.x, -p.y, p.z) + 0.05 * rng.vec3()).collect(),
                    _ => x.iter().map(|_| rng.vec3()).collect(),
                };
                let (r, s) = c.fit(&q);
                assert!(s >= 0.0);
                let p = project(&c, &q);
                assert!(c.set_residual(&p) < 1e-12, "k = {k}: off the set by {}", c.set_residual(&p));
                let cq = c.apply(&q);
                let d = dist2(&cq, &p);
                let copy =
                    |rot: DMat3, sc: f64| -> Vec<DVec3> { c.shape.rest.iter().map(|e| sc * (rot * *e)).collect() };
                for _ in 0..200 {
                    let far = copy(rotation(&mut rng), 2.0 * (rng.uniform() + 1.0));
                    assert!(d <= dist2(&cq, &far) + 1e-12, "a random similar copy is closer");
                    let near_r = r * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
                    let near_s = (s * (1.0 + 1e-3 * rng.uniform())).max(0.0);
                    assert!(d <= dist2(&cq, &copy(near_r, near_s)) + 1e-12, "a nearby similar copy is closer");
                }
            }
        }
    }

    #[test]
    fn the_residual_refuses_reflections_shears_and_translations_but_not_scales() {
        let mut rng = Rng(207);
        let x = cloud(&mut rng, 6);
        let c = Similarity::new((0..6).collect(), &x).unwrap();
        let p = project(&c, &x);
        for s in [0.0, 0.5, 3.0] {
            let scaled: Vec<DVec3> = p.iter().map(|e| s * *e).collect();
            assert!(c.set_residual(&scaled) < 1e-13, "s = {s}");
        }
        let mirrored: Vec<DVec3> = p.iter().map(|e| DVec3::new(-e.x, e.y, e.z)).collect();
        assert!(c.set_residual(&mirrored) > 1e-3);
        let stretched: Vec<DVec3> = p.iter().map(|e| DVec3::new(1.1 * e.x, e.y, e.z)).collect();
        assert!(c.set_residual(&stretched) > 1e-3);
        let shifted: Vec<DVec3> = p.iter().map(|e| *e + DVec3::Y * 0.01).collect();
        assert!(c.set_residual(&shifted) > 1e-3);
    }

    #[test]
    fn collapsed_input_and_rest_give_the_centroid() {
        let mut rng = Rng(209);
        let x = cloud(&mut rng, 4);
        let c = Similarity::new((0..4).collect(), &x).unwrap();
        let p = project(&c, &[DVec3::ONE; 4]);
        assert!(p.iter().all(|e| *e == DVec3::ZERO));
        assert_eq!(c.set_residual(&p), 0.0);
        let point = Similarity::new((0..3).collect(), &[DVec3::ONE; 3]).unwrap();
        let q: Vec<DVec3> = (0..3).map(|_| rng.vec3()).collect();
        let p = project(&point, &q);
        assert!(p.iter().all(|e| *e == DVec3::ZERO));
        assert_eq!(point.set_residual(&p), 0.0);
        assert!(point.set_residual(&q) > 0.0);
    }

    #[test]
    fn build_refuses_one_vertex_and_options() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let rest = RestGeometry::new(p, vec![[0, 1, 2]], vec![]);
        let frame = WorkingFrame::IDENTITY;
        let build = |sel: &Selection, params: Params| {
            build_constraints(KIND, &BuildContext { rest: &rest, selection: sel, frame: &frame }, params)
        };
        assert_eq!(build(&Selection::All, Params::default()).unwrap()[0].num_rows(), 3);
        let err = build(&Selection::from_indices(3, &[0]), Params::default()).unwrap_err();
        assert_eq!(err.to_string(), "similarity: needs at least 2 vertices, the selection has 1");
        let err = build(&Selection::All, Params::default().with("min_scale", 0.5)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
    }
}
