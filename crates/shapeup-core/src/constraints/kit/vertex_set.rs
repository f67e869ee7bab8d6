//! Vertex sets (line, plane, circle, sphere, rigid, similarity, rectangle, parallelogram): the
//! selection of a set, its mean-centred rows, and the centred rest shape a copy type matches.

use crate::constraints::contract::{BuildContext, RowSink};
use crate::constraints::error::ConstraintError;
use glam::{DMat3, DVec3};

/// The largest vertex set whose rows are mean-centred. C = I − 11ᵀ/k makes CᵀC a dense k×k
/// block (k² entries, k³ work to assemble: about 2 s at k = 500, minutes and tens of GB at a
/// few thousand); above this size a set's rows are its vertices themselves (C = I, CᵀC
/// diagonal) and its projection is the nearest point of the set at the current centroid,
/// p = p_c + q̄. Every set here (rigid and similar copies, lines, planes, circles, spheres) is
/// closed under translation, so min_{p ∈ S} ‖q − p‖² = min_{p ∈ S} ‖(q − q̄) − (p − p̄)‖²: the
/// energy is the same function of q either way (math reference, "Large vertex sets"). The
/// global step differs: with C = I it holds the set near its last centroid, so a large set
/// that must travel far takes more iterations.
pub(crate) const DENSE_SET_MAX: usize = 512;

/// Whether a set of `k` vertices has mean-centred rows (see [`DENSE_SET_MAX`]).
pub(crate) fn has_centred_rows(k: usize) -> bool {
    k <= DENSE_SET_MAX
}

/// Emits the rows of C over `vertices`: C = I − 11ᵀ/k (row i: q_i − (1/k) Σ_j q_j) up to
/// [`DENSE_SET_MAX`] vertices, else C = I (row i: q_i).
pub(crate) fn centred_rows(vertices: &[u32], sink: &mut RowSink) {
    if !has_centred_rows(vertices.len()) {
        for (row, &v) in vertices.iter().enumerate() {
            sink.push(row, v, 1.0);
        }
        return;
    }
    let share = 1.0 / vertices.len() as f64;
    for (row, &v) in vertices.iter().enumerate() {
        for &w in vertices {
            sink.push(row, w, if w == v { 1.0 - share } else { -share });
        }
    }
}

/// A projection `out` computed about the centroid, as C q's rows have it: moved back to the
/// current centroid of `vertices` when the rows are the vertices themselves (C = I).
pub(crate) fn to_row_frame(vertices: &[u32], q: &[DVec3], out: &mut [DVec3]) {
    if has_centred_rows(vertices.len()) {
        return;
    }
    let mean = vertices.iter().map(|&v| q[v as usize]).sum::<DVec3>() / vertices.len().max(1) as f64;
    for o in out.iter_mut() {
        *o += mean;
    }
}

/// Rows `p` (in the frame of C q) about their centroid, as the centred residuals take them:
/// themselves for centred rows, a recentred copy when C = I (its sets are closed under
/// translation).
pub(crate) fn centred_view(p: &[DVec3]) -> std::borrow::Cow<'_, [DVec3]> {
    if has_centred_rows(p.len()) {
        std::borrow::Cow::Borrowed(p)
    } else {
        let mut c = p.to_vec();
        recentre(&mut c);
        std::borrow::Cow::Owned(c)
    }
}

/// The rows of C q for C = I − 11ᵀ/k: the positions of `vertices` about their centroid.
pub(crate) fn centred(vertices: &[u32], q: &[DVec3]) -> Vec<DVec3> {
    let points: Vec<DVec3> = vertices.iter().map(|&v| q[v as usize]).collect();
    let mean = points.iter().copied().sum::<DVec3>() / points.len().max(1) as f64;
    points.into_iter().map(|x| x - mean).collect()
}

/// `p` shifted so that its rows sum to zero (a shift keeps a configuration on a line, plane,
/// circle or sphere, and brings it nearer to centred rows C q: ‖d − (p − p̄)‖² = ‖d − p‖² − k‖p̄‖²
/// when Σ d_i = 0).
pub(crate) fn recentre(p: &mut [DVec3]) {
    if p.is_empty() {
        return;
    }
    let mean = p.iter().copied().sum::<DVec3>() / p.len() as f64;
    for x in p.iter_mut() {
        *x -= mean;
    }
}

/// The selected vertices as one set of at least `min`: nothing selected is
/// [`ConstraintError::NothingSelected`], fewer than `min` an [`ConstraintError::Invalid`] naming
/// the count.
pub(crate) fn vertex_set(
    ctx: &BuildContext,
    kind: &'static str,
    min: usize,
    why: &str,
) -> Result<Vec<u32>, ConstraintError> {
    let vertices = ctx.selection.vertex_list(ctx.rest.num_vertices());
    match vertices.len() {
        0 => Err(ConstraintError::NothingSelected { kind, element: "vertices" }),
        n if n < min => Err(ConstraintError::Invalid {
            kind,
            problem: format!("needs at least {min} vertices, the selection has {n} ({why})",),
        }),
        _ => Ok(vertices),
    }
}

/// Emits the rows of `vertices` (one per vertex, in order): q_i − (1/k) Σ_j q_j (translation
/// invariant, as in ShapeOp), or q_i for sets larger than [`DENSE_SET_MAX`]
/// (see there: the same energy, a diagonal CᵀC).
pub(crate) fn push_centred_rows(vertices: &[u32], sink: &mut RowSink) {
    centred_rows(vertices, sink);
}

/// Writes q_i − (1/k) Σ_j q_j for each of `vertices` into `out` (the rows of
/// [`push_centred_rows`] applied to q).
pub(crate) fn centre_into(q: &[DVec3], vertices: &[u32], out: &mut [DVec3]) {
    let mean = vertices.iter().map(|&v| q[v as usize]).sum::<DVec3>() / vertices.len() as f64;
    for (o, &v) in out.iter_mut().zip(vertices) {
        *o = q[v as usize] - mean;
    }
}

/// A centred rest shape to match (rigid and similarity): its vertices, the centred rest
/// positions d⁰_i and what the residual needs.
#[derive(Debug, Clone)]
pub(crate) struct ShapeMatch {
    /// The selected vertices, in order (one row each).
    pub(crate) vertices: Box<[u32]>,
    /// d⁰_i = x⁰_i − c⁰.
    pub(crate) rest: Box<[DVec3]>,
    /// Σ_i ‖d⁰_i‖².
    pub(crate) rest_norm2: f64,
    /// Three rows spanning the rest shape as well as a greedy search finds (the longest d⁰_a,
    /// the d⁰_b farthest from its line, the d⁰_c farthest from their plane), for the
    /// orientation test.
    triple: [usize; 3],
    /// det[d⁰_a, d⁰_b, d⁰_c].
    triple_det: f64,
}

impl ShapeMatch {
    /// The centred rest shape of `vertices` (k ≥ 1) in `positions`.
    pub(crate) fn new(vertices: Vec<u32>, positions: &[DVec3]) -> Self {
        let mut rest = vec![DVec3::ZERO; vertices.len()];
        centre_into(positions, &vertices, &mut rest);
        let rest_norm2 = rest.iter().map(|d| d.length_squared()).sum();
        let argmax = |f: &dyn Fn(DVec3) -> f64| {
            rest.iter().enumerate().fold((0, f64::NEG_INFINITY), |best, (i, d)| {
                let x = f(*d);
                if x > best.1 { (i, x) } else { best }
            })
        };
        let a = argmax(&|d| d.length_squared()).0;
        let b = argmax(&|d| rest[a].cross(d).length_squared()).0;
        let normal = rest[a].cross(rest[b]);
        let c = argmax(&|d| normal.dot(d).abs()).0;
        let triple_det = normal.dot(rest[c]);
        ShapeMatch { vertices: vertices.into(), rest: rest.into(), rest_norm2, triple: [a, b, c], triple_det }
    }

    /// S = Σ_i e_i d⁰_iᵀ of centred rows `e` (accumulated by columns).
    pub(crate) fn covariance(&self, e: &[DVec3]) -> DMat3 {
        let (mut s0, mut s1, mut s2) = (DVec3::ZERO, DVec3::ZERO, DVec3::ZERO);
        for (e, d0) in e.iter().zip(self.rest.iter()) {
            s0 += *e * d0.x;
            s1 += *e * d0.y;
            s2 += *e * d0.z;
        }
        DMat3::from_cols(s0, s1, s2)
    }

    /// How far `p` is from {s R d⁰_i : R ∈ SO(3)} for the scale `s ≥ 0`, in length units:
    /// (max_ij |p_i·p_j − s² d⁰_i·d⁰_j|) / L + |det[p_a, p_b, p_c] − s³ det[d⁰_a, d⁰_b, d⁰_c]| / L²
    /// with L = max(max_i ‖p_i‖, s max_i ‖d⁰_i‖) (0 when L = 0: both are the origin; ∞ for a
    /// non-finite p). The first
    /// term is zero exactly for an orthogonal transform of s d⁰ (same lengths and angles); the
    /// second then tells a rotation from a reflection (they differ only for a non-planar shape,
    /// whose spanning triple then has det ≠ 0).
    pub(crate) fn residual(&self, p: &[DVec3], s: f64) -> f64 {
        if !p.iter().all(|x| x.is_finite()) {
            return f64::INFINITY;
        }
        let longest = |rows: &[DVec3]| rows.iter().map(|x| x.length()).fold(0.0, f64::max);
        let scale = longest(p).max(s * longest(&self.rest));
        if scale == 0.0 {
            return 0.0;
        }
        let s2 = s * s;
        let mut gram: f64 = 0.0;
        for i in 0..p.len() {
            for j in i..p.len() {
                gram = gram.max((p[i].dot(p[j]) - s2 * self.rest[i].dot(self.rest[j])).abs());
            }
        }
        let [a, b, c] = self.triple;
        let det = p[a].cross(p[b]).dot(p[c]);
        gram / scale + (det - s2 * s * self.triple_det).abs() / (scale * scale)
    }

    /// The nearest rotated copy of the rest shape to C q (shape matching, Müller et al. 2005):
    /// `out` = R d⁰_i with R = [`nearest_rotation3`](crate::linalg::nearest_rotation3)(S) of
    /// the centred rows, in the frame of C q's rows ([`to_row_frame`]). `rigid` and
    /// `attachment` project with it.
    pub(crate) fn project_rigid(&self, q: &[DVec3], out: &mut [DVec3]) {
        // The centred rows first, then overwritten by the rotated rest shape.
        centre_into(q, &self.vertices, out);
        let r = crate::linalg::nearest_rotation3(self.covariance(out));
        for (o, d0) in out.iter_mut().zip(self.rest.iter()) {
            *o = r * *d0;
        }
        to_row_frame(&self.vertices, q, out);
    }

    /// The vertex list of a vertex-set type's selection, refused with a clear line below 2.
    pub(crate) fn selected(ctx: &BuildContext, kind: &'static str) -> Result<Vec<u32>, ConstraintError> {
        let vertices = ctx.selection.vertex_list(ctx.rest.num_vertices());
        match vertices.len() {
            0 => Err(ConstraintError::NothingSelected { kind, element: "vertices" }),
            1 => {
                Err(ConstraintError::Invalid { kind, problem: "needs at least 2 vertices, the selection has 1".into() })
            }
            _ => Ok(vertices),
        }
    }
}
