//! [`Force`]: a constant load on one vertex, the constraint of both the `force` and the
//! `gravity` types (module docs of `types/force.rs` and `types/gravity.rs`).

use crate::constraints::contract::{Constraint, Load, RowSink};
use glam::DVec3;

/// A constant force on one vertex: a [`Load`] without rows. Also what `gravity` builds.
#[derive(Debug, Clone)]
pub struct Force {
    kind: &'static str,
    vertex: [u32; 1],
    force: [DVec3; 1],
    rest: [DVec3; 1],
}

impl Force {
    /// The force `force` (working frame) on `vertex` at rest position `rest`.
    pub fn new(vertex: u32, force: DVec3, rest: DVec3) -> Self {
        Force::of_kind("force", vertex, force, rest)
    }

    /// The same, reporting `kind` as its type name (`gravity`).
    pub(crate) fn of_kind(kind: &'static str, vertex: u32, force: DVec3, rest: DVec3) -> Self {
        Force { kind, vertex: [vertex], force: [force], rest: [rest] }
    }

    /// The force (working frame).
    pub fn force(&self) -> DVec3 {
        self.force[0]
    }
}

impl Constraint for Force {
    fn kind(&self) -> &'static str {
        self.kind
    }
    fn vertices(&self) -> &[u32] {
        &self.vertex
    }
    fn load(&self) -> Option<Load<'_>> {
        Some(Load { vertices: &self.vertex, forces: &self.force, rest: &self.rest })
    }
    fn element_weight(&self) -> f64 {
        1.0
    }
    fn num_rows(&self) -> usize {
        0
    }
    fn rows(&self, _sink: &mut RowSink) {}
    fn project(&self, _q: &[DVec3], _out: &mut [DVec3]) {}
    fn set_residual(&self, p: &[DVec3]) -> f64 {
        // The set of zero rows has one point, the empty one; anything else is off it.
        p.iter().map(|x| x.length()).fold(0.0, f64::max)
    }
}
