//! The surface that selected pieces follow (`attachment`).

use crate::geometry::{RestGeometry, is_degenerate_triangle};

/// The triangles (with area at rest) of the pieces ([`RestGeometry::pieces`]) that hold no
/// vertex `selected` says: the surface the selected pieces follow. Lazy, so that a menu asking
/// whether there is one stops at the first.
pub(crate) fn unselected_piece_triangles<'a>(
    rest: &'a RestGeometry,
    selected: impl Fn(u32) -> bool,
) -> impl Iterator<Item = [u32; 3]> + 'a {
    let (piece, count) = &rest.pieces;
    let mut touched = vec![false; *count];
    for (v, &p) in piece.iter().enumerate() {
        if selected(v as u32) {
            touched[p as usize] = true;
        }
    }
    let x = &rest.positions;
    rest.triangles
        .iter()
        .filter(move |t| !touched[piece[t[0] as usize] as usize])
        .filter(|t| !is_degenerate_triangle(x[t[0] as usize], x[t[1] as usize], x[t[2] as usize]))
        .copied()
}
