//! The undo history: one [`Snapshot`] per undoable step (one per drag), undo and redo.

use super::Document;
use crate::edit_state::EditState;
use glam::DVec3;
use std::sync::Arc;

/// Undo steps kept; older ones are dropped.
pub const UNDO_LIMIT: usize = 200;

/// One undo step: the edit state and the shape on screen before the change, so that undo
/// brings back what was seen (also after Reset shape, Make rest shape or a dynamics run).
#[derive(Debug, Clone)]
pub(super) struct Snapshot {
    pub(super) state: EditState,
    pub(super) positions: Arc<Vec<DVec3>>,
}

impl Document {
    /// Records an undo step for the current state and shape, e.g. before a dynamics run moves
    /// the shape: undo then brings the shape back.
    pub fn checkpoint(&mut self) {
        self.end_drag();
        self.record(self.state.clone());
    }

    /// Records the state before an undoable change, with the shape on screen now.
    pub(super) fn record(&mut self, previous: EditState) {
        self.redo.clear();
        self.modified = true;
        match self.drag {
            Some(true) => return,
            Some(false) => self.drag = Some(true),
            None => {}
        }
        self.undo.push(Snapshot { state: previous, positions: Arc::new(self.positions.clone()) });
        // Each step holds a copy of the shape: keep at most about 512 MiB of them.
        let per_step = (self.positions.len() * std::mem::size_of::<DVec3>()).max(1);
        let limit = UNDO_LIMIT.min((512 << 20) / per_step).max(10);
        if self.undo.len() > limit {
            let excess = self.undo.len() - limit;
            self.undo.drain(..excess);
        }
    }

    /// Starts a drag: every undoable command until [`Document::end_drag`] forms one undo step.
    pub fn begin_drag(&mut self) {
        self.drag = Some(false);
    }

    /// Ends a drag (see [`Document::begin_drag`]).
    pub fn end_drag(&mut self) {
        self.drag = None;
    }

    /// Whether a drag is under way (between [`Document::begin_drag`] and
    /// [`Document::end_drag`]): more changes are expected within a frame.
    pub fn is_dragging(&self) -> bool {
        self.drag.is_some()
    }

    /// Whether there is a step to undo.
    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// Whether there is a step to redo.
    pub fn can_redo(&self) -> bool {
        !self.redo.is_empty()
    }

    /// Undoes the last step; `false` if there was none. The shape goes back to what was on
    /// screen before the step (the next solve converges from there).
    ///
    /// While a drag is under way this does nothing and returns `false`: the drag is one step
    /// whatever the keyboard does meanwhile, and is undone as one once it ends.
    pub fn undo(&mut self) -> bool {
        !self.is_dragging() && self.step_history(true)
    }

    /// Redoes the last undone step; `false` if there was none or a drag is under way (see
    /// [`Document::undo`]).
    pub fn redo(&mut self) -> bool {
        !self.is_dragging() && self.step_history(false)
    }

    fn step_history(&mut self, back: bool) -> bool {
        let (from, to) = if back { (&mut self.undo, &mut self.redo) } else { (&mut self.redo, &mut self.undo) };
        let Some(snapshot) = from.pop() else { return false };
        if self.solver.sync(&snapshot.state).is_err() {
            // Every recorded state was built once, so this does not happen; keep the history.
            from.push(snapshot);
            return false;
        }
        let current = Arc::new(self.positions.clone());
        to.push(Snapshot { state: std::mem::replace(&mut self.state, snapshot.state), positions: current });
        // Back to the shape that was on screen (a new epoch: the next solve starts there).
        self.set_shape(Arc::unwrap_or_clone(snapshot.positions));
        self.modified = true;
        true
    }
}
