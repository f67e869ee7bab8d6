//! The Contact section: self-collision, thickness and self friction; one row per collider
//! (its type, the gizmo toggle, remove) with the numbers of the selected one; buttons that
//! add a primitive just below the shape. A mesh collider comes from a file: the app's
//! "Mesh…" row under this section (a native dialog or a typed path).

use super::PanelOutput;
use crate::collider::PRIMITIVES;
use crate::command::Command;
use crate::document::Document;
use eframe::egui;
use shapeup_core::contact::{ColliderSpec, ContactSettings, DEFAULT_THICKNESS_FRACTION, ShapeSpec};
use shapeup_core::motion::{Rotate, Spin};

/// The section's own state, which the viewport reads too (the gizmo sits on the selected
/// collider).
#[derive(Debug, Default)]
pub struct ContactPanel {
    /// The collider whose numbers are shown and the gizmo sits on, if any.
    pub selected: Option<usize>,
}

/// Draws the section for `document` and returns the commands asked for (one undo step per
/// number drag).
///
/// Checkbox "Self-collision", "auto thickness", fields "thickness", "self friction"; buttons
/// "Add sphere", "Add box", "Add plane", "Add capsule"; per collider a selectable
/// "N: TYPE" (the gizmo and its numbers) and "remove".
pub fn contact_panel(ui: &mut egui::Ui, document: &Document, state: &mut ContactPanel) -> PanelOutput {
    let mut out = PanelOutput::default();
    let (lo, hi) = document.rest_mesh().bounding_box();
    // Drag speed of lengths: a pixel moves a 500th of the mesh.
    let speed = ((hi - lo).length() / 500.0).max(1e-6);
    settings_rows(ui, document, speed, &mut out);
    ui.horizontal_wrapped(|ui| {
        for kind in PRIMITIVES {
            if ui.button(format!("Add {kind}")).on_hover_text(format!("a {kind} just below the shape")).clicked()
                && let Some(spec) = document.default_collider(kind)
            {
                out.commands.push(Command::AddCollider(spec));
                // The new one is appended: it gets the gizmo.
                state.selected = Some(document.colliders().len());
            }
        }
    });
    if document.colliders().is_empty() {
        ui.label("no colliders");
    }
    for (i, spec) in document.colliders().iter().enumerate() {
        ui.horizontal(|ui| {
            let selected = state.selected == Some(i);
            let hint = "show its numbers and put the gizmo on it";
            if ui.selectable_label(selected, format!("{i}: {}", spec.kind())).on_hover_text(hint).clicked() {
                state.selected = if selected { None } else { Some(i) };
            }
            if ui.small_button("remove").clicked() {
                out.commands.push(Command::RemoveCollider(i));
                state.selected = None;
            }
        });
        if state.selected == Some(i) {
            let mut edited = spec.clone();
            if collider_rows(ui, &mut edited, speed, &mut out) && edited != *spec {
                out.commands.push(Command::EditCollider { index: i, spec: edited });
            }
        }
    }
    if state.selected.is_some_and(|i| i > document.colliders().len()) {
        state.selected = None;
    }
    out
}

/// Self-collision, thickness (automatic or a number) and self friction.
fn settings_rows(ui: &mut egui::Ui, document: &Document, speed: f64, out: &mut PanelOutput) {
    let before = document.contact_settings();
    let mut s: ContactSettings = before;
    ui.checkbox(&mut s.self_collision, "Self-collision").on_hover_text("the surface collides with itself");
    ui.horizontal(|ui| {
        let mut auto = s.thickness.is_none();
        ui.checkbox(&mut auto, "auto thickness").on_hover_text(format!(
            "{DEFAULT_THICKNESS_FRACTION} × the mean edge length: the distance kept from colliders and between layers"
        ));
        match (auto, s.thickness) {
            (true, _) => s.thickness = None,
            (false, None) => s.thickness = Some(default_thickness(document)),
            (false, Some(mut t)) => {
                let r =
                    ui.add(egui::DragValue::new(&mut t).speed(0.1 * speed).range(0.0..=f64::MAX).prefix("thickness "));
                out.track_drag(&r);
                s.thickness = Some(t);
            }
        }
    });
    let r = ui
        .add(egui::DragValue::new(&mut s.friction).speed(0.01).range(0.0..=10.0).prefix("self friction "))
        .on_hover_text("Coulomb μ between parts of the surface");
    out.track_drag(&r);
    if s != before {
        out.commands.push(Command::SetContact(s));
    }
}

/// The automatic thickness in the mesh's units (what `auto` stands for).
fn default_thickness(document: &Document) -> f64 {
    let rest = &document.state().rest;
    DEFAULT_THICKNESS_FRACTION * shapeup_core::geometry::mean_edge_length(&rest.geometry) / rest.frame.scale
}

/// A labelled row of three numbers; whether one changed.
fn vector(ui: &mut egui::Ui, label: &str, v: &mut [f64; 3], speed: f64, out: &mut PanelOutput) -> bool {
    ui.horizontal(|ui| {
        let label = ui.label(label);
        let mut changed = false;
        for x in v.iter_mut() {
            let r = ui.add(egui::DragValue::new(x).speed(speed).max_decimals(4)).labelled_by(label.id);
            out.track_drag(&r);
            changed |= r.changed();
        }
        changed
    })
    .inner
}

/// A labelled number ≥ `min`; whether it changed.
fn number(ui: &mut egui::Ui, label: &str, x: &mut f64, speed: f64, min: f64, out: &mut PanelOutput) -> bool {
    let r = ui.add(egui::DragValue::new(x).speed(speed).range(min..=f64::MAX).max_decimals(4).prefix(label));
    out.track_drag(&r);
    r.changed()
}

/// The numbers of one collider; whether one changed.
fn collider_rows(ui: &mut egui::Ui, spec: &mut ColliderSpec, speed: f64, out: &mut PanelOutput) -> bool {
    let mut changed = false;
    // Radii stay above 0, as the scene requires.
    let tiny = 1e-6 * speed;
    match &mut spec.shape {
        ShapeSpec::Sphere { center, radius } => {
            changed |= vector(ui, "centre", center, speed, out);
            changed |= number(ui, "radius ", radius, speed, tiny, out);
        }
        ShapeSpec::Capsule { a, b, radius } => {
            changed |= vector(ui, "a", a, speed, out);
            changed |= vector(ui, "b", b, speed, out);
            changed |= number(ui, "radius ", radius, speed, tiny, out);
        }
        ShapeSpec::Box { min, max, rotate } => {
            changed |= vector(ui, "min", min, speed, out);
            changed |= vector(ui, "max", max, speed, out);
            changed |= rotation_rows(ui, rotate, out);
        }
        ShapeSpec::Plane { point, normal } => {
            changed |= vector(ui, "point", point, speed, out);
            changed |= vector(ui, "normal", normal, 0.01, out);
        }
        ShapeSpec::Mesh { path, closed, thickness, translate, rotate } => {
            ui.label(path.display().to_string());
            changed |= vector(ui, "translate", translate, speed, out);
            changed |= rotation_rows(ui, rotate, out);
            ui.horizontal(|ui| {
                ui.label("closed:");
                for (label, value) in [("auto", None), ("yes", Some(true)), ("no (one-sided)", Some(false))] {
                    changed |= ui.radio_value(closed, value, label).changed();
                }
            });
            let mut own = thickness.is_some();
            if ui.checkbox(&mut own, "own thickness behind an open mesh").changed() {
                *thickness = own.then_some(10.0 * speed);
                changed = true;
            }
            if let Some(t) = thickness {
                changed |= number(ui, "thickness ", t, 0.1 * speed, 0.0, out);
            }
        }
    }
    changed |= number(ui, "friction ", &mut spec.friction, 0.01, 0.0, out);
    changed |= vector(ui, "velocity", &mut spec.velocity, speed, out);
    // A constant spin (dynamic mode) about the shape's centre unless the scene gave one.
    let mut spins = spec.spin.is_some();
    if ui.checkbox(&mut spins, "spins").on_hover_text("turns at a constant rate while simulating").changed() {
        spec.spin = spins.then_some(Spin { axis: [0.0, 1.0, 0.0], deg_per_s: 30.0, center: None });
        changed = true;
    }
    if let Some(spin) = &mut spec.spin {
        changed |= vector(ui, "spin axis", &mut spin.axis, 0.01, out);
        changed |= number(ui, "spin (°/s) ", &mut spin.deg_per_s, 1.0, f64::MIN, out);
    }
    changed
}

/// The turn axis and angle of an optional rotation (none at 0°); whether one changed.
fn rotation_rows(ui: &mut egui::Ui, rotate: &mut Option<Rotate>, out: &mut PanelOutput) -> bool {
    let mut r = rotate.unwrap_or(Rotate { axis: [0.0, 1.0, 0.0], angle_deg: 0.0, center: None });
    let turned =
        vector(ui, "turn axis", &mut r.axis, 0.01, out) | number(ui, "turn (°) ", &mut r.angle_deg, 0.5, f64::MIN, out);
    if turned {
        *rotate = (r.angle_deg != 0.0).then_some(r);
    }
    turned
}
