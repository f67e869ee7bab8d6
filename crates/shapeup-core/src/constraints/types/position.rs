//! Position (a handle): pulls a set of vertices to target points.
//!
//! Term: ω ‖Q_S − Y‖² with Q_S the |S| selected positions (one row each), p = Y the targets,
//! ω = 1. Targets can change between solves without refactoring ([`Position::set_targets`]).

use crate::constraints::contract::{TypeInfo, BuildContext, Constraint, ConstraintType, RowSink};
use crate::constraints::error::ConstraintError;
use crate::constraints::kit::build::non_empty;
use crate::constraints::params::Params;
use crate::constraints::selection::Element;
use glam::DVec3;

/// A position group: vertices S pulled to targets Y (one row per vertex).
#[derive(Debug, Clone)]
pub struct Position {
    vertices: Vec<u32>,
    targets: Vec<DVec3>,
}

impl Position {
    /// Pulls `vertices[k]` to `targets[k]`; `None` if the lengths differ or the set is empty.
    pub fn new(vertices: Vec<u32>, targets: Vec<DVec3>) -> Option<Self> {
        (vertices.len() == targets.len() && !vertices.is_empty()).then_some(Position { vertices, targets })
    }

    /// The current targets, one per vertex (working frame).
    pub fn targets(&self) -> &[DVec3] {
        &self.targets
    }

    /// Replaces the targets; returns `false` (and changes nothing) if the count differs.
    /// Only the projection changes, so the factorization stays valid.
    pub fn set_targets(&mut self, targets: &[DVec3]) -> bool {
        if targets.len() != self.targets.len() {
            return false;
        }
        self.targets.copy_from_slice(targets);
        true
    }
}

impl Constraint for Position {
    fn kind(&self) -> &'static str {
        "position"
    }
    fn vertices(&self) -> &[u32] {
        &self.vertices
    }
    fn held_points(&self) -> Option<(&[u32], &[DVec3])> {
        Some((&self.vertices, &self.targets))
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        self.vertices.len()
    }
    fn rows(&self, sink: &mut RowSink) {
        for (row, &v) in self.vertices.iter().enumerate() {
            sink.push(row, v, 1.0);
        }
    }
    fn set_targets(&mut self, targets: &[DVec3]) -> bool {
        Position::set_targets(self, targets)
    }
    fn project(&self, _q: &[DVec3], out: &mut [DVec3]) {
        out.copy_from_slice(&self.targets);
    }
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        crate::constraints::kit::sets::max_distance(p, &self.targets)
    }
}

/// Builds one [`Position`] over the selected vertices, targets at their rest positions (a
/// fixed handle); scenes then move the targets (translate, rotate, explicit targets).
#[derive(Debug, Clone, Copy)]
pub struct PositionType;

/// What menus, scenes, the catalogue and the shared tests read of this type.
const INFO: TypeInfo = TypeInfo {
    name: "position",
    summary: "position (handle): selected vertices pulled to targets",
    options: &[],
    element: Element::VertexSet { min: 1 },
    default_multiplier: 1.0,
    has_targets: true,
    rigidly_invariant: true,
};

impl ConstraintType for PositionType {
    fn info(&self) -> &'static TypeInfo {
        &INFO
    }
    fn build(&self, ctx: &BuildContext, _params: &mut Params) -> Result<Vec<Box<dyn Constraint>>, ConstraintError> {
        let rest = &ctx.rest.positions;
        let vertices: Vec<u32> = (0..rest.len() as u32).filter(|&v| ctx.selection.contains(v)).collect();
        let targets = vertices.iter().map(|&v| rest[v as usize]).collect();
        let built = Position::new(vertices, targets).map(|c| Box::new(c) as Box<dyn Constraint>).into_iter().collect();
        non_empty(built, "position", "vertices")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_is_the_targets_and_energy_their_distance() {
        let mut c = Position::new(vec![1, 2], vec![DVec3::X, DVec3::Y]).unwrap();
        let q = [DVec3::ZERO, DVec3::ZERO, DVec3::Y];
        assert_eq!(c.apply(&q), vec![DVec3::ZERO, DVec3::Y]);
        assert!((c.energy(&q) - 1.0).abs() < 1e-15);
        assert!(c.set_targets(&[DVec3::ZERO, DVec3::Y]));
        assert_eq!(c.energy(&q), 0.0);
        assert!(!c.set_targets(&[DVec3::ZERO]), "wrong count is refused");
    }
}
