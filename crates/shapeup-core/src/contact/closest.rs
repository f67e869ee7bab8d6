//! Closest points of triangles and segments (Ericson, "Real-Time Collision Detection", 2005):
//! the narrow phase of self-collision, of the colliders' feature contacts and of the crossing
//! check.

use glam::DVec3;

/// The closest point to `x` of a triangle `p` without area: the nearest of its edges' closest
/// points, with its barycentric coordinates.
fn closest_on_degenerate_triangle(x: DVec3, p: [DVec3; 3]) -> (DVec3, [f64; 3]) {
    let mut best = (p[0], [1.0, 0.0, 0.0]);
    let mut nearest = (x - p[0]).length_squared();
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let (t, _, point, _) = closest_between_segments(p[i], p[j], x, x);
        let distance = (x - point).length_squared();
        if distance < nearest {
            let mut b = [0.0; 3];
            b[i] = 1.0 - t;
            b[j] = t;
            best = (point, b);
            nearest = distance;
        }
    }
    best
}

/// The closest point of triangle `p` to `x` and its barycentric coordinates (Ericson §5.1.5).
pub(crate) fn closest_on_triangle(x: DVec3, p: [DVec3; 3]) -> (DVec3, [f64; 3]) {
    let [a, b, c] = p;
    let (ab, ac, ap) = (b - a, c - a, x - a);
    // Collinear corners (a crumpled or pushed cloth can bring two together): the region tests
    // below assume an area, so the closest point of its three edges instead.
    if ab.cross(ac).length_squared() <= 1e-24 * ab.length_squared() * ac.length_squared() {
        return closest_on_degenerate_triangle(x, p);
    }
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
        let v = if d1 - d3 > 0.0 { d1 / (d1 - d3) } else { 0.0 };
        return (a + v * ab, [1.0 - v, v, 0.0]);
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = if d2 - d6 > 0.0 { d2 / (d2 - d6) } else { 0.0 };
        return (a + w * ac, [1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let across = (d4 - d3) + (d5 - d6);
        let w = if across > 0.0 { (d4 - d3) / across } else { 0.0 };
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
pub(crate) mod tests {
    use super::*;

    /// A uniform number in [−1, 1) from a linear congruential generator (Knuth's MMIX).
    pub(crate) fn rng(seed: &mut u64) -> f64 {
        *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }

    pub(crate) fn v(seed: &mut u64) -> DVec3 {
        DVec3::new(rng(seed), rng(seed), rng(seed))
    }

    #[test]
    fn a_triangle_with_two_vertices_at_one_point_has_finite_closest_points() {
        // Vertices pushed out of a sphere along the same ray land on one point; the edge
        // regions' parameters were 0/0 there.
        let (a, c) = (DVec3::ZERO, DVec3::new(0.0, 0.0, 1.0));
        for x in [
            DVec3::new(0.0, 1.0, 0.5),
            DVec3::new(-1.0, 0.0, 2.0),
            DVec3::new(0.3, 0.0, -0.2),
            DVec3::new(2.0, 1.0, 0.5),
        ] {
            for t in [[a, a, c], [a, c, a], [c, a, a], [a, a, a]] {
                let (p, b) = closest_on_triangle(x, t);
                assert!(p.is_finite() && b.iter().all(|w| w.is_finite()), "{x} {t:?}: {p} {b:?}");
                let on: DVec3 = (0..3).map(|k| b[k] * t[k]).sum();
                assert!((on - p).length() < 1e-12, "{x} {t:?}");
                // The closest point of the segment a–c (or the point a).
                let s = if t.contains(&c) { x.z.clamp(0.0, 1.0) } else { 0.0 };
                assert!((p - DVec3::new(0.0, 0.0, s)).length() < 1e-12, "{x} {t:?}: {p}");
            }
        }
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
}
