//! The selection section: what is selected, face mode, fix / clear / boundary, "Add constraint
//! to selection" with each type's options as widgets, and the connected pieces.

use super::count;
use crate::command::{Command, SelectMode};
use crate::document::Document;
use eframe::egui;
use egui::Color32;
use serde_json::{Map, Value};
use shapeup_core::constraints::{ConstraintType, OptionKind, OptionSpec, registry};

/// The section's own state.
#[derive(Debug, Default)]
pub struct SelectionPanel {
    /// Face mode: clicks and box selections pick polygon faces instead of vertices.
    pub face_mode: bool,
    /// The next click on the mesh selects the connected piece under it.
    pub pick_piece: bool,
    /// The type "Add constraint to selection" will add, and the options set in its widgets.
    add_kind: Option<&'static str>,
    add_options: Map<String, Value>,
}

/// Draws the section for `document`; returns the commands asked for.
///
/// Buttons: "Fix selection", "Clear selection", "Select boundary", "Add constraint to
/// selection", "Pin free pieces"; toggles: "Face mode", "Select connected piece".
pub fn selection_panel(ui: &mut egui::Ui, document: &Document, state: &mut SelectionPanel) -> Vec<Command> {
    let mut commands = Vec::new();
    let faces = document.face_selection().iter().filter(|s| **s).count();
    ui.horizontal(|ui| {
        let vertices = count(document.num_selected(), "vertex", "vertices");
        ui.label(match faces {
            0 => format!("{vertices} selected"),
            _ => format!("{vertices}, {} selected", count(faces, "face", "faces")),
        });
        ui.toggle_value(&mut state.face_mode, "Face mode")
            .on_hover_text("clicks and Ctrl+drag boxes select polygon faces (for plane, circle, rectangle…)");
    });
    ui.horizontal_wrapped(|ui| {
        if ui.button("Fix selection").on_hover_text("a handle holding the selected vertices").clicked() {
            commands.push(Command::FixSelection);
        }
        if ui.button("Clear selection").clicked() {
            commands.push(Command::ClearSelection);
        }
        if ui.button("Select boundary").clicked() {
            commands.push(Command::SelectBoundary(SelectMode::Replace));
        }
    });
    add_constraint_row(ui, document, state, &mut commands);
    // Pieces: every connected piece needs a handle, or the system is singular.
    let pieces = document.pieces().count;
    let free = document.num_free_pieces();
    ui.horizontal_wrapped(|ui| {
        if pieces > 1 || free > 0 {
            let text = match (free, pieces) {
                (1, 1) => "the mesh has no handle".to_owned(),
                (1, _) => format!("1 of {pieces} pieces has no handle"),
                _ => format!("{free} of {pieces} pieces have no handle"),
            };
            if free > 0 && document.state().has_handles() {
                ui.colored_label(Color32::from_rgb(200, 90, 0), text)
                    .on_hover_text("a piece without a handle has no defined position: the solve fails");
            } else {
                ui.label(text);
            }
        }
        if ui
            .add_enabled(free > 0, egui::Button::new("Attach free pieces"))
            .on_hover_text(
                "each piece without a handle follows the nearest surface of the held pieces (an eye, nails, \
                 a belt move with the body)",
            )
            .clicked()
        {
            commands.push(Command::AttachFreePieces);
        }
        if ui
            .add_enabled(free > 0, egui::Button::new("Pin free pieces"))
            .on_hover_text("one soft handle (weight 0.01) on every piece without one, at rest")
            .clicked()
        {
            commands.push(Command::PinFreePieces);
        }
        ui.toggle_value(&mut state.pick_piece, "Select connected piece")
            .on_hover_text("while on, a click on a vertex selects its piece (shift adds); click again to stop");
    });
    commands
}

/// "Add constraint to selection": every registered type that fits the selection, its
/// options as widgets generated from its option descriptions, and the button.
fn add_constraint_row(ui: &mut egui::Ui, document: &Document, state: &mut SelectionPanel, commands: &mut Vec<Command>) {
    let fitting = document.fitting_types();
    // With nothing selected the same rows stay, disabled (the type last chosen, else the
    // first), so the panel does not jump as the selection empties or fills.
    let enabled = !fitting.is_empty();
    let shown = if enabled { fitting } else { registry().to_vec() };
    let Some(&first) = shown.first() else { return };
    let chosen = state.add_kind.and_then(|k| shown.iter().copied().find(|t| t.name() == k));
    let ty = chosen.unwrap_or(first);
    if chosen.is_none() {
        state.add_kind = Some(ty.name());
        state.add_options.clear();
    }
    ui.add_enabled_ui(enabled, |ui| add_constraint_widgets(ui, ty, &shown, state, commands))
        .response
        .on_disabled_hover_text("select vertices or faces to add a constraint");
}

/// The type's menu (of `types`), the button and the type's options.
fn add_constraint_widgets(
    ui: &mut egui::Ui,
    ty: &'static dyn ConstraintType,
    types: &[&'static dyn ConstraintType],
    state: &mut SelectionPanel,
    commands: &mut Vec<Command>,
) {
    ui.horizontal(|ui| {
        egui::ComboBox::from_id_salt("add constraint type")
            .selected_text(ty.name())
            .show_ui(ui, |ui| {
                for t in types {
                    if ui.selectable_label(t.name() == ty.name(), t.name()).on_hover_text(t.summary()).clicked()
                        && t.name() != ty.name()
                    {
                        state.add_kind = Some(t.name());
                        state.add_options.clear();
                    }
                }
            })
            .response
            .on_hover_text(ty.summary());
        if ui.button("Add constraint to selection").on_hover_text(ty.summary()).clicked() {
            commands.push(Command::AddConstraint { kind: ty.name().into(), options: state.add_options.clone() });
        }
    });
    for option in ty.options() {
        option_widget(ui, option, &mut state.add_options);
    }
}

/// The widget of one constraint option, generated from its description: a number field
/// within its range (with "rest" for a default taken from the rest shape), a checkbox, or
/// three number fields; the value lands in `options` under the option's key, and an option
/// left at its default is left out.
fn option_widget(ui: &mut egui::Ui, option: &OptionSpec, options: &mut Map<String, Value>) {
    ui.horizontal(|ui| {
        ui.label(option.key).on_hover_text(option.doc);
        match option.kind {
            OptionKind::Number { default, min, max } => {
                let current = options.get(option.key).and_then(Value::as_f64);
                if default.is_none() {
                    let mut from_rest = current.is_none();
                    if ui.checkbox(&mut from_rest, "rest").on_hover_text(option.doc).changed() {
                        if from_rest {
                            options.remove(option.key);
                        } else {
                            options.insert(option.key.into(), min.max(0.0).min(max).into());
                        }
                    }
                    if from_rest {
                        return;
                    }
                }
                let mut value = current.or(default).unwrap_or(0.0);
                let speed = if max - min < 10.0 { 0.01 } else { 0.1 };
                if ui
                    .add(egui::DragValue::new(&mut value).range(min..=max).speed(speed))
                    .on_hover_text(option.doc)
                    .changed()
                {
                    options.insert(option.key.into(), value.into());
                }
            }
            OptionKind::Bool { default } => {
                let mut value = options.get(option.key).and_then(Value::as_bool).unwrap_or(default);
                if ui.checkbox(&mut value, "").on_hover_text(option.doc).changed() {
                    options.insert(option.key.into(), value.into());
                }
            }
            OptionKind::Vector { default } => {
                let mut value: [f64; 3] =
                    options.get(option.key).and_then(|v| serde_json::from_value(v.clone()).ok()).unwrap_or(default);
                let mut changed = false;
                for x in &mut value {
                    changed |= ui.add(egui::DragValue::new(x).speed(0.1)).on_hover_text(option.doc).changed();
                }
                if changed {
                    options.insert(option.key.into(), value.to_vec().into());
                }
            }
        }
    });
}
