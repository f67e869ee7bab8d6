//! Bending: keeps the length of the mean-curvature normal at its rest value.
//!
//! Term: ω ‖H(q) − p‖² with H(q) = Σ_j (c_ij / A_i)(q_i − q_j) the cotan Laplacian of interior
//! vertex i (rest cotan weights c_ij and vertex area A_i), ω = 0.01 A_i, and
//! p = ‖H⁰‖ H/‖H‖ (H⁰ = H(x⁰)); if ‖H‖ ≤ 1e-12 ‖H⁰‖ (no reliable direction), p = ‖H⁰‖ n̄ with
//! n̄ the normalized sum of the unit normals of i's triangles (H⁰'s direction where n̄ = 0 and
//! H = 0: a collapsed one-ring); p = 0 if ‖H⁰‖ ≤ 1e-14 Σ_j |c_ij/A_i| ‖x⁰_i − x⁰_j‖ (a flat rest
//! vertex: H⁰ is round-off of its terms). With flip prevention, p is negated when
//! sign(n̄·H) ≠ sign(n̄⁰·H⁰) and ‖H‖ > 1e-5 ‖H⁰‖. The thresholds are relative, so that the
//! constraint means the same at every scale (H is an inverse length).

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::options::OptionSpec;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::{RestGeometry, triangle_normal};
use glam::DVec3;
use crate::constraints::kit::laplacian_row::LaplacianRow;
use crate::constraints::options::OptionKind;


/// A rest vertex is flat when ‖H⁰‖ is at most this times the size of its terms,
/// Σ_j |c_ij/A_i| ‖x⁰_i − x⁰_j‖ (50 times their round-off).
const FLAT: f64 = 1e-14;
/// Below this times ‖H⁰‖, H has no reliable direction and p follows the normal instead (the
/// nearest point is then off by at most 4e-12 ‖H⁰‖² in squared distance: every direction is
/// nearly as near).
const NO_DIRECTION: f64 = 1e-12;
/// Flip prevention acts only on an H longer than this times ‖H⁰‖.
const FLIP_MIN: f64 = 1e-5;

/// Bending of one interior vertex.
#[derive(Debug, Clone)]
pub struct Bending {
    row: LaplacianRow,
    /// i's triangles, for the normal n̄.
    triangles: Vec<[u32; 3]>,
    /// ‖H⁰‖, 0 for a flat rest vertex.
    rest_norm: f64,
    /// H⁰/‖H⁰‖: the direction p takes when neither H nor n̄ has one.
    rest_direction: DVec3,
    /// sign(n̄⁰ · H⁰), for flip prevention.
    rest_sign: f64,
    prevent_flips: bool,
    weight: f64,
}

impl Bending {
    /// Bending of interior vertex `i` of the rest geometry.
    pub fn new(rest: &RestGeometry, i: usize, prevent_flips: bool) -> Self {
        let row = LaplacianRow::new(rest, i);
        let triangles: Vec<[u32; 3]> =
            rest.topology.vertex_triangles[i].iter().map(|&t| rest.triangles[t as usize]).collect();
        let h0 = row.apply(&rest.positions);
        let n0 = mean_normal(&triangles, &rest.positions);
        let x = &rest.positions;
        let terms: f64 =
            row.vertices.iter().zip(&row.coeffs).skip(1).map(|(&j, c)| c.abs() * (x[i] - x[j as usize]).length()).sum();
        let rest_norm = if h0.length() > FLAT * terms { h0.length() } else { 0.0 };
        Bending {
            row,
            triangles,
            rest_norm,
            rest_direction: h0.normalize_or(DVec3::Z),
            rest_sign: n0.dot(h0).signum(),
            prevent_flips,
            weight: 0.01 * rest.vertex_areas[i],
        }
    }
}

/// n̄: the normalized sum of the unit normals of `triangles` at positions `q`.
fn mean_normal(triangles: &[[u32; 3]], q: &[DVec3]) -> DVec3 {
    triangles
        .iter()
        .map(|t| triangle_normal(q[t[0] as usize], q[t[1] as usize], q[t[2] as usize]))
        .sum::<DVec3>()
        .normalize_or_zero()
}

impl Constraint for Bending {
    fn length_power(&self) -> i32 {
        // Rows: a mean-curvature normal.
        -1
    }
    fn kind(&self) -> &'static str {
        "bending"
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
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        if self.rest_norm == 0.0 {
            out[0] = DVec3::ZERO;
            return;
        }
        let h = self.row.apply(q);
        let length = h.length();
        let direction = if length <= NO_DIRECTION * self.rest_norm {
            // Every direction is (nearly) as near: the normal's is stable from one iteration to
            // the next; H's own, or the rest one, where the one-ring has no normal.
            let n = mean_normal(&self.triangles, q);
            if n != DVec3::ZERO {
                n
            } else if length > 0.0 {
                h / length
            } else {
                self.rest_direction
            }
        } else {
            h / length
        };
        let mut p = self.rest_norm * direction;
        if self.prevent_flips
            && length > FLIP_MIN * self.rest_norm
            && mean_normal(&self.triangles, q).dot(h).signum() != self.rest_sign
        {
            p = -p;
        }
        out[0] = p;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        (p[0].length() - self.rest_norm).abs()
    }
}

/// `prevent_flips`: keep the sign of the curvature normal.
const PREVENT_FLIPS: OptionSpec = OptionSpec {
    key: "prevent_flips",
    doc: "keep the curvature normal's side (no inversion of bumps); default false",
    kind: OptionKind::Bool { default: false },
};

/// Builds a [`Bending`] on every selected interior vertex. Option `prevent_flips` (default false).
#[derive(Debug, Clone, Copy)]
pub struct BendingType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: "bending",
    summary: "bending: each interior vertex keeps its mean curvature magnitude",
    options: &[PREVENT_FLIPS],
    element: Element::Vertex,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for BendingType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let prevent_flips = params.flag("bending", &PREVENT_FLIPS)?;
        let rest = ctx.rest;
        per_selected_vertex(ctx, "bending", "interior vertices", |i| {
            rest.topology.is_interior(i).then(|| Bending::new(rest, i, prevent_flips))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::constraints::kit::test_util::octahedron;
    use crate::constraints::kit::test_util::{Rng, dist2};

    #[test]
    fn projection_lies_on_sphere_of_rest_norm_and_is_closest() {
        let rest = octahedron();
        let c = Bending::new(&rest, 4, false);
        let mut rng = Rng(3);
        for _ in 0..30 {
            let q: Vec<DVec3> = rest.positions.iter().map(|&x| x + 0.3 * rng.vec3()).collect();
            let cq = c.apply(&q);
            let mut p = [DVec3::ZERO];
            c.project(&q, &mut p);
            assert!((p[0].length() - c.rest_norm).abs() < 1e-12);
            let d = dist2(&cq, &p);
            for _ in 0..200 {
                let s = rng.vec3().normalize() * c.rest_norm;
                assert!(d <= (cq[0] - s).length_squared() + 1e-12);
            }
        }
    }

    #[test]
    fn rest_state_has_zero_energy_and_rows_are_translation_invariant() {
        let rest = octahedron();
        let c = Bending::new(&rest, 0, true);
        assert!(c.energy(&rest.positions) < 1e-24);
        let shifted: Vec<DVec3> = rest.positions.iter().map(|&x| x + DVec3::new(3.0, -1.0, 2.0)).collect();
        assert!(c.energy(&shifted) < 1e-20);
    }

    #[test]
    fn flip_prevention_negates_an_inverted_curvature() {
        let rest = octahedron();
        let with = Bending::new(&rest, 4, true);
        let without = Bending::new(&rest, 4, false);
        // Push the apex through the equator: H points the other way relative to the normal.
        let mut q = rest.positions.clone();
        q[4] = DVec3::Z * -0.5;
        let (mut a, mut b) = ([DVec3::ZERO], [DVec3::ZERO]);
        with.project(&q, &mut a);
        without.project(&q, &mut b);
        assert!((a[0] + b[0]).length() < 1e-12, "{a:?} vs {b:?}");
    }

    #[test]
    fn vanishing_curvature_projects_along_the_normal() {
        let rest = octahedron();
        let c = Bending::new(&rest, 4, false);
        // Flatten the apex into the equator plane: H ≈ 0.
        let mut q = rest.positions.clone();
        q[4] = DVec3::ZERO;
        q[5] = DVec3::Z * -0.8;
        let mut p = [DVec3::ZERO];
        c.project(&q, &mut p);
        assert!((p[0].length() - c.rest_norm).abs() < 1e-12);
        assert!(p[0].is_finite());
    }
}
