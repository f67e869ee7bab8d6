//! The front view of a mesh ([`FrontView`], [`OrbitCamera::frame_front`]) on the bundled meshes,
//! rotated meshes and boxes.

use glam::{DQuat, DVec3, Vec2, Vec3};
use shapeup_app::OrbitCamera;
use shapeup_app::camera::{FRONT_PITCH, FrontView, THREE_QUARTER_YAW, projected_area};
use shapeup_core::io::read_mesh;
use shapeup_core::mesh::Mesh;
use std::path::Path;

fn bundled(name: &str) -> Mesh {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data").join(name);
    read_mesh(&path).unwrap().mesh
}

fn front_of(positions: &[DVec3], triangles: &[[u32; 3]]) -> FrontView {
    FrontView::of(positions, triangles)
}

/// The bounding box centre and the vertex with the largest `key`.
fn centre_and_extreme(positions: &[DVec3], key: impl Fn(DVec3) -> f64) -> (DVec3, DVec3) {
    let (lo, hi) = positions
        .iter()
        .fold((DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let extreme = positions.iter().copied().max_by(|a, b| key(*a).total_cmp(&key(*b))).unwrap();
    (0.5 * (lo + hi), extreme)
}

fn assert_axis(actual: Vec3, expected: Vec3, what: &str) {
    assert!((actual - expected).length() < 1e-6, "{what}: {actual} instead of {expected}");
}

/// The eye is on the `front` side, turned by the three-quarter yaw towards `turn`, slightly
/// from above.
fn assert_view(view: &FrontView, front: Vec3, turn: Vec3) {
    assert_axis(view.front, front, "front");
    assert_axis(view.turn, turn, "turn");
    assert!((view.pitch - FRONT_PITCH).abs() < 1e-6);
    let eye = view.eye_direction();
    assert!((eye.length() - 1.0).abs() < 1e-5);
    let horizontal = Vec3::new(eye.x, 0.0, eye.z).normalize();
    let (sin, cos) = THREE_QUARTER_YAW.sin_cos();
    assert!((horizontal.dot(front) - cos).abs() < 1e-5, "{eye}");
    assert!((horizontal.dot(turn) - sin).abs() < 1e-5, "{eye}");
    assert!(eye.y > 0.0, "from above: {eye}");
}

/// A box `[lo, hi]` as 12 outward-facing triangles.
fn cuboid(lo: DVec3, hi: DVec3) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let positions = (0..8)
        .map(|k| {
            DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    let quads = [[0, 4, 6, 2], [1, 3, 7, 5], [0, 1, 5, 4], [2, 6, 7, 3], [0, 2, 3, 1], [4, 5, 7, 6]];
    let triangles = quads.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    (positions, triangles)
}

#[test]
fn spot_is_seen_from_the_side_turned_towards_its_head() {
    let spot = bundled("spot.obj");
    // The data: Spot's horns (its highest vertex) and its snout are on the −z side; it is
    // longer (z) than wide (x), so its side (x) shows the most.
    let (centre, horn) = centre_and_extreme(&spot.positions, |p| p.y);
    assert!(horn.z < centre.z, "{horn} {centre}");
    assert!(
        projected_area(&spot.positions, &spot.triangles, DVec3::X)
            > projected_area(&spot.positions, &spot.triangles, DVec3::Z)
    );
    let view = front_of(&spot.positions, &spot.triangles);
    assert_view(&view, Vec3::X, Vec3::NEG_Z);
    // Not from behind: the eye is on the head's side.
    assert!(view.eye_direction().z < -0.4, "{}", view.eye_direction());
}

#[test]
fn the_cow_is_seen_from_plus_z_turned_towards_its_head() {
    let cow = bundled("cow.obj");
    // The data: the cow stands along x with its nose (largest x) and horns (largest y) at +x.
    let (centre, nose) = centre_and_extreme(&cow.positions, |p| p.x);
    let (_, horn) = centre_and_extreme(&cow.positions, |p| p.y);
    assert!(nose.y > centre.y && horn.x > centre.x, "{nose} {horn} {centre}");
    assert_view(&front_of(&cow.positions, &cow.triangles), Vec3::Z, Vec3::X);
}

#[test]
fn the_bunny_is_seen_from_plus_z_turned_towards_its_head() {
    let bunny = bundled("stanford-bunny.obj");
    // The data: the bunny's face (smallest x) is at −x, high up; its haunches are at +x.
    let (centre, nose) = centre_and_extreme(&bunny.positions, |p| -p.x);
    assert!(nose.y > centre.y, "{nose} {centre}");
    assert_view(&front_of(&bunny.positions, &bunny.triangles), Vec3::Z, Vec3::NEG_X);
}

#[test]
fn suzanne_is_seen_from_her_face() {
    let suzanne = bundled("suzanne.obj");
    // The data: the surface is open towards +z (her eye sockets): its net area-weighted normal
    // points to +z; her brow is the +z extreme, in the upper half.
    let net: f64 = suzanne
        .triangles
        .iter()
        .map(|t| t.map(|i| suzanne.positions[i as usize]))
        .map(|[a, b, c]| 0.5 * (b - a).cross(c - a).z)
        .sum();
    assert!(net > 0.05 * projected_area(&suzanne.positions, &suzanne.triangles, DVec3::Z), "{net}");
    let (centre, brow) = centre_and_extreme(&suzanne.positions, |p| p.z);
    assert!(brow.y > centre.y, "{brow} {centre}");
    // Symmetric left and right: the three-quarter turn goes towards +x.
    assert_view(&front_of(&suzanne.positions, &suzanne.triangles), Vec3::Z, Vec3::X);
}

#[test]
fn a_rotated_mesh_is_seen_from_its_rotated_front() {
    let rotate = |mesh: &Mesh, angle: f64| -> Vec<DVec3> {
        let q = DQuat::from_rotation_y(angle);
        mesh.positions.iter().map(|p| q * *p).collect()
    };
    let suzanne = bundled("suzanne.obj");
    // A quarter turn about +y takes +z to +x; her face follows.
    let quarter = std::f64::consts::FRAC_PI_2;
    for (angle, face) in [(quarter, Vec3::X), (-quarter, Vec3::NEG_X), (2.0 * quarter, Vec3::NEG_Z)] {
        let view = front_of(&rotate(&suzanne, angle), &suzanne.triangles);
        assert_axis(view.front, face, "Suzanne's face");
        assert!(view.eye_direction().dot(face) > 0.8);
    }
    // Spot's head (−z) turns to −x: seen from its side, now +z, turned towards −x.
    let spot = bundled("spot.obj");
    assert_view(&front_of(&rotate(&spot, quarter), &spot.triangles), Vec3::Z, Vec3::NEG_X);
    // The cow's head (+x) turns to −z: seen from its side, now +x, turned towards −z.
    let cow = bundled("cow.obj");
    assert_view(&front_of(&rotate(&cow, quarter), &cow.triangles), Vec3::X, Vec3::NEG_Z);
}

#[test]
fn a_symmetric_box_is_seen_from_plus_z() {
    let (positions, triangles) = cuboid(DVec3::splat(-1.0), DVec3::splat(1.0));
    let view = front_of(&positions, &triangles);
    assert_view(&view, Vec3::Z, Vec3::X);
    assert!((view.yaw - THREE_QUARTER_YAW).abs() < 1e-6);
    // Deeper than wide: its x side shows more, +x on the tie of the two sides.
    let (positions, triangles) = cuboid(DVec3::new(-1.0, -1.0, -3.0), DVec3::new(1.0, 1.0, 3.0));
    assert_view(&front_of(&positions, &triangles), Vec3::X, Vec3::Z);
    // Nothing to look at: the default view.
    assert_view(&front_of(&[], &[]), Vec3::Z, Vec3::X);
    assert_view(&front_of(&positions, &[[0, 1, 99]]), Vec3::Z, Vec3::X);
}

#[test]
fn an_open_surface_is_seen_from_the_side_it_faces() {
    // A square in the z = 0 plane with its normal towards −z.
    let positions =
        [DVec3::new(0.0, 0.0, 0.0), DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, 1.0, 0.0), DVec3::new(1.0, 0.0, 0.0)];
    let triangles = [[0, 1, 2], [0, 2, 3]];
    assert_axis(front_of(&positions, &triangles).front, Vec3::NEG_Z, "front");
}

#[test]
fn projected_area_is_half_the_sum_of_absolute_normal_components() {
    let (positions, triangles) = cuboid(DVec3::ZERO, DVec3::new(1.0, 2.0, 3.0));
    assert!((projected_area(&positions, &triangles, DVec3::X) - 6.0).abs() < 1e-12);
    assert!((projected_area(&positions, &triangles, DVec3::Y) - 3.0).abs() < 1e-12);
    assert!((projected_area(&positions, &triangles, DVec3::Z) - 2.0).abs() < 1e-12);
    // A convex body: its silhouette along a diagonal of the xy face.
    let d = DVec3::new(1.0, 1.0, 0.0).normalize();
    assert!((projected_area(&positions, &triangles, d) - 3.0 * 3.0 / 2f64.sqrt()).abs() < 1e-12);
}

#[test]
fn frame_front_frames_the_mesh_from_its_front() {
    let spot = bundled("spot.obj");
    let mut camera = OrbitCamera::with_angles(2.0, -0.7);
    camera.frame_front(&spot.positions, &spot.triangles);
    let view = front_of(&spot.positions, &spot.triangles);
    assert!(((camera.eye() - camera.target).normalize() - view.eye_direction()).length() < 1e-5);
    // Every vertex is in the viewport.
    let viewport = Vec2::new(800.0, 600.0);
    for p in &spot.positions {
        let (pixel, depth) = camera.project(p.as_vec3(), viewport).unwrap();
        assert!(pixel.cmpge(Vec2::ZERO).all() && pixel.cmple(viewport).all(), "{p} -> {pixel}");
        assert!((0.0..1.0).contains(&depth));
    }
    // It is the view Reset returns to.
    let framed = camera;
    camera.orbit(Vec2::new(120.0, 40.0), viewport);
    camera.zoom(3.0);
    camera.reset();
    assert_eq!(camera, framed);
    // No positions: only the angles change.
    let mut empty = OrbitCamera::default();
    empty.frame_front(&[], &[]);
    assert_eq!((empty.target, empty.distance), (OrbitCamera::default().target, OrbitCamera::default().distance));
    assert!((empty.yaw - THREE_QUARTER_YAW).abs() < 1e-6 && (empty.pitch - FRONT_PITCH).abs() < 1e-6);
}
