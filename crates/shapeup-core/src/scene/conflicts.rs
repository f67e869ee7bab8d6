//! Groups that work against each other or take less than the scene lists, found once a
//! scene's groups are built and said as warnings with counts (the run goes on): two hard
//! groups holding one vertex at different points, hard targets that a rigid (or similarity)
//! group cannot follow, listed faces a face type cannot take.

use super::spec::{GroupSpec, SelectionSpec};
use crate::constraints::{Element, constraint_type};
use crate::mesh::Mesh;
use crate::solver::System;
use crate::warnings::Warnings;
use glam::DVec3;
use std::collections::HashMap;

/// Two held points closer than this, relative to the larger of their distances from the
/// origin and the rest shape's size, are the same point (targets computed two ways differ by
/// round-off).
const SAME_POINT: f64 = 1e-9;

/// Adds the warnings of this module for `system`, built from `groups` on `mesh` (`rest`: the
/// rest positions in the same frame as the targets).
pub(super) fn warn_of_conflicts(
    system: &System,
    groups: &[GroupSpec],
    mesh: &Mesh,
    rest: &[DVec3],
    warnings: &mut Warnings,
) {
    let size = bounding_diagonal(rest).max(f64::MIN_POSITIVE);
    let (count, first) = hard_groups_at_odds(system, size);
    warnings.add_many(
        "hard_groups_conflict",
        "vertex(es) held by two hard groups at different points: the later group's target holds each (give each vertex one hard group)",
        count,
        || first.unwrap_or_default(),
    );
    let (count, first) = rigid_groups_broken_by_hard_targets(system, rest, size);
    warnings.add_many(
        "hard_targets_break_rigid_group",
        "rigid or similarity group(s) whose hard-held vertices are moved to targets no rigid motion (or uniform scaling) reaches, a mirror image among them: the hard targets win and the group cannot keep its shape",
        count,
        || first.unwrap_or_default(),
    );
    let (count, first) = faces_not_taken(groups, mesh);
    warnings.add_many(
        "faces_not_taken",
        "listed face(s) that their group's type cannot take (plane and circle act on faces of 4 or more corners, rectangle and parallelogram on quads), left out of the group",
        count,
        || first.unwrap_or_default(),
    );
}

fn bounding_diagonal(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    if points.is_empty() { 0.0 } else { (hi - lo).length() }
}

fn same_point(a: DVec3, b: DVec3, size: f64) -> bool {
    (a - b).length() <= SAME_POINT * size.max(a.length()).max(b.length())
}

/// (group name, vertex, point) of every vertex a hard group holds, group after group in the
/// system's order.
fn hard_held_points(system: &System) -> impl Iterator<Item = (&str, u32, DVec3)> {
    system.groups().filter(|(_, g)| g.hard).flat_map(|(_, group)| {
        group.constraints.iter().filter_map(|c| c.held_points()).flat_map(move |(vertices, points)| {
            vertices.iter().zip(points).map(move |(&v, &p)| (group.name.as_str(), v, p))
        })
    })
}

/// The vertices that two hard groups hold at different points (the later one wins: the
/// solver's rule), and the first as `vertex V: "A" and "B"`.
fn hard_groups_at_odds(system: &System, size: f64) -> (usize, Option<String>) {
    let mut held: HashMap<u32, (&str, DVec3)> = HashMap::new();
    let mut conflicting: Vec<(u32, String)> = Vec::new();
    for (group, v, p) in hard_held_points(system) {
        if let Some((name, earlier)) = held.insert(v, (group, p))
            && !same_point(earlier, p, size)
        {
            conflicting.push((v, format!("vertex {v}: \"{name}\" and \"{group}\"")));
        }
    }
    conflicting.sort_by_key(|(v, _)| *v);
    conflicting.dedup_by_key(|(v, _)| *v);
    let first = conflicting.first().map(|(_, text)| text.clone());
    (conflicting.len(), first)
}

/// The rigid and similarity groups some of whose vertices hard groups hold at targets that no
/// rigid motion (similarity: rigid motion and uniform scaling) of their rest positions
/// reaches, and the first as `"NAME" (vertices U and V)`. Distances are compared from each held
/// vertex to three of them (the first, and those a third and two thirds along): a distance
/// that changes (or changes by another ratio) cannot be one motion.
fn rigid_groups_broken_by_hard_targets(system: &System, rest: &[DVec3], size: f64) -> (usize, Option<String>) {
    // The later hard group's point, as the solver holds it.
    let target: HashMap<u32, DVec3> = hard_held_points(system).map(|(_, v, p)| (v, p)).collect();
    let mut broken = Vec::new();
    for (_, group) in system.groups().filter(|(_, g)| !g.hard && matches!(g.kind.as_str(), "rigid" | "similarity")) {
        let scales = group.kind == "similarity";
        for constraint in &group.constraints {
            let held: Vec<(u32, DVec3)> =
                constraint.vertices().iter().filter_map(|&v| target.get(&v).map(|&p| (v, p))).collect();
            if let Some((u, v)) = motion_breaker(&held, rest, scales, size) {
                broken.push(format!("\"{}\" (vertices {u} and {v})", group.name));
                break;
            }
        }
    }
    let first = broken.first().cloned();
    (broken.len(), first)
}

/// Two held vertices whose distance the targets change (by another ratio than the rest, when
/// `scales`), if there are any, or two of four that the targets mirror (distances kept, the
/// handedness of a tetrahedron of them reversed: no rotation does that); `held`: (vertex,
/// target).
fn motion_breaker(held: &[(u32, DVec3)], rest: &[DVec3], scales: bool, size: f64) -> Option<(u32, u32)> {
    let n = held.len();
    if n < 2 {
        return None;
    }
    let rest_at = |v: u32| rest.get(v as usize).copied().unwrap_or(DVec3::ZERO);
    if let Some(pair) = mirrored(held, &rest_at, size) {
        return Some(pair);
    }
    let references = [0, n / 3, 2 * n / 3];
    // Similarity: the ratio of the first pair with a rest distance sets the scale.
    let mut ratio: Option<f64> = None;
    for &r in &references {
        let (a, pa) = held[r];
        for &(b, pb) in held {
            let (d0, d1) = (rest_at(a).distance(rest_at(b)), pa.distance(pb));
            let tolerance = SAME_POINT * size.max(pa.length()).max(pb.length()) * 10.0;
            let expected = if scales {
                if d0 <= tolerance {
                    continue;
                }
                *ratio.get_or_insert(d1 / d0) * d0
            } else {
                d0
            };
            if (d1 - expected).abs() > tolerance.max(1e-6 * expected) {
                return Some((a.min(b), a.max(b)));
            }
        }
    }
    None
}

/// Two of four held vertices spanning a tetrahedron (the first; the farthest from it; the
/// farthest from their line; the farthest from their plane, at rest) whose signed volume the
/// targets reverse: a mirror image, which keeps every distance.
fn mirrored(held: &[(u32, DVec3)], rest_at: &dyn Fn(u32) -> DVec3, size: f64) -> Option<(u32, u32)> {
    let farthest = |score: &dyn Fn(DVec3) -> f64| {
        held.iter().copied().max_by(|a, b| score(rest_at(a.0)).total_cmp(&score(rest_at(b.0))))
    };
    let a = held[0];
    let pa = rest_at(a.0);
    let b = farthest(&|p| p.distance(pa))?;
    let pb = rest_at(b.0);
    let c = farthest(&|p| (p - pa).cross(pb - pa).length())?;
    let pc = rest_at(c.0);
    let normal = (pb - pa).cross(pc - pa);
    let d = farthest(&|p| (p - pa).dot(normal).abs())?;
    let volume = |p: [DVec3; 4]| (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0]));
    let at_rest = volume([a, b, c, d].map(|(v, _)| rest_at(v)));
    let moved = volume([a.1, b.1, c.1, d.1]);
    // Flat at rest (within round-off of the size cubed): any handedness is a rotation.
    let flat = 1e-9 * size.powi(3);
    (at_rest.abs() > flat && moved * at_rest < 0.0).then_some((a.0.min(d.0), a.0.max(d.0)))
}

/// The faces listed in `faces = [...]` selections that their face type cannot take (a face of
/// fewer or more corners than the type acts on), and the first as
/// `constraints[i] ("NAME"): face F (K corners)`. A group with `whole_selection = true` takes
/// the listed faces' corners as one set and leaves none out.
fn faces_not_taken(groups: &[GroupSpec], mesh: &Mesh) -> (usize, Option<String>) {
    let mut count = 0;
    let mut first = None;
    for (i, spec) in groups.iter().enumerate() {
        let SelectionSpec::Faces(listed) = &spec.selection else { continue };
        let Ok(kind) = constraint_type(&spec.kind) else { continue };
        let Element::Face { min, max } = kind.info().element else { continue };
        if spec.options.get("whole_selection").and_then(serde_json::Value::as_bool) == Some(true) {
            continue;
        }
        for &f in listed {
            let corners = mesh.polygons.get(f).map_or(0, |p| p.len());
            if !(min..=max).contains(&corners) {
                count += 1;
                first.get_or_insert_with(|| {
                    format!("constraints[{i}] (\"{}\"): face {f} ({corners} corners)", spec.name)
                });
            }
        }
    }
    (count, first)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn held(points: &[(u32, [f64; 3])]) -> Vec<(u32, DVec3)> {
        points.iter().map(|&(v, p)| (v, DVec3::from(p))).collect()
    }

    /// A rotation with a translation keeps every distance; a stretch does not; a uniform
    /// scaling only a similarity takes.
    #[test]
    fn a_motion_breaker_is_a_pair_whose_distance_changes() {
        let rest = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let turn = glam::DQuat::from_rotation_z(0.7);
        let moved: Vec<(u32, [f64; 3])> =
            (0..4).map(|v| (v, (turn * rest[v as usize] + DVec3::new(3.0, -1.0, 2.0)).to_array())).collect();
        assert_eq!(motion_breaker(&held(&moved), &rest, false, 1.0), None);
        let stretched = [(0, [0.0, 0.0, 0.0]), (1, [1.5, 0.0, 0.0]), (2, [0.0, 1.0, 0.0])];
        assert_eq!(motion_breaker(&held(&stretched), &rest, false, 1.0), Some((0, 1)));
        assert!(motion_breaker(&held(&stretched), &rest, true, 1.0).is_some(), "not uniform");
        let scaled = [(0, [0.0, 0.0, 0.0]), (1, [2.0, 0.0, 0.0]), (3, [0.0, 0.0, 2.0])];
        assert!(motion_breaker(&held(&scaled), &rest, false, 1.0).is_some());
        assert_eq!(motion_breaker(&held(&scaled), &rest, true, 1.0), None);
        assert_eq!(motion_breaker(&held(&[(2, [9.0, 9.0, 9.0])]), &rest, false, 1.0), None, "one vertex is any motion");
        // A mirror image keeps every distance; no rigid motion (or similarity) makes it.
        let mirrored: Vec<(u32, [f64; 3])> =
            (0..4).map(|v| (v, (rest[v as usize] * DVec3::new(-1.0, 1.0, 1.0)).to_array())).collect();
        assert!(motion_breaker(&held(&mirrored), &rest, false, 1.0).is_some());
        assert!(motion_breaker(&held(&mirrored), &rest, true, 1.0).is_some());
        // A flat set mirrored is a half turn: a rigid motion.
        let flat = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
        let turned: Vec<(u32, [f64; 3])> =
            (0..4).map(|v| (v, (flat[v as usize] * DVec3::new(-1.0, 1.0, 1.0)).to_array())).collect();
        assert_eq!(motion_breaker(&held(&turned), &flat, false, 1.0), None);
    }

    fn warnings_of(body: &str) -> Vec<(String, usize, String)> {
        use crate::scene::{Scene, SceneFormat};
        let text = format!(
            "[mesh]\ngenerate = {{ kind = \"cloth\", vertices = [5, 5], size = [1.0, 1.0] }}\n\
             [[constraints]]\ntype = \"edge_spring\"\n{body}"
        );
        let scene = Scene::parse(&text, SceneFormat::Toml, std::path::Path::new("s.toml"), Default::default()).unwrap();
        let loaded = scene.load().unwrap();
        let kinds = ["hard_groups_conflict", "hard_targets_break_rigid_group", "faces_not_taken"];
        loaded
            .warnings
            .iter()
            .filter(|w| kinds.contains(&w.kind.as_str()))
            .map(|w| (w.kind.clone(), w.count, w.first.clone()))
            .collect()
    }

    fn hard(name: &str, vertices: &str, translate: [f64; 3]) -> String {
        format!(
            "[[constraints]]\ntype = \"position\"\nname = \"{name}\"\nvertices = {vertices}\nhard = true\ntranslate = {translate:?}\n"
        )
    }

    /// Each conflict is said once with its count and first, and only when it is one: two hard
    /// groups that agree, one hard vertex in a rigid group, hard targets moved as one body
    /// and listed quads are no conflict.
    #[test]
    fn groups_at_odds_are_counted_once_and_agreeing_ones_are_not() {
        let left = hard("left", "[0, 1, 2]", [0.0; 3]);
        assert_eq!(warnings_of(&format!("{left}{}", hard("same", "[2, 3]", [0.0; 3]))), []);
        let at_odds = warnings_of(&format!("{left}{}", hard("moved", "[2, 3, 1]", [0.0, 0.5, 0.0])));
        assert_eq!(at_odds, [("hard_groups_conflict".into(), 2, "vertex 1: \"left\" and \"moved\"".into())]);

        let rigid = "[[constraints]]\ntype = \"rigid\"\nname = \"plate\"\nvertices = [0, 1, 2, 5, 6, 7]\n";
        assert_eq!(warnings_of(&format!("{rigid}{}", hard("pin", "[0]", [0.3, 0.0, 0.0]))), []);
        let together = format!("{}{}", hard("a", "[0]", [0.2, 0.1, 0.0]), hard("b", "[7]", [0.2, 0.1, 0.0]));
        assert_eq!(warnings_of(&format!("{rigid}{together}")), []);
        let apart = format!("{}{}", hard("a", "[0]", [0.0; 3]), hard("b", "[7]", [0.4, 0.0, 0.0]));
        let broken = warnings_of(&format!("{rigid}{apart}"));
        assert_eq!(broken, [("hard_targets_break_rigid_group".into(), 1, "\"plate\" (vertices 0 and 7)".into())]);
        // Two points are always a similarity of their rest (turned and scaled): three, moved
        // apart along a row, are not.
        let similarity = rigid.replace("\"rigid\"", "\"similarity\"");
        assert_eq!(warnings_of(&format!("{similarity}{apart}")), []);
        let stretched = format!("{}{}", hard("a", "[0, 1]", [0.0; 3]), hard("b", "[2]", [0.4, 0.0, 0.0]));
        assert_eq!(warnings_of(&format!("{similarity}{stretched}")).len(), 1);

        // The generated cloth is all triangles: whole_selection takes them as one set.
        let plane = "[[constraints]]\ntype = \"plane\"\nfaces = [0, 1, 2]\nwhole_selection = true\n";
        assert_eq!(warnings_of(plane), []);
    }

    /// Suzanne's faces 48 and 49 are triangles among quads: listed for a plane or a rectangle,
    /// they are counted as left out; listed quads are taken.
    #[test]
    fn listed_faces_a_type_cannot_take_are_counted() {
        use crate::scene::{Scene, SceneFormat};
        let suzanne = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/suzanne.obj");
        let at = |body: &str| {
            let text = format!(
                "[mesh]\npath = '{suzanne}'\n[[constraints]]\ntype = \"edge_spring\"\n\
                 [[constraints]]\ntype = \"position\"\nbox = {{ min = [-9, -9, -9], max = [9, 9, 9] }}\n{body}"
            );
            let scene =
                Scene::parse(&text, SceneFormat::Toml, std::path::Path::new("s.toml"), Default::default()).unwrap();
            let loaded = scene.load().unwrap();
            let found = loaded.warnings.iter().find(|w| w.kind == "faces_not_taken");
            found.map(|w| (w.count, w.first.clone(), w.file.clone()))
        };
        let mesh = crate::io::read_mesh(std::path::Path::new(suzanne)).unwrap().mesh;
        assert_eq!([0, 48, 49].map(|f| mesh.polygons.get(f).unwrap().len()), [4, 3, 3]);
        assert_eq!(at("[[constraints]]\ntype = \"plane\"\nfaces = [0, 1, 2]\n"), None);
        let both = "[[constraints]]\ntype = \"plane\"\nfaces = [0, 48, 49]\n\
                    [[constraints]]\ntype = \"rectangle\"\nname = \"rect\"\nfaces = [1, 48]\n";
        let first = "constraints[2] (\"plane\"): face 48 (3 corners)".to_string();
        assert_eq!(at(both), Some((3, first, Some(std::path::PathBuf::from("s.toml")))));
    }
}
