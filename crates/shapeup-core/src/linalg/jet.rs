//! Numbers with derivatives (forward mode): [`Scalar`] over `f64`, [`Jet1`] (value and
//! gradient) and [`Jet2`] (value, gradient and Hessian), and 3-vectors of them ([`V3`]), so that
//! one residual formula of a fit gives its exact derivatives.

use glam::DVec3;

/// A number the fits' residuals are computed in: `f64` for values, [`Jet1`] for values and
/// gradients, [`Jet2`] for values, gradients and Hessians (forward-mode differentiation, so
/// that one residual formula gives the exact derivatives).
pub(crate) trait Scalar:
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
pub(crate) struct Jet1<const P: usize> {
    /// The value.
    pub v: f64,
    /// Its gradient.
    pub g: [f64; P],
}

impl<const P: usize> Jet1<P> {
    /// Variable i: value 0, gradient the i-th unit vector.
    pub(crate) fn variable(i: usize) -> Self {
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
pub(crate) struct Jet2<const P: usize> {
    /// The value.
    pub v: f64,
    /// Its gradient.
    pub g: [f64; P],
    /// Its Hessian.
    pub h: [[f64; P]; P],
}

impl<const P: usize> Jet2<P> {
    /// Variable i: value 0, gradient the i-th unit vector.
    pub(crate) fn variable(i: usize) -> Self {
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
pub(crate) struct V3<T>(pub T, pub T, pub T);

impl<T: Scalar> V3<T> {
    /// A constant vector.
    pub(crate) fn constant(v: DVec3) -> Self {
        V3(T::constant(v.x), T::constant(v.y), T::constant(v.z))
    }
    /// The constant vector v times the number a.
    pub(crate) fn along(v: DVec3, a: T) -> Self {
        V3(a.scale(v.x), a.scale(v.y), a.scale(v.z))
    }
    pub(crate) fn add(self, o: Self) -> Self {
        V3(self.0 + o.0, self.1 + o.1, self.2 + o.2)
    }
    pub(crate) fn sub(self, o: Self) -> Self {
        V3(self.0 - o.0, self.1 - o.1, self.2 - o.2)
    }
    pub(crate) fn times(self, a: T) -> Self {
        V3(self.0 * a, self.1 * a, self.2 * a)
    }
    pub(crate) fn scale(self, c: f64) -> Self {
        V3(self.0.scale(c), self.1.scale(c), self.2.scale(c))
    }
    pub(crate) fn dot(self, o: Self) -> T {
        self.0 * o.0 + self.1 * o.1 + self.2 * o.2
    }
    pub(crate) fn cross(self, o: Self) -> Self {
        V3(self.1 * o.2 - self.2 * o.1, self.2 * o.0 - self.0 * o.2, self.0 * o.1 - self.1 * o.0)
    }
    /// R(ω) v to second order in ω: v + ω × v + ½ ω × (ω × v) (what the fits' steps do, to
    /// the order their derivatives need).
    pub(crate) fn turned(v: DVec3, omega: Self) -> Self {
        let v = Self::constant(v);
        let once = omega.cross(v);
        v.add(once).add(omega.cross(once).scale(0.5))
    }
}
