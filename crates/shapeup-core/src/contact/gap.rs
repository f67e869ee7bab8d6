//! One contact over one step: a linear gap between a vertex and a collider's half-space
//! ([`Contact`]), or between the points of a vertex–triangle or edge–edge pair ([`Pair`]), with
//! its normal and points fixed for the step. Beneath both the detection
//! ([`super::self_collision`], [`super::model`]) and the solve ([`super::model`]).

use glam::DVec3;

/// One collider contact over one step: the half-space g(p) = n · p − offset ≥ 0 for the
/// position p of one vertex.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Contact {
    pub(crate) vertex: u32,
    pub(crate) normal: DVec3,
    /// n · (surface point) + thickness.
    pub(crate) offset: f64,
    /// The collider's Coulomb μ.
    pub(crate) friction: f64,
    /// The collider's motion over the step at the contact.
    pub(crate) shift: DVec3,
}

impl Contact {
    /// g(p) at the vertex's position p: negative when too close.
    #[inline]
    pub(crate) fn gap(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }
}

/// One self contact over one step, a vertex–triangle pair (the vertex, then the triangle's
/// three) or an edge–edge pair (both edges' ends): g(q) = n · Σ_j α_j q_j − d with Σ_j α_j = 0.
/// Compact (88 bytes) because each iteration of a step reads every pair.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pair {
    pub(crate) vertices: [u32; 4],
    pub(crate) alpha: [f64; 4],
    pub(crate) normal: DVec3,
    /// The distance the pair must keep this step.
    pub(crate) distance: f64,
    /// How many vertex–triangle and edge–edge pairs of elements reached these closest
    /// features (see `self_collision::distinct_features`): its weight among a vertex's pairs.
    pub(crate) copies: u32,
}

impl Pair {
    /// The α-weighted sum Σ_j α_j x_j (the vector between the pair's two points).
    #[inline]
    pub(crate) fn combine(&self, x: &[DVec3]) -> DVec3 {
        let [a, b, c, d] = self.vertices.map(|v| x[v as usize]);
        self.alpha[0] * a + self.alpha[1] * b + self.alpha[2] * c + self.alpha[3] * d
    }

    /// g(q): negative when too close.
    #[inline]
    pub(crate) fn gap(&self, q: &[DVec3]) -> f64 {
        self.normal.dot(self.combine(q)) - self.distance
    }

    pub(crate) fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.vertices.iter().zip(&self.alpha).map(|(&v, &a)| (v as usize, a))
    }
}
