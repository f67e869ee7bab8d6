//! Tetrahedral strain: keeps each tetrahedron's deformation gradient a rotation (or within a
//! band of stretch around one).
//!
//! Term: ω ‖T − p‖²_F with T = [q_b − q_a, q_c − q_a, q_d − q_a] D⁻¹ (its three columns are the
//! three rows of C q), D = [x⁰_b − x⁰_a, x⁰_c − x⁰_a, x⁰_d − x⁰_a]. Projection (math reference):
//! SVD T = UΣVᵀ, clamp σ to [1 − f, 1 + f], if det U · det V < 0 the smallest σ becomes
//! −max(1 − f, 0) (the band's lower end, with det p ≥ 0), p = UΣ'Vᵀ: the nearest point of
//! {P : σ(P) in the band, det P ≥ 0} (f = `strain_freedom`, default 0: the nearest rotation,
//! det +1 even for an inverted tetrahedron). ω = |V_T|, the rest volume; tetrahedra of volume
//! ≤ 1e-12 get no constraint.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_element;
use crate::constraints::kit::options::take_strain_freedom;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::{nearest_rotation3, svd3_rotations};
use glam::{DMat3, DVec3};
use crate::constraints::kit::gradient::TetGradient;
use crate::constraints::kit::options::STRAIN_FREEDOM_OPTION;

/// Name in scene files.
const KIND: &str = "tet_strain";


/// A strain constraint on tetrahedron (a, b, c, d).
#[derive(Debug, Clone)]
pub struct TetStrain {
    gradient: TetGradient,
    strain_freedom: f64,
}

impl TetStrain {
    /// A constraint on tetrahedron (a, b, c, d) of the rest shape `rest` with strain freedom
    /// `f ≥ 0`; `None` if its rest volume |V_T| is ≤ 1e-12 ([`TetGradient::new`]).
    pub fn new(vertices: [u32; 4], rest: &[DVec3], strain_freedom: f64) -> Option<Self> {
        TetGradient::new(vertices, rest).map(|gradient| TetStrain { gradient, strain_freedom })
    }

    /// The strain freedom f.
    pub fn strain_freedom(&self) -> f64 {
        self.strain_freedom
    }
}

/// The projection with strain freedom `f > 0`: the nearest point of the set
/// {P : every σ(P) ∈ [1 − f, 1 + f], det P ≥ 0}.
///
/// The set is invariant under P ↦ Q P R (Q, R rotations), so with the rotation-variant SVD
/// T = U diag(σ₁, σ₂, σ̃₃) Vᵀ (U, V rotations, σ̃₃ signed, |σ̃₃| ≤ σ₂ ≤ σ₁) its nearest point is
/// U diag(d) Vᵀ for the nearest d to (σ₁, σ₂, σ̃₃) among vectors with every |dᵢ| in the band and
/// an even number of negative entries: `p = U diag(c(σ₁), c(σ₂), c⁺(σ̃₃)) Vᵀ`, with
/// c(σ) = min(max(σ, 1 − f), 1 + f) and c⁺ the same with the lower end at least 0. For an
/// inverted T (σ̃₃ < 0) that is the band's lower end, not c(|σ̃₃|) (reflecting σ̃₃, the "negate
/// the smallest singular value" of strain limiting, is farther once |σ̃₃| > 1 − f: |σ̃₃| +
/// c(|σ̃₃|) against |σ̃₃| + 1 − f), and negating two entries instead costs at least as much
/// since σ₂ ≥ |σ̃₃|. Shortcut: when
/// det T > 0 and every σ already lies in (1 − f, 1 + f) (tested without an SVD: `TᵀT − (1−f)²I`
/// and `(1+f)²I − TᵀT` positive definite), p = T.
#[inline]
fn clamp_strain(t: DMat3, f: f64) -> DMat3 {
    let (lo, hi) = (1.0 - f, 1.0 + f);
    let c = t.transpose() * t;
    let lo2 = lo.max(0.0) * lo.max(0.0);
    if t.determinant() > 0.0
        && positive_definite(c - DMat3::from_diagonal(DVec3::splat(lo2)))
        && positive_definite(DMat3::from_diagonal(DVec3::splat(hi * hi)) - c)
    {
        return t;
    }
    let svd = svd3_rotations(t);
    let clamp = |s: f64| s.max(lo).min(hi);
    let sigma = DVec3::new(clamp(svd.sigma.x), clamp(svd.sigma.y), svd.sigma.z.max(lo.max(0.0)).min(hi));
    svd.u * DMat3::from_diagonal(sigma) * svd.v.transpose()
}

/// Sylvester's criterion for a symmetric 3×3 matrix: all leading principal minors > 0.
#[inline]
fn positive_definite(m: DMat3) -> bool {
    let (a, b, d) = (m.x_axis.x, m.y_axis.x, m.y_axis.y);
    a > 0.0 && a * d - b * b > 0.0 && m.determinant() > 0.0
}

impl Constraint for TetStrain {
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
        self.gradient.rest_volume
    }
    fn num_rows(&self) -> usize {
        3
    }
    fn rows(&self, sink: &mut RowSink) {
        self.gradient.rows(sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let t = self.gradient.at(q);
        let p = if self.strain_freedom == 0.0 { nearest_rotation3(t) } else { clamp_strain(t, self.strain_freedom) };
        out[0] = p.x_axis;
        out[1] = p.y_axis;
        out[2] = p.z_axis;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let f = self.strain_freedom;
        crate::constraints::kit::sets::strain_band_residual(DMat3::from_cols(p[0], p[1], p[2]), 1.0 - f, 1.0 + f)
    }
}

/// Builds a [`TetStrain`] on every tetrahedron (of the rest geometry's `tetrahedra`) whose four
/// vertices are selected and whose rest volume is > 1e-12. Option `strain_freedom` (number ≥ 0,
/// default 0). Default multiplier 10 (as triangle strain).
#[derive(Debug, Clone, Copy)]
pub struct TetStrainType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "tetrahedral strain: each tetrahedron stays a rotation of its rest shape (stretch within ±strain_freedom)",
    options: &[STRAIN_FREEDOM_OPTION],
    element: Element::Tetrahedron,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for TetStrainType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let f = take_strain_freedom(KIND, params)?;
        let rest = &ctx.rest.positions;
        let selected = ctx.rest.tetrahedra.iter().filter(|t| ctx.selection.contains_all(&t[..]));
        per_selected_element(selected, KIND, "tetrahedra", |t| TetStrain::new(*t, rest, f))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::geometry::tet_volume;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::linalg::svd3;
    use glam::DQuat;

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    fn rest_tet() -> [DVec3; 4] {
        [DVec3::new(0.1, 0.0, -0.1), DVec3::new(0.5, 0.1, 0.0), DVec3::new(0.2, 0.6, 0.1), DVec3::new(0.2, 0.3, 0.4)]
    }

    fn cols(m: DMat3) -> [DVec3; 3] {
        [m.x_axis, m.y_axis, m.z_axis]
    }

    fn project(c: &TetStrain, q: &[DVec3]) -> DMat3 {
        let mut p = [DVec3::ZERO; 3];
        c.project(q, &mut p);
        DMat3::from_cols(p[0], p[1], p[2])
    }

    /// Current positions whose deformation gradient is `t` (a at the origin).
    fn positions_for(rest: &[DVec3; 4], t: DMat3) -> Vec<DVec3> {
        rest.iter().map(|x| t * (*x - rest[0])).collect()
    }

    fn assert_on_set(p: DMat3, f: f64) {
        let svd = svd3(p);
        assert!(p.determinant() > 0.0, "det p = {}", p.determinant());
        let (lo, hi) = ((1.0 - f).max(0.0), 1.0 + f);
        for s in svd.sigma.to_array() {
            assert!(s >= lo - 1e-12 && s <= hi + 1e-12, "σ = {s} outside [{lo}, {hi}]");
        }
    }

    #[test]
    fn rest_state_projects_to_itself() {
        let rest = rest_tet();
        let mut flipped = rest;
        flipped.swap(1, 2);
        for r in [rest, flipped] {
            for f in [0.0, 0.2] {
                let c = TetStrain::new([0, 1, 2, 3], &r, f).unwrap();
                assert!(c.energy(&r) < 1e-28);
                assert!((c.element_weight() - tet_volume(r[0], r[1], r[2], r[3]).abs()).abs() < 1e-16);
            }
        }
    }

    #[test]
    fn rows_have_zero_sums_and_match_the_deformation_gradient() {
        let mut rng = Rng(5);
        let rest = rest_tet();
        let c = TetStrain::new([0, 1, 2, 3], &rest, 0.0).unwrap();
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        for row in 0..3 {
            let sum: f64 = sink.entries.iter().filter(|e| e.row == row).map(|e| e.coeff).sum();
            assert!(sum.abs() < 1e-12, "row {row} sums to {sum}");
        }
        let q = [rng.vec3(), rng.vec3(), rng.vec3(), rng.vec3()];
        assert!(dist2(&c.apply(&q), &cols(c.gradient.at(&q))) < 1e-26);
        let shifted: Vec<DVec3> = q.iter().map(|x| *x + DVec3::new(-2.0, 1.0, 5.0)).collect();
        assert!(dist2(&c.apply(&q), &c.apply(&shifted)) < 1e-24, "translation invariant");
    }

    #[test]
    fn rigid_projection_is_the_nearest_rotation_even_when_inverted() {
        let mut rng = Rng(17);
        let rest = rest_tet();
        let c = TetStrain::new([0, 1, 2, 3], &rest, 0.0).unwrap();
        let mut inverted = 0;
        for trial in 0..200 {
            let mut t =
                rotation(&mut rng) * (DMat3::IDENTITY + 0.5 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()));
            if trial % 2 == 0 {
                t.z_axis = -t.z_axis; // inverted
            }
            if t.determinant() < 0.0 {
                inverted += 1;
            }
            let q = positions_for(&rest, t);
            let p = project(&c, &q);
            assert!(dist2(&cols(p.transpose() * p), &cols(DMat3::IDENTITY)) < 1e-28);
            assert!((p.determinant() - 1.0).abs() < 1e-14, "a rotation, det +1");
            let d = dist2(&c.apply(&q), &cols(p));
            for _ in 0..200 {
                let sample = rotation(&mut rng);
                assert!(d <= dist2(&cols(t), &cols(sample)) + 1e-12);
                let near = p * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
                assert!(d <= dist2(&cols(t), &cols(near)) + 1e-12);
            }
        }
        assert!(inverted > 50);
    }

    #[test]
    fn clamped_projection_is_on_the_set_and_no_sample_is_closer() {
        let mut rng = Rng(23);
        let rest = rest_tet();
        for f in [0.05, 0.3] {
            let (lo, hi) = (1.0 - f, 1.0 + f);
            let c = TetStrain::new([0, 1, 2, 3], &rest, f).unwrap();
            for _ in 0..100 {
                // Inverted T included: the projection is the exact nearest point for both signs.
                let t =
                    rotation(&mut rng) * (DMat3::IDENTITY + 0.6 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()));
                let q = positions_for(&rest, t);
                let p = project(&c, &q);
                assert_on_set(p, f);
                let svd = svd3(p);
                let d = dist2(&cols(t), &cols(p));
                for _ in 0..300 {
                    let s = DVec3::new(
                        lo + (hi - lo) * 0.5 * (1.0 + rng.uniform()),
                        lo + (hi - lo) * 0.5 * (1.0 + rng.uniform()),
                        lo + (hi - lo) * 0.5 * (1.0 + rng.uniform()),
                    );
                    let sample = rotation(&mut rng) * DMat3::from_diagonal(s) * rotation(&mut rng);
                    assert!(d <= dist2(&cols(t), &cols(sample)) + 1e-12, "f = {f}: a sample is closer");
                    // Nearby points of the set: p's factors slightly turned, σ moved within bounds.
                    let turn = |rng: &mut Rng| DMat3::from_axis_angle(rng.vec3().normalize(), 1e-3 * rng.uniform());
                    let moved = (svd.sigma + 1e-3 * rng.vec3()).clamp(DVec3::splat(lo), DVec3::splat(hi));
                    let near =
                        turn(&mut rng) * svd.u * DMat3::from_diagonal(moved) * svd.v.transpose() * turn(&mut rng);
                    assert!(d <= dist2(&cols(t), &cols(near)) + 1e-12, "f = {f}: a nearby sample is closer");
                }
            }
        }
    }

    #[test]
    fn inverted_with_freedom_takes_the_band_s_lower_end() {
        // det T < 0, f > 0: clamp σ₁, σ₂; the smallest goes to the band's lower end with the
        // other sign (det U · det V < 0), the nearest point with det ≥ 0 (strain limiting's
        // "negate the smallest clamped σ" reflects it: farther by |σ₃| − (1 − f)).
        let mut rng = Rng(29);
        let rest = rest_tet();
        let f = 0.2;
        let c = TetStrain::new([0, 1, 2, 3], &rest, f).unwrap();
        let mut strictly_nearer = 0;
        for _ in 0..100 {
            let mut t =
                rotation(&mut rng) * (DMat3::IDENTITY + 0.6 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()));
            if t.determinant() > 0.0 {
                t.y_axis = -t.y_axis;
            }
            let q = positions_for(&rest, t);
            let p = project(&c, &q);
            assert_on_set(p, f);
            let svd = svd3(t); // standard: σ ≥ 0, det U = −1 here
            assert!(svd.u.determinant() * svd.v.determinant() < 0.0);
            let mut clamped = svd.sigma.clamp(DVec3::splat(1.0 - f), DVec3::splat(1.0 + f));
            clamped.z = -(1.0 - f);
            let reference = svd.u * DMat3::from_diagonal(clamped) * svd.v.transpose();
            assert!(dist2(&cols(p), &cols(reference)) < 1e-24);
            let reflected = svd.sigma.clamp(DVec3::splat(1.0 - f), DVec3::splat(1.0 + f)) * DVec3::new(1.0, 1.0, -1.0);
            let reflected = svd.u * DMat3::from_diagonal(reflected) * svd.v.transpose();
            // Equal when σ₃ ≤ 1 − f (both at the lower end, up to the distances' round-off),
            // else nearer by (σ₃ + c(σ₃))² − (σ₃ + 1 − f)² > 0, c the clamp.
            let (d, d_reflected) = (dist2(&cols(t), &cols(p)), dist2(&cols(t), &cols(reflected)));
            assert!(d <= d_reflected + 1e-12, "{d} > {d_reflected}");
            if svd.sigma.z > 1.0 - f + 1e-3 {
                assert!(d < d_reflected - 1e-3, "{d} vs {d_reflected}: not strictly nearer");
                strictly_nearer += 1;
            }
        }
        assert!(strictly_nearer > 10, "{strictly_nearer} cases with σ₃ above the band's lower end");
    }

    #[test]
    fn projection_matches_the_reference_formula_computed_by_nalgebra() {
        let mut rng = Rng(59);
        let rest = rest_tet();
        for f in [0.0, 0.1, 0.4] {
            let c = TetStrain::new([0, 1, 2, 3], &rest, f).unwrap();
            for trial in 0..300 {
                let mut t =
                    rotation(&mut rng) * (DMat3::IDENTITY + 0.7 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()));
                if trial % 2 == 0 {
                    t.x_axis = -t.x_axis;
                }
                let q = positions_for(&rest, t);
                let m = nalgebra::Matrix3::from_column_slice(&t.to_cols_array());
                let svd = m.svd(true, true);
                let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
                let mut s = svd.singular_values.map(|x| x.clamp(1.0 - f, 1.0 + f));
                if u.determinant() * vt.determinant() < 0.0 {
                    // nalgebra sorts σ descending: the smallest is last; it goes to the band's
                    // lower end with the other sign (the nearest point with det ≥ 0).
                    s[2] = -(1.0 - f);
                }
                let want = u * nalgebra::Matrix3::from_diagonal(&s) * vt;
                let got = nalgebra::Matrix3::from_column_slice(&project(&c, &q).to_cols_array());
                let sv = svd.singular_values;
                let gap = (sv[1] - sv[2]).min(sv[0] - sv[1]).min(sv[2]) / sv[0];
                assert!((got - want).norm() < 1e-12 / gap.max(1e-4), "f = {f}: {got} vs {want}");
            }
        }
    }

    #[test]
    fn within_bounds_is_unchanged_when_free() {
        let mut rng = Rng(31);
        let rest = rest_tet();
        let c = TetStrain::new([0, 1, 2, 3], &rest, 0.3).unwrap();
        for _ in 0..100 {
            let s = DVec3::new(1.0 + 0.28 * rng.uniform(), 1.0 + 0.28 * rng.uniform(), 1.0 + 0.28 * rng.uniform());
            let t = rotation(&mut rng) * DMat3::from_diagonal(s) * rotation(&mut rng);
            let q = positions_for(&rest, t);
            assert!(dist2(&c.apply(&q), &cols(project(&c, &q))) < 1e-26);
            // The SVD path (bypassing the shortcut) agrees.
            let svd = svd3_rotations(t);
            assert!(dist2(&cols(svd.reconstruct()), &cols(t)) < 1e-26);
        }
    }

    #[test]
    fn rigid_motion_rotates_the_projection() {
        let mut rng = Rng(37);
        let rest = rest_tet();
        for f in [0.0, 0.15] {
            let c = TetStrain::new([0, 1, 2, 3], &rest, f).unwrap();
            for _ in 0..50 {
                let q = [rng.vec3(), rng.vec3(), rng.vec3(), rng.vec3()];
                let (r, shift) = (rotation(&mut rng), rng.vec3());
                let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
                let p = r * project(&c, &q);
                assert!(dist2(&cols(p), &cols(project(&c, &moved))) < 1e-22);
            }
        }
    }

    #[test]
    fn collapsed_tet_projects_to_a_finite_point_of_the_set() {
        let rest = rest_tet();
        for f in [0.0, 0.2] {
            let c = TetStrain::new([0, 1, 2, 3], &rest, f).unwrap();
            for q in [[DVec3::ONE; 4], [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)]] {
                let p = project(&c, &q);
                assert!(cols(p).iter().all(|x| x.is_finite()));
                assert_on_set(p, f);
            }
        }
    }

    #[test]
    fn build_skips_flat_tets_and_checks_options() {
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(1.0, 1.0, 0.0)];
        let tets = vec![[0, 1, 2, 3], [0, 1, 2, 4], [1, 2, 3, 4]];
        let triangles = vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]];
        let rest = RestGeometry::new(positions, triangles, tets);
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 2, "the flat tetrahedron is skipped");
        assert!(built.iter().all(|c| c.kind() == KIND && c.num_rows() == 3));
        assert_eq!(build_constraints(KIND, &ctx, Params::default().with("strain_freedom", 0.1)).unwrap().len(), 2);
        let sel = Selection::from_indices(5, &[0, 1, 2, 3]);
        assert_eq!(
            build_constraints(
                KIND,
                &BuildContext { rest: &rest, selection: &sel, frame: &WorkingFrame::IDENTITY },
                Params::default()
            )
            .unwrap()
            .len(),
            1
        );
        let err = build_constraints(KIND, &ctx, Params::default().with("strain_freedom", -1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::BadOption { .. }), "{err}");
        let err = build_constraints(KIND, &ctx, Params::default().with("freedom", 0.1)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let surface = RestGeometry::new(rest.positions.clone(), rest.triangles.clone(), vec![]);
        let err = build_constraints(
            KIND,
            &BuildContext { rest: &surface, selection: &Selection::All, frame: &WorkingFrame::IDENTITY },
            Params::default(),
        )
        .unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
