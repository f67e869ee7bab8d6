//! The constraint registry for the Python side: one `_TypeInfo` per type, and the catalogue.

use pyo3::prelude::*;

/// One registered constraint type, as `shapeup.ConstraintType` shows it (the Python side's
/// docstrings list them).
#[pyclass(name = "_TypeInfo", module = "shapeup._shapeup", frozen, get_all)]
pub(crate) struct TypeInfo {
    /// The type's name in scene files and `Solver.add`.
    name: String,
    /// What it acts on, plural ("vertices", "faces", …).
    acts_on: String,
    /// The weight when none is given.
    default_weight: f64,
    /// One line saying what it does.
    summary: String,
    /// Whether it takes translate, rotate, targets, hard.
    has_targets: bool,
    /// (key, "`key` = default and range", meaning) per option.
    options: Vec<(String, String, String)>,
}

/// The registry, in the order of `shapeup types`.
#[pyfunction]
pub(crate) fn constraint_types() -> Vec<TypeInfo> {
    shapeup_core::constraints::registry()
        .iter()
        .map(|t| {
            let options = t
                .options()
                .iter()
                .map(|o| (o.key.to_string(), shapeup_core::constraints::option_markdown(o), o.doc.to_string()))
                .collect();
            TypeInfo {
                name: t.name().into(),
                acts_on: t.element().plural(),
                default_weight: t.default_multiplier(),
                summary: t.summary().into(),
                has_targets: t.has_targets(),
                options,
            }
        })
        .collect()
}

/// The table `shapeup types` prints (Markdown).
#[pyfunction]
pub(crate) fn catalogue_markdown() -> String {
    shapeup_core::constraints::catalogue_markdown()
}
