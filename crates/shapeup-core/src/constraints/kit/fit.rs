//! The fit machinery of the sphere and circle types (docs/math.md, "circle" and "sphere"): the
//! generalized-sphere distance ([`distance`]), the algebraic-to-curvature conversion
//! ([`from_algebraic`]) and the multi-start Levenberg–Marquardt fit ([`Model`], [`best_fit`]).

use crate::linalg::jet::{Jet1, Jet2, Scalar, V3};
use crate::linalg::small::solve_spd;
use glam::DVec3;

/// Gauss–Newton iterations at most from each start ([`best_fit`]).
const START_ITERATIONS: usize = 30;
/// A start's Gauss–Newton refinement stops at steps this small.
const START_TOLERANCE: f64 = 1e-7;
/// Iterations at most on the best start's fit (Gauss–Newton, then damped Newton).
const POLISH_ITERATIONS: usize = 60;
/// Gauss–Newton counts as slow when a step is more than this fraction of the one before.
const SLOW_RATE: f64 = 0.25;
/// Damping increases tried in one iteration before the fit counts as converged.
const MAX_TRIES: usize = 40;
/// The fit has converged when an accepted step changes no parameter by more than this
/// (in units of the points' RMS radius, where every parameter is of order 1).
const STEP_TOLERANCE: f64 = 1e-13;
/// Initial relative damping λ.
const INITIAL_DAMPING: f64 = 1e-4;
/// Smallest relative damping λ (steps are then Newton's or Gauss–Newton's to rounding).
const MIN_DAMPING: f64 = 1e-15;
/// Steps this small (every coordinate) are taken when the cost is unchanged up to rounding.
const SMALL_STEP: f64 = 1e-6;
/// Relative rounding of the cost, a sum of squares of order-one terms.
const COST_ROUNDING: f64 = 1e-13;

/// The signed distance of a point from a generalized sphere (or, in a plane, circle) through
/// s with unit normal n there and curvature κ ([`distance`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Distance {
    /// dist = (2 y·n + κ‖y‖²)/(1 + ‖w‖): positive on the side n points to.
    pub d: f64,
    /// w = n + κ y, along the normal through the point (κ (x − c)).
    w: DVec3,
    w_len: f64,
}

/// The signed distance of s + y from the generalized sphere through s with unit normal n and
/// curvature κ: exact for every κ (κ = 0: the plane y·n = 0).
pub(crate) fn distance(y: DVec3, n: DVec3, kappa: f64) -> Distance {
    let w = n + kappa * y;
    let w_len = w.length();
    Distance { d: (2.0 * y.dot(n) + kappa * y.length_squared()) / (1.0 + w_len), w, w_len }
}

impl Distance {
    /// The unit direction along which the point moves to its nearest point (x − d·direction):
    /// w/‖w‖, or n at the centre, where every point of the sphere is as near.
    pub(crate) fn direction(&self, n: DVec3) -> DVec3 {
        if self.w_len > 0.0 && self.w_len.is_finite() { self.w / self.w_len } else { n }
    }
}

/// [`distance`] in any [`Scalar`]: (2 y·n + κ‖y‖²)/(1 + ‖n + κ y‖).
pub(crate) fn distance_in<T: Scalar>(y: V3<T>, n: V3<T>, kappa: T) -> T {
    let w = n.add(y.times(kappa));
    let denominator = T::constant(1.0) + w.dot(w).sqrt();
    (y.dot(n).scale(2.0) + kappa * y.dot(y)) * denominator.recip()
}

/// The generalized sphere a‖x‖² + b·x + e = 0 as (s, n, κ): s its point nearest the origin,
/// n the unit normal there (the gradient's direction), κ = 2a/√(‖b‖² − 4ae). `None` for an
/// imaginary or non-finite one. `fallback` is the direction of s when the origin is the centre.
pub(crate) fn from_algebraic(a: f64, b: DVec3, e: f64, fallback: DVec3) -> Option<(DVec3, DVec3, f64)> {
    let disc = b.length_squared() - 4.0 * a * e;
    if disc.is_nan() || disc <= 0.0 || disc.is_infinite() {
        return None;
    }
    let root = disc.sqrt();
    let (a, b, e) = (a / root, b / root, e / root);
    // Normalized (‖b‖² − 4ae = 1): the origin's signed distance is 2e/(1 + √(1 + 4ae)).
    let d0 = 2.0 * e / (1.0 + (1.0 + 4.0 * a * e).max(0.0).sqrt());
    let along = b.normalize_or(fallback);
    let s = -d0 * along;
    let n = (2.0 * a * s + b).normalize_or(along);
    let fit = (s, n, 2.0 * a);
    (s.is_finite() && n.is_finite() && fit.2.is_finite()).then_some(fit)
}

/// A shape fitted by [`best_fit`]: its residuals at the points as functions of P local
/// coordinates θ (the shape [`Model::step`] gives, to second order at θ = 0), and that step.
pub(crate) trait Model<const P: usize>: Copy {
    /// Calls `each` with every residual at `points`, for the shape moved by `theta`.
    fn residuals<T: Scalar>(&self, points: &[DVec3], theta: [T; P], each: impl FnMut(T));
    /// The shape moved by `delta` in the local coordinates of [`Model::residuals`].
    fn step(&self, delta: &[f64; P]) -> Self;
}

/// Σ r² at the model.
fn cost_of<const P: usize, M: Model<P>>(model: &M, points: &[DVec3]) -> f64 {
    let mut cost = 0.0;
    model.residuals(points, [0.0; P], |r: f64| cost += r * r);
    cost
}

/// The gradient Σ r ∇r and the Gauss–Newton matrix Σ ∇r ∇rᵀ (with `exact`, plus Σ r ∇²r:
/// the Hessian of ½ Σ r²) at the model.
fn linearize<const P: usize, M: Model<P>>(model: &M, points: &[DVec3], exact: bool) -> ([f64; P], [[f64; P]; P]) {
    let mut gradient = [0.0; P];
    let mut matrix = [[0.0; P]; P];
    let mut add = |r: f64, g: &[f64; P], h: Option<&[[f64; P]; P]>| {
        for i in 0..P {
            gradient[i] += r * g[i];
            for j in 0..P {
                matrix[i][j] += g[i] * g[j] + h.map_or(0.0, |h| r * h[i][j]);
            }
        }
    };
    if exact {
        model.residuals(points, std::array::from_fn(Jet2::variable), |r: Jet2<P>| add(r.v, &r.g, Some(&r.h)));
    } else {
        model.residuals(points, std::array::from_fn(Jet1::variable), |r: Jet1<P>| add(r.v, &r.g, None));
    }
    (gradient, matrix)
}

/// Levenberg–Marquardt from `start` on the sum of squared residuals, with Gauss–Newton's
/// matrix A = Σ ∇r∇rᵀ, or (with `newton`, once Gauss–Newton's steps shrink by less than
/// [`SLOW_RATE`] or it stalls) the exact Hessian of ½Σr²: damped Newton, which crosses the flat
/// valleys of nearly straight or flat input in a few steps where Gauss–Newton crawls, at a
/// higher cost per step. Returns the model and its cost (infinite when the start's is not
/// finite). Deterministic:
/// steps solve (A + μI) δ = −Σ r∇r, μ = λ tr(A)/P (invariant under orthogonal changes of the
/// local coordinates), λ ×4 until a step is accepted and ÷3 after; a step is accepted when the
/// cost falls, or when it is small ([`SMALL_STEP`]) and the cost unchanged up to rounding (near
/// the minimum the cost is flat to second order, so only the gradient still resolves the
/// parameters); stops after `iterations`, when no damping gives an accepted step, or when a
/// step changes no coordinate by more than `tolerance`.
fn refine<const P: usize, M: Model<P>>(
    start: M,
    points: &[DVec3],
    newton: bool,
    tolerance: f64,
    iterations: usize,
) -> (M, f64) {
    let mut model = start;
    let mut cost = cost_of(&model, points);
    if !cost.is_finite() {
        return (model, f64::INFINITY);
    }
    let mut damping = INITIAL_DAMPING;
    let mut exact = false;
    let mut previous = f64::INFINITY;
    for _ in 0..iterations {
        if cost == 0.0 {
            break;
        }
        let (gradient, matrix) = linearize(&model, points, exact);
        let trace = (0..P).map(|i| matrix[i][i]).sum::<f64>() / P as f64;
        let unit = if trace > 0.0 && trace.is_finite() { trace } else { 1.0 };
        let mut accepted = None;
        for _ in 0..MAX_TRIES {
            let mut damped = matrix;
            for (i, row) in damped.iter_mut().enumerate() {
                row[i] += damping * unit;
            }
            if let Some(delta) = solve_spd(damped, gradient.map(|x| -x)) {
                let candidate = model.step(&delta);
                let c = cost_of(&candidate, points);
                let largest = delta.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
                if c < cost || (largest <= SMALL_STEP && c <= cost * (1.0 + COST_ROUNDING)) {
                    accepted = Some((candidate, c, largest));
                    break;
                }
            }
            damping *= 4.0;
        }
        let Some((candidate, c, largest)) = accepted else {
            if newton && !exact {
                // Gauss–Newton stalled short of the tolerance: the exact Hessian may go on.
                exact = true;
                continue;
            }
            break;
        };
        damping = (damping / 3.0).max(MIN_DAMPING);
        model = candidate;
        cost = c;
        if largest <= tolerance {
            break;
        }
        // Gauss–Newton converges linearly; once it is slow, switch to Newton.
        exact |= newton && largest > SLOW_RATE * previous;
        previous = largest;
    }
    (model, cost)
}

/// The geometric best fit from several starts, and its cost: each start refined by
/// Gauss–Newton ([`START_ITERATIONS`] at most, to steps of [`START_TOLERANCE`]), then the
/// lowest (the first on ties: deterministic) refined on, by Gauss–Newton while it converges
/// fast and damped Newton after, to steps of [`STEP_TOLERANCE`] ([`POLISH_ITERATIONS`] at
/// most). `None` without starts.
pub(crate) fn best_fit<const P: usize, M: Model<P>>(
    starts: impl IntoIterator<Item = M>,
    points: &[DVec3],
) -> Option<(M, f64)> {
    let mut best: Option<(M, f64)> = None;
    for start in starts {
        let fit = refine(start, points, false, START_TOLERANCE, START_ITERATIONS);
        if best.is_none_or(|(_, cost)| fit.1 < cost) {
            best = Some(fit);
        }
    }
    best.map(|(model, _)| refine(model, points, true, STEP_TOLERANCE, POLISH_ITERATIONS))
}

/// The RMS distance of `points` from their centroid, and the centroid.
pub(crate) fn rms_radius(points: &[DVec3]) -> (DVec3, f64) {
    let k = points.len().max(1) as f64;
    let mean = points.iter().copied().sum::<DVec3>() / k;
    (mean, (points.iter().map(|&x| (x - mean).length_squared()).sum::<f64>() / k).sqrt())
}

#[cfg(test)]
pub(crate) mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::Rng;

    #[test]
    fn distance_matches_the_centre_radius_form() {
        let mut rng = Rng(23);
        for _ in 0..200 {
            let (s, n, kappa) = (rng.vec3(), rng.vec3().normalize(), 3.0 * rng.uniform());
            let x = 2.0 * rng.vec3();
            let dist = distance(x - s, n, kappa);
            let generic = distance_in(V3::constant(x - s), V3::constant(n), kappa);
            assert!((dist.d - generic).abs() < 1e-14 * (1.0 + generic.abs()));
            if kappa.abs() > 1e-3 {
                let c = s - n / kappa;
                let want = ((x - c).length() - 1.0 / kappa.abs()) * kappa.signum();
                assert!((dist.d - want).abs() < 1e-10 * (1.0 + want.abs()), "{} vs {want}", dist.d);
                let p = x - dist.d * dist.direction(n);
                assert!(((p - c).length() - 1.0 / kappa.abs()).abs() < 1e-10 / kappa.abs());
            }
        }
    }

    /// The gradient and (exact) Hessian [`linearize`] gives, against central differences of
    /// the cost along the model's own steps: the residuals' local coordinates are the steps'.
    pub(crate) fn check_derivatives<const P: usize, M: Model<P>>(model: M, points: &[DVec3]) {
        let cost = |delta: [f64; P]| cost_of(&model.step(&delta), points);
        let (gradient, hessian) = linearize(&model, points, true);
        let (_, gauss_newton) = linearize(&model, points, false);
        let unit = |i: usize, h: f64| -> [f64; P] { std::array::from_fn(|j| if i == j { h } else { 0.0 }) };
        let add = |a: [f64; P], b: [f64; P]| -> [f64; P] { std::array::from_fn(|j| a[j] + b[j]) };
        let h = 1e-4;
        let scale = 1.0 + cost([0.0; P]);
        for i in 0..P {
            let numeric = (cost(unit(i, h)) - cost(unit(i, -h))) / (2.0 * h);
            assert!((numeric - 2.0 * gradient[i]).abs() < 1e-6 * scale, "∂{i}: {numeric} vs {}", 2.0 * gradient[i]);
            for j in 0..P {
                let numeric = (cost(add(unit(i, h), unit(j, h)))
                    - cost(add(unit(i, h), unit(j, -h)))
                    - cost(add(unit(i, -h), unit(j, h)))
                    + cost(add(unit(i, -h), unit(j, -h))))
                    / (4.0 * h * h);
                assert!(
                    (numeric - 2.0 * hessian[i][j]).abs() < 1e-4 * scale,
                    "∂{i}∂{j}: {numeric} vs {}",
                    2.0 * hessian[i][j]
                );
                assert!((hessian[i][j] - hessian[j][i]).abs() < 1e-12 * scale);
                assert!((gauss_newton[i][j] - gauss_newton[j][i]).abs() < 1e-12 * scale);
            }
        }
    }
}
