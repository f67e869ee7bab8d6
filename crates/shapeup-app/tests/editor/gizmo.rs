//! The handle gizmo's model driven by scripted pointer drags, without a window: arrows move
//! only along their axis and keep the grabbed point under the cursor, squares stay in their
//! plane, rings turn about their axis in the sense the cursor turns, there-and-back drags are
//! the identity, modifiers leave presses to the viewport, and a document takes a gizmo drag
//! as one undo step.

use glam::{DVec3, Vec2, Vec3};
use shapeup_app::gizmo::{
    GizmoController, GizmoOutput, GizmoTarget, GizmoTool, PointerState, SNAP_ANGLE, apply_to_targets,
    command_from_result, snap_step,
};
use shapeup_app::{Command, Document, GroupKey, OrbitCamera, SelectMode, ShapeModel};
use transform_gizmo::{GizmoResult, mint};

const VIEWPORT: Vec2 = Vec2::new(800.0, 600.0);
const HANDLE: GroupKey = GroupKey(7);
const CENTER: DVec3 = DVec3::new(0.2, -0.1, 0.3);
/// The crate's default gizmo size (pixels): arrows end near it, rings have this radius.
const SIZE_PX: f64 = 75.0;
const AXES: [DVec3; 3] = [DVec3::X, DVec3::Y, DVec3::Z];

/// The editor's first view (three-quarter, from above) of a 2×2×2 box.
fn camera() -> OrbitCamera {
    let mut c = OrbitCamera::with_angles(0.5, 0.25);
    c.frame(Vec3::splat(-1.0), Vec3::splat(1.0));
    c
}

fn target(center: DVec3) -> GizmoTarget {
    GizmoTarget { handle: HANDLE, center, scale_hint: 2.0 * 3f64.sqrt() }
}

fn pixel(c: &OrbitCamera, p: DVec3) -> Vec2 {
    c.project(p.as_vec3(), VIEWPORT).expect("in front of the camera").0
}

/// World length of one pixel at the depth of `p` (the gizmo is sized in pixels).
fn world_per_px(c: &OrbitCamera, p: DVec3) -> f64 {
    f64::from(c.drag_in_view_plane(Vec2::X, p.as_vec3(), VIEWPORT).length())
}

#[derive(Debug, Default)]
struct Drag {
    commands: Vec<Command>,
    hovered_before: bool,
    started: bool,
    stopped: bool,
    /// `hovered` on each frame from the press to the last one with the button down.
    hovered_while_down: Vec<bool>,
}

fn frame(g: &mut GizmoController, c: &OrbitCamera, center: DVec3, pointer: PointerState) -> GizmoOutput {
    g.update(c, VIEWPORT, 1.0, target(center), pointer)
}

/// Hovers `path[0]`, presses there, moves through the rest of `path` and releases at its end.
fn drag_with(
    g: &mut GizmoController,
    c: &OrbitCamera,
    center: DVec3,
    path: &[Vec2],
    modifiers: bool,
    snap: bool,
) -> Drag {
    let mut drag = Drag::default();
    let record = |out: GizmoOutput, drag: &mut Drag| {
        drag.started |= out.drag_started;
        drag.stopped |= out.drag_stopped;
        drag.commands.extend(out.commands);
        out.hovered
    };
    let at = |p: Vec2| PointerState { pos: Some(p), modifiers, snap, ..PointerState::default() };
    drag.hovered_before = record(frame(g, c, center, at(path[0])), &mut drag);
    let pressed = PointerState { pressed: true, down: true, ..at(path[0]) };
    let press = frame(g, c, center, pressed);
    // Nor does the press: a click does not move the handle.
    assert!(press.commands.is_empty(), "{press:?}");
    let h = record(press, &mut drag);
    drag.hovered_while_down.push(h);
    for &p in &path[1..] {
        let h = record(frame(g, c, center, PointerState { down: true, ..at(p) }), &mut drag);
        drag.hovered_while_down.push(h);
    }
    let last = *path.last().unwrap();
    let release = frame(g, c, center, at(last));
    // The release frame carries no command: the app may end the document's drag at once.
    assert!(release.commands.is_empty(), "{release:?}");
    record(release, &mut drag);
    assert!(!g.is_dragging());
    drag
}

fn drag_on(g: &mut GizmoController, c: &OrbitCamera, center: DVec3, path: &[Vec2]) -> Drag {
    drag_with(g, c, center, path, false, false)
}

/// `steps` points from `a` to `b` (both included), each nudged sideways by `wobble` pixels in
/// turn, to check that off-axis cursor motion does not leak into the handle.
fn path(a: Vec2, b: Vec2, steps: usize, wobble: f32) -> Vec<Vec2> {
    let side = (b - a).perp().normalize_or_zero();
    (0..=steps)
        .map(|i| {
            let t = i as f32 / steps as f32;
            let nudge = if i == 0 || i == steps { 0.0 } else { wobble * if i % 2 == 0 { 1.0 } else { -1.0 } };
            a.lerp(b, t) + nudge * side
        })
        .collect()
}

fn total_move(commands: &[Command]) -> DVec3 {
    commands
        .iter()
        .map(|c| match c {
            Command::MoveHandle { handle, delta } => {
                assert_eq!(*handle, HANDLE);
                *delta
            }
            other => panic!("expected MoveHandle, got {other:?}"),
        })
        .sum()
}

/// Rotation axis (unit, sign of `reference`) and total angle about it.
fn total_turn(commands: &[Command], reference: DVec3) -> (DVec3, f64) {
    total_turn_within(commands, reference, 1e-12)
}

/// [`total_turn`] with a tolerance on the axis (the view axis comes from f32 matrices).
fn total_turn_within(commands: &[Command], reference: DVec3, tolerance: f64) -> (DVec3, f64) {
    let mut total = 0.0;
    for c in commands {
        match c {
            Command::RotateHandle { handle, axis, angle } => {
                assert_eq!(*handle, HANDLE);
                let unit = axis.normalize();
                let sign = unit.dot(reference).signum();
                assert!((unit * sign - reference).length() < tolerance, "axis {axis} is not ±{reference}");
                total += sign * angle;
            }
            other => panic!("expected RotateHandle, got {other:?}"),
        }
    }
    (reference, total)
}

/// The point of the `axis` ring of a gizmo at `center` on the eye's side that projects farthest
/// from the centre (the ring is least foreshortened there), away from where the other rings
/// cross it.
fn ring_point(c: &OrbitCamera, center: DVec3, axis: DVec3) -> DVec3 {
    let r = SIZE_PX * world_per_px(c, center);
    let to_eye = (c.eye().as_dvec3() - center).normalize();
    let u = (to_eye - to_eye.dot(axis) * axis).normalize();
    let v = axis.cross(u);
    let centre_px = pixel(c, center);
    (-35..=35)
        .map(|k| f64::from(k) * 2f64.to_radians())
        .map(|phi| phi.cos() * u + phi.sin() * v)
        .filter(|d| AXES.iter().all(|b| d.dot(*b).abs() < 0.8))
        .map(|d| center + r * d)
        .max_by(|a, b| (pixel(c, *a) - centre_px).length().total_cmp(&(pixel(c, *b) - centre_px).length()))
        .unwrap()
}

fn screen_angle(p: Vec2, centre: Vec2) -> f64 {
    let d = p - centre;
    f64::from(d.y).atan2(f64::from(d.x))
}

/// The cursor from `start` around `centre` by `angle` (screen radians, +y down), in steps.
fn arc(start: Vec2, centre: Vec2, angle: f64, steps: usize) -> Vec<Vec2> {
    let r = (start - centre).length();
    let a0 = screen_angle(start, centre);
    (0..=steps)
        .map(|i| {
            let a = a0 + angle * i as f64 / steps as f64;
            centre + r * Vec2::new(a.cos() as f32, a.sin() as f32)
        })
        .collect()
}

#[test]
fn arrows_move_only_along_their_axis_and_keep_the_grabbed_point_under_the_cursor() {
    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    for axis in AXES {
        let mut g = GizmoController::new();
        let grabbed = CENTER + 45.0 * wpp * axis;
        let wanted = 30.0 * wpp * axis;
        let drag = drag_on(&mut g, &c, CENTER, &path(pixel(&c, grabbed), pixel(&c, grabbed + wanted), 6, 5.0));
        assert!(drag.hovered_before && drag.started && drag.stopped, "{axis}: {drag:?}");
        assert!(drag.hovered_while_down.iter().all(|h| *h), "{axis}: {drag:?}");
        assert!(drag.commands.len() >= 3, "{axis}: {drag:?}");
        for command in &drag.commands {
            let Command::MoveHandle { delta, .. } = command else { panic!("{command:?}") };
            let across = *delta - delta.dot(axis) * axis;
            assert!(across.length() <= 1e-12 * wpp, "{axis}: {delta} leaves the axis");
        }
        let moved = total_move(&drag.commands);
        assert!((moved - wanted).length() < 1e-3 * wanted.length(), "{axis}: moved {moved}, wanted {wanted}");
    }
}

#[test]
fn an_arrow_drag_there_and_back_is_the_identity() {
    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    let mut g = GizmoController::new();
    let start = pixel(&c, CENTER + 40.0 * wpp * DVec3::Y);
    let away = pixel(&c, CENTER + 90.0 * wpp * DVec3::Y);
    let mut there_and_back = path(start, away, 5, 3.0);
    there_and_back.extend(path(away, start, 5, 3.0).into_iter().skip(1));
    let drag = drag_on(&mut g, &c, CENTER, &there_and_back);
    assert!(drag.started && drag.stopped);
    assert!(drag.commands.len() >= 6);
    assert!(total_move(&drag.commands).length() < 1e-6 * wpp);
    let mut targets = vec![DVec3::ONE, DVec3::new(-0.5, 2.0, 0.0)];
    let before = targets.clone();
    apply_to_targets(HANDLE, &mut targets, &drag.commands);
    for (a, b) in targets.iter().zip(&before) {
        assert!((*a - *b).length() < 1e-6 * wpp);
    }
}

#[test]
fn plane_squares_move_in_their_plane_under_the_cursor() {
    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    for normal in AXES {
        // The crate puts each square at (a + b)·size/2, a and b the two other axes.
        let others: Vec<DVec3> = AXES.into_iter().filter(|x| *x != normal).collect();
        let square = CENTER + 0.5 * SIZE_PX * wpp * (others[0] + others[1]);
        let wanted = wpp * (25.0 * others[0] - 15.0 * others[1]);
        let mut g = GizmoController::new();
        let drag = drag_on(&mut g, &c, CENTER, &path(pixel(&c, square), pixel(&c, square + wanted), 5, 4.0));
        assert!(drag.started && drag.stopped, "{normal}: {drag:?}");
        for command in &drag.commands {
            let Command::MoveHandle { delta, .. } = command else { panic!("{normal}: {command:?}") };
            assert!(delta.dot(normal).abs() <= 1e-12 * wpp, "{normal}: {delta} leaves the plane");
        }
        let moved = total_move(&drag.commands);
        assert!((moved - wanted).length() < 1e-3 * wanted.length(), "{normal}: moved {moved}, wanted {wanted}");
    }
}

#[test]
fn rings_turn_about_their_axis_in_the_sense_of_the_cursor_and_back() {
    let c = camera();
    let centre_px = pixel(&c, CENTER);
    for axis in AXES {
        for turn in [40f64.to_radians(), -25f64.to_radians()] {
            let grabbed = ring_point(&c, CENTER, axis);
            let start = pixel(&c, grabbed);
            let mut g = GizmoController::new();
            let drag = drag_on(&mut g, &c, CENTER, &arc(start, centre_px, turn, 8));
            assert!(drag.started && drag.stopped, "{axis}: {drag:?}");
            let (axis, angle) = total_turn(&drag.commands, axis);
            // The crate turns by the cursor's angle about the gizmo's centre on screen.
            assert!((angle.abs() - turn.abs()).abs() < 1e-4, "{axis}: turned {angle}, cursor {turn}");
            // The grabbed point turns the way the cursor did.
            let turned = CENTER + glam::DQuat::from_axis_angle(axis, angle) * (grabbed - CENTER);
            let seen = screen_angle(pixel(&c, turned), centre_px) - screen_angle(start, centre_px);
            let seen = (seen + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU) - std::f64::consts::PI;
            assert!(seen * turn > 0.0, "{axis}: the grabbed point turned {seen} on screen, the cursor {turn}");

            // And back: the identity.
            let mut g = GizmoController::new();
            let mut there_and_back = arc(start, centre_px, turn, 8);
            there_and_back.extend(arc(*there_and_back.last().unwrap(), centre_px, -turn, 8).into_iter().skip(1));
            let drag = drag_on(&mut g, &c, CENTER, &there_and_back);
            let (_, angle) = total_turn(&drag.commands, axis);
            assert!(angle.abs() < 1e-5, "{axis}: {angle}");
            let mut targets = vec![CENTER + DVec3::new(0.3, 0.1, -0.2), CENTER - DVec3::new(0.3, 0.1, -0.2)];
            let before = targets.clone();
            apply_to_targets(HANDLE, &mut targets, &drag.commands);
            for (a, b) in targets.iter().zip(&before) {
                assert!((*a - *b).length() < 1e-5, "{a} != {b}");
            }
        }
    }
}

#[test]
fn view_circles_move_in_the_view_plane_and_turn_about_the_view_direction() {
    let c = camera();
    let (right, up, forward) = c.basis();
    let centre_px = pixel(&c, CENTER);
    let wpp = world_per_px(&c, CENTER);

    // Inner circle: the centre follows the cursor in the plane facing the camera.
    let mut g = GizmoController::new();
    let start = centre_px + Vec2::new(4.0, -3.0);
    let delta_px = Vec2::new(-37.0, 22.0);
    let drag = drag_on(&mut g, &c, CENTER, &path(start, start + delta_px, 4, 0.0));
    assert!(drag.started && drag.stopped);
    let moved = total_move(&drag.commands);
    let wanted = c.drag_in_view_plane(delta_px, CENTER.as_vec3(), VIEWPORT).as_dvec3();
    assert!(moved.dot(forward.as_dvec3()).abs() < 1e-6 * moved.length(), "{moved} leaves the view plane");
    assert!((moved - wanted).length() < 1e-2 * wanted.length(), "moved {moved}, wanted {wanted}");

    // Outer circle (just outside the rings): turns about the view direction.
    let mut g = GizmoController::new();
    let on_circle = CENTER + (SIZE_PX + 9.0) * wpp * (0.6 * right + 0.8 * up).as_dvec3();
    let drag = drag_on(&mut g, &c, CENTER, &arc(pixel(&c, on_circle), centre_px, 0.5, 5));
    assert!(drag.started && drag.stopped, "{drag:?}");
    let (_, angle) = total_turn_within(&drag.commands, forward.as_dvec3(), 1e-6);
    assert!((angle.abs() - 0.5).abs() < 1e-3, "{angle}");
}

#[test]
fn presses_with_modifiers_or_off_the_gizmo_are_left_to_the_viewport() {
    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    let on_arrow = pixel(&c, CENTER + 45.0 * wpp * DVec3::X);
    let elsewhere = pixel(&c, CENTER) + Vec2::new(250.0, 200.0);

    // Hovering an arrow claims the pointer; a modifier gives it back and a press does nothing.
    let mut g = GizmoController::new();
    let hover = frame(&mut g, &c, CENTER, PointerState { pos: Some(on_arrow), ..PointerState::default() });
    assert!(hover.hovered && g.claims_pointer());
    let drag = drag_with(&mut g, &c, CENTER, &path(on_arrow, on_arrow + Vec2::new(40.0, 0.0), 4, 0.0), true, false);
    assert!(!drag.hovered_before && !drag.started && !drag.stopped && drag.commands.is_empty(), "{drag:?}");
    assert!(!g.claims_pointer());

    // A drag that starts elsewhere and crosses the gizmo (an orbit) is not the gizmo's, and the
    // gizmo does not claim the pointer on its way.
    let mut g = GizmoController::new();
    let drag = drag_on(&mut g, &c, CENTER, &path(elsewhere, on_arrow, 6, 0.0));
    assert!(!drag.hovered_before && !drag.started && !drag.stopped && drag.commands.is_empty(), "{drag:?}");
    assert!(drag.hovered_while_down.iter().all(|h| !h), "{drag:?}");
    // Released over the arrow: now it is hovered.
    assert!(g.claims_pointer());

    // A click on a part: an empty drag (begin/end with nothing between).
    let mut g = GizmoController::new();
    let drag = drag_on(&mut g, &c, CENTER, &[on_arrow]);
    assert!(drag.started && drag.stopped && drag.commands.is_empty(), "{drag:?}");

    // Outside the viewport (no position): nothing.
    let mut g = GizmoController::new();
    let out =
        frame(&mut g, &c, CENTER, PointerState { pos: None, pressed: true, down: true, ..PointerState::default() });
    assert_eq!(out, GizmoOutput::default());
}

#[test]
fn tools_show_only_their_parts() {
    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    let on_arrow = pixel(&c, CENTER + 45.0 * wpp * DVec3::X);
    let on_ring = pixel(&c, ring_point(&c, CENTER, DVec3::Y));
    let centre_px = pixel(&c, CENTER);

    let mut g = GizmoController::new();
    g.set_tool(GizmoTool::Rotate);
    assert!(!drag_on(&mut g, &c, CENTER, &path(on_arrow, on_arrow + Vec2::new(30.0, 5.0), 3, 0.0)).started);
    let turn = drag_on(&mut g, &c, CENTER, &arc(on_ring, centre_px, 0.3, 3));
    assert!(turn.started);
    total_turn(&turn.commands, DVec3::Y);

    g.set_tool(GizmoTool::Translate);
    assert_eq!(g.tool(), GizmoTool::Translate);
    assert!(!drag_on(&mut g, &c, CENTER, &arc(on_ring, centre_px, 0.3, 3)).started);
    let moved = drag_on(&mut g, &c, CENTER, &path(on_arrow, on_arrow + Vec2::new(30.0, 5.0), 3, 0.0));
    assert!(moved.started);
    total_move(&moved.commands);
}

#[test]
fn snapping_moves_by_steps_of_the_scale_hint_and_turns_by_15_degrees() {
    assert_eq!(snap_step(2.0 * 3f64.sqrt()), 0.1);
    assert_eq!(snap_step(10.0), 1.0);
    assert!((snap_step(0.5) - 0.01).abs() < 1e-15);
    assert_eq!(snap_step(f64::NAN), 0.1);
    assert_eq!(snap_step(0.0), 0.1);

    let c = camera();
    let wpp = world_per_px(&c, CENTER);
    let step = snap_step(target(CENTER).scale_hint);
    let grabbed = CENTER + 45.0 * wpp * DVec3::Z;
    let mut g = GizmoController::new();
    let drag = drag_with(
        &mut g,
        &c,
        CENTER,
        &path(pixel(&c, grabbed), pixel(&c, grabbed + 0.27 * DVec3::Z), 7, 0.0),
        false,
        true,
    );
    let moved = total_move(&drag.commands);
    assert!((moved - 0.3 * DVec3::Z).length() < 1e-5, "{moved}: not 0.27 snapped to {step}");

    let centre_px = pixel(&c, CENTER);
    let mut g = GizmoController::new();
    let drag = drag_with(
        &mut g,
        &c,
        CENTER,
        &arc(pixel(&c, ring_point(&c, CENTER, DVec3::X)), centre_px, 0.45, 6),
        false,
        true,
    );
    let (_, angle) = total_turn(&drag.commands, DVec3::X);
    let steps = angle / SNAP_ANGLE;
    assert!((steps.abs() - 2.0).abs() < 1e-4, "{angle} is not 2 snapping steps of 15°");
}

#[test]
fn draw_data_surrounds_the_centre_and_is_empty_behind_the_camera() {
    let c = camera();
    let mut g = GizmoController::new();
    assert!(g.draw_data().vertices.is_empty(), "nothing before the first update");
    let _ = frame(&mut g, &c, CENTER, PointerState::default());
    let data = g.draw_data();
    assert!(data.indices.len() >= 3 * 50 && data.indices.len().is_multiple_of(3));
    assert_eq!(data.vertices.len(), data.colors.len());
    assert!(data.indices.iter().all(|&i| (i as usize) < data.vertices.len()));
    let centre_px = pixel(&c, CENTER);
    let reach = data.vertices.iter().map(|&[x, y]| (Vec2::new(x, y) - centre_px).length()).fold(0.0, f32::max);
    assert!((60.0..120.0).contains(&reach), "the gizmo reaches {reach} px from its centre");

    let behind = c.eye().as_dvec3() + c.basis().2.as_dvec3() * -1.0;
    let out = frame(&mut g, &c, behind, PointerState { pos: Some(centre_px), ..PointerState::default() });
    assert!(!out.hovered);
    assert!(g.draw_data().vertices.is_empty());
}

#[test]
fn results_convert_to_commands() {
    let v = |x: f64, y: f64, z: f64| mint::Vector3 { x, y, z };
    let moved = GizmoResult::Translation { delta: v(0.1, 0.0, -0.2), total: v(1.0, 0.0, 0.0) };
    assert_eq!(
        command_from_result(HANDLE, &moved),
        Some(Command::MoveHandle { handle: HANDLE, delta: DVec3::new(0.1, 0.0, -0.2) })
    );
    let turned = GizmoResult::Rotation { axis: v(0.0, 0.0, 1.0), delta: 0.25, total: 1.0, is_view_axis: false };
    assert_eq!(
        command_from_result(HANDLE, &turned),
        Some(Command::RotateHandle { handle: HANDLE, axis: DVec3::Z, angle: 0.25 })
    );
    let still = GizmoResult::Translation { delta: v(0.0, 0.0, 0.0), total: v(1.0, 0.0, 0.0) };
    assert_eq!(command_from_result(HANDLE, &still), None);
    let no_turn = GizmoResult::Rotation { axis: v(1.0, 0.0, 0.0), delta: 0.0, total: 0.0, is_view_axis: false };
    assert_eq!(command_from_result(HANDLE, &no_turn), None);
    let scaled = GizmoResult::Scale { total: v(2.0, 2.0, 2.0) };
    assert_eq!(command_from_result(HANDLE, &scaled), None);

    // The crate's own convention: its rotation results turn a transform by
    // `DQuat::from_axis_angle(axis, delta)`, right-handed like `RotateHandle`.
    let mut targets = vec![DVec3::new(1.0, 0.0, 0.0), DVec3::new(-1.0, 0.0, 0.0)];
    apply_to_targets(HANDLE, &mut targets, &[command_from_result(HANDLE, &turned).unwrap()]);
    assert!((targets[0] - DVec3::new(0.25f64.cos(), 0.25f64.sin(), 0.0)).length() < 1e-12);
    // Other handles are left alone.
    apply_to_targets(GroupKey(1), &mut targets, &[Command::MoveHandle { handle: HANDLE, delta: DVec3::ONE }]);
    assert!((targets[0] - DVec3::new(0.25f64.cos(), 0.25f64.sin(), 0.0)).length() < 1e-12);
}

/// A flat (n+1)×(n+1) grid in the XY plane.
fn grid(n: u32) -> shapeup_core::mesh::Mesh {
    let mut positions = Vec::new();
    for y in 0..=n {
        for x in 0..=n {
            positions.push(DVec3::new(f64::from(x) / f64::from(n), f64::from(y) / f64::from(n), 0.0));
        }
    }
    let mut triangles = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let v = y * (n + 1) + x;
            triangles.push([v, v + 1, v + n + 2]);
            triangles.push([v, v + n + 2, v + n + 1]);
        }
    }
    shapeup_core::mesh::Mesh::new(positions, triangles).unwrap()
}

/// What the app does with a gizmo frame.
fn apply(doc: &mut Document, out: GizmoOutput) {
    if out.drag_started {
        doc.begin_drag();
    }
    for command in out.commands {
        doc.apply(command).unwrap();
    }
    if out.drag_stopped {
        doc.end_drag();
    }
}

#[test]
fn a_document_takes_gizmo_drags_as_single_undo_steps() {
    let mut doc = Document::new(grid(6), ShapeModel::EdgeSprings).unwrap();
    let corner: Vec<u32> = vec![40, 41, 47, 48];
    doc.apply(Command::Select { vertices: corner, mode: SelectMode::Replace }).unwrap();
    doc.apply(Command::FixSelection).unwrap();
    let handle = doc.handles().last().unwrap().key;
    let targets = |doc: &Document| doc.group(handle).unwrap().targets();
    let start = targets(&doc);
    let center = doc.group(handle).unwrap().target_centroid().unwrap();

    let mut c = OrbitCamera::with_angles(0.5, 0.25);
    c.frame(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0));
    let wpp = world_per_px(&c, center);
    let gt = GizmoTarget { handle, center, scale_hint: 2f64.sqrt() };
    let mut g = GizmoController::new();
    let run = |doc: &mut Document, g: &mut GizmoController, path: &[Vec2]| {
        let center = doc.group(handle).unwrap().target_centroid().unwrap();
        let gt = GizmoTarget { center, ..gt };
        let at = |p: Vec2| PointerState { pos: Some(p), ..PointerState::default() };
        apply(doc, g.update(&c, VIEWPORT, 1.0, gt, at(path[0])));
        apply(doc, g.update(&c, VIEWPORT, 1.0, gt, PointerState { pressed: true, down: true, ..at(path[0]) }));
        for &p in &path[1..] {
            apply(doc, g.update(&c, VIEWPORT, 1.0, gt, PointerState { down: true, ..at(p) }));
        }
        apply(doc, g.update(&c, VIEWPORT, 1.0, gt, at(*path.last().unwrap())));
    };

    // Along x: only the targets' x changes, by the same amount for all.
    let grabbed = center + 45.0 * wpp * DVec3::X;
    let px = |p: DVec3| pixel(&c, p);
    run(&mut doc, &mut g, &path(px(grabbed), px(grabbed + 0.2 * DVec3::X), 6, 4.0));
    let moved = targets(&doc);
    for (a, b) in moved.iter().zip(&start) {
        let d = *a - *b;
        assert!((d - 0.2 * DVec3::X).length() < 1e-3, "{d}");
        assert!(d.y == 0.0 && d.z == 0.0, "{d}");
        assert!((d - (moved[0] - start[0])).length() < 1e-15);
    }

    // About z, there and back: the targets come back; about z and kept: distances to the
    // centroid are kept.
    let moved_center = doc.group(handle).unwrap().target_centroid().unwrap();
    let ring = pixel(&c, ring_point(&c, moved_center, DVec3::Z));
    let centre_px = px(moved_center);
    let mut there_and_back = arc(ring, centre_px, 0.6, 6);
    there_and_back.extend(arc(*there_and_back.last().unwrap(), centre_px, -0.6, 6).into_iter().skip(1));
    run(&mut doc, &mut g, &there_and_back);
    for (a, b) in targets(&doc).iter().zip(&moved) {
        assert!((*a - *b).length() < 1e-6, "{a} != {b}");
    }
    run(&mut doc, &mut g, &arc(ring, centre_px, 0.6, 6));
    let turned = targets(&doc);
    let turned_center = doc.group(handle).unwrap().target_centroid().unwrap();
    assert!((turned_center - moved_center).length() < 1e-12);
    for (a, b) in turned.iter().zip(&moved) {
        assert!(((*a - turned_center).length() - (*b - moved_center).length()).abs() < 1e-12);
        assert!((a.z - b.z).abs() < 1e-12, "a turn about z keeps z");
    }
    assert!((turned[0] - moved[0]).length() > 1e-3, "it turned");

    // Each drag is one undo step.
    assert!(doc.undo());
    for (a, b) in targets(&doc).iter().zip(&moved) {
        assert!((*a - *b).length() < 1e-6);
    }
    assert!(doc.undo(), "the there-and-back drag");
    assert!(doc.undo(), "the move along x");
    assert_eq!(targets(&doc), start);
}

#[test]
fn the_gizmo_moves_and_turns_a_collider_in_single_undo_steps() {
    use shapeup_app::collider::center as collider_center;
    use shapeup_app::gizmo::{COLLIDER_GIZMO, collider_command};
    use shapeup_core::contact::ShapeSpec;
    let mut doc = Document::new(grid(6), ShapeModel::EdgeSprings).unwrap();
    doc.apply(Command::AddCollider(doc.default_collider("box").unwrap())).unwrap();
    let start = doc.colliders()[0].clone();
    let center = |doc: &Document| collider_center(&doc.colliders()[0]);
    let mut c = OrbitCamera::with_angles(0.5, 0.25);
    c.frame(Vec3::new(0.0, -0.5, 0.0), Vec3::new(1.0, 1.0, 0.0));
    let mut g = GizmoController::new();
    // What the app does: the gizmo on the collider's centre, its commands the collider's.
    let run = |doc: &mut Document, g: &mut GizmoController, path: &[Vec2]| {
        let gt = GizmoTarget { handle: COLLIDER_GIZMO, center: center(doc), scale_hint: 2f64.sqrt() };
        let mut frame = |doc: &mut Document, pointer: PointerState| {
            let mut out = g.update(&c, VIEWPORT, 1.0, gt, pointer);
            out.commands = out.commands.into_iter().map(|cmd| collider_command(0, cmd)).collect();
            apply(doc, out);
        };
        let at = |p: Vec2| PointerState { pos: Some(p), ..PointerState::default() };
        frame(doc, at(path[0]));
        frame(doc, PointerState { pressed: true, down: true, ..at(path[0]) });
        for &p in &path[1..] {
            frame(doc, PointerState { down: true, ..at(p) });
        }
        frame(doc, at(*path.last().unwrap()));
    };

    let from = center(&doc);
    let grabbed = from + 45.0 * world_per_px(&c, from) * DVec3::X;
    run(&mut doc, &mut g, &path(pixel(&c, grabbed), pixel(&c, grabbed + 0.2 * DVec3::X), 6, 4.0));
    let moved = center(&doc) - from;
    assert!((moved - 0.2 * DVec3::X).length() < 1e-3 && moved.y == 0.0 && moved.z == 0.0, "{moved}");

    let ring = pixel(&c, ring_point(&c, center(&doc), DVec3::Y));
    let turn = arc(ring, pixel(&c, center(&doc)), 0.6, 6);
    run(&mut doc, &mut g, &turn);
    let ShapeSpec::Box { rotate: Some(r), .. } = doc.colliders()[0].shape else { panic!("{:?}", doc.colliders()[0]) };
    assert!(r.axis[1].abs() > 0.999 && r.angle_deg.abs() > 5.0, "turned about y: {r:?}");
    assert!((center(&doc) - from - moved).length() < 1e-9, "about its centre");

    assert!(doc.undo() && doc.undo(), "two drags, two steps");
    assert_eq!(doc.colliders()[0], start);
}

/// The egui adapter in a headless egui (no rendering): pointer events in the viewport's frame
/// reach the model, the viewport holds back its own drags while the gizmo claims the pointer,
/// and windows over the viewport shield it.
#[cfg(feature = "gui")]
mod gui {
    use super::*;
    use eframe::egui;
    use egui_kittest::Harness;
    use shapeup_app::gui::gizmo::HandleGizmo;

    #[derive(Default)]
    struct State {
        gizmo: HandleGizmo,
        rect: Option<egui::Rect>,
        commands: Vec<Command>,
        started: usize,
        stopped: usize,
        /// Drags the viewport itself started (orbit, alt-drag…).
        viewport_drags: usize,
        /// A window over the viewport at this point.
        cover: Option<egui::Pos2>,
    }

    /// A viewport below a 50-point gap, wired as `EditorApp::viewport` should be.
    fn viewport_harness() -> Harness<'static, State> {
        let mut harness = Harness::builder().with_size(egui::vec2(900.0, 700.0)).build_ui_state(
            |ui, s: &mut State| {
                ui.add_space(50.0);
                let size = egui::vec2(VIEWPORT.x, VIEWPORT.y);
                let (rect, response) = ui.allocate_exact_size(size, egui::Sense::click_and_drag());
                s.rect = Some(rect);
                if response.drag_started() && !s.gizmo.claims_pointer() {
                    s.viewport_drags += 1;
                }
                let out = s.gizmo.show(ui, rect, &camera(), HANDLE, CENTER, 2.0 * 3f64.sqrt());
                s.started += usize::from(out.drag_started);
                s.stopped += usize::from(out.drag_stopped);
                s.commands.extend(out.commands);
                if let Some(at) = s.cover {
                    let area = egui::Area::new(egui::Id::unique("cover")).fixed_pos(at - egui::vec2(30.0, 30.0));
                    area.show(ui.ctx(), |ui| {
                        ui.allocate_exact_size(egui::vec2(60.0, 60.0), egui::Sense::click());
                    });
                }
            },
            State::default(),
        );
        harness.step();
        harness
    }

    fn at(harness: &Harness<'_, State>, p: Vec2) -> egui::Pos2 {
        harness.state().rect.unwrap().min + egui::vec2(p.x, p.y)
    }

    /// Hovers, presses, moves along `path` and releases, holding `modifiers` throughout.
    fn pointer_drag(harness: &mut Harness<'_, State>, path: &[Vec2], modifiers: egui::Modifiers) {
        harness.event(egui::Event::ModifiersChanged(modifiers));
        let start = at(harness, path[0]);
        harness.hover_at(start);
        harness.step();
        let button =
            |pos, pressed| egui::Event::PointerButton { pos, button: egui::PointerButton::Primary, pressed, modifiers };
        harness.event(button(start, true));
        harness.step();
        for &p in &path[1..] {
            let pos = at(harness, p);
            harness.hover_at(pos);
            harness.step();
        }
        let end = at(harness, *path.last().unwrap());
        harness.event(button(end, false));
        harness.step();
        harness.event(egui::Event::ModifiersChanged(egui::Modifiers::NONE));
        harness.step();
    }

    #[test]
    fn a_drag_on_an_arrow_moves_the_handle_and_not_the_camera() {
        let mut harness = viewport_harness();
        assert_ne!(harness.state().rect.unwrap().min, egui::Pos2::ZERO, "the viewport is offset in the window");
        let meshes = harness.output().shapes.iter().filter(|s| matches!(s.shape, egui::Shape::Mesh(_))).count();
        assert_eq!(meshes, 1, "the gizmo paints one mesh");
        let c = camera();
        let wpp = world_per_px(&c, CENTER);
        let grabbed = CENTER + 45.0 * wpp * DVec3::X;
        let wanted = 30.0 * wpp * DVec3::X;
        let drag_path = path(pixel(&c, grabbed), pixel(&c, grabbed + wanted), 6, 3.0);
        pointer_drag(&mut harness, &drag_path, egui::Modifiers::NONE);
        let s = harness.state();
        assert_eq!((s.started, s.stopped, s.viewport_drags), (1, 1, 0));
        let moved = total_move(&s.commands);
        assert!((moved - wanted).length() < 1e-3 * wanted.length(), "moved {moved}, wanted {wanted}");
        assert!(!s.gizmo.is_dragging());
    }

    #[test]
    fn alt_drags_and_covered_parts_are_the_viewports() {
        let c = camera();
        let wpp = world_per_px(&c, CENTER);
        let on_arrow = pixel(&c, CENTER + 45.0 * wpp * DVec3::X);
        let drag_path = path(on_arrow, on_arrow + Vec2::new(60.0, 10.0), 4, 0.0);

        let mut harness = viewport_harness();
        pointer_drag(&mut harness, &drag_path, egui::Modifiers::ALT);
        let s = harness.state();
        assert_eq!((s.started, s.stopped, s.viewport_drags), (0, 0, 1));
        assert!(s.commands.is_empty());

        let mut harness = viewport_harness();
        let cover = at(&harness, on_arrow);
        harness.state_mut().cover = Some(cover);
        harness.step();
        pointer_drag(&mut harness, &drag_path, egui::Modifiers::NONE);
        let s = harness.state();
        assert_eq!((s.started, s.stopped), (0, 0));
        assert!(s.commands.is_empty());
    }
}
