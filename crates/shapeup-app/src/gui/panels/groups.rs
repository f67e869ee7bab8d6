//! The shape model and the groups: the model's radio buttons, one row per group (name, rename
//! and remove, weight slider), hover highlighting and the handle the gizmo sits on.

use super::PanelOutput;
use crate::command::Command;
use crate::document::{Document, GroupKey, GroupRole, ShapeModel, WEIGHT_RANGE};
use eframe::egui;

/// The section's own state, which the viewport reads too (the hovered group is highlighted, the
/// gizmo sits on the active handle).
#[derive(Debug, Default)]
pub struct GroupsPanel {
    /// The group whose row the pointer is over.
    pub hovered: Option<GroupKey>,
    /// The handle the gizmo sits on (the last one made until a row is clicked).
    pub active_handle: Option<GroupKey>,
    /// The handle being renamed and the name typed so far.
    renaming: Option<(GroupKey, String)>,
}

/// "Shape constraints": one radio button per shape model; returns the model chosen.
pub fn shape_model_panel(ui: &mut egui::Ui, document: &Document) -> Option<Command> {
    ui.label("Shape constraints");
    let current = document.shape_model();
    let mut chosen = None;
    for model in ShapeModel::ALL {
        if ui.radio(current == Some(model), model.label()).clicked() && current != Some(model) {
            chosen = Some(Command::SetShapeModel(model));
        }
    }
    chosen
}

/// Draws one row per group of `document` ("NAME (TYPE)", "rename" for handles, "remove" but for
/// shape groups, a "weight" slider) and "Clear handles"; updates the hovered group and the
/// active handle; returns the commands asked for.
pub fn groups_panel(ui: &mut egui::Ui, document: &Document, state: &mut GroupsPanel) -> PanelOutput {
    let mut out = PanelOutput::default();
    ui.label("Groups (hover to highlight, click a handle's name for the gizmo)");
    state.hovered = None;
    for group in document.groups() {
        let row = ui.vertical(|ui| {
            ui.horizontal(|ui| {
                let active = state.active_handle == Some(group.key);
                let name = format!("{} ({})", group.spec.name, group.spec.kind);
                if group.role == GroupRole::Handle {
                    if ui.selectable_label(active, name).on_hover_text("put the gizmo on this handle").clicked() {
                        state.active_handle = Some(group.key);
                    }
                    if ui.small_button("rename").clicked() {
                        state.renaming = Some((group.key, group.spec.name.clone()));
                    }
                } else {
                    ui.label(name);
                }
                if group.role != GroupRole::Shape && ui.small_button("remove").clicked() {
                    out.commands.push(Command::RemoveGroup(group.key));
                }
            });
            if let Some(weight) = weight_control(ui, group.spec.weight, &mut out) {
                out.commands.push(Command::SetWeight { group: group.key, weight });
            }
        });
        // The whole row, children included (they cover the row's own response).
        if ui.rect_contains_pointer(row.response.rect) {
            state.hovered = Some(group.key);
        }
    }
    if let Some((key, name)) = &mut state.renaming {
        let key = *key;
        let done = ui
            .horizontal(|ui| {
                let label = ui.label("new name");
                let edit = ui.text_edit_singleline(name).labelled_by(label.id);
                edit.lost_focus() || ui.button("OK").clicked()
            })
            .inner;
        if done {
            out.commands.push(Command::RenameHandle { handle: key, name: name.clone() });
            state.renaming = None;
        }
    }
    if ui.button("Clear handles").clicked() {
        out.commands.push(Command::ClearHandles);
    }
    out
}

/// A weight slider over log10(w) from [`WEIGHT_RANGE`], with text entry (the number field:
/// type any weight) and fine steps while shift is held. Returns the new weight when it
/// changed. One undo step per slider drag (noted in `out`).
fn weight_control(ui: &mut egui::Ui, weight: f64, out: &mut PanelOutput) -> Option<f64> {
    let (lo, hi) = (WEIGHT_RANGE.0.log10(), WEIGHT_RANGE.1.log10());
    let before = weight.max(WEIGHT_RANGE.0).log10();
    let mut exponent = before;
    let slider = egui::Slider::new(&mut exponent, lo..=hi)
        .text("weight")
        .custom_formatter(|x, _| format_weight(10f64.powf(x)))
        .custom_parser(|text| text.trim().parse::<f64>().ok().filter(|w| *w > 0.0).map(f64::log10));
    let response = ui.add(slider);
    out.track_drag(&response);
    if response.dragged() && ui.input(|i| i.modifiers.shift) {
        // Fine: a tenth of the pointer's motion.
        let per_px = (hi - lo) / f64::from(ui.spacing().slider_width.max(1.0));
        exponent = (before + 0.1 * per_px * f64::from(response.drag_delta().x)).clamp(lo, hi);
    }
    let weight = 10f64.powf(exponent);
    (exponent != before && response.changed()).then_some(weight)
}

/// A weight as the slider shows it: 3 significant digits, scientific outside [0.01, 1000).
fn format_weight(w: f64) -> String {
    if (0.01..1000.0).contains(&w) {
        format!("{:.3}", w).trim_end_matches('0').trim_end_matches('.').into()
    } else {
        format!("{w:.2e}")
    }
}
