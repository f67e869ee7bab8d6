//! Sphere: a set of vertices kept on a common sphere.
//!
//! Term: ω Σ_i ‖(q_i − q̄) − p_i‖² over the k ≥ 4 selected vertices, q̄ = (1/k) Σ_j q_j. The k
//! rows of C are mean-centred as in ShapeOp, C = I − 11ᵀ/k, so the set is that of the centred
//! configurations on one sphere, S = {p : Σ_i p_i = 0, ‖p_i − c‖ = r for some c, r}, taken
//! with its closure: the coplanar configurations (spheres of infinite radius). Without them the
//! nearest point would not exist for flat input, whose best spheres grow without bound.
//!
//! Projection: the nearest point of S to d_i = q_i − q̄ (the rows of C q) is the geometric
//! best-fit sphere, argmin Σ_i (‖d_i − c‖ − r)², with each d_i moved to its nearest point on it,
//! p_i = c + r (d_i − c)/‖d_i − c‖; then p is recentred (a shift stays on a sphere and only
//! brings p nearer to the centred d). The fit, on the points scaled to unit RMS radius:
//! 1. starts: the algebraic (Kåsa) sphere, the least-squares solution of
//!    ‖x‖² + b·x + e = 0 (linear in b, e); the same sphere curved the other way at its point
//!    nearest the centroid (the other side of a nearly flat set); the best-fit plane (PCA);
//! 2. each start refined by Levenberg–Marquardt with Gauss–Newton steps (to steps of 1e-7,
//!    at most 30 iterations), then the lowest (the first on ties) refined on to steps of 1e-13
//!    (at most 60 iterations): by Gauss–Newton while it converges fast, by damped Newton on the
//!    exact Hessian (forward-mode second derivatives of the same residuals) once it is slow,
//!    as in the flat valleys of nearly flat sets. Damping μ = λ tr(A)/4 on the step's matrix A,
//!    λ ×4 until the cost falls and ÷3 after ([`best_fit`]). Deterministic, and equivariant
//!    under rigid motions since every start is.
//!
//! The sphere is parametrized by a point s on it, the unit normal n there and the signed
//! curvature κ (centre s − n/κ, radius 1/|κ|; κ = 0 the plane through s normal to n), with the
//! signed distance of x, y = x − s, w = n + κ y:
//! dist = (2 y·n + κ‖y‖²) / (1 + ‖w‖), nearest point x − dist·w/‖w‖,
//! which is exact, has no cancellation for large radii and passes smoothly through planes
//! (Karimäki's circle parametrization, in 3D). Steps rotate n about s (two tangent angles),
//! move s along n and change κ: the sphere's 4 degrees of freedom.
//!
//! Set residual (a direct test of the definition, no fit): the smallest singular value σ₅ of
//! the k×5 matrix with rows (‖y_i‖²/L, y_i, L), y_i = p_i − p̄, L = max ‖y_i‖
//! ([`sets::lifted_singular_values`]), which vanishes exactly when one sphere or plane holds
//! every p_i, combined with the centroid offset ‖Σ p_i‖/√k.
//!
//! ω = 1: the term is already the squared distance (length²) of the points from the set; as in
//! ShapeOp the weight is left to the group multiplier. Default multiplier 10 (as edge springs).
//!
//! Sources: ShapeUp (Bouaziz et al. 2012, §4 "spheres": points projected on their best-fit
//! sphere) and ShapeOp's `SphereConstraint` (Deuss et al. 2015: mean-centred rows, the
//! algebraic (Kåsa) sphere; when its 3×3 system is nearly singular, determinant ≤ 1e-5, the
//! points are left as they are). Choices left open: the algebraic fit is not the nearest point
//! of the set (it minimizes Σ(‖x_i − c‖² − r²)², which weights points by their distance), so we
//! refine it to the geometric fit; nearly flat sets go to large spheres or the plane (the
//! closure) instead of a scale-dependent determinant threshold; the starts, the parametrization
//! and the schedule above are ours; four points always lie on a sphere or plane, so at k = 4
//! the term is zero.
//!
//! This file also holds the fit machinery that [`super::circle`] shares: the generalized-sphere
//! distance ([`distance`]), the algebraic-to-curvature conversion ([`from_algebraic`]), the
//! small Cholesky solve ([`solve_spd`]), numbers with derivatives ([`Scalar`], [`V3`]) and the
//! multi-start Levenberg–Marquardt fit ([`Model`], [`best_fit`]).

use super::line::{centred, centred_rows, centred_view, recentre, to_row_frame, vertex_set};
use super::{BuildContext, Constraint, ConstraintError, ConstraintType, Element, OptionSpec, Params, RowSink, sets};
use glam::{DQuat, DVec3};

/// Name in scene files.
const KIND: &str = "sphere";

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
pub(super) struct Distance {
    /// dist = (2 y·n + κ‖y‖²)/(1 + ‖w‖): positive on the side n points to.
    pub d: f64,
    /// w = n + κ y, along the normal through the point (κ (x − c)).
    w: DVec3,
    w_len: f64,
}

/// The signed distance of s + y from the generalized sphere through s with unit normal n and
/// curvature κ: exact for every κ (κ = 0: the plane y·n = 0).
pub(super) fn distance(y: DVec3, n: DVec3, kappa: f64) -> Distance {
    let w = n + kappa * y;
    let w_len = w.length();
    Distance { d: (2.0 * y.dot(n) + kappa * y.length_squared()) / (1.0 + w_len), w, w_len }
}

impl Distance {
    /// The unit direction along which the point moves to its nearest point (x − d·direction):
    /// w/‖w‖, or n at the centre, where every point of the sphere is as near.
    pub(super) fn direction(&self, n: DVec3) -> DVec3 {
        if self.w_len > 0.0 && self.w_len.is_finite() { self.w / self.w_len } else { n }
    }
}

/// A number the fits' residuals are computed in: `f64` for values, [`Jet1`] for values and
/// gradients, [`Jet2`] for values, gradients and Hessians (forward-mode differentiation, so
/// that one residual formula gives the exact derivatives).
pub(super) trait Scalar:
    Copy + std::ops::Add<Output = Self> + std::ops::Sub<Output = Self> + std::ops::Mul<Output = Self>
{
    /// A constant.
    fn constant(x: f64) -> Self;
    /// Times a constant.
    fn scale(self, c: f64) -> Self;
    /// Square root (derivatives taken as 0 at 0, where it has none: only reached at a
    /// sphere's centre, where every direction is as good).
    fn sqrt(self) -> Self;
    /// 1/x.
    fn recip(self) -> Self;
}

impl Scalar for f64 {
    fn constant(x: f64) -> Self {
        x
    }
    fn scale(self, c: f64) -> Self {
        self * c
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn recip(self) -> Self {
        1.0 / self
    }
}

/// A value with its gradient in P variables.
#[derive(Debug, Clone, Copy)]
pub(super) struct Jet1<const P: usize> {
    v: f64,
    g: [f64; P],
}

impl<const P: usize> Jet1<P> {
    fn variable(i: usize) -> Self {
        let mut g = [0.0; P];
        g[i] = 1.0;
        Jet1 { v: 0.0, g }
    }
    /// f(x) with f(v) = f0, f′(v) = f1.
    fn chain(self, f0: f64, f1: f64) -> Self {
        Jet1 { v: f0, g: self.g.map(|x| f1 * x) }
    }
}

impl<const P: usize> std::ops::Add for Jet1<P> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Jet1 { v: self.v + o.v, g: std::array::from_fn(|i| self.g[i] + o.g[i]) }
    }
}

impl<const P: usize> std::ops::Sub for Jet1<P> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Jet1 { v: self.v - o.v, g: std::array::from_fn(|i| self.g[i] - o.g[i]) }
    }
}

impl<const P: usize> std::ops::Mul for Jet1<P> {
    type Output = Self;
    /// The product rule.
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn mul(self, o: Self) -> Self {
        Jet1 { v: self.v * o.v, g: std::array::from_fn(|i| self.v * o.g[i] + o.v * self.g[i]) }
    }
}

impl<const P: usize> Scalar for Jet1<P> {
    fn constant(x: f64) -> Self {
        Jet1 { v: x, g: [0.0; P] }
    }
    fn scale(self, c: f64) -> Self {
        Jet1 { v: self.v * c, g: self.g.map(|x| x * c) }
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        self.chain(r, if r > 0.0 { 0.5 / r } else { 0.0 })
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r)
    }
}

/// A value with its gradient and Hessian in P variables.
#[derive(Debug, Clone, Copy)]
pub(super) struct Jet2<const P: usize> {
    v: f64,
    g: [f64; P],
    h: [[f64; P]; P],
}

impl<const P: usize> Jet2<P> {
    fn variable(i: usize) -> Self {
        let mut g = [0.0; P];
        g[i] = 1.0;
        Jet2 { v: 0.0, g, h: [[0.0; P]; P] }
    }
    /// f(x) with f(v) = f0, f′(v) = f1, f″(v) = f2.
    fn chain(self, f0: f64, f1: f64, f2: f64) -> Self {
        let g = self.g;
        Jet2 {
            v: f0,
            g: g.map(|x| f1 * x),
            h: std::array::from_fn(|i| std::array::from_fn(|j| f1 * self.h[i][j] + f2 * g[i] * g[j])),
        }
    }
}

impl<const P: usize> std::ops::Add for Jet2<P> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Jet2 {
            v: self.v + o.v,
            g: std::array::from_fn(|i| self.g[i] + o.g[i]),
            h: std::array::from_fn(|i| std::array::from_fn(|j| self.h[i][j] + o.h[i][j])),
        }
    }
}

impl<const P: usize> std::ops::Sub for Jet2<P> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Jet2 {
            v: self.v - o.v,
            g: std::array::from_fn(|i| self.g[i] - o.g[i]),
            h: std::array::from_fn(|i| std::array::from_fn(|j| self.h[i][j] - o.h[i][j])),
        }
    }
}

impl<const P: usize> std::ops::Mul for Jet2<P> {
    type Output = Self;
    /// The product rule, to second order.
    #[allow(clippy::suspicious_arithmetic_impl)]
    fn mul(self, o: Self) -> Self {
        Jet2 {
            v: self.v * o.v,
            g: std::array::from_fn(|i| self.v * o.g[i] + o.v * self.g[i]),
            h: std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    self.v * o.h[i][j] + o.v * self.h[i][j] + self.g[i] * o.g[j] + o.g[i] * self.g[j]
                })
            }),
        }
    }
}

impl<const P: usize> Scalar for Jet2<P> {
    fn constant(x: f64) -> Self {
        Jet2 { v: x, g: [0.0; P], h: [[0.0; P]; P] }
    }
    fn scale(self, c: f64) -> Self {
        Jet2 { v: self.v * c, g: self.g.map(|x| x * c), h: self.h.map(|row| row.map(|x| x * c)) }
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        if r > 0.0 { self.chain(r, 0.5 / r, -0.25 / (r * self.v)) } else { self.chain(r, 0.0, 0.0) }
    }
    fn recip(self) -> Self {
        let r = 1.0 / self.v;
        self.chain(r, -r * r, 2.0 * r * r * r)
    }
}

/// A 3-vector of [`Scalar`]s.
#[derive(Debug, Clone, Copy)]
pub(super) struct V3<T>(pub T, pub T, pub T);

impl<T: Scalar> V3<T> {
    /// A constant vector.
    pub(super) fn constant(v: DVec3) -> Self {
        V3(T::constant(v.x), T::constant(v.y), T::constant(v.z))
    }
    /// The constant vector v times the number a.
    pub(super) fn along(v: DVec3, a: T) -> Self {
        V3(a.scale(v.x), a.scale(v.y), a.scale(v.z))
    }
    pub(super) fn add(self, o: Self) -> Self {
        V3(self.0 + o.0, self.1 + o.1, self.2 + o.2)
    }
    pub(super) fn sub(self, o: Self) -> Self {
        V3(self.0 - o.0, self.1 - o.1, self.2 - o.2)
    }
    pub(super) fn times(self, a: T) -> Self {
        V3(self.0 * a, self.1 * a, self.2 * a)
    }
    pub(super) fn scale(self, c: f64) -> Self {
        V3(self.0.scale(c), self.1.scale(c), self.2.scale(c))
    }
    pub(super) fn dot(self, o: Self) -> T {
        self.0 * o.0 + self.1 * o.1 + self.2 * o.2
    }
    pub(super) fn cross(self, o: Self) -> Self {
        V3(self.1 * o.2 - self.2 * o.1, self.2 * o.0 - self.0 * o.2, self.0 * o.1 - self.1 * o.0)
    }
    /// R(ω) v to second order in ω: v + ω × v + ½ ω × (ω × v) (what the fits' steps do, to
    /// the order their derivatives need).
    pub(super) fn turned(v: DVec3, omega: Self) -> Self {
        let v = Self::constant(v);
        let once = omega.cross(v);
        v.add(once).add(omega.cross(once).scale(0.5))
    }
}

/// [`distance`] in any [`Scalar`]: (2 y·n + κ‖y‖²)/(1 + ‖n + κ y‖).
pub(super) fn distance_in<T: Scalar>(y: V3<T>, n: V3<T>, kappa: T) -> T {
    let w = n.add(y.times(kappa));
    let denominator = T::constant(1.0) + w.dot(w).sqrt();
    (y.dot(n).scale(2.0) + kappa * y.dot(y)) * denominator.recip()
}

/// The generalized sphere a‖x‖² + b·x + e = 0 as (s, n, κ): s its point nearest the origin,
/// n the unit normal there (the gradient's direction), κ = 2a/√(‖b‖² − 4ae). `None` for an
/// imaginary or non-finite one. `fallback` is the direction of s when the origin is the centre.
pub(super) fn from_algebraic(a: f64, b: DVec3, e: f64, fallback: DVec3) -> Option<(DVec3, DVec3, f64)> {
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

/// Solves `a x = b` for a symmetric positive definite P×P `a` (Cholesky); `None` when a pivot
/// is not positive (singular or indefinite) or the result is not finite.
#[allow(clippy::needless_range_loop)] // triangular index patterns read best as indices
pub(super) fn solve_spd<const P: usize>(mut a: [[f64; P]; P], mut b: [f64; P]) -> Option<[f64; P]> {
    for j in 0..P {
        let mut pivot = a[j][j];
        for k in 0..j {
            pivot -= a[j][k] * a[j][k];
        }
        if pivot.is_nan() || pivot <= 0.0 {
            return None;
        }
        let pivot = pivot.sqrt();
        a[j][j] = pivot;
        for i in j + 1..P {
            let mut x = a[i][j];
            for k in 0..j {
                x -= a[i][k] * a[j][k];
            }
            a[i][j] = x / pivot;
        }
    }
    for i in 0..P {
        let mut x = b[i];
        for k in 0..i {
            x -= a[i][k] * b[k];
        }
        b[i] = x / a[i][i];
    }
    for i in (0..P).rev() {
        let mut x = b[i];
        for k in i + 1..P {
            x -= a[k][i] * b[k];
        }
        b[i] = x / a[i][i];
    }
    b.iter().all(|x| x.is_finite()).then_some(b)
}

/// The least-squares solution of Σ_rows (row·x − rhs)² by the normal equations (for the
/// algebraic starts, where an approximate solution is enough); `None` when singular.
pub(super) fn linear_least_squares<const P: usize>(rows: impl Iterator<Item = ([f64; P], f64)>) -> Option<[f64; P]> {
    let mut a = [[0.0; P]; P];
    let mut b = [0.0; P];
    for (row, rhs) in rows {
        for i in 0..P {
            b[i] += row[i] * rhs;
            for j in 0..P {
                a[i][j] += row[i] * row[j];
            }
        }
    }
    solve_spd(a, b)
}

/// A shape fitted by [`best_fit`]: its residuals at the points as functions of P local
/// coordinates θ (the shape [`Model::step`] gives, to second order at θ = 0), and that step.
pub(super) trait Model<const P: usize>: Copy {
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
pub(super) fn best_fit<const P: usize, M: Model<P>>(
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
pub(super) fn rms_radius(points: &[DVec3]) -> (DVec3, f64) {
    let k = points.len().max(1) as f64;
    let mean = points.iter().copied().sum::<DVec3>() / k;
    (mean, (points.iter().map(|&x| (x - mean).length_squared()).sum::<f64>() / k).sqrt())
}

/// A generalized sphere through `s` with unit normal `n` there and curvature `kappa`.
#[derive(Debug, Clone, Copy)]
struct SphereFit {
    s: DVec3,
    n: DVec3,
    kappa: f64,
}

impl Model<4> for SphereFit {
    /// θ = (two tangent angles of n about s, s along n, κ): n(θ) = R(n × τ) n with
    /// τ = θ₀t₁ + θ₁t₂, s(θ) = s + θ₂n, κ(θ) = κ + θ₃.
    fn residuals<T: Scalar>(&self, points: &[DVec3], theta: [T; 4], mut each: impl FnMut(T)) {
        let (t1, t2) = self.n.any_orthonormal_pair();
        let tangent = V3::along(t1, theta[0]).add(V3::along(t2, theta[1]));
        let n = V3::turned(self.n, V3::constant(self.n).cross(tangent));
        let s = V3::constant(self.s).add(V3::along(self.n, theta[2]));
        let kappa = T::constant(self.kappa) + theta[3];
        for &x in points {
            each(distance_in(V3::constant(x).sub(s), n, kappa));
        }
    }
    fn step(&self, delta: &[f64; 4]) -> Self {
        let (t1, t2) = self.n.any_orthonormal_pair();
        let tangent = delta[0] * t1 + delta[1] * t2;
        let n = (DQuat::from_scaled_axis(self.n.cross(tangent)) * self.n).normalize_or(self.n);
        SphereFit { s: self.s + delta[2] * self.n, n, kappa: self.kappa + delta[3] }
    }
}

/// The geometric best-fit generalized sphere of `points` (centred, unit RMS radius), and its
/// cost: the best of the fits from the algebraic start, its mirror and the best-fit plane.
fn fit_sphere(points: &[DVec3]) -> (SphereFit, f64) {
    let (_, _, axes) = sets::principal_axes(points);
    let mut starts = Vec::with_capacity(3);
    let kasa = linear_least_squares(points.iter().map(|&x| ([x.x, x.y, x.z, 1.0], -x.length_squared())));
    if let Some((s, n, kappa)) = kasa.and_then(|a| from_algebraic(1.0, DVec3::new(a[0], a[1], a[2]), a[3], axes[2])) {
        starts.push(SphereFit { s, n, kappa });
        starts.push(SphereFit { s, n, kappa: -kappa });
    }
    let plane = SphereFit { s: DVec3::ZERO, n: axes[2], kappa: 0.0 };
    starts.push(plane);
    best_fit(starts, points).unwrap_or((plane, f64::INFINITY))
}

/// The sphere constraint on a vertex set.
#[derive(Debug, Clone)]
pub struct Sphere {
    vertices: Box<[u32]>,
}

impl Sphere {
    /// Keeps `vertices` (k ≥ 4, distinct) on one sphere; `None` with fewer than 4.
    pub fn new(vertices: Vec<u32>) -> Option<Self> {
        (vertices.len() >= 4).then(|| Sphere { vertices: vertices.into() })
    }
}

impl Constraint for Sphere {
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
        self.vertices.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        centred_rows(&self.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let d = centred(&self.vertices, q);
        let (mean, scale) = rms_radius(&d);
        if !(scale > 0.0 && scale.is_finite()) {
            // Coincident points are on every sphere through them (non-finite input: as given).
            for (o, &x) in out.iter_mut().zip(&d) {
                *o = x - mean;
            }
            to_row_frame(&self.vertices, q, out);
            return;
        }
        let points: Vec<DVec3> = d.iter().map(|&x| (x - mean) / scale).collect();
        let (fit, _) = fit_sphere(&points);
        for (o, &x) in out.iter_mut().zip(&points) {
            let dist = distance(x - fit.s, fit.n, fit.kappa);
            *o = (x - dist.d * dist.direction(fit.n)) * scale;
        }
        recentre(out);
        to_row_frame(&self.vertices, q, out);
    }
    /// √(‖Σ p_i‖²/k + σ₅²), σ₅ the smallest singular value of the lifted rows
    /// (‖y_i‖²/L, y_i, L): zero exactly on one sphere (or plane), centred.
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        let p = centred_view(p);
        let sigma = sets::lifted_singular_values(&p);
        (sets::centroid_offset(&p).powi(2) + sigma[4] * sigma[4]).sqrt()
    }
}

/// Builds one [`Sphere`] over all the selected vertices (at least 4). No options. Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct SphereType;

impl ConstraintType for SphereType {
    fn name(&self) -> &'static str {
        KIND
    }
    fn summary(&self) -> &'static str {
        "sphere: the selected vertices stay on one sphere"
    }
    fn options(&self) -> &'static [OptionSpec] {
        &[]
    }
    fn element(&self) -> Element {
        Element::VertexSet { min: 4 }
    }
    fn default_multiplier(&self) -> f64 {
        10.0
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let vertices = vertex_set(ctx, KIND, 4, "four points always lie on a sphere or a plane")?;
        let sphere = Sphere::new(vertices)
            .ok_or_else(|| ConstraintError::Invalid { kind: KIND, problem: "needs at least 4 vertices".into() })?;
        Ok(vec![Box::new(sphere)])
    }
}

#[cfg(test)]
pub(crate) mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};

    fn project(c: &dyn Constraint, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; c.num_rows()];
        c.project(q, &mut out);
        out
    }

    /// Σ_i (‖x_i − c‖ − r)²: the squared distance of the points from the sphere (c, r).
    fn sphere_cost(points: &[DVec3], c: DVec3, r: f64) -> f64 {
        points.iter().map(|&x| ((x - c).length() - r).powi(2)).sum()
    }

    /// The smallest singular value of the lifted rows, by nalgebra (independent of the
    /// Jacobi SVD the residual uses).
    fn lifted_smallest(p: &[DVec3], columns: usize) -> f64 {
        let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let l = p.iter().map(|&x| (x - mean).length()).fold(0.0, f64::max);
        let m = nalgebra::DMatrix::from_fn(p.len(), 5, |i, j| {
            let y = p[i] - mean;
            [y.length_squared() / l, y.x, y.y, y.z, l][j]
        });
        let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s.resize(5, 0.0);
        s[columns - 1]
    }

    /// k points near a sphere of radius r about a random centre, covering a cap of the given
    /// angular extent, with noise.
    fn near_sphere(rng: &mut Rng, k: usize, r: f64, cap: f64, noise: f64) -> Vec<DVec3> {
        let c = rng.vec3();
        (0..k)
            .map(|_| {
                let (theta, phi) = (cap * (0.5 + 0.5 * rng.uniform()), std::f64::consts::PI * rng.uniform());
                let u = DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                c + r * u + noise * rng.vec3()
            })
            .collect()
    }

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

    #[test]
    fn derivatives_are_those_of_the_steps() {
        let mut rng = Rng(19);
        for trial in 0..20 {
            let points: Vec<DVec3> = (0..7).map(|_| rng.vec3()).collect();
            let kappa = [0.0, 0.8, -1.5, 1e-6][trial % 4];
            check_derivatives(SphereFit { s: 0.3 * rng.vec3(), n: rng.vec3().normalize(), kappa }, &points);
        }
    }

    #[test]
    fn projection_is_cospherical_centred_and_no_sampled_sphere_is_closer() {
        let mut rng = Rng(29);
        for trial in 0..60 {
            let k = 4 + trial % 20;
            let c = Sphere::new((0..k as u32).collect()).unwrap();
            let noise = [0.0, 0.01, 0.1, 0.5][trial % 4];
            let cap = [3.0, 1.0, 0.4][trial % 3];
            let r = 0.3 + rng.uniform().abs();
            let q = near_sphere(&mut rng, k, r, cap, noise);
            let cq = c.apply(&q);
            let p = project(&c, &q);
            let size = 1.0 + cq.iter().map(|x| x.length()).fold(0.0, f64::max);
            assert!(lifted_smallest(&p, 5) < 1e-12 * size, "trial {trial}: σ₅ = {:e}", lifted_smallest(&p, 5));
            assert!(sets::centroid_offset(&p) < 1e-13 * size);
            assert!(c.set_residual(&p) < 1e-12 * size);
            let d = dist2(&cq, &p);
            // The fit's sphere, and spheres near it and far from it: none is nearer.
            let (mean, scale) = rms_radius(&cq);
            let points: Vec<DVec3> = cq.iter().map(|&x| (x - mean) / scale).collect();
            let (fit, cost) = fit_sphere(&points);
            assert!((cost * scale * scale - d).abs() <= 1e-10 * (1.0 + d), "{} vs {d}", cost * scale * scale);
            if fit.kappa.abs() > 1e-6 {
                let (centre, r) = (mean + scale * (fit.s - fit.n / fit.kappa), scale / fit.kappa.abs());
                for j in 0..300 {
                    let eps = [1e-4, 1e-2, 0.2][j % 3] * r;
                    let cost = sphere_cost(&cq, centre + eps * rng.vec3(), r + eps * rng.uniform());
                    assert!(d <= cost + 1e-12, "trial {trial}: a sampled sphere is nearer ({cost:e} < {d:e})");
                }
            }
            // Spheres through 4 random points of the input, and the best plane (in the closure).
            let plane = crate::constraints::Plane::new((0..k as u32).collect()).unwrap();
            assert!(d <= plane.energy(&q) + 1e-12);
            for _ in 0..50 {
                let pick: Vec<DVec3> = (0..4).map(|_| cq[(rng.uniform().abs() * k as f64) as usize % k]).collect();
                let a = linear_least_squares(pick.iter().map(|&x| ([x.x, x.y, x.z, 1.0], -x.length_squared())));
                if let Some(a) = a {
                    let centre = -0.5 * DVec3::new(a[0], a[1], a[2]);
                    let r2 = centre.length_squared() - a[3];
                    if r2 > 0.0 {
                        assert!(d <= sphere_cost(&cq, centre, r2.sqrt()) + 1e-12);
                    }
                }
            }
        }
    }

    #[test]
    fn the_fit_is_the_lowest_of_many_random_starts() {
        let mut rng = Rng(31);
        for trial in 0..30 {
            let k = 5 + trial % 10;
            let q = near_sphere(&mut rng, k, 0.5, [2.5, 0.8][trial % 2], 0.3);
            let (mean, scale) = rms_radius(&q);
            let points: Vec<DVec3> = q.iter().map(|&x| (x - mean) / scale).collect();
            let (fit, cost) = fit_sphere(&points);
            // Converged: refining the fit again moves no projected point.
            let (again, _) = best_fit([fit], &points).unwrap();
            let nearest = |f: &SphereFit, x: DVec3| {
                let dist = distance(x - f.s, f.n, f.kappa);
                x - dist.d * dist.direction(f.n)
            };
            let moved = points.iter().map(|&x| (nearest(&fit, x) - nearest(&again, x)).length()).fold(0.0, f64::max);
            assert!(moved < 1e-12, "trial {trial}: a second fit moves a point by {moved:e}");
            for _ in 0..40 {
                let start = SphereFit { s: rng.vec3(), n: rng.vec3().normalize(), kappa: 2.0 * rng.uniform() };
                let (_, other) = best_fit([start], &points).unwrap();
                assert!(cost <= other + 1e-12, "trial {trial}: a random start found {other:e} < {cost:e}");
            }
        }
    }

    #[test]
    fn points_on_a_sphere_stay_and_degenerate_sets_stay_finite() {
        let mut rng = Rng(37);
        let c = Sphere::new((0..8).collect()).unwrap();
        let on = near_sphere(&mut rng, 8, 0.7, 2.0, 0.0);
        let cq = c.apply(&on);
        assert!(dist2(&project(&c, &on), &cq) < 1e-24, "a cospherical set is its own projection");
        // Coplanar, not concyclic: on the closure (a plane), so it stays and is finite.
        let flat: Vec<DVec3> = (0..8).map(|_| DVec3::new(rng.uniform(), rng.uniform(), 0.0)).collect();
        let p = project(&c, &flat);
        assert!(p.iter().all(|x| x.is_finite()));
        assert!(c.set_residual(&p) < 1e-12);
        assert!(dist2(&p, &c.apply(&flat)) < 1e-20, "{:e}", dist2(&p, &c.apply(&flat)));
        // Collinear and coincident points.
        let line: Vec<DVec3> = (0..8).map(|i| DVec3::new(i as f64, 2.0 * i as f64, 0.5)).collect();
        assert!(project(&c, &line).iter().all(|x| x.is_finite()));
        assert!(project(&c, &[DVec3::ONE; 8]).iter().all(|x| *x == DVec3::ZERO));
    }

    #[test]
    fn rigid_motions_move_the_projection_along() {
        let mut rng = Rng(41);
        let c = Sphere::new((0..12).collect()).unwrap();
        for trial in 0..20 {
            let q = near_sphere(&mut rng, 12, 0.6, [2.0, 0.5][trial % 2], 0.2);
            let turn = DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize();
            let shift = rng.vec3();
            let moved: Vec<DVec3> = q.iter().map(|&x| turn * x + shift).collect();
            let turned: Vec<DVec3> = project(&c, &q).iter().map(|&x| turn * x).collect();
            let off = dist2(&turned, &project(&c, &moved));
            assert!(off < 1e-20, "trial {trial}: {off:e}");
        }
    }

    #[test]
    fn build_refuses_fewer_than_four_vertices() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
        let rest = RestGeometry::new(p, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]], vec![]);
        let frame = WorkingFrame::IDENTITY;
        let all = BuildContext { rest: &rest, selection: &Selection::All, frame: &frame };
        let built = build_constraints(KIND, &all, Params::default()).unwrap();
        assert_eq!(built.len(), 1);
        assert_eq!(built[0].num_rows(), 5);
        let three = Selection::from_indices(5, &[0, 1, 4]);
        let err =
            build_constraints(KIND, &BuildContext { rest: &rest, selection: &three, frame: &frame }, Params::default())
                .unwrap_err();
        let text = err.to_string();
        assert!(
            matches!(err, ConstraintError::Invalid { .. }) && text.contains("has 3") && !text.contains('\n'),
            "{text}"
        );
    }
}
