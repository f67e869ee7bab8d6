//! Polygon faces a face type builds on: the selected faces of 4 or more corners, the selected
//! quads, and the `whole_selection` option that trades them for one set over the selection.

use crate::constraints::contract::BuildContext;
use crate::constraints::error::ConstraintError;
use crate::constraints::options::{OptionKind, OptionSpec};

/// `whole_selection`: one plane through every selected vertex instead of one per face.
pub(crate) const WHOLE_SELECTION: OptionSpec = OptionSpec {
    key: "whole_selection",
    doc: "true: one constraint over all the selected vertices; false: one per selected polygon face of 4 or more corners; default false",
    kind: OptionKind::Bool { default: false },
};

/// The polygon faces (corners, in file order) a face-type group builds on: each selected face
/// of 4 or more corners; an [`ConstraintError::Invalid`] when the mesh has none of that size
/// (`why`: what a triangle already satisfies).
pub(crate) fn selected_faces(
    ctx: &BuildContext,
    kind: &'static str,
    why: &str,
) -> Result<Vec<Vec<u32>>, ConstraintError> {
    let faces = &ctx.rest.faces;
    if !faces.iter().any(|corners| corners.len() >= 4) {
        let reason = if faces.is_empty() {
            "it has no faces".to_string()
        } else {
            format!("its {} faces are all triangles, {why}", faces.len())
        };
        return Err(ConstraintError::Invalid {
            kind,
            problem: format!(
                "the mesh has no polygon faces of 4 or more corners ({reason}); \
                 set whole_selection = true for one constraint over the selected vertices"
            ),
        });
    }
    Ok(faces
        .iter()
        .enumerate()
        .filter(|&(f, corners)| corners.len() >= 4 && ctx.selection.contains_face(f, corners))
        .map(|(_, corners)| corners.to_vec())
        .collect())
}

/// The selected quad faces of the input (4 corners as read), for rectangle and parallelogram.
///
/// # Errors
/// [`ConstraintError::Invalid`] when the mesh has no quad face at all (a clear line: the type
/// acts on the input's quads, and which face sizes the mesh has);
/// [`ConstraintError::NothingSelected`] when it has some but none is selected.
pub(crate) fn selected_quads(ctx: &BuildContext, kind: &'static str) -> Result<Vec<[u32; 4]>, ConstraintError> {
    let faces = &ctx.rest.faces;
    if !faces.iter().any(|f| f.len() == 4) {
        let mut sizes: Vec<usize> = faces.iter().map(|f| f.len()).collect();
        sizes.sort_unstable();
        sizes.dedup();
        let has = if sizes.is_empty() {
            "this mesh has no faces".to_string()
        } else {
            let list: Vec<String> = sizes.iter().map(|n| n.to_string()).collect();
            format!("this mesh's faces have {} corners", list.join(", "))
        };
        return Err(ConstraintError::Invalid {
            kind,
            problem: format!(
                "the mesh has no quad faces ({kind} acts on the input's 4-corner faces as read, not on \
                 triangles; {has})"
            ),
        });
    }
    Ok(faces
        .iter()
        .enumerate()
        .filter(|&(f, corners)| corners.len() == 4 && ctx.selection.contains_face(f, corners))
        .map(|(_, c)| [c[0], c[1], c[2], c[3]])
        .collect())
}
