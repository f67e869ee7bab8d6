//! Edge strain: keeps each edge's length within a band around its rest length (ShapeOp's
//! `EdgeStrainConstraint`, Deuss et al. 2015, "ShapeOp — a robust and extensible geometric
//! modelling paradigm"; the ShapeUp energy of Bouaziz et al. 2012).
//!
//! Term: ω ‖(q_j − q_i) − p‖² (one row, C q = q_j − q_i). Set: the vectors of length in
//! [max(1 − f, 0) L⁰, (1 + f) L⁰], f = `strain_freedom`. Projection (exact, the nearest point
//! of a spherical shell): p = e · clamp(‖e‖, lo, hi)/‖e‖ for e = q_j − q_i ≠ 0; for e = 0 every
//! point at distance lo is equally near and p = lo · (x⁰_j − x⁰_i)/L⁰ (the rest direction).
//! ω = L⁰, the rest length; rest edges of length ≤ 1e-12 get no constraint.
//!
//! Choice: ShapeOp takes a range [rangeMin, rangeMax] (default [1, 1]); here the band is
//! symmetric, f as in triangle and tet strain, with default f = 0.05 (±5 %) — f = 0 is
//! exactly an edge spring, so the type's point is the band. Elements are those of edge springs:
//! every mesh edge, or on a tet mesh every edge of its tetrahedra.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::sets::interval_distance;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;

/// Shortest rest edge that gets a constraint (shorter ones are skipped).
const MIN_REST_LENGTH: f64 = 1e-12;
/// Current edges shorter than this have no usable direction: the rest direction is taken.
const MIN_CURRENT_LENGTH: f64 = 1e-300;
/// Name in scene files.
const KIND: &str = "edge_strain";

/// `strain_freedom`: the band f of lengths [1 − f, 1 + f] L⁰.
const STRAIN_FREEDOM_OPTION: OptionSpec = OptionSpec {
    key: "strain_freedom",
    doc: "f ≥ 0: each edge's length stays in [1 − f, 1 + f] times its rest length; default 0.05",
    kind: OptionKind::Number { default: Some(0.05), min: 0.0, max: f64::MAX },
};

/// A strain-band constraint on edge (i, j).
#[derive(Debug, Clone)]
pub struct EdgeStrain {
    vertices: [u32; 2],
    rest_edge: DVec3,
    rest_length: f64,
    /// Shortest allowed length max(1 − f, 0) L⁰.
    lo: f64,
    /// Longest allowed length (1 + f) L⁰.
    hi: f64,
}

impl EdgeStrain {
    /// A constraint on edge (i, j) of the rest shape `rest` with strain freedom `f ≥ 0`;
    /// `None` if its rest length is ≤ 1e-12.
    pub fn new(i: u32, j: u32, rest: &[DVec3], strain_freedom: f64) -> Option<Self> {
        let rest_edge = rest[j as usize] - rest[i as usize];
        let rest_length = rest_edge.length();
        (rest_length > MIN_REST_LENGTH).then_some(EdgeStrain {
            vertices: [i, j],
            rest_edge,
            rest_length,
            lo: (1.0 - strain_freedom).max(0.0) * rest_length,
            hi: (1.0 + strain_freedom) * rest_length,
        })
    }

    /// The allowed lengths [lo, hi].
    pub fn range(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }
}

impl Constraint for EdgeStrain {
    fn kind(&self) -> &'static str {
        KIND
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
        out[0] = if length >= self.lo && length <= self.hi {
            e
        } else if length > MIN_CURRENT_LENGTH {
            e * (length.max(self.lo).min(self.hi) / length)
        } else {
            self.rest_edge * (self.lo / self.rest_length)
        };
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        interval_distance(p[0].length(), self.lo, self.hi)
    }
}

/// Builds an [`EdgeStrain`] on every edge whose two vertices are selected (the tetrahedra's
/// edges on a tet mesh). Option `strain_freedom` (number ≥ 0, default 0.05). Default
/// multiplier 10 (as edge springs).
#[derive(Debug, Clone, Copy)]
pub struct EdgeStrainType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "edge strain: every edge keeps its length within ±strain_freedom of its rest length",
    options: &[STRAIN_FREEDOM_OPTION],
    element: Element::Edge,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for EdgeStrainType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let f = params.number(KIND, &STRAIN_FREEDOM_OPTION)?.unwrap_or(0.05);
        let rest = &ctx.rest.positions;
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
            .filter_map(|e| EdgeStrain::new(e[0], e[1], rest, f))
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "edges")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};

    #[test]
    fn projection_is_on_the_shell_and_no_sample_is_closer() {
        let rest = [DVec3::ZERO, DVec3::new(0.3, 0.4, 0.0)];
        let mut rng = Rng(11);
        for f in [0.0, 0.05, 0.5, 1.5] {
            let c = EdgeStrain::new(0, 1, &rest, f).unwrap();
            assert_eq!(c.element_weight(), 0.5);
            let (lo, hi) = ((1.0 - f).max(0.0) * 0.5, (1.0 + f) * 0.5);
            assert_eq!(c.range(), (lo, hi));
            for _ in 0..100 {
                let q = [rng.vec3(), rng.vec3() * 1.5];
                let cq = c.apply(&q);
                let mut p = [DVec3::ZERO];
                c.project(&q, &mut p);
                let l = p[0].length();
                assert!(l >= lo - 1e-15 && l <= hi + 1e-15, "f = {f}: length {l}");
                assert!(c.set_residual(&p) <= 1e-15);
                let d = dist2(&cq, &p);
                for _ in 0..200 {
                    let r = lo + (hi - lo) * 0.5 * (1.0 + rng.uniform());
                    let sample = rng.vec3().normalize() * r;
                    assert!(d <= (cq[0] - sample).length_squared() + 1e-14, "f = {f}: a sample is closer");
                }
            }
        }
    }

    #[test]
    fn inside_the_band_is_unchanged_and_a_collapsed_edge_takes_the_rest_direction() {
        let rest = [DVec3::ZERO, DVec3::X];
        let c = EdgeStrain::new(0, 1, &rest, 0.1).unwrap();
        let mut p = [DVec3::ZERO];
        let q = [DVec3::ONE, DVec3::ONE + DVec3::new(0.0, 1.05, 0.0)];
        c.project(&q, &mut p);
        assert_eq!(p[0], q[1] - q[0]);
        c.project(&[DVec3::ONE, DVec3::ONE], &mut p);
        assert!((p[0] - DVec3::X * 0.9).length() < 1e-15);
        c.project(&[DVec3::ZERO, DVec3::Y * 3.0], &mut p);
        assert!((p[0] - DVec3::Y * 1.1).length() < 1e-15);
        assert!(EdgeStrain::new(0, 1, &[DVec3::ONE, DVec3::ONE], 0.1).is_none());
    }

    #[test]
    fn build_uses_tetrahedron_edges_and_checks_options() {
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let tets = RestGeometry::new(positions.clone(), vec![], vec![[0, 1, 2, 3]]);
        let ctx = BuildContext { rest: &tets, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 6);
        let surface = RestGeometry::new(positions, vec![[0, 1, 2]], vec![]);
        let ctx = BuildContext { rest: &surface, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default().with("strain_freedom", 0.2)).unwrap().len(), 3);
        let err = build_constraints(KIND, &ctx, Params::default().with("strain_freedom", -0.1)).unwrap_err();
        assert!(matches!(err, ConstraintError::BadOption { .. }) && err.to_string().contains("strain_freedom"));
        let err = build_constraints(KIND, &ctx, Params::default().with("stiffness", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let one = Selection::from_indices(4, &[0, 3]);
        let ctx = BuildContext { rest: &surface, selection: &one, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
