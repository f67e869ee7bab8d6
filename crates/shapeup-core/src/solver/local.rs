//! Local step: every constraint's projection P_i = p_i(q), in parallel.
//!
//! The projection buffer is split into each constraint's disjoint rows by recursive halving
//! (rayon::join), so the parallel loop needs no locks, no unsafe code and no allocation.

use crate::constraints::Constraint;
use glam::DVec3;

/// Constraints per task below which the projections run sequentially.
const GRAIN: usize = 512;

/// Writes p_i(q) of `constraints[k]` into `out[offsets[k] - offsets[0]..offsets[k+1] - offsets[0]]`.
pub(crate) fn project_all(constraints: &[Box<dyn Constraint>], offsets: &[usize], q: &[DVec3], out: &mut [DVec3]) {
    if constraints.len() <= GRAIN {
        let base = offsets[0];
        for (k, c) in constraints.iter().enumerate() {
            c.project(q, &mut out[offsets[k] - base..offsets[k + 1] - base]);
        }
        return;
    }
    let mid = constraints.len() / 2;
    let (out_a, out_b) = out.split_at_mut(offsets[mid] - offsets[0]);
    rayon::join(
        || project_all(&constraints[..mid], &offsets[..=mid], q, out_a),
        || project_all(&constraints[mid..], &offsets[mid..], q, out_b),
    );
}
