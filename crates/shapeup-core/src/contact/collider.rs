//! A collider: a [`Shape`], its Coulomb friction and its rigid motion in time.
//!
//! The motion is x ↦ R(t)(x − c) + c + v t: a spin R(t) by ω t about the axis through c, then
//! a translation at constant velocity v. Queries at time t map the point back into the rest
//! pose, ask the shape, and map the answer forward.

use super::shape::{Proximity, Shape};
use glam::{DQuat, DVec3};

/// A rigid motion at constant rates (working frame).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion {
    /// Velocity v (working units per second).
    pub velocity: DVec3,
    /// Spin: unit axis, the centre c it passes through, and the rate ω in radians per second.
    pub spin: Option<(DVec3, DVec3, f64)>,
}

impl Motion {
    /// Whether the collider stays put.
    pub fn is_static(&self) -> bool {
        self.velocity == DVec3::ZERO && self.spin.is_none_or(|(_, _, w)| w == 0.0)
    }

    /// (R(t), c, v t): the pose at time t.
    fn pose(&self, t: f64) -> (DQuat, DVec3, DVec3) {
        match self.spin {
            Some((axis, center, rate)) => (DQuat::from_axis_angle(axis, rate * t), center, self.velocity * t),
            None => (DQuat::IDENTITY, DVec3::ZERO, self.velocity * t),
        }
    }

    /// Where the rest-pose point `x` is at time t.
    pub fn apply(&self, x: DVec3, t: f64) -> DVec3 {
        let (r, c, shift) = self.pose(t);
        r * (x - c) + c + shift
    }

    /// The rest-pose point that is at `y` at time t.
    pub fn invert(&self, y: DVec3, t: f64) -> DVec3 {
        let (r, c, shift) = self.pose(t);
        r.inverse() * (y - c - shift) + c
    }

    /// A direction of the rest pose at time t.
    pub fn turn(&self, d: DVec3, t: f64) -> DVec3 {
        self.pose(t).0 * d
    }

    /// A direction at time t0 turned with the body to where it points at t1: R(t1) R(t0)⁻¹ d.
    pub fn carry(&self, d: DVec3, t0: f64, t1: f64) -> DVec3 {
        self.pose(t1).0 * (self.pose(t0).0.inverse() * d)
    }
}

/// A collider (working frame): its shape at rest, μ and its motion.
#[derive(Debug, Clone)]
pub struct Collider {
    /// The shape in its rest pose (time 0).
    pub shape: Shape,
    /// Coulomb friction coefficient μ ≥ 0 against it.
    pub friction: f64,
    /// How it moves.
    pub motion: Motion,
}

impl Collider {
    /// [`Shape::closest`] against the collider as it is at time t.
    pub fn closest_at(&self, x: DVec3, t: f64) -> Proximity {
        self.closest_from(x, t, t)
    }

    /// The feature of the collider closest to `x` as the collider is at time t0, carried by
    /// its motion to where it is at t1 (point and outward normal there); the distance is the
    /// one at t0. A vertex keeps the side of the collider it started the step on: a thin plate
    /// that sweeps past it within the step pushes it from its front face, where the closest
    /// feature at t1 would be the back face.
    pub fn closest_from(&self, x: DVec3, t0: f64, t1: f64) -> Proximity {
        if self.motion.is_static() {
            return self.shape.closest(x);
        }
        let p = self.shape.closest(self.motion.invert(x, t0));
        Proximity {
            point: self.motion.apply(p.point, t1),
            normal: self.motion.turn(p.normal, t1),
            distance: p.distance,
        }
    }

    /// [`Shape::segment_entry`] of a point moving from x0 at time t0 to x1 at t1, seen from the
    /// collider: the path x0 → x1 in the collider's own frame (x0 taken back by its pose at t0,
    /// x1 by its pose at t1), so that a collider which sweeps over a point within the step is
    /// caught as a point that crosses a still one is. The entry point and the outward normal
    /// there, where the collider is at t1.
    pub fn segment_entry_at(&self, x0: DVec3, t0: f64, x1: DVec3, t1: f64) -> Option<(DVec3, DVec3)> {
        if self.motion.is_static() {
            let (s, n) = self.shape.segment_entry(x0, x1)?;
            return Some((x0 + s * (x1 - x0), n));
        }
        let (y0, y1) = (self.motion.invert(x0, t0), self.motion.invert(x1, t1));
        let (s, n) = self.shape.segment_entry(y0, y1)?;
        Some((self.motion.apply(y0 + s * (y1 - y0), t1), self.motion.turn(n, t1)))
    }

    /// How far the collider's material point that is at `y` at time `t1` moved since `t0`.
    pub fn displacement(&self, y: DVec3, t0: f64, t1: f64) -> DVec3 {
        if self.motion.is_static() {
            return DVec3::ZERO;
        }
        y - self.motion.apply(self.motion.invert(y, t1), t0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_sphere_is_queried_where_it_is() {
        let c = Collider {
            shape: Shape::Sphere { center: DVec3::ZERO, radius: 1.0 },
            friction: 0.0,
            motion: Motion { velocity: DVec3::new(2.0, 0.0, 0.0), spin: None },
        };
        let p = c.closest_at(DVec3::new(4.0, 0.0, 0.0), 1.0);
        assert!((p.distance - 1.0).abs() < 1e-12 && (p.point - DVec3::new(3.0, 0.0, 0.0)).length() < 1e-12);
        assert!((c.displacement(DVec3::new(3.0, 0.0, 0.0), 0.5, 1.0) - DVec3::new(1.0, 0.0, 0.0)).length() < 1e-12);
    }

    #[test]
    fn spinning_box_turns_its_normal() {
        let c = Collider {
            shape: Shape::Box { center: DVec3::ZERO, half: DVec3::new(1.0, 0.1, 1.0), rotation: DQuat::IDENTITY },
            friction: 0.0,
            motion: Motion { velocity: DVec3::ZERO, spin: Some((DVec3::Z, DVec3::ZERO, std::f64::consts::FRAC_PI_2)) },
        };
        // After 1 s the plate stands upright: +x is now its top.
        let p = c.closest_at(DVec3::new(-0.5, 0.0, 0.0), 1.0);
        assert!(p.normal.dot(DVec3::new(-1.0, 0.0, 0.0)) > 0.999, "{:?}", p.normal);
        assert!((p.distance - 0.4).abs() < 1e-9);
        // A point on its rim moves along a circle.
        let d = c.displacement(DVec3::new(0.0, 1.0, 0.0), 0.0, 1.0);
        assert!((d - DVec3::new(-1.0, 1.0, 0.0)).length() < 1e-9, "{d:?}");
    }
}
