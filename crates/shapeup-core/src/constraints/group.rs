//! The one route from a group description (type, selection, weight, options, targets) to a
//! [`ConstraintGroup`]: scenes, the editor (static and dynamic) and library users all build
//! groups with [`build_group`], so no layer outside a constraint's own file names a concrete
//! type.

use super::{BuildContext, ConstraintError, Params, Selection, build_constraints, constraint_type};
use crate::geometry::{RestGeometry, WorkingFrame};
use crate::solver::ConstraintGroup;
use glam::DVec3;

/// A constraint group as users describe it.
#[derive(Debug, Clone)]
pub struct GroupDescription {
    /// Constraint type name, as in scene files (`"plane"`).
    pub kind: String,
    /// Group name (scenes default it to the type).
    pub name: String,
    /// Multiplier g; `None` for the type's default.
    pub weight: Option<f64>,
    /// The vertices or faces it applies to.
    pub selection: Selection,
    /// Type options, and the common `hard` (`true`: hold the group's vertices exactly; only
    /// for types with targets).
    pub options: Params,
    /// For types with targets ([`super::ConstraintType::has_targets`]): where each held vertex
    /// goes (working frame), as (vertex, point) pairs; `None` keeps them at rest. Every held
    /// vertex needs a pair.
    pub targets: Option<Vec<(u32, DVec3)>>,
}

impl GroupDescription {
    /// A group of type `kind` named after it, on `selection`, with the type's default weight
    /// and options.
    pub fn new(kind: &str, selection: Selection) -> Self {
        GroupDescription {
            kind: kind.into(),
            name: kind.into(),
            weight: None,
            selection,
            options: Params::default(),
            targets: None,
        }
    }

    /// Sets an option.
    pub fn with(mut self, key: &str, value: impl Into<serde_json::Value>) -> Self {
        self.options = self.options.with(key, value);
        self
    }

    /// Sets the multiplier.
    pub fn weight(mut self, weight: f64) -> Self {
        self.weight = Some(weight);
        self
    }
}

/// Builds the group a description asks for on the rest shape (working frame; `frame` converts
/// options given in input units).
///
/// # Errors
/// [`ConstraintError`] for an unknown type or option, a bad value, a selection with nothing
/// to constrain, `hard` on a type without targets, or targets that do not match the held
/// vertices.
pub fn build_group(
    description: &GroupDescription,
    rest: &RestGeometry,
    frame: &WorkingFrame,
) -> Result<ConstraintGroup, ConstraintError> {
    let ty = constraint_type(&description.kind)?;
    let kind = ty.name();
    let mut params = description.options.clone();
    let hard = params.take_bool(kind, "hard", false)?;
    let ctx = BuildContext { rest, selection: &description.selection, frame };
    let mut constraints = build_constraints(kind, &ctx, params)?;
    let invalid = |problem: String| ConstraintError::Invalid { kind, problem };
    if hard && constraints.iter().any(|c| c.held_points().is_none()) {
        return Err(invalid("\"hard = true\" is for groups that hold vertices at targets (position)".into()));
    }
    if let Some(pairs) = &description.targets {
        if !ty.has_targets() {
            return Err(invalid("takes no targets (translate, rotate, targets, spin)".into()));
        }
        let mut at = std::collections::HashMap::with_capacity(pairs.len());
        for &(v, p) in pairs {
            if !p.is_finite() {
                return Err(invalid(format!("the target of vertex {v} is not finite")));
            }
            at.insert(v, p);
        }
        for c in &mut constraints {
            let Some((vertices, _)) = c.held_points() else { continue };
            let targets = vertices
                .iter()
                .map(|v| at.get(v).copied().ok_or_else(|| invalid(format!("vertex {v} has no target"))))
                .collect::<Result<Vec<_>, _>>()?;
            if !c.set_targets(&targets) {
                return Err(invalid("its constraints do not take targets".into()));
            }
        }
    }
    let weight = description.weight.unwrap_or_else(|| ty.default_multiplier());
    if !(weight.is_finite() && weight >= 0.0) {
        return Err(invalid(format!("weight must be a finite number ≥ 0, found {weight}")));
    }
    Ok(ConstraintGroup::new(description.name.clone(), weight, constraints).with_hard(hard))
}

/// The points a group's constraints hold their vertices at, concatenated in constraint order
/// ([`super::Constraint::held_points`]), with those vertices: what
/// [`crate::solver::System::set_targets`] takes, in this order.
pub fn held_vertices(group: &ConstraintGroup) -> Vec<u32> {
    group.constraints.iter().filter_map(|c| c.held_points()).flat_map(|(v, _)| v.iter().copied()).collect()
}
