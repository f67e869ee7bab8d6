//! Volume: keeps each tetrahedron's volume within a range of its rest volume (ShapeOp's
//! `VolumeConstraint`, Deuss et al. 2015, "ShapeOp — a robust and extensible geometric
//! modelling paradigm"; the ShapeUp energy of Bouaziz et al. 2012).
//!
//! Term: ω ‖T − p‖²_F with T = [q_b − q_a, q_c − q_a, q_d − q_a] D⁻¹ (its three columns are the
//! three rows of C q), D = [x⁰_b − x⁰_a, x⁰_c − x⁰_a, x⁰_d − x⁰_a], as in tet strain (T = I at
//! rest, for either orientation of the rest tetrahedron).
//!
//! Set: {T : det T ∈ [min, max]}, det T the current signed volume over the rest volume (options
//! `min`, `max` ≥ 0, default 1 and 1). An inverted tetrahedron (det T < 0) is outside the set
//! for every range, so the projection also un-inverts.
//!
//! Projection (exact): p = T when det T ∈ [min, max]; else, with the rotation-variant SVD
//! T = U diag(s₁, s₂, s₃) Vᵀ (U, V rotations, s₁ ≥ s₂ ≥ |s₃|, s₃ carrying the sign of det T)
//! and c = clamp(det T, min, max), p = U diag(x) Vᵀ with x the point of x₁x₂x₃ = c nearest to
//! s. Sharing T's singular vectors is optimal by the signed von Neumann inequality
//! tr(AᵀB) ≤ Σ s̃ᵢ(A) s̃ᵢ(B) over rotations (Miranda–Thompson), and the nearest x is then all
//! positive and ordered. The 3-D problem ([`nearest_with_product3`]): stationary points satisfy
//! xᵢ(xᵢ − sᵢ) = κ for one multiplier κ; parametrized by x₃ = t they are the curve
//! xᵢ(t) = Sᵢ + √(δᵢ + (t − m)²) (i = 1, 2; Sᵢ = sᵢ/2, m = s₃/2, δᵢ = Sᵢ² − m²), on which
//! G(t) = t x₁(t) x₂(t) must equal c (a smaller xᵢ branch for x₁ or x₂ cannot be the minimum: it
//! would be out of order or fail the second-order condition).
//! - det T < c (growing, or inverted): the set {x > 0, Πx ≥ c} is convex, G is increasing on
//!   t ∈ [max(s₃, 0), c^⅓] with G ≤ c at the left end and G ≥ t³ ≥ c at the right: one root.
//! - det T > c (shrinking, s₃ > 0): the nearest boundary point from inside a convex set can be
//!   any of several stationary points (as for σ₁ = σ₂ = σ₃). On t ∈ (0, s₃], with τ = m − t,
//!   dG/dt has the sign of −Ξ(τ), Ξ(τ) = Σᵢ Sᵢ τ/√(δᵢ + τ²) − m − 3τ, which is concave with
//!   Ξ(m) = −2m < 0; so G is increasing, then possibly decreasing on the interval where Ξ ≥ 0
//!   (its ends found by bracketed 1-D solves around the maximum of Ξ, where Ξ' — decreasing —
//!   vanishes), then increasing: at most three monotone pieces, each with at most one root of
//!   G = c, every stationary point found; the nearest of them is the projection.
//!
//! Every root is found by a bracketed solve to full precision, and x₃ = c/(x₁x₂) puts the
//! result on the set to rounding. For c = 0 (max = 0, or min = 0 for an inverted tetrahedron),
//! x = (s₁, s₂, 0).
//!
//! ω = |V_T|, the rest volume; tetrahedra of volume ≤ 1e-12 get no constraint. ShapeOp takes
//! five Gauss–Newton steps on the singular values instead of the exact nearest point.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_element;
use crate::constraints::kit::gradient::TetGradient;
use crate::constraints::kit::options::take_range;
use crate::constraints::kit::sets::{bracketed_root, interval_distance};
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::svd3_rotations;
use glam::{DMat3, DVec3};

/// Name in scene files.
const KIND: &str = "volume";

/// `min`: the smallest volume ratio.
const MIN_OPTION: OptionSpec = OptionSpec {
    key: "min",
    doc: "smallest volume, as a ratio of the rest volume (≥ 0, ≤ max); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};
/// `max`: the largest volume ratio.
const MAX_OPTION: OptionSpec = OptionSpec {
    key: "max",
    doc: "largest volume, as a ratio of the rest volume (≥ min); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};

/// A volume constraint on tetrahedron (a, b, c, d).
#[derive(Debug, Clone)]
pub struct Volume {
    gradient: TetGradient,
    min: f64,
    max: f64,
}

impl Volume {
    /// A constraint on tetrahedron (a, b, c, d) of the rest shape `rest` keeping its volume
    /// ratio in `[min, max]` (0 ≤ min ≤ max expected); `None` if its rest volume is ≤ 1e-12
    /// ([`TetGradient::new`]: the rows of tetrahedral strain).
    pub fn new(vertices: [u32; 4], rest: &[DVec3], min: f64, max: f64) -> Option<Self> {
        TetGradient::new(vertices, rest).map(|gradient| Volume { gradient, min, max })
    }

    /// The range [min, max] of the volume ratio.
    pub fn range(&self) -> (f64, f64) {
        (self.min, self.max)
    }
}

/// The point x of x₁x₂x₃ = c nearest to s, for signed singular values s₁ ≥ s₂ ≥ |s₃| and c ≥ 0
/// (module doc). The result has x₁ ≥ x₂ ≥ x₃ > 0 (or x₃ = 0 for c = 0).
pub(crate) fn nearest_with_product3(s: [f64; 3], c: f64) -> [f64; 3] {
    let [s1, s2, s3] = s;
    if c <= 0.0 {
        return [s1, s2, 0.0];
    }
    let m = 0.5 * s3;
    let half = [0.5 * s1, 0.5 * s2];
    let delta = half.map(|h| ((h - m) * (h + m)).max(0.0));
    // The stationary curve: x₁, x₂ as functions of x₃ = t.
    let others = |t: f64| {
        let d = (t - m) * (t - m);
        [half[0] + (delta[0] + d).sqrt(), half[1] + (delta[1] + d).sqrt()]
    };
    let g = |t: f64| {
        let [x1, x2] = others(t);
        t * x1 * x2 - c
    };
    let point = |t: f64| {
        let [x1, x2] = others(t);
        [x1, x2, c / (x1 * x2)]
    };
    let det = s1 * s2 * s3;
    if det < c {
        return point(bracketed_root(g, s3.max(0.0), c.cbrt()));
    }
    if det == c {
        return s;
    }
    // Shrinking: s₃ > 0. Ξ(τ) and Ξ'(τ), τ = m − t ∈ [0, m]; ρᵢ = τ/√(δᵢ + τ²) (1 for δᵢ = 0).
    let xi = |tau: f64| {
        let rho = |d: f64| if d > 0.0 { tau / (d + tau * tau).sqrt() } else { 1.0 };
        half[0] * rho(delta[0]) + half[1] * rho(delta[1]) - m - 3.0 * tau
    };
    let xi_slope = |tau: f64| {
        let term = |h: f64, d: f64| if d > 0.0 { h * d / (d + tau * tau).powf(1.5) } else { 0.0 };
        term(half[0], delta[0]) + term(half[1], delta[1]) - 3.0
    };
    let peak = if xi_slope(0.0) > 0.0 { bracketed_root(xi_slope, 0.0, m) } else { 0.0 };
    // The monotone pieces of G (an empty piece [s₃, s₃] holds no root: G(s₃) > 0).
    let pieces = if xi(peak) <= 0.0 {
        [(0.0, s3), (s3, s3), (s3, s3)]
    } else {
        let rise = if xi(0.0) >= 0.0 { 0.0 } else { bracketed_root(xi, 0.0, peak) };
        let fall = bracketed_root(xi, peak, m);
        [(0.0, m - fall), (m - fall, m - rise), (m - rise, s3)]
    };
    let cost = |x: [f64; 3]| (x[0] - s1).powi(2) + (x[1] - s2).powi(2) + (x[2] - s3).powi(2);
    let mut best: Option<([f64; 3], f64)> = None;
    for (lo, hi) in pieces {
        let (glo, ghi) = (g(lo), g(hi));
        if (glo <= 0.0) != (ghi <= 0.0) || glo == 0.0 || ghi == 0.0 {
            let x = point(bracketed_root(g, lo, hi));
            let e = cost(x);
            if best.is_none_or(|(_, b)| e < b) {
                best = Some((x, e));
            }
        }
    }
    // G(0) = −c < 0 < G(s₃): some piece always holds a root; the fallback is never taken.
    best.map_or_else(|| point(bracketed_root(g, 0.0, s3)), |(x, _)| x)
}

impl Constraint for Volume {
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
        let det = t.determinant();
        let p = if det >= self.min && det <= self.max {
            t
        } else {
            let target = det.max(self.min).min(self.max);
            let svd = svd3_rotations(t);
            let x = nearest_with_product3(svd.sigma.to_array(), target);
            svd.u * DMat3::from_diagonal(DVec3::from(x)) * svd.v.transpose()
        };
        out[0] = p.x_axis;
        out[1] = p.y_axis;
        out[2] = p.z_axis;
    }
    /// How far σ₃ must move to bring the volume ratio σ₁σ₂σ₃ into [min, max] (signed σ of the
    /// rotation-variant SVD), |σ₁σ₂σ₃ − clamp|/(σ₁σ₂): a distance from the set in the rows'
    /// units (det is cubic in them), and computed from the SVD, accurate to ε σ₁ even for a very
    /// flat P where det P itself is round-off (ε σ₁³); where σ₁σ₂ = 0, √3 times the cube root
    /// of the ratio's distance (exact from 0).
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        if !p.iter().all(|x| x.is_finite()) {
            return f64::INFINITY;
        }
        let sigma = svd3_rotations(DMat3::from_cols(p[0], p[1], p[2])).sigma;
        let off = interval_distance(sigma.x * sigma.y * sigma.z, self.min, self.max);
        let area = sigma.x * sigma.y;
        if off == 0.0 {
            0.0
        } else if area > 0.0 {
            off / area
        } else {
            3f64.sqrt() * off.cbrt()
        }
    }
    /// The volume ratio's distance from [min, max] (what a report means by a volume's error).
    fn violation(&self, cq: &[DVec3]) -> f64 {
        interval_distance(DMat3::from_cols(cq[0], cq[1], cq[2]).determinant(), self.min, self.max)
    }
}

/// Builds a [`Volume`] on every tetrahedron whose four vertices are selected and whose rest
/// volume is > 1e-12. Options `min`, `max` (volume ratios, default 1 and 1). Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct VolumeType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "volume: each tetrahedron keeps its volume within [min, max] times its rest volume",
    options: &[MIN_OPTION, MAX_OPTION],
    element: Element::Tetrahedron,
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for VolumeType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let (min, max) = take_range(KIND, params, &MIN_OPTION, &MAX_OPTION)?;
        let rest = &ctx.rest.positions;
        let selected = ctx.rest.tetrahedra.iter().filter(|t| ctx.selection.contains_all(&t[..]));
        per_selected_element(selected, KIND, "tetrahedra", |t| Volume::new(*t, rest, min, max))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::tet_volume;
    use crate::geometry::{RestGeometry, WorkingFrame};
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

    fn project(c: &Volume, q: &[DVec3]) -> DMat3 {
        let mut p = [DVec3::ZERO; 3];
        c.project(q, &mut p);
        DMat3::from_cols(p[0], p[1], p[2])
    }

    fn cost(x: [f64; 3], s: [f64; 3]) -> f64 {
        x.iter().zip(&s).map(|(a, b)| (a - b).powi(2)).sum()
    }

    /// Brute force over the surface x₁x₂x₃ = c (x₃ = c/(x₁x₂)), all sign patterns with a
    /// positive product: a log grid in (x₁, x₂), then a local pattern search from the best cells.
    fn brute_force3(s: [f64; 3], c: f64) -> f64 {
        let mut best = f64::INFINITY;
        for signs in [[1.0, 1.0], [-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0]] {
            let sign3 = signs[0] * signs[1];
            let eval = |l1: f64, l2: f64| {
                let (x1, x2) = (signs[0] * l1.exp(), signs[1] * l2.exp());
                cost([x1, x2, sign3 * c / (l1 + l2).exp()], s)
            };
            let n = 120;
            let mut starts = Vec::new();
            for i in 0..=n {
                for j in 0..=n {
                    let (l1, l2) = (-6.0 + 9.0 * i as f64 / n as f64, -6.0 + 9.0 * j as f64 / n as f64);
                    starts.push((eval(l1, l2), l1, l2));
                }
            }
            starts.sort_by(|a, b| a.0.total_cmp(&b.0));
            for &(_, mut l1, mut l2) in starts.iter().take(6) {
                let mut step = 0.1;
                let mut here = eval(l1, l2);
                while step > 1e-13 {
                    let mut moved = false;
                    for (d1, d2) in [
                        (1.0, 0.0),
                        (-1.0, 0.0),
                        (0.0, 1.0),
                        (0.0, -1.0),
                        (1.0, 1.0),
                        (-1.0, -1.0),
                        (1.0, -1.0),
                        (-1.0, 1.0),
                    ] {
                        let e = eval(l1 + step * d1, l2 + step * d2);
                        if e < here {
                            (here, l1, l2, moved) = (e, l1 + step * d1, l2 + step * d2, true);
                        }
                    }
                    if !moved {
                        step *= 0.5;
                    }
                }
                best = best.min(here);
            }
        }
        best
    }

    /// Signed singular values s₁ ≥ s₂ ≥ |s₃|.
    fn sorted(mut s: [f64; 3]) -> [f64; 3] {
        let sign = s.iter().map(|x| x.signum()).product::<f64>();
        let mut a = s.map(f64::abs);
        a.sort_by(|x, y| y.total_cmp(x));
        s = a;
        s[2] *= sign;
        s
    }

    #[test]
    fn nearest_point_of_the_product_surface_is_global() {
        let mut rng = Rng(1234);
        for trial in 0..400 {
            let mut s = [rng.uniform() * 2.0, rng.uniform() * 2.0, rng.uniform() * 2.0];
            match trial % 6 {
                0 => s = [s[0].abs(); 3],                            // isotropic
                1 => s = [s[0].abs() + 0.3, s[1].abs(), s[1].abs()], // σ₂ = σ₃
                2 => s = [s[0].abs(), s[0].abs(), s[1]],             // σ₁ = σ₂
                _ => {}
            }
            let s = sorted(s);
            let c = [0.05, 0.3, 1.0, 2.5][trial % 4] * (0.5 + 0.5 * rng.uniform().abs());
            let x = nearest_with_product3(s, c);
            assert!((x[0] * x[1] * x[2] - c).abs() <= 1e-13 * c, "{x:?}: product {c}");
            assert!(x[0] >= x[1] && x[1] >= x[2] * (1.0 - 1e-14) && x[2] > 0.0, "{x:?}");
            let got = cost(x, s);
            let want = brute_force3(s, c);
            assert!(got <= want + 1e-10 * (1.0 + want), "s = {s:?}, c = {c}: {got} > {want} ({x:?})");
        }
    }

    #[test]
    fn isotropic_shrink_picks_the_nearer_of_the_competing_stationary_points() {
        // s = (1, 1, 1): the candidates are (1 − t, 1 − t, t) with t(1 − t)² = c and the uniform
        // scaling c^⅓ (1, 1, 1); the first wins for c up to ≈ 0.146, the second after.
        for (c, squashed) in [(0.13, true), (0.145, true), (0.1475, false), (0.05, true), (0.9, false)] {
            let x = nearest_with_product3([1.0, 1.0, 1.0], c);
            let t = bracketed_root(|t| t * (1.0 - t) * (1.0 - t) - c, 0.0, 1.0 / 3.0);
            let flat = cost([1.0 - t, 1.0 - t, t], [1.0; 3]);
            let uniform = 3.0 * (1.0 - c.cbrt()).powi(2);
            let want = if squashed { flat } else { uniform };
            assert!((flat < uniform) == squashed, "c = {c}: {flat} vs {uniform}");
            assert!((cost(x, [1.0; 3]) - want).abs() < 1e-12, "c = {c}: {x:?}");
        }
        // Growing and inverted: one stationary point.
        let x = nearest_with_product3([1.0, 0.5, -0.2], 1.0);
        assert!((x[0] * x[1] * x[2] - 1.0).abs() < 1e-14 && x[2] > 0.0);
        assert_eq!(nearest_with_product3([1.0, 0.5, -0.2], 0.0), [1.0, 0.5, 0.0]);
        let x = nearest_with_product3([0.0; 3], 8.0);
        assert!(x.iter().all(|v| (v - 2.0).abs() < 1e-14), "{x:?}");
    }

    #[test]
    fn rest_state_projects_to_itself_with_the_rest_volume_as_weight() {
        let rest = rest_tet();
        let mut flipped = rest;
        flipped.swap(1, 2);
        for r in [rest, flipped] {
            let c = Volume::new([0, 1, 2, 3], &r, 1.0, 1.0).unwrap();
            assert!(c.energy(&r) < 1e-28);
            assert!((c.element_weight() - tet_volume(r[0], r[1], r[2], r[3]).abs()).abs() < 1e-16);
        }
    }

    #[test]
    fn projection_is_on_the_set_and_no_sample_is_closer() {
        let mut rng = Rng(77);
        let rest = rest_tet();
        for (lo, hi) in [(1.0, 1.0), (0.9, 1.2), (0.0, 0.3), (2.0, 3.0)] {
            let c = Volume::new([0, 1, 2, 3], &rest, lo, hi).unwrap();
            for trial in 0..60 {
                let t = match trial % 3 {
                    0 => {
                        rotation(&mut rng)
                            * (DMat3::IDENTITY + 0.4 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()))
                    }
                    1 => DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()),
                    _ => {
                        let mut t = rotation(&mut rng)
                            * (DMat3::IDENTITY + 0.3 * DMat3::from_cols(rng.vec3(), rng.vec3(), rng.vec3()));
                        t.z_axis = -t.z_axis; // inverted
                        t
                    }
                };
                let q: Vec<DVec3> = rest.iter().map(|x| t * (*x - rest[0])).collect();
                let cq = c.apply(&q);
                let p = project(&c, &q);
                let det = p.determinant();
                assert!(det >= lo - 1e-12 && det <= hi + 1e-12, "[{lo}, {hi}]: det {det}");
                let d = dist2(&cq, &cols(p));
                for _ in 0..300 {
                    // W diag(s) Zᵀ, W and Z rotations, det = s₁s₂s₃ in [lo, hi].
                    let target = lo + (hi - lo) * 0.5 * (1.0 + rng.uniform());
                    let (s1, s2) = ((1.2 * rng.uniform()).exp(), (1.2 * rng.uniform()).exp());
                    let sample = rotation(&mut rng)
                        * DMat3::from_diagonal(DVec3::new(s1, s2, target / (s1 * s2)))
                        * rotation(&mut rng).transpose();
                    assert!(d <= dist2(&cq, &cols(sample)) + 1e-12, "[{lo}, {hi}]: a sample is closer");
                    // The same singular vectors as p, other singular values on the set.
                    let svd = svd3_rotations(p);
                    let near = svd.u
                        * DMat3::from_diagonal(
                            svd.sigma * DVec3::new(1.0 + 0.1 * rng.uniform(), 1.0 + 0.1 * rng.uniform(), 1.0),
                        )
                        * svd.v.transpose();
                    let scale = (p.determinant() / near.determinant()).cbrt();
                    if scale.is_finite() {
                        assert!(d <= dist2(&cq, &cols(near * scale)) + 1e-12, "[{lo}, {hi}]: a nearby point is closer");
                    }
                }
            }
        }
    }

    #[test]
    fn within_range_is_unchanged_and_rigid_motions_commute() {
        let mut rng = Rng(5);
        let rest = rest_tet();
        let c = Volume::new([0, 1, 2, 3], &rest, 0.5, 2.0).unwrap();
        for _ in 0..30 {
            let t = rotation(&mut rng) * DMat3::from_diagonal(DVec3::new(1.1, 0.9, 1.05));
            let q: Vec<DVec3> = rest.iter().map(|x| t * *x + DVec3::ONE).collect();
            assert!(dist2(&c.apply(&q), &cols(project(&c, &q))) < 1e-28);
        }
        let c = Volume::new([0, 1, 2, 3], &rest, 1.0, 1.0).unwrap();
        for _ in 0..30 {
            let q = [rng.vec3(), rng.vec3(), rng.vec3(), rng.vec3()];
            let (r, shift) = (rotation(&mut rng), rng.vec3());
            let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
            let p = r * project(&c, &q);
            assert!(dist2(&cols(p), &cols(project(&c, &moved))) < 1e-20);
        }
    }

    #[test]
    fn build_checks_options_and_selection() {
        let rest = RestGeometry::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE],
            vec![],
            vec![[0, 1, 2, 3], [1, 2, 3, 4]],
        );
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 2);
        let err = build_constraints(KIND, &ctx, Params::default().with("max", 0.5)).unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }), "{err}");
        assert!(err.to_string().contains("\"min\"") && err.to_string().contains("\"max\""), "{err}");
        for key in ["min", "max"] {
            let err = build_constraints(KIND, &ctx, Params::default().with(key, -1.0)).unwrap_err();
            assert!(matches!(err, ConstraintError::BadOption { .. }) && err.to_string().contains(key), "{err}");
        }
        let none = Selection::from_indices(5, &[0, 1, 2, 4]);
        let ctx = BuildContext { rest: &rest, selection: &none, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
