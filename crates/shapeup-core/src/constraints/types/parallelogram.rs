//! Parallelogram: each selected quad face of the input becomes a parallelogram.
//!
//! Term: ω ‖D − p‖² over the centred corners d_i = q_i − ¼ Σ_j q_j (i = 0…3 in face order),
//! with p the nearest point of the parallelograms x₀ − x₁ + x₂ − x₃ = 0 (opposite sides equal
//! and parallel; equivalently the diagonals bisect each other).
//!
//! - Rows of C (4, translation-invariant as in ShapeOp): d_i = q_i − ¼ Σ_j q_j.
//! - Set: the linear subspace {p : p₀ − p₁ + p₂ − p₃ = 0} (any centre; degenerate
//!   parallelograms, flat or collapsed, included).
//! - Projection: with σ = (+1, −1, +1, −1) (‖σ‖² = 4) and the defect δ = ¼ Σ_i σ_i d_i, the
//!   orthogonal projection onto the subspace is p_i = d_i − σ_i δ (exact: the set is the
//!   orthogonal complement of σ in each coordinate). As σ ⊥ (1, 1, 1, 1), p stays centred.
//! - ω = 1 (per constraint, as ShapeOp). Default multiplier 10, as rectangle.
//! - Residual (direct): ‖p₀ − p₁ + p₂ − p₃‖, in length units.
//!
//! Sources: ShapeOp's ParallelogramConstraint (Deuss et al. 2015), ShapeUp (Bouaziz et al.
//! 2012).
//!
//! Choices left open: ω = 1 rather than the rest face area (as rectangle); ShapeOp's 4
//! centred rows rather than the single row x₀ − x₁ + x₂ − x₃ with projection 0. Both give the
//! same energy (ω‖D − p‖² = 4ω‖δ‖² = (ω/4)‖x₀ − x₁ + x₂ − x₃‖²), but the single row is a
//! linear term the global step satisfies at once, while the 4 rows (CᵀC = I − ¼11ᵀ, rank 3)
//! also hold the other two centred directions at the last local step's values, which can slow
//! convergence; the 4 rows are kept for ShapeOp's form and the same rows as rectangle. Only
//! quads as read are constrained; a triangulated mesh is refused.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::faces::selected_quads;
use crate::constraints::kit::vertex_set::{centre_into, push_centred_rows};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;

/// Name in scene files.
const KIND: &str = "parallelogram";

/// The alternating corner signs σ.
const SIGMA: [f64; 4] = [1.0, -1.0, 1.0, -1.0];

/// A parallelogram constraint on one quad face.
#[derive(Debug, Clone)]
pub struct Parallelogram {
    /// The corners in face order.
    vertices: [u32; 4],
}

impl Parallelogram {
    /// The constraint on the quad with these corners (in face order).
    pub fn new(corners: [u32; 4]) -> Self {
        Parallelogram { vertices: corners }
    }
}

impl Constraint for Parallelogram {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        4
    }
    fn rows(&self, sink: &mut RowSink) {
        push_centred_rows(&self.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let mut d = [DVec3::ZERO; 4];
        centre_into(q, &self.vertices, &mut d);
        let defect = 0.25 * (d[0] - d[1] + d[2] - d[3]);
        for (i, o) in out.iter_mut().enumerate().take(4) {
            *o = d[i] - SIGMA[i] * defect;
        }
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let defect = p[0] - p[1] + p[2] - p[3];
        if defect.is_finite() { defect.length() } else { f64::INFINITY }
    }
}

/// Builds a [`Parallelogram`] on every selected quad face of the input. No options. Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct ParallelogramType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "parallelogram: every selected quad face becomes a parallelogram",
    options: &[],
    element: Element::Face { min: 4, max: 4 },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for ParallelogramType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let built = selected_quads(ctx, KIND)?
            .into_iter()
            .map(|corners| Box::new(Parallelogram::new(corners)) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "quad faces")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::mesh::{Mesh, Polygons};

    fn project(c: &Parallelogram, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; 4];
        c.project(q, &mut out);
        out
    }

    /// The parallelogram with corners c − a − b, c + a − b, c + a + b, c − a + b.
    fn parallelogram(c: DVec3, a: DVec3, b: DVec3) -> Vec<DVec3> {
        vec![c - a - b, c + a - b, c + a + b, c - a + b]
    }

    #[test]
    fn a_parallelogram_projects_to_itself() {
        let mut rng = Rng(401);
        let c = Parallelogram::new([0, 1, 2, 3]);
        for _ in 0..20 {
            let x = parallelogram(rng.vec3(), rng.vec3(), rng.vec3());
            assert!(c.energy(&x) < 1e-28);
            assert!(c.set_residual(&project(&c, &x)) < 1e-15);
        }
    }

    #[test]
    fn projection_is_orthogonal_and_no_sampled_parallelogram_is_closer() {
        let mut rng = Rng(403);
        let c = Parallelogram::new([3, 0, 2, 1]);
        for _ in 0..200 {
            let q: Vec<DVec3> = (0..4).map(|_| rng.vec3()).collect();
            let p = project(&c, &q);
            assert!(c.set_residual(&p) < 1e-15);
            let cq = c.apply(&q);
            let d = dist2(&cq, &p);
            let near: Vec<DVec3> = p.iter().map(|x| *x + 1e-2 * rng.vec3()).collect();
            for _ in 0..100 {
                let y = parallelogram(rng.vec3(), rng.vec3(), rng.vec3());
                assert!(d <= dist2(&cq, &y) + 1e-12, "a random parallelogram is closer");
                // The residual is orthogonal to the set: (Cq − p)·(p − y) = 0 for y on it.
                let dot: f64 = (0..4).map(|i| (cq[i] - p[i]).dot(p[i] - y[i])).sum();
                assert!(dot.abs() < 1e-12);
                let mut y = near.clone();
                let fix = 0.25 * (y[0] - y[1] + y[2] - y[3]);
                for (i, v) in y.iter_mut().enumerate() {
                    *v -= SIGMA[i] * fix;
                }
                assert!(c.set_residual(&y) < 1e-14);
                assert!(d <= dist2(&cq, &y) + 1e-12, "a nearby parallelogram is closer");
            }
        }
    }

    #[test]
    fn the_residual_refuses_a_trapezoid() {
        let c = Parallelogram::new([0, 1, 2, 3]);
        let trapezoid = [DVec3::ZERO, DVec3::X, DVec3::new(0.8, 1.0, 0.0), DVec3::new(0.2, 1.0, 0.0)];
        assert!((c.set_residual(&trapezoid) - 0.4).abs() < 1e-15);
    }

    #[test]
    fn build_takes_quads_and_refuses_a_mesh_without_quads() {
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.3), DVec3::Y, DVec3::new(0.5, 2.0, 0.0)];
        let mut polygons = Polygons::new();
        polygons.push(&[0, 1, 2, 3]);
        polygons.push(&[3, 2, 4]);
        let mesh = Mesh::from_polygons(positions, polygons).unwrap().0;
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let frame = WorkingFrame::IDENTITY;
        let build = |rest: &RestGeometry, sel: &Selection| {
            build_constraints(KIND, &BuildContext { rest, selection: sel, frame: &frame }, Params::default())
        };
        let built = build(&rest, &Selection::All).unwrap();
        assert_eq!(built.len(), 1);
        assert_eq!(built[0].vertices(), &[0, 1, 2, 3]);
        assert_eq!(built[0].element_weight(), 1.0);
        let triangles = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let err = build(&triangles, &Selection::All).unwrap_err();
        assert!(err.to_string().starts_with("parallelogram: the mesh has no quad faces ("), "{err}");
        let empty = RestGeometry::new(mesh.positions.clone(), vec![], vec![]);
        let err = build(&empty, &Selection::All).unwrap_err();
        assert!(err.to_string().contains("this mesh has no faces"), "{err}");
    }
}
