//! Colliders in the editor: the scene's description of each ([`ColliderSpec`], kept in the
//! document's [`EditState`](crate::edit_state::EditState) as a scene's `[[colliders]]` entry
//! says it, input frame), defaults placed around a mesh, rigid moves and turns (the gizmo's
//! commands), and what the viewport draws of each (line segments, input frame).
//!
//! How colliders become the solver's contact is the core's one rule, `Scene::build_contact`:
//! [`contact_model`] hands the document's colliders and `[contact]` settings to it, for the
//! static solve ([`EditSolver`](crate::edit_state::EditSolver)) and for dynamic mode alike.

use crate::error::EditorError;
use glam::{DQuat, DVec3};
use shapeup_core::contact::{ColliderSpec, ContactModel, ContactSettings, ShapeSpec};
use shapeup_core::geometry::{RestGeometry, WorkingFrame};
use shapeup_core::mesh::Mesh;
use shapeup_core::scene::{MeshSettings, Rotate, Scene, SceneError, SolverSettings};
use shapeup_core::warnings::Warnings;
use std::path::{Path, PathBuf};

/// The primitive collider types the editor adds with defaults, in menu order (a mesh comes
/// from a file: [`mesh_collider`]).
pub const PRIMITIVES: [&str; 4] = ["sphere", "box", "plane", "capsule"];

/// A collider of type `kind` (one of [`PRIMITIVES`]) placed for a mesh whose bounding box is
/// [`lo`, `hi`] (input frame) and that falls along −y: a sphere, a box (a table) or a capsule
/// (a bar across z) just below its centre, or a ground plane below it; `None` for another
/// type. Something dropped onto it lands on it.
pub fn default_collider(kind: &str, lo: DVec3, hi: DVec3) -> Option<ColliderSpec> {
    let size = hi - lo;
    let diagonal = if size.length() > 0.0 { size.length() } else { 1.0 };
    let c = 0.5 * (lo + hi);
    // Below the lowest point, so that the rest shape does not start inside.
    let gap = 0.1 * diagonal;
    let top = lo.y - gap;
    let shape = match kind {
        "sphere" => {
            let radius = 0.3 * size.x.max(size.z).max(0.2 * diagonal);
            ShapeSpec::Sphere { center: [c.x, top - radius, c.z], radius }
        }
        "box" => {
            let half = DVec3::new(0.3 * size.x.max(0.2 * diagonal), 0.05 * diagonal, 0.3 * size.z.max(0.2 * diagonal));
            ShapeSpec::Box {
                min: [c.x - half.x, top - 2.0 * half.y, c.z - half.z],
                max: [c.x + half.x, top, c.z + half.z],
                rotate: None,
            }
        }
        "plane" => ShapeSpec::Plane { point: [c.x, lo.y - 2.0 * gap, c.z], normal: [0.0, 1.0, 0.0] },
        "capsule" => {
            let radius = 0.03 * diagonal;
            let reach = 0.5 * size.z + 0.25 * diagonal;
            let y = top - radius;
            ShapeSpec::Capsule { a: [c.x, y, c.z - reach], b: [c.x, y, c.z + reach], radius }
        }
        _ => return None,
    };
    Some(ColliderSpec { shape, friction: 0.3, velocity: [0.0; 3], spin: None })
}

/// A mesh collider from `path` (closed when every edge has two triangles, else one-sided),
/// with the default friction of [`default_collider`]. A relative path is made absolute (the
/// document keeps mesh colliders' paths resolved, and a saved scene writes them so).
pub fn mesh_collider(path: &Path) -> ColliderSpec {
    let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    ColliderSpec {
        shape: ShapeSpec::Mesh { path, closed: None, thickness: None, translate: [0.0; 3], rotate: None },
        friction: 0.3,
        velocity: [0.0; 3],
        spin: None,
    }
}

/// A box's pose: its centre (input frame, after its rotation), half extents and rotation.
fn box_pose(min: [f64; 3], max: [f64; 3], rotate: Option<&Rotate>) -> (DVec3, DVec3, DQuat) {
    let (lo, hi) = (DVec3::from(min), DVec3::from(max));
    let center = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    match rotate {
        Some(r) => {
            let turn = DQuat::from_axis_angle(DVec3::from(r.axis).normalize_or(DVec3::Y), r.angle_deg.to_radians());
            let pivot = r.center.map_or(center, DVec3::from);
            (pivot + turn * (center - pivot), half, turn)
        }
        None => (center, half, DQuat::IDENTITY),
    }
}

/// The box of centre `center`, half extents `half` and rotation `turn` as a scene writes it
/// (turned about its own centre; no `rotate` when it is not turned).
fn box_shape(center: DVec3, half: DVec3, turn: DQuat) -> ShapeSpec {
    let (axis, angle) = turn.normalize().to_axis_angle();
    let rotate = (angle.abs() > 1e-12 && axis.is_finite()).then(|| Rotate {
        axis: axis.to_array(),
        angle_deg: angle.to_degrees(),
        center: None,
    });
    ShapeSpec::Box { min: (center - half).to_array(), max: (center + half).to_array(), rotate }
}

/// Where the gizmo sits on a collider and what it turns about (input frame): a sphere's
/// centre, a capsule's midpoint, a box's centre, a plane's point, a mesh's placed origin (its
/// rotation centre, moved by its translation: where a DCC tool shows an object's origin).
pub fn center(spec: &ColliderSpec) -> DVec3 {
    match &spec.shape {
        ShapeSpec::Sphere { center, .. } => DVec3::from(*center),
        ShapeSpec::Capsule { a, b, .. } => 0.5 * (DVec3::from(*a) + DVec3::from(*b)),
        ShapeSpec::Box { min, max, rotate } => box_pose(*min, *max, rotate.as_ref()).0,
        ShapeSpec::Plane { point, .. } => DVec3::from(*point),
        ShapeSpec::Mesh { translate, rotate, .. } => {
            rotate.and_then(|r| r.center).map_or(DVec3::ZERO, DVec3::from) + DVec3::from(*translate)
        }
    }
}

/// `spec` moved by `delta` (input frame); an explicit spin centre moves with it.
///
/// # Errors
/// [`EditorError::BadValue`] for a non-finite translation.
pub fn translated(spec: &ColliderSpec, delta: DVec3) -> Result<ColliderSpec, EditorError> {
    if !delta.is_finite() {
        return Err(EditorError::BadValue(format!("translation must be finite, found {delta}")));
    }
    let shift = |p: [f64; 3]| (DVec3::from(p) + delta).to_array();
    let shape = match &spec.shape {
        ShapeSpec::Sphere { center, radius } => ShapeSpec::Sphere { center: shift(*center), radius: *radius },
        ShapeSpec::Capsule { a, b, radius } => ShapeSpec::Capsule { a: shift(*a), b: shift(*b), radius: *radius },
        ShapeSpec::Box { min, max, rotate } => ShapeSpec::Box {
            min: shift(*min),
            max: shift(*max),
            rotate: rotate.map(|r| Rotate { center: r.center.map(shift), ..r }),
        },
        ShapeSpec::Plane { point, normal } => ShapeSpec::Plane { point: shift(*point), normal: *normal },
        // The rotation centre is in the file's coordinates: only the translation moves.
        ShapeSpec::Mesh { path, closed, thickness, translate, rotate } => ShapeSpec::Mesh {
            path: path.clone(),
            closed: *closed,
            thickness: *thickness,
            translate: shift(*translate),
            rotate: *rotate,
        },
    };
    let spin = spec.spin.map(|s| shapeup_core::scene::Spin { center: s.center.map(shift), ..s });
    Ok(ColliderSpec { shape, spin, ..spec.clone() })
}

/// `spec` turned by `angle` radians about `axis` (input frame, right-handed) through its
/// [`center`]: a capsule's ends, a box's rotation, a plane's normal turn (a sphere stays as it
/// is); an explicit spin centre turns with it.
///
/// # Errors
/// [`EditorError::BadValue`] for a zero axis or a non-finite angle.
pub fn turned(spec: &ColliderSpec, axis: DVec3, angle: f64) -> Result<ColliderSpec, EditorError> {
    let axis = axis.try_normalize().filter(|_| angle.is_finite()).ok_or_else(|| {
        EditorError::BadValue(format!("rotation needs a non-zero axis and a finite angle ({axis}, {angle})"))
    })?;
    let pivot = center(spec);
    let turn = DQuat::from_axis_angle(axis, angle);
    let about = |p: [f64; 3]| (pivot + turn * (DVec3::from(p) - pivot)).to_array();
    let shape = match &spec.shape {
        ShapeSpec::Sphere { .. } => spec.shape.clone(),
        ShapeSpec::Capsule { a, b, radius } => ShapeSpec::Capsule { a: about(*a), b: about(*b), radius: *radius },
        ShapeSpec::Box { min, max, rotate } => {
            let (c, half, old) = box_pose(*min, *max, rotate.as_ref());
            box_shape(c, half, turn * old)
        }
        ShapeSpec::Plane { point, normal } => {
            ShapeSpec::Plane { point: *point, normal: (turn * DVec3::from(*normal)).to_array() }
        }
        // About its placed origin c + t: p ↦ c + t + T R (p − c), so R becomes T R.
        ShapeSpec::Mesh { path, closed, thickness, translate, rotate } => {
            let old = rotate.map_or(DQuat::IDENTITY, |r| {
                DQuat::from_axis_angle(DVec3::from(r.axis).normalize_or(DVec3::Y), r.angle_deg.to_radians())
            });
            let (axis, angle) = (turn * old).to_axis_angle();
            let center = rotate.and_then(|r| r.center);
            ShapeSpec::Mesh {
                path: path.clone(),
                closed: *closed,
                thickness: *thickness,
                translate: *translate,
                rotate: (angle.abs() > 1e-12).then(|| Rotate {
                    axis: axis.to_array(),
                    angle_deg: angle.to_degrees(),
                    center,
                }),
            }
        }
    };
    let spin = spec.spin.map(|s| shapeup_core::scene::Spin { center: s.center.map(about), ..s });
    Ok(ColliderSpec { shape, spin, ..spec.clone() })
}

/// Circle points: `n` segments of the circle of `radius` about `c` in the plane of unit `u`, `v`.
fn circle(c: DVec3, u: DVec3, v: DVec3, radius: f64, n: usize, out: &mut Vec<[DVec3; 2]>) {
    let at = |k: usize| {
        let t = std::f64::consts::TAU * k as f64 / n as f64;
        c + radius * (t.cos() * u + t.sin() * v)
    };
    out.extend((0..n).map(|k| [at(k), at(k + 1)]));
}

/// Two unit vectors perpendicular to unit `d` and to each other.
fn perpendiculars(d: DVec3) -> (DVec3, DVec3) {
    let u = d.any_orthonormal_vector();
    (u, d.cross(u))
}

/// The most edges drawn of a mesh collider (a finer mesh shows every k-th edge).
pub const MAX_DRAWN_EDGES: usize = 20_000;

/// Segments per full circle in [`outline`].
const CIRCLE_SEGMENTS: usize = 48;

/// What the viewport draws of a collider: line segments in the input frame. A sphere: three
/// great circles; a capsule: its end circles, four lines along it and its caps' arcs; a box:
/// its twelve edges; a plane: a square grid of side `extent` about its point; a mesh: the
/// edges of `mesh` (its file, read by the caller; nothing without it), at most
/// [`MAX_DRAWN_EDGES`].
pub fn outline(spec: &ColliderSpec, mesh: Option<&Mesh>, extent: f64) -> Vec<[DVec3; 2]> {
    let mut out = Vec::new();
    let n = CIRCLE_SEGMENTS;
    match &spec.shape {
        ShapeSpec::Sphere { center, radius } => {
            let c = DVec3::from(*center);
            circle(c, DVec3::X, DVec3::Y, *radius, n, &mut out);
            circle(c, DVec3::Y, DVec3::Z, *radius, n, &mut out);
            circle(c, DVec3::Z, DVec3::X, *radius, n, &mut out);
        }
        ShapeSpec::Capsule { a, b, radius } => {
            let (a, b) = (DVec3::from(*a), DVec3::from(*b));
            let d = (b - a).normalize_or(DVec3::Y);
            let (u, v) = perpendiculars(d);
            let r = *radius;
            circle(a, u, v, r, n, &mut out);
            circle(b, u, v, r, n, &mut out);
            for side in [u, v, -u, -v] {
                out.push([a + r * side, b + r * side]);
            }
            // Half circles over each end, in the planes (d, u) and (d, v).
            for (end, dir) in [(b, d), (a, -d)] {
                for side in [u, v] {
                    let at = |k: usize| {
                        let t = std::f64::consts::PI * k as f64 / (n / 2) as f64;
                        end + r * (t.cos() * side + t.sin() * dir)
                    };
                    out.extend((0..n / 2).map(|k| [at(k), at(k + 1)]));
                }
            }
        }
        ShapeSpec::Box { min, max, rotate } => {
            let (c, half, turn) = box_pose(*min, *max, rotate.as_ref());
            let corner = |i: usize| {
                let s = DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                c + turn * (s * half)
            };
            for i in 0..8 {
                for bit in [1, 2, 4] {
                    if i & bit == 0 {
                        out.push([corner(i), corner(i | bit)]);
                    }
                }
            }
        }
        ShapeSpec::Plane { point, normal } => out = plane_grid(DVec3::from(*point), DVec3::from(*normal), extent),
        ShapeSpec::Mesh { translate, rotate, .. } => {
            if let Some(mesh) = mesh {
                let (edges, _) = shapeup_core::topology::unique_edges(&mesh.triangles);
                let stride = edges.len().div_ceil(MAX_DRAWN_EDGES).max(1);
                let place = shapeup_core::contact::mesh_placement(*translate, rotate.as_ref());
                let p = &mesh.positions;
                out.extend(edges.iter().step_by(stride).map(|&[a, b]| [place(p[a as usize]), place(p[b as usize])]));
            }
        }
    }
    out
}

/// A square grid of 9 × 9 lines, `extent` across, centred on `point` in the plane of normal
/// `normal` (Y when zero): how a plane collider and the floor are drawn.
pub fn plane_grid(point: DVec3, normal: DVec3, extent: f64) -> Vec<[DVec3; 2]> {
    let (u, v) = perpendiculars(normal.normalize_or(DVec3::Y));
    let h = 0.5 * extent;
    let lines = 8;
    let mut out = Vec::with_capacity(2 * (lines + 1));
    for k in 0..=lines {
        let t = -h + extent * k as f64 / lines as f64;
        out.push([point + t * u - h * v, point + t * u + h * v]);
        out.push([point - h * u + t * v, point + h * u + t * v]);
    }
    out
}

/// The core's contact model of `colliders` and `settings` on `mesh` with rest geometry `rest`
/// in `frame`, made by the scene's one rule (`Scene::build_contact`: the thickness default,
/// which vertices take part, the self-collision surface); `None` when nothing can touch. Mesh
/// colliders' paths are used as they are (the document keeps them absolute).
///
/// # Errors
/// [`EditorError::Collider`] naming the collider (a mesh file that cannot be read, has no
/// faces or is said to be closed while open; a bad value).
pub fn contact_model(
    colliders: &[ColliderSpec],
    settings: ContactSettings,
    mesh: &Mesh,
    rest: &RestGeometry,
    frame: &WorkingFrame,
) -> Result<Option<ContactModel>, EditorError> {
    settings.validate().map_err(|e| EditorError::Collider(format!("[contact]: {e}")))?;
    let scene = Scene {
        mesh: MeshSettings {
            path: PathBuf::new(),
            generate: None,
            normalize: true,
            tetrahedralize: false,
            start: None,
            units: None,
        },
        solver: SolverSettings::default(),
        groups: Vec::new(),
        colliders: colliders.to_vec(),
        contact: settings,
        output: Default::default(),
        material: None,
        loads: Default::default(),
        base_dir: PathBuf::new(),
        file: PathBuf::new(),
    };
    scene.build_contact(mesh, rest, None, frame, &mut Warnings::new()).map_err(|e| {
        EditorError::Collider(match e {
            SceneError::Invalid { entry, message, .. } => format!("{entry}: {message}"),
            other => other.to_string(),
        })
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used)]
    use super::*;

    fn close(a: [f64; 3], b: [f64; 3]) -> bool {
        (DVec3::from(a) - DVec3::from(b)).length() < 1e-9
    }

    #[test]
    fn defaults_lie_below_the_mesh_and_are_valid() {
        let (lo, hi) = (DVec3::new(-0.5, 0.0, -0.5), DVec3::new(0.5, 0.0, 0.5));
        for kind in PRIMITIVES {
            let spec = default_collider(kind, lo, hi).unwrap();
            spec.validate().unwrap();
            assert_eq!(spec.kind(), kind);
            let c = center(&spec);
            assert!(c.y < lo.y, "{kind} below the mesh: {c}");
        }
        assert!(default_collider("mesh", lo, hi).is_none());
    }

    #[test]
    fn a_turned_box_turns_about_its_centre_and_moves_with_its_rotation() {
        let spec = default_collider("box", DVec3::splat(-1.0), DVec3::splat(1.0)).unwrap();
        let c = center(&spec);
        let turned = turned(&spec, DVec3::Y, std::f64::consts::FRAC_PI_2).unwrap();
        assert!((center(&turned) - c).length() < 1e-12, "same centre");
        let ShapeSpec::Box { rotate: Some(r), .. } = &turned.shape else { panic!("{turned:?}") };
        assert!((r.angle_deg - 90.0).abs() < 1e-9 && close(r.axis, [0.0, 1.0, 0.0]), "{r:?}");
        let back = self::turned(&turned, DVec3::Y, -std::f64::consts::FRAC_PI_2).unwrap();
        assert!(matches!(back.shape, ShapeSpec::Box { rotate: None, .. }), "{back:?}");
        let moved = translated(&turned, DVec3::X).unwrap();
        assert!((center(&moved) - c - DVec3::X).length() < 1e-12);
    }

    #[test]
    fn a_capsule_and_a_plane_turn_and_a_sphere_does_not() {
        let capsule = ColliderSpec {
            shape: ShapeSpec::Capsule { a: [0.0, 0.0, -1.0], b: [0.0, 0.0, 1.0], radius: 0.1 },
            friction: 0.0,
            velocity: [0.0; 3],
            spin: None,
        };
        let t = turned(&capsule, DVec3::Y, std::f64::consts::FRAC_PI_2).unwrap();
        let ShapeSpec::Capsule { a, b, .. } = t.shape else { panic!() };
        assert!(close(a, [-1.0, 0.0, 0.0]) && close(b, [1.0, 0.0, 0.0]), "{a:?} {b:?}");
        let plane = default_collider("plane", DVec3::ZERO, DVec3::ONE).unwrap();
        let t = turned(&plane, DVec3::X, std::f64::consts::FRAC_PI_2).unwrap();
        let ShapeSpec::Plane { normal, .. } = t.shape else { panic!() };
        assert!(close(normal, [0.0, 0.0, 1.0]), "{normal:?}");
        let sphere = default_collider("sphere", DVec3::ZERO, DVec3::ONE).unwrap();
        assert_eq!(turned(&sphere, DVec3::X, 1.0).unwrap(), sphere);
        assert!(translated(&sphere, DVec3::NAN).is_err() && turned(&sphere, DVec3::ZERO, 1.0).is_err());
    }

    #[test]
    fn a_mesh_collider_moves_and_turns_about_its_placed_origin() {
        // Its outline (the placed mesh) follows: moved by X, then turned a quarter about Y
        // through the moved origin, a vertex p of the file lands at X + R_y(90°) p.
        let grid = shapeup_core::generate::cloth_grid(3, 3, 1.0, 1.0);
        let mesh = mesh_collider(Path::new("/tmp/terrain.obj"));
        assert!(center(&mesh).length() < 1e-12);
        let moved = translated(&mesh, DVec3::X).unwrap();
        assert!((center(&moved) - DVec3::X).length() < 1e-12);
        let turned = turned(&moved, DVec3::Y, std::f64::consts::FRAC_PI_2).unwrap();
        let q = DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2);
        let expected: Vec<[DVec3; 2]> =
            outline(&mesh, Some(&grid), 1.0).iter().map(|s| s.map(|p| DVec3::X + q * p)).collect();
        let found = outline(&turned, Some(&grid), 1.0);
        assert_eq!(found.len(), expected.len());
        for (a, b) in found.iter().zip(&expected) {
            assert!((a[0] - b[0]).length() < 1e-12 && (a[1] - b[1]).length() < 1e-12, "{a:?} {b:?}");
        }
        // Turning back leaves no rotation.
        let back = self::turned(&turned, DVec3::Y, -std::f64::consts::FRAC_PI_2).unwrap();
        assert!(matches!(back.shape, ShapeSpec::Mesh { rotate: None, .. }), "{back:?}");
    }

    #[test]
    fn outlines_have_the_expected_segments() {
        let (lo, hi) = (DVec3::ZERO, DVec3::ONE);
        let count = |kind| outline(&default_collider(kind, lo, hi).unwrap(), None, 2.0).len();
        assert_eq!(count("box"), 12);
        assert_eq!(count("sphere"), 3 * CIRCLE_SEGMENTS);
        assert_eq!(count("plane"), 18);
        assert_eq!(count("capsule"), 2 * CIRCLE_SEGMENTS + 4 + 4 * (CIRCLE_SEGMENTS / 2));
        // A sphere's outline lies on the sphere.
        let sphere = default_collider("sphere", lo, hi).unwrap();
        let ShapeSpec::Sphere { center: c, radius } = sphere.shape else { panic!() };
        for [p, _] in outline(&sphere, None, 1.0) {
            assert!(((p - DVec3::from(c)).length() - radius).abs() < 1e-12);
        }
        let grid = shapeup_core::generate::cloth_grid(3, 3, 1.0, 1.0);
        assert_eq!(outline(&mesh_collider(Path::new("x.obj")), Some(&grid), 1.0).len(), 16, "unique edges");
    }
}
