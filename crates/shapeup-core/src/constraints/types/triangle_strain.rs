//! Triangle strain: keeps each triangle's deformation gradient a rotation (or within a band of
//! stretch around one).
//!
//! Term: ω ‖T − p‖²_F with T = [q_b − q_a, q_c − q_a] D⁻¹ (3×2, its two columns are the two
//! rows of C q), D = P⁰ᵀ[x⁰_b − x⁰_a, x⁰_c − x⁰_a] and P⁰ an orthonormal 3×2 basis of the rest
//! triangle's plane. Projection: thin SVD T = UΣVᵀ, p = U clamp(Σ, 1 − f, 1 + f) Vᵀ (f =
//! `strain_freedom`, default 0: the nearest matrix with orthonormal columns). ω = A_t, the rest
//! area; zero-area rest triangles get no constraint.
//!
//! The projection is computed in a frame P(q) of the current triangle (math reference, Notes):
//! T's columns lie in its plane, so p = P(q) proj₂(P(q)ᵀT) with the closed-form 2×2 kernels.
//! P(q) takes the current normal's orientation, so `det P(q)ᵀT ≥ 0` and the 2×2 polar factor
//! is a rotation: a triangle flipped in 3D projects to the nearest rotation in its own plane.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_element;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::{clamp_singular_values2, nearest_rotation2};
use glam::DVec3;
use crate::constraints::kit::gradient::TriangleGradient;
use crate::constraints::kit::options::{STRAIN_FREEDOM_OPTION, take_strain_freedom};

/// Name in scene files.
const KIND: &str = "triangle_strain";


/// A strain constraint on triangle (a, b, c).
#[derive(Debug, Clone)]
pub struct TriangleStrain {
    gradient: TriangleGradient,
    strain_freedom: f64,
}

impl TriangleStrain {
    /// A constraint on triangle (a, b, c) of the rest shape `rest` with strain freedom `f ≥ 0`;
    /// `None` if the rest triangle is degenerate ([`TriangleGradient::new`]).
    pub fn new(vertices: [u32; 3], rest: &[DVec3], strain_freedom: f64) -> Option<Self> {
        TriangleGradient::new(vertices, rest).map(|gradient| TriangleStrain { gradient, strain_freedom })
    }

    /// The strain freedom f.
    pub fn strain_freedom(&self) -> f64 {
        self.strain_freedom
    }
}

impl Constraint for TriangleStrain {
    fn length_power(&self) -> i32 {
        // Rows: the deformation gradient.
        0
    }
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.gradient.vertices
    }
    fn element_weight(&self) -> f64 {
        self.gradient.rest_area
    }
    fn num_rows(&self) -> usize {
        2
    }
    fn rows(&self, sink: &mut RowSink) {
        self.gradient.rows(sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let t = self.gradient.at(q);
        let frame = self.gradient.current_frame(&t);
        let m = TriangleGradient::in_frame(frame, &t);
        let f = self.strain_freedom;
        let p = if f == 0.0 { nearest_rotation2(m) } else { clamp_singular_values2(m, 1.0 - f, 1.0 + f) };
        TriangleGradient::out_of_frame(frame, p, out);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let f = self.strain_freedom;
        let s = crate::constraints::kit::sets::singular_values_3x2(p[0], p[1]);
        s.iter().map(|&x| crate::constraints::kit::sets::interval_distance(x, 1.0 - f, 1.0 + f)).fold(0.0, f64::max)
    }
}

/// Builds a [`TriangleStrain`] on every non-degenerate triangle whose three vertices are
/// selected. Option `strain_freedom` (number ≥ 0, default 0). Default multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct TriangleStrainType;


/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "triangle strain: each triangle stays a rotation of its rest shape (stretch within ±strain_freedom)",
    options: &[STRAIN_FREEDOM_OPTION],
    element: Element::Triangle,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for TriangleStrainType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let f = take_strain_freedom(KIND, params)?;
        let rest = &ctx.rest.positions;
        let selected = ctx.rest.triangles.iter().filter(|t| ctx.selection.contains_all(&t[..]));
        per_selected_element(selected, KIND, "triangles", |t| TriangleStrain::new(*t, rest, f))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use glam::{DMat2, DVec2};
    use crate::constraints::kit::options::STRAIN_FREEDOM;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use glam::{DMat3, DQuat};

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    fn rest_triangle() -> [DVec3; 3] {
        [DVec3::new(0.1, 0.2, -0.1), DVec3::new(0.5, 0.1, 0.0), DVec3::new(0.2, 0.6, 0.3)]
    }

    /// A 3×2 matrix (as 2 columns) with orthonormal columns, random.
    fn orthonormal_pair(rng: &mut Rng) -> [DVec3; 2] {
        let r = rotation(rng);
        [r.x_axis, r.y_axis]
    }

    /// W diag(s) Zᵀ: W 3×2 orthonormal columns, Z a 2×2 rotation or reflection, s in [lo, hi].
    fn sample_of_set(rng: &mut Rng, lo: f64, hi: f64, plane: Option<[DVec3; 2]>) -> [DVec3; 2] {
        let w = plane.unwrap_or_else(|| orthonormal_pair(rng));
        let s = [lo + (hi - lo) * 0.5 * (1.0 + rng.uniform()), lo + (hi - lo) * 0.5 * (1.0 + rng.uniform())];
        let z = DMat2::from_angle(4.0 * rng.uniform())
            * if rng.uniform() < 0.0 { DMat2::from_diagonal(DVec2::new(1.0, -1.0)) } else { DMat2::IDENTITY };
        // column k of W diag(s) Zᵀ = Σ_i w_i s_i Z[k][i]
        let col = |k: usize| w[0] * s[0] * z.col(0)[k] + w[1] * s[1] * z.col(1)[k];
        [col(0), col(1)]
    }

    /// Singular values of a 3×2 matrix given as columns (descending).
    fn singular_values(t: &[DVec3]) -> [f64; 2] {
        let (a, b, c) = (t[0].dot(t[0]), t[0].dot(t[1]), t[1].dot(t[1]));
        let h = (0.25 * (a - c) * (a - c) + b * b).sqrt();
        let m = 0.5 * (a + c);
        [(m + h).sqrt(), (m - h).max(0.0).sqrt()]
    }

    fn project(c: &TriangleStrain, q: &[DVec3]) -> Vec<DVec3> {
        let mut p = vec![DVec3::ZERO; 2];
        c.project(q, &mut p);
        p
    }

    #[test]
    fn rest_state_projects_to_itself() {
        let rest = rest_triangle();
        for f in [0.0, 0.2] {
            let c = TriangleStrain::new([0, 1, 2], &rest, f).unwrap();
            assert!(c.energy(&rest) < 1e-28);
            let t = c.apply(&rest);
            assert!(
                (t[0].length() - 1.0).abs() < 1e-14
                    && (t[1].length() - 1.0).abs() < 1e-14
                    && t[0].dot(t[1]).abs() < 1e-14
            );
        }
        let c = TriangleStrain::new([0, 1, 2], &rest, 0.0).unwrap();
        let area = 0.5 * (rest[1] - rest[0]).cross(rest[2] - rest[0]).length();
        assert!((c.element_weight() - area).abs() < 1e-15);
    }

    #[test]
    fn rows_have_zero_sums_and_match_the_deformation_gradient() {
        let mut rng = Rng(3);
        let rest = rest_triangle();
        let c = TriangleStrain::new([0, 1, 2], &rest, 0.0).unwrap();
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        for row in 0..2 {
            let sum: f64 = sink.entries.iter().filter(|e| e.row == row).map(|e| e.coeff).sum();
            assert!(sum.abs() < 1e-12, "row {row} sums to {sum}");
        }
        let q = [rng.vec3(), rng.vec3(), rng.vec3()];
        let shifted: Vec<DVec3> = q.iter().map(|x| *x + DVec3::new(3.0, -1.0, 2.0)).collect();
        assert!(dist2(&c.apply(&q), &c.gradient.at(&q)) < 1e-28);
        assert!(dist2(&c.apply(&q), &c.apply(&shifted)) < 1e-26, "translation invariant");
    }

    #[test]
    fn projection_is_on_the_set_and_no_sample_is_closer() {
        let mut rng = Rng(21);
        let rest = rest_triangle();
        for f in [0.0, 0.1, 0.5] {
            let (lo, hi) = (1.0 - f, 1.0 + f);
            let c = TriangleStrain::new([0, 1, 2], &rest, f).unwrap();
            for trial in 0..60 {
                let q: Vec<DVec3> = if trial % 3 == 0 {
                    // a mild deformation of the rest triangle, rotated
                    let r = rotation(&mut rng);
                    rest.iter().map(|x| r * (*x + 0.1 * rng.vec3())).collect()
                } else {
                    vec![rng.vec3(), rng.vec3(), rng.vec3()]
                };
                let cq = c.apply(&q);
                let p = project(&c, &q);
                let [s1, s2] = singular_values(&p);
                assert!(s1 <= hi + 1e-12 && s2 >= lo - 1e-12, "σ = ({s1}, {s2}) outside [{lo}, {hi}]");
                // p's columns lie in the current triangle's plane.
                let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize();
                assert!(p[0].dot(n).abs() < 1e-12 && p[1].dot(n).abs() < 1e-12);
                let d = dist2(&cq, &p);
                let plane = [(q[1] - q[0]).normalize(), n.cross((q[1] - q[0]).normalize())];
                for _ in 0..300 {
                    let general = sample_of_set(&mut rng, lo, hi, None);
                    assert!(d <= dist2(&cq, &general) + 1e-12, "f = {f}: a 3×2 sample is closer");
                    let in_plane = sample_of_set(&mut rng, lo, hi, Some(plane));
                    assert!(d <= dist2(&cq, &in_plane) + 1e-12, "f = {f}: an in-plane sample is closer");
                }
            }
        }
    }

    #[test]
    fn projection_matches_the_thin_svd_formula_computed_by_nalgebra() {
        let mut rng = Rng(57);
        let rest = rest_triangle();
        for f in [0.0, 0.15, 0.6] {
            let c = TriangleStrain::new([0, 1, 2], &rest, f).unwrap();
            for _ in 0..300 {
                let q = [rng.vec3(), rng.vec3(), rng.vec3()];
                let t = c.apply(&q);
                let m = nalgebra::Matrix3x2::new(t[0].x, t[1].x, t[0].y, t[1].y, t[0].z, t[1].z);
                let svd = m.svd(true, true);
                let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
                let s = svd.singular_values.map(|x| x.clamp(1.0 - f, 1.0 + f));
                let want = u * nalgebra::Matrix2::from_diagonal(&s) * vt;
                let p = project(&c, &q);
                let got = nalgebra::Matrix3x2::new(p[0].x, p[1].x, p[0].y, p[1].y, p[0].z, p[1].z);
                // nalgebra's 3×2 SVD goes through TᵀT: compare to its accuracy.
                let gap = svd.singular_values.min() / svd.singular_values.max();
                assert!((got - want).norm() < 1e-12 / gap.max(1e-4), "f = {f}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn within_bounds_is_unchanged_when_free() {
        let mut rng = Rng(8);
        let rest = rest_triangle();
        let c = TriangleStrain::new([0, 1, 2], &rest, 0.3).unwrap();
        for _ in 0..50 {
            // T = R · diag(s) · Z with s within [0.7, 1.3]: scale the rest shape anisotropically.
            let r = rotation(&mut rng);
            let (sx, sy) = (1.0 + 0.25 * rng.uniform(), 1.0 + 0.25 * rng.uniform());
            let (u, v, shift) = (c.gradient.rest_frame[0], c.gradient.rest_frame[1], rng.vec3());
            let q: Vec<DVec3> =
                rest.iter().map(|x| r * (u * (sx * u.dot(*x)) + v * (sy * v.dot(*x))) + shift).collect();
            let cq = c.apply(&q);
            assert!(dist2(&cq, &project(&c, &q)) < 1e-26);
        }
    }

    #[test]
    fn rigid_motion_rotates_the_projection() {
        let mut rng = Rng(13);
        let rest = rest_triangle();
        for f in [0.0, 0.25] {
            let c = TriangleStrain::new([0, 1, 2], &rest, f).unwrap();
            for _ in 0..30 {
                let q = [rng.vec3(), rng.vec3(), rng.vec3()];
                let (r, shift) = (rotation(&mut rng), rng.vec3());
                let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
                let p: Vec<DVec3> = project(&c, &q).iter().map(|x| r * *x).collect();
                assert!(dist2(&p, &project(&c, &moved)) < 1e-24);
            }
        }
    }

    #[test]
    fn flipped_triangle_projects_to_a_rotation_in_its_plane() {
        let rest = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let c = TriangleStrain::new([0, 1, 2], &rest, 0.0).unwrap();
        // Mirrored in its plane: b and c swap places.
        let q = [DVec3::ZERO, DVec3::Y, DVec3::X];
        let p = project(&c, &q);
        // Swapping b and c is a reflection in the plane, i.e. a half turn about (1, 1, 0) in 3D.
        let half_turn = DMat3::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), std::f64::consts::PI);
        assert!(dist2(&p, &[half_turn * DVec3::X, half_turn * DVec3::Y]) < 1e-28, "{p:?}");
        // A flipped, squashed triangle: still orthonormal columns in the current plane.
        let q = [DVec3::ZERO, DVec3::new(0.3, 0.1, 0.2), DVec3::new(-0.1, -0.4, 0.5)];
        let q2 = [q[0], q[2], q[1]];
        for q in [q, q2] {
            let p = project(&c, &q);
            let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize();
            assert!((p[0].length() - 1.0).abs() < 1e-14 && (p[1].length() - 1.0).abs() < 1e-14);
            assert!(p[0].dot(p[1]).abs() < 1e-14 && p[0].dot(n).abs() < 1e-14 && p[1].dot(n).abs() < 1e-14);
            // Nearest among in-plane rotations of either orientation.
            let cq = c.apply(&q);
            let d = dist2(&cq, &p);
            let u = (q[1] - q[0]).normalize();
            for k in 0..360 {
                let a = k as f64 / 360.0 * std::f64::consts::TAU;
                let (x, y) = (u * a.cos() + n.cross(u) * a.sin(), n.cross(u) * a.cos() - u * a.sin());
                assert!(d <= dist2(&cq, &[x, y]) + 1e-13 && d <= dist2(&cq, &[x, -y]) + 1e-13);
            }
        }
    }

    #[test]
    fn collapsed_triangles_project_to_finite_points_of_the_set() {
        let rest = rest_triangle();
        for f in [0.0, 0.2, 2.0] {
            let c = TriangleStrain::new([0, 1, 2], &rest, f).unwrap();
            let cases = [
                [DVec3::ONE, DVec3::ONE, DVec3::ONE],                                    // a point
                [DVec3::ZERO, DVec3::X, DVec3::X * 2.0],                                 // a segment
                [DVec3::ZERO, DVec3::new(1.0, 1e-17, 0.0), DVec3::new(2.0, 0.0, 1e-18)], // nearly one
            ];
            for q in cases {
                let p = project(&c, &q);
                assert!(p.iter().all(|x| x.is_finite()), "{p:?}");
                let [s1, s2] = singular_values(&p);
                assert!(s1 <= 1.0 + f + 1e-12 && s2 >= (1.0 - f).max(0.0) - 1e-12, "f = {f}: ({s1}, {s2})");
            }
        }
    }

    #[test]
    fn build_skips_degenerate_triangles_and_checks_options() {
        let positions = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::Y,
            DVec3::new(2.0, 0.0, 0.0), // collinear with 0 and 1
            DVec3::new(1.0, 1.0, 0.0),
        ];
        let triangles = vec![[0, 1, 2], [0, 1, 3], [1, 4, 2]];
        let rest = RestGeometry::new(positions, triangles, vec![]);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 2, "the zero-area triangle is skipped");
        assert!(built.iter().all(|c| c.kind() == KIND && c.num_rows() == 2));
        let built = build_constraints(KIND, &ctx, Params::default().with(STRAIN_FREEDOM, 0.25)).unwrap();
        assert_eq!(built.len(), 2);
        let sel = Selection::from_indices(5, &[0, 1, 2]);
        let ctx_sel = BuildContext { rest: &rest, selection: &sel, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx_sel, Params::default()).unwrap().len(), 1);
        let err = build_constraints(KIND, &ctx, Params::default().with(STRAIN_FREEDOM, -0.1)).unwrap_err();
        assert!(matches!(err, ConstraintError::BadOption { .. }), "{err}");
        let err = build_constraints(KIND, &ctx, Params::default().with("stiffness", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let none = Selection::from_indices(5, &[0, 3]);
        let err = build_constraints(
            KIND,
            &BuildContext { rest: &rest, selection: &none, frame: &WorkingFrame::IDENTITY },
            Params::default(),
        )
        .unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
