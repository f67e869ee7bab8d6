//! Edge spring: keeps an edge at its rest length.
//!
//! Term: ω ‖(q_j − q_i) − p‖² with p = L⁰ (q_j − q_i) / ‖q_j − q_i‖ (the rest edge vector
//! x⁰_j − x⁰_i when the current edge is at most 1e-12 L⁰ long: it has no reliable direction,
//! and every point of the sphere is nearly as near), ω = L⁰ the rest length.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;

/// Shortest rest edge that gets a spring (shorter ones are skipped).
const MIN_REST_LENGTH: f64 = 1e-12;
/// A current edge at most this times L⁰ long has no reliable direction: p is the rest edge. A
/// relative bound, so that the projection is the nearest point at every scale (an absolute one
/// took the rest edge for every edge of a mesh 1e-12 across).
const NO_DIRECTION: f64 = 1e-12;

/// A spring on edge (i, j).
#[derive(Debug, Clone)]
pub struct EdgeSpring {
    vertices: [u32; 2],
    rest_edge: DVec3,
    rest_length: f64,
}

impl EdgeSpring {
    /// A spring on edge (i, j) of the rest shape `rest`; `None` if its rest length is ≤ 1e-12.
    pub fn new(i: u32, j: u32, rest: &[DVec3]) -> Option<Self> {
        let rest_edge = rest[j as usize] - rest[i as usize];
        let rest_length = rest_edge.length();
        (rest_length > MIN_REST_LENGTH).then_some(EdgeSpring { vertices: [i, j], rest_edge, rest_length })
    }
}

impl Constraint for EdgeSpring {
    fn kind(&self) -> &'static str {
        "edge_spring"
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        self.rest_length
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        sink.push(0, self.vertices[0], -1.0);
        sink.push(0, self.vertices[1], 1.0);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let e = q[self.vertices[1] as usize] - q[self.vertices[0] as usize];
        let length = e.length();
        out[0] =
            if length <= NO_DIRECTION * self.rest_length { self.rest_edge } else { e * (self.rest_length / length) };
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        (p[0].length() - self.rest_length).abs()
    }
}

/// Builds an [`EdgeSpring`] on every mesh edge whose two vertices are selected.
#[derive(Debug, Clone, Copy)]
pub struct EdgeSpringType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: "edge_spring",
    summary: "edge springs: every edge keeps its rest length",
    options: &[],
    element: Element::Edge,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for EdgeSpringType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = &ctx.rest.positions;
        // A volume is held by all the edges of its tetrahedra, not only its surface's.
        let tet_edges;
        let edges = if ctx.rest.tetrahedra.is_empty() {
            &ctx.rest.topology.edges
        } else {
            tet_edges = crate::topology::tetrahedron_edges(&ctx.rest.tetrahedra);
            &tet_edges
        };
        let built = edges
            .iter()
            .filter(|e| ctx.selection.contains_all(&e[..]))
            .filter_map(|e| EdgeSpring::new(e[0], e[1], rest))
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .collect();
        non_empty(built, "edge_spring", "edges")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};

    #[test]
    fn projection_has_rest_length_and_is_closest_on_sampled_sphere() {
        let rest = [DVec3::ZERO, DVec3::new(0.3, 0.4, 0.0)];
        let c = EdgeSpring::new(0, 1, &rest).unwrap();
        assert_eq!(c.element_weight(), 0.5);
        let mut rng = Rng(7);
        for _ in 0..50 {
            let q = [rng.vec3(), rng.vec3()];
            let cq = c.apply(&q);
            let mut p = [DVec3::ZERO];
            c.project(&q, &mut p);
            assert!((p[0].length() - 0.5).abs() < 1e-14, "on the set: length L⁰");
            let d = dist2(&cq, &p);
            for _ in 0..200 {
                let sample = rng.vec3().normalize() * 0.5;
                assert!(d <= (cq[0] - sample).length_squared() + 1e-14, "no sample of the set is closer");
            }
        }
    }

    #[test]
    fn collapsed_edge_projects_to_rest_edge() {
        let rest = [DVec3::ZERO, DVec3::X];
        let c = EdgeSpring::new(0, 1, &rest).unwrap();
        let mut p = [DVec3::ZERO];
        c.project(&[DVec3::ONE, DVec3::ONE], &mut p);
        assert_eq!(p[0], DVec3::X);
    }

    #[test]
    fn zero_length_rest_edge_is_skipped() {
        assert!(EdgeSpring::new(0, 1, &[DVec3::ONE, DVec3::ONE]).is_none());
    }
}
