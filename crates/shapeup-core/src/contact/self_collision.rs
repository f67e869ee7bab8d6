//! Self-collision detection: vertex–triangle and edge–edge pairs of a surface that may come
//! within the thickness during a step.
//!
//! Broad phase: parry3d's BVH over each triangle's (and each edge's) box swept from the step's
//! start x_n to its prediction s, grown by the thickness, queried with each vertex's (each
//! edge's) swept box. Narrow phase at x_n: the closest points (Ericson, "Real-Time Collision
//! Detection", 2005, §5.1.5 point–triangle and §5.1.9 segment–segment); a pair closer than the
//! thickness plus twice its relative predicted motion is a contact, with the normal from the
//! second closest point to the first (the side it started on).

use super::gap::Contact;
use glam::DVec3;
use parry3d_f64::bounding_volume::Aabb;
use parry3d_f64::partitioning::{Bvh, BvhBuildStrategy};
use rayon::prelude::*;

/// The surface that collides with itself: its triangles, their edges and their vertices, and
/// the BVH over the triangles' swept boxes (refitted each step, rebuilt every
/// [`REBUILD_EVERY`] steps as the surface moves away from the tree's layout).
#[derive(Debug, Clone)]
pub(crate) struct Surface {
    triangles: Vec<[u32; 3]>,
    /// For each triangle, the indices of its three edges in `edges`.
    triangle_edges: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    vertices: Vec<u32>,
    bvh: Option<Bvh>,
    since_build: u32,
}

/// Steps between two full builds of the triangle BVH (refits in between).
const REBUILD_EVERY: u32 = 20;

impl Surface {
    /// The triangles whose three vertices are all `active`.
    pub(crate) fn new(triangles: &[[u32; 3]], active: &[bool]) -> Self {
        let triangles: Vec<[u32; 3]> =
            triangles.iter().copied().filter(|t| t.iter().all(|&v| active.get(v as usize) == Some(&true))).collect();
        let (edges, _, triangle_edges) = crate::topology::indexed_edges(&triangles);
        let mut vertices: Vec<u32> = triangles.iter().flatten().copied().collect();
        vertices.sort_unstable();
        vertices.dedup();
        Surface { triangles, triangle_edges, edges, vertices, bvh: None, since_build: 0 }
    }

    /// The BVH of the triangles' boxes `boxes`: refitted, or rebuilt when due.
    fn tree(&mut self, boxes: &[Aabb]) {
        match &mut self.bvh {
            Some(bvh) if self.since_build < REBUILD_EVERY => {
                for (i, b) in boxes.iter().enumerate() {
                    bvh.update_partially_if_present(*b, i as u32, 0.0);
                }
                bvh.refit_without_opt();
                self.since_build += 1;
            }
            _ => {
                self.bvh = Some(Bvh::from_leaves(BvhBuildStrategy::Binned, boxes));
                self.since_build = 0;
            }
        }
    }
}

fn to_parry(p: DVec3) -> parry3d_f64::math::Vector {
    parry3d_f64::math::Vector::new(p.x, p.y, p.z)
}

/// The box around the points at `start` and `predicted` of `vertices`, grown by `grow`.
fn swept_box(vertices: &[u32], start: &[DVec3], predicted: &[DVec3], grow: f64) -> Aabb {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for &v in vertices {
        for p in [start[v as usize], predicted[v as usize]] {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    Aabb::new(to_parry(lo - DVec3::splat(grow)), to_parry(hi + DVec3::splat(grow)))
}

/// The largest predicted motion of any of `others` relative to `first`'s vertices.
fn relative_motion(first: &[u32], others: &[u32], start: &[DVec3], predicted: &[DVec3]) -> f64 {
    let motion = |v: u32| predicted[v as usize] - start[v as usize];
    let mut most = 0.0f64;
    for &a in first {
        for &b in others {
            most = most.max((motion(a) - motion(b)).length());
        }
    }
    most
}

/// Every vertex–triangle and edge–edge contact of the step (see the [module docs](self)).
pub(crate) fn detect_self_contacts(
    surface: &mut Surface,
    start: &[DVec3],
    predicted: &[DVec3],
    thickness: f64,
    friction: f64,
) -> Vec<Contact> {
    if surface.triangles.is_empty() {
        return Vec::new();
    }
    let triangle_boxes: Vec<Aabb> =
        surface.triangles.par_iter().map(|t| swept_box(t, start, predicted, thickness)).collect();
    surface.tree(&triangle_boxes);
    let surface = &*surface;
    let Some(triangles) = &surface.bvh else { return Vec::new() };
    let mut contacts: Vec<Contact> = surface
        .vertices
        .par_iter()
        .flat_map_iter(|&v| {
            let query = swept_box(&[v], start, predicted, 0.0);
            let found: Vec<u32> = triangles.intersect_aabb(&query).collect();
            found.into_iter().filter_map(move |k| {
                let t = surface.triangles[k as usize];
                if t.contains(&v) {
                    return None;
                }
                let x = start[v as usize];
                let (c, b) = closest_on_triangle(x, t.map(|i| start[i as usize]));
                let distance = (x - c).length();
                let margin = thickness + 2.0 * relative_motion(&[v], &t, start, predicted);
                if distance >= margin || distance < 1e-12 {
                    return None;
                }
                let normal = (x - c) / distance;
                Some(Contact::new(&[v, t[0], t[1], t[2]], &[1.0, -b[0], -b[1], -b[2]], normal, thickness, friction))
            })
        })
        .collect();
    // Edge–edge: each edge against the edges of the triangles its swept box meets.
    contacts.par_extend(surface.edges.par_iter().enumerate().flat_map_iter(|(i, &e)| {
        let query = swept_box(&e, start, predicted, 0.0);
        let mut found: Vec<u32> = triangles
            .intersect_aabb(&query)
            .flat_map(|t| surface.triangle_edges[t as usize])
            .filter(|&j| j as usize > i)
            .collect();
        found.sort_unstable();
        found.dedup();
        found.into_iter().filter_map(move |j| {
            let f = surface.edges[j as usize];
            if f.contains(&e[0]) || f.contains(&e[1]) {
                return None;
            }
            let p = e.map(|v| start[v as usize]);
            let r = f.map(|v| start[v as usize]);
            let (s, t, a, b) = closest_between_segments(p[0], p[1], r[0], r[1]);
            let distance = (a - b).length();
            let margin = thickness + 2.0 * relative_motion(&e, &f, start, predicted);
            if distance >= margin || distance < 1e-12 {
                return None;
            }
            let normal = (a - b) / distance;
            Some(Contact::new(&[e[0], e[1], f[0], f[1]], &[1.0 - s, s, -(1.0 - t), -t], normal, thickness, friction))
        })
    }));
    contacts
}

/// The closest point of triangle `p` to `x` and its barycentric coordinates (Ericson §5.1.5).
pub(crate) fn closest_on_triangle(x: DVec3, p: [DVec3; 3]) -> (DVec3, [f64; 3]) {
    let [a, b, c] = p;
    let (ab, ac, ap) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, [1.0, 0.0, 0.0]);
    }
    let bp = x - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + w * (c - b), [0.0, 1.0 - w, w]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    if !(v.is_finite() && w.is_finite()) {
        // A degenerate triangle: its closest vertex.
        let d = [a, b, c].map(|q| (q - x).length_squared());
        let k = if d[0] <= d[1] && d[0] <= d[2] {
            0
        } else if d[1] <= d[2] {
            1
        } else {
            2
        };
        let mut bary = [0.0; 3];
        bary[k] = 1.0;
        return ([a, b, c][k], bary);
    }
    (a + ab * v + ac * w, [1.0 - v - w, v, w])
}

/// The closest points a = p0 + s (p1 − p0), b = q0 + t (q1 − q0) of two segments (Ericson
/// §5.1.9), as (s, t, a, b).
pub(crate) fn closest_between_segments(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> (f64, f64, DVec3, DVec3) {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    const EPS: f64 = 1e-24;
    let (s, t) = if a <= EPS && e <= EPS {
        (0.0, 0.0)
    } else if a <= EPS {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= EPS {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > EPS * a * e { ((b * f - c * e) / denom).clamp(0.0, 1.0) } else { 0.0 };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    (s, t, p0 + s * d1, q0 + t * d2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    fn v(seed: &mut u64) -> DVec3 {
        DVec3::new(rng(seed), rng(seed), rng(seed))
    }

    #[test]
    fn triangle_closest_point_beats_every_sample() {
        let mut seed = 5;
        for _ in 0..200 {
            let (x, p) = (v(&mut seed) * 2.0, [v(&mut seed), v(&mut seed), v(&mut seed)]);
            let (c, b) = closest_on_triangle(x, p);
            assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12 && b.iter().all(|&w| w >= -1e-12));
            assert!((p[0] * b[0] + p[1] * b[1] + p[2] * b[2] - c).length() < 1e-12);
            let d = (x - c).length();
            for i in 0..=30 {
                for j in 0..=30 - i {
                    let (u, w) = (i as f64 / 30.0, j as f64 / 30.0);
                    let s = p[0] * (1.0 - u - w) + p[1] * u + p[2] * w;
                    assert!(d <= (x - s).length() + 1e-12);
                }
            }
        }
    }

    #[test]
    fn segment_closest_points_beat_every_sample() {
        let mut seed = 9;
        for _ in 0..200 {
            let (p0, p1, q0, q1) = (v(&mut seed), v(&mut seed), v(&mut seed), v(&mut seed));
            let (s, t, a, b) = closest_between_segments(p0, p1, q0, q1);
            assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
            let d = (a - b).length();
            for i in 0..=40 {
                for j in 0..=40 {
                    let x = p0 + (p1 - p0) * (i as f64 / 40.0);
                    let y = q0 + (q1 - q0) * (j as f64 / 40.0);
                    assert!(d <= (x - y).length() + 1e-12);
                }
            }
        }
    }

    #[test]
    fn two_parallel_sheets_make_pairs_only_across() {
        // Two unit squares (two triangles each) 0.05 apart; thickness 0.1: every vertex of one
        // is near a triangle of the other, no pair within a sheet is (its triangles hold all
        // its vertices within 1 > 0.1).
        let mut start = Vec::new();
        for y in [0.0, 0.05] {
            for (x, z) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                start.push(DVec3::new(x, y, z));
            }
        }
        let triangles = [[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]];
        let mut surface = Surface::new(&triangles, &[true; 8]);
        let contacts = detect_self_contacts(&mut surface, &start, &start, 0.1, 0.0);
        assert!(!contacts.is_empty());
        for c in &contacts {
            let sheet = |v: u32| v / 4;
            let vs = &c.vertices[..c.len as usize];
            assert!(vs.iter().any(|&v| sheet(v) == 0) && vs.iter().any(|&v| sheet(v) == 1), "{vs:?}");
            assert!((c.gap(&start) - (0.05 - 0.1)).abs() < 1e-12, "gap {}", c.gap(&start));
        }
    }
}
