//! Connectivity of a triangle mesh: unique edges, ordered one-rings, boundary flags and
//! connected pieces. Built once per mesh ([`Topology::new`]); positions play no part.

use std::collections::HashMap;

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
}

impl Topology {
    /// Builds the connectivity of `n` vertices and `triangles`. [O(m log m)]
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Self {
        let (edges, edge_triangle_count) = unique_edges(triangles);
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

/// Unique undirected edges of `triangles` (`[i, j]`, `i < j`, sorted) and, for each, the number
/// of triangles it belongs to. An edge of three or more triangles counts them all.
pub fn unique_edges(triangles: &[[u32; 3]]) -> (Vec<[u32; 2]>, Vec<u32>) {
    let mut all: Vec<[u32; 2]> = triangles
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| [a.min(b), a.max(b)])
        .collect();
    all.sort_unstable();
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(all.len() / 2 + 1);
    let mut counts: Vec<u32> = Vec::with_capacity(all.len() / 2 + 1);
    for e in all {
        if edges.last() == Some(&e) {
            if let Some(c) = counts.last_mut() {
                *c += 1;
            }
        } else {
            edges.push(e);
            counts.push(1);
        }
    }
    (edges, counts)
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

/// Boundary flags: vertex i is on the boundary when one of its edges has exactly one triangle.
pub fn boundary_vertices(n: usize, edges: &[[u32; 2]], edge_triangle_count: &[u32]) -> Vec<bool> {
    let mut boundary = vec![false; n];
    for (e, &count) in edges.iter().zip(edge_triangle_count) {
        if count == 1 {
            boundary[e[0] as usize] = true;
            boundary[e[1] as usize] = true;
        }
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
    links.iter().map(|l| order_fan(l)).collect()
}

/// Chains the directed links (b → c) of one vertex into a cyclic order, or returns the sorted
/// unique neighbours when they do not form one fan.
fn order_fan(links: &[(u32, u32)]) -> Vec<u32> {
    let mut sorted: Vec<u32> = links.iter().flat_map(|&(b, c)| [b, c]).collect();
    sorted.sort_unstable();
    sorted.dedup();
    if links.is_empty() {
        return sorted;
    }
    let mut next: HashMap<u32, u32> = HashMap::with_capacity(links.len());
    for &(b, c) in links {
        if next.insert(b, c).is_some() {
            return sorted; // two triangles leave b the same way: not a single fan
        }
    }
    // Start at a neighbour with no incoming link (the boundary), else anywhere on the cycle.
    let start = sorted.iter().copied().find(|v| !links.iter().any(|&(_, c)| c == *v)).unwrap_or(links[0].0);
    let mut ring = Vec::with_capacity(sorted.len());
    let mut v = start;
    loop {
        ring.push(v);
        match next.get(&v) {
            Some(&w) if w != start && ring.len() < sorted.len() => v = w,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A hexagonal fan: centre 0, ring 1..=6.
    fn hexagon() -> Vec<[u32; 3]> {
        (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect()
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
}
