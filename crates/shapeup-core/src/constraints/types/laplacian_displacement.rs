//! Laplacian displacement (detail preservation): each vertex keeps its rest umbrella vector
//! δ⁰_i = L_i x⁰, expressed in the frame of its one-ring, which moves rigidly with it.
//!
//! Term: ω Σ_r ‖(C q)_r − p_r‖² over k + 1 rows for a vertex i with k ≥ 1 neighbours j₁ … j_k:
//!
//!   rows r = 1 … k:  e_j = q_j − q_i                        rest values e⁰_j = x⁰_j − x⁰_i
//!   row  k + 1:      L_i q = q_i − (1/k) Σ_j q_j            rest value  δ⁰   = L_i x⁰
//!
//! (the uniform Laplacian of `laplacian`). Writing c_r for the rows of C q and r_r for their
//! rest values, the set is the rest one-ring with its Laplacian moved by a rotation,
//! {R r : R ∈ SO(3)}, and the projection is its exact nearest point (orthogonal Procrustes):
//!
//!   S = Σ_r c_r r_rᵀ = Σ_j e_j e⁰_jᵀ + (L_i q) δ⁰ᵀ,   R = U diag(1, 1, det UVᵀ) Vᵀ for S = UΣVᵀ,
//!   p_r = R r_r   (p_{k+1} = R δ⁰).
//!
//! With `similarity = true` the set is {s R r : s ≥ 0, R ∈ SO(3)} (the ring may also scale, as
//! in Laplacian surface editing) and p_r = s R r_r with the same R and
//! s = max(0, Σ_r c_r · R r_r) / Σ_r ‖r_r‖², again the exact nearest point (for any s > 0 the
//! best R maximizes tr(RᵀS), independently of s; then s minimizes a quadratic).
//! ω = 1, as ShapeOp's weight.
//!
//! Sources: ShapeOp's `UniformLaplacianConstraint` with `displacement = true` (Deuss et al.
//! 2015); the rotated detail vector of Laplacian surface editing (Sorkine et al., SGP 2004),
//! whose per-vertex transformation is also fitted to the vertex and its one-ring; the
//! local-global solver of ShapeUp (Bouaziz et al., SGP 2012).
//!
//! Choices, and why:
//! - ShapeOp keeps δ⁰ fixed in world space (p = δ⁰, a linear constraint). Then rotating the
//!   input and the handles does not rotate the result (the detail keeps pointing the world's
//!   way), which is wrong for detail preservation and fails the shared rigid-motion test. So δ⁰
//!   is rotated with the vertex's neighbourhood: p = R δ⁰, R the best rotation of the one-ring,
//!   as `iso_one_ring` finds it.
//! - The one-ring edges are rows too, so that p is the exact nearest point of the set. With only
//!   the Laplacian row and R from the one-ring, the set would be {R δ⁰ : R ∈ SO(3)}, the sphere
//!   of radius ‖δ⁰‖, whose nearest point to L_i q is ‖δ⁰‖ L_i q / ‖L_i q‖, not R δ⁰: the local
//!   step would not minimize its own term, and E could rise. Defining the set as that sphere
//!   instead would make the type a uniform-weight `bending` that forgets where the detail
//!   points relative to the surface (a bump could turn into a dent). Fitting R to the ring and
//!   the Laplacian together (Sorkine et al.'s fit) keeps the whole local shape, detail
//!   direction included, and the projection exact. The price: the term includes the
//!   `iso_one_ring` term (with ω = 1) plus the Laplacian row, so the one-ring is also held
//!   rigid (or similar, with `similarity`).
//! - N(i) is the triangles' one-ring (`topology.one_rings`), as in `laplacian`.

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::per_selected_vertex;
use crate::constraints::kit::laplacian_row::UniformLaplacianRow;
use crate::constraints::options::{OptionKind, OptionSpec};
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use crate::geometry::RestGeometry;
use crate::linalg::nearest_rotation3;
use glam::{DMat3, DVec3};

/// Name in scene files.
const KIND: &str = "laplacian_displacement";

/// Rest triples with |det| at most this times the product of their lengths count as planar
/// (then a reflection of the rest vectors is also a rotation of them).
const PLANAR: f64 = 1e-9;

/// `similarity`: let each one-ring scale as well as rotate.
const SIMILARITY: OptionSpec = OptionSpec {
    key: "similarity",
    doc: "let each one-ring scale as well as rotate (as-similar-as-possible, as Laplacian surface editing); \
          default false: rotate only",
    kind: OptionKind::Bool { default: false },
};

/// The Laplacian displacement constraint of one vertex.
#[derive(Debug, Clone)]
pub struct LaplacianDisplacement {
    row: UniformLaplacianRow,
    /// Rest values of the rows: the k rest edges e⁰_j, then δ⁰.
    rest: Box<[DVec3]>,
    /// Σ_r ‖r_r‖².
    rest_norm2: f64,
    similarity: bool,
    /// Three rest rows spanning space and the sign of their determinant, for the orientation
    /// test of [`Constraint::set_residual`]; `None` when the rest rows are planar.
    orientation: Option<([usize; 3], f64)>,
}

impl LaplacianDisplacement {
    /// The constraint of vertex `i` of the rest geometry; `None` if `i` has no neighbour.
    pub fn new(rest: &RestGeometry, i: usize, similarity: bool) -> Option<Self> {
        let row = UniformLaplacianRow::new(rest, i)?;
        let x = &rest.positions;
        let xi = x[i];
        let values: Box<[DVec3]> =
            row.vertices[1..].iter().map(|&j| x[j as usize] - xi).chain(std::iter::once(row.apply(x))).collect();
        let rest_norm2 = values.iter().map(|r| r.length_squared()).sum();
        let orientation = spanning_triple(&values);
        Some(LaplacianDisplacement { row, rest: values, rest_norm2, similarity, orientation })
    }

    /// C q: the k edges e_j, then L_i q.
    fn rows_at(&self, q: &[DVec3], out: &mut [DVec3]) {
        let qi = q[self.row.vertices[0] as usize];
        let k = self.row.degree();
        let mut mean = DVec3::ZERO;
        for (o, &j) in out.iter_mut().zip(&self.row.vertices[1..]) {
            *o = q[j as usize] - qi;
            mean += *o;
        }
        out[k] = -mean / k as f64;
    }

    /// The best rotation R = argmax tr(Rᵀ S), S = Σ_r c_r r_rᵀ, for rows `c`.
    fn rotation(&self, c: &[DVec3]) -> DMat3 {
        let (mut s0, mut s1, mut s2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (cr, r) in c.iter().zip(self.rest.iter()) {
            s0 += *cr * r.x;
            s1 += *cr * r.y;
            s2 += *cr * r.z;
        }
        nearest_rotation3(DMat3::from_cols(s0, s1, s2))
    }
}

/// A greedy choice of three of `r` that span space (the longest, the one farthest from its
/// line, the one farthest from their plane) and the sign of their determinant; `None` if `r`
/// is planar to [`PLANAR`].
fn spanning_triple(r: &[DVec3]) -> Option<([usize; 3], f64)> {
    let argmax = |f: &dyn Fn(DVec3) -> f64| {
        (0..r.len()).map(|k| (k, f(r[k]))).fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
    };
    let (a, la) = argmax(&|v| v.length());
    let (b, _) = argmax(&|v| r[a].cross(v).length());
    let (c, det) = argmax(&|v| r[a].cross(r[b]).dot(v).abs());
    let scale = la * r[b].length() * r[c].length();
    (scale > 0.0 && det > PLANAR * scale).then(|| ([a, b, c], r[a].cross(r[b]).dot(r[c]).signum()))
}

impl Constraint for LaplacianDisplacement {
    fn kind(&self) -> &'static str {
        KIND
    }
    fn vertices(&self) -> &[u32] {
        &self.row.vertices
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        self.rest.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        let centre = self.row.vertices[0];
        for (r, &j) in self.row.vertices[1..].iter().enumerate() {
            sink.push(r, centre, -1.0);
            sink.push(r, j, 1.0);
        }
        self.row.rows(sink, self.row.degree());
    }
    fn project(&self, q: &[DVec3], out: &mut [DVec3]) {
        // C q into `out` first (it has the right length), then overwritten by p.
        self.rows_at(q, out);
        let r = self.rotation(out);
        let scale = if self.similarity {
            let fit: f64 = out.iter().zip(self.rest.iter()).map(|(c, x)| c.dot(r * *x)).sum();
            if self.rest_norm2 > 0.0 { fit.max(0.0) / self.rest_norm2 } else { 0.0 }
        } else {
            1.0
        };
        for (o, x) in out.iter_mut().zip(self.rest.iter()) {
            *o = scale * (r * *x);
        }
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        // p = s R r exactly when its Gram matrix is s² that of r (an orthogonal map times s) and,
        // for a spanning r, the orientation is kept (a rotation, not a reflection). Gram entries
        // are squared lengths and determinants cubed: divided by the rows' size L (and L²) the
        // residual is a length at every scale.
        if !p.iter().all(|x| x.is_finite()) {
            return f64::INFINITY;
        }
        let s2 = if self.similarity && self.rest_norm2 > 0.0 {
            p.iter().map(|x| x.length_squared()).sum::<f64>() / self.rest_norm2
        } else {
            1.0
        };
        let longest = |rows: &[DVec3]| rows.iter().map(|x| x.length()).fold(0.0, f64::max);
        let size = longest(p).max(s2.sqrt() * longest(&self.rest));
        if size == 0.0 {
            return 0.0;
        }
        let mut worst: f64 = 0.0;
        for a in 0..p.len() {
            for b in a..p.len() {
                worst = worst.max((p[a].dot(p[b]) - s2 * self.rest[a].dot(self.rest[b])).abs());
            }
        }
        worst /= size;
        if let Some(([a, b, c], sign)) = self.orientation {
            let det = p[a].cross(p[b]).dot(p[c]);
            worst = worst.max((-sign * det).max(0.0) / (size * size));
        }
        worst
    }
}

/// Builds a [`LaplacianDisplacement`] on every selected vertex with at least one neighbour
/// (the neighbours need not be selected). Option `similarity` (default false). Default
/// multiplier 1.
#[derive(Debug, Clone, Copy)]
pub struct LaplacianDisplacementType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: KIND,
    summary: "Laplacian displacement: each vertex keeps its rest detail vector, turning with its one-ring",
    options: &[SIMILARITY],
    element: Element::Vertex,
    default_multiplier: 1.0,
    has_targets: false,
    rigidly_invariant: true,
};

impl ConstraintType for LaplacianDisplacementType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let similarity = params.flag(KIND, &SIMILARITY)?;
        let rest = ctx.rest;
        per_selected_vertex(ctx, KIND, "vertices with a neighbour", |i| LaplacianDisplacement::new(rest, i, similarity))
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
    use glam::DQuat;

    fn rotation(rng: &mut Rng) -> DMat3 {
        DMat3::from_quat(DQuat::from_xyzw(rng.uniform(), rng.uniform(), rng.uniform(), rng.uniform()).normalize())
    }

    fn project(c: &LaplacianDisplacement, q: &[DVec3]) -> Vec<DVec3> {
        let mut out = vec![DVec3::ZERO; c.num_rows()];
        c.project(q, &mut out);
        out
    }

    #[test]
    fn rows_are_the_edges_and_the_uniform_laplacian() {
        let rest = octahedron();
        let c = LaplacianDisplacement::new(&rest, 4, false).unwrap();
        let ring = &rest.topology.one_rings[4];
        assert_eq!(c.num_rows(), ring.len() + 1);
        let mut rng = Rng(11);
        let q: Vec<DVec3> = rest.positions.iter().map(|&x| x + 0.2 * rng.vec3()).collect();
        let cq = c.apply(&q);
        let mut direct = vec![DVec3::ZERO; c.num_rows()];
        c.rows_at(&q, &mut direct);
        assert!(dist2(&cq, &direct) < 1e-28);
        for (r, &j) in ring.iter().enumerate() {
            assert!((cq[r] - (q[j as usize] - q[4])).length() < 1e-14);
        }
        let lap = q[4] - ring.iter().map(|&j| q[j as usize]).sum::<DVec3>() / ring.len() as f64;
        assert!((cq[ring.len()] - lap).length() < 1e-14);
        // At rest: E = 0, and δ⁰ is the rest Laplacian (the apex is curved).
        assert!(c.energy(&rest.positions) < 1e-28);
        assert!(c.rest[ring.len()].length() > 0.1);
    }

    #[test]
    fn projection_is_on_the_set_and_no_sampled_point_is_closer() {
        let rest = octahedron();
        let mut rng = Rng(13);
        for similarity in [false, true] {
            for i in [0, 4, 5] {
                let c = LaplacianDisplacement::new(&rest, i, similarity).unwrap();
                assert!(c.orientation.is_some(), "the octahedron's rings are not planar");
                for trial in 0..40 {
                    let q: Vec<DVec3> = match trial % 3 {
                        0 => {
                            let r = rotation(&mut rng);
                            rest.positions.iter().map(|&x| 1.3 * (r * x) + 0.2 * rng.vec3()).collect()
                        }
                        1 => rest.positions.iter().map(|x| DVec3::new(x.x, -x.y, x.z) + 0.05 * rng.vec3()).collect(),
                        _ => rest.positions.iter().map(|_| rng.vec3()).collect(),
                    };
                    let cq = c.apply(&q);
                    let p = project(&c, &q);
                    assert!(c.set_residual(&p) < 1e-12, "off the set by {:e}", c.set_residual(&p));
                    let d = dist2(&cq, &p);
                    let r = c.rotation(&cq);
                    for _ in 0..300 {
                        let s = if similarity { 2.0 * rng.uniform().abs() } else { 1.0 };
                        let rot = if rng.uniform() < 0.0 {
                            rotation(&mut rng)
                        } else {
                            r * DMat3::from_axis_angle(rng.vec3().normalize(), 1e-2 * rng.uniform())
                        };
                        let sample: Vec<DVec3> = c.rest.iter().map(|x| s * (rot * *x)).collect();
                        assert!(c.set_residual(&sample) < 1e-12);
                        assert!(d <= dist2(&cq, &sample) + 1e-12, "a point of the set is closer");
                    }
                }
            }
        }
    }

    #[test]
    fn a_reflection_or_a_scaled_ring_is_off_the_rigid_set() {
        let rest = octahedron();
        let rigid = LaplacianDisplacement::new(&rest, 4, false).unwrap();
        let similar = LaplacianDisplacement::new(&rest, 4, true).unwrap();
        let mirrored: Vec<DVec3> = rigid.rest.iter().map(|x| DVec3::new(x.x, x.y, -x.z)).collect();
        assert!(rigid.set_residual(&mirrored) > 1e-3);
        assert!(similar.set_residual(&mirrored) > 1e-3);
        let scaled: Vec<DVec3> = rigid.rest.iter().map(|x| 1.5 * *x).collect();
        assert!(rigid.set_residual(&scaled) > 1e-3);
        assert!(similar.set_residual(&scaled) < 1e-12);
        // The fixed world-space δ⁰ of ShapeOp with rotated edges is not on the set.
        let r = DMat3::from_axis_angle(DVec3::X, 0.7);
        let mut world: Vec<DVec3> = rigid.rest.iter().map(|x| r * *x).collect();
        let k = world.len() - 1;
        world[k] = rigid.rest[k];
        assert!(rigid.set_residual(&world) > 1e-3);
    }

    #[test]
    fn rigid_motion_rotates_the_projection_and_scaling_shrinks_with_the_ring() {
        let rest = octahedron();
        let mut rng = Rng(17);
        for similarity in [false, true] {
            let c = LaplacianDisplacement::new(&rest, 4, similarity).unwrap();
            for _ in 0..30 {
                let q: Vec<DVec3> = rest.positions.iter().map(|&x| x + 0.2 * rng.vec3()).collect();
                let (r, shift) = (rotation(&mut rng), rng.vec3());
                let moved: Vec<DVec3> = q.iter().map(|x| r * *x + shift).collect();
                let rotated: Vec<DVec3> = project(&c, &q).iter().map(|x| r * *x).collect();
                assert!(dist2(&rotated, &project(&c, &moved)) < 1e-24);
            }
        }
        // A uniformly shrunk rest shape is on the similarity set (E = 0), not on the rigid one.
        let half: Vec<DVec3> = rest.positions.iter().map(|&x| 0.5 * x).collect();
        assert!(LaplacianDisplacement::new(&rest, 4, true).unwrap().energy(&half) < 1e-26);
        assert!(LaplacianDisplacement::new(&rest, 4, false).unwrap().energy(&half) > 1e-3);
    }

    #[test]
    fn a_collapsed_ring_projects_to_a_finite_point_of_the_set() {
        let rest = octahedron();
        for similarity in [false, true] {
            let c = LaplacianDisplacement::new(&rest, 4, similarity).unwrap();
            for q in [vec![DVec3::ONE; 6], rest.positions.iter().map(|x| DVec3::new(x.x, 0.0, 0.0)).collect()] {
                let p = project(&c, &q);
                assert!(p.iter().all(|x| x.is_finite()));
                assert!(c.set_residual(&p) < 1e-12);
            }
        }
    }

    #[test]
    fn build_reads_similarity_and_refuses_bad_values_by_name() {
        let rest = octahedron();
        let ctx = BuildContext { rest: &rest, selection: &Selection::All, frame: &WorkingFrame::IDENTITY };
        assert_eq!(build_constraints(KIND, &ctx, Params::default()).unwrap().len(), 6);
        assert_eq!(build_constraints(KIND, &ctx, Params::default().with("similarity", true)).unwrap().len(), 6);
        let err = build_constraints(KIND, &ctx, Params::default().with("similarity", 2.0)).unwrap_err();
        assert!(err.to_string().contains("similarity"), "{err}");
    }
}
