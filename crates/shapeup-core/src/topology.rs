//! Connectivity of a triangle mesh: unique edges, ordered one-rings, boundary flags and
//! connected pieces. Built once per mesh ([`Topology::new`]); positions play no part.

use rayon::prelude::*;

/// Connectivity derived from a mesh's triangles, computed eagerly.
#[derive(Debug, Clone, Default)]
pub struct Topology {
    /// Unique undirected edges `[i, j]` with `i < j`, sorted.
    pub edges: Vec<[u32; 2]>,
    /// Number of triangles on each edge of [`Topology::edges`] (1 = boundary edge).
    pub edge_triangle_count: Vec<u32>,
    /// Neighbours of each vertex, in cyclic order around it where the one-ring is a single fan.
    pub one_rings: Vec<Vec<u32>>,
    /// `true` for a vertex with an edge that belongs to exactly one triangle.
    pub boundary: Vec<bool>,
    /// `true` for a vertex that belongs to at least one triangle.
    pub in_triangle: Vec<bool>,
    /// Indices of the triangles around each vertex.
    pub vertex_triangles: Vec<Vec<u32>>,
    /// For triangle t = (a, b, c), the indices in [`Topology::edges`] of its edges ab, bc, ca.
    pub triangle_edges: Vec<[u32; 3]>,
}

impl Topology {
    /// Builds the connectivity of `n` vertices and `triangles`. [O(m log m)]
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Self {
        let (edges, edge_triangle_count, triangle_edges) = indexed_edges(triangles);
        let boundary = boundary_vertices(n, &edges, &edge_triangle_count);
        let vertex_triangles = vertex_triangles(n, triangles);
        let in_triangle = vertex_triangles.iter().map(|t| !t.is_empty()).collect();
        Topology {
            one_rings: one_rings(n, triangles),
            edges,
            edge_triangle_count,
            boundary,
            in_triangle,
            vertex_triangles,
            triangle_edges,
        }
    }

    /// Whether vertex `i` is interior: in a triangle and on no boundary edge.
    pub fn is_interior(&self, i: usize) -> bool {
        self.in_triangle[i] && !self.boundary[i]
    }

    /// Index of edge `{i, j}` in [`Topology::edges`], if it exists. [O(log m)]
    pub fn edge_index(&self, i: u32, j: u32) -> Option<usize> {
        let key = [i.min(j), i.max(j)];
        self.edges.binary_search(&key).ok()
    }
}

/// Unique undirected edges of `tetrahedra` (`[i, j]`, `i < j`, sorted): the six edges of each,
/// interior ones included. [O(t log t)]
pub fn tetrahedron_edges(tetrahedra: &[[u32; 4]]) -> Vec<[u32; 2]> {
    let mut all: Vec<[u32; 2]> = tetrahedra
        .iter()
        .flat_map(|&[a, b, c, d]| [(a, b), (a, c), (a, d), (b, c), (b, d), (c, d)])
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// Unique undirected edges of `polygons` (`[i, j]`, `i < j`, sorted): the sides of each polygon
/// as read, not the diagonals a triangulation adds; a side from a corner to itself is skipped.
/// [O(c log c), c corners]
pub fn polygon_edges<'a>(polygons: impl IntoIterator<Item = &'a [u32]>) -> Vec<[u32; 2]> {
    let mut all: Vec<[u32; 2]> = polygons
        .into_iter()
        .flat_map(|f| (0..f.len()).map(move |k| (f[k], f[(k + 1) % f.len()])))
        .filter(|&(a, b)| a != b)
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// Unique undirected edges of `triangles` (`[i, j]`, `i < j`, sorted) and, for each, the number
/// of triangles it belongs to. An edge of three or more triangles counts them all.
pub fn unique_edges(triangles: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<u32>) {
    let (edges, counts, _) = indexed_edges(triangles);
    (edges, counts)
}

/// [`unique_edges`], and for each triangle (a, b, c) the indices of its edges ab, bc, ca, found
/// by the same sort (no search per corner). [O(m log m)]
pub fn indexed_edges(triangles: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<u32>, Vec<[u32; 3]>) {
    let mut all: Vec<([u32; 2], u32)> = triangles
        .iter()
        .enumerate()
        .flat_map(|(t, tri)| (0..3).map(move |k| (tri[k], tri[(k + 1) % 3], (3 * t + k) as u32)))
        .map(|(a, b, corner)| ([a.min(b), a.max(b)], corner))
        .collect();
    all.par_sort_unstable();
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(all.len() / 2 + 1);
    let mut counts: Vec<u32> = Vec::with_capacity(all.len() / 2 + 1);
    let mut triangle_edges = vec![[0u32; 3]; triangles.len()];
    for (e, corner) in all {
        if edges.last() == Some(&e) {
            if let Some(c) = counts.last_mut() {
                *c += 1;
            }
        } else {
            edges.push(e);
            counts.push(1);
        }
        triangle_edges[corner as usize / 3][corner as usize % 3] = (edges.len() - 1) as u32;
    }
    (edges, counts, triangle_edges)
}

/// The triangles around each vertex: index t is in list i when triangle t has corner i.
pub fn vertex_triangles(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut around = vec![Vec::new(); n];
    for (t, tri) in triangles.iter().enumerate() {
        for &v in tri {
            around[v as usize].push(t as u32);
        }
    }
    around
}

/// The boundary edges among `edges`: those of exactly one triangle (`edge_triangle_count`, as
/// [`unique_edges`] gives it).
pub fn boundary_edges<'a>(
    edges: &'a [[u32; 2]],
    edge_triangle_count: &'a [u32],
) -> impl Iterator<Item = [u32; 2]> + 'a {
    edges.iter().zip(edge_triangle_count).filter(|&(_, &count)| count == 1).map(|(&e, _)| e)
}

/// Boundary flags: vertex i is on the boundary when one of its edges has exactly one triangle.
pub fn boundary_vertices(n: usize, edges: &[[u32; 2]], edge_triangle_count: &[u32]) -> Vec<bool> {
    let mut boundary = vec![false; n];
    for [a, b] in boundary_edges(edges, edge_triangle_count) {
        boundary[a as usize] = true;
        boundary[b as usize] = true;
    }
    boundary
}

/// One-ring neighbours of each vertex. Where the triangles around a vertex form a single fan
/// (manifold vertex, interior or boundary), the ring is in the fan's cyclic order (starting at
/// the boundary for a boundary vertex); otherwise the neighbours are sorted by index.
pub fn one_rings(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    // links[i] = directed pairs (b, c): triangle (i, b, c) seen counter-clockwise from i.
    let mut links: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            links[t[k] as usize].push((t[(k + 1) % 3], t[(k + 2) % 3]));
        }
    }
    links.par_iter().map(|l| order_fan(l)).collect()
}

/// Chains the directed links (b → c) of one vertex into a cyclic order, or returns the sorted
/// unique neighbours when they do not form one fan. [O(k log k) for k links: sorted arrays and
/// binary searches, no hash map, so that a vertex of huge degree costs no more than its size]
fn order_fan(links: &[(u32, u32)]) -> Vec<u32> {
    let mut sorted: Vec<u32> = links.iter().flat_map(|&(b, c)| [b, c]).collect();
    sorted.sort_unstable();
    sorted.dedup();
    if links.is_empty() {
        return sorted;
    }
    let mut by_start = links.to_vec();
    by_start.sort_unstable();
    if by_start.windows(2).any(|w| w[0].0 == w[1].0) {
        return sorted; // two triangles leave b the same way: not a single fan
    }
    let next = |v: u32| by_start.binary_search_by_key(&v, |&(b, _)| b).ok().map(|k| by_start[k].1);
    // Start at a neighbour with no incoming link (the boundary), else anywhere on the cycle.
    let mut ends: Vec<u32> = links.iter().map(|&(_, c)| c).collect();
    ends.sort_unstable();
    let start = sorted.iter().copied().find(|v| ends.binary_search(v).is_err()).unwrap_or(links[0].0);
    let mut ring = Vec::with_capacity(sorted.len());
    let mut v = start;
    loop {
        ring.push(v);
        match next(v) {
            Some(w) if w != start && ring.len() < sorted.len() => v = w,
            _ => break,
        }
    }
    if ring.len() == sorted.len() { ring } else { sorted }
}

/// Connected pieces of `n` vertices linked by `links` (each a list of vertices that are joined,
/// e.g. the vertices of one constraint). Returns a piece label per vertex (0-based, in order of
/// each piece's smallest vertex) and the number of pieces; a vertex in no link is its own piece.
pub fn connected_pieces<'a>(n: usize, links: impl IntoIterator<Item = &'a [u32]>) -> (Vec<u32>, usize) {
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for link in links {
        if let Some((&first, rest)) = link.split_first() {
            for &v in rest {
                let (a, b) = (find(&mut parent, first), find(&mut parent, v));
                if a != b {
                    parent[a.max(b) as usize] = a.min(b);
                }
            }
        }
    }
    let mut label = vec![u32::MAX; n];
    let mut count = 0u32;
    for v in 0..n as u32 {
        let root = find(&mut parent, v);
        if label[root as usize] == u32::MAX {
            label[root as usize] = count;
            count += 1;
        }
        label[v as usize] = label[root as usize];
    }
    (label, count as usize)
}

/// Boundary faces of a tetrahedral mesh: the faces that belong to exactly one tetrahedron.
///
/// For tetrahedron (a, b, c, d) the faces are (b, c, d), (a, d, c), (a, b, d), (a, c, b) (each
/// named by the opposite corner a, b, c, d), so that when the tetrahedron is positively oriented,
/// (b − a)·((c − a) × (d − a)) > 0, every face's right-hand normal points out of it. A face shared
/// by two or more tetrahedra, whatever their orientation, is interior. The faces come in the order
/// of their tetrahedra and, within one, in the order above, so the result is deterministic.
/// Positions play no part. [O(t log t)]
pub fn tetrahedron_boundary(tets: &[[u32; 4]]) -> Vec<[u32; 3]> {
    let faces: Vec<[u32; 3]> =
        tets.iter().flat_map(|&[a, b, c, d]| [[b, c, d], [a, d, c], [a, b, d], [a, c, b]]).collect();
    // Sort the faces by their vertex set; a set that occurs once is on the boundary.
    let mut keyed: Vec<([u32; 3], usize)> = faces
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut key = *f;
            key.sort_unstable();
            (key, i)
        })
        .collect();
    keyed.sort_unstable();
    let mut on_boundary = vec![false; faces.len()];
    for group in keyed.chunk_by(|x, y| x.0 == y.0) {
        if let [(_, i)] = group {
            on_boundary[*i] = true;
        }
    }
    faces.into_iter().zip(on_boundary).filter_map(|(f, keep)| keep.then_some(f)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hexagonal fan: centre 0, ring 1..=6.
    fn hexagon() -> Vec<[u32; 3]> {
        (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect()
    }

    #[test]
    fn polygon_edges_are_the_sides_without_diagonals() {
        // Two quads sharing the side 1–2, and a face that repeats a corner (3, 3).
        let polygons: [&[u32]; 3] = [&[0, 1, 2, 3], &[1, 4, 5, 2], &[3, 3, 2]];
        assert_eq!(polygon_edges(polygons), vec![[0, 1], [0, 3], [1, 2], [1, 4], [2, 3], [2, 5], [4, 5]]);
    }

    #[test]
    fn edges_are_unique_with_triangle_counts() {
        let (edges, counts) = unique_edges(&hexagon());
        assert_eq!(edges.len(), 12);
        assert_eq!(counts.iter().filter(|&&c| c == 2).count(), 6, "spokes are interior");
        assert_eq!(counts.iter().filter(|&&c| c == 1).count(), 6, "rim is boundary");
    }

    #[test]
    fn one_ring_is_cyclic_and_boundary_detected() {
        let topo = Topology::new(7, &hexagon());
        let ring = &topo.one_rings[0];
        assert_eq!(ring.len(), 6);
        for k in 0..6 {
            let (a, b) = (ring[k], ring[(k + 1) % 6]);
            assert_eq!(b, 1 + a % 6, "consecutive neighbours share a triangle");
        }
        assert!(topo.is_interior(0));
        assert!((1..7).all(|v| topo.boundary[v]));
        // A boundary vertex's ring starts at the boundary: 1's ring is 2, 0, 6 (ccw).
        assert_eq!(topo.one_rings[1], vec![2, 0, 6]);
    }

    #[test]
    fn triangle_edges_name_each_triangles_edges() {
        let tris = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [2, 1, 5], [5, 6, 2]];
        let topo = Topology::new(7, &tris);
        for (t, tri) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                assert_eq!(
                    topo.edges[topo.triangle_edges[t][k] as usize],
                    [a.min(b), a.max(b)],
                    "triangle {t} edge {k}"
                );
                assert_eq!(topo.edge_index(a, b), Some(topo.triangle_edges[t][k] as usize));
            }
        }
    }

    /// A vertex of high degree whose links do not chain (here: every second triangle turned) gets
    /// its sorted neighbours, and one that does gets its fan order, both in time linear-log in
    /// the degree.
    #[test]
    fn a_high_degree_fan_is_ordered_or_sorted() {
        let k = 20_000u32;
        let fan: Vec<[u32; 3]> = (0..k).map(|i| [0, 1 + i, 1 + (i + 1) % k]).collect();
        let ring = &Topology::new(k as usize + 1, &fan).one_rings[0];
        assert_eq!(ring.len(), k as usize);
        assert!(ring.windows(2).all(|w| w[1] == 1 + w[0] % k), "not in fan order");
        let broken: Vec<[u32; 3]> =
            fan.iter().enumerate().map(|(i, t)| if i % 2 == 0 { *t } else { [t[0], t[2], t[1]] }).collect();
        let ring = &Topology::new(k as usize + 1, &broken).one_rings[0];
        assert_eq!(*ring, (1..=k).collect::<Vec<u32>>());
    }

    #[test]
    fn non_manifold_edge_is_not_boundary() {
        let tris = [[0, 1, 2], [1, 0, 3], [0, 1, 4]];
        let (edges, counts) = unique_edges(&tris);
        let i = edges.binary_search(&[0, 1]).unwrap();
        assert_eq!(counts[i], 3);
    }

    #[test]
    fn pieces_are_labelled_by_smallest_vertex() {
        let links: Vec<Vec<u32>> = vec![vec![3, 4], vec![0, 1], vec![4, 5]];
        let (label, count) = connected_pieces(7, links.iter().map(|l| l.as_slice()));
        assert_eq!(count, 4);
        assert_eq!(label, vec![0, 0, 1, 2, 2, 2, 3]);
    }

    /// Signed volume ×6 of tetrahedron `t` of `p`.
    fn volume6(p: &[[f64; 3]], t: [u32; 4]) -> f64 {
        let [a, b, c, d] = t.map(|v| p[v as usize]);
        let e = |q: [f64; 3]| [q[0] - a[0], q[1] - a[1], q[2] - a[2]];
        let (u, v, w) = (e(b), e(c), e(d));
        u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) + u[2] * (v[0] * w[1] - v[1] * w[0])
    }

    #[test]
    fn boundary_of_one_tetrahedron_points_outward() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let tet = [0, 1, 2, 3];
        assert!(volume6(&p, tet) > 0.0);
        let faces = tetrahedron_boundary(&[tet]);
        assert_eq!(faces, vec![[1, 2, 3], [0, 3, 2], [0, 1, 3], [0, 2, 1]]);
        for f in faces {
            // The face with the opposite corner appended is negatively oriented: that corner is
            // behind the face, so the normal points away from the tetrahedron.
            let opposite = (0..4).find(|v| !f.contains(v)).unwrap();
            assert!(volume6(&p, [f[0], f[1], f[2], opposite]) < 0.0, "{f:?}");
        }
    }

    #[test]
    fn shared_face_is_interior_and_surface_is_closed() {
        // Two tetrahedra on either side of the face (0, 1, 2).
        let tets = [[0, 1, 2, 3], [0, 2, 1, 4]];
        let faces = tetrahedron_boundary(&tets);
        assert_eq!(faces.len(), 6);
        assert!(faces.iter().all(|f| !(f.contains(&0) && f.contains(&1) && f.contains(&2))));
        let (_, counts) = unique_edges(&faces);
        assert!(counts.iter().all(|&c| c == 2), "every edge in two faces: {counts:?}");
        assert_eq!(tetrahedron_boundary(&tets), faces, "deterministic");
        assert!(tetrahedron_boundary(&[]).is_empty());
    }
}
