//! The Dynamics panel: run, pause, restart and stop the simulation, and its settings (gravity,
//! floor, tetrahedra, model, speed, stiffness, time step, damping, grab strength) and timings.
//!
//! The panel edits [`SimulationSettings`] in place and says what the user asked for; the editor
//! acts on it (starting, pausing, dropping runners, [`SimulationRunner::update_settings`]).

use crate::error::TetrahedraError;
use crate::simulation::{DynamicsModel, SimulationRunner, SimulationSettings, Speed};
use eframe::egui;
use egui::Color32;

/// What the user did in the panel this frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DynamicsAction {
    /// Start a new simulation from the rest shape, at rest (dropping any runner), and step.
    RunFromRest,
    /// Step on: resume the paused runner, or start one from the shape on screen, at rest.
    Continue,
    /// Stop stepping, keeping the runner (`set_running(false)`).
    Pause,
    /// Back to the shape the runner started from (`reset`).
    Restart,
    /// Leave dynamic mode, keeping the current shape (drop the runner).
    Stop,
    /// The settings changed: apply them to the runner (`update_settings`), or drop it when
    /// that returns `false` (a new model, floor or tetrahedralization).
    SettingsChanged,
}

/// Stiffness slider range (log): from a jelly to nearly rigid at the default time step.
const STIFFNESS_RANGE: std::ops::RangeInclusive<f64> = 1.0..=1e5;

/// Time step slider range, in milliseconds.
const TIME_STEP_MS_RANGE: std::ops::RangeInclusive<f64> = 1.0..=50.0;

/// Draws the panel; `runner` is the current simulation, if any, and `tetrahedralize` whether
/// Tetrahedralize can be ticked (the reason why not, from
/// [`crate::simulation::tetrahedralize_available`]). Returns what the user did, if anything.
///
/// Buttons: "Run from rest", "Continue" / "Pause" (one toggle; Continue is disabled without a
/// runner while Tetrahedralize is ticked), "Restart", "Stop". Checkboxes: "Gravity", "Floor",
/// "Tetrahedralize". Model radio buttons: "Document's shape model", "Tet strain". Speed radio
/// buttons: "Real time", "Slow motion (¼)", "As fast as possible". Sliders:
/// "stiffness", "time step (ms)", "damping", "grab strength".
pub fn dynamics_panel(
    ui: &mut egui::Ui,
    settings: &mut SimulationSettings,
    runner: Option<&SimulationRunner>,
    tetrahedralize: Result<(), TetrahedraError>,
) -> Option<DynamicsAction> {
    let before = *settings;
    let mut action = None;
    let running = runner.is_some_and(SimulationRunner::is_running);
    ui.horizontal_wrapped(|ui| {
        if ui.button("Run from rest").on_hover_text("a new simulation from the rest shape, at rest").clicked() {
            action = Some(DynamicsAction::RunFromRest);
        }
        // One button in one place: Continue while stopped or paused, Pause while running.
        if running {
            if ui.button("Pause").on_hover_text("stop stepping; the shape stays").clicked() {
                action = Some(DynamicsAction::Pause);
            }
        } else {
            // Tetrahedra are made on the rest shape: a new solid starts there (the runner
            // would refuse a deformed shape on screen).
            let solid_at_rest = runner.is_none() && settings.tetrahedralize;
            let hint = if runner.is_some() {
                "step on from where the simulation was paused"
            } else {
                "simulate from the shape on screen, at rest"
            };
            if ui
                .add_enabled(!solid_at_rest, egui::Button::new("Continue"))
                .on_hover_text(hint)
                .on_disabled_hover_text("Tetrahedralize fills the rest shape: use Run from rest")
                .clicked()
            {
                action = Some(DynamicsAction::Continue);
            }
        }
        if ui
            .add_enabled(runner.is_some(), egui::Button::new("Restart"))
            .on_hover_text("back to the shape the simulation started from, at rest")
            .clicked()
        {
            action = Some(DynamicsAction::Restart);
        }
        if ui
            .add_enabled(runner.is_some(), egui::Button::new("Stop"))
            .on_hover_text("leave dynamic mode, keeping the current shape")
            .clicked()
        {
            action = Some(DynamicsAction::Stop);
        }
    });

    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut settings.gravity, "Gravity");
        ui.checkbox(&mut settings.floor, "Floor").on_hover_text("a floor just below the shape");
        let available = tetrahedralize.is_ok();
        // Never leave a tick that cannot be taken back.
        let mut tick = settings.tetrahedralize && available;
        let response = ui
            .add_enabled(available, egui::Checkbox::new(&mut tick, "Tetrahedralize"))
            .on_hover_text("fill the closed surface with tetrahedra (TetGen): a solid body");
        if let Err(why) = &tetrahedralize {
            response.on_disabled_hover_text(why.to_string());
        }
        if tick != settings.tetrahedralize {
            settings.tetrahedralize = tick;
            // A solid wants the solid's model; without tetrahedra there is none.
            settings.model = if tick { DynamicsModel::TetStrain } else { DynamicsModel::Document };
        }
    });

    let has_tetrahedra = settings.tetrahedralize || runner.is_some_and(|r| r.num_tetrahedra > 0);
    ui.horizontal_wrapped(|ui| {
        ui.label("Model:");
        ui.radio_value(&mut settings.model, DynamicsModel::Document, DynamicsModel::Document.label())
            .on_hover_text("the document's shape constraints (on the surface)");
        ui.add_enabled_ui(has_tetrahedra, |ui| {
            ui.radio_value(&mut settings.model, DynamicsModel::TetStrain, DynamicsModel::TetStrain.label())
                .on_hover_text("every tetrahedron keeps its rest shape: the body keeps its volume")
                .on_disabled_hover_text("needs tetrahedra: tick Tetrahedralize");
        });
    });

    ui.horizontal_wrapped(|ui| {
        ui.label("Speed:");
        for speed in Speed::ALL {
            let hint = match speed {
                Speed::RealTime => "a step of h every h seconds: motion at its real speed",
                Speed::SlowMotion => "a step of h every 4 h seconds",
                Speed::AsFastAsPossible => "each step as soon as the last is done",
            };
            ui.radio_value(&mut settings.speed, speed, speed.label()).on_hover_text(hint);
        }
    });

    ui.add(egui::Slider::new(&mut settings.stiffness, STIFFNESS_RANGE).logarithmic(true).text("stiffness"))
        .on_hover_text("k: how strongly the constraints act against inertia");
    let mut ms = settings.time_step * 1e3;
    if ui
        .add(egui::Slider::new(&mut ms, TIME_STEP_MS_RANGE).text("time step (ms)"))
        .on_hover_text("h: simulated time per step")
        .changed()
    {
        settings.time_step = ms * 1e-3;
    }
    ui.add(egui::Slider::new(&mut settings.damping, 0.0..=0.5).text("damping"))
        .on_hover_text("the fraction of the velocity lost per step");
    ui.add(egui::Slider::new(&mut settings.grab_strength, 0.05..=1.0).text("grab strength"))
        .on_hover_text("how closely grabbed vertices follow the cursor (1: exactly)");

    if let Some(runner) = runner {
        let s = runner.stats();
        let tets =
            if runner.num_tetrahedra > 0 { format!(", {} tetrahedra", runner.num_tetrahedra) } else { String::new() };
        let contact = if s.contact_ms > 0.0 {
            format!(", contact {:.1} ms; {} vertices touching", s.contact_ms, s.contact_vertices)
        } else {
            String::new()
        };
        ui.label(format!(
            "{} steps, {:.0} steps/s, {:.1} ms per step (local {:.1} ms, global {:.1} ms{contact}){tets}",
            s.steps, s.steps_per_second, s.step_ms, s.local_ms, s.global_ms
        ));
        if s.unconverged_steps > 0 {
            // As the command line's `unconverged` warning says it.
            ui.colored_label(
                Color32::YELLOW,
                format!(
                    "{} of {} steps checked stopped short of the converged step (the worst misses {:.0} % of its motion): lower the stiffness or the time step (the editor runs {} iterations a step)",
                    s.unconverged_steps,
                    s.checked_steps,
                    100.0 * s.worst_residual,
                    shapeup_core::scene::SolverSettings::default().iterations
                ),
            );
        }
        if let Some(e) = s.error {
            ui.colored_label(Color32::RED, e.to_string());
        }
        ui.label("alt+left drag: grab and pull the mesh");
    }

    if action.is_none() && *settings != before {
        action = Some(DynamicsAction::SettingsChanged);
    }
    action
}
