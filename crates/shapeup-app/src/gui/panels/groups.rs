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
    /// A typed weight that was refused, and why, shown under its row until the row's weight
    /// next changes.
    weight_error: Option<(GroupKey, String)>,
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
            match weight_control(ui, group.spec.weight, &mut out) {
                Ok(Some(weight)) => {
                    out.commands.push(Command::SetWeight { group: group.key, weight });
                    state.weight_error = None;
                }
                Ok(None) => {}
                Err(why) => state.weight_error = Some((group.key, why)),
            }
            if let Some((_, why)) = state.weight_error.as_ref().filter(|(key, _)| *key == group.key) {
                ui.colored_label(egui::Color32::RED, why);
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
/// type any weight in the range) and fine steps while shift is held. Returns the new weight
/// when it changed. One undo step per slider drag (noted in `out`).
///
/// # Errors
/// Typed text that is no weight ([`typed_weight`]): why, in one line for the row.
fn weight_control(ui: &mut egui::Ui, weight: f64, out: &mut PanelOutput) -> Result<Option<f64>, String> {
    let (lo, hi) = (WEIGHT_RANGE.0.log10(), WEIGHT_RANGE.1.log10());
    let before = weight.log10();
    let mut exponent = before;
    let (refused, typed) = (std::cell::RefCell::new(None), std::cell::Cell::new(None));
    // A scene's weight outside the range stays as it is until the user moves it.
    let slider = egui::Slider::new(&mut exponent, lo..=hi)
        .clamping(egui::SliderClamping::Edits)
        .text("weight")
        .custom_formatter(|x, _| format_weight(10f64.powf(x)))
        .custom_parser(|text| match typed_weight(text) {
            Ok(w) => {
                typed.set(Some(w));
                Some(w.log10())
            }
            Err(why) => {
                *refused.borrow_mut() = Some(why);
                None
            }
        });
    let response = ui.add(slider);
    out.track_drag(&response);
    if let Some(why) = refused.into_inner() {
        return Err(why);
    }
    if response.interact_pointer_pos().is_some() && ui.input(|i| i.modifiers.shift) {
        // Fine: a tenth of the pointer's motion, from the press to the release (every frame
        // in which the slider itself puts the value under the pointer).
        // egui's rail: slider_width less a handle radius (thickness / 2.5) at each end.
        let thickness = ui.text_style_height(&egui::TextStyle::Body).max(ui.spacing().interact_size.y);
        let rail = ui.spacing().slider_width - 2.0 * thickness / 2.5;
        let per_px = (hi - lo) / f64::from(rail.max(1.0));
        exponent = (before + 0.1 * per_px * f64::from(ui.input(|i| i.pointer.delta().x))).clamp(lo, hi);
    }
    // What was typed, exactly (250, not 10^log10(250) = 249.99999999999994).
    let weight = typed.get().filter(|w| w.log10() == exponent).unwrap_or_else(|| 10f64.powf(exponent));
    Ok((exponent != before).then_some(weight))
}

/// A typed weight: a number in [`WEIGHT_RANGE`] (the slider's).
///
/// # Errors
/// Why not, naming what was typed: not a number, NaN, infinite, negative or out of range (0
/// would turn the group off: the row's remove does that).
fn typed_weight(text: &str) -> Result<f64, String> {
    let text = text.trim();
    let (lo, hi) = WEIGHT_RANGE;
    match text.parse::<f64>() {
        Ok(w) if (lo..=hi).contains(&w) => Ok(w),
        Ok(0.0) => Err(format!(
            "weight \"{text}\" refused: a weight of 0 turns the group off; remove the group instead (weights go from {lo:e} to {hi:e})"
        )),
        _ => Err(format!("weight \"{text}\" refused: type a number from {lo:e} to {hi:e}")),
    }
}

/// A weight as the slider shows it: 3 significant digits, scientific outside [0.01, 1000).
fn format_weight(w: f64) -> String {
    if (0.01..1000.0).contains(&w) {
        format!("{:.3}", w).trim_end_matches('0').trim_end_matches('.').into()
    } else {
        format!("{w:.2e}")
    }
}
