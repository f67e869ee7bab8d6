//! Vertex picking and box selection, occlusion-aware, as plain functions on positions,
//! triangles and an [`OrbitCamera`].
//!
//! Visibility comes from a CPU depth buffer: every triangle is rasterized (pixel centres, at
//! the viewport's resolution capped at [`MAX_BUFFER_SIDE`] pixels on the long side) keeping the
//! nearest depth, and a vertex is visible when it is no farther than the depth buffer around
//! its pixel. Cost: O(n + m + covered pixels) for n vertices and m triangles.

use crate::camera::{OrbitCamera, project_with};
use glam::{DVec3, Vec2, Vec3};

/// Longest side of the depth buffer in pixels; larger viewports are sampled down to it.
pub const MAX_BUFFER_SIDE: f32 = 2048.0;

/// Relative tolerance of the visibility test on view depth: a vertex up to 0.5 % of its
/// distance behind the depth buffer still counts as visible (it is on the surface there).
pub const DEPTH_TOLERANCE: f32 = 5e-3;

/// A vertex as seen on screen: its pixel and its reciprocal view depth 1/w (which, unlike w,
/// interpolates linearly across a triangle on screen).
#[derive(Debug, Clone, Copy)]
struct Projected {
    pixel: Vec2,
    inv_w: f32,
}

/// Projects every vertex; `None` behind the eye.
fn project_all(positions: &[DVec3], camera: &OrbitCamera, viewport: Vec2) -> Vec<Option<Projected>> {
    let view_projection = camera.view_projection(viewport);
    positions
        .iter()
        .map(|p| {
            let p = p.as_vec3();
            let clip = view_projection * p.extend(1.0);
            project_with(&view_projection, p, viewport).map(|(pixel, _)| Projected { pixel, inv_w: 1.0 / clip.w })
        })
        .collect()
}

/// A depth buffer of reciprocal view depths (larger = nearer; 0 = empty).
struct DepthBuffer {
    width: usize,
    height: usize,
    /// Buffer pixels per viewport pixel (≤ 1).
    scale: f32,
    inv_w: Vec<f32>,
}

impl DepthBuffer {
    fn new(viewport: Vec2) -> Self {
        let scale = (MAX_BUFFER_SIDE / viewport.x.max(viewport.y).max(1.0)).min(1.0);
        let width = (viewport.x * scale).ceil().max(1.0) as usize;
        let height = (viewport.y * scale).ceil().max(1.0) as usize;
        DepthBuffer { width, height, scale, inv_w: vec![0.0; width * height] }
    }

    /// Buffer cell of a viewport pixel, if inside.
    fn cell(&self, pixel: Vec2) -> Option<(usize, usize)> {
        let p = pixel * self.scale;
        let inside = p.x >= 0.0 && p.y >= 0.0 && (p.x as usize) < self.width && (p.y as usize) < self.height;
        inside.then_some((p.x as usize, p.y as usize))
    }

    fn write(&mut self, x: usize, y: usize, inv_w: f32) {
        let cell = &mut self.inv_w[y * self.width + x];
        *cell = cell.max(inv_w);
    }

    /// Rasterizes one triangle at the buffer's pixel centres, keeping the nearest depth; also
    /// writes its corners' own cells so that triangles smaller than a pixel leave no holes.
    fn rasterize(&mut self, corners: [Projected; 3]) {
        let p = corners.map(|c| c.pixel * self.scale);
        for (c, q) in corners.iter().zip(&p) {
            if let Some((x, y)) = self.cell(*q / self.scale) {
                self.write(x, y, c.inv_w);
            }
        }
        let area = edge(p[0], p[1], p[2]);
        if area.abs() < 1e-12 {
            return;
        }
        let lo = p[0].min(p[1]).min(p[2]).max(Vec2::ZERO);
        let hi = p[0].max(p[1]).max(p[2]).min(Vec2::new(self.width as f32, self.height as f32));
        if lo.x >= hi.x || lo.y >= hi.y {
            return;
        }
        // Pixel (x, y) has its centre at (x + ½, y + ½).
        let (x0, x1) = ((lo.x - 0.5).ceil().max(0.0) as usize, ((hi.x - 0.5).floor() as usize).min(self.width - 1));
        let (y0, y1) = ((lo.y - 0.5).ceil().max(0.0) as usize, ((hi.y - 0.5).floor() as usize).min(self.height - 1));
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                // Barycentric coordinates from signed areas (either winding).
                let b = [edge(p[1], p[2], c) / area, edge(p[2], p[0], c) / area, edge(p[0], p[1], c) / area];
                if b.iter().all(|&b| b >= -1e-6) {
                    let inv_w = b[0] * corners[0].inv_w + b[1] * corners[1].inv_w + b[2] * corners[2].inv_w;
                    self.write(x, y, inv_w);
                }
            }
        }
    }

    /// The farthest depth (smallest 1/w) among the covered cells around a cell; an empty cell
    /// nearby means nothing occludes the vertex there (its own silhouette).
    fn farthest_around(&self, x: usize, y: usize) -> f32 {
        let mut farthest = f32::INFINITY;
        for yy in y.saturating_sub(1)..=(y + 1).min(self.height - 1) {
            for xx in x.saturating_sub(1)..=(x + 1).min(self.width - 1) {
                farthest = farthest.min(self.inv_w[yy * self.width + xx]);
            }
        }
        farthest
    }
}

/// Twice the signed area of (a, b, c).
fn edge(a: Vec2, b: Vec2, c: Vec2) -> f32 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// Which vertices are visible: inside the viewport, in front of the eye and not hidden behind
/// the surface (triangles with a corner behind the eye are not drawn as occluders).
///
/// `positions`: n world positions; `triangles`: m index triples. Returns n flags.
pub fn visible_vertices(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    camera: &OrbitCamera,
    viewport: Vec2,
) -> Vec<bool> {
    let projected = project_all(positions, camera, viewport);
    let mut buffer = DepthBuffer::new(viewport);
    for t in triangles {
        let corners = t.map(|v| projected.get(v as usize).copied().flatten());
        if let [Some(a), Some(b), Some(c)] = corners {
            buffer.rasterize([a, b, c]);
        }
    }
    projected
        .iter()
        .map(|p| {
            p.is_some_and(|p| {
                buffer.cell(p.pixel).is_some_and(|(x, y)| {
                    // Visible when w ≤ w_buffer (1 + tolerance), i.e. in terms of 1/w:
                    p.inv_w * (1.0 + DEPTH_TOLERANCE) >= buffer.farthest_around(x, y)
                })
            })
        })
        .collect()
}

/// The visible vertices inside the screen rectangle spanned by two pixel corners (in either
/// order, bounds included), as ascending indices.
pub fn box_select(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    camera: &OrbitCamera,
    viewport: Vec2,
    corner_a: Vec2,
    corner_b: Vec2,
) -> Vec<u32> {
    let (lo, hi) = (corner_a.min(corner_b), corner_a.max(corner_b));
    let visible = visible_vertices(positions, triangles, camera, viewport);
    let view_projection = camera.view_projection(viewport);
    positions
        .iter()
        .zip(&visible)
        .enumerate()
        .filter(|&(_, (p, &vis))| {
            vis && project_with(&view_projection, p.as_vec3(), viewport)
                .is_some_and(|(pixel, _)| pixel.cmpge(lo).all() && pixel.cmple(hi).all())
        })
        .map(|(v, _)| v as u32)
        .collect()
}

/// The visible vertex nearest to the cursor on screen, within `radius_px` pixels.
/// `visible` comes from [`visible_vertices`] (compute it once per camera or shape change).
pub fn pick_vertex(
    positions: &[DVec3],
    visible: &[bool],
    camera: &OrbitCamera,
    viewport: Vec2,
    cursor: Vec2,
    radius_px: f32,
) -> Option<u32> {
    let view_projection = camera.view_projection(viewport);
    let mut best: Option<(u32, f32)> = None;
    for (v, (p, &vis)) in positions.iter().zip(visible).enumerate() {
        if !vis {
            continue;
        }
        let Some((pixel, _)) = project_with(&view_projection, p.as_vec3(), viewport) else { continue };
        let d = pixel.distance(cursor);
        if d <= radius_px && best.is_none_or(|(_, bd)| d < bd) {
            best = Some((v as u32, d));
        }
    }
    best.map(|(v, _)| v)
}

/// The polygon face under the cursor: the front-most triangle (largest interpolated 1/w)
/// whose screen projection contains it, mapped to its face by `triangle_face` (the mesh's
/// triangle → polygon table). `None` when the cursor is off the mesh.
pub fn pick_face(
    positions: &[DVec3],
    triangles: &[[u32; 3]],
    triangle_face: &[u32],
    camera: &OrbitCamera,
    viewport: Vec2,
    cursor: Vec2,
) -> Option<u32> {
    let projected = project_all(positions, camera, viewport);
    let mut best: Option<(u32, f32)> = None;
    for (t, &face) in triangles.iter().zip(triangle_face) {
        let [Some(a), Some(b), Some(c)] = t.map(|v| projected.get(v as usize).copied().flatten()) else { continue };
        let area = edge(a.pixel, b.pixel, c.pixel);
        if area.abs() <= f32::EPSILON {
            continue;
        }
        // Barycentric coordinates of the cursor; all of one sign inside (either winding).
        let (wa, wb, wc) = (
            edge(b.pixel, c.pixel, cursor) / area,
            edge(c.pixel, a.pixel, cursor) / area,
            edge(a.pixel, b.pixel, cursor) / area,
        );
        if wa < 0.0 || wb < 0.0 || wc < 0.0 {
            continue;
        }
        let inv_w = wa * a.inv_w + wb * b.inv_w + wc * c.inv_w;
        if best.is_none_or(|(_, d)| inv_w > d) {
            best = Some((face, inv_w));
        }
    }
    best.map(|(f, _)| f)
}

/// The faces all of whose corners are in `vertices` (ascending vertex indices), ascending:
/// what a box selection in face mode picks.
pub fn faces_within(faces: &shapeup_core::mesh::Polygons, vertices: &[u32], num_vertices: usize) -> Vec<u32> {
    let mut inside = vec![false; num_vertices];
    for &v in vertices {
        if let Some(x) = inside.get_mut(v as usize) {
            *x = true;
        }
    }
    faces
        .iter()
        .enumerate()
        .filter(|(_, corners)| corners.iter().all(|&v| inside.get(v as usize).copied().unwrap_or(false)))
        .map(|(f, _)| f as u32)
        .collect()
}

/// Axis-aligned bounds (min, max) of positions as f32, for [`OrbitCamera::frame`]; a unit box
/// around the origin when there are none.
pub fn bounds(positions: &[DVec3]) -> (Vec3, Vec3) {
    if positions.is_empty() {
        return (Vec3::splat(-0.5), Vec3::splat(0.5));
    }
    let (lo, hi) = positions.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (lo.as_vec3(), hi.as_vec3())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    const VIEWPORT: Vec2 = Vec2::new(800.0, 600.0);

    /// A camera on +Z looking at the origin head-on.
    fn head_on() -> OrbitCamera {
        let mut c = OrbitCamera::with_angles(0.0, 0.0);
        c.frame(Vec3::splat(-1.0), Vec3::splat(1.0));
        c
    }

    /// Two unit quads facing +Z: vertices 0..4 at z = 0.5 (front), 4..8 at z = −0.5 (back).
    fn two_quads(back_size: f64) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mut p = Vec::new();
        for (z, s) in [(0.5, 0.5), (-0.5, back_size)] {
            p.extend([DVec3::new(-s, -s, z), DVec3::new(s, -s, z), DVec3::new(s, s, z), DVec3::new(-s, s, z)]);
        }
        (p, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]])
    }

    /// A closed cube [-0.5, 0.5]³ of 12 triangles, outward normals.
    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p =
            (0..8).map(|k| DVec3::new((k & 1) as f64 - 0.5, ((k >> 1) & 1) as f64 - 0.5, ((k >> 2) & 1) as f64 - 0.5));
        let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
        let tris = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
        (p.collect(), tris)
    }

    #[test]
    fn front_quad_hides_the_one_behind() {
        let (p, t) = two_quads(0.4);
        let visible = visible_vertices(&p, &t, &head_on(), VIEWPORT);
        assert_eq!(visible, [true, true, true, true, false, false, false, false]);
        let all = box_select(&p, &t, &head_on(), VIEWPORT, Vec2::ZERO, VIEWPORT);
        assert_eq!(all, [0, 1, 2, 3]);
    }

    #[test]
    fn a_larger_quad_behind_shows_its_corners() {
        let (p, t) = two_quads(2.0);
        let visible = visible_vertices(&p, &t, &head_on(), VIEWPORT);
        assert_eq!(visible, [true; 8]);
    }

    #[test]
    fn cube_seen_head_on() {
        let (p, t) = cube();
        let c = head_on();
        let visible = visible_vertices(&p, &t, &c, VIEWPORT);
        let front: Vec<bool> = p.iter().map(|q| q.z > 0.0).collect();
        assert_eq!(visible, front);
        // Seen from a corner direction, the far corner (-,-,-) is hidden, the near one is not.
        let mut corner = OrbitCamera::with_angles(0.6, 0.5);
        corner.frame(Vec3::splat(-1.0), Vec3::splat(1.0));
        let visible = visible_vertices(&p, &t, &corner, VIEWPORT);
        assert!(visible[7] && !visible[0], "{visible:?}");
    }

    #[test]
    fn selection_respects_the_rectangle() {
        let (p, t) = two_quads(0.4);
        let c = head_on();
        let (a, _) = c.project(p[0].as_vec3(), VIEWPORT).unwrap();
        // A box around the bottom-left front corner only (the back corner is hidden anyway).
        let picked = box_select(&p, &t, &c, VIEWPORT, a + Vec2::splat(5.0), a - Vec2::splat(5.0));
        assert_eq!(picked, [0]);
        // A box in an empty part of the screen picks nothing.
        assert!(box_select(&p, &t, &c, VIEWPORT, Vec2::ZERO, Vec2::splat(20.0)).is_empty());
        // The left half: corners 0 and 3.
        let picked = box_select(&p, &t, &c, VIEWPORT, Vec2::ZERO, Vec2::new(400.0, 600.0));
        assert_eq!(picked, [0, 3]);
    }

    #[test]
    fn pick_takes_the_nearest_visible_vertex() {
        let (p, t) = two_quads(0.4);
        let c = head_on();
        let visible = visible_vertices(&p, &t, &c, VIEWPORT);
        let (a, _) = c.project(p[2].as_vec3(), VIEWPORT).unwrap();
        assert_eq!(pick_vertex(&p, &visible, &c, VIEWPORT, a + Vec2::new(3.0, -2.0), 8.0), Some(2));
        assert_eq!(pick_vertex(&p, &visible, &c, VIEWPORT, a + Vec2::new(30.0, 0.0), 8.0), None);
        // The hidden back corner is never picked, even with the cursor right on it.
        let (b, _) = c.project(p[6].as_vec3(), VIEWPORT).unwrap();
        assert_ne!(pick_vertex(&p, &visible, &c, VIEWPORT, b, 8.0), Some(6));
    }

    #[test]
    fn dense_grid_is_fast_and_fully_visible() {
        // 190 × 190 ≈ 36k vertices, 71k triangles: a flat sheet facing the camera.
        let n = 190;
        let p: Vec<DVec3> = (0..n * n)
            .map(|k| DVec3::new((k % n) as f64 / (n - 1) as f64 - 0.5, (k / n) as f64 / (n - 1) as f64 - 0.5, 0.0))
            .collect();
        let mut t = Vec::new();
        for y in 0..n - 1 {
            for x in 0..n - 1 {
                let v = (y * n + x) as u32;
                t.push([v, v + 1, v + n as u32 + 1]);
                t.push([v, v + n as u32 + 1, v + n as u32]);
            }
        }
        let start = std::time::Instant::now();
        let picked = box_select(&p, &t, &head_on(), VIEWPORT, Vec2::ZERO, VIEWPORT);
        assert!(start.elapsed().as_secs_f64() < 2.0, "{:?}", start.elapsed());
        assert_eq!(picked.len(), n * n);
    }

    #[test]
    fn bounds_of_points() {
        let (lo, hi) = bounds(&[DVec3::new(1.0, -2.0, 0.0), DVec3::new(-1.0, 3.0, 0.5)]);
        assert_eq!((lo, hi), (Vec3::new(-1.0, -2.0, 0.0), Vec3::new(1.0, 3.0, 0.5)));
    }
}
