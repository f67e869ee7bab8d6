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
}

/// A BVH over boxes that move a little each step: refitted, and rebuilt every
/// [`REBUILD_EVERY`] steps as the surface moves away from the tree's layout.
#[derive(Debug, Clone, Default)]
struct Tree {
    bvh: Option<Bvh>,
    since_build: u32,
}

/// Steps between two full builds of a BVH (refits in between).
const REBUILD_EVERY: u32 = 20;

impl Tree {
    /// The BVH of `boxes`: refitted, or rebuilt when due.
    fn update(&mut self, boxes: &[Aabb]) -> &Bvh {
        match &mut self.bvh {
            Some(bvh) if self.since_build < REBUILD_EVERY => {
                for (i, b) in boxes.iter().enumerate() {
                    bvh.update_partially_if_present(*b, i as u32, 0.0);
                }
                bvh.refit_without_opt();
                self.since_build += 1;
            }
            _ => {
                self.bvh = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, boxes));
                self.since_build = 0;
            }
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
        }
    }
}

fn to_parry(p: DVec3) -> parry3d_f64::math::Vector {
    parry3d_f64::math::Vector::new(p.x, p.y, p.z)
}

/// The mean predicted motion of `vertices`: the translation they share (gravity's h² g in a
/// falling or resting cloth), taken out of every swept box.
fn common_motion(vertices: &[u32], start: &[DVec3], predicted: &[DVec3]) -> DVec3 {
    if vertices.is_empty() {
        return DVec3::ZERO;
    }
    let sum: DVec3 = vertices.par_iter().map(|&v| predicted[v as usize] - start[v as usize]).sum();
    sum / vertices.len() as f64
}

/// The box around the points of `vertices` at `start` and at `predicted` less `drift`, grown
/// by `grow`: the element's sweep in a frame that moves by `drift` over the step. Distances
/// at each instant are the same in any frame that translates, so two elements that come
/// within the thickness during the step still have meeting boxes; taking out the motion the
/// surface shares keeps the boxes small.
fn swept_box(vertices: &[u32], start: &[DVec3], predicted: &[DVec3], drift: DVec3, grow: f64) -> Aabb {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &v in vertices {
        for p in [start[v as usize], predicted[v as usize] - drift] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    Aabb::new(to_parry(lo - DVec3::splat(grow)), to_parry(hi + DVec3::splat(grow)))
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
    surface.self_contacts(start, predicted, thickness).0
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
        let Surface { triangles, edges, vertices, triangle_tree, edge_tree, vertex_tree, drift } = self;
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
    pub(crate) fn self_contacts(
        &self,
        start: &[DVec3],
        predicted: &[DVec3],
        thickness: f64,
    ) -> (Vec<Pair>, Vec<ElementPair>) {
        let Some((triangle_bvh, edge_bvh, vertex_bvh)) = self.bvhs() else {
            return (Vec::new(), Vec::new());
        };
        let (triangles, edges, vertices) = (&self.triangles, &self.edges, &self.vertices);
        // Candidates, each passed to the narrow phase as it is met (no list of candidates):
        // vertex–triangle pairs from one traversal of the vertex tree against the triangle
        // tree, edge–edge pairs from one of the edge tree against itself, less those that
        // share a vertex. The two traversals run side by side.
        let (mut contacts, edge_edge) = rayon::join(
            || -> Vec<(Option<Pair>, ElementPair)> {
                vertex_bvh
                    .leaf_pairs(triangle_bvh, |a, b| a.intersects(b))
                    .filter_map(|(i, k)| {
                        vertex_triangle_contact(
                            vertices[i as usize],
                            triangles[k as usize],
                            start,
                            predicted,
                            thickness,
                        )
                    })
                    .collect()
            },
            || -> Vec<(Option<Pair>, ElementPair)> {
                let contact = |i: u32, j: u32| {
                    edge_edge_contact(edges[i as usize], edges[j as usize], start, predicted, thickness)
                };
                if rayon::current_num_threads() > 1 {
                    // parry's parallel traversal lists the pairs (in the sequential one's order).
                    let pairs = edge_bvh.traverse_bvtt_single_tree_parallel::<false>();
                    pairs.par_iter().filter_map(|&(i, j)| contact(i, j)).collect()
                } else {
                    let mut out = Vec::new();
                    edge_bvh.traverse_bvtt_single_tree::<false>(&mut BvhWorkspace::default(), &mut |i, j| {
                        out.extend(contact(i, j));
                    });
                    out
                }
            },
        );
        contacts.extend(edge_edge);
        let (pairs, elements): (Vec<Option<Pair>>, _) = contacts.into_iter().unzip();
        (distinct_features(pairs.into_iter().flatten().collect()), elements)
    }

    /// Every pair of elements (vertex–triangle and edge–edge, not neighbours) of which one has
    /// a vertex in `moved` and whose boxes meet, each with distance 0: the moved elements'
    /// boxes swept from `start` to `end` and grown by `grow`, in BVHs of their own, against
    /// each other and against the step's trees (whose boxes must hold the other elements'
    /// paths from `start` to `end`). For the end-of-step check ([`super::crossing`]).
    pub(crate) fn pairs_of_moved(&self, moved: &[bool], start: &[DVec3], end: &[DVec3], grow: f64) -> Vec<ElementPair> {
        let Some((triangle_bvh, edge_bvh, vertex_bvh)) = self.bvhs() else {
            return Vec::new();
        };
        let is_moved = |v: &u32| moved[*v as usize];
        let (triangles, edges, vertices) = (&self.triangles, &self.edges, &self.vertices);
        // The moved elements (indices into `items`, `size` vertices each) and their BVH.
        let pick = |items: &[u32], size: usize| -> (Vec<u32>, Bvh) {
            let chosen: Vec<u32> =
                items.chunks(size).enumerate().filter(|(_, e)| e.iter().any(is_moved)).map(|(i, _)| i as u32).collect();
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
fn distinct_features(mut pairs: Vec<Pair>) -> Vec<Pair> {
    // Fewer than four features: the last slot is unused.
    let mut keys: Vec<(FeatureKey, u32)> = pairs
        .par_iter()
        .enumerate()
        .map(|(i, c)| (feature_key(c), i as u32))
        .filter(|((key, _), _)| key[3] == u32::MAX)
        .collect();
    if keys.is_empty() {
        return pairs;
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
    pairs
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

    #[test]
    fn the_broad_phase_misses_no_pair_a_brute_force_search_finds() {
        // A 9 × 9 sheet folded over itself with noise (so the layers nearly touch), at rest
        // (the margin is then the thickness, and a pair within it always has meeting boxes):
        // the contacts are exactly those of testing every vertex–triangle and edge–edge pair.
        let mut seed = 3;
        let n = 9;
        let mut start = Vec::new();
        for i in 0..n {
            for j in 0..n {
                let x = i as f64 / (n - 1) as f64;
                let (x, y) = if x < 0.5 { (x, 0.0) } else { (1.0 - x, 0.04) };
                start.push(DVec3::new(x, y, j as f64 / (n - 1) as f64) + 0.02 * v(&mut seed));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..n - 1 {
            for j in 0..n - 1 {
                let k = (i * n + j) as u32;
                triangles.push([k, k + n as u32, k + 1]);
                triangles.push([k + 1, k + n as u32, k + n as u32 + 1]);
            }
        }
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
        let distinct = distinct_features(pairs);
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
