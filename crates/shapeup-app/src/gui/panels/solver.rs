//! The solver section: the convergence line, tolerance, iteration cap, acceleration, and
//! Reset shape / Make rest shape / Undo / Redo.

use super::PanelOutput;
use crate::command::Command;
use crate::document::Document;
use crate::gui::metrics::SolveProgress;
use eframe::egui;
use egui::Color32;
use shapeup_core::solver::Acceleration;

/// Tolerance slider range, as powers of ten.
const TOLERANCE_EXPONENTS: std::ops::RangeInclusive<f64> = -12.0..=-2.0;

/// Draws the section for `document` with the background convergence's `progress`; returns the
/// commands asked for (one undo step per slider drag).
///
/// Slider "tolerance", field "iteration cap", combo box "acceleration"; buttons "Reset shape",
/// "Make rest shape", "Undo", "Redo".
pub fn solver_panel(ui: &mut egui::Ui, document: &Document, progress: &SolveProgress) -> PanelOutput {
    let mut out = PanelOutput::default();
    ui.label("Solver");
    let converged = progress.converged;
    let color = if converged { Color32::from_rgb(20, 140, 60) } else { ui.visuals().text_color() };
    ui.colored_label(color, if progress.line.is_empty() { "—" } else { &progress.line });
    let mut exponent = document.tolerance().log10();
    let response = ui
        .add(
            egui::Slider::new(&mut exponent, TOLERANCE_EXPONENTS)
                .step_by(0.5)
                .custom_formatter(|x, _| format!("{:.0e}", 10f64.powf(x)))
                .custom_parser(|t| t.trim().parse::<f64>().ok().filter(|v| *v > 0.0).map(f64::log10))
                .text("tolerance"),
        )
        .on_hover_text("converged when an iteration changes the energy by at most this fraction");
    out.track_drag(&response);
    if response.changed() {
        out.commands.push(Command::SetTolerance(10f64.powf(exponent)));
    }
    let mut cap = document.iterations();
    let response = ui
        .add(egui::DragValue::new(&mut cap).range(1..=10_000_000).prefix("iteration cap "))
        .on_hover_text("the most iterations one convergence runs");
    out.track_drag(&response);
    if response.changed() {
        out.commands.push(Command::SetIterations(cap));
    }
    let current = document.acceleration();
    let mut chosen = current;
    egui::ComboBox::from_label("acceleration")
        .selected_text(acceleration_label(current))
        .show_ui(ui, |ui| {
            for a in Acceleration::ALL {
                ui.selectable_value(&mut chosen, a, acceleration_label(a)).on_hover_text(acceleration_hint(a));
            }
        })
        .response
        .on_hover_text(acceleration_hint(current));
    if chosen != current {
        out.commands.push(Command::SetAcceleration(chosen));
    }
    ui.horizontal_wrapped(|ui| {
        if ui.button("Reset shape").on_hover_text("back to the rest shape (undoable)").clicked() {
            out.commands.push(Command::ResetShape);
        }
        if ui.button("Make rest shape").on_hover_text("the current shape becomes the rest shape").clicked() {
            out.commands.push(Command::MakeRest);
        }
        if ui.add_enabled(document.can_undo(), egui::Button::new("Undo")).clicked() {
            out.commands.push(Command::Undo);
        }
        if ui.add_enabled(document.can_redo(), egui::Button::new("Redo")).clicked() {
            out.commands.push(Command::Redo);
        }
    });
    out
}

/// The editor's name for an acceleration.
fn acceleration_label(a: Acceleration) -> &'static str {
    match a {
        Acceleration::Anderson => "Anderson",
        Acceleration::Lbfgs => "L-BFGS",
        Acceleration::None => "none (plain)",
    }
}

/// What an acceleration does, in one hover line.
fn acceleration_hint(a: Acceleration) -> &'static str {
    match a {
        Acceleration::Anderson => {
            "mix the last iterations (Peng et al. 2018); a mixed step that does not lower the energy is replaced by a plain one"
        }
        Acceleration::Lbfgs => {
            "quasi-Newton steps with the global matrix as first Hessian (Liu et al. 2017): the converged shape in the fewest iterations; a step that does not lower the energy enough is replaced by a plain one"
        }
        Acceleration::None => "plain local-global iterations: the energy decreases, slowly",
    }
}
