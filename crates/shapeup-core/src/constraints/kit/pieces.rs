//! Pieces of a mesh and the surface that selected pieces follow (`attachment`).

use crate::geometry::{RestGeometry, is_degenerate_triangle};
use crate::topology::connected_pieces;

/// The connected pieces of the rest mesh: vertices joined by triangles or tetrahedra. A label
/// per vertex and the number of pieces ([`connected_pieces`]).
pub(crate) fn pieces_of(rest: &RestGeometry) -> (Vec<u32>, usize) {
    let triangles = rest.triangles.iter().map(|t| &t[..]);
    let tetrahedra = rest.tetrahedra.iter().map(|t| &t[..]);
    connected_pieces(rest.num_vertices(), triangles.chain(tetrahedra))
}

/// The triangles (with area at rest) of the pieces that hold no vertex `selected` says: the
/// surface the selected pieces follow.
pub(crate) fn unselected_piece_triangles(rest: &RestGeometry, selected: impl Fn(u32) -> bool) -> Vec<[u32; 3]> {
    let (piece, count) = pieces_of(rest);
    let mut touched = vec![false; count];
    for (v, &p) in piece.iter().enumerate() {
        if selected(v as u32) {
            touched[p as usize] = true;
        }
    }
    let x = &rest.positions;
    rest.triangles
        .iter()
        .filter(|t| !touched[piece[t[0] as usize] as usize])
        .filter(|t| !is_degenerate_triangle(x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]))
        .copied()
        .collect()
}
