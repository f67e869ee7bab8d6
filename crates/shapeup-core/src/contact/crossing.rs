//! The fail-safe of self-collision: at the end of a time step, the element pairs whose paths
//! from the step's start x_n to its end q cross (a vertex through a triangle, an edge through
//! an edge) are found by a continuous check, and their vertices are stopped: put back at x_n.
//! Repeated until nothing crosses, so a step never makes the surface pass through itself:
//! x_n had no crossing, and a step that stops every vertex is x_n again.
//!
//! The contacts of a step keep pairs apart only as far as a finite number of iterations and
//! projections can: a fold pressed between a collider and itself, where the collider's
//! projection has the last word, let a vertex slip through a triangle. Stopping is the
//! simplest of the fail-safes of Bridson, Fedkiw and Anderson ("Robust Treatment of Collisions,
//! Contact and Friction for Cloth Animation", SIGGRAPH 2002, §7.3, rigid impact zones): a
//! stopped vertex loses its velocity for that step, which is rare and local.
//!
//! The continuous check of a pair (Provot, "Collision and self-collision handling in cloth
//! model dedicated to design garments", 1997): the four points, moving linearly over the step,
//! are coplanar where the cubic f(t) = (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀) vanishes; at each of its
//! roots in [0, 1] the pair crosses when the vertex is on the triangle (the two edges meet), to
//! within a tolerance.

use super::closest::{closest_between_segments, closest_on_triangle};
use glam::DVec3;
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

    /// Whether the pair can come within `0` of itself over a step whose vertices move by
    /// `q − start`: the distance at x_n less the largest relative motion of a vertex of one
    /// side against one of the other (any point of an element moves by a convex combination
    /// of its vertices' motions).
    fn may_meet(&self, start: &[DVec3], q: &[DVec3]) -> bool {
        let motion = |v: u32| q[v as usize] - start[v as usize];
        let split = if self.vertex_triangle { 1 } else { 2 };
        let (first, second) = self.vertices.split_at(split);
        let mut most = 0.0f64;
        for &a in first {
            for &b in second {
                most = most.max((motion(a) - motion(b)).length_squared());
            }
        }
        most.sqrt() >= self.distance
    }

    /// Whether the pair's paths from `start` to `q` cross (see the [module docs](self)), to
    /// within `tolerance`.
    pub(crate) fn crosses(&self, start: &[DVec3], q: &[DVec3], tolerance: f64) -> bool {
        let x = self.vertices.map(|v| start[v as usize]);
        let d = self.vertices.map(|v| q[v as usize] - start[v as usize]);
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
        coplanar_times(x, d).into_iter().flatten().any(meet)
    }
}

/// The times t ∈ [0, 1] at which the points x_k + t d_k are coplanar: the roots of the cubic
/// f(t) = (x₁ − x₀) × (x₂ − x₀) · (x₃ − x₀), each bracketed between the cubic's turning points
/// and bisected; where f vanishes at a bracket's end, that end (so a pair coplanar throughout
/// is tested at 0, 1 and its turning points).
fn coplanar_times(x: [DVec3; 4], d: [DVec3; 4]) -> [Option<f64>; 5] {
    let (a0, a1) = (x[1] - x[0], d[1] - d[0]);
    let (b0, b1) = (x[2] - x[0], d[2] - d[0]);
    let (c0, c1) = (x[3] - x[0], d[3] - d[0]);
    // (a0 + t a1) × (b0 + t b1) · (c0 + t c1), term by term.
    let (ab0, ab1, ab2) = (a0.cross(b0), a1.cross(b0) + a0.cross(b1), a1.cross(b1));
    let k = [ab0.dot(c0), ab1.dot(c0) + ab0.dot(c1), ab2.dot(c0) + ab1.dot(c1), ab2.dot(c1)];
    let f = |t: f64| ((k[3] * t + k[2]) * t + k[1]) * t + k[0];
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
        let (mut lo, mut hi) = (w[0], w[1]);
        let (mut flo, fhi) = (f(lo), f(hi));
        if flo == 0.0 {
            roots[found] = Some(lo);
            found += 1;
        } else if flo * fhi < 0.0 {
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                let fm = f(mid);
                if (fm < 0.0) == (flo < 0.0) {
                    lo = mid;
                    flo = fm;
                } else {
                    hi = mid;
                }
            }
            roots[found] = Some(0.5 * (lo + hi));
            found += 1;
        }
    }
    if f(1.0) == 0.0 {
        roots[found] = Some(1.0);
    }
    roots
}

/// Puts back at `start` the vertices of every pair whose paths from `start` to `q` cross,
/// until none does (see the [module docs](self)). The pairs checked each round are `pairs`
/// and those `more` gives for the current `q` (the pairs a step's own detection cannot vouch
/// for); after `MAX_ROUNDS` rounds, every vertex of `all` is put back. Vertices whose inverse
/// mass is 0 (hard pins, driven handles) are never put back: their motion is prescribed.
/// Returns how many vertices were stopped.
pub(crate) fn stop_crossings(
    pairs: &[ElementPair],
    mut more: impl FnMut(&[DVec3]) -> Vec<ElementPair>,
    (all, inverse_mass): (&[u32], &[f64]),
    start: &[DVec3],
    q: &mut [DVec3],
    tolerance: f64,
) -> usize {
    const MAX_ROUNDS: usize = 16;
    let mut stopped = 0;
    for _ in 0..MAX_ROUNDS {
        let extra = more(q);
        let view: &[DVec3] = q;
        let crossing: Vec<[u32; 4]> = pairs
            .par_iter()
            .chain(extra.par_iter())
            .filter(|p| p.may_meet(start, view) && p.crosses(start, view, tolerance))
            .map(|p| p.vertices)
            .collect();
        let mut changed = false;
        for v in crossing.into_iter().flatten() {
            let v = v as usize;
            if q[v] != start[v] && inverse_mass[v] > 0.0 {
                q[v] = start[v];
                stopped += 1;
                changed = true;
            }
        }
        if !changed {
            return stopped;
        }
    }
    for &v in all {
        let v = v as usize;
        if q[v] != start[v] && inverse_mass[v] > 0.0 {
            q[v] = start[v];
            stopped += 1;
        }
    }
    stopped
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn coplanar_times_are_the_cubics_roots() {
        // A vertex falling at unit speed through the plane y = 0 at t = 0.3.
        let x = [DVec3::new(0.2, 0.3, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2]];
        let d = [DVec3::new(0.0, -1.0, 0.0), DVec3::ZERO, DVec3::ZERO, DVec3::ZERO];
        let roots: Vec<f64> = coplanar_times(x, d).into_iter().flatten().collect();
        assert_eq!(roots.len(), 1);
        assert!((roots[0] - 0.3).abs() < 1e-12, "{roots:?}");
    }

    #[test]
    fn stopping_puts_every_crossing_vertex_back_and_leaves_the_others() {
        // Vertex 0 falls through the triangle; vertex 4 falls far away.
        let start = [DVec3::new(0.2, 0.5, 0.2), TRIANGLE[0], TRIANGLE[1], TRIANGLE[2], DVec3::new(5.0, 0.5, 5.0)];
        let mut q = start;
        q[0].y = -0.5;
        q[4].y = -0.5;
        let pairs = [pair(true)];
        let free = [1.0; 5];
        let stopped = stop_crossings(&pairs, |_| Vec::new(), (&[0, 1, 2, 3, 4], &free), &start, &mut q, 1e-9);
        assert_eq!(stopped, 1);
        assert_eq!(q[0], start[0]);
        assert_eq!(q[4].y, -0.5);
        assert!(!pairs[0].crosses(&start, &q, 1e-9));
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
        stop_crossings(&[pair(true)], |_| Vec::new(), (&[0, 1, 2, 3], &inverse_mass), &start, &mut q, 1e-9);
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
