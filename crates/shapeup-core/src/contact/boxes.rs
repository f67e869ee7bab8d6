//! Boxes in parry's types: the boxes of elements the contact's BVHs hold (the point conversion
//! is `crate::nearest`'s). Beneath the self-collision detection, the crossing check, the
//! colliders' features and the mesh collider's queries.

pub(crate) use crate::nearest::{from_parry, to_parry};
use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;

/// The box around `points`, grown by `grow` on every side.
pub(crate) fn aabb(points: impl IntoIterator<Item = DVec3>, grow: f64) -> Aabb {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for p in points {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    Aabb::new(to_parry(lo - DVec3::splat(grow)), to_parry(hi + DVec3::splat(grow)))
}

/// The box around the points of `vertices` at `start` and at `predicted` less `drift`, grown
/// by `grow`: the element's sweep in a frame that moves by `drift` over the step. Distances
/// at each instant are the same in any frame that translates, so two elements that come
/// within the thickness during the step still have meeting boxes; taking out the motion the
/// surface shares keeps the boxes small.
pub(crate) fn swept_box(vertices: &[u32], start: &[DVec3], predicted: &[DVec3], drift: DVec3, grow: f64) -> Aabb {
    aabb(vertices.iter().flat_map(|&v| [start[v as usize], predicted[v as usize] - drift]), grow)
}
