//! Pressure: a gas of constant pressure p inside a surface (a balloon, a cushion, pneumatic
//! form finding), as the energy −p V(q) of the volume it encloses.
//!
//! V(q) = Σ_t V_t, V_t = (x_a − c) · ((x_b − c) × (x_c − c)) / 6 over the surface's triangles
//! (a, b, c), c a fixed point (the rest centroid): the divergence theorem's volume of a closed,
//! consistently oriented surface, whatever c. Its gradient at a vertex is Σ_{t ∋ v} A_t n_t / 3,
//! so the force p ∂V/∂x_v is the pressure p A n on each triangle, a third to each corner: the
//! load of a gas on a closed surface, which is conservative. On an open surface V depends on c
//! through the boundary, so an open surface (a cushion, a sail) must have its boundary held.
//!
//! How it enters the solver (as a material does, [module docs](super)): each triangle's term
//! has three rows, its corners' positions (C q = (x_a, x_b, x_c)), weight ω = |p| ℓ/6 (ℓ the
//! longest rest edge: the size of V_t's Hessian, p times lengths), energy −2 p V_t (the solver's
//! factor 2) and "projection" x_i + (p/ω) ∂V_t/∂x_i, so that ω (C q − p) is half the gradient
//! of −2 p V_t. p > 0 pushes outward along the triangles' normals (counter-clockwise corners
//! seen from outside), p < 0 sucks in.

use crate::constraints::{Constraint, ConstraintGroup, RowSink};
use crate::geometry::RestGeometry;
use glam::DVec3;

/// Name of the group a pressure builds, and the kind of its terms.
pub const PRESSURE_GROUP: &str = "pressure";

/// The pressure term of one triangle ([module docs](self)).
#[derive(Debug, Clone)]
pub struct PressureTerm {
    vertices: [u32; 3],
    /// p, Pa (working units).
    pressure: f64,
    /// c, the fixed point of the cone volumes.
    center: DVec3,
    /// ω = |p| ℓ / 6 (at least 1e-300 so that the rows stay in the matrix at p = 0).
    weight: f64,
}

impl PressureTerm {
    /// The term of triangle `vertices` of `rest` under pressure `pressure`, cones from `center`.
    pub fn new(vertices: [u32; 3], rest: &[DVec3], pressure: f64, center: DVec3) -> Self {
        let p = vertices.map(|v| rest[v as usize]);
        let longest = super::longest_edge(&p);
        PressureTerm { vertices, pressure, center, weight: (pressure.abs() * longest / 6.0).max(1e-300) }
    }

    /// The signed volume V_t of the cone from c over the triangle at corners `x`.
    pub fn cone_volume(&self, x: &[DVec3]) -> f64 {
        let [a, b, c] = [x[0] - self.center, x[1] - self.center, x[2] - self.center];
        a.dot(b.cross(c)) / 6.0
    }
}

impl Constraint for PressureTerm {
    fn kind(&self) -> &'static str {
        PRESSURE_GROUP
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        self.weight
    }
    fn num_rows(&self) -> usize {
        3
    }
    fn rows(&self, sink: &mut RowSink) {
        for (k, &v) in self.vertices.iter().enumerate() {
            sink.push(k, v, 1.0);
        }
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let [a, b, c] = self.vertices.map(|v| q[v as usize] - self.center);
        let s = self.pressure / (6.0 * self.weight);
        out[0] = q[self.vertices[0] as usize] + b.cross(c) * s;
        out[1] = q[self.vertices[1] as usize] + c.cross(a) * s;
        out[2] = q[self.vertices[2] as usize] + a.cross(b) * s;
    }
    fn is_projective(&self) -> bool {
        false
    }
    fn energy_from_rows(&self, cq: &[DVec3]) -> Option<f64> {
        Some(-2.0 * self.pressure * self.cone_volume(cq))
    }
    /// No set: a load has no shape it projects onto.
    fn set_residual(&self, _p: &[DVec3]) -> f64 {
        0.0
    }
    fn violation(&self, _cq: &[DVec3]) -> f64 {
        0.0
    }
}

/// The pressure group on every triangle of `rest` (the surface; a tetrahedral mesh's boundary),
/// `pressure` in working units, multiplier `multiplier` (1 in static mode; 1/k in dynamic mode
/// with a material, as for the material's group). `None` when the mesh has no triangle.
pub fn pressure_group(rest: &RestGeometry, pressure: f64, multiplier: f64) -> Option<ConstraintGroup> {
    if rest.triangles.is_empty() {
        return None;
    }
    let mut used = vec![false; rest.num_vertices()];
    rest.triangles.iter().flatten().for_each(|&v| used[v as usize] = true);
    let count = used.iter().filter(|&&u| u).count().max(1) as f64;
    let center = rest.positions.iter().zip(&used).filter(|(_, u)| **u).map(|(p, _)| *p).sum::<DVec3>() / count;
    let terms = rest
        .triangles
        .iter()
        .map(|&t| Box::new(PressureTerm::new(t, &rest.positions, pressure, center)) as Box<dyn Constraint>)
        .collect();
    Some(ConstraintGroup::new(PRESSURE_GROUP, multiplier, terms))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::octahedron;

    /// Σ_t ω Cᵀ(C q − p) at q: half the gradient of the solver's energy.
    fn half_gradient(group: &ConstraintGroup, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; q.len()];
        for term in &group.constraints {
            let mut p = vec![DVec3::ZERO; 3];
            term.project(q, &mut p);
            let cq = term.apply(q);
            for (k, &v) in term.vertices().iter().enumerate() {
                out[v as usize] += term.element_weight() * (cq[k] - p[k]);
            }
        }
        out
    }

    fn energy(group: &ConstraintGroup, q: &[DVec3]) -> f64 {
        group.constraints.iter().map(|c| c.energy(q)).sum()
    }

    #[test]
    fn the_cones_sum_to_the_enclosed_volume_and_the_energy_is_minus_twice_p_v() {
        let rest = octahedron();
        // Square base of diagonal 2 (area 2), apexes 1.3 above and 0.8 below.
        let volume = 2.0 * (1.3 + 0.8) / 3.0;
        let group = pressure_group(&rest, 250.0, 1.0).unwrap();
        assert_eq!(group.constraints.len(), 8);
        assert!((energy(&group, &rest.positions) + 2.0 * 250.0 * volume).abs() < 1e-9);
        // Whatever the cones' apex: moved far away, the same volume.
        let far = PressureTerm::new([0, 2, 4], &rest.positions, 1.0, DVec3::new(50.0, -20.0, 7.0));
        let total: f64 = rest
            .triangles
            .iter()
            .map(|&t| {
                let term = PressureTerm { vertices: t, ..far.clone() };
                term.cone_volume(&term.apply(&rest.positions))
            })
            .sum();
        assert!((total - volume).abs() < 1e-10, "{total} vs {volume}");
    }

    #[test]
    fn the_force_is_the_energys_gradient_and_p_a_n_on_each_face() {
        let rest = octahedron();
        let q: Vec<DVec3> = rest
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| *p * 1.1 + DVec3::new(0.05 * i as f64, -0.02, 0.03 * (i % 2) as f64))
            .collect();
        let pressure = -300.0;
        let group = pressure_group(&rest, pressure, 1.0).unwrap();
        let half = half_gradient(&group, &q);
        for v in 0..q.len() {
            for axis in 0..3 {
                let h = 1e-6;
                let (mut plus, mut minus) = (q.clone(), q.clone());
                plus[v][axis] += h;
                minus[v][axis] -= h;
                let fd = (energy(&group, &plus) - energy(&group, &minus)) / (2.0 * h);
                assert!(
                    (fd - 2.0 * half[v][axis]).abs() < 1e-5,
                    "vertex {v} axis {axis}: {fd} vs {}",
                    2.0 * half[v][axis]
                );
            }
            // The load on a vertex is p Σ A_t n_t / 3 over its triangles.
            let faces: DVec3 = rest
                .triangles
                .iter()
                .filter(|t| t.contains(&(v as u32)))
                .map(|t| {
                    let [a, b, c] = t.map(|i| q[i as usize]);
                    (b - a).cross(c - a) / 2.0
                })
                .sum();
            assert!((-half[v] - pressure * faces / 3.0).length() < 1e-9, "vertex {v}");
        }
        // A closed surface: no net force and no net torque.
        let net: DVec3 = half.iter().sum();
        let torque: DVec3 = q.iter().zip(&half).map(|(x, f)| x.cross(*f)).sum();
        assert!(net.length() < 1e-9 && torque.length() < 1e-9, "{net} {torque}");
    }
}
