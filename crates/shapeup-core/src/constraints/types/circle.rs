//! Circle (circularity): the corners of each polygon face, or a whole vertex set, kept on one
//! circle.
//!
//! Term ω Σ_i ‖(q_i − q̄) − p_i‖² over the k corners of a face (k ≥ 4), or over all the selected
//! vertices (k ≥ 3) with `whole_selection = true`, mean-centred rows C = I − 11ᵀ/k (as
//! ShapeOp); the set is the centred concyclic configurations, with its closure, the collinear
//! ones. Projection: the nearest points on the geometric best-fit circle in 3D, found by the
//! multi-start Levenberg–Marquardt fit of [`kit::fit`](crate::constraints::kit::fit), then
//! recentred. Residual: the centroid offset and σ₄ of the lifted matrix
//! ([`lifted_singular_values`](crate::constraints::kit::sets::lifted_singular_values)). ω = 1,
//! default multiplier 10.
//!
//! The formulas, the starts, the schedule, the sources (ShapeUp, ShapeOp `CircleConstraint`)
//! and the choices left open are in the math reference, docs/math.md, "circle".

use crate::constraints::contract::{BuildContext, Constraint, ConstraintType, TypeInfo};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::sets;
use crate::constraints::kit::faces::WHOLE_SELECTION;
use crate::constraints::kit::fit::{Model, best_fit, distance, distance_in, from_algebraic};
use crate::constraints::kit::point_set::{PointSet, Primitive, faces_or_set, project_at_unit_scale};
use crate::constraints::kit::vertex_set::centred_view;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::linalg::jet::{Scalar, V3};
use crate::linalg::small::linear_least_squares;
use glam::{DQuat, DVec3};

/// Name in scene files.
const KIND: &str = "circle";

/// Up to this many points, the fit starts from the circle through every triple.
const ALL_TRIPLES_UP_TO: usize = 6;

/// A generalized circle: through `s`, axis `m`, in-plane normal `n` at s, curvature `kappa`.
#[derive(Debug, Clone, Copy)]
struct CircleFit {
    m: DVec3,
    n: DVec3,
    s: DVec3,
    kappa: f64,
}

impl CircleFit {
    /// The nearest point of the circle to x: into its plane, then along the in-plane normal.
    fn nearest(&self, x: DVec3) -> DVec3 {
        let y = x - self.s;
        let z = y.dot(self.m);
        let dist = distance(y - z * self.m, self.n, self.kappa);
        x - z * self.m - dist.d * dist.direction(self.n)
    }
}

impl Model<6> for CircleFit {
    /// Two residuals per point, the out-of-plane offset z = m·y and the in-plane distance,
    /// y = x − s. θ = (the frame turned by ω = θ₀m + θ₁n + θ₂t about s, s moved θ₃ along n
    /// and θ₄ along m, κ + θ₅).
    fn residuals<T: Scalar>(&self, points: &[DVec3], theta: [T; 6], mut each: impl FnMut(T)) {
        let t = self.m.cross(self.n);
        let omega = V3::along(self.m, theta[0]).add(V3::along(self.n, theta[1])).add(V3::along(t, theta[2]));
        let (m, n) = (V3::turned(self.m, omega), V3::turned(self.n, omega));
        let s = V3::constant(self.s).add(V3::along(self.n, theta[3])).add(V3::along(self.m, theta[4]));
        let kappa = T::constant(self.kappa) + theta[5];
        for &x in points {
            let y = V3::constant(x).sub(s);
            let z = y.dot(m);
            each(z);
            each(distance_in(y.sub(m.times(z)), n, kappa));
        }
    }
    fn step(&self, delta: &[f64; 6]) -> Self {
        let t = self.m.cross(self.n);
        let turn = DQuat::from_scaled_axis(delta[0] * self.m + delta[1] * self.n + delta[2] * t);
        let m = (turn * self.m).normalize_or(self.m);
        let n = turn * self.n;
        let n = (n - n.dot(m) * m).normalize_or(self.n);
        CircleFit { m, n, s: self.s + delta[3] * self.n + delta[4] * self.m, kappa: self.kappa + delta[5] }
    }
}

/// The Kåsa circle of `points` in the plane through `origin` spanned by the orthonormal `e1`,
/// `e2` (axis `m`): the least-squares solution of u² + v² + a u + b v + e = 0; `None` when
/// singular (collinear) or imaginary.
fn kasa_circle(points: &[DVec3], origin: DVec3, e1: DVec3, e2: DVec3, m: DVec3) -> Option<CircleFit> {
    let rows = points.iter().map(|&x| {
        let (u, v) = ((x - origin).dot(e1), (x - origin).dot(e2));
        ([u, v, 1.0], -(u * u + v * v))
    });
    let a = linear_least_squares(rows)?;
    let (s, n, kappa) = from_algebraic(1.0, DVec3::new(a[0], a[1], 0.0), a[2], DVec3::X)?;
    Some(CircleFit { m, n: n.x * e1 + n.y * e2, s: origin + s.x * e1 + s.y * e2, kappa })
}

/// The triples of point indices the fit also starts from: all of them for k ≤ 6, else up to
/// four spread ones (distinct).
fn triples(k: usize) -> Vec<[usize; 3]> {
    if k <= ALL_TRIPLES_UP_TO {
        let mut all = Vec::new();
        for a in 0..k {
            for b in a + 1..k {
                for c in b + 1..k {
                    all.push([a, b, c]);
                }
            }
        }
        all
    } else {
        let mut spread: Vec<[usize; 3]> = Vec::with_capacity(4);
        for r in 0..4 {
            let triple = [r * k / 12, r * k / 12 + k / 3, r * k / 12 + 2 * k / 3];
            if !spread.contains(&triple) {
                spread.push(triple);
            }
        }
        spread
    }
}

/// The geometric best-fit generalized circle of `points` (centred, unit RMS radius), and its
/// cost: the best of the fits from the starts the module doc lists.
fn fit_circle(points: &[DVec3]) -> (CircleFit, f64) {
    let (_, _, [e1, e2, e3]) = sets::principal_axes(points);
    let line = CircleFit { m: e3, n: e2, s: DVec3::ZERO, kappa: 0.0 };
    let mut starts = Vec::new();
    if let Some(kasa) = kasa_circle(points, DVec3::ZERO, e1, e2, e3) {
        starts.push(kasa);
    }
    starts.push(line);
    for [a, b, c] in triples(points.len()) {
        let (pa, pb, pc) = (points[a], points[b], points[c]);
        let (u, v) = (pb - pa, pc - pa);
        let normal = u.cross(v);
        if normal.length() <= 1e-9 * u.length() * v.length() || normal.length() == 0.0 {
            continue;
        }
        let (e1, m) = (u.normalize(), normal.normalize());
        if let Some(start) = kasa_circle(&[pa, pb, pc], pa, e1, m.cross(e1), m) {
            starts.push(start);
        }
    }
    best_fit(starts, points).unwrap_or((line, f64::INFINITY))
}

/// The circle constraint on a face's corners or a vertex set (k ≥ 3, distinct):
/// [`PointSet::new`] keeps them on one circle, `None` with fewer than 3.
pub type Circle = PointSet<Concyclic>;

/// The circle's primitive: centred concyclic configurations (and collinear ones, their
/// closure), projected onto the geometric best-fit circle.
#[derive(Debug, Clone, Copy)]
pub struct Concyclic;

impl Primitive for Concyclic {
    const KIND: &'static str = KIND;
    const MIN_VERTICES: usize = 3;

    fn project(d: &[DVec3], out: &mut [DVec3]) {
        project_at_unit_scale(d, out, |points, out| {
            let (fit, _) = fit_circle(points);
            for (o, &x) in out.iter_mut().zip(points) {
                *o = fit.nearest(x);
            }
        });
    }
    /// √(‖Σ p_i‖²/k + σ₄²), σ₄ the fourth singular value of the lifted rows
    /// (‖y_i‖²/L, y_i, L): zero exactly on one circle (or line), centred.
    fn set_residual(p: &[DVec3]) -> f64 {
        let p = centred_view(p);
        let sigma = sets::lifted_singular_values(&p);
        (sets::centroid_offset(&p).powi(2) + sigma[3] * sigma[3]).sqrt()
    }
}

/// Builds a [`Circle`] on every selected polygon face of 4 or more corners, or one over all
/// the selected vertices (at least 3) with `whole_selection = true`. Default multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct CircleType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "circle: the corners of each polygon face (or the whole selection) stay on one circle",
    options: &[WHOLE_SELECTION],
    element: Element::Face { min: 4, max: usize::MAX },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for CircleType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        faces_or_set::<Concyclic>(
            ctx,
            params,
            "three points always lie on a circle or a line",
            "which always lie on a circle",
        )
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::fit::rms_radius;
    use crate::constraints::kit::test_util::{Rng, dist2, project};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};
    use crate::mesh::{Mesh, Polygons};

    /// Σ_i dist(x_i, circle)² for the circle of centre c, unit axis a, radius r, by the
    /// textbook formula (out-of-plane offset, radial offset).
    fn circle_cost(points: &[DVec3], c: DVec3, a: DVec3, r: f64) -> f64 {
        points
            .iter()
            .map(|&x| {
                let y = x - c;
                let z = y.dot(a);
                ((y - z * a).length() - r).powi(2) + z * z
            })
            .sum()
    }

    /// The 4th singular value of the lifted rows, by nalgebra (independent of the residual's
    /// Jacobi SVD).
    fn lifted_fourth(p: &[DVec3]) -> f64 {
        let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let l = p.iter().map(|&x| (x - mean).length()).fold(0.0, f64::max);
        let m = nalgebra::DMatrix::from_fn(p.len(), 5, |i, j| {
            let y = p[i] - mean;
            [y.length_squared() / l, y.x, y.y, y.z, l][j]
        });
        let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
        s.sort_by(|a, b| b.total_cmp(a));
        s.resize(5, 0.0);
        s[3]
    }

    /// k points near a circle of radius r (random centre and axis) over an arc of the given
    /// extent, with noise.
    fn near_circle(rng: &mut Rng, k: usize, r: f64, arc: f64, noise: f64) -> Vec<DVec3> {
        let (c, a) = (rng.vec3(), rng.vec3().normalize());
        let (u, v) = a.any_orthonormal_pair();
        (0..k)
            .map(|_| {
                let t = arc * rng.uniform();
                c + r * (t.cos() * u + t.sin() * v) + noise * rng.vec3()
            })
            .collect()
    }

    /// The fitted circle in the input's units: centre, axis, radius (None for a line).
    fn fitted(cq: &[DVec3]) -> (Option<(DVec3, DVec3, f64)>, f64) {
        let (mean, scale) = rms_radius(cq);
        let points: Vec<DVec3> = cq.iter().map(|&x| (x - mean) / scale).collect();
        let (fit, cost) = fit_circle(&points);
        let circle = (fit.kappa.abs() > 1e-9)
            .then(|| (mean + scale * (fit.s - fit.n / fit.kappa), fit.m, scale / fit.kappa.abs()));
        (circle, cost * scale * scale)
    }

    #[test]
    fn projection_is_concyclic_centred_and_no_sampled_circle_is_closer() {
        let mut rng = Rng(53);
        for trial in 0..60 {
            let k = 3 + trial % 10;
            let c = Circle::new((0..k as u32).collect()).unwrap();
            let noise = [0.0, 0.01, 0.1, 0.4][trial % 4];
            let arc = [3.2, 1.0, 0.3][trial % 3];
            let r = 0.2 + rng.uniform().abs();
            let q = near_circle(&mut rng, k, r, arc, noise);
            let cq = c.apply(&q);
            let p = project(&c, &q);
            let size = 1.0 + cq.iter().map(|x| x.length()).fold(0.0, f64::max);
            if k >= 4 {
                assert!(lifted_fourth(&p) < 1e-12 * size, "trial {trial}: σ₄ = {:e}", lifted_fourth(&p));
            }
            assert!(sets::centroid_offset(&p) < 1e-13 * size);
            assert!(c.set_residual(&p) < 1e-12 * size);
            let d = dist2(&cq, &p);
            let (circle, cost) = fitted(&cq);
            assert!(d <= cost + 1e-14 && cost - d <= 1e-10 * (1.0 + d), "{cost} vs {d}");
            if let Some((centre, axis, r)) = circle {
                for j in 0..300 {
                    let eps = [1e-4, 1e-2, 0.2][j % 3] * r;
                    let turned = (axis + [1e-4, 1e-2, 0.2][j % 3] * rng.vec3()).normalize();
                    let other = circle_cost(&cq, centre + eps * rng.vec3(), turned, r + eps * rng.uniform());
                    assert!(d <= other + 1e-12, "trial {trial}: a sampled circle is nearer ({other:e} < {d:e})");
                }
            }
            // Circles through 3 random points of the input: none nearer.
            for _ in 0..50 {
                let i: Vec<usize> = (0..3).map(|_| (rng.uniform().abs() * k as f64) as usize % k).collect();
                let (a, b, e) = (cq[i[0]], cq[i[1]], cq[i[2]]);
                let axis = (b - a).cross(e - a);
                if axis.length() > 1e-6 {
                    // Circumcentre of a, b, e.
                    let (u, v) = (b - a, e - a);
                    let centre = a
                        + (u.length_squared() * v - v.length_squared() * u).cross(axis) / (2.0 * axis.length_squared());
                    assert!(d <= circle_cost(&cq, centre, axis.normalize(), (a - centre).length()) + 1e-12);
                }
            }
        }
    }

    #[test]
    fn derivatives_are_those_of_the_steps() {
        let mut rng = Rng(71);
        for trial in 0..20 {
            let points: Vec<DVec3> = (0..6).map(|_| rng.vec3()).collect();
            let m = rng.vec3().normalize();
            let kappa = [0.0, 0.8, -1.5, 1e-6][trial % 4];
            let fit = CircleFit { m, n: m.any_orthonormal_vector(), s: 0.3 * rng.vec3(), kappa };
            crate::constraints::kit::fit::tests::check_derivatives(fit, &points);
        }
    }

    #[test]
    fn the_fit_is_the_lowest_of_many_random_starts() {
        let mut rng = Rng(59);
        for trial in 0..30 {
            let k = 4 + trial % 6;
            let q = near_circle(&mut rng, k, 0.5, [3.2, 1.0][trial % 2], 0.3);
            let (mean, scale) = rms_radius(&q);
            let points: Vec<DVec3> = q.iter().map(|&x| (x - mean) / scale).collect();
            let (fit, cost) = fit_circle(&points);
            // Converged: refining the fit again moves no projected point.
            let (again, _) = best_fit([fit], &points).unwrap();
            let moved = points.iter().map(|&x| (fit.nearest(x) - again.nearest(x)).length()).fold(0.0, f64::max);
            assert!(moved < 1e-12, "trial {trial}: a second fit moves a point by {moved:e}");
            for _ in 0..40 {
                let m = rng.vec3().normalize();
                let n = m.any_orthonormal_vector();
                let start = CircleFit { m, n, s: rng.vec3(), kappa: 2.0 * rng.uniform() };
                let (_, other) = best_fit([start], &points).unwrap();
                assert!(cost <= other + 1e-12, "trial {trial}: a random start found {other:e} < {cost:e}");
            }
        }
    }

    #[test]
    fn points_on_a_circle_stay_and_degenerate_sets_stay_finite() {
        let mut rng = Rng(61);
        let c = Circle::new((0..6).collect()).unwrap();
        let on = near_circle(&mut rng, 6, 0.7, 3.0, 0.0);
        assert!(dist2(&project(&c, &on), &c.apply(&on)) < 1e-24, "a concyclic set is its own projection");
        // Collinear: on the closure (a line), so it stays, finite.
        let line: Vec<DVec3> = (0..6).map(|i| DVec3::new(i as f64, -2.0 * i as f64, 0.5)).collect();
        let p = project(&c, &line);
        assert!(p.iter().all(|x| x.is_finite()));
        assert!(c.set_residual(&p) < 1e-12);
        assert!(dist2(&p, &c.apply(&line)) < 1e-20);
        // Nearly collinear: a huge circle, still finite and on the set.
        let bent: Vec<DVec3> = (0..6).map(|i| DVec3::new(i as f64, 1e-7 * ((i * i) as f64), 0.0)).collect();
        let p = project(&c, &bent);
        assert!(p.iter().all(|x| x.is_finite()) && c.set_residual(&p) < 1e-10);
        // Coincident points.
        assert!(project(&c, &[DVec3::ONE; 6]).iter().all(|x| *x == DVec3::ZERO));
    }

    #[test]
    fn rigid_motions_move_the_projection_along() {
        let mut rng = Rng(67);
        let c = Circle::new((0..5).collect()).unwrap();
        for trial in 0..20 {
            let q = near_circle(&mut rng, 5, 0.6, [3.0, 0.8][trial % 2], 0.2);
            let turn = DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize();
            let shift = rng.vec3();
            let moved: Vec<DVec3> = q.iter().map(|&x| turn * x + shift).collect();
            let turned: Vec<DVec3> = project(&c, &q).iter().map(|&x| turn * x).collect();
            let off = dist2(&turned, &project(&c, &moved));
            assert!(off < 1e-20, "trial {trial}: {off:e}");
        }
    }

    #[test]
    fn build_refuses_two_vertices_and_triangle_only_meshes() {
        let mut positions = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                positions.push(DVec3::new(i as f64, j as f64, 0.1 * (i * j) as f64));
            }
        }
        let mut polygons = Polygons::new();
        for j in 0..2u32 {
            for i in 0..2u32 {
                polygons.push(&[3 * j + i, 3 * j + i + 1, 3 * j + i + 4, 3 * j + i + 3]);
            }
        }
        let mesh = Mesh::from_polygons(positions, polygons).unwrap().0;
        let rest = RestGeometry::of_mesh(mesh.positions.clone(), &mesh);
        let frame = WorkingFrame::IDENTITY;
        let ctx = |selection| BuildContext { rest: &rest, selection, frame: &frame };
        assert_eq!(build_constraints(KIND, &ctx(&Selection::All), Params::default()).unwrap().len(), 4);
        let whole = Params::default().with("whole_selection", true);
        assert_eq!(build_constraints(KIND, &ctx(&Selection::All), whole.clone()).unwrap()[0].num_rows(), 9);
        let two = Selection::from_indices(9, &[0, 8]);
        let err = build_constraints(KIND, &ctx(&two), whole).unwrap_err();
        let text = err.to_string();
        assert!(
            matches!(err, ConstraintError::Invalid { .. }) && text.contains("has 2") && !text.contains('\n'),
            "{text}"
        );
        let triangles = RestGeometry::new(rest.positions.clone(), rest.triangles.clone(), vec![]);
        let err = build_constraints(
            KIND,
            &BuildContext { rest: &triangles, selection: &Selection::All, frame: &frame },
            Params::default(),
        )
        .unwrap_err();
        assert!(err.to_string().starts_with("circle: the mesh has no polygon faces of 4 or more corners ("), "{err}");
    }
}
