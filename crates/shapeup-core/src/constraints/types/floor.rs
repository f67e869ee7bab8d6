//! Floor: keeps vertices above the plane y = h.
//!
//! Term: ω ‖q_i − p‖² with p = q_i, except p_y = h + κ (h − q_{i,y}) when q_{i,y} < h (push
//! κ ≥ 0, default 0: the closest point of the half-space y ≥ h). ω = 10 A_i on a surface, or
//! m_i / ρ = Σ_{T ∋ i} |V_T| / 4 on a tetrahedral mesh.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::options::OptionSpec;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::tet_volume;
use glam::DVec3;
use crate::constraints::options::OptionKind;

/// How far below the lowest rest vertex the default floor lies, in working units (the mesh's
/// radius is 0.5 there, so 1 % of it).
pub const DEFAULT_FLOOR_GAP: f64 = 0.005;

/// A floor under one vertex.
#[derive(Debug, Clone)]
pub struct Floor {
    vertex: [u32; 1],
    height: f64,
    push: f64,
    weight: f64,
}

impl Floor {
    /// Keeps vertex `i` above y = `height` (working frame) with push `push` and weight `weight`.
    pub fn new(i: u32, height: f64, push: f64, weight: f64) -> Self {
        Floor { vertex: [i], height, push, weight }
    }
}

impl Constraint for Floor {
    fn kind(&self) -> &'static str {
        "floor"
    }
    fn vertices(&self) -> &[u32] {
        &self.vertex
    }
    fn element_weight(&self) -> f64 {
        self.weight
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        sink.push(0, self.vertex[0], 1.0);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let mut p = q[self.vertex[0] as usize];
        if p.y < self.height {
            p.y = self.height + self.push * (self.height - p.y);
        }
        out[0] = p;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        (self.height - p[0].y).max(0.0)
    }
}

/// `height`: the floor's height (input frame).
const HEIGHT: OptionSpec = OptionSpec {
    key: "height",
    doc: "the floor's height y (input units); default just below the lowest vertex",
    kind: OptionKind::Number { default: None, min: -f64::MAX, max: f64::MAX },
};
/// `push`: over-projection κ.
const PUSH: OptionSpec = OptionSpec {
    key: "push",
    doc: "κ ≥ 0: a vertex below the floor is pushed κ times its depth above it; default 0",
    kind: OptionKind::Number { default: Some(0.0), min: 0.0, max: f64::MAX },
};

/// Builds a [`Floor`] under every selected vertex of a triangle or tetrahedron. Options:
/// `height` (input frame; default: just below the lowest vertex) and `push` (κ ≥ 0, default 0).
#[derive(Debug, Clone, Copy)]
pub struct FloorType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: "floor",
    summary: "floor: vertices stay above the plane y = height",
    options: &[HEIGHT, PUSH],
    element: Element::Vertex,
    // A floor must win against the shape and, in dynamic mode, against inertia and the
    // weight of the body resting on the few vertices in contact (m/h² ≈ 3600 m at 60 steps/s
    // vs k·g·ω = 100·g·m). Measured: a falling box sinks < 1 % of its height at 1e3; Spot on
    // its hooves sinks 4.5 cm at 1e4 and 1.7 cm at 1e5 (of 1.7 m). Stiffer floors slow the
    // convergence of everything else, as the floor term holds every vertex it covers.
    default_multiplier: 1e4,
    has_targets: false,
    rigidly_invariant: false,
};

impl ConstraintType for FloorType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = ctx.rest;
        let lowest = rest.positions.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let default_input = ctx.frame.to_input(DVec3::new(0.0, lowest - DEFAULT_FLOOR_GAP, 0.0)).y;
        let height_input = params.number("floor", &HEIGHT)?.unwrap_or(default_input);
        let height = ctx.frame.to_working(DVec3::new(0.0, height_input, 0.0)).y;
        let push = params.number("floor", &PUSH)?.unwrap_or(0.0);
        let weights = floor_weights(ctx);
        per_selected_vertex(ctx, "floor", "vertices of a triangle or tetrahedron", |i| {
            (weights[i] > 0.0).then(|| Floor::new(i as u32, height, push, weights[i]))
        })
    }
}

/// ω per vertex: Σ_{T ∋ i} |V_T| / 4 on a tetrahedral mesh, else 10 A_i for vertices in a
/// triangle; 0 for a vertex in no element.
fn floor_weights(ctx: &BuildContext) -> Vec<f64> {
    let rest = ctx.rest;
    let mut w = vec![0.0; rest.num_vertices()];
    if rest.tetrahedra.is_empty() {
        for (i, wi) in w.iter_mut().enumerate() {
            if rest.topology.in_triangle[i] {
                *wi = 10.0 * rest.vertex_areas[i];
            }
        }
    } else {
        for t in &rest.tetrahedra {
            let p = t.map(|v| rest.positions[v as usize]);
            let v = tet_volume(p[0], p[1], p[2], p[3]).abs();
            for &i in t {
                w[i as usize] += v / 4.0;
            }
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::kit::test_util::Rng;

    #[test]
    fn projection_is_closest_point_of_half_space() {
        let c = Floor::new(0, -0.2, 0.0, 1.0);
        let mut rng = Rng(11);
        for _ in 0..100 {
            let q = [rng.vec3()];
            let mut p = [DVec3::ZERO];
            c.project(&q, &mut p);
            assert!(p[0].y >= -0.2 - 1e-15, "on the set");
            let d = (q[0] - p[0]).length_squared();
            for _ in 0..100 {
                let mut s = rng.vec3();
                s.y = s.y.abs() - 0.2; // a sample of y ≥ -0.2
                assert!(d <= (q[0] - s).length_squared() + 1e-15);
            }
        }
    }

    #[test]
    fn push_reflects_penetration() {
        let c = Floor::new(0, 0.0, 0.5, 1.0);
        let mut p = [DVec3::ZERO];
        c.project(&[DVec3::new(1.0, -0.2, 3.0)], &mut p);
        assert!((p[0] - DVec3::new(1.0, 0.1, 3.0)).length() < 1e-15);
    }
}
