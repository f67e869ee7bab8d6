//! Self-collision detection: vertex–triangle and edge–edge pairs of a surface that may come
//! within the thickness during a step.
//!
//! Broad phase: parry3d's BVHs over the boxes of each vertex, edge and triangle swept from the
//! step's start x_n to its prediction s (less the surface's mean motion) and grown by half the
//! thickness (two boxes meet when their gap is under the thickness), refitted each step. One
//! simultaneous traversal of the vertex tree and the triangle tree gives the vertex–triangle
//! candidates, one of the edge tree against itself the edge–edge ones: each pair once, without
//! a query per element, each handed to the narrow phase as it is met. Narrow
//! phase at x_n: the closest points (Ericson, "Real-Time Collision Detection", 2005, §5.1.5
//! point–triangle and §5.1.9 segment–segment); a pair closer than the thickness plus twice its
//! relative predicted motion is a contact, with the normal from the second closest point to
//! the first (the side it started on).

use super::boxes::swept_box;
use super::closest::{closest_between_segments, closest_on_triangle};
use super::crossing::ElementPair;
use super::gap::Pair;
use glam::DVec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy, BvhWorkspace};
use rayon::prelude::*;

/// The surface that collides with itself: its triangles, their edges and their vertices, and
/// a BVH over the swept boxes of each kind.
#[derive(Debug, Clone)]
pub(crate) struct Surface {
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    vertices: Vec<u32>,
    triangle_tree: Tree,
    edge_tree: Tree,
    vertex_tree: Tree,
    /// The mean motion of the last refit.
    drift: DVec3,
    /// The edge–edge half of [`Surface::self_contacts_into`], found beside the other (scratch).
    edge_scratch: (Vec<Pair>, Vec<ElementPair>),
}

/// A BVH over boxes that move a little each step: built once, then refitted, and a part of
/// it rebuilt each step (parry's incremental optimization, which goes round the whole tree
/// over successive steps) as the surface moves away from the tree's layout: a full rebuild
/// every 20 steps cost as much as those 20 steps' refits, all in one step.
#[derive(Debug, Clone, Default)]
struct Tree {
    bvh: Option<Bvh>,
    workspace: Workspace,
}

/// parry's scratch for refits and incremental optimization (kept between steps).
#[derive(Clone, Default)]
struct Workspace(BvhWorkspace);

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("BvhWorkspace")
    }
}

impl Tree {
    /// The BVH of `boxes`: refitted and partly rebuilt, or built at the first call.
    fn update(&mut self, boxes: &[Aabb]) -> &Bvh {
        match &mut self.bvh {
            Some(bvh) => {
                for (i, b) in boxes.iter().enumerate() {
                    bvh.update_partially_if_present(*b, i as u32, 0.0);
                }
                bvh.refit(&mut self.workspace.0);
                bvh.optimize_incremental(&mut self.workspace.0);
            }
            None => self.bvh = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, boxes)),
        }
        self.bvh.get_or_insert_with(Bvh::new)
    }
}

impl Surface {
    /// The triangles whose three vertices are all `active`.
    pub(crate) fn new(triangles: &[[u32; 3]], active: &[bool]) -> Self {
        let triangles: Vec<[u32; 3]> =
            triangles.iter().copied().filter(|t| t.iter().all(|&v| active.get(v as usize) == Some(&true))).collect();
        let (edges, _, _) = crate::topology::indexed_edges(&triangles);
        let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        Surface {
            triangles,
            edges,
            vertices,
            triangle_tree: Tree::default(),
            edge_tree: Tree::default(),
            vertex_tree: Tree::default(),
            drift: DVec3::ZERO,
            edge_scratch: (Vec::new(), Vec::new()),
        }
    }
}

/// The mean predicted motion of `vertices`: the translation they share (gravity's h² g in a
/// falling or resting cloth), taken out of every swept box.
fn common_motion(vertices: &[u32], start: &[DVec3], predicted: &[DVec3]) -> DVec3 {
    if vertices.is_empty() {
        return DVec3::ZERO;
    }
    let sum = super::ordered_sum(vertices, |v| predicted[v as usize] - start[v as usize]);
    sum / vertices.len() as f64
}

/// The largest predicted motion of any of `others` relative to `first`'s vertices.
pub(crate) fn relative_motion(first: &[u32], others: &[u32], start: &[DVec3], predicted: &[DVec3]) -> f64 {
    let motion = |v: u32| predicted[v as usize] - start[v as usize];
    let mut most = 0.0f64;
    for &a in first {
        let m = motion(a);
        for &b in others {
            most = most.max((m - motion(b)).length_squared());
        }
    }
    most.sqrt()
}

/// Every vertex–triangle and edge–edge contact of the step (see the [module docs](self)):
/// [`Surface::refit`] of every tree, then [`Surface::self_contacts`].
pub(crate) fn detect_self_contacts(
    surface: &mut Surface,
    start: &[DVec3],
    predicted: &[DVec3],
    thickness: f64,
) -> Vec<Pair> {
    surface.refit(start, predicted, thickness, Trees { triangles: true, edges: true, vertices: true });
    let (mut pairs, mut elements) = (Vec::new(), Vec::new());
    surface.self_contacts_into(start, predicted, thickness, &mut pairs, &mut elements);
    pairs
}

/// How many pairs of an edge and a triangle of the surface at `positions` that share no vertex
/// meet: the edge passes through the triangle or touches it (closer than [`TOUCHING`]). Such a
/// surface is caught in itself from the start: self-collision keeps every pair on the side it
/// starts on, and pairs that touch exactly have no side (no contact normal).
/// Returns the count and the first pair found.
pub(crate) fn edges_through_triangles(surface: &mut Surface, positions: &[DVec3]) -> (usize, Option<EdgeTriangle>) {
    surface.refit(positions, positions, 2.0 * TOUCHING, Trees { triangles: true, edges: true, vertices: false });
    let (Some(triangle_bvh), Some(edge_bvh)) = (surface.triangle_bvh(), surface.edge_bvh()) else {
        return (0, None);
    };
    let at = |v: u32| positions[v as usize];
    let (mut count, mut first) = (0, None);
    for (i, k) in edge_bvh.leaf_pairs(triangle_bvh, |a, b| a.intersects(b)) {
        let (e, t) = (surface.edges[i as usize], surface.triangles[k as usize]);
        if !t.contains(&e[0]) && !t.contains(&e[1]) && segment_meets_triangle(at(e[0]), at(e[1]), t.map(at)) {
            count += 1;
            first.get_or_insert((e, t));
        }
    }
    (count, first)
}

/// An edge's and a triangle's vertices.
pub type EdgeTriangle = ([u32; 2], [u32; 3]);

/// Whether segment p0 p1 passes through triangle `t` or comes within [`TOUCHING`] of it: its
/// crossing of the triangle's plane lies in the triangle, or an end lies on the triangle, or
/// it meets one of the triangle's edges (which covers a segment in the triangle's plane).
fn segment_meets_triangle(p0: DVec3, p1: DVec3, t: [DVec3; 3]) -> bool {
    let normal = (t[1] - t[0]).cross(t[2] - t[0]);
    let (d0, d1) = (normal.dot(p0 - t[0]), normal.dot(p1 - t[0]));
    if d0 * d1 < 0.0 {
        let crossing = p0 + (d0 / (d0 - d1)) * (p1 - p0);
        if (crossing - closest_on_triangle(crossing, t).0).length() < TOUCHING {
            return true;
        }
    }
    let near = |p: DVec3| (p - closest_on_triangle(p, t).0).length() < TOUCHING;
    let meets = |a: DVec3, b: DVec3| {
        let (_, _, x, y) = closest_between_segments(p0, p1, a, b);
        (x - y).length() < TOUCHING
    };
    near(p0) || near(p1) || meets(t[0], t[1]) || meets(t[1], t[2]) || meets(t[2], t[0])
}

/// Which of a surface's BVHs a step needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Trees {
    pub(crate) triangles: bool,
    pub(crate) edges: bool,
    pub(crate) vertices: bool,
}

impl Surface {
    /// The triangles.
    pub(crate) fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// The edges (each once).
    pub(crate) fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }

    /// The vertices (each once).
    pub(crate) fn vertices(&self) -> &[u32] {
        &self.vertices
    }

    /// The BVH of the triangles' swept boxes of the last [`Surface::refit`] that asked for it.
    pub(crate) fn triangle_bvh(&self) -> Option<&Bvh> {
        self.triangle_tree.bvh.as_ref()
    }

    /// The BVH of the edges' swept boxes of the last [`Surface::refit`] that asked for it.
    pub(crate) fn edge_bvh(&self) -> Option<&Bvh> {
        self.edge_tree.bvh.as_ref()
    }

    /// The mean motion taken out of the boxes of the last [`Surface::refit`] (see
    /// [`common_motion`]).
    pub(crate) fn drift(&self) -> DVec3 {
        self.drift
    }

    /// Refits (or rebuilds) the BVHs in `which` over the boxes swept from `start` to
    /// `predicted`, less the surface's mean motion, each grown by half the thickness: two
    /// boxes meet when their elements come within the thickness of each other.
    pub(crate) fn refit(&mut self, start: &[DVec3], predicted: &[DVec3], thickness: f64, which: Trees) {
        if self.triangles.is_empty() {
            return;
        }
        let grow = 0.5 * thickness;
        let Surface { triangles, edges, vertices, triangle_tree, edge_tree, vertex_tree, drift, .. } = self;
        let (triangles, edges, vertices) = (&*triangles, &*edges, &*vertices);
        *drift = common_motion(vertices, start, predicted);
        let drift = *drift;
        let boxes = |items: &[u32], size: usize| -> Vec<Aabb> {
            items.par_chunks(size).map(|item| swept_box(item, start, predicted, drift, grow)).collect()
        };
        rayon::join(
            || {
                rayon::join(
                    || which.triangles.then(|| triangle_tree.update(&boxes(triangles.as_flattened(), 3))),
                    || which.edges.then(|| edge_tree.update(&boxes(edges.as_flattened(), 2))),
                )
            },
            || which.vertices.then(|| vertex_tree.update(&boxes(vertices, 1))),
        );
    }

    /// The triangle, edge and vertex BVHs, once all three are built.
    fn bvhs(&self) -> Option<(&Bvh, &Bvh, &Bvh)> {
        Some((self.triangle_tree.bvh.as_ref()?, self.edge_tree.bvh.as_ref()?, self.vertex_tree.bvh.as_ref()?))
    }

    /// The self contacts of the step, from the trees of the last [`Surface::refit`] (which
    /// must have refitted all three).
    #[cfg(test)]
    pub(crate) fn self_contacts(
        &mut self,
        start: &[DVec3],
        predicted: &[DVec3],
        thickness: f64,
    ) -> (Vec<Pair>, Vec<ElementPair>) {
        let (mut pairs, mut elements) = (Vec::new(), Vec::new());
        self.self_contacts_into(start, predicted, thickness, &mut pairs, &mut elements);
        (pairs, elements)
    }

    /// [`Surface::self_contacts`] written into `pairs` and `elements` (cleared first): a step
    /// meets some hundred thousand pairs of elements, and lists grown afresh each step cost
    /// more in page faults and copies than their narrow phase.
    pub(crate) fn self_contacts_into(
        &mut self,
        start: &[DVec3],
        predicted: &[DVec3],
        thickness: f64,
        pairs: &mut Vec<Pair>,
        elements: &mut Vec<ElementPair>,
    ) {
        pairs.clear();
        elements.clear();
        let Surface { triangles, edges, vertices, triangle_tree, edge_tree, vertex_tree, edge_scratch, .. } = self;
        let (Some(triangle_bvh), Some(edge_bvh), Some(vertex_bvh)) =
            (triangle_tree.bvh.as_ref(), edge_tree.bvh.as_ref(), vertex_tree.bvh.as_ref())
        else {
            return;
        };
        let (edge_pairs, edge_elements) = edge_scratch;
        edge_pairs.clear();
        edge_elements.clear();
        // Candidates, each passed to the narrow phase as it is met (no list of candidates):
        // vertex–triangle pairs from one traversal of the vertex tree against the triangle
        // tree, edge–edge pairs from one of the edge tree against itself, less those that
        // share a vertex. The two traversals run side by side.
        rayon::join(
            || {
                for (i, k) in vertex_bvh.leaf_pairs(triangle_bvh, |a, b| a.intersects(b)) {
                    let found = vertex_triangle_contact(
                        vertices[i as usize],
                        triangles[k as usize],
                        start,
                        predicted,
                        thickness,
                    );
                    if let Some((pair, element)) = found {
                        pairs.extend(pair);
                        elements.push(element);
                    }
                }
            },
            || {
                let contact = |i: u32, j: u32| {
                    edge_edge_contact(edges[i as usize], edges[j as usize], start, predicted, thickness)
                };
                if rayon::current_num_threads() > 1 {
                    // parry's parallel traversal lists the pairs (in the sequential one's order).
                    let found: Vec<(Option<Pair>, ElementPair)> = edge_bvh
                        .traverse_bvtt_single_tree_parallel::<false>()
                        .par_iter()
                        .filter_map(|&(i, j)| contact(i, j))
                        .collect();
                    for (pair, element) in found {
                        edge_pairs.extend(pair);
                        edge_elements.push(element);
                    }
                } else {
                    edge_bvh.traverse_bvtt_single_tree::<false>(&mut BvhWorkspace::default(), &mut |i, j| {
                        if let Some((pair, element)) = contact(i, j) {
                            edge_pairs.extend(pair);
                            edge_elements.push(element);
                        }
                    });
                }
            },
        );
        pairs.extend_from_slice(edge_pairs);
        elements.extend_from_slice(edge_elements);
        distinct_features(pairs);
    }

    /// Whether the element of `vertices` may have left its box in the step's trees (the box
    /// of its vertices at x_n and at the prediction less the trees' drift, grown by `grow`,
    /// half the thickness) on its way to `end`, given per vertex in the trees' frame: one of
    /// its vertices ended outside the box. Any point of the element moves by a convex
    /// combination of its vertices' motions, so an element whose vertices all end in its box
    /// stays in it (a vertex that leaves its own small box mostly ends in its triangle's).
    pub(crate) fn strays(
        &self,
        vertices: &[u32],
        (start, predicted): (&[DVec3], &[DVec3]),
        end: impl Fn(u32) -> DVec3,
        grow: f64,
    ) -> bool {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for &v in vertices {
            let (a, b) = (start[v as usize], predicted[v as usize] - self.drift);
            lo = lo.min(a.min(b));
            hi = hi.max(a.max(b));
        }
        let (lo, hi) = (lo - DVec3::splat(grow), hi + DVec3::splat(grow));
        vertices.iter().any(|&v| {
            let p = end(v);
            p.cmplt(lo).any() || p.cmpgt(hi).any()
        })
    }

    /// Every pair of elements (vertex–triangle and edge–edge, not neighbours) of which one
    /// `strays` and whose boxes meet, each with distance 0: the strayed elements' boxes swept
    /// from `start` to `end` and grown by `grow`, in BVHs of their own, against each other and
    /// against the step's trees (whose boxes must hold the other elements' paths from `start`
    /// to `end`). `strays` is given an element's vertices. For the end-of-step check
    /// ([`super::crossing`]).
    pub(crate) fn pairs_of_strayed(
        &self,
        strays: impl Fn(&[u32]) -> bool + Sync,
        start: &[DVec3],
        end: &[DVec3],
        grow: f64,
    ) -> Vec<ElementPair> {
        let Some((triangle_bvh, edge_bvh, vertex_bvh)) = self.bvhs() else {
            return Vec::new();
        };
        let (triangles, edges, vertices) = (&self.triangles, &self.edges, &self.vertices);
        // The strayed elements (indices into `items`, `size` vertices each) and their BVH.
        let pick = |items: &[u32], size: usize| -> (Vec<u32>, Bvh) {
            let chosen: Vec<u32> =
                items.par_chunks(size).enumerate().filter(|(_, e)| strays(e)).map(|(i, _)| i as u32).collect();
            let boxes: Vec<Aabb> = chosen
                .iter()
                .map(|&i| swept_box(&items[size * i as usize..][..size], start, end, DVec3::ZERO, grow))
                .collect();
            (chosen, Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes))
        };
        let (my_triangles, my_triangle_bvh) = pick(triangles.as_flattened(), 3);
        let (my_edges, my_edge_bvh) = pick(edges.as_flattened(), 2);
        let (my_vertices, my_vertex_bvh) = pick(vertices, 1);
        // A pair from the step's trees is kept only when the other element's own box meets too.
        let path = |items: &[u32]| swept_box(items, start, end, DVec3::ZERO, grow);
        let meet = |a: &[u32], b: &[u32]| path(a).intersects(&path(b));
        let mut out = Vec::new();
        let mut vertex_triangle =
            |v: u32, t: [u32; 3]| out.extend(ElementPair::vertex_triangle(v, t, 0.0).filter(|_| meet(&[v], &t)));
        let overlap = |a: &parry3d_f64::partitioning::BvhNode, b: &parry3d_f64::partitioning::BvhNode| a.intersects(b);
        for (i, k) in my_vertex_bvh.leaf_pairs(triangle_bvh, overlap) {
            vertex_triangle(vertices[my_vertices[i as usize] as usize], triangles[k as usize]);
        }
        for (i, k) in vertex_bvh.leaf_pairs(&my_triangle_bvh, overlap) {
            vertex_triangle(vertices[i as usize], triangles[my_triangles[k as usize] as usize]);
        }
        for (i, k) in my_vertex_bvh.leaf_pairs(&my_triangle_bvh, overlap) {
            vertex_triangle(vertices[my_vertices[i as usize] as usize], triangles[my_triangles[k as usize] as usize]);
        }
        let mut edge_edge =
            |e: [u32; 2], f: [u32; 2]| out.extend(ElementPair::edge_edge(e, f, 0.0).filter(|_| meet(&e, &f)));
        for (i, j) in my_edge_bvh.leaf_pairs(edge_bvh, overlap) {
            edge_edge(edges[my_edges[i as usize] as usize], edges[j as usize]);
        }
        my_edge_bvh.traverse_bvtt_single_tree::<false>(&mut BvhWorkspace::default(), &mut |i, j| {
            edge_edge(edges[my_edges[i as usize] as usize], edges[my_edges[j as usize] as usize]);
        });
        out
    }
}

/// The contact of vertex `v` with triangle `t` (narrow phase at x_n), when they are not
/// neighbours and are close enough (see [`separation`]), and the pair of elements with
/// their distance at x_n (for the end-of-step check, [`super::crossing`]): only the latter
/// when they touch exactly (no normal) or are too far apart for a contact. Every pair whose
/// boxes meet is an element: the check searches again only around vertices that left their
/// boxes, so a pair of the others it does not get here it never checks (a pair left out for
/// being far from its prediction crossed where the end strayed from it within the boxes).
fn vertex_triangle_contact(
    v: u32,
    t: [u32; 3],
    start: &[DVec3],
    predicted: &[DVec3],
    thickness: f64,
) -> Option<(Option<Pair>, ElementPair)> {
    let x = start[v as usize];
    let mut element = ElementPair::vertex_triangle(v, t, 0.0)?;
    let (c, b) = closest_on_triangle(x, t.map(|i| start[i as usize]));
    element.distance = (x - c).length();
    if element.distance < TOUCHING {
        return Some((None, element));
    }
    let Some((normal, target)) = separation(x - c, thickness, || relative_motion(&[v], &t, start, predicted)) else {
        return Some((None, element));
    };
    let alpha = [1.0, -b[0], -b[1], -b[2]];
    let pair = Pair { vertices: element.vertices, alpha, normal, distance: target, copies: 1 };
    Some((Some(pair), element))
}

/// The contact of edges `e` and `f` (narrow phase at x_n), when they share no vertex and are
/// close enough (see [`separation`]), and the pair of elements as for
/// [`vertex_triangle_contact`].
fn edge_edge_contact(
    e: [u32; 2],
    f: [u32; 2],
    start: &[DVec3],
    predicted: &[DVec3],
    thickness: f64,
) -> Option<(Option<Pair>, ElementPair)> {
    let mut element = ElementPair::edge_edge(e, f, 0.0)?;
    let (p, r) = (e.map(|v| start[v as usize]), f.map(|v| start[v as usize]));
    let (s, t, a, b) = closest_between_segments(p[0], p[1], r[0], r[1]);
    element.distance = (a - b).length();
    if element.distance < TOUCHING {
        return Some((None, element));
    }
    let Some((normal, target)) = separation(a - b, thickness, || relative_motion(&e, &f, start, predicted)) else {
        return Some((None, element));
    };
    let alpha = [1.0 - s, s, -(1.0 - t), -t];
    let pair = Pair { vertices: element.vertices, alpha, normal, distance: target, copies: 1 };
    Some((Some(pair), element))
}

/// The pairs whose closest features differ, in the order found, each with the
/// number of element pairs that reached it. A vertex–triangle pair whose closest point is on an
/// edge or a corner of the triangle, and an edge–edge pair whose closest point is at an edge's
/// end, is the same constraint as the other pairs reaching those features (a vertex above a
/// corner of a flat sheet meets all six triangles around it, and its edges meet that corner's
/// edges): in a crumpled cloth half the pairs are such copies. One is kept and solved, weighted
/// by its copies in the Jacobi mean of [`super::model`] as when each was solved (the weighting
/// that holds the thickness: the copies weigh a vertex's and an edge's contacts against a
/// face's). The features of a pair are its vertices with α ≠ 0 on each side (the clamped
/// coordinates of the closest-point routines are exactly 0); of pairs with the same, the first
/// found is kept.
///
/// Only pairs with fewer than four features can have copies: a vertex over a triangle's
/// interior (1 + 3) is that one vertex–triangle pair, and two edges crossing in their interiors
/// (2 + 2) that one edge–edge pair. So only the others are sorted by their features.
fn distinct_features(pairs: &mut Vec<Pair>) {
    // Fewer than four features: the last slot is unused.
    let mut keys: Vec<(FeatureKey, u32)> = pairs
        .par_iter()
        .enumerate()
        .map(|(i, c)| (feature_key(c), i as u32))
        .filter(|((key, _), _)| key[3] == u32::MAX)
        .collect();
    if keys.is_empty() {
        return;
    }
    keys.par_sort_unstable();
    // The first found of each feature pair keeps its place: the end-of-step Gauss–Seidel
    // corrections visit pairs in this order, and the detection's order (vertex–triangle pairs,
    // then edge–edge ones) holds a stack of cloths apart at the thickness where an order by
    // vertex let it settle to a fifth of it.
    let mut copies = vec![1u32; pairs.len()];
    let mut group = 0;
    for k in 1..=keys.len() {
        if k == keys.len() || keys[k].0 != keys[group].0 {
            // Sorted by (key, index): the group's first is the first found.
            copies[keys[group].1 as usize] = (k - group) as u32;
            for &(_, later) in &keys[group + 1..k] {
                copies[later as usize] = 0;
            }
            group = k;
        }
    }
    let mut kept = 0;
    for i in 0..pairs.len() {
        if copies[i] > 0 {
            pairs[kept] = pairs[i];
            pairs[kept].copies = copies[i];
            kept += 1;
        }
    }
    pairs.truncate(kept);
}

/// Both sides' vertices with α ≠ 0, each side sorted, the smaller side first (unused slots
/// u32::MAX), and how many the first side has.
type FeatureKey = ([u32; 4], u8);

fn feature_key(c: &Pair) -> FeatureKey {
    let side = |positive: bool| {
        let mut out = [u32::MAX; 4];
        let mut n = 0;
        for (&v, &a) in c.vertices.iter().zip(&c.alpha) {
            if a != 0.0 && (a > 0.0) == positive {
                out[n] = v;
                n += 1;
            }
        }
        out[..n].sort_unstable();
        (out, n)
    };
    let ((p, np), (m, nm)) = (side(true), side(false));
    let ((first, n1), (second, n2)) = if (p, np) <= (m, nm) { ((p, np), (m, nm)) } else { ((m, nm), (p, np)) };
    let mut key = [u32::MAX; 4];
    key[..n1].copy_from_slice(&first[..n1]);
    key[n1..n1 + n2].copy_from_slice(&second[..n2]);
    (key, n1 as u8)
}

/// The unit normal of a pair whose closest points are `d` apart and the distance it must keep
/// this step, when it is a contact: closer than the thickness plus twice its relative
/// predicted motion (computed only when needed), and not touching exactly (no normal then).
///
/// A pair that starts closer than the thickness is asked for only [`RECOVERY`] of the way
/// back to it per step: pushing it all the way out in one step would become a velocity
/// (depth / h) that throws the layers apart and feeds energy into a crumpled cloth.
pub(crate) fn separation(d: DVec3, thickness: f64, relative_motion: impl FnOnce() -> f64) -> Option<(DVec3, f64)> {
    let distance = d.length();
    if distance < TOUCHING || (distance >= thickness && distance >= thickness + 2.0 * relative_motion()) {
        return None;
    }
    let target = if distance < thickness { distance + RECOVERY * (thickness - distance) } else { thickness };
    Some((d / distance, target))
}

/// Closer than this a pair touches exactly and has no normal: no contact, but its elements are
/// still checked for crossing at the step's end ([`super::crossing`]).
const TOUCHING: f64 = 1e-12;

/// The share of its missing distance to the thickness that a pair which starts too close is
/// given back per step.
pub(crate) const RECOVERY: f64 = 0.2;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::closest::tests::v;

    /// The triangles of an `n` × `n` grid of vertices (row i, column j is vertex i n + j).
    fn grid_triangles(n: usize) -> Vec<[u32; 3]> {
        let mut triangles = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let k = (i * n + j) as u32;
                triangles.push([k, k + n as u32, k + 1]);
                triangles.push([k + 1, k + n as u32, k + n as u32 + 1]);
            }
        }
        triangles
    }

    /// The vertices of an `n` × `n` unit sheet folded over itself at x = 0.5, its upper half
    /// `gap` above the lower, each moved by `noise` × a random vector in [−1, 1]³.
    fn folded_sheet(n: usize, gap: f64, noise: f64, seed: &mut u64) -> Vec<DVec3> {
        let mut start = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let x = i as f64 / (n - 1) as f64;
                let (x, y) = if x < 0.5 { (x, 0.0) } else { (1.0 - x, gap) };
                start.push(DVec3::new(x, y, j as f64 / (n - 1) as f64) + noise * v(seed));
            }
        }
        start
    }

    #[test]
    fn the_steps_pairs_and_those_of_its_strayed_elements_hold_every_pair_that_crosses() {
        // A 10 × 10 sheet folded over itself, its layers 0.02 apart, predicted to fall with a
        // little noise; at the end a fifth of its vertices strayed far from the prediction
        // (through the other layer). Every vertex–triangle and edge–edge pair whose paths
        // cross (tested by brute force) is among the step's elements or the pairs of the
        // elements that left their boxes, found in the trees' frame (the drift taken out).
        let n = 10;
        let triangles = grid_triangles(n);
        let edges = crate::topology::indexed_edges(&triangles).0;
        let (thickness, tolerance) = (0.02, 2e-5);
        let mut seed = 17;
        let mut crossing = 0;
        let mut strayed_only = 0;
        for _ in 0..6 {
            let start = folded_sheet(n, 0.02, 0.005, &mut seed);
            let fall = DVec3::new(0.0, -0.05, 0.0);
            let predicted: Vec<DVec3> = start.iter().map(|&x| x + fall + 0.005 * v(&mut seed)).collect();
            let end: Vec<DVec3> = predicted
                .iter()
                .enumerate()
                .map(|(i, &p)| p + if i % 5 == 0 { 0.08 * v(&mut seed) } else { 0.002 * v(&mut seed) })
                .collect();
            let mut surface = Surface::new(&triangles, &vec![true; start.len()]);
            surface.refit(&start, &predicted, thickness, Trees { triangles: true, edges: true, vertices: true });
            let (_, elements) = surface.self_contacts(&start, &predicted, thickness);
            let drift = surface.drift();
            let shifted: Vec<DVec3> = end.iter().map(|&p| p - drift).collect();
            let strays = |e: &[u32]| surface.strays(e, (&start, &predicted), |v| shifted[v as usize], 0.5 * thickness);
            let extra = surface.pairs_of_strayed(strays, &start, &shifted, tolerance);
            // Edge–edge pairs are found in either order.
            let has = |list: &[ElementPair], p: &ElementPair| {
                let [a, b, c, d] = p.vertices;
                list.iter().any(|q| {
                    q.vertex_triangle == p.vertex_triangle
                        && (q.vertices == p.vertices || (!p.vertex_triangle && q.vertices == [c, d, a, b]))
                })
            };
            let mut check = |p: ElementPair| {
                if p.crosses(&start, &end, tolerance) {
                    crossing += 1;
                    assert!(has(&elements, &p) || has(&extra, &p), "{:?} crosses unseen", p.vertices);
                    strayed_only += usize::from(!has(&elements, &p));
                }
            };
            for v in 0..start.len() as u32 {
                for &t in &triangles {
                    if let Some(p) = ElementPair::vertex_triangle(v, t, 0.0) {
                        check(p);
                    }
                }
            }
            for (i, &e) in edges.iter().enumerate() {
                for &f in &edges[i + 1..] {
                    if let Some(p) = ElementPair::edge_edge(e, f, 0.0) {
                        check(p);
                    }
                }
            }
        }
        // The check had something to find, and some of it only through the strayed elements.
        assert!(crossing > 50 && strayed_only > 10, "{crossing} {strayed_only}");
    }

    #[test]
    fn the_broad_phase_misses_no_pair_a_brute_force_search_finds() {
        // A 9 × 9 sheet folded over itself with noise (so the layers nearly touch), at rest
        // (the margin is then the thickness, and a pair within it always has meeting boxes):
        // the contacts are exactly those of testing every vertex–triangle and edge–edge pair.
        let mut seed = 3;
        let n = 9;
        let start = folded_sheet(n, 0.04, 0.02, &mut seed);
        let triangles = grid_triangles(n);
        let thickness = 0.05;
        let mut surface = Surface::new(&triangles, &vec![true; start.len()]);
        // Every pair within the thickness, by brute force, as the constraint it makes: its
        // closest features.
        let mut brute = Vec::new();
        let pair =
            |vertices: [u32; 4], alpha: [f64; 4]| Pair { vertices, alpha, normal: DVec3::Y, distance: 0.0, copies: 1 };
        for (v, &x) in start.iter().enumerate() {
            for t in &triangles {
                let (c, b) = closest_on_triangle(x, t.map(|i| start[i as usize]));
                let d = (x - c).length();
                if !t.contains(&(v as u32)) && d < thickness && d >= 1e-12 {
                    brute.push(feature_key(&pair([v as u32, t[0], t[1], t[2]], [1.0, -b[0], -b[1], -b[2]])));
                }
            }
        }
        let edges = crate::topology::indexed_edges(&triangles).0;
        for (i, e) in edges.iter().enumerate() {
            for f in &edges[i + 1..] {
                if f.contains(&e[0]) || f.contains(&e[1]) {
                    continue;
                }
                let p = |v: u32| start[v as usize];
                let (s, t, a, b) = closest_between_segments(p(e[0]), p(e[1]), p(f[0]), p(f[1]));
                let d = (a - b).length();
                if d < thickness && d >= 1e-12 {
                    brute.push(feature_key(&pair([e[0], e[1], f[0], f[1]], [1.0 - s, s, -(1.0 - t), -t])));
                }
            }
        }
        let element_pairs = brute.len();
        brute.sort_unstable();
        brute.dedup();
        assert!(brute.len() > 100, "the fold should bring the layers within the thickness: {}", brute.len());
        assert!(brute.len() < element_pairs, "a fold has pairs reaching the same features");
        // Found: each feature pair once, with as many copies as element pairs reached it.
        let contacts = detect_self_contacts(&mut surface, &start, &start, thickness);
        let copies: u32 = contacts.iter().map(|c| c.copies).sum();
        let mut found: Vec<_> = contacts.iter().map(feature_key).collect();
        found.sort_unstable();
        let missing: Vec<_> = brute.iter().filter(|k| found.binary_search(k).is_err()).take(4).collect();
        assert!(found == brute, "{} contacts, {} by brute force; missing e.g. {missing:?}", found.len(), brute.len());
        assert_eq!(copies as usize, element_pairs);
    }

    #[test]
    fn a_pair_too_far_for_a_contact_whose_boxes_meet_is_still_an_element() {
        // Vertex 3 (of a second triangle) lies in the plane of triangle 0 1 2, inside its box
        // but 0.42 from its hypotenuse, and nothing moves: no contact, but the end-of-step
        // check, which searches again only around vertices that leave their boxes, must still
        // be given the pair.
        let start = [
            DVec3::ZERO,
            DVec3::X,
            DVec3::Z,
            DVec3::new(0.8, 0.0, 0.8),
            DVec3::new(1.0, 0.0, 0.8),
            DVec3::new(0.8, 0.0, 1.0),
        ];
        let mut surface = Surface::new(&[[0, 1, 2], [3, 4, 5]], &[true; 6]);
        surface.refit(&start, &start, 0.01, Trees { triangles: true, edges: true, vertices: true });
        let (pairs, elements) = surface.self_contacts(&start, &start, 0.01);
        assert!(pairs.is_empty());
        let element = elements.iter().find(|e| e.vertex_triangle && e.vertices == [3, 0, 1, 2]).copied();
        let distance = element.map(|e| e.distance).unwrap_or_default();
        assert!((distance - 0.6 / 2f64.sqrt()).abs() < 1e-12, "{element:?}");
    }

    #[test]
    fn pairs_reaching_the_same_features_are_one_with_its_copies_in_the_order_found() {
        // A vertex (9) above the middle vertex (4) of a 3 × 3 sheet meets its triangles at that
        // corner: one vertex–vertex constraint. A vertex (11) above edge 1–4 meets both
        // triangles on it: one vertex–edge constraint. A vertex (10) above a triangle's inside:
        // its own.
        let pair =
            |vertices: [u32; 4], alpha: [f64; 4]| Pair { vertices, alpha, normal: DVec3::Y, distance: 0.1, copies: 1 };
        let corner = |t: [u32; 3], k: usize| {
            let mut alpha = [1.0, 0.0, 0.0, 0.0];
            alpha[1 + k] = -1.0;
            pair([9, t[0], t[1], t[2]], alpha)
        };
        let on_edge = |t: [u32; 3]| {
            let alpha = t.map(|v| match v {
                1 => -0.25,
                4 => -0.75,
                _ => 0.0,
            });
            pair([11, t[0], t[1], t[2]], [1.0, alpha[0], alpha[1], alpha[2]])
        };
        let inside = pair([10, 0, 1, 3], [1.0, -0.2, -0.3, -0.5]);
        let pairs = vec![
            inside,
            corner([4, 1, 3], 0),
            on_edge([4, 1, 3]),
            corner([1, 4, 2], 1),
            on_edge([1, 4, 2]),
            corner([3, 7, 4], 2),
        ];
        let mut distinct = pairs;
        distinct_features(&mut distinct);
        let found: Vec<_> = distinct.iter().map(|c| (c.vertices, c.copies)).collect();
        assert_eq!(found, [([10, 0, 1, 3], 1), ([9, 4, 1, 3], 3), ([11, 4, 1, 3], 2)]);
    }

    #[test]
    fn two_parallel_sheets_make_pairs_only_across() {
        // Two unit squares (two triangles each) 0.05 apart; thickness 0.1: every vertex of one
        // is near a triangle of the other, no pair within a sheet is (its triangles hold all
        // its vertices within 1 > 0.1).
        let mut start = Vec::new();
        for y in [0.0, 0.05] {
            for (x, z) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                start.push(DVec3::new(x, y, z));
            }
        }
        let triangles = [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]];
        let mut surface = Surface::new(&triangles, &[true; 8]);
        let contacts = detect_self_contacts(&mut surface, &start, &start, 0.1);
        assert!(!contacts.is_empty());
        for c in &contacts {
            let sheet = |v: u32| v / 4;
            let vs = &c.vertices[..];
            assert!(vs.iter().any(|&v| sheet(v) == 0) && vs.iter().any(|&v| sheet(v) == 1), "{vs:?}");
            // 0.05 apart, too close by 0.05: asked for RECOVERY of that back this step.
            assert!((c.gap(&start) + RECOVERY * 0.05).abs() < 1e-12, "gap {}", c.gap(&start));
        }
    }
}
