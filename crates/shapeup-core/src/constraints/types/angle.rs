//! Angle: keeps the angle at each corner of a polygon face within a range (ShapeOp's
//! `AngleConstraint`, Deuss et al. 2015, "ShapeOp — a robust and extensible geometric
//! modelling paradigm"; the ShapeUp energy of Bouaziz et al. 2012).
//!
//! Elements: every corner c of every selected polygon face, with its neighbours prev and next
//! along the face. Term: ω ‖[e₁, e₂] − p‖² with the two rows e₁ = q_prev − q_c and
//! e₂ = q_next − q_c. ω = 1 (as in ShapeOp).
//!
//! Set: the pairs (p₁, p₂) whose angle ∠(p₁, p₂) = atan2(‖p₁ × p₂‖, p₁ · p₂) lies in
//! [min, max] ⊂ [0, π], together with the pairs where p₁ or p₂ is zero (the set's closure: a
//! zero vector has every angle; without it a nearest point would not always exist).
//!
//! Projection (exact, closed form): with θ = ∠(e₁, e₂) outside the range and the needed change
//! Δ = |clamp(θ, min, max) − θ|, a point of the set at angle θ ± Δ' (Δ' ≥ Δ) has directions at
//! angles γ₁, γ₂ from e₁, e₂ with γ₁ + γ₂ ≥ Δ (triangle inequality on the sphere), equality
//! when both turn in the plane of e₁ and e₂, towards each other (closing) or apart (opening);
//! and the nearest point of the ray at angle γ from e is its projection, at squared distance
//! ‖e‖² sin²γ (γ ≤ π/2) or ‖e‖² (beyond: the origin). So p minimizes
//! a sin²γ₁ + b sin²γ₂ over γ₁ + γ₂ = Δ, a = ‖e₁‖², b = ‖e₂‖². For Δ ≤ π/2 that is
//! (a + b)/2 − ½ Re(e^{2iγ₁} conj(a + b e^{2iΔ})), maximal at 2γ₁ = arg(a + b e^{2iΔ}) ∈ [0, 2Δ]:
//! γ₁ = ½ atan2(b sin 2Δ, a + b cos 2Δ), γ₂ = Δ − γ₁, and pᵢ = cos γᵢ (cos γᵢ eᵢ + sin γᵢ ‖eᵢ‖ wᵢ)
//! with wᵢ the unit in-plane direction eᵢ turns to. For Δ > π/2 the minimum over both ranges of
//! γ₁ (each side saturated) is min(a, b): the shorter vector goes to 0, the other stays. ShapeOp
//! turns both vectors by fixed shares of Δ; the split here is the exact one, so the iteration's
//! energy never increases. Parallel or opposite e₁, e₂ (no plane) turn in a plane through e₁
//! chosen by [`DVec3::any_orthonormal_vector`]; a zero e₁ or e₂ is on the set.
//!
//! Options `min`, `max` (radians, in [0, π]); each defaults to the corner's rest angle θ⁰ —
//! the rest angle is kept exactly when both are absent. Choice: when only one bound is given,
//! the other is the rest angle moved, where needed, to the given bound (range [min, max(θ⁰,
//! min)] or [min(θ⁰, max), max]), so that one bound alone never empties a corner's range;
//! both given with min > max is refused. Corners with a rest edge of length ≤ 1e-12 (or a
//! repeated vertex) get no constraint.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::sets::interval_distance;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;
use std::f64::consts::{FRAC_PI_2, PI};

/// Shortest rest edge of a corner that gets a constraint.
const MIN_REST_LENGTH: f64 = 1e-12;
/// Name in scene files.
const KIND: &str = "angle";

/// `min`: the smallest angle.
const MIN_OPTION: OptionSpec = OptionSpec {
    key: "min",
    doc: "smallest corner angle, radians in [0, π]; default the rest angle of each corner",
    kind: OptionKind::Number { default: None, min: 0.0, max: PI },
};
/// `max`: the largest angle.
const MAX_OPTION: OptionSpec = OptionSpec {
    key: "max",
    doc: "largest corner angle, radians in [0, π] (≥ min); default the rest angle of each corner",
    kind: OptionKind::Number { default: None, min: 0.0, max: PI },
};

/// The angle ∠(a, b) ∈ [0, π], accurate for every angle.
#[inline]
fn angle_between(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// An angle constraint on the corner at `centre` between `prev` and `next`.
#[derive(Debug, Clone)]
pub struct Angle {
    /// prev, centre, next.
    vertices: [u32; 3],
    min: f64,
    max: f64,
}

impl Angle {
    /// A constraint keeping the angle at `centre` between the edges to `prev` and `next` in
    /// `[min, max]` (0 ≤ min ≤ max ≤ π expected). No rest-shape check (see
    /// [`Angle::rest_angle`]).
    pub fn new(prev: u32, centre: u32, next: u32, min: f64, max: f64) -> Self {
        Angle { vertices: [prev, centre, next], min, max }
    }

    /// The angle at `centre` between `prev` and `next` in `rest`, or `None` for a corner with
    /// a repeated vertex or an edge of length ≤ 1e-12.
    pub fn rest_angle(prev: u32, centre: u32, next: u32, rest: &[DVec3]) -> Option<f64> {
        if prev == centre || next == centre {
            return None;
        }
        let x = rest[centre as usize];
        let (e1, e2) = (rest[prev as usize] - x, rest[next as usize] - x);
        (e1.length() > MIN_REST_LENGTH && e2.length() > MIN_REST_LENGTH).then(|| angle_between(e1, e2))
    }

    /// The range [min, max] of the angle.
    pub fn range(&self) -> (f64, f64) {
        (self.min, self.max)
    }
}

/// The nearest pair to (e₁, e₂) whose angle is in [min, max] (module doc).
fn project_angle(e1: DVec3, e2: DVec3, min: f64, max: f64) -> [DVec3; 2] {
    let (a, b) = (e1.length_squared(), e2.length_squared());
    if !(a > 0.0 && b > 0.0 && a.is_finite() && b.is_finite()) {
        return [e1, e2];
    }
    let (n1, n2) = (a.sqrt(), b.sqrt());
    let (u1, u2) = (e1 / n1, e2 / n2);
    let normal = u1.cross(u2);
    let (sin, cos) = (normal.length(), u1.dot(u2));
    let theta = sin.atan2(cos);
    if theta >= min && theta <= max {
        return [e1, e2];
    }
    let opening = theta < min;
    let delta = if opening { min - theta } else { theta - max };
    if delta > FRAC_PI_2 {
        return if a <= b { [DVec3::ZERO, e2] } else { [e1, DVec3::ZERO] };
    }
    // In-plane frame (u₁, k) with u₂ = cos θ u₁ + sin θ k; w₁ = k turns e₁ towards e₂ and
    // w₂ = sin θ u₁ − cos θ k turns e₂ towards e₁ (both negated to open).
    let k = normal.cross(u1).normalize_or(u1.any_orthonormal_vector());
    let r = sin.hypot(cos);
    let (s, c) = if r > 0.0 { (sin / r, cos / r) } else { (0.0, 1.0) };
    let sign = if opening { -1.0 } else { 1.0 };
    let (w1, w2) = (sign * k, sign * (s * u1 - c * k));
    let (s2d, c2d) = (2.0 * delta).sin_cos();
    let gamma1 = 0.5 * (b * s2d).atan2(a + b * c2d);
    let gamma2 = (delta - gamma1).max(0.0);
    let turn = |e: DVec3, n: f64, w: DVec3, g: f64| {
        let (sg, cg) = g.sin_cos();
        cg * (cg * e + sg * n * w)
    };
    [turn(e1, n1, w1, gamma1), turn(e2, n2, w2, gamma2)]
}

impl Constraint for Angle {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        2
    }
    fn rows(&self, sink: &mut RowSink) {
        let [prev, centre, next] = self.vertices;
        sink.push(0, prev, 1.0);
        sink.push(0, centre, -1.0);
        sink.push(1, next, 1.0);
        sink.push(1, centre, -1.0);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let [prev, centre, next] = self.vertices.map(|v| q[v as usize]);
        let [p1, p2] = project_angle(prev - centre, next - centre, self.min, self.max);
        out[0] = p1;
        out[1] = p2;
    }
    /// The shorter vector's length times the angle's distance from [min, max]: about the
    /// distance from the set, and 0 when a vector is zero.
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let shorter = p[0].length().min(p[1].length());
        if shorter == 0.0 { 0.0 } else { shorter * interval_distance(angle_between(p[0], p[1]), self.min, self.max) }
    }
}

/// Builds an [`Angle`] on every corner of every selected polygon face (of 3 or more corners).
/// Options `min`, `max` (radians; default each corner's rest angle). Default multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct AngleType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "angle: the angle at each corner of a face stays within [min, max] radians (default its rest angle)",
    options: &[MIN_OPTION, MAX_OPTION],
    element: Element::Face { min: 3, max: usize::MAX },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for AngleType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let min = params.number(KIND, &MIN_OPTION)?;
        let max = params.number(KIND, &MAX_OPTION)?;
        if let (Some(lo), Some(hi)) = (min, max)
            && lo > hi
        {
            return Err(ConstraintError::Invalid {
                kind: KIND,
                problem: format!("\"min\" ({lo}) is larger than \"max\" ({hi})"),
            });
        }
        let rest = &ctx.rest.positions;
        let mut built: Vec<Box<dyn Constraint>> = Vec::new();
        for (f, corners) in ctx.rest.faces.iter().enumerate() {
            let n = corners.len();
            if n < 3 || !ctx.selection.contains_face(f, corners) {
                continue;
            }
            for k in 0..n {
                let (prev, centre, next) = (corners[(k + n - 1) % n], corners[k], corners[(k + 1) % n]);
                let Some(theta) = Angle::rest_angle(prev, centre, next, rest) else { continue };
                let (lo, hi) = match (min, max) {
                    (Some(lo), Some(hi)) => (lo, hi),
                    (Some(lo), None) => (lo, theta.max(lo)),
                    (None, Some(hi)) => (theta.min(hi), hi),
                    (None, None) => (theta, theta),
                };
                built.push(Box::new(Angle::new(prev, centre, next, lo, hi)));
            }
        }
        non_empty(built, KIND, "polygon faces")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::mesh::Polygons;
    use glam::{DMat3, DQuat};

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    /// A random pair of the set: two directions at an angle in [lo, hi], random lengths.
    fn sample_of_set(rng: &mut Rng, lo: f64, hi: f64, plane: Option<(DVec3, DVec3)>) -> [DVec3; 2] {
        let (x, y) = plane.unwrap_or_else(|| {
            let r = rotation(rng);
            (r.x_axis, r.y_axis)
        });
        let phi = 4.0 * rng.uniform();
        let angle = lo + (hi - lo) * 0.5 * (1.0 + rng.uniform());
        let d1 = x * phi.cos() + y * phi.sin();
        let d2 = x * (phi + angle).cos() + y * (phi + angle).sin();
        [d1 * (1.0 + rng.uniform()), d2 * (1.0 + rng.uniform())]
    }

    /// Brute force over the plane of e₁, e₂: min over γ₁ of the cost with γ₂ = Δ − γ₁.
    fn brute_force(e1: DVec3, e2: DVec3, lo: f64, hi: f64) -> f64 {
        let theta = angle_between(e1, e2);
        let delta = if theta < lo {
            lo - theta
        } else if theta > hi {
            theta - hi
        } else {
            return 0.0;
        };
        let (a, b) = (e1.length_squared(), e2.length_squared());
        let s = |g: f64| if g >= FRAC_PI_2 { 1.0 } else { g.sin().powi(2) };
        let mut best = f64::INFINITY;
        for k in 0..=20000 {
            let g = delta * k as f64 / 20000.0;
            best = best.min(a * s(g) + b * s(delta - g));
        }
        best
    }

    #[test]
    fn projection_is_on_the_set_exact_and_no_sample_is_closer() {
        let mut rng = Rng(3);
        for (lo, hi) in [(1.0, 1.0), (0.5, 2.0), (0.0, 0.3), (2.8, PI), (FRAC_PI_2, FRAC_PI_2)] {
            let c = Angle::new(0, 1, 2, lo, hi);
            for trial in 0..200 {
                let mut q = [rng.vec3(), rng.vec3(), rng.vec3()];
                if trial % 4 == 0 {
                    q[2] = q[1] + (q[0] - q[1]) * (0.5 + rng.uniform().abs()); // parallel
                }
                if trial % 4 == 1 {
                    q[2] = q[1] - (q[0] - q[1]) * (0.5 + rng.uniform().abs()); // opposite
                }
                let cq = c.apply(&q);
                let mut p = [DVec3::ZERO; 2];
                c.project(&q, &mut p);
                assert!(c.set_residual(&p) <= 1e-13, "[{lo}, {hi}]: off the set by {}", c.set_residual(&p));
                let d = dist2(&cq, &p);
                let want = brute_force(cq[0], cq[1], lo, hi);
                assert!(d <= want + 1e-12 && d >= want - 1e-5 * (1.0 + want), "[{lo}, {hi}]: {d} vs {want}");
                let n = cq[0].cross(cq[1]);
                let x = cq[0].normalize();
                let plane = (x, n.cross(x).normalize_or(x.any_orthonormal_vector()));
                for _ in 0..300 {
                    let general = sample_of_set(&mut rng, lo, hi, None);
                    assert!(d <= dist2(&cq, &general) + 1e-12, "[{lo}, {hi}]: a sample is closer");
                    let in_plane = sample_of_set(&mut rng, lo, hi, Some(plane));
                    assert!(d <= dist2(&cq, &in_plane) + 1e-12, "[{lo}, {hi}]: an in-plane sample is closer");
                    // Collapsing one vector is also on the set.
                    assert!(d <= (cq[0].length_squared()).min(cq[1].length_squared()) + 1e-12);
                }
            }
        }
    }

    #[test]
    fn within_range_and_zero_vectors_are_unchanged_and_rigid_motions_commute() {
        let c = Angle::new(0, 1, 2, 0.5, 1.0);
        let mut p = [DVec3::ZERO; 2];
        let q = [DVec3::X, DVec3::ZERO, DVec3::new(0.8f64.cos(), 0.8f64.sin(), 0.0) * 2.0];
        c.project(&q, &mut p);
        assert_eq!(p, [q[0], q[2]]);
        let q = [DVec3::ZERO, DVec3::ZERO, DVec3::Y];
        c.project(&q, &mut p);
        assert_eq!(p, [DVec3::ZERO, DVec3::Y]);
        assert_eq!(c.set_residual(&p), 0.0);
        let mut rng = Rng(8);
        for _ in 0..50 {
            let q = [rng.vec3(), rng.vec3(), rng.vec3()];
            let (r, shift) = (rotation(&mut rng), rng.vec3());
            let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
            c.project(&q, &mut p);
            let turned = [r * p[0], r * p[1]];
            let mut p_moved = [DVec3::ZERO; 2];
            c.project(&moved, &mut p_moved);
            assert!(dist2(&turned, &p_moved) < 1e-24);
        }
    }

    #[test]
    fn a_right_angle_closed_symmetrically() {
        // Equal edges at π/2 closed to π/3: each turns by π/12 and shortens by cos(π/12).
        let c = Angle::new(0, 1, 2, 0.0, PI / 3.0);
        let mut p = [DVec3::ZERO; 2];
        c.project(&[DVec3::X, DVec3::ZERO, DVec3::Y], &mut p);
        let g = PI / 12.0;
        let want = [DVec3::new(g.cos(), g.sin(), 0.0) * g.cos(), DVec3::new(g.sin(), g.cos(), 0.0) * g.cos()];
        assert!(dist2(&p, &want) < 1e-30, "{p:?}");
        // A wide change: the shorter vector collapses.
        let c = Angle::new(0, 1, 2, 2.9, PI);
        c.project(&[DVec3::X * 0.5, DVec3::ZERO, DVec3::new(1.0, 0.1, 0.0)], &mut p);
        assert_eq!(p, [DVec3::ZERO, DVec3::new(1.0, 0.1, 0.0)]);
    }

    fn quad_rest() -> RestGeometry {
        // A unit square and a triangle sharing an edge (faces as polygons).
        let positions = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y, DVec3::new(2.0, 0.5, 0.0)];
        let mut rest = RestGeometry::new(positions, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]], vec![]);
        let mut faces = Polygons::new();
        faces.push(&[0, 1, 2, 3]);
        faces.push(&[1, 4, 2]);
        rest.faces = faces;
        rest
    }

    #[test]
    fn build_makes_one_constraint_per_corner_with_rest_angles_and_checks_options() {
        let rest = quad_rest();
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 7);
        for c in &built {
            assert!(c.energy(&rest.positions) < 1e-28);
        }
        let quad = Selection::from_faces(5, &rest.faces, &[0]);
        let ctx_quad = BuildContext { rest: &rest, selection: &quad, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx_quad, Params::default().with("max", 1.0)).unwrap();
        assert_eq!(built.len(), 4);
        let range = |c: &dyn Constraint| {
            let any: &dyn std::any::Any = c;
            any.downcast_ref::<Angle>().unwrap().range()
        };
        // Only max given: min is the rest angle π/2, moved down to max.
        assert!(built.iter().all(|c| range(c.as_ref()) == (1.0, 1.0)));
        let built = build_constraints(KIND, &ctx_quad, Params::default().with("max", 2.0)).unwrap();
        assert!(built.iter().all(|c| (range(c.as_ref()).0 - FRAC_PI_2).abs() < 1e-15 && range(c.as_ref()).1 == 2.0));
        // Only min given: every rest angle here is below 2, so each max moves up to it.
        let built = build_constraints(KIND, &ctx, Params::default().with("min", 2.0)).unwrap();
        assert_eq!(built.len(), 7);
        assert!(built.iter().all(|c| range(c.as_ref()) == (2.0, 2.0)));
        let err = build_constraints(KIND, &ctx, Params::default().with("min", 2.0).with("max", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }), "{err}");
        assert!(err.to_string().contains("\"min\"") && err.to_string().contains("\"max\""), "{err}");
        for key in ["min", "max"] {
            for bad in [-0.1, 3.5] {
                let err = build_constraints(KIND, &ctx, Params::default().with(key, bad)).unwrap_err();
                assert!(matches!(err, ConstraintError::BadOption { .. }) && err.to_string().contains(key), "{err}");
            }
        }
        let none = Selection::from_indices(5, &[0, 1, 4]);
        let ctx = BuildContext { rest: &rest, selection: &none, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
    }
}
