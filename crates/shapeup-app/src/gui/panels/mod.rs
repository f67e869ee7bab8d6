//! The side panel's sections, one file each. Each is a function that takes what it shows (the
//! document, its own UI state) and returns what the user asked for: [`Command`]s to apply after
//! the UI pass, and the start and end of a slider drag ([`PanelOutput`]), as
//! [`dynamics_panel`](super::dynamics_panel::dynamics_panel) returns its action.

pub mod contact;
pub mod groups;
pub mod selection;
pub mod solver;
pub mod stats;

use crate::command::Command;
use eframe::egui;

/// What a section asked for this frame.
#[derive(Debug, Default)]
pub struct PanelOutput {
    /// To apply after the UI pass, in order.
    pub commands: Vec<Command>,
    /// A slider drag started: the commands until its end make one undo step.
    pub drag_started: bool,
    /// A slider drag ended.
    pub drag_stopped: bool,
}

impl PanelOutput {
    /// Notes a slider's drag start and end (one undo step per drag).
    fn track_drag(&mut self, response: &egui::Response) {
        self.drag_started |= response.drag_started();
        self.drag_stopped |= response.drag_stopped();
    }

    /// Takes `other`'s commands after these, and its drag events.
    pub fn extend(&mut self, other: PanelOutput) {
        self.commands.extend(other.commands);
        self.drag_started |= other.drag_started;
        self.drag_stopped |= other.drag_stopped;
    }
}

/// "1 vertex", "2 vertices".
pub(in crate::gui) fn count(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}
