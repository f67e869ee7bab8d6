//! Smoothing: drives the cotan Laplacian of chosen interior vertices to zero.
//!
//! Term: ω ‖H(q)‖² with H(q) = Σ_j (c_ij / A_i)(q_i − q_j), p = 0, ω = 0.01 A_i.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::kit::laplacian_row::LaplacianRow;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::RestGeometry;
use glam::DVec3;

/// Smoothing of one interior vertex.
#[derive(Debug, Clone)]
pub struct Smoothing {
    row: LaplacianRow,
    weight: f64,
}

impl Smoothing {
    /// Smoothing of interior vertex `i` of the rest geometry.
    pub fn new(rest: &RestGeometry, i: usize) -> Self {
        Smoothing { row: LaplacianRow::new(rest, i), weight: 0.01 * rest.vertex_areas[i] }
    }
}

impl Constraint for Smoothing {
    fn length_power(&self) -> i32 {
        // Rows: a mean-curvature normal.
        -1
    }
    fn kind(&self) -> &'static str {
        "smoothing"
    }
    fn vertices(&self) -> &[u32] {
        &self.row.vertices
    }
    fn element_weight(&self) -> f64 {
        self.weight
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        self.row.rows(sink);
    }
    fn project(&self, _q: &[DVec3], out: &mut [DVec3]) {
        out[0] = DVec3::ZERO;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        p[0].length()
    }
}

/// Builds a [`Smoothing`] on every selected interior vertex.
#[derive(Debug, Clone, Copy)]
pub struct SmoothingType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: "smoothing",
    summary: "smoothing: flattens the selected region (Laplacian to zero)",
    options: &[],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for SmoothingType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        per_selected_vertex(ctx, "smoothing", "interior vertices", |i| {
            rest.topology.is_interior(i).then(|| Smoothing::new(rest, i))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::kit::test_util::octahedron;

    #[test]
    fn energy_is_weighted_squared_laplacian() {
        let rest = octahedron();
        let c = Smoothing::new(&rest, 4);
        let h = c.row.apply(&rest.positions);
        assert!(h.length() > 0.1, "the apex is curved");
        assert!((c.energy(&rest.positions) - 0.01 * rest.vertex_areas[4] * h.length_squared()).abs() < 1e-14);
        // A vertex in the plane of its neighbours' centroid-weighted average has zero energy.
        let mut q = rest.positions.clone();
        q[4] = DVec3::ZERO;
        q[5] = DVec3::ZERO;
        let mut p = [DVec3::ONE];
        c.project(&q, &mut p);
        assert_eq!(p[0], DVec3::ZERO);
    }
}
