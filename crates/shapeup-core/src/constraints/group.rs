//! The one route from a group description (type, selection, weight, options, targets) to a
//! [`ConstraintGroup`]: scenes, the editor (static and dynamic) and library users all build
//! groups with [`build_group`], so no layer outside a constraint's own file names a concrete
//! type. [`ConstraintGroup`] itself lives here, below the solver that takes it.

use super::contract::{BuildContext, Constraint};
use super::error::ConstraintError;
use super::params::Params;
use super::registry::{build_constraints, constraint_type};
use super::selection::Selection;
use crate::geometry::{RestGeometry, WorkingFrame};
use glam::DVec3;

/// A named set of constraints of one type sharing a multiplier g (w_i = ω_i · g).
#[derive(Debug)]
pub struct ConstraintGroup {
    /// Display name, unique by convention (`"shape"`, `"handle 1"`).
    pub name: String,
    /// Constraint type name (`"edge_spring"`, …).
    pub kind: String,
    /// The multiplier g ≥ 0.
    pub multiplier: f64,
    /// The constraints.
    pub constraints: Vec<Box<dyn Constraint>>,
    /// Hold the group's vertices exactly at their points instead of pulling them there
    /// (default `false`): they leave the linear system, which then covers the other vertices
    /// only, and moving the points changes only the right-hand side (libigl's
    /// `min_quad_with_fixed`). Only for constraints with [`Constraint::held_points`] (position
    /// groups); the multiplier then plays no part and the group adds nothing to E.
    pub hard: bool,
}

impl ConstraintGroup {
    /// A group of `constraints` named `name` with multiplier `multiplier`; its kind is that of
    /// its first constraint.
    pub fn new(name: impl Into<String>, multiplier: f64, constraints: Vec<Box<dyn Constraint>>) -> Self {
        let kind = constraints.first().map(|c| c.kind()).unwrap_or("empty").to_string();
        ConstraintGroup { name: name.into(), kind, multiplier, constraints, hard: false }
    }

    /// Whether its terms are projective ([`Constraint::is_projective`]); a group is of one kind,
    /// so its first term says it (an empty group is).
    pub fn is_projective(&self) -> bool {
        self.constraints.first().is_none_or(|c| c.is_projective())
    }

    /// The group made hard (or soft again): see [`ConstraintGroup::hard`].
    pub fn with_hard(mut self, hard: bool) -> Self {
        self.hard = hard;
        self
    }

    /// Total number of rows of its constraints.
    pub fn num_rows(&self) -> usize {
        self.constraints.iter().map(|c| c.num_rows()).sum()
    }

    /// How far q is from meeting the group: the largest [`Constraint::violation`] of
    /// `C_i q` over its constraints (0 when every term is on its set; in the rows' units, a
    /// length for the point-set types: plane, circle, sphere, line, rigid, …). 0 for a group
    /// with no rows (a load).
    pub fn max_violation(&self, q: &[DVec3]) -> f64 {
        // Any power of 1 is 1: each violation in its rows' units.
        self.relative_violation(q, 1.0)
    }

    /// [`ConstraintGroup::max_violation`] made scale-free: each constraint's violation over
    /// `length` (the mean edge length) to the power of its rows' unit
    /// ([`Constraint::length_power`]): a length over `length`, a ratio as it is, a curvature
    /// times `length`.
    pub fn relative_violation(&self, q: &[DVec3], length: f64) -> f64 {
        self.constraints
            .iter()
            .filter(|c| c.num_rows() > 0)
            .map(|c| c.violation(&c.apply(q)) / length.powi(c.length_power()))
            .fold(0.0, f64::max)
    }
}

/// A handle to a group of a solver's `System`; stays valid until that group is removed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct GroupId(pub u32);

/// A multiplier (or another weight: inertia, a load scale) that is negative or not finite.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("weight must be a finite number ≥ 0, found {0}")]
pub struct WeightError(pub f64);

/// The one test of a weight: finite and ≥ 0. Returns the weight.
///
/// # Errors
/// [`WeightError`] with the value otherwise.
pub fn check_weight(weight: f64) -> Result<f64, WeightError> {
    if weight.is_finite() && weight >= 0.0 { Ok(weight) } else { Err(WeightError(weight)) }
}

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
    let weight = check_weight(description.weight.unwrap_or_else(|| ty.default_multiplier()))
        .map_err(|e| invalid(e.to_string()))?;
    Ok(ConstraintGroup::new(description.name.clone(), weight, constraints).with_hard(hard))
}

/// The points a group's constraints hold their vertices at, concatenated in constraint order
/// ([`super::Constraint::held_points`]), with those vertices: what
/// the solver's `System::set_targets` takes, in this order.
pub fn held_vertices(group: &ConstraintGroup) -> Vec<u32> {
    group.constraints.iter().filter_map(|c| c.held_points()).flat_map(|(v, _)| v.iter().copied()).collect()
}
