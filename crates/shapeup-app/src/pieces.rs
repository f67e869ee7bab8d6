//! The connected pieces of a mesh, for "select piece" and for finding pieces no handle holds.

/// The connected pieces of a mesh: vertices joined by triangle edges (a vertex no triangle
/// uses is a piece of its own, but is never solved and so never counted as free).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pieces {
    /// Piece of each vertex, numbered 0.. in order of each piece's first vertex.
    pub of_vertex: Vec<u32>,
    /// Number of pieces that have triangles.
    pub count: usize,
    /// Whether each piece has triangles.
    used: Vec<bool>,
}

impl Pieces {
    /// The pieces of `n` vertices joined by `triangles` (union–find over the triangles' edges;
    /// a few lines, not worth a graph crate).
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Pieces {
        fn root(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let up = parent[parent[v as usize] as usize];
                parent[v as usize] = up;
                v = up;
            }
            v
        }
        let mut parent: Vec<u32> = (0..n as u32).collect();
        let mut in_triangle = vec![false; n];
        for t in triangles {
            for &v in t {
                in_triangle[v as usize] = true;
            }
            for (a, b) in [(t[0], t[1]), (t[1], t[2])] {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                if ra != rb {
                    parent[ra.max(rb) as usize] = ra.min(rb);
                }
            }
        }
        let mut label = vec![u32::MAX; n];
        let mut of_vertex = vec![0; n];
        let mut used = Vec::new();
        for v in 0..n {
            let r = root(&mut parent, v as u32) as usize;
            if label[r] == u32::MAX {
                label[r] = used.len() as u32;
                used.push(false);
            }
            of_vertex[v] = label[r];
            used[label[r] as usize] |= in_triangle[v];
        }
        let count = used.iter().filter(|u| **u).count();
        Pieces { of_vertex, count, used }
    }

    /// The vertices of the piece that holds vertex `v`, ascending (empty when out of range).
    pub fn piece_of(&self, v: u32) -> Vec<u32> {
        let Some(&piece) = self.of_vertex.get(v as usize) else { return Vec::new() };
        (0..self.of_vertex.len() as u32).filter(|&u| self.of_vertex[u as usize] == piece).collect()
    }

    /// Pieces with triangles none of whose vertices is in `pinned`.
    pub fn free(&self, pinned: &[bool]) -> Vec<u32> {
        let mut held = vec![false; self.used.len()];
        for (v, &p) in pinned.iter().enumerate() {
            if p && let Some(&piece) = self.of_vertex.get(v) {
                held[piece as usize] = true;
            }
        }
        (0..self.used.len() as u32).filter(|&p| self.used[p as usize] && !held[p as usize]).collect()
    }
}
