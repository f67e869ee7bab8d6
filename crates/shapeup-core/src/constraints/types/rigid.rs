//! Rigid: the selected vertices move as one rigid body (shape matching).
//!
//! Term: ω Σ_i ‖(q_i − c) − R d⁰_i‖² over the k ≥ 2 selected vertices, with c = (1/k) Σ_j q_j
//! the current centroid, d⁰_i = x⁰_i − c⁰ the centred rest shape (c⁰ its centroid) and R the
//! rotation that minimizes it.
//!
//! - Rows of C (k, translation-invariant as in ShapeOp): row i is q_i − (1/k) Σ_j q_j, i.e.
//!   C[i, i] = 1 − 1/k and C[i, j] = −1/k (j ≠ i); for more than
//!   [`DENSE_SET_MAX`](crate::constraints::kit::vertex_set::DENSE_SET_MAX) vertices row i is q_i and p_i = c + R d⁰_i
//!   (the same energy, without a dense k×k block in CᵀC).
//! - Set: the centred rotated copies {R d⁰_i : R ∈ SO(3)} of the rest shape.
//! - Projection (shape matching, Müller et al. 2005; the rotation part of Umeyama 1991):
//!   S = Σ_i (q_i − c) d⁰_iᵀ = UΣVᵀ, R = U diag(1, 1, det(UVᵀ)) Vᵀ
//!   ([`nearest_rotation3`]`(S)`, the maximizer of tr(RᵀS) over rotations), p_i = R d⁰_i: the
//!   exact nearest point of the set, as ‖C q − R D⁰‖² = ‖C q‖² + ‖D⁰‖² − 2 tr(RᵀS).
//! - ω = 1 (per constraint: the framework has no per-row weights). Default multiplier 100, as
//!   iso_one_ring, so that a rigid part stays rigid inside a soft body (springs and strain 10).
//! - Residual (a direct test of the set): max_ij |p_i·p_j − d⁰_i·d⁰_j| (an orthogonal copy) and
//!   the orientation of one spanning triple of the rest shape (a rotation, not a reflection),
//!   scaled to length units (`ShapeMatch::residual`).
//!
//! Sources: ShapeOp's RigidConstraint (Deuss et al. 2015), ShapeUp (Bouaziz et al. 2012),
//! Müller et al. 2005 "Meshless deformations based on shape matching".
//!
//! Choices left open: the vertices are weighted equally (Müller weights them by mass; here
//! that would need rows √m_i (q_i − c_m) about the mass-weighted centroid, which the framework
//! could express but ShapeOp does not do); ω = 1 rather than a size (k or the rest area), so a
//! bigger rigid part pulls harder, as in ShapeOp. The k rows have k² entries (ShapeOp's
//! choice); rows relative to one vertex would be sparser but the fit would then not be the
//! shape-matching one.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::vertex_set::centred_view;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::nearest_rotation3;
use glam::{DMat3, DVec3};
use crate::constraints::kit::vertex_set::{ShapeMatch, centre_into, push_centred_rows};

/// Name in scene files.
const KIND: &str = "rigid";

/// A rigid group: its selected vertices move as one rigid body.
#[derive(Debug, Clone)]
pub struct Rigid {
    shape: ShapeMatch,
}

impl Rigid {
    /// A rigid group of `vertices` (at least 2, indices into `rest`) at their rest positions;
    /// `None` with fewer than 2.
    pub fn new(vertices: Vec<u32>, rest: &[DVec3]) -> Option<Self> {
        (vertices.len() >= 2).then(|| Rigid { shape: ShapeMatch::new(vertices, rest) })
    }

    /// The best-fit rotation R = argmax tr(RᵀS) of the current positions.
    pub fn rotation(&self, q: &[DVec3]) -> DMat3 {
        let mut e = vec![DVec3::ZERO; self.shape.vertices.len()];
        centre_into(q, &self.shape.vertices, &mut e);
        nearest_rotation3(self.shape.covariance(&e))
    }
}

impl Constraint for Rigid {
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
        self.shape.project_rigid(q, out);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        self.shape.residual(&centred_view(p), 1.0)
    }
}

/// Builds one [`Rigid`] over all the selected vertices (at least 2). No options. Default
/// multiplier 100.
#[derive(Debug, Clone, Copy)]
pub struct RigidType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "rigid: the selected vertices move as one rigid body (shape matching)",
    options: &[],
    element: Element::VertexSet { min: 2 },
    default_multiplier: 100.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for RigidType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let vertices = ShapeMatch::selected(ctx, KIND)?;
        Ok(Rigid::new(vertices, &ctx.rest.positions).map(|c| Box::new(c) as Box<dyn Constraint>).into_iter().collect())
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

    /// A non-planar cloud of `k` points.
    fn cloud(rng: &mut Rng, k: usize) -> Vec<DVec3> {
        (0..k).map(|_| rng.vec3() * DVec3::new(1.0, 0.7, 0.4)).collect()
    }

    fn project(c: &Rigid, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; c.num_rows()];
        c.project(q, &mut out);
        out
    }

    fn all(k: usize) -> Vec<u32> {
        (0..k as u32).collect()
    }

    #[test]
    fn rows_are_centred_and_the_rest_shape_projects_to_itself() {
        let mut rng = Rng(101);
        let x = cloud(&mut rng, 7);
        let c = Rigid::new(vec![1, 2, 4, 6], &x).unwrap();
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        for row in 0..4 {
            let sum: f64 = sink.entries.iter().filter(|e| e.row == row).map(|e| e.coeff).sum();
            assert!(sum.abs() < 1e-15);
        }
        let q: Vec<DVec3> = (0..7).map(|_| rng.vec3()).collect();
        let mean = (q[1] + q[2] + q[4] + q[6]) / 4.0;
        let want: Vec<DVec3> = [1, 2, 4, 6].iter().map(|&v| q[v] - mean).collect();
        assert!(dist2(&c.apply(&q), &want) < 1e-28);
        assert!(c.energy(&x) < 1e-28);
        // Rigidly moved rest shape: still zero energy.
        let (r, t) = (rotation(&mut rng), rng.vec3());
        let moved: Vec<DVec3> = x.iter().map(|p| r * *p + t).collect();
        assert!(c.energy(&moved) < 1e-26);
        assert!((c.rotation(&moved) - r).abs().to_cols_array().iter().all(|e| *e < 1e-12));
    }

    #[test]
    fn projection_is_a_rotated_rest_copy_and_no_sampled_rotation_is_closer() {
        let mut rng = Rng(103);
        for k in [2, 3, 4, 9] {
            let x = cloud(&mut rng, k);
            let c = Rigid::new(all(k), &x).unwrap();
            for trial in 0..40 {
                let q: Vec<DVec3> = match trial % 3 {
                    0 => {
                        let r = rotation(&mut rng);
                        x.iter().map(|p| r * (*p + 0.3 * rng.vec3())).collect()
                    }
                    // mirrored: det S < 0
                    1 => x.iter().map(|p| DVec3::new(p.x, -p.y, p.z) + 0.05 * rng.vec3()).collect(),
                    _ => x.iter().map(|_| rng.vec3()).collect(),
                };
                let r = c.rotation(&q);
                assert!((r.transpose() * r - DMat3::IDENTITY).abs().to_cols_array().iter().all(|e| *e < 1e-13));
                assert!((r.determinant() - 1.0).abs() < 1e-13);
                let p = project(&c, &q);
                assert!(c.set_residual(&p) < 1e-13, "k = {k}: off the set by {}", c.set_residual(&p));
                let cq = c.apply(&q);
                let d = dist2(&cq, &p);
                let copy = |rot: DMat3| -> Vec<DVec3> { c.shape.rest.iter().map(|e| rot * *e).collect() };
                for _ in 0..200 {
                    assert!(d <= dist2(&cq, &copy(rotation(&mut rng))) + 1e-12, "a random rotation is closer");
                    let near = r * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
                    assert!(d <= dist2(&cq, &copy(near)) + 1e-12, "a nearby rotation is closer");
                }
            }
        }
    }

    #[test]
    fn a_large_set_has_one_entry_per_row_and_the_same_energy_as_centred_rows() {
        // Above DENSE_SET_MAX the rows are the vertices; the projection is the rotated rest
        // copy at the current centroid, and E equals the centred form ‖(q − q̄) − R d⁰‖².
        let mut rng = Rng(113);
        let k = crate::constraints::kit::vertex_set::DENSE_SET_MAX + 37;
        let x = cloud(&mut rng, k);
        let c = Rigid::new(all(k), &x).unwrap();
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        assert_eq!(sink.entries.len(), k, "one entry per row: CᵀC is diagonal");
        let r0 = rotation(&mut rng);
        let q: Vec<DVec3> = x.iter().map(|p| r0 * (*p + 0.2 * rng.vec3()) + DVec3::new(3.0, -1.0, 2.0)).collect();
        let p = project(&c, &q);
        assert!(c.set_residual(&p) < 1e-12, "off the set by {}", c.set_residual(&p));
        let mean = q.iter().copied().sum::<DVec3>() / k as f64;
        let r = c.rotation(&q);
        let centred: f64 = q.iter().zip(c.shape.rest.iter()).map(|(a, d)| (*a - mean - r * *d).length_squared()).sum();
        assert!((c.energy(&q) - centred).abs() <= 1e-12 * centred.max(1.0));
        // No sampled rigid copy (rotation and translation) is closer to C q = q.
        let d = dist2(&q, &p);
        for _ in 0..200 {
            let (rot, t) = (rotation(&mut rng), mean + 0.1 * rng.vec3());
            let copy: Vec<DVec3> = c.shape.rest.iter().map(|e| rot * *e + t).collect();
            assert!(d <= dist2(&q, &copy) + 1e-12, "a random rigid copy is closer");
            let near = r * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
            let copy: Vec<DVec3> = c.shape.rest.iter().map(|e| near * *e + mean + 1e-3 * t).collect();
            assert!(d <= dist2(&q, &copy) + 1e-12, "a nearby rigid copy is closer");
        }
        // The residual measures the shape, not where it is.
        let shifted: Vec<DVec3> = p.iter().map(|e| *e + DVec3::X).collect();
        assert!(c.set_residual(&shifted) < 1e-12);
    }

    #[test]
    fn the_residual_refuses_reflections_stretches_and_translations() {
        let mut rng = Rng(107);
        let x = cloud(&mut rng, 6);
        let c = Rigid::new(all(6), &x).unwrap();
        let p = project(&c, &x);
        assert!(c.set_residual(&p) < 1e-14);
        let r = rotation(&mut rng);
        let rotated: Vec<DVec3> = p.iter().map(|e| r * *e).collect();
        assert!(c.set_residual(&rotated) < 1e-13);
        let mirrored: Vec<DVec3> = p.iter().map(|e| DVec3::new(-e.x, e.y, e.z)).collect();
        assert!(c.set_residual(&mirrored) > 1e-3, "a reflection of a solid shape is not a rotation");
        let stretched: Vec<DVec3> = p.iter().map(|e| 1.01 * *e).collect();
        assert!(c.set_residual(&stretched) > 1e-3);
        let shifted: Vec<DVec3> = p.iter().map(|e| *e + DVec3::X * 0.01).collect();
        assert!(c.set_residual(&shifted) > 1e-3);
    }

    #[test]
    fn collapsed_input_projects_to_a_finite_rotated_copy() {
        let mut rng = Rng(109);
        let x = cloud(&mut rng, 5);
        let c = Rigid::new(all(5), &x).unwrap();
        for q in [vec![DVec3::ONE; 5], x.iter().map(|p| DVec3::new(p.x, 0.0, 0.0)).collect()] {
            let p = project(&c, &q);
            assert!(p.iter().all(|e| e.is_finite()));
            assert!(c.set_residual(&p) < 1e-13);
        }
    }

    #[test]
    fn build_takes_the_selection_and_refuses_one_vertex() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.3)];
        let rest = RestGeometry::new(p, vec![[0, 1, 2], [1, 3, 2]], vec![]);
        let frame = WorkingFrame::IDENTITY;
        let build = |sel: &Selection, params: Params| {
            build_constraints(KIND, &BuildContext { rest: &rest, selection: sel, frame: &frame }, params)
        };
        let built = build(&Selection::All, Params::default()).unwrap();
        assert_eq!(built.len(), 1);
        assert_eq!(built[0].num_rows(), 4);
        assert_eq!(built[0].element_weight(), 1.0);
        let two = build(&Selection::from_indices(4, &[1, 3]), Params::default()).unwrap();
        assert_eq!(two[0].vertices(), &[1, 3]);
        let err = build(&Selection::from_indices(4, &[2]), Params::default()).unwrap_err();
        assert_eq!(err.to_string(), "rigid: needs at least 2 vertices, the selection has 1");
        let err = build(&Selection::from_indices(4, &[]), Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
        let err = build(&Selection::All, Params::default().with("scale", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
    }

    #[test]
    fn a_rigid_part_of_a_soft_sheet_stays_rigid_under_a_handle() {
        use crate::constraints::{GroupDescription, build_group};
        use crate::solver::{SolverParams, System};
        let n = 4u32;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                positions.push(DVec3::new(x, y, 0.1 * (3.0 * x).sin() * y));
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let rest = RestGeometry::new(positions, triangles, vec![]);
        let nv = rest.num_vertices();
        let frame = WorkingFrame::IDENTITY;
        let part: Vec<usize> =
            [(2, 2), (3, 2), (2, 3), (3, 3), (4, 4)].iter().map(|&(i, j)| at(i, j) as usize).collect();
        let rigid =
            build_group(&GroupDescription::new(KIND, Selection::from_indices(nv, &part)), &rest, &frame).unwrap();
        let corner = at(n, n);
        let solve = |with_rigid: bool| {
            let mut system = System::new(nv, SolverParams::default());
            let springs = GroupDescription::new("edge_spring", Selection::All);
            system.add_group(build_group(&springs, &rest, &frame).unwrap()).unwrap();
            if with_rigid {
                let part = GroupDescription::new(KIND, Selection::from_indices(nv, &part));
                system.add_group(build_group(&part, &rest, &frame).unwrap()).unwrap();
            }
            let lifted = rest.positions[corner as usize] + DVec3::new(0.3, 0.2, 0.5);
            let pull = GroupDescription {
                targets: Some(vec![(0, rest.positions[0]), (corner, lifted)]),
                ..GroupDescription::new("position", Selection::from_indices(nv, &[0, corner as usize]))
            };
            system.add_group(build_group(&pull, &rest, &frame).unwrap()).unwrap();
            let mut q = rest.positions.clone();
            system.solve(&mut q, 300, 0.0).unwrap();
            q
        };
        let c = &rigid.constraints[0];
        let (q, soft) = (solve(true), solve(false));
        let (off, off_soft) = (c.set_residual(&c.apply(&q)), c.set_residual(&c.apply(&soft)));
        let moved = (q[corner as usize] - rest.positions[corner as usize]).length();
        assert!(moved > 0.1, "the handle moved the part");
        assert!(off < 0.1 * off_soft, "the part stayed rigid: {off:e} (without the group: {off_soft:e})");
    }
}
