//! Rectangle: each selected quad face of the input becomes a rectangle.
//!
//! Term: ω Σ_i ‖(q_i − c) − (s_i a u + t_i b v)‖² over the corners i = 0…3 of a quad face in
//! face order, c = ¼ Σ_j q_j, minimized over unit u ⊥ v and a, b ∈ ℝ, with the corner signs
//! (s_i, t_i) = (−,−), (+,−), (+,+), (−,+).
//!
//! - Rows of C (4, translation-invariant as in ShapeOp): d_i = q_i − ¼ Σ_j q_j.
//! - Set: the rectangles c ± a u ± b v (any centre; segments and points, a or b = 0,
//!   included so that the set is closed).
//! - Projection (closed form). The translation is optimal at the centroid (Σ s_i = Σ t_i = 0),
//!   and as Σ s_i² = Σ t_i² = 4, Σ s_i t_i = 0, with P = Σ s_i d_i and Q = Σ t_i d_i:
//!   Σ‖d_i − s_i a u − t_i b v‖² = Σ‖d_i‖² − 2a u·P − 2b v·Q + 4a² + 4b², so a = u·P/4,
//!   b = v·Q/4, and it remains to maximize f = (u·P)² + (v·Q)² over orthonormal u, v. f is
//!   convex in the projections of u, v onto a plane Π ⊇ span(P, Q), which lie in the 2×2
//!   matrices of norm ≤ 1; a convex function's maximum there is at an extreme point, an
//!   orthonormal pair of Π, which is itself feasible, so the optimum lies in Π. In an orthonormal basis (e₁, e₂) of Π with u = (cos θ, sin θ),
//!   v = (−sin θ, cos θ) (the other orientation of v only flips the sign of b) and P, Q as
//!   complex numbers P_c, Q_c: f = ½(|P|² + |Q|²) + ½ Re(e^{−2iθ} z) with z = P_c² − Q_c², so
//!   θ = ½ arg z exactly (f_max = ½(|P|² + |Q|² + |z|), |z|² = (|P|² − |Q|²)² + 4‖P × Q‖²).
//!   p_i = s_i a u + t_i b v.
//!   Degenerate cases: P = Q = 0 (the centred corners are a pure (+,−,+,−) pattern): every
//!   rectangle through a point is as near, p = 0; P ∥ Q (or one of them 0): Π is any plane
//!   containing them (e₂ any unit vector ⊥ e₁); z = 0 (P = ±Q): every θ is optimal, θ = 0.
//! - ω = 1 (ShapeOp's weights are per constraint, set by the user). Default multiplier 10, as
//!   edge springs and strain: the faces are pulled toward rectangles about as strongly as the
//!   mesh holds its shape.
//! - Residual (direct): ‖p₀ − p₁ + p₂ − p₃‖ (a parallelogram) plus
//!   |(p₁ − p₀)·(p₃ − p₀)| / max(‖p₁ − p₀‖, ‖p₃ − p₀‖) (a right angle at corner 0), in length
//!   units; zero exactly on the set.
//!
//! Sources: ShapeOp's RectangleConstraint (Deuss et al. 2015), ShapeUp (Bouaziz et al. 2012,
//! which lists rectangle among its shape constraints).
//!
//! Choices left open: ω = 1 rather than the rest face area (ShapeOp's choice; with the area a
//! finer mesh would not pull harder in total); only quads as read (`ctx.rest.faces`), so a
//! triangulated input has none and is refused with a clear line; a face given in the other
//! winding is the same constraint (the sign pattern is symmetric under reversal).

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::kit::vertex_set::{centre_into, push_centred_rows};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;
use crate::constraints::kit::faces::selected_quads;

/// Name in scene files.
const KIND: &str = "rectangle";

/// Corner signs along u.
const S: [f64; 4] = [-1.0, 1.0, 1.0, -1.0];
/// Corner signs along v.
const T: [f64; 4] = [-1.0, -1.0, 1.0, 1.0];


/// A rectangle constraint on one quad face.
#[derive(Debug, Clone)]
pub struct Rectangle {
    /// The corners in face order.
    vertices: [u32; 4],
}

impl Rectangle {
    /// The constraint on the quad with these corners (in face order).
    pub fn new(corners: [u32; 4]) -> Self {
        Rectangle { vertices: corners }
    }

    /// The nearest rectangle to centred corners `d` (Σ d_i = 0): its (a u, b v), with
    /// p_i = s_i a u + t_i b v.
    pub fn fit(d: &[DVec3; 4]) -> (DVec3, DVec3) {
        let p: DVec3 = (0..4).map(|i| S[i] * d[i]).sum();
        let q: DVec3 = (0..4).map(|i| T[i] * d[i]).sum();
        let (pn, qn) = (p.length(), q.length());
        let (longer, other, ln) = if pn >= qn { (p, q, pn) } else { (q, p, qn) };
        if ln == 0.0 || !ln.is_finite() {
            return (DVec3::ZERO, DVec3::ZERO);
        }
        let e1 = longer / ln;
        // e₂ ⊥ e₁ in span(P, Q); Gram–Schmidt twice, so that e₂ ⊥ e₁ to rounding even when
        // P and Q are nearly parallel.
        let e2 = (other - e1 * e1.dot(other))
            .try_normalize()
            .map(|w| (w - e1 * e1.dot(w)).normalize())
            .filter(|w| w.is_finite())
            .unwrap_or_else(|| e1.any_orthonormal_vector());
        let (p1, p2, q1, q2) = (e1.dot(p), e2.dot(p), e1.dot(q), e2.dot(q));
        // z = P_c² − Q_c²; θ = ½ arg z.
        let theta = 0.5 * (2.0 * (p1 * p2 - q1 * q2)).atan2(p1 * p1 - p2 * p2 - q1 * q1 + q2 * q2);
        let (sin, cos) = theta.sin_cos();
        let u = cos * e1 + sin * e2;
        let v = cos * e2 - sin * e1;
        (u * (0.25 * u.dot(p)), v * (0.25 * v.dot(q)))
    }
}

impl Constraint for Rectangle {
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
        4
    }
    fn rows(&self, sink: &mut RowSink) {
        push_centred_rows(&self.vertices, sink);
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        let mut d = [DVec3::ZERO; 4];
        centre_into(q, &self.vertices, &mut d);
        let (au, bv) = Rectangle::fit(&d);
        for (i, o) in out.iter_mut().enumerate().take(4) {
            *o = S[i] * au + T[i] * bv;
        }
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        if !p.iter().all(|x| x.is_finite()) {
            return f64::INFINITY;
        }
        let defect = (p[0] - p[1] + p[2] - p[3]).length();
        let (side_u, side_v) = (p[1] - p[0], p[3] - p[0]);
        let longest = side_u.length().max(side_v.length());
        let angle = if longest > 0.0 { side_u.dot(side_v).abs() / longest } else { 0.0 };
        defect + angle
    }
}

/// Builds a [`Rectangle`] on every selected quad face of the input. No options. Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct RectangleType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "rectangle: every selected quad face becomes a rectangle",
    options: &[],
    element: Element::Face { min: 4, max: 4 },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for RectangleType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let built = selected_quads(ctx, KIND)?
            .into_iter()
            .map(|corners| Box::new(Rectangle::new(corners)) as Box<dyn Constraint>)
            .collect();
        non_empty(built, KIND, "quad faces")
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::test_util::{Rng, dist2};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::mesh::{Mesh, Polygons};

    fn project(c: &Rectangle, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; 4];
        c.project(q, &mut out);
        out
    }

    /// A rectangle c ± a u ± b v with u ⊥ v the orthonormalized (w₁, w₂).
    fn rectangle(c: DVec3, a: f64, b: f64, w1: DVec3, w2: DVec3) -> Vec<DVec3> {
        let u = w1.normalize();
        let v = (w2 - u * u.dot(w2)).normalize();
        (0..4).map(|i| c + S[i] * a * u + T[i] * b * v).collect()
    }

    #[test]
    fn a_rectangle_projects_to_itself_and_rows_are_centred() {
        let mut rng = Rng(301);
        let c = Rectangle::new([0, 1, 2, 3]);
        for _ in 0..20 {
            let x = rectangle(rng.vec3(), rng.uniform(), rng.uniform(), rng.vec3(), rng.vec3());
            assert!(c.energy(&x) < 1e-28);
            let p = project(&c, &x);
            assert!(c.set_residual(&p) < 1e-15);
            let mean = (x[0] + x[1] + x[2] + x[3]) / 4.0;
            let centred: Vec<DVec3> = x.iter().map(|y| *y - mean).collect();
            assert!(dist2(&c.apply(&x), &centred) < 1e-28);
            assert!(dist2(&p, &centred) < 1e-26);
        }
    }

    #[test]
    fn projection_is_a_rectangle_and_no_sampled_rectangle_is_closer() {
        let mut rng = Rng(303);
        let c = Rectangle::new([0, 1, 2, 3]);
        for trial in 0..300 {
            let q: Vec<DVec3> = match trial % 4 {
                0 => rectangle(rng.vec3(), rng.uniform(), rng.uniform(), rng.vec3(), rng.vec3())
                    .into_iter()
                    .map(|x| x + 0.3 * rng.vec3())
                    .collect(),
                1 => (0..4).map(|_| rng.vec3()).collect(),
                // nearly a square
                2 => rectangle(DVec3::ZERO, 0.5, 0.5, DVec3::X, DVec3::Y)
                    .into_iter()
                    .map(|x| x + 1e-3 * rng.vec3())
                    .collect(),
                // near P = Q (z ≈ 0): the angle is ill-conditioned, the distance is not
                _ => [DVec3::ZERO, DVec3::ZERO, DVec3::X, DVec3::ZERO].iter().map(|x| *x + 1e-3 * rng.vec3()).collect(),
            };
            let p = project(&c, &q);
            assert!(c.set_residual(&p) < 1e-14, "off the set by {}", c.set_residual(&p));
            let cq = c.apply(&q);
            let d = dist2(&cq, &p);
            // Brute force over orthonormal pairs: random ones, and ones near the optimum.
            let d0: [DVec3; 4] = [cq[0], cq[1], cq[2], cq[3]];
            let (au, bv) = Rectangle::fit(&d0);
            // The best rectangle with axes along the orthonormalized (u, v): a = u·P/4, b = v·Q/4.
            let pp: DVec3 = (0..4).map(|i| S[i] * cq[i]).sum();
            let qq: DVec3 = (0..4).map(|i| T[i] * cq[i]).sum();
            let best = |u: DVec3, v: DVec3| {
                let u = u.normalize();
                let v = (v - u * u.dot(v)).normalize();
                let (a, b) = (0.25 * u.dot(pp), 0.25 * v.dot(qq));
                (0..4).map(|i| S[i] * a * u + T[i] * b * v).collect::<Vec<_>>()
            };
            // The attained f = (u·P)² + (v·Q)² = 16(a² + b²) is the closed-form maximum
            // ½(|P|² + |Q|² + |z|), |z|² = (|P|² − |Q|²)² + 4‖P × Q‖².
            let (pn2, qn2) = (pp.length_squared(), qq.length_squared());
            let z = ((pn2 - qn2).powi(2) + 4.0 * pp.cross(qq).length_squared()).sqrt();
            let f = 16.0 * (au.length_squared() + bv.length_squared());
            assert!((f - 0.5 * (pn2 + qn2 + z)).abs() < 1e-12 * (1.0 + pn2 + qn2), "f = {f}");
            for _ in 0..200 {
                let sample = best(rng.vec3(), rng.vec3());
                assert!(d <= dist2(&cq, &sample) + 1e-12, "a random rectangle is closer");
                let (u0, v0) = (au.try_normalize().unwrap_or(DVec3::X), bv.try_normalize().unwrap_or(DVec3::Y));
                let near = best(u0 + 1e-3 * rng.vec3(), v0 + 1e-3 * rng.vec3());
                assert!(d <= dist2(&cq, &near) + 1e-12, "a nearby rectangle is closer");
                // Any rectangle near the projection (not just the best a, b for its axes).
                let other = rectangle(
                    1e-2 * rng.vec3(),
                    au.length() * (1.0 + 1e-2 * rng.uniform()),
                    bv.length() * (1.0 + 1e-2 * rng.uniform()),
                    au + 1e-2 * rng.vec3(),
                    bv + 1e-2 * rng.vec3(),
                );
                assert!(d <= dist2(&cq, &other) + 1e-12, "a rectangle near the projection is closer");
            }
        }
    }

    #[test]
    fn degenerate_inputs_give_finite_rectangles() {
        let c = Rectangle::new([0, 1, 2, 3]);
        let w = DVec3::new(0.3, -0.2, 0.9);
        let cases: Vec<Vec<DVec3>> = vec![
            vec![DVec3::ONE; 4],
            // pure (+,−,+,−) pattern: P = Q = 0, the nearest rectangle is a point
            vec![w, -w, w, -w],
            // P ∥ Q: all corners on a line
            vec![DVec3::ZERO, DVec3::X, 3.0 * DVec3::X, 0.5 * DVec3::X],
            // P = Q: every orientation is as good
            vec![DVec3::ZERO, DVec3::ZERO, DVec3::X, DVec3::ZERO],
        ];
        for q in cases {
            let p = project(&c, &q);
            assert!(p.iter().all(|x| x.is_finite()), "{q:?}");
            assert!(c.set_residual(&p) < 1e-15, "{q:?}");
            let cq = c.apply(&q);
            let d = dist2(&cq, &p);
            let mut rng = Rng(307);
            for _ in 0..200 {
                let other = rectangle(DVec3::ZERO, rng.uniform(), rng.uniform(), rng.vec3(), rng.vec3());
                assert!(d <= dist2(&cq, &other) + 1e-12, "{q:?}");
            }
        }
        let p = project(&c, &[w, -w, w, -w]);
        assert!(p.iter().all(|x| *x == DVec3::ZERO));
    }

    #[test]
    fn the_residual_refuses_parallelograms_and_trapezoids() {
        let c = Rectangle::new([0, 1, 2, 3]);
        let sheared = [DVec3::ZERO, DVec3::X, DVec3::new(1.3, 1.0, 0.0), DVec3::new(0.3, 1.0, 0.0)];
        assert!(c.set_residual(&sheared) > 0.1);
        let trapezoid = [DVec3::ZERO, DVec3::X, DVec3::new(0.8, 1.0, 0.0), DVec3::new(0.2, 1.0, 0.0)];
        assert!(c.set_residual(&trapezoid) > 0.1);
        let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        assert_eq!(c.set_residual(&square), 0.0);
    }

    fn quad_pair() -> Mesh {
        let positions = vec![
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::Y,
            DVec3::new(1.0, 1.0, 0.2),
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(1.0, 2.0, 0.0),
        ];
        let mut polygons = Polygons::new();
        polygons.push(&[0, 1, 4, 3]);
        polygons.push(&[1, 2, 5, 4]);
        polygons.push(&[3, 4, 6]);
        Mesh::from_polygons(positions, polygons).unwrap().0
    }

    #[test]
    fn build_takes_selected_quads_and_refuses_a_mesh_without_quads() {
        let mesh = quad_pair();
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let frame = WorkingFrame::IDENTITY;
        let build = |rest: &RestGeometry, sel: &Selection, params: Params| {
            build_constraints(KIND, &BuildContext { rest, selection: sel, frame: &frame }, params)
        };
        let all = build(&rest, &Selection::All, Params::default()).unwrap();
        assert_eq!(all.len(), 2, "the two quads, not the triangle");
        assert_eq!(all[0].vertices(), &[0, 1, 4, 3]);
        let second = build(&rest, &Selection::from_faces(7, &rest.faces, &[1]), Params::default()).unwrap();
        assert_eq!(second.len(), 1);
        assert_eq!(second[0].vertices(), &[1, 2, 5, 4]);
        let by_vertices = build(&rest, &Selection::from_indices(7, &[0, 1, 3, 4, 6]), Params::default()).unwrap();
        assert_eq!(by_vertices.len(), 1, "a vertex selection takes the quads all of whose corners it has");
        let err = build(&rest, &Selection::from_faces(7, &rest.faces, &[2]), Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::NothingSelected { .. }), "{err}");
        let err = build(&rest, &Selection::All, Params::default().with("aspect", 1.0)).unwrap_err();
        assert!(matches!(err, ConstraintError::UnknownOption { .. }), "{err}");

        let triangles = RestGeometry::new(mesh.positions.clone(), mesh.triangles.clone(), vec![]);
        let err = build(&triangles, &Selection::All, Params::default()).unwrap_err();
        assert!(matches!(err, ConstraintError::Invalid { .. }), "{err}");
        let text = err.to_string();
        assert!(text.starts_with("rectangle: the mesh has no quad faces ("), "{text}");
        assert!(text.contains("have 3 corners"), "{text}");
    }

    #[test]
    fn a_solve_makes_a_wavy_quad_grid_rectangular() {
        use crate::constraints::{GroupDescription, build_group};
        use crate::solver::{SolverParams, System};
        let n = 3u32;
        let mut positions = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                positions.push(DVec3::new(x + 0.1 * y * y, y, 0.2 * (3.0 * x).sin() * (2.0 * y).cos()));
            }
        }
        let mut polygons = Polygons::new();
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                polygons.push(&[at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let mesh = Mesh::from_polygons(positions, polygons).unwrap().0;
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let frame = WorkingFrame::IDENTITY;
        let group = build_group(&GroupDescription::new(KIND, Selection::All), &rest, &frame).unwrap();
        let worst = |q: &[DVec3]| group.constraints.iter().map(|c| c.set_residual(&c.apply(q))).fold(0.0, f64::max);
        let before = worst(&rest.positions);
        let mut system = System::new(rest.num_vertices(), SolverParams::default());
        system.add_group(build_group(&GroupDescription::new(KIND, Selection::All), &rest, &frame).unwrap()).unwrap();
        let closeness = GroupDescription::new("position", Selection::All).weight(1e-3);
        system.add_group(build_group(&closeness, &rest, &frame).unwrap()).unwrap();
        let mut q = rest.positions.clone();
        system.solve(&mut q, 500, 0.0).unwrap();
        let after = worst(&q);
        assert!(after < 1e-2 * before, "before {before:e}, after {after:e}");
    }
}
