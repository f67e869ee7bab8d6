//! Contact: colliders, self-collision and Coulomb friction, inside the projective solver
//! without refactoring its matrix (math reference, "Contact").
//!
//! Layers: [`shape`] (closest point and signed distance of each collider shape), [`collider`]
//! (a shape, its friction and rigid motion), a contact's linear gap (`gap`), the
//! self-collision broad and narrow phase, the contacts of colliders' corners, edges and
//! ridges with the surface's triangles and edges (`features`),
//! [`model`] (detection per step, contact targets per iteration, projection at the end), and
//! [`spec`] (the one description of a collider and of `[contact]` that scenes, the command
//! line, the editor and Python share). [`solve_with_contact`] is the iteration a time step
//! or a static solve runs when something can touch.

mod boxes;
mod closest;
pub mod collider;
mod crossing;
mod features;
mod gap;
pub mod model;
mod self_collision;
pub mod shape;
pub mod spec;

pub use collider::{Collider, Motion};
pub use model::{ContactModel, ContactParams, ContactStats};
pub use shape::{MeshShape, Proximity, Shape};
pub use spec::{
    COLLIDER_TYPES, ColliderError, ColliderSpec, ContactSettings, DEFAULT_THICKNESS_FRACTION,
    MAX_SELF_THICKNESS_FRACTION, ShapeSpec, mesh_placement,
};

use crate::solver::{SolveError, SolveReport, System};
use glam::DVec3;
use rayon::prelude::*;
use std::time::Instant;

/// Σ f(v) over `vertices`, the same bits at every thread count: fixed chunks summed in order,
/// then their sums in order (rayon's `sum` splits by thread count, and a step at 1 and at 2
/// threads drifted apart from a last-bit difference in the self-collision frame).
pub(crate) fn ordered_sum(vertices: &[u32], f: impl Fn(u32) -> DVec3 + Sync) -> DVec3 {
    const CHUNK: usize = 4096;
    let partial: Vec<DVec3> = vertices.par_chunks(CHUNK).map(|c| c.iter().map(|&v| f(v)).sum()).collect();
    partial.iter().sum()
}

/// `iterations` local-global iterations from q with contact (see [`model`]): each a local
/// step (the constraints' projections, then the contact targets at the same q) and a global
/// step with W_v p_v on its right-hand side. The system must carry the contact weights
/// ([`System::set_contact_weights`], from [`ContactModel::weights`]). The iterations are plain
/// ones: the contact targets change with the detection of each step, so the accelerations'
/// histories do not apply; `report.energies` stays empty.
///
/// # Errors
/// As [`System::global_step`]; [`SolveError::WrongLength`] when the system has no contact
/// weights. The system's contact forces are cleared whatever happens.
pub fn solve_with_contact(
    system: &mut System,
    contact: &mut ContactModel,
    q: &mut [DVec3],
    iterations: usize,
) -> Result<SolveReport, SolveError> {
    let mut report = SolveReport::default();
    let t = Instant::now();
    system.prepare()?;
    let weights =
        system.contact_weights().map(<[f64]>::to_vec).ok_or(SolveError::WrongLength { expected: q.len(), found: 0 })?;
    report.setup_seconds += t.elapsed().as_secs_f64();
    let result = (|| {
        for _ in 0..iterations {
            let t = Instant::now();
            system.local_step(q)?;
            let targets = contact.targets(q, &weights);
            report.local_seconds += t.elapsed().as_secs_f64();
            let t = Instant::now();
            system.set_contact_forces(targets)?;
            system.global_step(q)?;
            report.global_seconds += t.elapsed().as_secs_f64();
        }
        Ok(())
    })();
    system.clear_contact_forces();
    result.map(|()| report)
}
