//! Isometric one-ring (as-rigid-as-possible): the edges around a vertex move rigidly.
//!
//! Term: ω Σ_j ‖e_j − R e⁰_j‖² over the k ≥ 2 neighbours j of vertex i, with e_j = q_j − q_i
//! (the k rows of C q), e⁰_j = x⁰_j − x⁰_i and R the rotation that minimizes it:
//! S = Σ_j e_j e⁰_jᵀ = UΣVᵀ, R = U diag(1, 1, det(UVᵀ)) Vᵀ ([`nearest_rotation3`]`(S)`).
//! Projection p_j = R e⁰_j. ω = A_i, the rest vertex area.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::nearest_rotation3;
use glam::{DMat3, DVec3};

/// Name in scene files.
const KIND: &str = "iso_one_ring";

/// The isometric one-ring constraint of one vertex.
#[derive(Debug, Clone)]
pub struct IsoOneRing {
    /// The centre i, then its neighbours j₁ … j_k.
    vertices: Box<[u32]>,
    /// Rest edges e⁰_j = x⁰_j − x⁰_i, in the order of the neighbours.
    rest_edges: Box<[DVec3]>,
    area: f64,
}

impl IsoOneRing {
    /// The constraint of vertex `centre` with its one-ring `neighbours` in the rest shape `rest`
    /// and element weight `area` (A_i); `None` with fewer than 2 neighbours.
    pub fn new(centre: u32, neighbours: &[u32], rest: &[DVec3], area: f64) -> Option<Self> {
        if neighbours.len() < 2 {
            return None;
        }
        let xi = rest[centre as usize];
        let vertices = std::iter::once(centre).chain(neighbours.iter().copied()).collect();
        let rest_edges = neighbours.iter().map(|&j| rest[j as usize] - xi).collect();
        Some(IsoOneRing { vertices, rest_edges, area })
    }

    /// The best-fit rotation R = argmin_R Σ_j ‖e_j − R e⁰_j‖² of the current one-ring.
    #[inline]
    pub fn rotation(&self, q: &[DVec3]) -> DMat3 {
        let qi = q[self.vertices[0] as usize];
        // S = Σ_j e_j e⁰_jᵀ, accumulated by columns: column c gets e_j · e⁰_j[c].
        let (mut s0, mut s1, mut s2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (&j, e0) in self.vertices[1..].iter().zip(&self.rest_edges) {
            let e = q[j as usize] - qi;
            s0 += e * e0.x;
            s1 += e * e0.y;
            s2 += e * e0.z;
        }
        nearest_rotation3(DMat3::from_cols(s0, s1, s2))
    }
}

impl Constraint for IsoOneRing {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        self.area
    }
    fn num_rows(&self) -> usize {
        self.rest_edges.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        let centre = self.vertices[0];
        for (row, &j) in self.vertices[1..].iter().enumerate() {
            sink.push(row, centre, -1.0);
            sink.push(row, j, 1.0);
        }
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let r = self.rotation(q);
        for (o, e0) in out.iter_mut().zip(&self.rest_edges) {
            *o = r * *e0;
        }
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        crate::constraints::kit::sets::isometry_residual(p, &self.rest_edges)
    }
}

/// Builds an [`IsoOneRing`] on every selected vertex with at least 2 neighbours (chosen by its
/// centre vertex; the neighbours need not be selected). No options. Default multiplier 100.
#[derive(Debug, Clone, Copy)]
pub struct IsoOneRingType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "isometric one-ring: the edges around each vertex move as rigidly as possible",
    options: &[],
    element: Element::Vertex,
    default_multiplier: 100.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for IsoOneRingType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        let built = rest
            .topology
            .one_rings
            .iter()
            .enumerate()
            .filter(|&(i, _)| ctx.selection.contains(i as u32))
            .filter_map(|(i, ring)| IsoOneRing::new(i as u32, ring, &rest.positions, rest.vertex_areas[i]))
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "vertices with two or more neighbours")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::linalg::nearest_rotation3_svd;
    use glam::DQuat;

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    /// A curved 6-ring around vertex 0 (bump height `h`), as positions and neighbour list.
    fn ring(h: f64) -> (Vec<DVec3>, Vec<u32>) {
        let mut p = vec![DVec3::new(0.0, 0.0, h)];
        for k in 0..6 {
            let t = k as f64 / 6.0 * std::f64::consts::TAU;
            p.push(DVec3::new(t.cos() * (1.0 + 0.1 * (k % 2) as f64), t.sin(), 0.0));
        }
        (p, (1..=6).collect())
    }

    fn project(c: &IsoOneRing, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; c.num_rows()];
        c.project(q, &mut out);
        out
    }

    fn assert_rotation(r: DMat3) {
        let e = r.transpose() * r - DMat3::IDENTITY;
        assert!(e.x_axis.length() + e.y_axis.length() + e.z_axis.length() < 1e-13, "RᵀR ≠ I: {r:?}");
        assert!((r.determinant() - 1.0).abs() < 1e-13, "det R = {}", r.determinant());
    }

    #[test]
    fn rest_state_projects_to_itself() {
        for h in [0.0, 0.3] {
            let (p, nb) = ring(h);
            let c = IsoOneRing::new(0, &nb, &p, 0.7).unwrap();
            assert_eq!(c.element_weight(), 0.7);
            assert_eq!(c.num_rows(), 6);
            assert!(c.energy(&p) < 1e-28, "h = {h}");
            let r = c.rotation(&p);
            assert!((r - DMat3::IDENTITY).abs().to_cols_array().iter().all(|x| *x < 1e-14));
        }
    }

    #[test]
    fn rows_are_edges_with_zero_sums() {
        let mut rng = Rng(41);
        let (p, nb) = ring(0.2);
        let c = IsoOneRing::new(0, &nb, &p, 1.0).unwrap();
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        for row in 0..6 {
            let sum: f64 = sink.entries.iter().filter(|e| e.row == row).map(|e| e.coeff).sum();
            assert_eq!(sum, 0.0);
        }
        let q: Vec<DVec3> = (0..7).map(|_| rng.vec3()).collect();
        let edges: Vec<DVec3> = nb.iter().map(|&j| q[j as usize] - q[0]).collect();
        assert!(dist2(&c.apply(&q), &edges) < 1e-28);
    }

    #[test]
    fn projection_is_a_rotation_of_the_rest_ring_and_no_sample_is_closer() {
        let mut rng = Rng(43);
        for h in [0.0, 0.05, 0.4] {
            let (p, nb) = ring(h);
            let c = IsoOneRing::new(0, &nb, &p, 1.0).unwrap();
            for trial in 0..60 {
                let q: Vec<DVec3> = match trial % 3 {
                    // deformed and rotated
                    0 => {
                        let r = rotation(&mut rng);
                        p.iter().map(|x| r * (*x + 0.2 * rng.vec3())).collect()
                    }
                    // mirrored (det S < 0)
                    1 => p.iter().map(|x| DVec3::new(x.x, -x.y, x.z) + 0.05 * rng.vec3()).collect(),
                    _ => p.iter().map(|_| rng.vec3()).collect(),
                };
                let r = c.rotation(&q);
                assert_rotation(r);
                let out = project(&c, &q);
                let want: Vec<DVec3> = c.rest_edges.iter().map(|e| r * *e).collect();
                assert!(dist2(&out, &want) < 1e-28);
                // The same rotation as the SVD formula where it is unique.
                assert!(
                    (r - nearest_rotation3_svd(DMat3::from_cols(
                        c.rest_edges.iter().zip(&nb).map(|(e0, &j)| (q[j as usize] - q[0]) * e0.x).sum(),
                        c.rest_edges.iter().zip(&nb).map(|(e0, &j)| (q[j as usize] - q[0]) * e0.y).sum(),
                        c.rest_edges.iter().zip(&nb).map(|(e0, &j)| (q[j as usize] - q[0]) * e0.z).sum(),
                    )))
                    .abs()
                    .to_cols_array()
                    .iter()
                    .all(|x| *x < 1e-9)
                );
                let cq = c.apply(&q);
                let d = dist2(&cq, &out);
                let set_point = |rot: DMat3| -> Vec<DVec3> { c.rest_edges.iter().map(|e| rot * *e).collect() };
                for _ in 0..300 {
                    assert!(d <= dist2(&cq, &set_point(rotation(&mut rng))) + 1e-12, "a random rotation is closer");
                    let near = r * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
                    assert!(d <= dist2(&cq, &set_point(near)) + 1e-12, "a nearby rotation is closer");
                }
            }
        }
    }

    #[test]
    fn rigid_motion_rotates_the_projection() {
        let mut rng = Rng(47);
        let (p, nb) = ring(0.1);
        let c = IsoOneRing::new(0, &nb, &p, 1.0).unwrap();
        for _ in 0..50 {
            let q: Vec<DVec3> = p.iter().map(|x| *x + 0.3 * rng.vec3()).collect();
            let (r, shift) = (rotation(&mut rng), rng.vec3());
            let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
            let rotated: Vec<DVec3> = project(&c, &q).iter().map(|x| r * *x).collect();
            assert!(dist2(&rotated, &project(&c, &moved)) < 1e-24);
        }
    }

    #[test]
    fn collapsed_ring_projects_to_a_finite_rotation() {
        let (p, nb) = ring(0.0);
        let c = IsoOneRing::new(0, &nb, &p, 1.0).unwrap();
        for q in [vec![DVec3::ONE; 7], p.iter().map(|x| DVec3::new(x.x, 0.0, 0.0)).collect()] {
            assert_rotation(c.rotation(&q));
            assert!(project(&c, &q).iter().all(|x| x.is_finite()));
        }
    }

    #[test]
    fn build_chooses_centres_with_two_neighbours_and_takes_no_options() {
        let (mut p, _) = ring(0.1);
        p.push(DVec3::new(5.0, 5.0, 5.0)); // vertex 7: in no triangle
        let triangles: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        let rest = RestGeometry::new(p, triangles, vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 7, "every vertex but the isolated one");
        let centre = built.iter().find(|c| c.vertices()[0] == 0).unwrap();
        assert_eq!(centre.num_rows(), 6);
        assert!((centre.element_weight() - rest.vertex_areas[0]).abs() < 1e-15);
        let sel = Selection::from_indices(8, &[0]);
        let one = build_constraints(
            KIND,
            &BuildContext { rest: &rest, selection: &sel, frame: &WorkingFrame::IDENTITY },
            Params::default(),
        )
        .unwrap();
        assert_eq!(one.len(), 1, "chosen by its centre only");
        let err = build_constraints(KIND, &ctx, Params::default().with("strain_freedom", 0.1)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let isolated = Selection::from_indices(8, &[7]);
        let err = build_constraints(
            KIND,
            &BuildContext { rest: &rest, selection: &isolated, frame: &WorkingFrame::IDENTITY },
            Params::default(),
        )
        .unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
