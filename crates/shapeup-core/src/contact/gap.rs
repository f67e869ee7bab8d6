//! One contact over one step: a linear gap between a vertex and a collider's half-space, or
//! between the points of a vertex–triangle or edge–edge pair, with its normal and points fixed
//! for the step. Beneath both the detection ([`super::self_collision`], [`super::model`]) and
//! the solve ([`super::model`]).

use glam::DVec3;

/// One contact over one step: g(q) = n · Σ_j α_j q_j − offset.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Contact {
    pub(crate) vertices: [u32; 4],
    pub(crate) alpha: [f64; 4],
    pub(crate) len: u8,
    pub(crate) normal: DVec3,
    /// n · (surface point) + thickness for a collider, the thickness for a pair.
    pub(crate) offset: f64,
    pub(crate) friction: f64,
    /// The collider's motion over the step at the contact (0 for a pair).
    pub(crate) shift: DVec3,
    /// Which collider (for collider contacts), or `u32::MAX` for a self contact.
    pub(crate) collider: u32,
}

impl Contact {
    pub(crate) fn new(vertices: &[u32], alpha: &[f64], normal: DVec3, offset: f64, friction: f64) -> Contact {
        let mut v = [0; 4];
        let mut a = [0.0; 4];
        v[..vertices.len()].copy_from_slice(vertices);
        a[..alpha.len()].copy_from_slice(alpha);
        Contact {
            vertices: v,
            alpha: a,
            len: vertices.len() as u8,
            normal,
            offset,
            friction,
            shift: DVec3::ZERO,
            collider: u32::MAX,
        }
    }

    pub(crate) fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.vertices[..self.len as usize].iter().zip(&self.alpha).map(|(&v, &a)| (v as usize, a))
    }

    /// g(q): negative when too close.
    pub(crate) fn gap(&self, q: &[DVec3]) -> f64 {
        self.normal.dot(self.terms().map(|(v, a)| a * q[v]).sum::<DVec3>()) - self.offset
    }

    /// Tangential relative slip since the step's start (minus the collider's motion).
    pub(crate) fn slip(&self, q: &[DVec3], start: &[DVec3]) -> DVec3 {
        let u = self.terms().map(|(v, a)| a * (q[v] - start[v])).sum::<DVec3>() - self.shift;
        u - self.normal.dot(u) * self.normal
    }
}
