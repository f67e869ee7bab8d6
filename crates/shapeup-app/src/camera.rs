//! An orbit camera: it looks at a target from a distance, turned by yaw and pitch, with +Y up.
//!
//! Conventions: world space is right-handed with +Y up; pixels have their origin at the top-left
//! corner of the viewport, +x right and +y down; the projection maps view depth to wgpu's NDC
//! depth range 0..1 (0 at the near plane) with NDC y up. A viewport is its size in pixels
//! (`Vec2::new(width, height)`).
//!
//! [`FrontView`] picks the side a y-up mesh is first seen from, and [`OrbitCamera::frame_front`]
//! frames a mesh from there.

use glam::{DVec3, Mat4, Vec2, Vec3, Vec4};

/// Smallest distance to the target (zooming in stops here).
const MIN_DISTANCE: f32 = 1e-6;
/// Pitch stays this far from ±90° so that the view never aligns with the up vector.
const PITCH_LIMIT: f32 = std::f32::consts::FRAC_PI_2 - 1e-3;
/// Zoom factor per wheel step.
const ZOOM_PER_STEP: f32 = 0.9;

/// An orbit camera. Angles are in radians.
///
/// The eye sits at `target + distance · (cos pitch · sin yaw, sin pitch, cos pitch · cos yaw)`:
/// yaw = pitch = 0 looks along −Z.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct OrbitCamera {
    /// The point looked at and orbited around.
    pub target: Vec3,
    /// Distance from the eye to the target (> 0).
    pub distance: f32,
    /// Rotation about +Y.
    pub yaw: f32,
    /// Elevation above the XZ plane, within ±(90° − 0.06°).
    pub pitch: f32,
    /// Vertical field of view (default 45°).
    pub fov_y: f32,
    /// Radius of the framed scene, which sets the near and far planes.
    pub scene_radius: f32,
    /// The view [`OrbitCamera::reset`] returns to: the last framed one.
    home: Home,
}

/// The framed view, for [`OrbitCamera::reset`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
struct Home {
    target: Vec3,
    distance: f32,
    yaw: f32,
    pitch: f32,
}

impl Default for OrbitCamera {
    /// Looks at the origin from distance 3 along +Z, slightly from above, 45° field of view.
    fn default() -> Self {
        let home = Home { target: Vec3::ZERO, distance: 3.0, yaw: 0.0, pitch: 0.2 };
        OrbitCamera {
            target: home.target,
            distance: home.distance,
            yaw: home.yaw,
            pitch: home.pitch,
            fov_y: 45f32.to_radians(),
            scene_radius: 1.0,
            home,
        }
    }
}

impl OrbitCamera {
    /// The default camera turned to `yaw` and `pitch` (radians; pitch is clamped).
    pub fn with_angles(yaw: f32, pitch: f32) -> Self {
        OrbitCamera { yaw, pitch: pitch.clamp(-PITCH_LIMIT, PITCH_LIMIT), ..OrbitCamera::default() }
    }

    /// Frames the axis-aligned box `[min, max]`: looks at its centre from a distance at which
    /// its bounding sphere fits the vertical field of view (and the horizontal one of any
    /// viewport at least as wide as it is high), with a 10 % margin. Keeps yaw and pitch; the
    /// result becomes the view [`OrbitCamera::reset`] returns to.
    pub fn frame(&mut self, min: Vec3, max: Vec3) {
        self.look_at(min, max);
        self.scene_radius = (0.5 * (max - min).length()).max(1e-6);
        self.home = Home { target: self.target, distance: self.distance, yaw: self.yaw, pitch: self.pitch };
    }

    /// Looks at the box `[min, max]` as [`OrbitCamera::frame`] does (centre, distance), keeping
    /// the angles, the view [`OrbitCamera::reset`] returns to, and the scene's size (the clip
    /// planes): the editor's F on a selection.
    pub fn look_at(&mut self, min: Vec3, max: Vec3) {
        let radius = (0.5 * (max - min).length()).max(1e-6);
        self.target = 0.5 * (min + max);
        self.distance = 1.1 * radius / (0.5 * self.fov_y).sin();
    }

    /// Frames a mesh from its front (see [`FrontView`]): turns to [`FrontView::of`] the mesh and
    /// frames the bounding box of all `positions` (see [`OrbitCamera::frame`]), which becomes the
    /// view [`OrbitCamera::reset`] returns to. With no positions only the angles change.
    pub fn frame_front(&mut self, positions: &[DVec3], triangles: &[[u32; 3]]) {
        let front = FrontView::of(positions, triangles);
        self.yaw = front.yaw;
        self.pitch = front.pitch.clamp(-PITCH_LIMIT, PITCH_LIMIT);
        let bounds = positions.iter().fold(None, |bounds: Option<(DVec3, DVec3)>, &p| match bounds {
            None => Some((p, p)),
            Some((lo, hi)) => Some((lo.min(p), hi.max(p))),
        });
        match bounds {
            Some((lo, hi)) => self.frame(lo.as_vec3(), hi.as_vec3()),
            None => self.home = Home { yaw: self.yaw, pitch: self.pitch, ..self.home },
        }
    }

    /// Back to the last framed view (see [`OrbitCamera::frame`]).
    pub fn reset(&mut self) {
        let h = self.home;
        (self.target, self.distance, self.yaw, self.pitch) = (h.target, h.distance, h.yaw, h.pitch);
    }

    /// Turns the camera around the target by a mouse drag: a drag across the viewport's height
    /// turns by 180°; dragging right turns the scene right, dragging down tilts it down. The
    /// distance to the target does not change.
    pub fn orbit(&mut self, delta_px: Vec2, viewport: Vec2) {
        let per_px = std::f32::consts::PI / viewport.y.max(1.0);
        self.yaw -= delta_px.x * per_px;
        self.pitch = (self.pitch + delta_px.y * per_px).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves the target (and the eye) in the view plane so that a point at the target's depth
    /// follows the mouse exactly.
    pub fn pan(&mut self, delta_px: Vec2, viewport: Vec2) {
        // The scene follows the mouse, so the camera moves the other way.
        self.target -= self.drag_in_view_plane(delta_px, self.target, viewport);
    }

    /// Zooms by `wheel_steps` (positive = closer): the distance is multiplied by 0.9 per step.
    pub fn zoom(&mut self, wheel_steps: f32) {
        self.distance = (self.distance * ZOOM_PER_STEP.powf(wheel_steps)).max(MIN_DISTANCE);
    }

    /// Unit vector from the target to the eye.
    fn backward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }

    /// Unit vectors (right, up, forward) of the view, in world space.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = -self.backward();
        let right = forward.cross(Vec3::Y).normalize_or(Vec3::X);
        let up = right.cross(forward);
        (right, up, forward)
    }

    /// The eye position.
    pub fn eye(&self) -> Vec3 {
        self.target + self.distance * self.backward()
    }

    /// Near and far plane distances: they bracket the framed scene's sphere around the target
    /// generously, keeping their ratio moderate for depth precision.
    pub fn near_far(&self) -> (f32, f32) {
        let near = (self.distance * 1e-2).max(MIN_DISTANCE * 1e-2);
        let far = self.distance * 1e2 + 4.0 * self.scene_radius;
        (near, far)
    }

    /// World → view matrix (right-handed, looking down −Z in view space, +Y up).
    pub fn view(&self) -> Mat4 {
        let (_, up, _) = self.basis();
        glam::camera::rh::view::look_at_mat4(self.eye(), self.target, up)
    }

    /// View → clip perspective projection, right-handed, NDC depth 0..1 (near → 0) and NDC y
    /// up, as wgpu expects (glam's `camera::rh::proj::directx::perspective`).
    pub fn projection(&self, aspect: f32) -> Mat4 {
        let (near, far) = self.near_far();
        glam::camera::rh::proj::directx::perspective(self.fov_y, aspect.max(1e-6), near, far)
    }

    /// World → clip matrix for a viewport of this size.
    pub fn view_projection(&self, viewport: Vec2) -> Mat4 {
        self.projection(viewport.x / viewport.y.max(1.0)) * self.view()
    }

    /// Pixel position (top-left origin) and NDC depth (0 near … 1 far) of a world point;
    /// `None` when the point is behind the eye (or on its plane). Points outside the viewport
    /// still project (their pixel lies outside it).
    pub fn project(&self, p: Vec3, viewport: Vec2) -> Option<(Vec2, f32)> {
        project_with(&self.view_projection(viewport), p, viewport)
    }

    /// The ray through a pixel: (origin at the eye, unit direction).
    pub fn ray(&self, pixel: Vec2, viewport: Vec2) -> (Vec3, Vec3) {
        let inverse = self.view_projection(viewport).inverse();
        let ndc = Vec2::new(2.0 * pixel.x / viewport.x.max(1.0) - 1.0, 1.0 - 2.0 * pixel.y / viewport.y.max(1.0));
        let far = inverse * Vec4::new(ndc.x, ndc.y, 1.0, 1.0);
        let eye = self.eye();
        let dir = (far.truncate() / far.w - eye).normalize_or(self.basis().2);
        (eye, dir)
    }

    /// World displacement of a point at the anchor's depth that follows a mouse move of
    /// `delta_px` on screen (in the plane facing the camera through the anchor).
    pub fn drag_in_view_plane(&self, delta_px: Vec2, anchor: Vec3, viewport: Vec2) -> Vec3 {
        let (right, up, forward) = self.basis();
        let depth = (anchor - self.eye()).dot(forward).max(MIN_DISTANCE);
        // World units per pixel at that depth: the viewport height spans 2·depth·tan(fov/2).
        let per_px = 2.0 * depth * (0.5 * self.fov_y).tan() / viewport.y.max(1.0);
        per_px * (delta_px.x * right - delta_px.y * up)
    }
}

/// Yaw of the three-quarter view away from the front axis, towards the mesh's head (≈ 29°).
pub const THREE_QUARTER_YAW: f32 = 0.5;
/// Elevation of the front view (≈ 14°), so that the top of the mesh gives the view depth.
pub const FRONT_PITCH: f32 = 0.25;
/// Projected areas within this relative difference count as equal (then Z is the front axis).
const AREA_TIE: f64 = 0.02;
/// A surface faces one side of the front axis when its net area-weighted normal along the axis
/// is at least this fraction of its total `Σ |n·d| A` (below: both sides are equal).
const FACING_TIE: f64 = 0.01;
/// A mesh leans (its head is) towards one end of the cross axis when the correlation of height
/// and position along that axis is at least this large in magnitude.
const LEAN_TIE: f64 = 0.1;

/// The side a y-up mesh is first seen from: its front axis, and a three-quarter turn towards
/// its head.
///
/// The rule ([`FrontView::of`]), for a mesh with +Y up:
/// 1. **Front axis**: of the horizontal axes X and Z, the one along which the mesh has the
///    larger [`projected_area`], i.e. the view that shows the most of it (a cow or a bunny from
///    the side, Suzanne from the face); Z on a tie (within 2 %).
/// 2. **Side of that axis**: the side the surface faces, i.e. the sign of its net area-weighted
///    normal `Σ n_t A_t · d`, which is the difference of the areas it shows to the two sides.
///    An open surface (a mask, a relief, Suzanne with her open eye sockets: +3.7 % of
///    `Σ |n·d| A` towards +Z) shows more to the side it faces; a closed surface shows the same
///    area to both sides (within 1 %: a tie), and then the positive side is taken (+Z: the camera on +Z looking towards −Z, the convention of y-up
///    assets such as glTF's; +X for an X front axis).
/// 3. **Three-quarter turn**: the eye turns by [`THREE_QUARTER_YAW`] from the front axis
///    towards the mesh's head along the other horizontal axis, and looks down by
///    [`FRONT_PITCH`]. The head is the end the mesh leans up to: the sign of the area-weighted
///    correlation between height (y) and position along the axis over the surface (a tie
///    within ±0.1; Spot −0.55 along Z, the cow +0.33 and the bunny −0.35 along X). Animals
///    hold their head (horns, ears) above their rear and tail, so a side view turns to show
///    the face. A mesh symmetric along that axis (Suzanne left and right) turns towards +.
///
/// On the bundled meshes: Spot (head towards −Z) is seen from +X turned towards −Z, so its
/// face is in view rather than its rear; the cow (head towards +X) from +Z turned towards +X;
/// the Stanford bunny (head towards −X) from +Z turned towards −X; Suzanne (face towards +Z)
/// from +Z turned towards +X.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontView {
    /// The front axis, pointing from the mesh to the side the eye is on: ±X or ±Z.
    pub front: Vec3,
    /// The horizontal axis across `front` the eye turns towards (towards the head): ±X or ±Z.
    pub turn: Vec3,
    /// The camera's yaw for this view (see [`OrbitCamera`]).
    pub yaw: f32,
    /// The camera's pitch for this view.
    pub pitch: f32,
}

impl FrontView {
    /// The front view of a triangle mesh with +Y up (see [`FrontView`] for the rule). Triangles
    /// with a vertex index out of range are ignored; with no area at all the view is the
    /// default one from +Z turned towards +X.
    pub fn of(positions: &[DVec3], triangles: &[[u32; 3]]) -> Self {
        let area_x = projected_area(positions, triangles, DVec3::X);
        let area_z = projected_area(positions, triangles, DVec3::Z);
        let (axis, across) =
            if area_x > area_z * (1.0 + AREA_TIE) { (DVec3::X, DVec3::Z) } else { (DVec3::Z, DVec3::X) };
        let front = axis * facing_sign(positions, triangles, axis);
        let turn = across * lean_sign(positions, triangles, across);
        let (sin, cos) = THREE_QUARTER_YAW.sin_cos();
        let eye = cos * front.as_vec3() + sin * turn.as_vec3();
        FrontView { front: front.as_vec3(), turn: turn.as_vec3(), yaw: eye.x.atan2(eye.z), pitch: FRONT_PITCH }
    }

    /// Unit vector from the target to the eye in this view.
    pub fn eye_direction(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }
}

/// The projected area of a triangle mesh onto a plane with unit normal `d`, overlaps counted:
/// `½ Σ_t |n_t · d| A_t` (n_t the unit normal and A_t the area of triangle t). For a closed
/// surface it is the area each side of the plane sees (its silhouette's area when convex), for
/// an open one the mean of the two. Triangles with an index out of range are ignored.
pub fn projected_area(positions: &[DVec3], triangles: &[[u32; 3]], d: DVec3) -> f64 {
    0.5 * area_vectors(positions, triangles).map(|(area, _)| area.dot(d).abs()).sum::<f64>()
}

/// Each valid triangle's area vector `n_t A_t` and centroid.
fn area_vectors<'a>(positions: &'a [DVec3], triangles: &'a [[u32; 3]]) -> impl Iterator<Item = (DVec3, DVec3)> + 'a {
    triangles.iter().filter_map(|t| {
        let [a, b, c] = t.map(|i| positions.get(i as usize).copied());
        let (a, b, c) = (a?, b?, c?);
        Some((0.5 * (b - a).cross(c - a), (a + b + c) / 3.0))
    })
}

/// +1 or −1: the side of `axis` the surface faces (its net area-weighted normal), +1 when it
/// faces both alike (see [`FrontView`]).
fn facing_sign(positions: &[DVec3], triangles: &[[u32; 3]], axis: DVec3) -> f64 {
    let (net, total) = area_vectors(positions, triangles)
        .fold((0.0, 0.0), |(net, total), (area, _)| (net + area.dot(axis), total + area.dot(axis).abs()));
    if net < -FACING_TIE * total { -1.0 } else { 1.0 }
}

/// +1 or −1: the end of `axis` the surface leans up to (the sign of the area-weighted
/// correlation of y with the position along `axis`), +1 when it does not lean.
///
/// The moments are exact integrals over each triangle (not sums over centroids), so that they
/// do not depend on how the surface is triangulated: for linear `f` and `g` on a triangle of
/// area `A` with corner values `f_i`, `g_i`, `∫ f g dA = A/12 (Σ f_i g_i + Σ f_i Σ g_i)`.
fn lean_sign(positions: &[DVec3], triangles: &[[u32; 3]], axis: DVec3) -> f64 {
    let corners = |t: &[u32; 3]| -> Option<[DVec3; 3]> {
        let [a, b, c] = t.map(|i| positions.get(i as usize).copied());
        Some([a?, b?, c?])
    };
    let area = |[a, b, c]: [DVec3; 3]| 0.5 * (b - a).cross(c - a).length();
    // Area-weighted means of u = position along the axis and y.
    let (mut total, mut mean) = (0.0, DVec3::ZERO);
    for p in triangles.iter().filter_map(corners) {
        let a = area(p);
        total += a;
        mean += a * (p[0] + p[1] + p[2]) / 3.0;
    }
    if total <= 0.0 {
        return 1.0;
    }
    mean /= total;
    // Central second moments ∫ u y, ∫ u², ∫ y².
    let (mut cov, mut var_u, mut var_y) = (0.0, 0.0, 0.0);
    for p in triangles.iter().filter_map(corners) {
        let u = p.map(|q| (q - mean).dot(axis));
        let y = p.map(|q| q.y - mean.y);
        let moment = |f: [f64; 3], g: [f64; 3]| {
            (f[0] * g[0] + f[1] * g[1] + f[2] * g[2] + (f[0] + f[1] + f[2]) * (g[0] + g[1] + g[2])) / 12.0
        };
        let a = area(p);
        cov += a * moment(u, y);
        var_u += a * moment(u, u);
        var_y += a * moment(y, y);
    }
    let spread = (var_u * var_y).sqrt();
    if spread > 0.0 && cov < -LEAN_TIE * spread { -1.0 } else { 1.0 }
}

/// [`OrbitCamera::project`] with a precomputed world → clip matrix (for many points).
pub fn project_with(view_projection: &Mat4, p: Vec3, viewport: Vec2) -> Option<(Vec2, f32)> {
    let clip = *view_projection * p.extend(1.0);
    if clip.w <= 0.0 {
        return None;
    }
    let ndc = clip.truncate() / clip.w;
    let pixel = Vec2::new((ndc.x + 1.0) * 0.5 * viewport.x, (1.0 - ndc.y) * 0.5 * viewport.y);
    Some((pixel, ndc.z))
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    const VIEWPORT: Vec2 = Vec2::new(800.0, 600.0);

    fn camera() -> OrbitCamera {
        let mut c = OrbitCamera { yaw: 0.7, pitch: -0.3, ..OrbitCamera::default() };
        c.frame(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 4.0));
        c
    }

    #[test]
    fn project_and_ray_round_trip() {
        let c = camera();
        for p in [c.target, Vec3::new(0.0, 0.5, 3.0), Vec3::new(2.5, 0.9, 2.1)] {
            let (pixel, depth) = c.project(p, VIEWPORT).unwrap();
            assert!((0.0..=1.0).contains(&depth), "{depth}");
            let (origin, dir) = c.ray(pixel, VIEWPORT);
            assert!((dir.length() - 1.0).abs() < 1e-5);
            let to_p = p - origin;
            let off_ray = (to_p - to_p.dot(dir) * dir).length();
            assert!(off_ray < 1e-4 * c.distance, "{off_ray}");
        }
        // The target projects to the viewport's centre.
        let (centre, _) = c.project(c.target, VIEWPORT).unwrap();
        assert!((centre - 0.5 * VIEWPORT).length() < 1e-3);
        // A point behind the eye does not project.
        let (_, _, forward) = c.basis();
        assert!(c.project(c.eye() - forward, VIEWPORT).is_none());
    }

    #[test]
    fn depth_grows_away_from_the_eye() {
        let c = camera();
        let (_, _, forward) = c.basis();
        let (_, near) = c.project(c.target - 0.5 * forward, VIEWPORT).unwrap();
        let (_, far) = c.project(c.target + 0.5 * forward, VIEWPORT).unwrap();
        assert!(near < far);
    }

    #[test]
    fn framing_shows_the_whole_box() {
        let (min, max) = (Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 1.0, 4.0));
        for (yaw, pitch) in [(0.0, 0.0), (0.7, -0.3), (2.0, 1.2), (-3.0, 0.5)] {
            let mut c = OrbitCamera { yaw, pitch, ..OrbitCamera::default() };
            c.frame(min, max);
            for k in 0..8 {
                let corner = Vec3::new(
                    if k & 1 == 0 { min.x } else { max.x },
                    if k & 2 == 0 { min.y } else { max.y },
                    if k & 4 == 0 { min.z } else { max.z },
                );
                let (pixel, depth) = c.project(corner, VIEWPORT).unwrap();
                assert!(pixel.cmpge(Vec2::ZERO).all() && pixel.cmple(VIEWPORT).all(), "{corner} -> {pixel}");
                assert!((0.0..1.0).contains(&depth));
            }
        }
    }

    #[test]
    fn orbit_keeps_the_distance_to_the_target() {
        let mut c = camera();
        let before = c.eye().distance(c.target);
        c.orbit(Vec2::new(130.0, -45.0), VIEWPORT);
        c.orbit(Vec2::new(-10.0, 4000.0), VIEWPORT);
        assert!((c.eye().distance(c.target) - before).abs() < 1e-4 * before);
        assert!(c.pitch.abs() < std::f32::consts::FRAC_PI_2);
        c.reset();
        assert_eq!(c, camera());
    }

    #[test]
    fn pan_moves_the_point_under_the_cursor_with_the_mouse() {
        let mut c = camera();
        let anchor = c.target;
        let (before, _) = c.project(anchor, VIEWPORT).unwrap();
        let delta = Vec2::new(37.0, -21.0);
        c.pan(delta, VIEWPORT);
        let (after, _) = c.project(anchor, VIEWPORT).unwrap();
        assert!((after - before - delta).length() < 1e-2, "{before} -> {after}");
    }

    #[test]
    fn a_dragged_point_follows_the_mouse() {
        let c = camera();
        let anchor = Vec3::new(0.3, 0.8, 2.5);
        let delta = Vec2::new(-55.0, 12.0);
        let (before, depth) = c.project(anchor, VIEWPORT).unwrap();
        let moved = anchor + c.drag_in_view_plane(delta, anchor, VIEWPORT);
        let (after, depth_after) = c.project(moved, VIEWPORT).unwrap();
        assert!((after - before - delta).length() < 1e-2, "{before} -> {after}");
        assert!((depth - depth_after).abs() < 1e-5, "stays at the anchor's depth");
    }

    #[test]
    fn zoom_is_multiplicative() {
        let mut c = camera();
        let d = c.distance;
        c.zoom(2.0);
        assert!((c.distance - d * 0.81).abs() < 1e-5 * d);
        c.zoom(-2.0);
        assert!((c.distance - d).abs() < 1e-5 * d);
    }
}
