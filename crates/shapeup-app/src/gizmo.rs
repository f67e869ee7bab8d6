//! The handle gizmo's model: translate arrows (x, y, z), plane squares (yz, zx, xy), rotation
//! rings (x, y, z) and the two view circles (inner: move in the view plane, outer: turn about the
//! view direction), drawn at a handle's centroid. Dragging a part turns into incremental
//! [`Command::MoveHandle`] / [`Command::RotateHandle`] commands, one per frame.
//!
//! Picking, the drag math and the tessellation come from the framework-agnostic
//! [`transform_gizmo`] crate (its egui adapter, `transform-gizmo-egui`, does not support the
//! egui this editor pins). This module has no GUI dependency: [`GizmoController::update`] takes
//! the camera, the viewport size and a [`PointerState`] in viewport pixels (top-left origin, as
//! [`OrbitCamera`] uses), so the whole widget logic runs in tests without a window;
//! `gui::gizmo` only reads egui's pointer and paints [`GizmoController::draw_data`].
//!
//! The gizmo's parts are in world axes (global orientation): an arrow moves only along its
//! axis, a square only in its plane, a ring turns about its axis through the handle's centroid,
//! which is exactly what [`Command::RotateHandle`] does. On a collider the same drags move and
//! turn it about its centre ([`COLLIDER_GIZMO`], [`collider_command`]).

use crate::camera::OrbitCamera;
use crate::command::Command;
use crate::document::GroupKey;
use glam::{DMat4, DVec3, Vec2};
use transform_gizmo::math::Transform;
use transform_gizmo::mint;
use transform_gizmo::{EnumSet, Gizmo, GizmoConfig, GizmoInteraction, GizmoMode, GizmoOrientation, GizmoResult};

pub use transform_gizmo::GizmoDrawData;

/// Rotation snapping step (15°), while snapping.
pub const SNAP_ANGLE: f64 = std::f64::consts::PI / 12.0;

/// Which parts the gizmo shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GizmoTool {
    /// Arrows, squares, rings and both view circles at once.
    #[default]
    All,
    /// Arrows, squares and the inner view circle.
    Translate,
    /// Rings and the outer view circle.
    Rotate,
}

impl GizmoTool {
    /// Every tool, in menu order.
    pub const ALL: [GizmoTool; 3] = [GizmoTool::All, GizmoTool::Translate, GizmoTool::Rotate];

    /// Short name for a toggle.
    pub fn label(self) -> &'static str {
        match self {
            GizmoTool::All => "move + rotate",
            GizmoTool::Translate => "move",
            GizmoTool::Rotate => "rotate",
        }
    }

    /// The crate's modes for this tool (never scaling: handles have no scale command).
    pub fn modes(self) -> EnumSet<GizmoMode> {
        match self {
            GizmoTool::All => GizmoMode::all_translate() | GizmoMode::all_rotate(),
            GizmoTool::Translate => GizmoMode::all_translate(),
            GizmoTool::Rotate => GizmoMode::all_rotate(),
        }
    }
}

/// The pointer this frame, in viewport pixels (top-left origin).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PointerState {
    /// Where the pointer is; `None` when it is not over the viewport (outside it, or over a
    /// window covering it). During a gizmo drag, give the last known position even outside.
    pub pos: Option<Vec2>,
    /// The primary button went down this frame.
    pub pressed: bool,
    /// The primary button is down.
    pub down: bool,
    /// A modifier (alt, ctrl/cmd; not shift, which snaps) is held: a press then belongs to the viewport's own
    /// gestures (alt-drags, box selection, pan), not to the gizmo.
    pub modifiers: bool,
    /// Snap while dragging (translations to [`snap_step`] of the scale hint, rotations to
    /// [`SNAP_ANGLE`]).
    pub snap: bool,
}

/// What the gizmo is drawn on this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GizmoTarget {
    /// The handle the commands move.
    pub handle: GroupKey,
    /// Its targets' centroid (input frame), where the gizmo sits and rotations turn about.
    pub center: DVec3,
    /// A length typical of the scene, e.g. the mesh's bounding-box diagonal: snapping moves by
    /// [`snap_step`] of it. The gizmo's size itself is in pixels.
    pub scale_hint: f64,
}

/// One frame of the gizmo.
#[derive(Debug, Clone, Default, PartialEq)]
#[must_use]
pub struct GizmoOutput {
    /// Incremental [`Command::MoveHandle`] / [`Command::RotateHandle`] for this frame.
    pub commands: Vec<Command>,
    /// The pointer is on a part the gizmo would take a press on, or a gizmo drag is in progress:
    /// the viewport must not start its own gesture (orbit, pan, click…).
    pub hovered: bool,
    /// A gizmo drag started this frame: call `Document::begin_drag` (one undo step). No
    /// command comes with it.
    pub drag_started: bool,
    /// The gizmo drag ended this frame: call `Document::end_drag` (and solve once more). No
    /// command comes with it, so ending the drag before applying this frame's commands is safe.
    pub drag_stopped: bool,
}

/// The command a gizmo result gives for `handle`: a translation moves the handle by the
/// result's latest delta, a rotation turns it by the latest angle about the result's axis
/// (right-handed, through the handle's centroid). `None` for a zero change and for the modes
/// the editor does not use (scale, arcball).
pub fn command_from_result(handle: GroupKey, result: &GizmoResult) -> Option<Command> {
    match *result {
        GizmoResult::Translation { delta, .. } => {
            let delta = DVec3::from_array([delta.x, delta.y, delta.z]);
            (delta != DVec3::ZERO && delta.is_finite()).then_some(Command::MoveHandle { handle, delta })
        }
        GizmoResult::Rotation { axis, delta, .. } => {
            let axis = DVec3::from_array([axis.x, axis.y, axis.z]);
            (delta != 0.0 && delta.is_finite() && axis.length_squared() > 0.0 && axis.is_finite())
                .then_some(Command::RotateHandle { handle, axis, angle: delta })
        }
        GizmoResult::Scale { .. } | GizmoResult::Arcball { .. } => None,
    }
}

/// The key the gizmo is given when it sits on a collider: no group has it (group keys count
/// up from 0), and [`collider_command`] turns the commands for it into the collider's.
pub const COLLIDER_GIZMO: GroupKey = GroupKey(u32::MAX);

/// A gizmo command as the command for collider `index`: [`Command::MoveHandle`] moves it
/// ([`Command::MoveCollider`]), [`Command::RotateHandle`] turns it about its centre
/// ([`Command::RotateCollider`]), as they would a handle; other commands stay as they are.
pub fn collider_command(index: usize, command: Command) -> Command {
    match command {
        Command::MoveHandle { delta, .. } => Command::MoveCollider { index, delta },
        Command::RotateHandle { axis, angle, .. } => Command::RotateCollider { index, axis, angle },
        other => other,
    }
}

/// Snapping step for translations: the power of ten at most a tenth of `scale_hint` (0.1 for a
/// scene 1 to 10 units across); 0.1 when the hint is not a positive finite number.
pub fn snap_step(scale_hint: f64) -> f64 {
    if scale_hint.is_finite() && scale_hint > 0.0 { 10f64.powf((scale_hint / 10.0).log10().floor()) } else { 0.1 }
}

/// Where a handle's targets go under `commands` (a model of `Document::apply` for the gizmo's
/// commands, for checks and previews): translations add, rotations turn about the targets'
/// centroid. Commands for other handles and other commands are ignored.
pub fn apply_to_targets(handle: GroupKey, targets: &mut [DVec3], commands: &[Command]) {
    for command in commands {
        match *command {
            Command::MoveHandle { handle: h, delta } if h == handle => targets.iter_mut().for_each(|t| *t += delta),
            Command::RotateHandle { handle: h, axis, angle } if h == handle => {
                let Some(axis) = axis.try_normalize() else { continue };
                if targets.is_empty() {
                    continue;
                }
                let center = targets.iter().copied().sum::<DVec3>() / targets.len() as f64;
                let rotation = glam::DQuat::from_axis_angle(axis, angle);
                targets.iter_mut().for_each(|t| *t = center + rotation * (*t - center));
            }
            _ => {}
        }
    }
}

/// A column-major matrix of this crate's glam as the gizmo crate's row-major mint matrix.
fn to_mint(m: DMat4) -> mint::RowMatrix4<f64> {
    let c = m.to_cols_array_2d();
    let row = |i: usize| mint::Vector4 { x: c[0][i], y: c[1][i], z: c[2][i], w: c[3][i] };
    mint::RowMatrix4 { x: row(0), y: row(1), z: row(2), w: row(3) }
}

/// The gizmo's state across frames: the crate's gizmo (picking, the part being dragged) and
/// the handle a drag started on.
#[derive(Debug, Clone)]
pub struct GizmoController {
    gizmo: Gizmo,
    tool: GizmoTool,
    /// The handle being dragged, from the press to the release.
    dragging: Option<GroupKey>,
    /// Last frame's [`GizmoOutput::hovered`].
    hovered: bool,
    /// The last pointer position given (kept for frames without one during a drag).
    last_pos: Option<Vec2>,
    /// Whether the last update drew anything.
    visible: bool,
}

impl Default for GizmoController {
    fn default() -> Self {
        GizmoController {
            gizmo: Gizmo::new(GizmoConfig { modes: GizmoTool::All.modes(), ..GizmoConfig::default() }),
            tool: GizmoTool::All,
            dragging: None,
            hovered: false,
            last_pos: None,
            visible: false,
        }
    }
}

impl GizmoController {
    /// A gizmo showing every part.
    pub fn new() -> Self {
        Self::default()
    }

    /// The parts shown.
    pub fn tool(&self) -> GizmoTool {
        self.tool
    }

    /// Shows other parts from the next update (a drag in progress keeps its part until release).
    pub fn set_tool(&mut self, tool: GizmoTool) {
        self.tool = tool;
    }

    /// Whether a gizmo drag is in progress (from the press on a part to the release).
    pub fn is_dragging(&self) -> bool {
        self.dragging.is_some()
    }

    /// Whether the gizmo wants the pointer, as of the last update: it hovered a part or a drag
    /// is in progress. For viewport code that runs before this frame's update.
    pub fn claims_pointer(&self) -> bool {
        self.hovered || self.dragging.is_some()
    }

    /// Forgets a drag in progress without a release (e.g. the handle was deleted or the gizmo
    /// is no longer shown): returns whether there was one, in which case the caller ends the
    /// document's drag itself.
    pub fn cancel(&mut self) -> bool {
        let was = self.dragging.take().is_some();
        if was {
            // Let the crate release its active part.
            let released = GizmoInteraction { cursor_pos: self.cursor(), ..GizmoInteraction::default() };
            let _ = self.gizmo.update(released, &[]);
        }
        self.hovered = false;
        was
    }

    fn cursor(&self) -> (f32, f32) {
        self.last_pos.map_or((f32::NAN, f32::NAN), |p| (p.x, p.y))
    }

    /// One frame: configures the gizmo for `camera` and the viewport (its size in pixels, and
    /// the display's pixels per point for tessellation), lets it react to the pointer and
    /// returns the commands of this frame's drag motion. A press (without modifiers) on a part
    /// starts a drag, the release ends it; commands go to the handle the drag started on.
    pub fn update(
        &mut self,
        camera: &OrbitCamera,
        viewport: Vec2,
        pixels_per_point: f32,
        target: GizmoTarget,
        pointer: PointerState,
    ) -> GizmoOutput {
        let mut output = GizmoOutput::default();
        let viewport = viewport.max(Vec2::ONE);
        if pointer.pos.is_some() {
            self.last_pos = pointer.pos;
        }
        let in_front = target.center.is_finite() && camera.project(target.center.as_vec3(), viewport).is_some();
        if !in_front && self.dragging.is_none() {
            self.hovered = false;
            self.visible = false;
            return output;
        }
        let aspect = viewport.x / viewport.y;
        let config = GizmoConfig {
            view_matrix: to_mint(camera.view().as_dmat4()),
            projection_matrix: to_mint(camera.projection(aspect).as_dmat4()),
            viewport: transform_gizmo::math::Rect::from_min_max(
                transform_gizmo::math::Pos2::ZERO,
                transform_gizmo::math::Pos2::new(viewport.x, viewport.y),
            ),
            // A drag keeps its part even if the tool changes meanwhile.
            modes: if self.dragging.is_some() { self.gizmo.config().modes } else { self.tool.modes() },
            orientation: GizmoOrientation::Global,
            snapping: pointer.snap && self.dragging.is_some(),
            snap_angle: SNAP_ANGLE as f32,
            snap_distance: snap_step(target.scale_hint) as f32,
            pixels_per_point: pixels_per_point.max(0.1),
            ..*self.gizmo.config()
        };
        self.gizmo.update_config(config);

        let ours = self.dragging.is_some();
        // Another gesture holds the button (it was pressed elsewhere): no highlighting.
        let busy = pointer.down && !pointer.pressed && !ours;
        let interaction = GizmoInteraction {
            cursor_pos: self.cursor(),
            hovered: pointer.pos.is_some() && (ours || (!pointer.modifiers && !busy)),
            drag_started: pointer.pressed && !pointer.modifiers && !ours,
            dragging: pointer.down,
        };
        let transform = Transform {
            translation: mint::Vector3 { x: target.center.x, y: target.center.y, z: target.center.z },
            ..Transform::default()
        };
        let result = self.gizmo.update(interaction, &[transform]);

        if !ours && interaction.drag_started && pointer.down && self.gizmo.is_focused() {
            self.dragging = Some(target.handle);
            output.drag_started = true;
        }
        if let Some(handle) = self.dragging {
            // The press frame's result only snaps the picked point onto the part (the cursor
            // has not moved): a click must not move the handle. Rounding noise of frames
            // without motion is dropped too.
            let min_move =
                1e-6 * f64::from(camera.drag_in_view_plane(Vec2::X, target.center.as_vec3(), viewport).length());
            if let Some((result, _)) = result
                && !output.drag_started
            {
                output.commands.extend(command_from_result(handle, &result).filter(|c| match c {
                    Command::MoveHandle { delta, .. } => delta.length() > min_move,
                    Command::RotateHandle { angle, .. } => angle.abs() > 1e-9,
                    _ => true,
                }));
            }
            if !pointer.down {
                self.dragging = None;
                output.drag_stopped = true;
            }
        }
        output.hovered = self.dragging.is_some() || (interaction.hovered && self.gizmo.is_focused());
        self.hovered = output.hovered;
        self.visible = true;
        output
    }

    /// The gizmo as of the last update: triangles in viewport pixels with linear, premultiplied
    /// RGBA colours (empty when the handle's centroid is behind the camera).
    pub fn draw_data(&self) -> GizmoDrawData {
        if self.visible { self.gizmo.draw() } else { GizmoDrawData::default() }
    }
}
