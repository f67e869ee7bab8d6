//! The registry: every constraint type, found by name, and the catalogue printed from it.
//!
//! Adding a type: write `types/x.rs` (a [`Constraint`] and a unit struct implementing
//! [`ConstraintType`], importing only the contract and `kit/`) and add its one line to the
//! `types!` list in `types/mod.rs`, at the place menus should show it. That line declares the
//! module, re-exports its names from `shapeup_core::constraints` and puts it in [`registry`];
//! scenes, the CLI, the editor, Python and the shared tests (`tests/constraints/`) then know it.
//! The README and the scene contract print [`catalogue_markdown`] (a test keeps them equal).

use super::contract::{BuildContext, Constraint, ConstraintType};
use super::error::ConstraintError;
use super::options::option_markdown;
use super::params::Params;
use super::types;

/// Every constraint type, in the order menus list them.
pub fn registry() -> &'static [&'static dyn ConstraintType] {
    types::ALL
}

/// The registry as a Markdown table (type, elements, default weight, options, summary): what
/// `shapeup types` prints and the README and the scene contract show (a test keeps them equal).
pub fn catalogue_markdown() -> String {
    let mut out = String::from(
        "| type | acts on | default weight | options (default, range) | what it does |\n|---|---|---:|---|---|\n",
    );
    for ty in registry() {
        let options: Vec<String> = ty.options().iter().map(option_markdown).collect();
        let mut options = if options.is_empty() { "—".to_string() } else { options.join("; ") };
        if ty.has_targets() {
            options.push_str("; targets: translate, rotate, targets, spin, hard");
        }
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            ty.name(),
            ty.element().plural(),
            ty.default_multiplier(),
            options,
            ty.summary().replace('|', "\\|")
        ));
    }
    out
}

/// The names of every constraint type.
pub fn type_names() -> Vec<&'static str> {
    registry().iter().map(|t| t.name()).collect()
}

/// Looks a constraint type up by name.
///
/// # Errors
/// [`ConstraintError::UnknownType`] listing the known names.
pub fn constraint_type(name: &str) -> Result<&'static dyn ConstraintType, ConstraintError> {
    registry()
        .iter()
        .copied()
        .find(|t| t.name() == name)
        .ok_or_else(|| ConstraintError::UnknownType { name: name.to_string(), known: type_names() })
}

/// Builds the constraints of a type on a selection: looks up `kind`, passes `params` and rejects
/// options it did not take.
///
/// # Errors
/// As [`constraint_type`] and [`ConstraintType::build`], and an unknown option.
pub fn build_constraints(
    kind: &str,
    ctx: &BuildContext,
    mut params: Params,
) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
    let ty = constraint_type(kind)?;
    let built = ty.build(ctx, &mut params)?;
    params.finish(ty.name(), ty.options())?;
    Ok(built)
}
