//! What every builder does: one constraint per selected element, boxed, refused by name when
//! the selection holds none.

use crate::constraints::contract::{BuildContext, Constraint};
use crate::constraints::error::ConstraintError;

/// One constraint per selected vertex, in index order, as `make(i)` builds it (`None`: vertex i
/// gets none), or [`ConstraintError::NothingSelected`] naming `element` when none is built: the
/// build of every per-vertex type.
pub(crate) fn per_selected_vertex<C: Constraint>(
    ctx: &BuildContext,
    kind: &'static str,
    element: &'static str,
    make: impl FnMut(usize) -> Option<C>,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let vertices = (0..ctx.rest.num_vertices()).filter(|&i| ctx.selection.contains(i as u32));
    per_selected_element(vertices, kind, element, make)
}

/// One constraint per element of `elements` (already filtered by the selection), in order, as
/// `make` builds it (`None`: the element gets none), or [`ConstraintError::NothingSelected`]
/// naming `element` when none is built: the build of every per-element type.
pub(crate) fn per_selected_element<E, C: Constraint>(
    elements: impl Iterator<Item = E>,
    kind: &'static str,
    element: &'static str,
    make: impl FnMut(E) -> Option<C>,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let built = elements.filter_map(make).map(|c| Box::new(c) as Box<dyn Constraint>).collect();
    non_empty(built, kind, element)
}

/// `built`, or [`ConstraintError::NothingSelected`] naming `element` when it is empty: a group
/// that constrains nothing is refused, never silently kept.
pub(crate) fn non_empty(
    built: Vec<Box<dyn Constraint>>,
    kind: &'static str,
    element: &'static str,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    if built.is_empty() { Err(ConstraintError::NothingSelected { kind, element }) } else { Ok(built) }
}
