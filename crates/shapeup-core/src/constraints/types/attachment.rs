//! Attachment: each selected vertex follows the nearest triangle of the pieces the selection
//! does not touch, as if rigidly fixed to it (an accessory, an eye, a fingernail or a garment
//! modelled as a separate piece moves with the body it sits on).
//!
//! Term, per selected vertex v: ω Σ_{i ∈ {a, b, c, v}} ‖(q_i − c) − R d⁰_i‖², where (a, b, c)
//! is the triangle nearest to x⁰_v at rest among the triangles (with area) of the pieces that
//! hold no selected vertex, c = (q_a + q_b + q_c + q_v)/4, d⁰_i the centred rest positions of
//! the four and R the rotation that minimizes it: the `rigid` term on {a, b, c, v}.
//!
//! - Why rigid on four points rather than a barycentric point plus a fixed offset: the offset
//!   of v from its triangle (a fingernail's thickness, an eye's depth) turns with the triangle,
//!   so a turned hand keeps its nails on; a fixed offset would not turn. v on the triangle
//!   (offset 0) is the barycentric attachment itself: R fits a, b, c and v keeps its rest
//!   barycentric coordinates.
//! - Rows of C (4, centred): q_i − (1/4) Σ_j q_j; projection: R = nearest rotation of
//!   S = Σ_i (q_i − c) d⁰_iᵀ (shape matching, Müller et al. 2005; ShapeOp's RigidConstraint),
//!   p_i = R d⁰_i. The set and residual are `rigid`'s.
//! - Pieces: vertices joined by triangles or tetrahedra. The surface followed is the rest
//!   triangles of the pieces with no selected vertex, found through parry3d's BVH (closest
//!   point on the surface; its triangle).
//! - ω = 1 per attached vertex; default multiplier 100, as `rigid`, so an attached piece
//!   follows rather than hangs back. The triangle's corners are pulled towards their rest
//!   shape too (a quarter each of the fit): near many attached vertices the body is locally
//!   stiffer.
//!
//! Sources: ShapeUp (Bouaziz et al. 2012) shape matching; attachment of separate pieces to a
//! host surface as in embedded deformation and skin binding (e.g. Sumner et al. 2007).

use crate::constraints::contract::{BuildContext, Constraint, ConstraintType, RowSink, TypeInfo};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::pieces::unselected_piece_triangles;
use crate::nearest::NearestTriangle;
use crate::constraints::kit::vertex_set::{ShapeMatch, push_centred_rows};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;

/// Name in scene files.
const KIND: &str = "attachment";

/// Vertex v kept rigidly fixed to triangle (a, b, c).
#[derive(Debug, Clone)]
pub struct Attachment {
    /// Over [a, b, c, v].
    shape: ShapeMatch,
}

impl Attachment {
    /// Attaches vertex `v` to `triangle` at their rest positions in `rest`; `None` when v is a
    /// corner of the triangle.
    pub fn new(v: u32, triangle: [u32; 3], rest: &[DVec3]) -> Option<Self> {
        (!triangle.contains(&v)).then(|| {
            let [a, b, c] = triangle;
            Attachment { shape: ShapeMatch::new(vec![a, b, c, v], rest) }
        })
    }

    /// The attached vertex.
    pub fn vertex(&self) -> u32 {
        self.shape.vertices[3]
    }

    /// The triangle it follows.
    pub fn triangle(&self) -> [u32; 3] {
        [self.shape.vertices[0], self.shape.vertices[1], self.shape.vertices[2]]
    }
}

impl Constraint for Attachment {
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
        4
    }
    fn rows(&self, sink: &mut RowSink) {
        push_centred_rows(&self.shape.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        self.shape.project_rigid(q, out);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        self.shape.residual(p, 1.0)
    }
}

/// Builds one [`Attachment`] per selected vertex, to the nearest triangle of the pieces with
/// no selected vertex. No options. Default multiplier 100.
#[derive(Debug, Clone, Copy)]
pub struct AttachmentType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "attachment: each selected vertex follows the nearest triangle of the pieces the selection does not touch, rigidly",
    options: &[],
    element: Element::PieceVertex,
    default_multiplier: 100.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for AttachmentType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        let selected = ctx.selection.vertex_list(rest.num_vertices());
        if selected.is_empty() {
            return Err(ConstraintError::NothingSelected { kind: KIND, element: "vertices" });
        }
        let host: Vec<[u32; 3]> = unselected_piece_triangles(rest, |v| ctx.selection.contains(v)).collect();
        let surface = (!host.is_empty()).then(|| NearestTriangle::new(&rest.positions, host)).flatten().ok_or_else(|| {
            ConstraintError::Invalid {
                kind: KIND,
                problem: "every piece with triangles has a selected vertex: select the pieces that follow, not the body they follow".into(),
            }
        })?;
        let built = selected
            .iter()
            .filter_map(|&v| Attachment::new(v, surface.nearest(rest.positions[v as usize]).0, &rest.positions))
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "vertices")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{GroupDescription, Selection, build_group};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use glam::{DMat3, DQuat};

    /// A 2×2 quad sheet in z = 0 (vertices 0..9) and a small triangle 0.1 above its middle
    /// quad (vertices 9, 10, 11): two pieces.
    fn sheet_and_flake() -> RestGeometry {
        let mut p = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                p.push(DVec3::new(i as f64, j as f64, 0.0));
            }
        }
        p.extend([DVec3::new(0.2, 0.2, 0.1), DVec3::new(0.8, 0.3, 0.1), DVec3::new(0.4, 0.7, 0.12)]);
        let at = |i: u32, j: u32| j * 3 + i;
        let mut t = Vec::new();
        for j in 0..2 {
            for i in 0..2 {
                t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        t.push([9, 10, 11]);
        RestGeometry::new(p, t, vec![])
    }

    fn attach(rest: &RestGeometry, vertices: &[usize]) -> Result<crate::solver::ConstraintGroup, String> {
        let d = GroupDescription::new(KIND, Selection::from_indices(rest.num_vertices(), vertices));
        build_group(&d, rest, &WorkingFrame::IDENTITY).map_err(|e| e.to_string())
    }

    #[test]
    fn each_selected_vertex_follows_the_nearest_triangle_of_the_unselected_pieces() {
        let rest = sheet_and_flake();
        let group = attach(&rest, &[9, 10, 11]).unwrap();
        assert_eq!(group.constraints.len(), 3);
        // Vertex 9 at (0.2, 0.2) is over triangle [0, 1, 4] (x > y half of the first quad);
        // 10 at (0.8, 0.3) too; 11 at (0.4, 0.7) over [0, 4, 3].
        let triangles: Vec<Vec<u32>> = group.constraints.iter().map(|c| c.vertices().to_vec()).collect();
        assert_eq!(triangles, vec![vec![0, 1, 4, 9], vec![0, 1, 4, 10], vec![0, 4, 3, 11]]);
        // The rest shape is on every set, and a rigid motion of everything keeps it there.
        let turn = DMat3::from_quat(DQuat::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 1.1));
        let moved: Vec<DVec3> = rest.positions.iter().map(|x| turn * *x + DVec3::new(3.0, 1.0, -2.0)).collect();
        for c in &group.constraints {
            assert!(c.energy(&rest.positions) < 1e-28);
            assert!(c.energy(&moved) < 1e-26);
        }
    }

    #[test]
    fn the_offset_turns_with_the_triangle_and_the_projection_is_the_nearest_rigid_copy() {
        let rest = sheet_and_flake();
        let c = Attachment::new(11, [0, 4, 3], &rest.positions).unwrap();
        // The triangle turned by 90° about x, v left where it was: the projection puts v at its
        // offset turned with the triangle.
        let turn = DMat3::from_rotation_x(std::f64::consts::FRAC_PI_2);
        let mut q = rest.positions.clone();
        for v in [0, 4, 3] {
            q[v] = turn * rest.positions[v];
        }
        let mut p = [DVec3::ZERO; 4];
        c.project(&q, &mut p);
        assert!(c.set_residual(&p) < 1e-13);
        let mut rng = Rng(7);
        let cq = c.apply(&q);
        let d = dist2(&cq, &p);
        for _ in 0..300 {
            let r = DMat3::from_quat(
                DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize(),
            );
            let copy: Vec<DVec3> = c.shape.rest.iter().map(|e| r * *e).collect();
            assert!(d <= dist2(&cq, &copy) + 1e-12, "a sampled rotation is closer");
        }
        // Solved with the triangle held turned: v lands at its turned rest offset.
        let mut system = crate::solver::System::new(rest.num_vertices(), crate::solver::SolverParams::default());
        system.add_group(attach(&rest, &[9, 10, 11]).unwrap()).unwrap();
        let held: Vec<usize> = (0..9).collect();
        let pin = GroupDescription {
            targets: Some(held.iter().map(|&v| (v as u32, turn * rest.positions[v])).collect()),
            ..GroupDescription::new("position", Selection::from_indices(12, &held))
        }
        .weight(1e6);
        system.add_group(build_group(&pin, &rest, &WorkingFrame::IDENTITY).unwrap()).unwrap();
        let mut x = rest.positions.clone();
        system.solve(&mut x, 500, 0.0).unwrap();
        for (v, (got, rest)) in x.iter().zip(&rest.positions).enumerate().skip(9) {
            let want = turn * *rest;
            assert!((*got - want).length() < 1e-4, "vertex {v} at {got} where {want} is its turned place");
        }
    }

    #[test]
    fn a_selection_touching_every_piece_or_nothing_is_refused_in_one_line() {
        let rest = sheet_and_flake();
        let e = attach(&rest, &[0, 9]).unwrap_err();
        assert!(e.contains("attachment") && e.contains("every piece") && !e.contains('\n'), "{e}");
        let e = attach(&rest, &[]).unwrap_err();
        assert!(e.contains("attachment"), "{e}");
        // Part of one piece: its vertices follow the other piece.
        let group = attach(&rest, &[9]).unwrap();
        assert_eq!(group.constraints[0].vertices(), &[0, 1, 4, 9]);
        // The sheet's vertices may follow the flake instead.
        let group = attach(&rest, &[4]).unwrap();
        assert_eq!(group.constraints[0].vertices(), &[9, 10, 11, 4]);
    }
}
