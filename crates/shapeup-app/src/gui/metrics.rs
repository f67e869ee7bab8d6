//! What the editor measures: solve progress, frames, change-to-screen latencies, and the
//! `--stats` line on stderr.

use eframe::egui;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// How far the background convergence is, from the worker's last result.
#[derive(Debug, Clone, Default)]
pub(super) struct SolveProgress {
    /// "converged: 153 iterations, E 1.2e-3", "solving… 40 iterations, E …", or empty.
    pub(super) line: String,
    pub(super) converged: bool,
    pub(super) local_ms: f64,
    pub(super) global_ms: f64,
    pub(super) ms_per_iteration: f64,
}

/// Frame and latency measurements (nothing here changes the solve or the view).
pub(super) struct Metrics {
    pub(super) solves: VecDeque<Instant>,
    pub(super) solves_applied: u64,
    pub(super) frames: VecDeque<Instant>,
    /// The oldest change not shown yet (its request's sequence number and time), a change shown
    /// in this frame, and the latencies measured (milliseconds), for [`super::app::EditorApp::latencies`].
    pub(super) change_since: Option<(u64, Instant)>,
    pub(super) shown_change: Option<Instant>,
    pub(super) latencies: VecDeque<f64>,
    /// A change shown by the previous frame: once the next frame starts, that one has been
    /// painted and presented, giving `on_screen` latencies (upper bounds).
    pub(super) painted_change: Option<Instant>,
    pub(super) on_screen: VecDeque<f64>,
    /// How long the previous frame took to draw, when known (see [`frame_busy`]), and how long
    /// the current one has waited for the solver so far.
    pub(super) last_frame_busy: Option<Duration>,
    pub(super) waited: Duration,
    pub(super) last_stats_print: Instant,
}

impl Metrics {
    pub(super) fn new() -> Metrics {
        Metrics {
            solves: VecDeque::new(),
            solves_applied: 0,
            frames: VecDeque::new(),
            change_since: None,
            shown_change: None,
            latencies: VecDeque::new(),
            painted_change: None,
            on_screen: VecDeque::new(),
            last_frame_busy: None,
            waited: Duration::ZERO,
            last_stats_print: Instant::now(),
        }
    }

    /// One latency per change that has now been drawn (see [`super::app::EditorApp::latencies`]).
    pub(super) fn record_latency(&mut self) {
        if let Some(since) = self.shown_change.take() {
            push_bounded(&mut self.latencies, since.elapsed().as_secs_f64() * 1e3);
            self.painted_change = Some(since);
        }
    }

    /// One line per second on stderr: frames/s, updates/s, solve times, change-to-screen latency.
    pub(super) fn print_stats(&mut self, ctx: &egui::Context, reduced_resolution: bool, progress: &SolveProgress) {
        use std::io::Write as _;
        let now = Instant::now();
        if now.duration_since(self.last_stats_print).as_secs_f64() >= 1.0 {
            self.last_stats_print = now;
            let count =
                |q: &VecDeque<Instant>| q.iter().filter(|t| now.duration_since(**t).as_secs_f64() <= 1.0).count();
            let summary = |q: &VecDeque<f64>| {
                let mut sorted: Vec<f64> = q.iter().copied().collect();
                sorted.sort_by(f64::total_cmp);
                let at = |p: f64| sorted.get(((sorted.len() as f64 - 1.0) * p).round() as usize);
                match (at(0.5), at(0.9)) {
                    (Some(m), Some(p90)) => format!("median {m:.0} ms, p90 {p90:.0} ms"),
                    _ => "—".into(),
                }
            };
            // Best effort: a closed stderr must not stop the editor.
            let _ = writeln!(
                std::io::stderr().lock(),
                "stats: {} frames/s{}, {} updates/s, {:.1} ms per iteration; change to the UI pass showing it: {}, to the screen: {} ({} changes); {}",
                count(&self.frames),
                if reduced_resolution { " (3D view at half resolution)" } else { "" },
                count(&self.solves),
                progress.ms_per_iteration,
                summary(&self.latencies),
                summary(&self.on_screen),
                self.latencies.len(),
                progress.line,
            );
        }
        if self.painted_change.is_some() {
            // The next frame's start closes the on-screen measurement: no idle gap in it.
            ctx.request_repaint();
        }
        // Only while measuring: keep printing when idle (otherwise nothing redraws when idle).
        ctx.request_repaint_after(Duration::from_millis(250));
    }
}

/// How long the previous frame kept the renderer busy, from the gap between the starts of the
/// last two frames: only when the previous frame asked for the next one at once (`back_to_back`,
/// so the gap holds no idle time waiting for input) and less the time it spent waiting for the
/// solver (not drawing).
pub(super) fn frame_busy(gap: Option<Duration>, waited: Duration, back_to_back: bool) -> Option<Duration> {
    gap.filter(|_| back_to_back).map(|gap| gap.saturating_sub(waited))
}

/// Appends a latency, keeping the last 1000.
pub(super) fn push_bounded(latencies: &mut VecDeque<f64>, ms: f64) {
    latencies.push_back(ms);
    if latencies.len() > 1000 {
        latencies.pop_front();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gui::viewport::render_scale;

    #[test]
    fn a_frame_counts_as_slow_only_for_its_own_drawing() {
        let ms = Duration::from_millis;
        // Idle before the press (no repaint was pending): not the renderer's time.
        assert_eq!(frame_busy(Some(ms(2000)), ms(0), false), None);
        assert_eq!(frame_busy(None, ms(0), true), None);
        // Frames back to back: the gap is the frame's.
        assert_eq!(frame_busy(Some(ms(55)), ms(0), true), Some(ms(55)));
        // Waiting up to 50 ms for the solver's first answer is not drawing: a fast renderer
        // that waited 45 ms of a 50 ms frame drew for 5 ms.
        let busy = frame_busy(Some(ms(50)), ms(45), true);
        assert_eq!(busy, Some(ms(5)));
        assert_eq!(render_scale(true, false, busy), (1.0, false));
        assert_eq!(frame_busy(Some(ms(40)), ms(45), true), Some(ms(0)));
    }
}
