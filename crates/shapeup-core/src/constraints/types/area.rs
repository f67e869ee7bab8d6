//! Area: keeps each triangle's area within a range of its rest area (ShapeOp's
//! `AreaConstraint`, Deuss et al. 2015, "ShapeOp — a robust and extensible geometric modelling
//! paradigm"; the ShapeUp energy of Bouaziz et al. 2012).
//!
//! Term: ω ‖T − p‖²_F with T = [q_b − q_a, q_c − q_a] D⁻¹ (3×2, its two columns are the two rows
//! of C q) exactly as in triangle strain: D = P⁰ᵀ[x⁰_b − x⁰_a, x⁰_c − x⁰_a], P⁰ an orthonormal
//! basis of the rest triangle's plane, so T = I (as a 3×2 frame) at rest.
//!
//! Set: {T : σ₁σ₂ ∈ [min, max]}, σ the singular values of T, σ₁σ₂ = ‖t₀ × t₁‖ the current area
//! over the rest area (options `min`, `max`, default 1 and 1: the rest area kept exactly).
//! Orientation does not enter: a 3×2 matrix has no sign, so a triangle flipped in 3D is
//! measured by its unsigned area.
//!
//! Projection (exact): p = T when σ₁σ₂ ∈ [min, max]; else, with the thin SVD T = UΣVᵀ and the
//! target c = clamp(σ₁σ₂, min, max), p = U diag(x, y) Vᵀ where (x, y) is the point of xy = c
//! nearest to (σ₁, σ₂). That is the nearest point of the set: by von Neumann's trace inequality
//! ‖T − P‖² ≥ Σ(σᵢ(T) − σᵢ(P))², with equality for P sharing T's singular vectors. The 2-D
//! problem is solved without iterating on a non-convex function ([`nearest_with_product2`]):
//! in the rotated coordinates u = (x + y)/√2, v = (x − y)/√2 it is
//! min (u − α)² + (v − β)² s.t. u² − v² = 2c with α = (σ₁ + σ₂)/√2, β = (σ₁ − σ₂)/√2, a
//! quadratic with one quadratic constraint, whose global minimizer is the stationary point with
//! multiplier μ ∈ [−1, 1] (Moré 1993, generalized trust regions): u(1 − μ) = α, v(1 + μ) = β.
//! Eliminating μ leaves F(v) = α/√(2c + v²) + β/v − 2 = 0, strictly decreasing in v > 0 with
//! its root in [β/2, (α + β)/2], found to full precision by a bracketed 1-D solve; for β = 0
//! (σ₁ = σ₂, the "hard case") v = √(max(α²/4 − 2c, 0)) in closed form. Then u = √(2c + v²),
//! x = (u + v)/√2, y = c/x. For c = 0 (max = 0), (x, y) = (σ₁, 0).
//!
//! ω = A_t, the rest area; zero-area rest triangles get no constraint. ShapeOp takes five
//! Gauss–Newton steps on the singular values instead of the exact solve, and measures T in a
//! frame of the current triangle built from its first edge; the projection here is computed in
//! the same kind of frame (the columns of T span it), exact, and rigid-motion equivariant.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_element;
use crate::constraints::kit::gradient::TriangleGradient;
use crate::constraints::kit::sets::{bracketed_root, interval_distance};
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::svd2;
use glam::{DMat2, DVec2, DVec3};
use std::f64::consts::FRAC_1_SQRT_2;
use crate::constraints::kit::options::take_range;

/// Name in scene files.
const KIND: &str = "area";

/// `min`: the smallest area ratio.
const MIN_OPTION: OptionSpec = OptionSpec {
    key: "min",
    doc: "smallest area, as a ratio of the rest area (≥ 0, ≤ max); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};
/// `max`: the largest area ratio.
const MAX_OPTION: OptionSpec = OptionSpec {
    key: "max",
    doc: "largest area, as a ratio of the rest area (≥ min); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};

/// An area constraint on triangle (a, b, c).
#[derive(Debug, Clone)]
pub struct Area {
    gradient: TriangleGradient,
    min: f64,
    max: f64,
}

impl Area {
    /// A constraint on triangle (a, b, c) of the rest shape `rest` keeping its area ratio in
    /// `[min, max]` (0 ≤ min ≤ max expected); `None` if the rest triangle is degenerate
    /// ([`TriangleGradient::new`]: the rows and current frame of triangle strain).
    pub fn new(vertices: [u32; 3], rest: &[DVec3], min: f64, max: f64) -> Option<Self> {
        TriangleGradient::new(vertices, rest).map(|gradient| Area { gradient, min, max })
    }

    /// The range [min, max] of the area ratio.
    pub fn range(&self) -> (f64, f64) {
        (self.min, self.max)
    }
}

/// The point (x, y), x ≥ y ≥ 0, of the hyperbola xy = c nearest to (a, b), for a ≥ b ≥ 0 and
/// c ≥ 0 (module doc: the global minimizer through its multiplier, one monotone 1-D root).
pub(crate) fn nearest_with_product2(a: f64, b: f64, c: f64) -> (f64, f64) {
    if c <= 0.0 {
        return (a, 0.0);
    }
    let alpha = (a + b) * FRAC_1_SQRT_2;
    let beta = ((a - b) * FRAC_1_SQRT_2).max(0.0);
    let two_c = 2.0 * c;
    let v = if beta > 0.0 {
        // F(v) = α/√(2c + v²) + β/v − 2: F(β/2) > 0 > F((α + β)/2), strictly decreasing.
        let f = |v: f64| alpha / (two_c + v * v).sqrt() + beta / v - 2.0;
        bracketed_root(f, 0.5 * beta, 0.5 * (alpha + beta))
    } else {
        (0.25 * alpha * alpha - two_c).max(0.0).sqrt()
    };
    let u = (two_c + v * v).sqrt();
    let x = (u + v) * FRAC_1_SQRT_2;
    (x, c / x)
}

impl Constraint for Area {
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
        let ratio = t[0].cross(t[1]).length();
        if ratio >= self.min && ratio <= self.max {
            out[0] = t[0];
            out[1] = t[1];
            return;
        }
        let target = ratio.max(self.min).min(self.max);
        let frame = self.gradient.current_frame(&t);
        let svd = svd2(TriangleGradient::in_frame(frame, &t));
        let (x, y) = nearest_with_product2(svd.sigma.x, svd.sigma.y, target);
        let p = svd.u * DMat2::from_diagonal(DVec2::new(x, y)) * svd.v.transpose();
        TriangleGradient::out_of_frame(frame, p, out);
    }
    /// The area ratio's distance from [min, max] over its gradient's length ‖p‖_F (the
    /// first-order distance from the set, in the rows' units: the ratio is quadratic in the
    /// rows, and at a stretch of 1e12 its rounding alone is 1e8); from 0, the exact distance
    /// √(2 min).
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        if !p.iter().all(|x| x.is_finite()) {
            return f64::INFINITY;
        }
        let off = interval_distance(p[0].cross(p[1]).length(), self.min, self.max);
        let gradient = (p[0].length_squared() + p[1].length_squared()).sqrt();
        if off == 0.0 {
            0.0
        } else if gradient > 0.0 {
            off / gradient
        } else {
            (2.0 * off).sqrt()
        }
    }
    /// The area ratio's distance from [min, max] (what a report means by an area's error).
    fn violation(&self, cq: &[DVec3]) -> f64 {
        interval_distance(cq[0].cross(cq[1]).length(), self.min, self.max)
    }
}


/// Builds an [`Area`] on every non-degenerate triangle whose three vertices are selected.
/// Options `min`, `max` (area ratios, default 1 and 1). Default multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct AreaType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "area: each triangle keeps its area within [min, max] times its rest area",
    options: &[MIN_OPTION, MAX_OPTION],
    element: Element::Triangle,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for AreaType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let (min, max) = take_range(KIND, params, &MIN_OPTION, &MAX_OPTION)?;
        let rest = &ctx.rest.positions;
        let selected = ctx.rest.triangles.iter().filter(|t| ctx.selection.contains_all(&t[..]));
        per_selected_element(selected, KIND, "triangles", |t| Area::new(*t, rest, min, max))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
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

    fn project(c: &Area, q: &[DVec3]) -> Vec<DVec3> {
        let mut p = vec![DVec3::ZERO; 2];
        c.project(q, &mut p);
        p
    }

    /// A random point of the set: W diag(s) Zᵀ with W 3×2 orthonormal (or `plane`), Z a 2×2
    /// rotation or reflection, s₁s₂ = a ratio in [lo, hi].
    fn sample_of_set(rng: &mut Rng, lo: f64, hi: f64, plane: Option<[DVec3; 2]>) -> [DVec3; 2] {
        let w = plane.unwrap_or_else(|| {
            let r = rotation(rng);
            [r.x_axis, r.y_axis]
        });
        let ratio = lo + (hi - lo) * 0.5 * (1.0 + rng.uniform());
        let s1 = (ratio.max(1e-6)).sqrt() * (1.5 * rng.uniform()).exp();
        let s = [s1, ratio / s1];
        let z = DMat2::from_angle(4.0 * rng.uniform())
            * if rng.uniform() < 0.0 { DMat2::from_diagonal(DVec2::new(1.0, -1.0)) } else { DMat2::IDENTITY };
        let col = |k: usize| w[0] * s[0] * z.col(0)[k] + w[1] * s[1] * z.col(1)[k];
        [col(0), col(1)]
    }

    /// Brute force: min over x > 0 of (x − a)² + (c/x − b)² on a fine log grid, refined.
    fn brute_force2(a: f64, b: f64, c: f64) -> f64 {
        let cost = |x: f64| (x - a).powi(2) + (c / x - b).powi(2);
        let mut best = (f64::INFINITY, 0.0);
        for k in 0..=4000 {
            let x = (c.sqrt()) * (8.0 * (k as f64 / 4000.0 * 2.0 - 1.0)).exp();
            if cost(x) < best.0 {
                best = (cost(x), x);
            }
        }
        let (mut lo, mut hi) = (best.1 * 0.99, best.1 * 1.01);
        for _ in 0..200 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if cost(m1) < cost(m2) { hi = m2 } else { lo = m1 }
        }
        cost(0.5 * (lo + hi)).min(best.0)
    }

    #[test]
    fn nearest_point_of_the_hyperbola_is_global() {
        let mut rng = Rng(99);
        for trial in 0..3000 {
            let mut a = 2.0 * (1.0 + rng.uniform());
            let mut b = 2.0 * (1.0 + rng.uniform());
            if trial % 5 == 0 {
                b = a * (1.0 - 1e-9 * (1.0 + rng.uniform())); // nearly the hard case
            }
            if trial % 7 == 0 {
                b = a;
            }
            if a < b {
                std::mem::swap(&mut a, &mut b);
            }
            let c = (3.0 * rng.uniform()).exp();
            let (x, y) = nearest_with_product2(a, b, c);
            assert!(x >= y * (1.0 - 1e-14) && y > 0.0, "({a}, {b}) c = {c}: ({x}, {y})");
            assert!((x * y - c).abs() <= 1e-14 * c, "on the hyperbola");
            let got = (x - a).powi(2) + (y - b).powi(2);
            let want = brute_force2(a, b, c);
            assert!(got <= want + 1e-11 * (1.0 + want), "({a}, {b}) c = {c}: {got} > {want}");
        }
        // c = 0: the nearest point of the axes.
        assert_eq!(nearest_with_product2(2.0, 1.0, 0.0), (2.0, 0.0));
        // The origin: the vertex of the hyperbola.
        let (x, y) = nearest_with_product2(0.0, 0.0, 4.0);
        assert!((x - 2.0).abs() < 1e-15 && (y - 2.0).abs() < 1e-15);
        // The hard case σ₁ = σ₂ in closed form: (3, 3), c = 0.5: α² = 18, v = √(α²/4 − 2c).
        let (x, y) = nearest_with_product2(3.0, 3.0, 0.5);
        let v = (18.0f64 / 4.0 - 1.0).sqrt();
        let u = (1.0 + v * v).sqrt();
        assert!((x - (u + v) * FRAC_1_SQRT_2).abs() < 1e-14 && (y - (u - v) * FRAC_1_SQRT_2).abs() < 1e-14);
    }

    #[test]
    fn rest_state_projects_to_itself_with_the_rest_area_as_weight() {
        let rest = rest_triangle();
        let c = Area::new([0, 1, 2], &rest, 1.0, 1.0).unwrap();
        assert!(c.energy(&rest) < 1e-28);
        let area = 0.5 * (rest[1] - rest[0]).cross(rest[2] - rest[0]).length();
        assert!((c.element_weight() - area).abs() < 1e-15);
        let mut sink = RowSink::default();
        c.rows(&mut sink);
        for row in 0..2 {
            let sum: f64 = sink.entries.iter().filter(|e| e.row == row).map(|e| e.coeff).sum();
            assert!(sum.abs() < 1e-12, "row {row} sums to {sum}");
        }
    }

    #[test]
    fn projection_is_on_the_set_and_no_sample_is_closer() {
        let mut rng = Rng(23);
        let rest = rest_triangle();
        for (lo, hi) in [(1.0, 1.0), (0.8, 1.3), (0.0, 0.5), (2.0, 2.0), (0.0, 0.0)] {
            let c = Area::new([0, 1, 2], &rest, lo, hi).unwrap();
            for trial in 0..80 {
                let q: Vec<DVec3> = if trial % 3 == 0 {
                    let r = rotation(&mut rng);
                    rest.iter().map(|x| r * (*x + 0.2 * rng.vec3())).collect()
                } else {
                    vec![rng.vec3(), rng.vec3(), rng.vec3()]
                };
                let cq = c.apply(&q);
                let p = project(&c, &q);
                let ratio = p[0].cross(p[1]).length();
                assert!(ratio >= lo - 1e-12 && ratio <= hi + 1e-12, "[{lo}, {hi}]: ratio {ratio}");
                assert!(c.set_residual(&p) <= 1e-12);
                let d = dist2(&cq, &p);
                let n = (q[1] - q[0]).cross(q[2] - q[0]).normalize();
                let plane = [(q[1] - q[0]).normalize(), n.cross((q[1] - q[0]).normalize())];
                for _ in 0..300 {
                    let general = sample_of_set(&mut rng, lo, hi, None);
                    assert!(d <= dist2(&cq, &general) + 1e-12, "[{lo}, {hi}]: a 3×2 sample is closer");
                    let in_plane = sample_of_set(&mut rng, lo, hi, Some(plane));
                    assert!(d <= dist2(&cq, &in_plane) + 1e-12, "[{lo}, {hi}]: an in-plane sample is closer");
                }
            }
        }
    }

    #[test]
    fn within_range_is_unchanged_and_rigid_motions_commute() {
        let mut rng = Rng(31);
        let rest = rest_triangle();
        let c = Area::new([0, 1, 2], &rest, 0.5, 2.0).unwrap();
        for _ in 0..40 {
            let r = rotation(&mut rng);
            let scale = 1.0 + 0.2 * rng.uniform();
            let q: Vec<DVec3> = rest.iter().map(|x| r * (*x * scale) + DVec3::ONE).collect();
            assert!(dist2(&c.apply(&q), &project(&c, &q)) < 1e-28, "area ratio {scale}² is in range");
        }
        let c = Area::new([0, 1, 2], &rest, 1.0, 1.0).unwrap();
        for _ in 0..40 {
            let q = [rng.vec3(), rng.vec3(), rng.vec3()];
            let (r, shift) = (rotation(&mut rng), rng.vec3());
            let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
            let p: Vec<DVec3> = project(&c, &q).iter().map(|x| r * *x).collect();
            assert!(dist2(&p, &project(&c, &moved)) < 1e-22);
        }
    }

    #[test]
    fn collapsed_triangles_project_to_finite_points_of_the_set() {
        let rest = rest_triangle();
        let c = Area::new([0, 1, 2], &rest, 1.0, 1.0).unwrap();
        for q in [
            [DVec3::ONE, DVec3::ONE, DVec3::ONE],
            [DVec3::ZERO, DVec3::X, DVec3::X * 2.0],
            [DVec3::ZERO, DVec3::new(1.0, 1e-17, 0.0), DVec3::new(2.0, 0.0, 1e-18)],
        ] {
            let p = project(&c, &q);
            assert!(p.iter().all(|x| x.is_finite()), "{p:?}");
            assert!(c.set_residual(&p) < 1e-12, "{p:?}");
        }
    }

    fn grid_rest() -> RestGeometry {
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(2.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 0.0)];
        RestGeometry::new(positions, vec![[0, 1, 2], [0, 1, 3], [1, 4, 2]], vec![])
    }

    #[test]
    fn build_skips_degenerate_triangles_and_checks_options() {
        let rest = grid_rest();
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 2, "the zero-area triangle is skipped");
        let built = build_constraints(KIND, &ctx, Params::default().with("min", 0.5).with("max", 3.0)).unwrap();
        assert_eq!(built.len(), 2);
        let err = build_constraints(KIND, &ctx, Params::default().with("min", 2.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }), "{err}");
        assert!(err.to_string().contains("\"min\"") && err.to_string().contains("\"max\""), "{err}");
        for key in ["min", "max"] {
            let err = build_constraints(KIND, &ctx, Params::default().with(key, -0.5)).unwrap_err();
            assert!(matches!(err, ConstraintError::BadOption { .. }) && err.to_string().contains(key), "{err}");
        }
        let err = build_constraints(KIND, &ctx, Params::default().with("strain_freedom", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");
        let none = Selection::from_indices(5, &[0, 3]);
        let ctx = BuildContext { rest: &rest, selection: &none, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
