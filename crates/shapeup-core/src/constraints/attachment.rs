//! Edge attachment: a vertex that only degenerate (zero-area) triangles use follows its edge.
//!
//! Term: ω ‖q_v − ((1 − t) q_a + t q_b)‖² (one row of C q), p = 0, ω = 1, where (a, b) are the
//! two corners of a degenerate rest triangle ([`is_degenerate_triangle`]) farthest apart, v is
//! its third corner and t = clamp((x⁰_v − x⁰_a)·(x⁰_b − x⁰_a) / ‖x⁰_b − x⁰_a‖², 0, 1) its rest
//! parameter on segment ab (0 if a and b coincide).
//!
//! Such triangles add no cotan term and no strain constraint, so without this a vertex in no
//! other element stays at rest while its edge moves (math reference, "Edge cases"). The
//! attachments are not a scene type: [`degenerate_attachments`] finds them after the scene's
//! (or the editor's) own groups are built, and the caller adds them as one more group.

use super::contract::{Constraint, RowSink};
use super::group::ConstraintGroup;
use crate::geometry::{RestGeometry, is_degenerate_triangle};
use glam::DVec3;

/// Name of the group that holds the attachments.
pub const DEGENERATE_FACES_GROUP: &str = "degenerate faces";
/// Name in reports (`ConstraintGroup::kind`); not a type a scene can ask for.
const KIND: &str = "edge_attachment";

/// Vertex v attached to the point (1 − t) q_a + t q_b of edge (a, b):
/// ω ‖q_v − (1 − t) q_a − t q_b‖² with p = 0 and ω = 1.
#[derive(Debug, Clone, PartialEq)]
pub struct EdgeAttachment {
    /// v, a, b.
    vertices: [u32; 3],
    t: f64,
}

impl EdgeAttachment {
    /// Attaches `v` to edge (`a`, `b`) at parameter `t`; `None` unless t ∈ [0, 1] and v is
    /// neither a nor b (the row would vanish or pull v onto itself).
    pub fn new(v: u32, a: u32, b: u32, t: f64) -> Option<Self> {
        ((0.0..=1.0).contains(&t) && v != a && v != b).then_some(EdgeAttachment { vertices: [v, a, b], t })
    }

    /// The attachment of corner `k` (0, 1 or 2) of `triangle`, if that corner lies between the
    /// other two at rest: they are the triangle's farthest pair (a tie counts), ‖x⁰_b − x⁰_a‖ ≥
    /// ‖x⁰_v − x⁰_a‖, ‖x⁰_v − x⁰_b‖. t is v's projection on ab, clamped to [0, 1] (0 if a = b).
    pub fn between(triangle: [u32; 3], k: usize, rest: &[DVec3]) -> Option<Self> {
        let (v, a, b) = (triangle[k % 3], triangle[(k + 1) % 3], triangle[(k + 2) % 3]);
        let [xv, xa, xb] = [v, a, b].map(|i| rest[i as usize]);
        let ab = xb - xa;
        let base = ab.length_squared();
        if base < (xv - xa).length_squared() || base < (xv - xb).length_squared() {
            return None;
        }
        let t = if base > 0.0 { ((xv - xa).dot(ab) / base).clamp(0.0, 1.0) } else { 0.0 };
        EdgeAttachment::new(v, a, b, if t.is_finite() { t } else { 0.0 })
    }

    /// The attached vertex v.
    pub fn vertex(&self) -> u32 {
        self.vertices[0]
    }

    /// The edge (a, b) it follows.
    pub fn edge(&self) -> [u32; 2] {
        [self.vertices[1], self.vertices[2]]
    }

    /// Its parameter t on the edge.
    pub fn parameter(&self) -> f64 {
        self.t
    }
}

impl Constraint for EdgeAttachment {
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
        1
    }
    fn rows(&self, sink: &mut RowSink) {
        let [v, a, b] = self.vertices;
        sink.push(0, v, 1.0);
        sink.push(0, a, -(1.0 - self.t));
        sink.push(0, b, -self.t);
    }
    fn project(&self, _q: &[DVec3], out: &mut [DVec3]) {
        out[0] = DVec3::ZERO;
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        p[0].length()
    }
}

/// What [`degenerate_attachments`] found.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DegenerateAttachments {
    /// One attachment per (degenerate triangle, corner between the other two) whose edge is
    /// solved, in triangle order.
    pub attachments: Vec<EdgeAttachment>,
    /// Vertices that only degenerate triangles use, that no attachment reaches and that no
    /// constraint touches: they keep their rest positions (sorted).
    pub stranded: Vec<u32>,
}

impl DegenerateAttachments {
    /// The attached vertices, sorted, each once.
    pub fn attached_vertices(&self) -> Vec<u32> {
        let mut v: Vec<u32> = self.attachments.iter().map(EdgeAttachment::vertex).collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// The attachments as the group [`DEGENERATE_FACES_GROUP`] with multiplier 1; `None` if
    /// there are none.
    pub fn into_group(self) -> Option<ConstraintGroup> {
        (!self.attachments.is_empty()).then(|| {
            let constraints = self.attachments.into_iter().map(|c| Box::new(c) as Box<dyn Constraint>).collect();
            ConstraintGroup::new(DEGENERATE_FACES_GROUP, 1.0, constraints)
        })
    }
}

/// The attachments of the vertices of `rest` that only degenerate triangles use
/// ([`degenerate_attachments`] of every constraint of `groups`, a system's groups so far), as
/// the group [`DEGENERATE_FACES_GROUP`] for the caller to add after them (`None` if there are
/// none), with the attached vertices and the stranded ones (each sorted) for it to report. What
/// scenes and the editor both do after building their groups.
pub fn attach_degenerate_vertices<'a>(
    rest: &RestGeometry,
    groups: impl IntoIterator<Item = &'a ConstraintGroup>,
) -> (Option<ConstraintGroup>, Vec<u32>, Vec<u32>) {
    let found = degenerate_attachments(rest, groups.into_iter().flat_map(|g| g.constraints.iter().map(|c| c.as_ref())));
    let attached = found.attached_vertices();
    let stranded = found.stranded.clone();
    (found.into_group(), attached, stranded)
}

/// The attachments of the vertices that only degenerate triangles use, given the constraints
/// already built (`constraints`: every constraint of the system so far).
///
/// A vertex is *degenerate-only* if it is a corner of a degenerate rest triangle
/// ([`is_degenerate_triangle`]) and of no other triangle and no tetrahedron. Each such corner
/// that lies between the other two ([`EdgeAttachment::between`]) gets an attachment once both
/// ends of its edge are solved: touched by a constraint (a nonzero coefficient in a row of C, as
/// the assembler counts them) or attached themselves, repeated to a fixed point so that chains
/// of degenerate triangles follow. Because an attachment only ever adds a vertex whose edge is
/// already in the system, it never makes the system singular. A vertex that a position group
/// (a handle) holds is left to it.
pub fn degenerate_attachments<'a>(
    rest: &RestGeometry,
    constraints: impl IntoIterator<Item = &'a dyn Constraint>,
) -> DegenerateAttachments {
    let n = rest.num_vertices();
    let degenerate: Vec<bool> = rest
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| rest.positions[v as usize]);
            is_degenerate_triangle(a, b, c)
        })
        .collect();
    // 0: in no triangle or tetrahedron; 1: only in degenerate triangles; 2: in a real element.
    let mut class = vec![0u8; n];
    for (t, &deg) in rest.triangles.iter().zip(&degenerate) {
        for &v in t {
            class[v as usize] = class[v as usize].max(if deg { 1 } else { 2 });
        }
    }
    rest.tetrahedra.iter().flatten().for_each(|&v| class[v as usize] = 2);
    if !class.contains(&1) {
        return DegenerateAttachments::default();
    }

    let (mut solved, held) = touched_vertices(n, constraints);
    let candidates: Vec<EdgeAttachment> = rest
        .triangles
        .iter()
        .zip(&degenerate)
        .filter(|(_, deg)| **deg)
        .flat_map(|(&t, _)| (0..3).filter_map(move |k| EdgeAttachment::between(t, k, &rest.positions)))
        .filter(|c| class[c.vertex() as usize] == 1 && !held[c.vertex() as usize])
        .collect();
    // Fixed point as a worklist: each candidate waits for its unsolved edge ends; solving a
    // vertex releases the candidates waiting on it (linear in the number of candidates).
    let mut missing: Vec<u8> = vec![0; candidates.len()];
    let mut waiting: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut ready: Vec<usize> = Vec::new();
    for (i, c) in candidates.iter().enumerate() {
        let mut ends = c.edge();
        ends.sort_unstable();
        for (j, &e) in ends.iter().enumerate() {
            if !solved[e as usize] && (j == 0 || ends[0] != e) {
                missing[i] += 1;
                waiting[e as usize].push(i as u32);
            }
        }
        if missing[i] == 0 {
            ready.push(i);
        }
    }
    let mut attached: Vec<usize> = Vec::new();
    while let Some(i) = ready.pop() {
        attached.push(i);
        let v = candidates[i].vertex() as usize;
        if !std::mem::replace(&mut solved[v], true) {
            for j in std::mem::take(&mut waiting[v]) {
                missing[j as usize] -= 1;
                if missing[j as usize] == 0 {
                    ready.push(j as usize);
                }
            }
        }
    }
    // Triangle order, whichever round released them.
    attached.sort_unstable();
    let attachments = attached.into_iter().map(|i| candidates[i].clone()).collect();
    let stranded = (0..n as u32).filter(|&v| class[v as usize] == 1 && !solved[v as usize]).collect();
    DegenerateAttachments { attachments, stranded }
}

/// Per vertex: whether some row of `constraints` has a nonzero coefficient on it (repeated
/// entries of a row summed first and exact zeros dropped, as the assembler does: exactly its
/// solved vertices), and whether a position constraint holds it.
fn touched_vertices<'a>(n: usize, constraints: impl IntoIterator<Item = &'a dyn Constraint>) -> (Vec<bool>, Vec<bool>) {
    let (mut touched, mut held) = (vec![false; n], vec![false; n]);
    let mut sink = RowSink::default();
    for c in constraints {
        sink.entries.clear();
        c.rows(&mut sink);
        sink.entries.sort_unstable_by_key(|e| (e.row, e.vertex));
        for run in sink.entries.chunk_by(|x, y| (x.row, x.vertex) == (y.row, y.vertex)) {
            // Summed in the assembler's order, so that both agree on an exact zero.
            let sum = run[1..].iter().fold(run[0].coeff, |s, e| s + e.coeff);
            if let Some(t) = touched.get_mut(run[0].vertex as usize) {
                *t |= sum != 0.0;
            }
        }
        if c.held_points().is_some() {
            for &v in c.vertices() {
                if let Some(h) = held.get_mut(v as usize) {
                    *h = true;
                }
            }
        }
    }
    (touched, held)
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;
    use crate::constraints::{EdgeSpring, Position};

    /// A unit square (0, 1, 2, 3) and v = 4 on its bottom edge at x = 0.25, used only by the
    /// degenerate triangle (0, 4, 1).
    fn square_with_sliver() -> RestGeometry {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.25, 0.0, 0.0),
        ];
        RestGeometry::new(p, vec![[0, 1, 2], [0, 2, 3], [0, 4, 1]], vec![])
    }

    fn springs(rest: &RestGeometry, edges: &[[u32; 2]]) -> Vec<Box<dyn Constraint>> {
        edges
            .iter()
            .map(|e| Box::new(EdgeSpring::new(e[0], e[1], &rest.positions).unwrap()) as Box<dyn Constraint>)
            .collect()
    }

    #[test]
    fn row_is_v_minus_the_edge_point_and_projection_zero() {
        let c = EdgeAttachment::new(2, 0, 1, 0.25).unwrap();
        let q = [DVec3::ZERO, DVec3::new(4.0, 0.0, 0.0), DVec3::new(1.0, 2.0, 0.0)];
        assert_eq!(c.apply(&q), vec![DVec3::new(0.0, 2.0, 0.0)]);
        assert!((c.energy(&q) - 4.0).abs() < 1e-15);
        assert!(EdgeAttachment::new(0, 0, 1, 0.5).is_none(), "v on its own edge");
        assert!(EdgeAttachment::new(2, 0, 1, 1.5).is_none(), "t outside [0, 1]");
    }

    #[test]
    fn only_the_corner_between_the_others_is_attached() {
        let rest = square_with_sliver();
        let tri = [0, 4, 1];
        assert!(EdgeAttachment::between(tri, 0, &rest.positions).is_none());
        assert!(EdgeAttachment::between(tri, 2, &rest.positions).is_none());
        let c = EdgeAttachment::between(tri, 1, &rest.positions).unwrap();
        assert_eq!((c.vertex(), c.edge()), (4, [1, 0]));
        assert!((c.parameter() - 0.75).abs() < 1e-15, "from a = 1 towards b = 0");
        // All three corners coincide: t = 0.
        let point = [DVec3::ONE; 3];
        assert_eq!(EdgeAttachment::between([0, 1, 2], 0, &point).unwrap().parameter(), 0.0);
    }

    #[test]
    fn attaches_only_once_the_edge_is_solved() {
        let rest = square_with_sliver();
        let none = degenerate_attachments(&rest, std::iter::empty());
        assert!(none.attachments.is_empty());
        assert_eq!(none.stranded, vec![4]);
        // Only vertex 0 of the edge is touched: still nothing.
        let one = springs(&rest, &[[0, 3]]);
        assert!(degenerate_attachments(&rest, one.iter().map(|c| c.as_ref())).attachments.is_empty());
        let both = springs(&rest, &[[0, 1]]);
        let found = degenerate_attachments(&rest, both.iter().map(|c| c.as_ref()));
        assert_eq!(found.attached_vertices(), vec![4]);
        assert!(found.stranded.is_empty());
        let group = found.into_group().unwrap();
        assert_eq!((group.name.as_str(), group.kind.as_str(), group.multiplier), (DEGENERATE_FACES_GROUP, KIND, 1.0));
    }

    #[test]
    fn zero_coefficients_do_not_count_as_solved() {
        let rest = square_with_sliver();
        // A row 0·q_1 + q_0 − q_0 touches neither vertex.
        #[derive(Debug)]
        struct Zero;
        impl Constraint for Zero {
            fn kind(&self) -> &'static str {
                "zero"
            }
            fn vertices(&self) -> &[u32] {
                &[0, 1]
            }
            fn element_weight(&self) -> f64 {
                1.0
            }
            fn num_rows(&self) -> usize {
                1
            }
            fn rows(&self, sink: &mut RowSink) {
                sink.push(0, 0, 1.0);
                sink.push(0, 1, 0.0);
                sink.push(0, 0, -1.0);
            }
            fn set_residual(&self, p: &[DVec3]) -> f64 {
                p[0].length()
            }
            fn project(&self, _q: &[DVec3], out: &mut [DVec3]) {
                out[0] = DVec3::ZERO;
            }
        }
        let zero: Vec<Box<dyn Constraint>> = vec![Box::new(Zero)];
        assert!(degenerate_attachments(&rest, zero.iter().map(|c| c.as_ref())).attachments.is_empty());
    }

    #[test]
    fn a_vertex_a_handle_holds_is_left_to_it() {
        let rest = square_with_sliver();
        let mut built = springs(&rest, &[[0, 1]]);
        built.push(Box::new(Position::new(vec![4], vec![DVec3::ZERO]).unwrap()));
        let found = degenerate_attachments(&rest, built.iter().map(|c| c.as_ref()));
        assert!(found.attachments.is_empty());
        assert!(found.stranded.is_empty(), "the handle solves it");
    }

    #[test]
    fn a_vertex_of_a_real_triangle_is_never_attached() {
        // Vertex 4 is also in a good triangle: no attachment even though its sliver exists.
        let mut p = square_with_sliver().positions;
        p.push(DVec3::new(0.25, -1.0, 0.0));
        let rest = RestGeometry::new(p, vec![[0, 1, 2], [0, 2, 3], [0, 4, 1], [0, 5, 4]], vec![]);
        let built = springs(&rest, &[[0, 1]]);
        assert!(degenerate_attachments(&rest, built.iter().map(|c| c.as_ref())).attachments.is_empty());
    }

    #[test]
    fn chains_reach_a_fixed_point_in_triangle_order() {
        // 5 between 4 and 1, and 4 between 0 and 1 (listed first: it needs the second pass).
        let mut p = square_with_sliver().positions;
        p.push(DVec3::new(0.5, 0.0, 0.0));
        let rest = RestGeometry::new(p, vec![[0, 1, 2], [0, 2, 3], [4, 5, 1], [0, 4, 1]], vec![]);
        let built = springs(&rest, &[[0, 1]]);
        let found = degenerate_attachments(&rest, built.iter().map(|c| c.as_ref()));
        let got: Vec<(u32, [u32; 2])> = found.attachments.iter().map(|c| (c.vertex(), c.edge())).collect();
        assert_eq!(got, vec![(5, [1, 4]), (4, [1, 0])]);
        assert!((found.attachments[0].parameter() - 2.0 / 3.0).abs() < 1e-15);
    }
}
