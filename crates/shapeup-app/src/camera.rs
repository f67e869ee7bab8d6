//! An orbit camera: it looks at a target from a distance, turned by yaw and pitch, with +Y up.
//!
//! Conventions: world space is right-handed with +Y up; pixels have their origin at the top-left
//! corner of the viewport, +x right and +y down; the projection maps view depth to wgpu's NDC
//! depth range 0..1 (0 at the near plane) with NDC y up. A viewport is its size in pixels
//! (`Vec2::new(width, height)`).

use glam::{Mat4, Vec2, Vec3, Vec4};

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
        let radius = (0.5 * (max - min).length()).max(1e-6);
        self.target = 0.5 * (min + max);
        self.scene_radius = radius;
        self.distance = 1.1 * radius / (0.5 * self.fov_y).sin();
        self.home = Home { target: self.target, distance: self.distance, yaw: self.yaw, pitch: self.pitch };
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
