//! Contacts between a collider's features and the surface's triangles and edges: what keeps a
//! box's edge or corner, a mesh collider's ridge or a small sphere from cutting into a surface
//! whose vertices are all outside (each vertex has its own contact with each collider, see
//! [`super::model`]).
//!
//! A collider's features ([`Features::of`], rest pose) are points with a radius ρ (a sphere's
//! centre and a capsule's ends, ρ its radius; a box's corners and a mesh's ridge vertices,
//! ρ = 0) and segments (a capsule's axis; a box's edges and a mesh's ridges,
//! [`MeshShape::ridges`](super::shape::MeshShape::ridges)). Each step, every feature swept
//! over the step (in the frame that moves with the surface's mean motion, as the
//! self-collision boxes are) queries the BVH of the surface's triangles (a point) or edges (a
//! segment, in pieces of [`PIECE_THICKNESSES`] thicknesses so that a long box edge across a
//! cloth meets only the edges near it). The narrow phase at x_n makes a contact of the
//! closest points when they are closer than ρ + thickness plus twice their relative predicted
//! motion: g(q) = n · Σ_j α_j q_j − (n · P(t1) + d), where Σ_j α_j q_j is the surface's point
//! (barycentric coordinates α, Σ α = 1), P the feature's point and n the normal from P to it
//! at x_n, both carried by the collider's motion to the step's end, and d = ρ + thickness (a
//! pair already closer gets back [`RECOVERY`] of the way per step, as a self contact does).
//!
//! A contact is made only where the vertices' own contacts do not already hold it: the
//! surface's closest point must be inside a triangle or an edge (not at a vertex), the
//! feature's inside its segment (an end is a point feature of its own), and the surface's
//! point must lie far enough from the element's vertices that they could be kept at the
//! distance while it is a tenth of the thickness closer. A vertex at distance r from that
//! point, seen along the feature, is √(a² + r²) from the feature when the point is at
//! a = ρ + t, which is a + t/10 or more when r² ≥ t a/5 + t²/100 ([`needs_own_contact`]). So a
//! large sphere under a fine cloth adds none (r² ≈ ℓ²/4 < t R/5), a box's edge under it does.
//! A surface point that starts inside the collider (an edge pulled into a thin bar, a
//! triangle over a box's corner that points up) takes its normal from the side its element's
//! vertices are on, their outward normals weighted by α, where that points away from P; the
//! offset from P could point inward ([`contact_normal`]). Where the vertices are inside too,
//! their own contacts take them out first.

use super::boxes::aabb;
use super::closest::{closest_between_segments, closest_on_triangle};
use super::collider::Collider;
use super::gap::Pair;
use super::self_collision::{RECOVERY, Surface};
use super::shape::Shape;
use glam::DVec3;
use parry3d_f64::bounding_volume::{Aabb, BoundingVolume};
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use rayon::prelude::*;

/// A collider's points and segments that can cut into a surface (rest pose).
#[derive(Debug, Clone, Default)]
pub(crate) struct Features {
    points: Vec<DVec3>,
    segments: Vec<[DVec3; 2]>,
    /// ρ: the collider is the points within ρ of its features (sphere, capsule), else 0.
    radius: f64,
    /// Mesh colliders: a BVH over the points, then the segments (rest pose), which finds those
    /// near the surface among many.
    bvh: Option<Bvh>,
}

/// A collider contact with a triangle or an edge of the surface, with the collider's μ, the
/// collider's motion over the step at its point, and the feature where it is at the step's
/// end (for [`FeatureContact::project`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct FeatureContact {
    pub(crate) pair: Pair,
    pub(crate) friction: f64,
    pub(crate) shift: DVec3,
    /// The feature at the step's end: a point, or a segment's ends.
    end: FeatureAt,
    /// ρ + thickness.
    reach: f64,
    /// ρ > 0: a sphere's or a capsule's.
    pub(crate) round: bool,
}

/// A feature where it is at one instant.
#[derive(Debug, Clone, Copy)]
enum FeatureAt {
    Point(DVec3),
    Segment(DVec3, DVec3),
}

impl FeatureContact {
    /// The closest points of the feature (where it is at the step's end) and the surface's
    /// element at `q`: the element's coordinates α, the direction from the feature's point to
    /// the element's (the step's normal when that is on the wrong side of it) and the distance
    /// along it. `None` past an end of the element or of a segment feature (the vertices' and
    /// the point features' own contacts).
    fn closest_at(&self, q: &[DVec3]) -> Option<([f64; 4], DVec3, f64)> {
        let (alpha, offset) = match self.end {
            FeatureAt::Point(p) => {
                let t = [self.pair.vertices[0], self.pair.vertices[1], self.pair.vertices[2]];
                let (c, b) = closest_on_triangle(p, t.map(|v| q[v as usize]));
                ([b[0], b[1], b[2], 0.0], c - p)
            }
            FeatureAt::Segment(a, b) => {
                let [e0, e1] = [self.pair.vertices[0], self.pair.vertices[1]];
                let (s, u, on_edge, on_feature) = closest_between_segments(q[e0 as usize], q[e1 as usize], a, b);
                if s <= 0.0 || s >= 1.0 || u <= 0.0 || u >= 1.0 {
                    return None;
                }
                ([1.0 - s, s, 0.0, 0.0], on_edge - on_feature)
            }
        };
        let length = offset.length();
        let normal = self.pair.normal;
        let direction = if length > 1e-12 && offset.dot(normal) > 0.0 { offset / length } else { normal };
        Some((alpha, direction, offset.dot(direction)))
    }

    /// What makes two contacts the same one: the surface's element and the feature where it
    /// ends the step.
    pub(crate) fn key(&self) -> ([u32; 4], [u64; 6]) {
        let bits = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let end = match self.end {
            FeatureAt::Point(p) => [bits(p), [0; 3]],
            FeatureAt::Segment(a, b) => [bits(a), bits(b)],
        };
        (self.pair.vertices, [end[0][0], end[0][1], end[0][2], end[1][0], end[1][1], end[1][2]])
    }

    /// The vertices of the surface's element with α ≠ 0 at `q` when it is within the reach
    /// plus `tolerance` of the feature (it touches the collider).
    pub(crate) fn touching(&self, q: &[DVec3], tolerance: f64) -> Option<impl Iterator<Item = u32> + '_> {
        let (alpha, _, distance) = self.closest_at(q)?;
        (distance <= self.reach + tolerance)
            .then(move || self.pair.vertices.into_iter().zip(alpha).filter(|(_, a)| *a != 0.0).map(|(v, _)| v))
    }

    /// The end-of-step projection of the contact (after the vertices' own): its closest points
    /// taken again at `q` (the surface may have slid along the feature during the step, which
    /// moves them off the fixed α of the step's gap), and the surface's element moved out to
    /// the reach along their direction (the step's normal when they are on the wrong side of
    /// it), its vertices by α_j w_j / Σ α_k² w_k with w = `inverse_mass`; `give` of the reach
    /// is left (the surface is moved out to the reach less it, when closer). Whether it moved
    /// anything.
    pub(crate) fn project(&self, q: &mut [DVec3], inverse_mass: &[f64], give: f64) -> bool {
        let Some((alpha, direction, distance)) = self.closest_at(q) else { return false };
        let depth = self.reach - give - distance;
        let terms = || self.pair.vertices.iter().zip(alpha).map(|(&v, a)| (v as usize, a));
        let w: f64 = terms().map(|(v, a)| a * a * inverse_mass[v]).sum();
        if depth <= 0.0 || w <= 0.0 {
            return false;
        }
        for (v, a) in terms() {
            q[v] += (depth * a * inverse_mass[v] / w) * direction;
        }
        true
    }
}

/// The length of the pieces a segment feature queries the edge BVH in, in thicknesses.
pub const PIECE_THICKNESSES: f64 = 8.0;

/// Most pieces of one segment.
const MAX_PIECES: usize = 4096;

impl Features {
    /// The features of `shape` (see the [module docs](self)); a plane has none (a surface
    /// whose vertices are above it is above it).
    pub(crate) fn of(shape: &Shape) -> Self {
        match shape {
            Shape::Plane { .. } => Features::default(),
            Shape::Sphere { center, radius } => {
                Features { points: vec![*center], radius: *radius, ..Default::default() }
            }
            Shape::Capsule { a, b, radius } => Features {
                points: vec![*a, *b],
                segments: if a == b { Vec::new() } else { vec![[*a, *b]] },
                radius: *radius,
                bvh: None,
            },
            Shape::Box { center, half, rotation } => {
                let corner = |k: usize| {
                    let sign = |bit: usize| if k & (1 << bit) == 0 { -1.0 } else { 1.0 };
                    *center + *rotation * (*half * DVec3::new(sign(0), sign(1), sign(2)))
                };
                let points: Vec<DVec3> = (0..8).map(corner).collect();
                // Corners that differ in one bit share an edge; a flat box's zero-length ones
                // are its corners.
                let segments = (0..8)
                    .flat_map(|k| (0..3).map(move |bit| (k, k | (1 << bit))))
                    .filter(|&(k, l)| k != l && points[k] != points[l])
                    .map(|(k, l)| [points[k], points[l]])
                    .collect();
                Features { points, segments, radius: 0.0, bvh: None }
            }
            Shape::Mesh(mesh) => {
                let (points, segments) = mesh.ridges();
                let boxes: Vec<Aabb> =
                    points.iter().map(|p| aabb([*p], 0.0)).chain(segments.iter().map(|s| aabb(*s, 0.0))).collect();
                let bvh = (!boxes.is_empty()).then(|| Bvh::from_leaves(BvhBuildStrategy::Binned, &boxes));
                Features { points, segments, radius: 0.0, bvh }
            }
        }
    }

    /// Whether there are point features.
    pub(crate) fn has_points(&self) -> bool {
        !self.points.is_empty()
    }

    /// Whether the collider is the points within ρ > 0 of its features (a sphere, a capsule).
    pub(crate) fn is_round(&self) -> bool {
        self.radius > 0.0
    }

    /// Whether there are segment features.
    pub(crate) fn has_segments(&self) -> bool {
        !self.segments.is_empty()
    }

    /// Whether the points, and whether the segments, can make a contact with a surface whose
    /// longest edge is `longest`: a point of a triangle is at most ℓ/√3 from its nearest
    /// corner, a point of an edge ℓ/2 from its nearer end, so when no element is that long
    /// none passes [`needs_own_contact`] (a large sphere under a fine cloth) and the step
    /// neither refits the surface's trees for them nor queries them.
    pub(crate) fn can_cut(&self, longest: f64, thickness: f64) -> (bool, bool) {
        let reach = self.radius + thickness;
        let square = longest * longest;
        (
            self.has_points() && needs_own_contact(square / 3.0, thickness, reach),
            self.has_segments() && needs_own_contact(square / 4.0, thickness, reach),
        )
    }
}

/// The length of the longest edge of the surface at `x`.
pub(crate) fn longest_edge(surface: &Surface, x: &[DVec3]) -> f64 {
    surface
        .edges()
        .par_iter()
        .map(|[a, b]| (x[*a as usize] - x[*b as usize]).length_squared())
        .reduce(|| 0.0, f64::max)
        .sqrt()
}

/// Whether a surface point at a = ρ + t from a feature needs a contact of its own, its nearest
/// vertex being `r2` = r² from it seen along the feature (see the [module docs](self)).
fn needs_own_contact(r2: f64, thickness: f64, reach: f64) -> bool {
    r2 >= 0.2 * thickness * reach + 0.01 * thickness * thickness
}

/// [`needs_own_contact`] at x_n, or after the surface slides along the feature by up to
/// twice its relative predicted `motion` and [`PREDICTION_SLACK`] thicknesses more within the
/// step (a fold rolling over a box's edge moves the closest point from near a vertex to the
/// middle of an edge).
fn may_need_own_contact(r2: f64, motion: f64, thickness: f64, reach: f64) -> bool {
    let farthest = r2.sqrt() + 2.0 * motion + PREDICTION_SLACK * thickness;
    needs_own_contact(r2, thickness, reach) || needs_own_contact(farthest * farthest, thickness, reach)
}

/// How far (in thicknesses) a vertex may end from its prediction before the end of the step
/// looks for the colliders' feature contacts again over the path it took.
pub(crate) const PREDICTION_SLACK: f64 = 0.25;

/// One feature of one collider, as the detection visits it.
#[derive(Debug, Clone, Copy)]
enum Feature {
    Point(DVec3),
    /// A segment's ends and the piece [k/K, (k+1)/K] of it.
    Piece([DVec3; 2], usize, usize),
}

/// The contacts of the step between the colliders' `features` (one per collider) and the
/// surface moving from `start` to `predicted` (see the [module docs](self)), `longest` its
/// longest edge over the step ([`Features::can_cut`]). The surface's trees hold its boxes
/// swept to positions within `slack` of `predicted` ([`Surface::refit`] to them, `slack` 0; or
/// to the step's prediction when `predicted` is where the step ended, `slack` the farthest a
/// vertex ended from it: the features' boxes grow by it).
#[allow(clippy::too_many_arguments)]
pub(crate) fn detect_feature_contacts(
    surface: &Surface,
    colliders: &[Collider],
    features: &[Features],
    start: &[DVec3],
    predicted: &[DVec3],
    thickness: f64,
    longest: f64,
    slack: f64,
    (t0, t1): (f64, f64),
) -> Vec<FeatureContact> {
    if surface.triangles().is_empty() {
        return Vec::new();
    }
    let surface_box = || {
        let points = surface.vertices().iter().flat_map(|&v| [start[v as usize], predicted[v as usize]]);
        let b = aabb(points, 0.0);
        (DVec3::new(b.mins.x, b.mins.y, b.mins.z), DVec3::new(b.maxs.x, b.maxs.y, b.maxs.z))
    };
    let mut tasks: Vec<(usize, Feature)> = Vec::new();
    for (k, (collider, f)) in colliders.iter().zip(features).enumerate() {
        let (points, segments) = f.can_cut(longest, thickness);
        if !points && !segments {
            continue;
        }
        let add_segment = |tasks: &mut Vec<(usize, Feature)>, i: usize| {
            if !segments {
                return;
            }
            let [a, b] = f.segments[i];
            let pieces = ((a - b).length() / (PIECE_THICKNESSES * thickness)).ceil();
            let pieces = if pieces.is_finite() { (pieces as usize).clamp(1, MAX_PIECES) } else { 1 };
            tasks.extend((0..pieces).map(|j| (k, Feature::Piece([a, b], j, pieces))));
        };
        match &f.bvh {
            None => {
                if points {
                    tasks.extend(f.points.iter().map(|p| (k, Feature::Point(*p))));
                }
                (0..f.segments.len()).for_each(|i| add_segment(&mut tasks, i));
            }
            Some(bvh) => {
                // The surface's box over the step, in the collider's rest pose at t0 and at t1:
                // the features that can come near it.
                let (lo, hi) = surface_box();
                let corners = (0..8).map(|c: usize| {
                    DVec3::new(
                        if c & 1 == 0 { lo.x } else { hi.x },
                        if c & 2 == 0 { lo.y } else { hi.y },
                        if c & 4 == 0 { lo.z } else { hi.z },
                    )
                });
                let motion = &collider.motion;
                let rest = corners.flat_map(|p| [motion.invert(p, t0), motion.invert(p, t1)]);
                let query = aabb(rest, f.radius + thickness + slack);
                for leaf in bvh.intersect_aabb(&query) {
                    let leaf = leaf as usize;
                    if leaf < f.points.len() {
                        if points {
                            tasks.push((k, Feature::Point(f.points[leaf])));
                        }
                    } else {
                        add_segment(&mut tasks, leaf - f.points.len());
                    }
                }
            }
        }
    }
    let (triangle_bvh, edge_bvh) = (surface.triangle_bvh(), surface.edge_bvh());
    let drift = surface.drift();
    tasks
        .par_iter()
        .flat_map_iter(|&(k, feature)| {
            let (collider, radius) = (&colliders[k], features[k].radius);
            let motion = &collider.motion;
            let at = move |p: DVec3, t: f64| if motion.is_static() { p } else { motion.apply(p, t) };
            let middle = 0.5 * (t0 + t1);
            // The feature's sweep over the step, less the surface's mean motion, grown by ρ and
            // half the thickness (the surface's boxes carry the other half).
            let swept = |p: DVec3| [at(p, t0), at(p, middle) - 0.5 * drift, at(p, t1) - drift];
            let grow = radius + 0.5 * thickness + slack;
            let found: Vec<FeatureContact> = match feature {
                Feature::Point(p) => {
                    let Some(bvh) = triangle_bvh else { return Vec::new().into_iter() };
                    bvh.intersect_aabb(&aabb(swept(p), grow))
                        .filter_map(|i| {
                            let triangle = surface.triangles()[i as usize];
                            let (p0, p1) = (at(p, t0), at(p, t1));
                            point_triangle_contact(
                                collider,
                                radius,
                                [p0, p1],
                                triangle,
                                (start, predicted),
                                thickness,
                                (t0, t1),
                                ClosestAt::Start,
                            )
                        })
                        .collect()
                }
                Feature::Piece([a, b], piece, pieces) => {
                    let Some(bvh) = edge_bvh else { return Vec::new().into_iter() };
                    let along = |s: f64| a + (b - a) * s;
                    let (from, to) = (along(piece as f64 / pieces as f64), along((piece + 1) as f64 / pieces as f64));
                    let query = aabb(swept(from).into_iter().chain(swept(to)), grow);
                    bvh.intersect_aabb(&query)
                        .filter_map(|i| {
                            let edge = surface.edges()[i as usize];
                            let ends = [[at(a, t0), at(b, t0)], [at(a, t1), at(b, t1)]];
                            segment_edge_contact(
                                collider,
                                radius,
                                ends,
                                (piece, pieces),
                                edge,
                                (start, predicted),
                                thickness,
                                (t0, t1),
                                ClosestAt::Start,
                            )
                        })
                        .collect()
                }
            };
            found.into_iter()
        })
        .collect()
}

/// The contacts of round colliders' features (sphere, capsule) with the elements of the
/// surface that ended the step at `end` within reach of them, made from where the elements
/// started (`start`, the side they came from): an edge pulled into a thin bar beyond its
/// prediction, which the step's detection did not see coming. Every element is tested against
/// the features' boxes at t1 (a handful of features; the surface's trees stay as the step
/// left them, since the self contacts' order follows them).
pub(crate) fn detect_round_contacts_at_end(
    surface: &Surface,
    colliders: &[Collider],
    features: &[Features],
    (start, end): (&[DVec3], &[DVec3]),
    thickness: f64,
    longest: f64,
    (t0, t1): (f64, f64),
) -> Vec<FeatureContact> {
    let mut found = Vec::new();
    for (collider, f) in colliders.iter().zip(features) {
        let (points, segments) = f.can_cut(longest, thickness);
        if !f.is_round() || !(points || segments) {
            continue;
        }
        let reach = f.radius + thickness;
        let at = |p: DVec3, t: f64| if collider.motion.is_static() { p } else { collider.motion.apply(p, t) };
        let near = |b: &Aabb, element: &[u32]| aabb(element.iter().map(|&v| end[v as usize]), 0.0).intersects(b);
        for &p in f.points.iter().filter(|_| points) {
            let ends = [at(p, t0), at(p, t1)];
            let b = aabb([ends[1]], reach);
            found.par_extend(surface.triangles().par_iter().filter(|t| near(&b, &t[..])).filter_map(|&t| {
                point_triangle_contact(collider, f.radius, ends, t, (start, end), thickness, (t0, t1), ClosestAt::End)
            }));
        }
        for &[a, b] in f.segments.iter().filter(|_| segments) {
            let ends = [[at(a, t0), at(b, t0)], [at(a, t1), at(b, t1)]];
            let bounds = aabb(ends[1], reach);
            found.par_extend(surface.edges().par_iter().filter(|e| near(&bounds, &e[..])).filter_map(|&e| {
                segment_edge_contact(
                    collider,
                    f.radius,
                    ends,
                    (0, 1),
                    e,
                    (start, end),
                    thickness,
                    (t0, t1),
                    ClosestAt::End,
                )
            }));
        }
    }
    found
}

/// The largest predicted motion of `vertices` relative to the feature's point, which moves
/// by `shift`.
fn relative_motion(vertices: &[u32], shift: DVec3, start: &[DVec3], predicted: &[DVec3]) -> f64 {
    vertices.iter().map(|&v| (predicted[v as usize] - start[v as usize] - shift).length()).fold(0.0, f64::max)
}

/// The distance a contact whose points are `gap` apart along its normal (negative: crossed)
/// must keep this step, `reach` = ρ + t, when it is one: closer than the reach plus twice the
/// relative motion (computed only when needed). As a self contact's.
fn target(gap: f64, reach: f64, motion: impl FnOnce() -> f64) -> Option<f64> {
    if gap >= reach && gap >= reach + 2.0 * motion() {
        return None;
    }
    Some(if gap < reach { gap + RECOVERY * (reach - gap) } else { reach })
}

/// The normal of a contact at x_n whose surface point `on_surface` is `offset` from the
/// feature's point, and the gap along it. Outside the collider, the direction of the offset.
/// Inside it (the element cut in while its vertices stayed out, or the offset is too short
/// to have a direction), the side the element's vertices are on: their outward normals
/// weighted by α; the offset's direction still where it is on that side (an element dipping
/// into a capsule above its axis). `None` where the vertices are inside too (their own
/// contacts take them out first) or on no clear side (an edge across a thin bar).
fn contact_normal(
    collider: &Collider,
    radius: f64,
    element: (&[u32], &[f64]),
    (on_surface, offset): (DVec3, DVec3),
    start: &[DVec3],
    t0: f64,
) -> Option<(DVec3, f64)> {
    let length = offset.length();
    let inside = if radius > 0.0 { length < radius } else { collider.closest_from(on_surface, t0, t0).distance < 0.0 };
    if !inside && length > 1e-12 {
        return Some((offset / length, length));
    }
    let mut side = DVec3::ZERO;
    for (&v, &a) in element.0.iter().zip(element.1) {
        if a != 0.0 {
            let p = collider.closest_from(start[v as usize], t0, t0);
            if p.distance < 0.0 || p.distance.is_nan() {
                return None;
            }
            // Farther behind an open mesh than its thickness: on its back, which faces away.
            side += a * if p.distance.is_infinite() { -p.normal } else { p.normal };
        }
    }
    // Half of α-weighted unit normals: the vertices agree to within about 120°.
    if side.length() < 0.5 {
        return None;
    }
    let side = side.normalize();
    if length > 1e-12 && offset.dot(side) > 0.0 {
        return Some((offset / length, length));
    }
    Some((side, offset.dot(side)))
}

/// A contact between the surface's element (`vertices` with coordinates `alpha`, at
/// `on_surface` at x_n) and a feature whose point `on_feature` at t0 is at `later` at t1;
/// `nearest` is r², the element's nearest vertex from its point seen along the feature.
struct Candidate {
    vertices: [u32; 4],
    alpha: [f64; 4],
    on_surface: DVec3,
    on_feature: DVec3,
    later: DVec3,
    nearest: f64,
    end: FeatureAt,
    /// 3 for a triangle, 2 for an edge: the leading `vertices`.
    size: usize,
}

impl Candidate {
    /// The contact, where the vertices' own contacts do not hold it and the points are within
    /// reach this step (see the [module docs](self)).
    fn contact(
        self,
        collider: &Collider,
        radius: f64,
        (start, predicted): (&[DVec3], &[DVec3]),
        thickness: f64,
        (t0, t1): (f64, f64),
    ) -> Option<FeatureContact> {
        let element = &self.vertices[..self.size];
        let reach = radius + thickness;
        let shift = self.later - self.on_feature;
        let motion = relative_motion(element, shift, start, predicted);
        if !may_need_own_contact(self.nearest, motion, thickness, reach) {
            return None;
        }
        let offset = self.on_surface - self.on_feature;
        let (normal, gap) = contact_normal(
            collider,
            radius,
            (element, &self.alpha[..element.len()]),
            (self.on_surface, offset),
            start,
            t0,
        )?;
        let target = target(gap, reach, || motion)?;
        let normal = collider.motion.carry(normal, t0, t1);
        Some(FeatureContact {
            pair: Pair {
                vertices: self.vertices,
                alpha: self.alpha,
                normal,
                distance: normal.dot(self.later) + target,
                copies: 1,
            },
            friction: collider.friction,
            shift,
            end: self.end,
            reach,
            round: radius > 0.0,
        })
    }
}

/// Where a contact's closest points are taken: at the step's start (the detection), or at its
/// end (elements that ended within reach, [`detect_round_contacts_at_end`]; the normal still
/// from where they started).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ClosestAt {
    Start,
    End,
}

/// The contact of a point feature at `p` = [P(t0), P(t1)] with `triangle`.
#[allow(clippy::too_many_arguments)]
fn point_triangle_contact(
    collider: &Collider,
    radius: f64,
    [p0, p1]: [DVec3; 2],
    triangle: [u32; 3],
    positions: (&[DVec3], &[DVec3]),
    thickness: f64,
    times: (f64, f64),
    at: ClosestAt,
) -> Option<FeatureContact> {
    let (shape, p) = if at == ClosestAt::Start { (positions.0, p0) } else { (positions.1, p1) };
    let x = triangle.map(|v| shape[v as usize]);
    let (c, alpha) = closest_on_triangle(p, x);
    let nearest =
        (0..3).filter(|&k| alpha[k] != 0.0).map(|k| (x[k] - c).length_squared()).fold(f64::INFINITY, f64::min);
    // Where the element's point was at the step's start, when the closest was taken at its end.
    let on_surface = match at {
        ClosestAt::Start => c,
        ClosestAt::End => (0..3).map(|k| alpha[k] * positions.0[triangle[k] as usize]).sum(),
    };
    Candidate {
        vertices: [triangle[0], triangle[1], triangle[2], triangle[0]],
        alpha: [alpha[0], alpha[1], alpha[2], 0.0],
        on_surface,
        on_feature: p0,
        later: p1,
        nearest,
        end: FeatureAt::Point(p1),
        size: 3,
    }
    .contact(collider, radius, positions, thickness, times)
}

/// The contact of piece `piece` of a segment feature (`ends` at t0 and at t1) with `edge`:
/// made by the piece its closest point lies in, so that each is made once.
#[allow(clippy::too_many_arguments)]
fn segment_edge_contact(
    collider: &Collider,
    radius: f64,
    [[a0, b0], [a1, b1]]: [[DVec3; 2]; 2],
    (piece, pieces): (usize, usize),
    edge: [u32; 2],
    positions: (&[DVec3], &[DVec3]),
    thickness: f64,
    times: (f64, f64),
    at: ClosestAt,
) -> Option<FeatureContact> {
    let (shape, [a, b]) = if at == ClosestAt::Start { (positions.0, [a0, b0]) } else { (positions.1, [a1, b1]) };
    let x = edge.map(|v| shape[v as usize]);
    let (s, u, on_edge, _) = closest_between_segments(x[0], x[1], a, b);
    // At an end of either: a vertex's or a point feature's contact.
    if s <= 0.0 || s >= 1.0 || u <= 0.0 || u >= 1.0 || ((u * pieces as f64) as usize).min(pieces - 1) != piece {
        return None;
    }
    let axis = (b - a).normalize_or_zero();
    let across = |d: DVec3| (d - d.dot(axis) * axis).length_squared();
    let start = edge.map(|v| positions.0[v as usize]);
    Candidate {
        vertices: [edge[0], edge[1], edge[0], edge[1]],
        alpha: [1.0 - s, s, 0.0, 0.0],
        on_surface: (1.0 - s) * start[0] + s * start[1],
        on_feature: a0 + u * (b0 - a0),
        later: a1 + u * (b1 - a1),
        nearest: across(x[0] - on_edge).min(across(x[1] - on_edge)),
        end: FeatureAt::Segment(a1, b1),
        size: 2,
    }
    .contact(collider, radius, positions, thickness, times)
}
