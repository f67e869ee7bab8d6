//! Uniform Laplacian (fairing): drives the umbrella vector of each vertex to zero.
//!
//! Term: ω ‖L_i q − p‖² with the uniform ("umbrella") Laplacian of vertex i with k ≥ 1
//! neighbours j ∈ N(i),
//!
//!   L_i q = q_i − (1/k) Σ_{j ∈ N(i)} q_j      (1 row: coefficient 1 on i, −1/k on each j),
//!
//! the projection p = 0 (the set is {0}), and ω = 1.
//!
//! Source: ShapeOp's `UniformLaplacianConstraint` with `displacement = false` (Deuss et al.,
//! "ShapeOp — a robust and extensible geometric modelling paradigm", 2015), in the ShapeUp
//! local-global framework (Bouaziz et al., SGP 2012).
//!
//! Choices, and why:
//! - Uniform weights, not cotan ones (that is `smoothing`): the umbrella operator depends on
//!   connectivity only, so it also regularizes the tangential distribution of vertices (fairing
//!   evens out the mesh), which a cotan Laplacian does not; and it needs no interior vertex: a
//!   boundary vertex's umbrella pulls it towards its neighbours' centroid, as in ShapeOp.
//! - ω = 1, as ShapeOp's weight (the group multiplier g scales it): no area factor, so every
//!   vertex counts the same whatever the local resolution, which is what fairing of the vertex
//!   distribution wants.
//! - N(i) is the one-ring of the triangles (`topology.one_rings`); for a tetrahedral mesh that is
//!   its boundary surface, so interior tet vertices get no constraint.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::RestGeometry;
use glam::DVec3;
use crate::constraints::kit::laplacian_row::UniformLaplacianRow;

/// Name in scene files.
const KIND: &str = "laplacian";


/// The uniform Laplacian (fairing) constraint of one vertex.
#[derive(Debug, Clone)]
pub struct Laplacian {
    row: UniformLaplacianRow,
}

impl Laplacian {
    /// The constraint of vertex `i` of the rest geometry; `None` if `i` has no neighbour.
    pub fn new(rest: &RestGeometry, i: usize) -> Option<Self> {
        UniformLaplacianRow::new(rest, i).map(|row| Laplacian { row })
    }
}

impl Constraint for Laplacian {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.row.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        self.row.rows(sink, 0);
    }
    fn project(&self, _q: &[DVec3], out: &mut [DVec3]) {
        out[0] = DVec3::ZERO;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        p[0].length()
    }
}

/// Builds a [`Laplacian`] on every selected vertex with at least one neighbour (the
/// neighbours need not be selected). No options. Default multiplier 1.
#[derive(Debug, Clone, Copy)]
pub struct LaplacianType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "uniform Laplacian: fairs the selected vertices (each towards its neighbours' centroid)",
    options: &[],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for LaplacianType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        per_selected_vertex(ctx, KIND, "vertices with a neighbour", |i| Laplacian::new(rest, i))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::octahedron;
    use crate::constraints::kit::test_util::Rng;
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::WorkingFrame;

    #[test]
    fn the_row_is_the_umbrella_vector_and_the_projection_zero() {
        let rest = octahedron();
        let c = Laplacian::new(&rest, 4).unwrap();
        assert_eq!(c.element_weight(), 1.0);
        let mut rng = Rng(5);
        for _ in 0..20 {
            let q: Vec<DVec3> = rest.positions.iter().map(|&x| x + 0.3 * rng.vec3()).collect();
            let ring = &rest.topology.one_rings[4];
            let want = q[4] - ring.iter().map(|&j| q[j as usize]).sum::<DVec3>() / ring.len() as f64;
            assert!((c.apply(&q)[0] - want).length() < 1e-14);
            let mut p = [DVec3::ONE];
            c.project(&q, &mut p);
            assert_eq!(p[0], DVec3::ZERO);
            assert_eq!(c.set_residual(&p), 0.0);
            assert!((c.energy(&q) - want.length_squared()).abs() < 1e-14);
        }
        // The set is {0}: any other point is off it.
        assert!(c.set_residual(&[DVec3::X * 1e-3]) > 0.0);
        // Rows sum to zero (translation invariance).
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        assert!(sink.entries.iter().map(|e| e.coeff).sum::<f64>().abs() < 1e-15);
    }

    #[test]
    fn build_takes_every_vertex_with_a_neighbour_and_no_options() {
        let mut p = octahedron().positions;
        p.push(DVec3::splat(3.0)); // vertex 6: in no triangle
        let t = octahedron().triangles;
        let rest = RestGeometry::new(p, t, vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 6);
        let err = build_constraints(KIND, &ctx, Params::default().with("min", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let isolated = Selection::from_indices(7, &[6]);
        let ctx = BuildContext { rest: &rest, selection: &isolated, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
