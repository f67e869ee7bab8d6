//! Hinge bending: the discrete-quadratic-bending vector of each interior edge keeps its rest
//! length (or a length within a band around it).
//!
//! For an interior edge (i, j) with its two triangles T₀ = (i, j, k) and T₁ = (j, i, l)
//! (k and l the opposite corners), with rest cotangents of the angles at i and j in each
//! triangle, cot_{i,0} = cot ∠(x⁰_j − x⁰_i, x⁰_k − x⁰_i) and so on:
//!
//!   K q = c_i q_i + c_j q_j + c_k q_k + c_l q_l        (1 row)
//!   c_i = cot_{j,0} + cot_{j,1},   c_j = cot_{i,0} + cot_{i,1},
//!   c_k = −(cot_{i,0} + cot_{j,0}), c_l = −(cot_{i,1} + cot_{j,1})
//!
//! (Σ c = 0, and K x = 0 for a flat hinge: K q is the hinge's discrete mean curvature normal
//! times the edge, the stencil of Wardetzky et al. 2007 and Bergou et al. 2006). With
//! n⁰ = ‖K x⁰‖ and the band [lo, hi] = [min·n⁰, max·n⁰] (options `min`, `max`, default 1, 1),
//! the set is {v : lo ≤ ‖v‖ ≤ hi} and the projection its nearest point:
//!
//!   p = clamp(‖K q‖, lo, hi) · K q / ‖K q‖ (K q itself inside the band);
//!   if ‖K q‖ < lo and ‖K q‖ ≤ 1e-12 hi (no reliable direction): p = lo · σ⁰ n̄ with n̄ the
//!   normalized sum of the two triangles' current unit normals and σ⁰ = sign(n̄⁰ · K x⁰) the rest
//!   side (any vector of length lo is nearly as near then; this one is rigidly invariant; where
//!   n̄ = 0, K q's own direction, or K x⁰'s if K q = 0); p = 0 if
//!   n⁰ ≤ 1e-14 Σ_v |c_v| ‖x⁰_v − x⁰_i‖ (a flat rest hinge, K x⁰ round-off of its terms: the
//!   set is {0}). Both thresholds are relative, so the constraint means the same at every scale.
//!
//!   ω = 3 / (A₀ + A₁), the rest areas of the two triangles.
//!
//! Sources: ShapeOp's `BendingConstraint` (Deuss et al. 2015), the same stencil, band and
//! weight (ShapeOp's weight multiplied by 3/(A₀ + A₁)); Bergou, Wardetzky, Harmon, Zorin and
//! Grinspun, "A quadratic bending model for inextensible surfaces" (SGP 2006), whose energy
//! 3/(A₀ + A₁) ‖K x‖² this is; Wardetzky et al., "Discrete quadratic curvature energies"
//! (CAGD 2007); the ShapeUp solver (Bouaziz et al. 2012).
//!
//! Choices, and why:
//! - ω = 3/(A₀ + A₁), as Bergou et al. and ShapeOp: with it ω‖K x‖² approximates the
//!   integrated squared mean curvature over the hinge's area (A₀ + A₁)/3, so the energy does not
//!   change with the mesh's resolution. Default multiplier 1, ShapeOp's weight.
//! - Interior edges only (exactly two triangles, both of rest area > 1e-12, both corners of the
//!   edge selected): a boundary edge has no hinge, an edge of three or more triangles no single
//!   one, and a zero-area triangle no cotangent (its ω would be infinite).
//! - ShapeOp leaves p = K q when ‖K q‖ ≤ 1e-6 (off the set when lo > 0); here p is a point of the
//!   set, so the local step always minimizes its term.
//! - `min` > `max` is refused (an empty band).

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::sets;
use crate::constraints::kit::build::non_empty;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::{RestGeometry, cotangent, is_degenerate_triangle, triangle_area, triangle_normal};
use glam::DVec3;

/// Name in scene files.
const KIND: &str = "hinge_bending";

/// A rest hinge is flat when ‖K x⁰‖ is at most this times the size of its terms,
/// Σ_v |c_v| ‖x⁰_v − x⁰_i‖ (50 times their round-off).
const FLAT: f64 = 1e-14;
/// Below this times the band's top, ‖K q‖ has no reliable direction (p follows the normal).
const NO_DIRECTION: f64 = 1e-12;

/// `min`: the band's lower end, a multiple of the rest norm.
const MIN: OptionSpec = OptionSpec {
    key: "min",
    doc: "smallest allowed ‖K q‖ as a multiple of its rest value (≥ 0, at most max); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};

/// `max`: the band's upper end, a multiple of the rest norm.
const MAX: OptionSpec = OptionSpec {
    key: "max",
    doc: "largest allowed ‖K q‖ as a multiple of its rest value (at least min); default 1",
    kind: OptionKind::Number { default: Some(1.0), min: 0.0, max: f64::MAX },
};

/// The bending constraint of one interior edge.
#[derive(Debug, Clone)]
pub struct HingeBending {
    /// `[i, j, k, l]`: the edge, then the corners opposite it in T₀ and T₁.
    vertices: [u32; 4],
    /// The stencil c_i, c_j, c_k, c_l.
    coeffs: [f64; 4],
    /// The band [lo, hi] of ‖K q‖ (both 0 for a flat rest hinge).
    band: [f64; 2],
    /// σ⁰ = sign(n̄⁰ · K x⁰): which side of the hinge K x⁰ points to.
    rest_side: f64,
    /// K x⁰/‖K x⁰‖, for a K q of length 0 whose hinge has no normal either.
    rest_direction: DVec3,
    weight: f64,
}

impl HingeBending {
    /// The constraint of edge (i, j) between triangles (i, j, k) and (j, i, l) of the rest
    /// shape `x`, with the band [min, max] · ‖K x⁰‖; `None` if a triangle has zero area.
    pub fn new(x: &[DVec3], [i, j, k, l]: [u32; 4], min: f64, max: f64) -> Option<Self> {
        let [xi, xj, xk, xl] = [i, j, k, l].map(|v| x[v as usize]);
        if is_degenerate_triangle(xi, xj, xk) || is_degenerate_triangle(xj, xi, xl) {
            return None;
        }
        // cotangent(a, b, c) is the cotangent of the angle at c, opposite edge (a, b).
        let cot_i0 = cotangent(xj, xk, xi)?;
        let cot_j0 = cotangent(xi, xk, xj)?;
        let cot_i1 = cotangent(xj, xl, xi)?;
        let cot_j1 = cotangent(xi, xl, xj)?;
        let coeffs = [cot_j0 + cot_j1, cot_i0 + cot_i1, -(cot_i0 + cot_j0), -(cot_i1 + cot_j1)];
        let mut c = HingeBending {
            vertices: [i, j, k, l],
            coeffs,
            band: [0.0; 2],
            rest_side: 1.0,
            rest_direction: DVec3::Z,
            weight: 3.0 / (triangle_area(xi, xj, xk) + triangle_area(xj, xi, xl)),
        };
        let k0 = c.apply_row(x);
        let n0 = k0.length();
        let terms: f64 = [xi, xj, xk, xl].iter().zip(&coeffs).map(|(v, c)| c.abs() * (*v - xi).length()).sum();
        if n0 > FLAT * terms {
            c.band = [min * n0, max * n0];
            c.rest_direction = k0 / n0;
            c.rest_side = if c.normal(x).dot(k0) < 0.0 { -1.0 } else { 1.0 };
        }
        Some(c)
    }

    /// K q.
    #[inline]
    fn apply_row(&self, q: &[DVec3]) -> DVec3 {
        self.vertices.iter().zip(&self.coeffs).map(|(&v, &c)| c * q[v as usize]).sum()
    }

    /// n̄: the normalized sum of the unit normals of T₀ = (i, j, k) and T₁ = (j, i, l) at q.
    fn normal(&self, q: &[DVec3]) -> DVec3 {
        let [i, j, k, l] = self.vertices.map(|v| q[v as usize]);
        (triangle_normal(i, j, k) + triangle_normal(j, i, l)).normalize_or_zero()
    }
}

impl Constraint for HingeBending {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn element_weight(&self) -> f64 {
        self.weight
    }
    fn num_rows(&self) -> usize {
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        for (&v, &c) in self.vertices.iter().zip(&self.coeffs) {
            sink.push(0, v, c);
        }
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let [lo, hi] = self.band;
        let e = self.apply_row(q);
        let length = e.length();
        out[0] = if hi == 0.0 {
            DVec3::ZERO
        } else if length >= lo && length <= hi {
            e
        } else if length <= NO_DIRECTION * hi {
            // Below the band without a reliable direction: every point of the sphere of radius
            // lo is nearly as near. The normal's side, else K q's own, else the rest one.
            let n = self.normal(q);
            lo * if n != DVec3::ZERO {
                self.rest_side * n
            } else if length > 0.0 {
                e / length
            } else {
                self.rest_direction
            }
        } else {
            e * (length.clamp(lo, hi) / length)
        };
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        sets::interval_distance(p[0].length(), self.band[0], self.band[1])
    }
}

/// For each interior edge of `rest` (two triangles, both corners selected): `[i, j, k, l]`,
/// the edge (i, j) as in its first triangle (i, j, k) and the opposite corner l of the other.
fn hinges(rest: &RestGeometry, selected: impl Fn(u32) -> bool) -> Vec<[u32; 4]> {
    let topology = &rest.topology;
    // The (up to two) triangles on each edge, and the corner opposite it in each.
    let mut sides: Vec<[Option<(u32, u32, u32)>; 2]> = vec![[None; 2]; topology.edges.len()];
    for (t, edges) in rest.triangles.iter().zip(&topology.triangle_edges) {
        for k in 0..3 {
            let Some(slot) = sides.get_mut(edges[k] as usize) else { continue };
            let side = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
            if slot[0].is_none() {
                slot[0] = Some(side);
            } else if slot[1].is_none() {
                slot[1] = Some(side);
            }
        }
    }
    topology
        .edges
        .iter()
        .zip(&topology.edge_triangle_count)
        .zip(&sides)
        .filter(|((e, count), _)| **count == 2 && selected(e[0]) && selected(e[1]))
        .filter_map(|(_, side)| match side {
            [Some((i, j, k)), Some((_, _, l))] => Some([*i, *j, *k, *l]),
            _ => None,
        })
        .collect()
}

/// Builds a [`HingeBending`] on every interior edge whose two vertices are selected. Options
/// `min`, `max` (default 1, 1; `min` > `max` refused). Default multiplier 1.
#[derive(Debug, Clone, Copy)]
pub struct HingeBendingType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "hinge bending: each interior edge keeps its rest bending (discrete quadratic bending, as ShapeOp)",
    options: &[MIN, MAX],
    element: Element::Edge,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for HingeBendingType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let min = params.number(KIND, &MIN)?.unwrap_or(1.0);
        let max = params.number(KIND, &MAX)?.unwrap_or(1.0);
        if min > max {
            return Err(ConstraintError::Invalid {
                kind: KIND,
                problem: format!("min ({min}) must not exceed max ({max})"),
            });
        }
        let rest = ctx.rest;
        let built = hinges(rest, |v| ctx.selection.contains(v))
            .into_iter()
            .filter_map(|h| HingeBending::new(&rest.positions, h, min, max))
            .map(|c| Box::new(c) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "interior edges")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::octahedron;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::WorkingFrame;
    use glam::{DMat3, DQuat};

    /// A hinge on edge (0, 1) along x, its wings at heights `h` and `g`.
    fn hinge(h: f64, g: f64) -> Vec<DVec3> {
        vec![DVec3::ZERO, DVec3::X, DVec3::new(0.4, 0.9, h), DVec3::new(0.6, -0.8, g)]
    }

    fn project(c: &HingeBending, q: &[DVec3]) -> DVec3 {
        let mut p = [DVec3::ZERO];
        c.project(q, &mut p);
        p[0]
    }

    #[test]
    fn the_stencil_is_translation_invariant_and_vanishes_on_a_flat_hinge() {
        let flat = hinge(0.0, 0.0);
        let c = HingeBending::new(&flat, [0, 1, 2, 3], 1.0, 1.0).unwrap();
        assert!(c.coeffs.iter().sum::<f64>().abs() < 1e-14);
        assert!(c.apply_row(&flat).length() < 1e-14, "linear precision");
        assert_eq!(c.band, [0.0, 0.0], "a flat rest hinge");
        assert_eq!(project(&c, &hinge(0.3, -0.2)), DVec3::ZERO);
        // A flat hinge in any plane, rotated and moved.
        let r = DMat3::from_quat(DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.8));
        let moved: Vec<DVec3> = flat.iter().map(|&x| r * x + DVec3::ONE).collect();
        assert!(c.apply_row(&moved).length() < 1e-14);
        // ω = 3 / (A₀ + A₁).
        let areas = triangle_area(flat[0], flat[1], flat[2]) + triangle_area(flat[1], flat[0], flat[3]);
        assert!((c.element_weight() - 3.0 / areas).abs() < 1e-12);
    }

    #[test]
    fn the_row_is_bergous_stencil() {
        // Bergou et al. 2006: K = [c₀₃ + c₀₄, c₀₁ + c₀₂, −c₀₁ − c₀₃, −c₀₂ − c₀₄] with
        // c₀ₖ = cot∠(e₀, e_k), e₀ = x₁ − x₀, e₁ = x₂ − x₀, e₂ = x₃ − x₀, e₃ = x₂ − x₁, e₄ = x₃ − x₁.
        let x = hinge(0.3, 0.2);
        let cot = |a: DVec3, b: DVec3| a.dot(b) / a.cross(b).length();
        let (e0, e1, e2, e3, e4) = (x[1] - x[0], x[2] - x[0], x[3] - x[0], x[2] - x[1], x[3] - x[1]);
        let (c01, c02, c03, c04) = (cot(e0, e1), cot(e0, e2), cot(-e0, e3), cot(-e0, e4));
        let want = [c03 + c04, c01 + c02, -c01 - c03, -c02 - c04];
        let c = HingeBending::new(&x, [0, 1, 2, 3], 1.0, 1.0).unwrap();
        for (a, b) in c.coeffs.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{:?} vs {want:?}", c.coeffs);
        }
    }

    #[test]
    fn projection_is_on_the_band_and_no_sampled_point_is_closer() {
        let x = hinge(0.35, 0.15);
        let mut rng = Rng(23);
        for (min, max) in [(1.0, 1.0), (0.5, 2.0), (0.0, 0.3), (0.0, 0.0)] {
            let c = HingeBending::new(&x, [0, 1, 2, 3], min, max).unwrap();
            let n0 = c.apply_row(&x).length();
            assert!(n0 > 0.1 && (c.band[0] - min * n0).abs() < 1e-15 && (c.band[1] - max * n0).abs() < 1e-15);
            assert!(c.energy(&x) < 1e-28 || min > 1.0 || max < 1.0);
            for trial in 0..60 {
                let amplitude = [0.05, 0.3, 1.0][trial % 3];
                let q: Vec<DVec3> = x.iter().map(|&p| p + amplitude * rng.vec3()).collect();
                let cq = c.apply(&q);
                let p = project(&c, &q);
                assert!(c.set_residual(&[p]) < 1e-12);
                let d = (cq[0] - p).length_squared();
                for _ in 0..200 {
                    let length = c.band[0] + (c.band[1] - c.band[0]) * 0.5 * (1.0 + rng.uniform());
                    let s = rng.vec3().normalize() * length;
                    assert!(c.set_residual(&[s]) < 1e-12);
                    assert!(d <= (cq[0] - s).length_squared() + 1e-12, "a point of the band is closer");
                }
            }
            // Off the band.
            if c.band[1] > 0.0 {
                assert!(c.set_residual(&[DVec3::X * (c.band[1] * 1.5)]) > 1e-3);
            }
            if c.band[0] > 0.0 {
                assert!(c.set_residual(&[DVec3::X * (c.band[0] * 0.5)]) > 1e-3);
            }
        }
    }

    #[test]
    fn a_vanishing_row_projects_along_the_rest_side_of_the_normal() {
        let x = hinge(0.35, 0.15);
        let c = HingeBending::new(&x, [0, 1, 2, 3], 1.0, 1.0).unwrap();
        let p = project(&c, &hinge(0.0, 0.0));
        assert!((p.length() - c.band[0]).abs() < 1e-12);
        assert!(p.dot(c.apply_row(&x)) > 0.0, "the rest side");
        // Rotating the flat hinge rotates p.
        let r = DMat3::from_axis_angle(DVec3::new(0.3, 1.0, -0.2).normalize(), 1.1);
        let turned: Vec<DVec3> = hinge(0.0, 0.0).iter().map(|&y| r * y).collect();
        assert!((project(&c, &turned) - r * p).length() < 1e-12);
    }

    #[test]
    fn rigid_motion_rotates_the_projection() {
        let x = hinge(0.35, -0.25);
        let c = HingeBending::new(&x, [0, 1, 2, 3], 0.8, 1.2).unwrap();
        let mut rng = Rng(29);
        for _ in 0..30 {
            let q: Vec<DVec3> = x.iter().map(|&p| p + 0.3 * rng.vec3()).collect();
            let r = DMat3::from_quat(
                DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize(),
            );
            let moved: Vec<DVec3> = q.iter().map(|&p| r * p + DVec3::new(1.0, -2.0, 0.5)).collect();
            assert!(dist2(&[r * project(&c, &q)], &[project(&c, &moved)]) < 1e-24);
        }
    }

    #[test]
    fn build_takes_interior_edges_and_refuses_a_bad_band_by_key() {
        let rest = octahedron();
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let built = build_constraints(KIND, &ctx, Params::default()).unwrap();
        assert_eq!(built.len(), 12, "every edge of the closed octahedron");
        for c in &built {
            let v = c.vertices();
            let edge = [v[0].min(v[1]), v[0].max(v[1])];
            assert!(rest.topology.edge_index(edge[0], edge[1]).is_some());
            assert!(v[2] != v[3] && !edge.contains(&v[2]) && !edge.contains(&v[3]));
        }
        // An open fan: only its interior edges, only those with both ends selected.
        let mut p = vec![DVec3::new(0.0, 0.0, 0.3)];
        for k in 0..5 {
            let t = k as f64 / 5.0 * std::f64::consts::TAU;
            p.push(DVec3::new(t.cos(), t.sin(), 0.0));
        }
        let fan = RestGeometry::new(p, (0..4).map(|k| [0, 1 + k, 2 + k]).collect(), vec![]);
        let ctx = BuildContext { rest: &fan, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 3);
        let some = Selection::from_indices(6, &[0, 2]);
        let ctx = BuildContext { rest: &fan, selection: &some, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 1);

        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        let err = build_constraints(KIND, &ctx, Params::default().with("min", 2.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }) && err.to_string().contains("min"), "{err}");
        let err = build_constraints(KIND, &ctx, Params::default().with("max", -1.0)).unwrap_err();
        assert!(err.to_string().contains("max"), "{err}");
        let err = build_constraints(KIND, &ctx, Params::default().with("min", -0.5)).unwrap_err();
        assert!(err.to_string().contains("min"), "{err}");
        let band = Params::default().with("min", 0.5).with("max", 2.0);
        assert_eq!(build_constraints(KIND, &ctx, band).unwrap().len(), 12);
    }
}
