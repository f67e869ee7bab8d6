//! Polygon triangulation: holes joined by a bridge edge (a corner and the bridge repeated, as
//! LightWave and other exporters write them), the reasons a polygon is left out, and work
//! linear in the corners for convex polygons and bounded for tangled ones.

use glam::{DQuat, DVec2, DVec3};
use shapeup_core::io::read_mesh;
use shapeup_core::mesh::{
    Mesh, PolygonProblem, Polygons, TriangulationScratch, triangulate_polygon, triangulation_work_budget,
};
use shapeup_core::scene::{Scene, SceneFormat};
use std::path::{Path, PathBuf};

use crate::common::Rng;

fn tilt() -> DQuat {
    DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7)
}

/// Triangulates `polygon` over the 2D points `flat` laid into a tilted plane.
fn triangulate(flat: &[DVec2], polygon: &[u32]) -> (Vec<[u32; 3]>, shapeup_core::mesh::PolygonTriangulation) {
    let positions: Vec<DVec3> = flat.iter().map(|q| tilt() * q.extend(0.0)).collect();
    let mut out = Vec::new();
    let done = triangulate_polygon(&positions, polygon, &mut TriangulationScratch::default(), &mut out).unwrap();
    assert_eq!(done.triangles, out.len());
    (out, done)
}

fn signed_area(flat: &[DVec2], [a, b, c]: [u32; 3]) -> f64 {
    let [a, b, c] = [a, b, c].map(|v| flat[v as usize]);
    0.5 * (b - a).perp_dot(c - a)
}

fn inside_triangle(flat: &[DVec2], t: [u32; 3], q: DVec2) -> bool {
    let [a, b, c] = t.map(|v| flat[v as usize]);
    let s = [(b - a).perp_dot(q - a), (c - b).perp_dot(q - b), (a - c).perp_dot(q - c)];
    s.iter().all(|&x| x > 0.0) || s.iter().all(|&x| x < 0.0)
}

/// Whether q is inside the closed loop `ring` (even-odd rule).
fn inside_loop(flat: &[DVec2], ring: &[u32], q: DVec2) -> bool {
    let mut inside = false;
    for i in 0..ring.len() {
        let (a, b) = (flat[ring[i] as usize], flat[ring[(i + 1) % ring.len()] as usize]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
    }
    inside
}

/// The triangles tile the region inside `outer` and outside every hole: no triangle folds
/// (each turns as `winding`), the areas add up, and sample points of the region are covered
/// exactly once, those of a hole or outside never.
fn assert_tiles(flat: &[DVec2], triangles: &[[u32; 3]], outer: &[u32], holes: &[&[u32]], winding: f64, label: &str) {
    let loop_area = |ring: &[u32]| {
        (0..ring.len())
            .map(|i| flat[ring[i] as usize].perp_dot(flat[ring[(i + 1) % ring.len()] as usize]))
            .sum::<f64>()
            .abs()
            / 2.0
    };
    let expected = loop_area(outer) - holes.iter().map(|h| loop_area(h)).sum::<f64>();
    for &t in triangles {
        assert!(winding * signed_area(flat, t) > 0.0, "{label}: triangle {t:?} folds over or is flat");
    }
    let total: f64 = triangles.iter().map(|&t| winding * signed_area(flat, t)).sum();
    assert!((total - expected).abs() < 1e-9 * expected, "{label}: area {total}, expected {expected}");
    let (lo, hi) = flat.iter().fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(lo, hi), q| (lo.min(*q), hi.max(*q)));
    let steps = 61;
    for i in 0..steps {
        for j in 0..steps {
            // Irrational offsets keep the samples off the edges.
            let t = DVec2::new(
                (i as f64 + 0.5 + 0.01 * 2f64.sqrt()) / steps as f64,
                (j as f64 + 0.5 + 0.01 * 3f64.sqrt()) / steps as f64,
            );
            let q = lo + t * (hi - lo);
            let in_region = inside_loop(flat, outer, q) && !holes.iter().any(|h| inside_loop(flat, h, q));
            let covered = triangles.iter().filter(|&&t| inside_triangle(flat, t, q)).count();
            assert_eq!(covered, usize::from(in_region), "{label}: point {q} covered {covered} times");
        }
    }
}

/// Outer square 0 1 2 3 (4 × 4) and inner square 4 5 6 7 (2 × 2, counter-clockwise).
fn square_with_hole() -> Vec<DVec2> {
    [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0), (1.0, 1.0), (3.0, 1.0), (3.0, 3.0), (1.0, 3.0)]
        .map(|(x, y)| DVec2::new(x, y))
        .to_vec()
}

#[test]
fn square_with_a_square_hole_joined_by_a_bridge_tiles_the_ring() {
    let flat = square_with_hole();
    // `f 1 2 3 4 1 5 8 7 6 5`: round the outline, over the bridge 0 → 4, round the hole the
    // other way, back over the bridge.
    let written: Vec<u32> = vec![0, 1, 2, 3, 0, 4, 7, 6, 5, 4];
    for start in 0..written.len() {
        for reversed in [false, true] {
            let mut polygon: Vec<u32> = written[start..].iter().chain(&written[..start]).copied().collect();
            if reversed {
                polygon.reverse();
            }
            let label = format!("start {start}, reversed {reversed}");
            let (triangles, done) = triangulate(&flat, &polygon);
            assert!(done.repeated_corners && !done.fan_fallback, "{label}");
            assert_eq!(triangles.len(), 8, "{label}: a square ring has 8 triangles");
            let winding = if reversed { -1.0 } else { 1.0 };
            assert_tiles(&flat, &triangles, &[0, 1, 2, 3], &[&[4, 5, 6, 7]], winding, &label);
            // In 3D: every triangle turns as the polygon (the tilted plane's normal).
            let positions: Vec<DVec3> = flat.iter().map(|q| tilt() * q.extend(0.0)).collect();
            for t in &triangles {
                let [a, b, c] = t.map(|v| positions[v as usize]);
                assert!(winding * (b - a).cross(c - a).dot(tilt() * DVec3::Z) > 0.0, "{label}: {t:?}");
            }
        }
    }
}

#[test]
fn bridge_from_any_outer_corner_to_any_hole_corner() {
    // Every bridge that meets the hole only at its end: along a diagonal (0 → 4), along a
    // side's line (1 → 4 passes under corner 5), to a far corner (0 → 5).
    let flat = square_with_hole();
    for (o, h) in [(0u32, 4u32), (1, 5), (2, 6), (3, 7), (1, 4), (3, 4), (2, 5), (0, 5), (0, 7), (2, 7)] {
        let outer: Vec<u32> = (0..4).map(|i| (o + i) % 4).collect();
        // The hole clockwise from h: h, h-1, … (in 4..8).
        let hole: Vec<u32> = (0..4).map(|i| 4 + (h - 4 + 4 - i) % 4).collect();
        let mut polygon = outer.clone();
        polygon.push(o);
        polygon.extend(&hole);
        polygon.push(h);
        let label = format!("bridge {o} → {h}: {polygon:?}");
        let (triangles, _) = triangulate(&flat, &polygon);
        assert_eq!(triangles.len(), 8, "{label}");
        assert_tiles(&flat, &triangles, &[0, 1, 2, 3], &[&[4, 5, 6, 7]], 1.0, &label);
    }
}

#[test]
fn l_shape_with_a_hole_bridged_from_its_reflex_corner() {
    // The L: 0 (0,0) 1 (4,0) 2 (4,2) 3 (2,2) 4 (2,4) 5 (0,4); reflex at 3. A square hole in the
    // foot, 6..9, bridged from the reflex corner 3 to the hole's corner 8 (2.5, 1.5).
    let flat: Vec<DVec2> = [
        (0.0, 0.0),
        (4.0, 0.0),
        (4.0, 2.0),
        (2.0, 2.0),
        (2.0, 4.0),
        (0.0, 4.0),
        (2.5, 0.5),
        (3.5, 0.5),
        (3.5, 1.5),
        (2.5, 1.5),
    ]
    .map(|(x, y)| DVec2::new(x, y))
    .to_vec();
    let polygon = [0, 1, 2, 3, 9, 8, 7, 6, 9, 3, 4, 5];
    for start in 0..polygon.len() {
        let rotated: Vec<u32> = polygon[start..].iter().chain(&polygon[..start]).copied().collect();
        let (triangles, done) = triangulate(&flat, &rotated);
        assert!(done.repeated_corners);
        // V − 2 + 2·holes = 10 triangles.
        assert_eq!(triangles.len(), 10, "start {start}");
        assert_tiles(&flat, &triangles, &[0, 1, 2, 3, 4, 5], &[&[6, 7, 8, 9]], 1.0, &format!("start {start}"));
    }
}

#[test]
fn random_star_shapes_with_bridged_holes_tile() {
    // A star-shaped outline (random radii at even angles) with one or two regular holes around
    // the centre, each joined by a radial bridge: simple once bridged, so the triangles tile.
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for case in 0..60 {
        let k = 5 + case % 23;
        let mut flat: Vec<DVec2> = (0..k)
            .map(|i| {
                let a = std::f64::consts::TAU * i as f64 / k as f64;
                (0.6 + rng.unit()) * DVec2::new(a.cos(), a.sin())
            })
            .collect();
        let outer: Vec<u32> = (0..k as u32).collect();
        let mut polygon = outer.clone();
        let mut holes: Vec<Vec<u32>> = Vec::new();
        let hole_count = 1 + case % 2;
        for h in 0..hole_count {
            // Hole h: a regular m-gon of radius 0.2 around a point at radius 0.3 (two holes on
            // opposite sides), bridged radially from the outline corner nearest its direction.
            let m = 3 + (case + h) % 5;
            let first = flat.len() as u32;
            let joint = (k * h / hole_count) as u32; // outline corner at angle about π·h
            let joint_angle = std::f64::consts::TAU * joint as f64 / k as f64;
            let direction = DVec2::new(joint_angle.cos(), joint_angle.sin());
            // On the joint's ray, so that the bridge is radial (inside the star, outside the hole).
            let (centre, radius) = if hole_count == 1 { (DVec2::ZERO, 0.3) } else { (0.3 * direction, 0.15) };
            for j in 0..m {
                let a = joint_angle + std::f64::consts::TAU * j as f64 / m as f64;
                flat.push(centre + radius * DVec2::new(a.cos(), a.sin()));
            }
            let hole: Vec<u32> = (0..m as u32).map(|j| first + j).collect();
            // Insert after the joint's corner: joint, hole clockwise from its corner 0, back.
            let at = polygon.iter().position(|&v| v == joint).unwrap();
            let mut bridge = vec![first];
            bridge.extend((1..m as u32).rev().map(|j| first + j));
            bridge.push(first);
            bridge.push(joint);
            polygon.splice(at + 1..at + 1, bridge);
            holes.push(hole);
        }
        let label = format!("case {case}: {polygon:?}");
        let (triangles, done) = triangulate(&flat, &polygon);
        assert!(done.repeated_corners && !done.fan_fallback, "{label}");
        let holes: Vec<&[u32]> = holes.iter().map(Vec::as_slice).collect();
        assert_eq!(triangles.len(), flat.len() - 2 + 2 * holes.len(), "{label}");
        assert_tiles(&flat, &triangles, &outer, &holes, 1.0, &label);
    }
}

#[test]
fn faces_that_still_cannot_be_triangulated_say_why() {
    let flat = square_with_hole();
    let positions: Vec<DVec3> = flat.iter().map(|q| q.extend(0.0)).collect();
    let mut scratch = TriangulationScratch::default();
    let problem = |polygon: &[u32]| {
        let mut scratch = TriangulationScratch::default();
        triangulate_polygon(&positions, polygon, &mut scratch, &mut Vec::new()).unwrap_err()
    };
    assert_eq!(problem(&[0, 1, 1]), PolygonProblem::TooFewCorners);
    assert_eq!(problem(&[0, 1, 0, 1]), PolygonProblem::TooFewCorners);
    assert_eq!(problem(&[0, 1, 2, 1]), PolygonProblem::NoArea, "a spike out and back");
    assert_eq!(problem(&[0, 1, 2, 0, 1, 2]), PolygonProblem::RepeatedEdge(0, 1), "wound twice");
    assert_eq!(problem(&[0, 1, 99]), PolygonProblem::MissingVertex(99));
    assert!(problem(&[0, 1, 1]).to_string().contains("fewer than 3 distinct corners"));
    // Nothing is appended on failure; a spike on a good polygon is dropped, the rest kept.
    let mut out = vec![[7, 7, 7]];
    assert!(triangulate_polygon(&positions, &[0, 1, 2, 1], &mut scratch, &mut out).is_err());
    assert_eq!(out, vec![[7, 7, 7]]);
    out.clear();
    triangulate_polygon(&positions, &[0, 1, 5, 1, 2, 3], &mut scratch, &mut out).unwrap();
    assert_eq!(out.len(), 2);

    // Through a mesh: the face is kept and counted with its reason.
    let polygons: Polygons = [&[0u32, 1, 2][..], &[0, 1, 1]].into_iter().collect();
    let (mesh, warnings) = Mesh::from_polygons(positions.clone(), polygons).unwrap();
    assert_eq!((mesh.num_polygons(), mesh.num_triangles()), (2, 1));
    let w = warnings.iter().find(|w| w.kind == "faces_not_triangulated").unwrap();
    assert_eq!(w.first, "face 1 (vertices 0 1 1): fewer than 3 distinct corners");
}

/// A scratch folder removed at the end.
struct Folder(PathBuf);
impl Folder {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("shapeup-polygons-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Folder(dir)
    }
    fn write(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }
    fn scene(&self, mesh: &Path) -> Scene {
        let text = format!("[mesh]\npath = {:?}\n[[constraints]]\ntype = \"edge_spring\"\n", mesh.to_str().unwrap());
        Scene::parse(&text, SceneFormat::Toml, &self.0.join("s.toml"), self.0.clone()).unwrap()
    }
}
impl Drop for Folder {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

const SQUARE_WITH_HOLE_OBJ: &str = "v 0 0 0\nv 4 0 0\nv 4 4 0\nv 0 4 0\nv 1 1 0\nv 3 1 0\nv 3 3 0\nv 1 3 0\n";

#[test]
fn an_obj_whose_only_face_has_a_bridged_hole_loads_as_a_scene() {
    let folder = Folder::new("bridge");
    let path = folder.write("ring.obj", &format!("{SQUARE_WITH_HOLE_OBJ}f 1 2 3 4 1 5 8 7 6 5\n"));
    let loaded = read_mesh(&path).unwrap();
    assert_eq!(loaded.mesh.num_polygons(), 1);
    assert_eq!(loaded.mesh.polygons.get(0).unwrap(), &[0, 1, 2, 3, 0, 4, 7, 6, 5, 4]);
    assert_eq!(loaded.mesh.num_triangles(), 8);
    assert_eq!(loaded.warnings.count("faces_not_triangulated"), 0);
    let flat = square_with_hole();
    assert_tiles(&flat, &loaded.mesh.triangles, &[0, 1, 2, 3], &[&[4, 5, 6, 7]], 1.0, "ring.obj");
    let scene = folder.scene(&path).load().unwrap();
    assert_eq!(scene.mesh.num_triangles(), 8);
}

#[test]
fn a_file_without_a_usable_face_names_the_face_and_why() {
    let folder = Folder::new("unusable");
    let path = folder.write("spike.obj", &format!("{SQUARE_WITH_HOLE_OBJ}f 1 2 2\n"));
    let message = folder.scene(&path).load().unwrap_err().to_string();
    assert!(message.contains("spike.obj"), "{message}");
    assert!(
        message.contains("face 0 (vertices 0 1 1)") && message.contains("fewer than 3 distinct corners"),
        "{message}"
    );
    assert_eq!(message.lines().count(), 1, "{message}");
    let path = folder.write("two.obj", &format!("{SQUARE_WITH_HOLE_OBJ}f 1 2 2\nf 1 2 3 2\n"));
    let message = folder.scene(&path).load().unwrap_err().to_string();
    assert!(message.contains("none of its 2 faces") && message.contains("face 0 (vertices 0 1 1)"), "{message}");
}

/// k corners on a circle, strictly convex.
fn circle(k: usize) -> Vec<DVec2> {
    (0..k)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / k as f64;
            DVec2::new(a.cos(), a.sin())
        })
        .collect()
}

#[test]
fn a_convex_polygon_of_150000_corners_is_its_fan_in_linear_work() {
    let k = 150_000;
    let flat = circle(k);
    let polygon: Vec<u32> = (0..k as u32).collect();
    let (triangles, done) = triangulate(&flat, &polygon);
    eprintln!("{} corners: work {} (budget {})", k, done.work, triangulation_work_budget(k));
    assert!(!done.fan_fallback && !done.repeated_corners);
    assert_eq!(triangles.len(), k - 2);
    assert!(triangles.iter().enumerate().all(|(i, &t)| t == [0, i as u32 + 1, i as u32 + 2]), "the fan from corner 0");
    assert!(done.work <= 3 * k, "work {} for {k} corners", done.work);
}

#[test]
fn nearly_convex_polygons_of_150000_corners_take_linear_work() {
    // The circle with every 1000th corner pulled inwards (150 reflex corners), then every
    // third (50,000): ears stay small, so each test looks at a few grid cells.
    let k = 150_000;
    for (every, per_corner) in [(1000, 16), (3, 96)] {
        let mut flat = circle(k);
        for i in (every / 2..k).step_by(every) {
            flat[i] *= 0.999_999_9;
        }
        let polygon: Vec<u32> = (0..k as u32).collect();
        let (triangles, done) = triangulate(&flat, &polygon);
        eprintln!(
            "{k} corners, every {every}th pulled in: work {} (budget {})",
            done.work,
            triangulation_work_budget(k)
        );
        assert!(!done.fan_fallback);
        assert_eq!(triangles.len(), k - 2);
        assert!(done.work <= per_corner * k, "every {every}: work {} for {k} corners", done.work);
        assert!(triangles.iter().all(|&t| signed_area(&flat, t) > 0.0), "every {every}: no triangle folds");
    }
}

#[test]
fn a_star_polygon_of_20000_corners_is_ear_clipped_within_the_budget() {
    // Simple but with half its corners reflex: the grid keeps every ear test local.
    let k = 20_000;
    let mut rng = Rng(7);
    let flat: Vec<DVec2> =
        circle(k).iter().enumerate().map(|(i, q)| *q * if i % 2 == 0 { 1.0 } else { 0.5 + 0.4 * rng.unit() }).collect();
    let polygon: Vec<u32> = (0..k as u32).collect();
    let (triangles, done) = triangulate(&flat, &polygon);
    eprintln!("{} corners: work {} (budget {})", k, done.work, triangulation_work_budget(k));
    assert!(!done.fan_fallback, "work {} of {}", done.work, triangulation_work_budget(k));
    assert_eq!(triangles.len(), k - 2);
    assert!(triangles.iter().all(|&t| signed_area(&flat, t) > 0.0), "no triangle folds");
    let area: f64 = triangles.iter().map(|&t| signed_area(&flat, t)).sum();
    let expected: f64 = (0..k).map(|i| flat[i].perp_dot(flat[(i + 1) % k])).sum::<f64>() / 2.0;
    assert!((area - expected).abs() < 1e-9 * expected, "{area} vs {expected}");
}

#[test]
fn a_random_polygon_of_150000_corners_falls_back_to_a_fan_within_its_budget() {
    let k = 150_000;
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let flat: Vec<DVec2> = (0..k).map(|_| DVec2::new(rng.unit(), rng.unit())).collect();
    let polygon: Vec<u32> = (0..k as u32).collect();
    let (triangles, done) = triangulate(&flat, &polygon);
    eprintln!("{} corners: work {} (budget {})", k, done.work, triangulation_work_budget(k));
    assert!(done.fan_fallback, "a self-intersecting tangle of 150,000 corners runs out of budget");
    assert_eq!(triangles.len(), k - 2, "still one triangle per corner but two");
    assert!(done.work <= triangulation_work_budget(k) + 2 * k, "work {}", done.work);

    // Through a mesh: counted, naming the face.
    let positions: Vec<DVec3> = flat.iter().map(|q| q.extend(0.0)).collect();
    let polygons: Polygons = [&[0u32, 1, 2][..], &polygon].into_iter().collect();
    let (mesh, warnings) = Mesh::from_polygons(positions, polygons).unwrap();
    assert_eq!(mesh.num_triangles(), k - 1);
    let w = warnings.iter().find(|w| w.kind == "polygons_fanned").unwrap();
    assert_eq!((w.count, w.first.as_str()), (1, "face 1 (150000 corners)"));
}

#[test]
fn repeated_corner_checks_are_not_quadratic() {
    // 150,000 corners, each vertex twice (the loop run twice): refused at once, not after
    // 10¹⁰ comparisons; and a loop with one bridge-like repeat every 3 corners is taken.
    let k = 75_000u32;
    let flat = circle(k as usize);
    let positions: Vec<DVec3> = flat.iter().map(|q| q.extend(0.0)).collect();
    let twice: Vec<u32> = (0..2 * k).map(|i| i % k).collect();
    let mut scratch = TriangulationScratch::default();
    let err = triangulate_polygon(&positions, &twice, &mut scratch, &mut Vec::new()).unwrap_err();
    assert_eq!(err, PolygonProblem::RepeatedEdge(0, 1));
}
