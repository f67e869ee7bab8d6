//! The connected pieces of a mesh, for "select piece" and for finding pieces no handle holds.

use shapeup_core::topology::connected_pieces;

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
    /// The pieces of `n` vertices joined by `triangles` (the core's union–find,
    /// [`connected_pieces`]).
    pub fn new(n: usize, triangles: &[[u32; 3]]) -> Pieces {
        let (of_vertex, pieces) = connected_pieces(n, triangles.iter().map(|t| &t[..]));
        let mut used = vec![false; pieces];
        for t in triangles {
            used[of_vertex[t[0] as usize] as usize] = true;
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

    /// The vertices of the `pieces` (by piece label), ascending.
    pub fn vertices_of(&self, pieces: &[u32]) -> Vec<u32> {
        let mut chosen = vec![false; self.used.len()];
        for &p in pieces {
            if let Some(c) = chosen.get_mut(p as usize) {
                *c = true;
            }
        }
        (0..self.of_vertex.len() as u32).filter(|&v| chosen[self.of_vertex[v as usize] as usize]).collect()
    }

    /// The piece with the most of `triangles` (the first on a tie); `None` without triangles.
    pub fn largest(&self, triangles: &[[u32; 3]]) -> Option<u32> {
        let mut count = vec![0usize; self.used.len()];
        for t in triangles {
            count[self.of_vertex[t[0] as usize] as usize] += 1;
        }
        let most = *count.iter().max()?;
        (most > 0).then(|| count.iter().position(|&c| c == most).map(|p| p as u32)).flatten()
    }
}
