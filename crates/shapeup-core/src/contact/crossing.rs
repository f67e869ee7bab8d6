//! The fail-safe of self-collision: at the end of a time step, the element pairs whose paths
//! from the step's start x_n to its end q cross (a vertex through a triangle, an edge through
//! an edge) are found by a continuous check, and their vertices are gathered in rigid impact
//! zones (Bridson, Fedkiw and Anderson, "Robust Treatment of Collisions, Contact and Friction
//! for Cloth Animation", SIGGRAPH 2002, §7.3; Harmon et al., "Robust Treatment of Simultaneous
//! Collisions", SIGGRAPH 2008): each zone moves as a rigid body with its vertices' linear and
//! angular momentum, so no pair inside it crosses. Zones merge until nothing crosses; a step
//! never makes the surface pass through itself, as x_n had no crossing and, after
//! `MAX_ROUNDS`, the step is x_n again.
//!
//! The contacts of a step keep pairs apart only as far as a finite number of iterations and
//! projections can: a fold pressed between a collider and itself, where the collider's
//! projection has the last word, let a vertex slip through a triangle. A zone keeps its
//! momentum (the fold goes on falling, turning, sliding) and loses only the motion that
//! crossed: an inelastic impact. Stopping the vertices instead (putting them back at x_n)
//! froze whole cloths in mid-air when a coarse step crossed every frame.
//!
//! The continuous check of a pair (Provot, "Collision and self-collision handling in cloth
//! model dedicated to design garments", 1997): the four points, moving linearly over the step,
//! are coplanar where the cubic f(t) = (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀) vanishes; at each of its
//! roots in [0, 1] the pair crosses when the vertex is on the triangle (the two edges meet), to
//! within a tolerance.

use super::boxes::swept_box;
use super::closest::{closest_between_segments, closest_on_triangle};
use glam::DVec3;
use parry3d_f64::bounding_volume::BoundingVolume;
use rayon::prelude::*;

/// A vertex–triangle pair (`vertices` = the vertex, then the triangle's three) or an edge–edge
/// pair (both edges' ends) of the step's detection, with the distance between them at x_n.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ElementPair {
    pub(crate) vertices: [u32; 4],
    pub(crate) vertex_triangle: bool,
    pub(crate) distance: f64,
}

impl ElementPair {
    /// Vertex `v` and triangle `t` at `distance`, unless `v` is a corner of `t` (neighbours
    /// are not a pair).
    pub(crate) fn vertex_triangle(v: u32, t: [u32; 3], distance: f64) -> Option<Self> {
        (!t.contains(&v)).then_some(ElementPair { vertices: [v, t[0], t[1], t[2]], vertex_triangle: true, distance })
    }

    /// Edges `e` and `f` at `distance`, unless they share a vertex.
    pub(crate) fn edge_edge(e: [u32; 2], f: [u32; 2], distance: f64) -> Option<Self> {
        (!(f.contains(&e[0]) || f.contains(&e[1]))).then_some(ElementPair {
            vertices: [e[0], e[1], f[0], f[1]],
            vertex_triangle: false,
            distance,
        })
    }

    /// The vertices of each side: the vertex and the triangle's, or each edge's.
    fn sides(&self) -> (&[u32], &[u32]) {
        self.vertices.split_at(if self.vertex_triangle { 1 } else { 2 })
    }

    /// Whether the pair can come within `0` of itself over a step whose vertices move by
    /// `q − start`: the distance at x_n less the largest relative motion of a vertex of one
    /// side against one of the other (any point of an element moves by a convex combination
    /// of its vertices' motions).
    fn may_meet(&self, start: &[DVec3], q: &[DVec3]) -> bool {
        let motion = |v: u32| q[v as usize] - start[v as usize];
        let (first, second) = self.sides();
        let mut most = 0.0f64;
        for &a in first {
            for &b in second {
                most = most.max((motion(a) - motion(b)).length_squared());
            }
        }
        most.sqrt() >= self.distance
    }

    /// Whether a vertex of one side is within `tolerance` of one of the other at `start`: two
    /// vertices at one place (pushed onto one point by a collider) are as neighbours, with no
    /// side to keep (the self contacts take them apart). Their pairs' coplanarity at t = 0
    /// would count as a crossing at every step, stopping them for good.
    fn coincident(&self, start: &[DVec3], tolerance: f64) -> bool {
        let (first, second) = self.sides();
        first.iter().any(|&a| second.iter().any(|&b| start[a as usize].distance(start[b as usize]) <= tolerance))
    }

    /// Whether the pair's paths from `start` to `q` cross (see the [module docs](self)), to
    /// within `tolerance`.
    pub(crate) fn crosses(&self, start: &[DVec3], q: &[DVec3], tolerance: f64) -> bool {
        let x = self.vertices.map(|v| start[v as usize]);
        let e = self.vertices.map(|v| q[v as usize]);
        // Each side's points stay in the box of its vertices' starts and ends: sides whose
        // boxes are farther apart than twice the tolerance never meet (most pairs of a step
        // that may meet by their motions' size; a cheap way out before the cubic).
        let (first, second) = self.sides();
        let path = |side: &[u32]| swept_box(side, start, q, DVec3::ZERO, tolerance);
        if !path(first).intersects(&path(second)) {
            return false;
        }
        let d = [0, 1, 2, 3].map(|k| e[k] - x[k]);
        let at = |t: f64| -> [DVec3; 4] { [0, 1, 2, 3].map(|k| x[k] + t * d[k]) };
        let meet = |t: f64| {
            let p = at(t);
            if self.vertex_triangle {
                let (c, _) = closest_on_triangle(p[0], [p[1], p[2], p[3]]);
                (p[0] - c).length() <= tolerance
            } else {
                let (_, _, a, b) = closest_between_segments(p[0], p[1], p[2], p[3]);
                (a - b).length() <= tolerance
            }
        };
        // Ending on the other side's element is a crossing too (no side left to keep): there
        // the cubic's root at t = 1 can be lost to round-off (f(1) ≈ 1e-21 with every Bernstein
        // coefficient positive), and a vertex an upper sheet pressed onto a box, level with the
        // lower sheet's triangle, lay on it for good.
        coplanar_times(x, d).into_iter().flatten().any(meet) || (self.may_touch_at_end(e, tolerance) && meet(1.0))
    }
}

impl ElementPair {
    /// Whether the pair's points `e` can be within `tolerance` of each other: the volume
    /// f = (e₁ − e₀) × (e₂ − e₀) · (e₃ − e₀) is the distance between the vertex and the
    /// triangle's plane (or between the edges' lines) times |n|, n the triangle's doubled area
    /// vector (the edges' cross product), and both distances are at most the points' distance.
    /// So |f| > tolerance |n| rules out a meeting without the closest points (the slack
    /// covers round-off).
    fn may_touch_at_end(&self, e: [DVec3; 4], tolerance: f64) -> bool {
        let (a, b, c) = (e[1] - e[0], e[2] - e[0], e[3] - e[0]);
        let volume = a.cross(b).dot(c);
        let normal = if self.vertex_triangle { (e[2] - e[1]).cross(e[3] - e[1]) } else { a.cross(e[3] - e[2]) };
        let slack = 1e-9 * a.length() * b.length() * c.length();
        volume.abs() <= 2.0 * tolerance * normal.length() + slack
    }
}

/// The times t ∈ [0, 1] at which the points x_k + t d_k are coplanar: the roots of the cubic
/// f(t) = (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀), each bracketed between the cubic's turning points
/// and refined ([`bracketed_root`]); where f vanishes at a bracket's end, that end (so a pair coplanar throughout
/// is tested at 0, 1 and its turning points).
fn coplanar_times(x: [DVec3; 4], d: [DVec3; 4]) -> [Option<f64>; 5] {
    let (a0, a1) = (x[1] - x[0], d[1] - d[0]);
    let (b0, b1) = (x[2] - x[0], d[2] - d[0]);
    let (c0, c1) = (x[3] - x[0], d[3] - d[0]);
    // (a0 + t a1) × (b0 + t b1) · (c0 + t c1), term by term.
    let (ab0, ab1, ab2) = (a0.cross(b0), a1.cross(b0) + a0.cross(b1), a1.cross(b1));
    let k = [ab0.dot(c0), ab1.dot(c0) + ab0.dot(c1), ab2.dot(c0) + ab1.dot(c1), ab2.dot(c1)];
    let f = |t: f64| ((k[3] * t + k[2]) * t + k[1]) * t + k[0];
    // The cubic's Bernstein coefficients on [0, 1]: f lies in their convex hull, so when all
    // have one sign f has no root there (most pairs a step checks: a cheap way out).
    let bernstein = [k[0], k[0] + k[1] / 3.0, k[0] + (2.0 * k[1] + k[2]) / 3.0, k[0] + k[1] + k[2] + k[3]];
    if bernstein.iter().all(|&b| b > 0.0) || bernstein.iter().all(|&b| b < 0.0) {
        return [None; 5];
    }
    // Turning points: 3 k3 t² + 2 k2 t + k1 = 0.
    let mut ends = [0.0, 1.0, 1.0, 1.0];
    let (qa, qb, qc) = (3.0 * k[3], 2.0 * k[2], k[1]);
    let mut n = 1;
    if qa != 0.0 {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc >= 0.0 {
            let s = disc.sqrt();
            let mut r = [(-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa)];
            if r[0] > r[1] {
                r.swap(0, 1);
            }
            for t in r {
                if t > 0.0 && t < 1.0 {
                    ends[n] = t;
                    n += 1;
                }
            }
        }
    } else if qb != 0.0 {
        let t = -qc / qb;
        if t > 0.0 && t < 1.0 {
            ends[n] = t;
            n += 1;
        }
    }
    ends[n] = 1.0;
    let mut roots = [None; 5];
    let mut found = 0;
    for w in ends[..=n].windows(2) {
        let (lo, hi) = (w[0], w[1]);
        let (flo, fhi) = (f(lo), f(hi));
        if flo == 0.0 {
            roots[found] = Some(lo);
            found += 1;
        } else if flo * fhi < 0.0 {
            roots[found] = Some(bracketed_root(f, (lo, flo), (hi, fhi)));
            found += 1;
        }
    }
    if f(1.0) == 0.0 {
        roots[found] = Some(1.0);
    }
    roots
}

/// The root of `f` in [lo, hi], where f changes sign: the Illinois variant of regula falsi
/// (Dowell and Jarratt, BIT 11, 1971), superlinear where bisection halves the bracket once
/// per evaluation, and kept to the bracket. Stops when the bracket or the step is below
/// 1e-15 (a time within the step: positions then agree far below any tolerance) or f
/// vanishes.
fn bracketed_root(f: impl Fn(f64) -> f64, (mut lo, mut flo): (f64, f64), (mut hi, mut fhi): (f64, f64)) -> f64 {
    const CLOSE: f64 = 1e-15;
    // Which end the last step replaced: -1 the low one, 1 the high one.
    let mut side = 0;
    let mut t = f64::NAN;
    for _ in 0..100 {
        let last = t;
        let next = (lo * fhi - hi * flo) / (fhi - flo);
        // Round-off can put the secant's root on an end: bisect then.
        t = if next > lo && next < hi { next } else { 0.5 * (lo + hi) };
        let ft = f(t);
        if ft == 0.0 {
            return t;
        }
        if (ft < 0.0) == (flo < 0.0) {
            (lo, flo) = (t, ft);
            if side == -1 {
                fhi *= 0.5;
            }
            side = -1;
        } else {
            (hi, fhi) = (t, ft);
            if side == 1 {
                flo *= 0.5;
            }
            side = 1;
        }
        if hi - lo <= CLOSE || (t - last).abs() <= CLOSE {
            break;
        }
    }
    t
}

/// Resolves every crossing of the step in rigid impact zones (see the [module docs](self)):
/// the vertices of each pair whose paths from `start` to `q` cross are merged into a zone, and
/// each zone's vertices are given the rigid motion with the linear and angular momentum their
/// own motions had ([`rigid_motion`]); repeated, zones merging, until nothing crosses. The pairs
/// checked each round are `pairs` and those `more` gives for the current `q` (the pairs a
/// step's own detection cannot vouch for). A zone with a vertex whose inverse mass is 0 (a hard
/// pin, a driven handle: its motion is prescribed) cannot move rigidly with it: its other
/// vertices are put back at `start`. A zone whose rigid motion would take a vertex `v` to a
/// point p where `outside(v, p)` is a push (into a collider or across one: the push takes p
/// back out to its thickness; zero where none can) is moved on by the deepest push, up to 3
/// times, as a body resting on the collider is; failing that it takes half, a quarter or none
/// of its motion (pushed out likewise: a moving collider may have come over `start`), else is
/// put back at `start` as it is. After `MAX_ROUNDS` rounds, every vertex of `all` is put back
/// (x_n had no crossing). Returns how many vertices' motion was changed.
pub(crate) fn stop_crossings(
    pairs: &[ElementPair],
    mut more: impl FnMut(&[DVec3]) -> Vec<ElementPair>,
    (all, inverse_mass): (&[u32], &[f64]),
    outside: impl Fn(u32, DVec3) -> Option<DVec3> + Sync,
    start: &[DVec3],
    q: &mut [DVec3],
    tolerance: f64,
) -> usize {
    // Zones grow by the pairs each round finds: a strip whose driven end jumped 0.6 m in a
    // step needed more than 16 rounds, and the whole strip stood still for 22 steps.
    const MAX_ROUNDS: usize = 64;
    // Pushes out of the colliders a zone's motion may take.
    const PUSHES: usize = 3;
    // The motions the step gave, and the zones (allocated at the first crossing).
    let mut zones: Option<(Vec<DVec3>, ImpactZones)> = None;
    let changed = |q: &[DVec3], free: &[DVec3]| all.iter().filter(|&&v| q[v as usize] != free[v as usize]).count();
    // The vertices the last round's zones moved (none before the first round). A pair none of
    // whose vertices moved crosses as it did then: not at all (a crossing pair's vertices
    // joined a zone, which moved them or put them back where they started), or inside a zone,
    // or held against a prescribed motion, which merges nothing either way.
    let mut moved: Option<Vec<bool>> = None;
    for _ in 0..MAX_ROUNDS {
        let extra = more(q);
        let view: &[DVec3] = q;
        let again = |p: &&ElementPair| moved.as_deref().is_none_or(|m| p.vertices.iter().any(|&v| m[v as usize]));
        let crossing: Vec<[u32; 4]> = pairs
            .par_iter()
            .chain(extra.par_iter())
            .filter(again)
            .filter(|p| p.may_meet(start, view) && !p.coincident(start, tolerance) && p.crosses(start, view, tolerance))
            .map(|p| p.vertices)
            .collect();
        if crossing.is_empty() {
            return zones.map_or(0, |(free, _)| changed(q, &free));
        }
        let (free, zones) = zones.get_or_insert_with(|| (view.to_vec(), ImpactZones::new(view.len())));
        let mut merged = false;
        for vertices in &crossing {
            for &v in &vertices[1..] {
                merged |= zones.union(vertices[0], v);
            }
        }
        if !merged {
            // Only pairs inside a zone cross (its motion is rigid, so they keep their side), or
            // one held still against a prescribed motion.
            return changed(q, free);
        }
        let moved = moved.insert(vec![false; view.len()]);
        for members in zones.members() {
            // The zone's rigid motion, or as large a part of it as keeps out of the colliders
            // (a part of a rigid motion is one too), pushed out of them.
            let rigid = members.iter().all(|&v| inverse_mass[v as usize] > 0.0).then_some(()).and_then(|()| {
                let (centre, motion, turn) = rigid_motion(&members, inverse_mass, start, free);
                [1.0, 0.5, 0.25, 0.0].into_iter().find_map(|part| {
                    let rotation = glam::DQuat::from_scaled_axis(part * turn);
                    let mut moved: Vec<DVec3> = members
                        .iter()
                        .map(|&v| centre + part * motion + rotation * (start[v as usize] - centre))
                        .collect();
                    // Stopping a zone that lies on a collider froze cloth resting on a box.
                    for _ in 0..PUSHES {
                        let deepest = members
                            .iter()
                            .zip(&moved)
                            .filter_map(|(&v, &p)| outside(v, p))
                            .max_by(|a, b| a.length_squared().total_cmp(&b.length_squared()));
                        match deepest {
                            None => return Some(moved),
                            Some(push) if push != DVec3::ZERO => moved.iter_mut().for_each(|p| *p += push),
                            Some(_) => return None,
                        }
                    }
                    members.iter().zip(&moved).all(|(&v, &p)| outside(v, p).is_none()).then_some(moved)
                })
            });
            let mut place = |v: u32, p: DVec3| {
                let v = v as usize;
                moved[v] |= q[v] != p;
                q[v] = p;
            };
            match rigid {
                Some(rigid) => {
                    for (&v, p) in members.iter().zip(rigid) {
                        place(v, p);
                    }
                }
                None => {
                    for &v in &members {
                        if inverse_mass[v as usize] > 0.0 {
                            place(v, start[v as usize]);
                        }
                    }
                }
            }
        }
    }
    for &v in all {
        let v = v as usize;
        if inverse_mass[v] > 0.0 {
            q[v] = start[v];
        }
    }
    zones.map_or(0, |(free, _)| changed(q, &free))
}

/// Disjoint sets of vertices (union–find with path halving), for the impact zones.
struct ImpactZones {
    parent: Vec<u32>,
    /// Every vertex ever merged (a zone of more than one vertex holds only these).
    merged: Vec<u32>,
}

impl ImpactZones {
    fn new(n: usize) -> Self {
        ImpactZones { parent: (0..n as u32).collect(), merged: Vec::new() }
    }

    fn root(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let up = self.parent[self.parent[v as usize] as usize];
            self.parent[v as usize] = up;
            v = up;
        }
        v
    }

    /// Merges the zones of `a` and `b`; whether they were apart.
    fn union(&mut self, a: u32, b: u32) -> bool {
        let (ra, rb) = (self.root(a), self.root(b));
        if ra == rb {
            return false;
        }
        self.parent[ra.max(rb) as usize] = ra.min(rb);
        self.merged.extend([a, b]);
        true
    }

    /// The zones of more than one vertex, each a list of its vertices.
    fn members(&mut self) -> Vec<Vec<u32>> {
        let mut merged = std::mem::take(&mut self.merged);
        merged.sort_unstable();
        merged.dedup();
        let mut keyed: Vec<(u32, u32)> = merged.iter().map(|&v| (self.root(v), v)).collect();
        self.merged = merged;
        keyed.sort_unstable();
        keyed.chunk_by(|a, b| a.0 == b.0).map(|zone| zone.iter().map(|&(_, v)| v).collect()).collect()
    }
}

/// The rigid motion of `members` from `start` (centre x_c, its motion d_c, rotation vector ω)
/// with the momentum of their motions `free − start`
/// (Bridson, Fedkiw and Anderson 2002, §7.3), masses 1 / `inverse_mass`: the centre of mass
/// x_c moves by the mean motion d_c = Σ mᵢ dᵢ / M, and the zone turns about it by the rotation
/// vector ω = I⁻¹ L, L = Σ mᵢ rᵢ × (dᵢ − d_c), I = Σ mᵢ (|rᵢ|² 1 − rᵢ rᵢᵀ), rᵢ = xᵢ − x_c.
/// The turn is at most a quarter turn (the straight paths from a configuration to its turned
/// image then pass through affine images of it only, where no pair of the zone can cross).
fn rigid_motion(members: &[u32], inverse_mass: &[f64], start: &[DVec3], free: &[DVec3]) -> (DVec3, DVec3, DVec3) {
    let mass = |v: u32| 1.0 / inverse_mass[v as usize];
    let total: f64 = members.iter().map(|&v| mass(v)).sum();
    let centre = members.iter().map(|&v| mass(v) * start[v as usize]).sum::<DVec3>() / total;
    let motion = members.iter().map(|&v| mass(v) * (free[v as usize] - start[v as usize])).sum::<DVec3>() / total;
    let (mut momentum, mut inertia) = (DVec3::ZERO, glam::DMat3::ZERO);
    for &v in members {
        let r = start[v as usize] - centre;
        let d = free[v as usize] - start[v as usize] - motion;
        momentum += mass(v) * r.cross(d);
        inertia += mass(v) * (glam::DMat3::from_diagonal(DVec3::splat(r.length_squared())) - outer(r, r));
    }
    // A zone on a line (or a point) does not turn about its axis: the inertia is singular
    // there, and so is the momentum, which a small regularization leaves at 0.
    let trace = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
    let mut turn = DVec3::ZERO;
    if trace > 0.0 && trace.is_finite() {
        let regular = inertia + glam::DMat3::from_diagonal(DVec3::splat(1e-12 * trace));
        turn = regular.inverse() * momentum;
        let angle = turn.length();
        if !angle.is_finite() {
            turn = DVec3::ZERO;
        } else if angle > std::f64::consts::FRAC_PI_2 {
            turn *= std::f64::consts::FRAC_PI_2 / angle;
        }
    }
    (centre, motion, turn)
}

/// The 3 × 3 matrix a bᵀ.
fn outer(a: DVec3, b: DVec3) -> glam::DMat3 {
    glam::DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::closest::tests::{rng, v};

    fn pair(vertex_triangle: bool) -> ElementPair {
        ElementPair { vertices: [0, 1, 2, 3], vertex_triangle, distance: 0.0 }
    }

    const TRIANGLE: [DVec3; 3] = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 1.0)];

    #[test]
    fn a_vertex_through_a_triangle_crosses_and_one_beside_it_does_not() {
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let mut through = start;
        through[0].y = -0.5;
        assert!(pair(true).crosses(&start, &through, 1e-9));
        // Beside the triangle (x + z > 1): coplanar at t = ½, but not on it.
        let beside = [DVec3::new(0.8, 0.5, 0.8), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let mut down = beside;
        down[0].y = -0.5;
        assert!(!pair(true).crosses(&beside, &down, 1e-9));
        // Stopping short of the plane.
        let mut short = start;
        short[0].y = 0.01;
        assert!(!pair(true).crosses(&start, &short, 1e-9));
    }

    #[test]
    fn a_vertex_that_ends_on_the_triangle_crosses() {
        // A trial's numbers: the vertex ends exactly level with (and inside) a triangle lying
        // in y = 0.004, one corner of which slid within the plane.
        let start = [
            DVec3::new(0.09537015379801726, 0.008786477051152392, 0.04480825219474272),
            DVec3::new(0.09000000000002396, 0.004, 0.029999999999988772),
            DVec3::new(0.12000000000002414, 0.004, 0.05999999999998916),
            DVec3::new(0.09000000000002395, 0.004, 0.059999999999988965),
        ];
        let mut q = start;
        q[0] = DVec3::new(0.09542479278423913, 0.004, 0.04425638140815717);
        q[2] = DVec3::new(0.11998917737074065, 0.004, 0.059923763321671826);
        assert!(pair(true).crosses(&start, &q, 4e-6));
        // Ending just above it is no crossing.
        q[0].y += 1e-4;
        assert!(!pair(true).crosses(&start, &q, 4e-6));
    }

    #[test]
    fn a_triangle_swept_over_a_resting_vertex_crosses() {
        // The vertex stays; the triangle rises through it (every point moves, f is cubic).
        let start = [DVec3::new(0.2, 0.0, 0.2), TRIANGLE[0] - DVec3::Y, TRIANGLE[1] - DVec3::Y, TRIANGLE[2] - DVec3::Y];
        let mut end = start;
        end[1] = TRIANGLE[0] + DVec3::new(0.0, 1.0, 0.0);
        end[2] = TRIANGLE[1] + DVec3::new(0.0, 0.5, 0.0);
        end[3] = TRIANGLE[2] + DVec3::new(0.0, 2.0, 0.0);
        assert!(pair(true).crosses(&start, &end, 1e-9));
    }

    #[test]
    fn crossing_edges_cross_and_parallel_ones_do_not() {
        let start = [
            DVec3::new(-1.0, 1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let mut end = start;
        end[0].y = -1.0;
        end[1].y = -1.0;
        assert!(pair(false).crosses(&start, &end, 1e-9));
        // The same fall, the second edge beyond the first's end.
        let mut far = start;
        far[2].x = 2.0;
        far[3].x = 2.0;
        let mut far_end = far;
        far_end[0].y = -1.0;
        far_end[1].y = -1.0;
        assert!(!pair(false).crosses(&far, &far_end, 1e-9));
    }

    #[test]
    fn the_bernstein_bound_keeps_every_root() {
        // Random cubics: where the early way out says "no root", f has one sign on a fine grid.
        let mut seed = 7u64;
        let mut skipped = 0;
        for _ in 0..2000 {
            let x = [0, 1, 2, 3].map(|_| v(&mut seed));
            let d = [0, 1, 2, 3].map(|_| 0.5 * v(&mut seed));
            if coplanar_times(x, d).iter().all(Option::is_none) {
                skipped += 1;
                let f = |t: f64| {
                    let p = [0, 1, 2, 3].map(|k| x[k] + t * d[k]);
                    (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0])
                };
                let first = f(0.0).signum();
                assert!((0..=1000).all(|i| f(i as f64 / 1000.0).signum() == first));
            }
        }
        assert!(skipped > 100, "{skipped}");
    }

    #[test]
    fn the_refined_roots_are_every_sign_change_of_the_cubic() {
        // Random motions: each sign change of f on a fine grid has a root of coplanar_times
        // within the grid's step, and f vanishes there to round-off (what bisection to 2⁻⁶⁰
        // gave, in a few evaluations).
        let mut seed = 11u64;
        let mut checked = 0;
        for _ in 0..2000 {
            let x = [0; 4].map(|_| v(&mut seed));
            let d = [0; 4].map(|_| 3.0 * v(&mut seed));
            let f = |t: f64| {
                let p = [0, 1, 2, 3].map(|k| x[k] + t * d[k]);
                (p[1] - p[0]).cross(p[2] - p[0]).dot(p[3] - p[0])
            };
            let roots: Vec<f64> = coplanar_times(x, d).into_iter().flatten().collect();
            let scale = (0..4).map(|k| x[k].length() + d[k].length()).fold(0.0, f64::max).powi(3);
            for &t in &roots {
                assert!(f(t).abs() < 1e-12 * scale, "f({t}) = {}", f(t));
            }
            const N: usize = 4000;
            for i in 0..N {
                let (a, b) = (i as f64 / N as f64, (i + 1) as f64 / N as f64);
                if f(a) * f(b) < 0.0 {
                    checked += 1;
                    assert!(roots.iter().any(|&t| t >= a - 1e-12 && t <= b + 1e-12), "{a}..{b}: {roots:?}");
                }
            }
        }
        assert!(checked > 500, "{checked}");
    }

    #[test]
    fn the_end_volume_bound_never_rules_out_a_pair_that_touches() {
        // Random pairs ending at random distances around the tolerance: whenever the closest
        // points are within it, the cheap bound lets the pair through; and it rules out most
        // of those that are farther.
        let mut seed = 5u64;
        let tolerance = 0.01;
        let (mut touching, mut ruled_out) = (0, 0);
        for k in 0..20000 {
            let vertex_triangle = k % 2 == 0;
            let mut e = [0; 4].map(|_| v(&mut seed));
            // Move the first side to within a few tolerances of the other.
            let (a, b) = if vertex_triangle {
                let (c, _) = closest_on_triangle(e[0], [e[1], e[2], e[3]]);
                (e[0], c)
            } else {
                let (_, _, a, b) = closest_between_segments(e[0], e[1], e[2], e[3]);
                (a, b)
            };
            let dir = (a - b).normalize_or_zero();
            let wanted = 3.0 * tolerance * (0.5 * rng(&mut seed) + 0.5);
            let shift = b + wanted * dir - a;
            let side = if vertex_triangle { 1 } else { 2 };
            for p in &mut e[..side] {
                *p += shift;
            }
            let distance = if vertex_triangle {
                let (c, _) = closest_on_triangle(e[0], [e[1], e[2], e[3]]);
                (e[0] - c).length()
            } else {
                let (_, _, a, b) = closest_between_segments(e[0], e[1], e[2], e[3]);
                (a - b).length()
            };
            let gate = pair(vertex_triangle).may_touch_at_end(e, tolerance);
            if distance <= tolerance {
                touching += 1;
                assert!(gate, "{e:?} at {distance}");
            } else if !gate {
                ruled_out += 1;
            }
        }
        assert!(touching > 3000 && ruled_out > 3000, "{touching} {ruled_out}");
    }

    #[test]
    fn coplanar_times_are_the_cubics_roots() {
        // A vertex falling at unit speed through the plane y = 0 at t = 0.3.
        let x = [DVec3::new(0.2, 0.3, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let d = [DVec3::new(0.0, -1.0, 0.0), DVec3::ZERO, DVec3::ZERO, DVec3::ZERO];
        let roots: Vec<f64> = coplanar_times(x, d).into_iter().flatten().collect();
        assert_eq!(roots.len(), 1);
        assert!((roots[0] - 0.3).abs() < 1e-12, "{roots:?}");
    }

    #[test]
    fn a_crossing_pair_moves_as_a_rigid_zone_with_its_momentum_and_the_others_keep_theirs() {
        // Vertex 0 falls through the triangle; vertex 4 falls far away.
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2], DVec3::new(5.0, 0.5, 5.0)];
        let mut q = start;
        q[0] = DVec3::new(0.3, -0.5, 0.25);
        q[4].y = -0.5;
        let free = q;
        let pairs = [pair(true)];
        let unit = [1.0; 5];
        let changed =
            stop_crossings(&pairs, |_| Vec::new(), (&[0, 1, 2, 3, 4], &unit), |_, _| None, &start, &mut q, 1e-9);
        assert_eq!(changed, 4);
        assert!(!pairs[0].crosses(&start, &q, 1e-9));
        assert_eq!(q[4], free[4]);
        // Rigid: every distance in the zone kept.
        for i in 0..4 {
            for j in 0..4 {
                let (before, after) = (start[i].distance(start[j]), q[i].distance(q[j]));
                assert!((before - after).abs() < 1e-12, "{i} {j}: {before} {after}");
            }
        }
        // Linear momentum Σ dᵢ and angular momentum Σ rᵢ × dᵢ kept (about the start's centre,
        // to first order in the turn: the zone's own motion is small here).
        let linear = |p: &[DVec3]| (0..4).map(|i| p[i] - start[i]).sum::<DVec3>();
        assert!((linear(&q) - linear(&free)).length() < 1e-12);
        let centre = (0..4).map(|i| start[i]).sum::<DVec3>() / 4.0;
        let angular = |p: &[DVec3]| (0..4).map(|i| (start[i] - centre).cross(p[i] - start[i])).sum::<DVec3>();
        let (kept, had) = (angular(&q), angular(&free));
        assert!((kept - had).length() < 0.05 * had.length(), "{kept} {had}");
    }

    #[test]
    fn a_zone_whose_motion_enters_a_collider_is_moved_back_out_by_the_deepest_push() {
        // The pair above over a floor at y = −0.2 with a thickness of 0.05: the zone's rigid
        // motion (down by about 0.25) takes every vertex below the floor; the zone is lifted
        // as one to the thickness above it instead of being put back where it started.
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let mut q = start;
        q[0] = DVec3::new(0.3, -0.5, 0.25);
        let (floor, thickness) = (-0.2, 0.05);
        let outside =
            |_: u32, p: DVec3| (p.y < floor + thickness).then(|| DVec3::new(0.0, floor + thickness - p.y, 0.0));
        let unit = [1.0; 4];
        stop_crossings(&[pair(true)], |_| Vec::new(), (&[0, 1, 2, 3], &unit), outside, &start, &mut q, 1e-9);
        assert!(!pair(true).crosses(&start, &q, 1e-9));
        let lowest = q.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        assert!((lowest - (floor + thickness)).abs() < 1e-12, "lowest {lowest}");
        for i in 0..4 {
            assert_ne!(q[i], start[i], "vertex {i} was stopped");
            for j in 0..4 {
                assert!((start[i].distance(start[j]) - q[i].distance(q[j])).abs() < 1e-12, "{i} {j}");
            }
        }
        // Where no push can help (a path went through a collider just under the triangle),
        // and no part of the motion keeps out of it, the zone is put back.
        let mut q2 = start;
        q2[0] = DVec3::new(0.3, -0.5, 0.25);
        let through = |_: u32, p: DVec3| (p.y < -0.01).then_some(DVec3::ZERO);
        stop_crossings(&[pair(true)], |_| Vec::new(), (&[0, 1, 2, 3], &unit), through, &start, &mut q2, 1e-9);
        assert_eq!(q2, start);
    }

    #[test]
    fn zones_merge_until_nothing_crosses() {
        // Vertex 0 falls through the triangle, which a zone then carries down through a second
        // triangle lying under it: the second pair joins the zone.
        let below = [TRIANGLE[0] - 0.05 * DVec3::Y, TRIANGLE[1] - 0.05 * DVec3::Y, TRIANGLE[2] - 0.05 * DVec3::Y];
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2], below[0], below[1], below[2]];
        let mut q = start;
        q[0].y = -2.0;
        let first = pair(true);
        let seconds: Vec<ElementPair> =
            [0, 1, 2, 3].into_iter().filter_map(|v| ElementPair::vertex_triangle(v, [4, 5, 6], 0.0)).collect();
        let mut all_pairs = vec![first];
        all_pairs.extend(&seconds);
        let unit = [1.0; 7];
        stop_crossings(&all_pairs, |_| Vec::new(), (&[0, 1, 2, 3, 4, 5, 6], &unit), |_, _| None, &start, &mut q, 1e-9);
        for p in &all_pairs {
            assert!(!p.crosses(&start, &q, 1e-9), "{p:?}");
        }
        // Momentum kept across the merged zone: it all moves down by 2.5 / 7 on average.
        let mean = (0..7).map(|i| q[i] - start[i]).sum::<DVec3>() / 7.0;
        assert!((mean - DVec3::new(0.0, -2.5 / 7.0, 0.0)).length() < 1e-12, "{mean}");
    }

    #[test]
    fn vertices_at_one_place_are_no_crossing() {
        // Vertex 0 sits on the triangle's corner 1 (pushed there with it): leaving downward
        // is not a crossing, and a vertex falling through the middle still is.
        let start = [TRIANGLE[0], TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let mut q = start;
        q[0].y = -0.5;
        assert!(pair(true).coincident(&start, 1e-9));
        let unit = [1.0; 4];
        let changed =
            stop_crossings(&[pair(true)], |_| Vec::new(), (&[0, 1, 2, 3], &unit), |_, _| None, &start, &mut q, 1e-9);
        assert_eq!(changed, 0);
        let apart = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        assert!(!pair(true).coincident(&apart, 1e-9));
        let mut q = apart;
        q[0].y = -0.5;
        assert!(pair(true).crosses(&apart, &q, 1e-9));
    }

    #[test]
    fn a_held_vertex_keeps_its_motion_and_the_others_stop() {
        // The triangle is driven up through a resting vertex: the vertex (free) is put back,
        // the driven triangle is not.
        let start = [DVec3::new(0.2, 0.0, 0.2), TRIANGLE[0] - DVec3::Y, TRIANGLE[1] - DVec3::Y, TRIANGLE[2] - DVec3::Y];
        let mut q = start;
        q[0] = DVec3::new(0.2, -0.1, 0.2);
        for p in &mut q[1..] {
            *p += 2.0 * DVec3::Y;
        }
        let driven = q;
        let inverse_mass = [1.0, 0.0, 0.0, 0.0];
        stop_crossings(
            &[pair(true)],
            |_| Vec::new(),
            (&[0, 1, 2, 3], &inverse_mass),
            |_, _| None,
            &start,
            &mut q,
            1e-9,
        );
        assert_eq!(q[0], start[0]);
        assert_eq!(&q[1..], &driven[1..]);
    }

    #[test]
    fn a_pair_farther_than_its_motion_is_not_checked() {
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let mut q = start;
        q[0].y = 0.1;
        let far = ElementPair { distance: 0.5, ..pair(true) };
        assert!(!far.may_meet(&start, &q));
        q[0].y = -0.1;
        assert!(far.may_meet(&start, &q));
    }
}
