//! Sphere: a set of vertices kept on a common sphere.
//!
//! Term ω Σ_i ‖(q_i − q̄) − p_i‖² over the k ≥ 4 selected vertices, mean-centred rows
//! C = I − 11ᵀ/k (as ShapeOp); the set is the centred configurations on one sphere, with its
//! closure, the coplanar ones. Projection: the nearest points on the geometric best-fit sphere,
//! found by the multi-start Levenberg–Marquardt fit of [`kit::fit`](crate::constraints::kit::fit)
//! on the sphere's parametrization (a point s, the normal n there, the curvature κ: [`SphereFit`]),
//! then recentred. Residual: the centroid offset and σ₅ of the lifted matrix
//! ([`lifted_singular_values`](crate::constraints::kit::sets::lifted_singular_values)). ω = 1,
//! default multiplier 10.
//!
//! The formulas, the starts, the schedule, the sources (ShapeUp §4, ShapeOp `SphereConstraint`)
//! and the choices left open are in the math reference, docs/math.md, "sphere".

use crate::constraints::contract::{BuildContext, Constraint, ConstraintType, TypeInfo};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::sets;
use crate::constraints::kit::point_set::{PointSet, Primitive, one_set, project_at_unit_scale};
use crate::constraints::kit::vertex_set::centred_view;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::{DQuat, DVec3};
use crate::constraints::kit::fit::{Model, best_fit, distance, distance_in, from_algebraic};
use crate::linalg::jet::{Scalar, V3};
use crate::linalg::small::linear_least_squares;

/// Name in scene files.
const KIND: &str = "sphere";




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

/// The sphere constraint on a vertex set (k ≥ 4, distinct): [`PointSet::new`] keeps them on one
/// sphere, `None` with fewer than 4.
pub type Sphere = PointSet<Cospherical>;

/// The sphere's primitive: centred cospherical configurations (and coplanar ones, their
/// closure), projected onto the geometric best-fit sphere.
#[derive(Debug, Clone, Copy)]
pub struct Cospherical;

impl Primitive for Cospherical {
    const KIND: &'static str = KIND;
    const MIN_VERTICES: usize = 4;

    fn project(d: &[DVec3], out: &mut [DVec3]) {
        project_at_unit_scale(d, out, |points, out| {
            let (fit, _) = fit_sphere(points);
            for (o, &x) in out.iter_mut().zip(points) {
                let dist = distance(x - fit.s, fit.n, fit.kappa);
                *o = x - dist.d * dist.direction(fit.n);
            }
        });
    }
    /// √(‖Σ p_i‖²/k + σ₅²), σ₅ the smallest singular value of the lifted rows
    /// (‖y_i‖²/L, y_i, L): zero exactly on one sphere (or plane), centred.
    fn set_residual(p: &[DVec3]) -> f64 {
        let p = centred_view(p);
        let sigma = sets::lifted_singular_values(&p);
        (sets::centroid_offset(&p).powi(2) + sigma[4] * sigma[4]).sqrt()
    }
}

/// Builds one [`Sphere`] over all the selected vertices (at least 4). No options. Default
/// multiplier 10.
#[derive(Debug, Clone, Copy)]
pub struct SphereType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "sphere: the selected vertices stay on one sphere",
    options: &[],
    element: Element::VertexSet { min: 4 },
    default_multiplier: 10.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for SphereType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        one_set::<Cospherical>(ctx, "four points always lie on a sphere or a plane")
    }
}

#[cfg(test)]
pub(crate) mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::kit::fit::tests::check_derivatives;
    use crate::constraints::kit::fit::rms_radius;
    use crate::constraints::kit::test_util::{Rng, dist2, project};
    use crate::constraints::{Selection, build_constraints};
    use crate::geometry::{RestGeometry, WorkingFrame};

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
