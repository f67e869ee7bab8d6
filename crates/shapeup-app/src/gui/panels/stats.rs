//! The statistics at the bottom of the side panel: mesh size, timings, rates and the energy
//! plot.

use super::count;
use crate::document::Document;
use crate::gui::metrics::{Metrics, SolveProgress};
use eframe::egui;
use egui::{Color32, Pos2, Sense, Stroke};
use std::collections::VecDeque;
use std::time::Instant;

/// Draws the vertex, triangle and piece counts, the last update's timings (`progress`), the
/// updates and frames of the last second (from `metrics`, whose older entries it drops), and
/// the energy over recent iterations (`energy_history`, log scale).
pub fn stats_panel(
    ui: &mut egui::Ui,
    document: &Document,
    metrics: &mut Metrics,
    progress: &SolveProgress,
    energy_history: &VecDeque<f64>,
) {
    let now = Instant::now();
    for q in [&mut metrics.solves, &mut metrics.frames] {
        while q.front().is_some_and(|t| now.duration_since(*t).as_secs_f64() > 1.0) {
            q.pop_front();
        }
    }
    let p = progress;
    ui.label(format!(
        "{}, {}, {}\n{:.1} ms per iteration (last update: local {:.1} ms, global {:.1} ms)\n{} updates/s, {} frames/s",
        count(document.num_vertices(), "vertex", "vertices"),
        count(document.triangles().len(), "triangle", "triangles"),
        count(document.pieces().count, "piece", "pieces"),
        p.ms_per_iteration,
        p.local_ms,
        p.global_ms,
        metrics.solves.len(),
        metrics.frames.len(),
    ));
    // Energy over recent iterations, log scale.
    let (rect, _) = ui.allocate_exact_size(egui::vec2(ui.available_width(), 60.0), Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_stroke(rect, 2.0, Stroke::new(1.0, Color32::GRAY), egui::StrokeKind::Inside);
    let logs: Vec<f64> = energy_history.iter().filter(|e| **e > 0.0).map(|e| e.log10()).collect();
    if logs.len() >= 2 {
        let (lo, hi) = logs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        let span = (hi - lo).max(1e-9);
        let points: Vec<Pos2> = logs
            .iter()
            .enumerate()
            .map(|(i, &e)| {
                let x = rect.left() + rect.width() * i as f32 / (logs.len() - 1) as f32;
                let y = rect.bottom() - rect.height() * ((e - lo) / span) as f32;
                Pos2::new(x, y)
            })
            .collect();
        painter.add(egui::Shape::line(points, Stroke::new(1.5, Color32::LIGHT_BLUE)));
    }
    ui.label("energy (log) over recent iterations");
}
