//! Force: a constant load on each selected vertex (static mode: form finding, a loaded net).
//!
//! Term: no projective rows (k = 0, C and p empty); the constraint is a [`Load`]: for vertex v
//! with the force f (working frame) and rest position x⁰_v, E gains
//!
//!   −2 g f · (q_v − x⁰_v)
//!
//! (g the group multiplier), the potential of a constant force in the factor-2 convention of
//! E = Σ w ‖C q − p‖² (a spring ½k‖Δ‖² − f·Δ, doubled), so that the global step's right-hand
//! side gains g f at v, as ShapeOp's `Solver::setForces` does (math reference, "Forces"). The
//! minimum balances the force with the constraints: Σ_i w_i C_iᵀ(C_i q − p_i) = g f per vertex.
//! ω = 1 (it multiplies nothing: there are no rows).
//!
//! Option `force`: the vector [x, y, z] in input units (default [0, −1, 0]), converted with
//! `frame.force_to_working`: multiplied by the working frame's scale, or, in a scene with a
//! material, in newtons and unchanged.
//!
//! Sources: ShapeOp's external forces (Deuss et al. 2015), in the ShapeUp solver (Bouaziz et
//! al. 2012).
//!
//! Choices, and why:
//! - A force scales as a length. Every projective term is a squared length (ω‖C q − p‖²) and
//!   the load's term is f times a length, so the balance f ↔ w (C q − p) holds in the same
//!   units only if f scales like a length. Converting it as a vector (× the working scale)
//!   makes a scene mean the same for a mesh in millimetres or metres: the same mesh, force and
//!   weights give the same shape in both, up to the unit.
//! - One constraint per selected vertex (an [`Element::Vertex`] type). The solver's unknowns
//!   are the vertices some row touches: a vertex that only a load touches is not solved, so its
//!   force moves nothing and its potential stays 0 (a load alone solves to "nothing moves").
//! - The force is a vector option, so rotating a scene rotates it with the mesh (the shared
//!   rigid-motion test turns it).
//! - Loads make E negative: E is bounded below only if the rows anchor every loaded piece (a
//!   position group, a hard handle); a loaded piece of shape terms that nothing anchors is the
//!   solver's singular-system error (`SolveError::Unanchored`), as for any unanchored piece.
//! - In dynamic mode the objective's constraint terms carry the stiffness k (the inertia is
//!   m/(k h²)), and the simulation multiplies every load by 1/k (`System::set_load_scale`), so
//!   a force acts there as the physical force g f. In a scene with a material it is in newtons.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
pub use crate::constraints::kit::load::Force;

/// Name in scene files.
const KIND: &str = "force";

/// `force`: the force on each vertex, input units.
const FORCE: OptionSpec = OptionSpec {
    key: "force",
    doc: "the force on each selected vertex [x, y, z]: newtons with a [material], else input units (scaled like lengths); default [0, -1, 0]",
    kind: OptionKind::Vector { default: [0.0, -1.0, 0.0] },
};

/// Builds a [`Force`] on every selected vertex. Option `force` (input units, default
/// [0, −1, 0]). Default multiplier 1.
#[derive(Debug, Clone, Copy)]
pub struct ForceType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "force: a constant force on each selected vertex (static loads, form finding)",
    options: &[FORCE],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for ForceType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let force = ctx.frame.force_to_working(params.vector(KIND, &FORCE)?);
        let rest = &ctx.rest.positions;
        let built = (0..rest.len() as u32)
            .filter(|&v| ctx.selection.contains(v))
            .map(|v| Box::new(Force::new(v, force, rest[v as usize])) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "vertices")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::contract::RowSink;
    use glam::DVec3;
    use crate::constraints::kit::test_util::octahedron;
    use crate::constraints::{GroupDescription, Selection, build_constraints, build_group};
    use crate::geometry::WorkingFrame;
    use crate::solver::{SolveError, SolverParams, System};

    #[test]
    fn a_force_has_no_rows_and_its_load_is_the_work_potential() {
        let c = Force::new(3, DVec3::new(0.0, -2.0, 1.0), DVec3::new(1.0, 1.0, 1.0));
        assert_eq!((c.num_rows(), c.kind(), c.vertices()), (0, "force", &[3u32][..]));
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        assert!(sink.entries.is_empty());
        assert_eq!(c.set_residual(&[]), 0.0);
        assert!(c.set_residual(&[DVec3::X]) > 0.0);
        let mut q = vec![DVec3::ZERO; 4];
        q[3] = DVec3::new(1.0, 0.0, 2.0); // moved by (0, −1, 1): work f·Δ = 2 + 1
        let load = c.load().unwrap();
        assert!((load.energy(&q) + 2.0 * 3.0).abs() < 1e-14);
        assert_eq!(c.energy(&q), 0.0, "no projective part");
    }

    #[test]
    fn the_option_is_in_input_units_and_scales_like_a_length() {
        let rest = octahedron();
        let frame = WorkingFrame { center: DVec3::new(5.0, 0.0, 0.0), scale: 0.001, physical: false };
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &frame };
        let built = build_constraints(KIND, &ctx, Params::default().with("force", vec![0.0, 0.0, 2000.0])).unwrap();
        assert_eq!(built.len(), 6);
        for c in &built {
            let load = c.load().unwrap();
            assert!((load.forces[0] - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-12);
            assert_eq!(load.rest[0], rest.positions[load.vertices[0] as usize]);
        }
        let default = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert!((default[0].load().unwrap().forces[0] - DVec3::new(0.0, -0.001, 0.0)).length() < 1e-15);
        for bad in [serde_json::json!([1.0, 2.0]), serde_json::json!("down"), serde_json::json!(3.0)] {
            let err = build_constraints(KIND, &ctx, Params::default().with("force", bad)).unwrap_err();
            assert!(err.to_string().contains("force"), "{err}");
        }
    }

    #[test]
    fn a_loaded_piece_that_nothing_anchors_is_a_singular_system_not_nan() {
        // The octahedron under a force with translation-invariant shape terms only: nothing
        // holds it, so the load would carry it away.
        let rest = octahedron();
        let frame = WorkingFrame::IDENTITY;
        for shape in ["edge_spring", "laplacian", "hinge_bending"] {
            let mut system = System::new(rest.num_vertices(), SolverParams::default());
            system
                .add_group(build_group(&GroupDescription::new(shape, Selection::All), &rest, &frame).unwrap())
                .unwrap();
            system
                .add_group(build_group(&GroupDescription::new(KIND, Selection::All), &rest, &frame).unwrap())
                .unwrap();
            let mut q = rest.positions.clone();
            let err = system.solve(&mut q, 10, 0.0).unwrap_err();
            assert!(matches!(err, SolveError::Unanchored { .. }), "{shape}: {err}");
            assert!(err.to_string().starts_with("singular system"), "{err}");
            assert!(q.iter().all(|p| p.is_finite()));
        }
    }
}
