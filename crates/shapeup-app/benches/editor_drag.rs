//! The latency a user sees while dragging in the editor: the whole app (panels, background
//! convergence, 3D rendering through wgpu, on whatever adapter there is — lavapipe, a software
//! renderer, on a machine without a GPU) driven by `egui_kittest` with a scripted drag, rendered
//! with the window's renderer settings.
//!
//! Scene: the 35k-vertex Stanford bunny with triangle strain + bending, the lowest and the
//! highest 5 % of its vertices (by y) fixed; the top handle is dragged (a drag begun as a pointer
//! drag begins one) by mouse events arriving at 60 Hz on their own clock for `DRAG_SECONDS`.
//! Frames run back to back; each takes in, as one change, the events that arrived before it
//! started (as egui gathers input at the start of a frame). Printed: the time from a change to
//! the end of the UI pass that shows a solve of it ([`EditorApp::latencies`]) and to the end of
//! that frame's rendering; the time from each mouse event to that rendered frame (waiting for
//! the frame under way included), for every event and for the oldest of each batch; frame and
//! UI pass times; how long the convergence takes after the drag stops.
//!
//! Run: `cargo bench -p shapeup-app --features gui --bench editor_drag` (release build).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::print_stdout, missing_docs)]

use eframe::egui;
use egui_kittest::Harness;
use glam::DVec3;
use shapeup_app::gui::app::EditorApp;
use shapeup_app::{Command, Document, SelectMode, ShapeModel};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const DRAG_SECONDS: f64 = 4.0;
const FRAME: Duration = Duration::from_millis(16);
/// Mouse events at 60 Hz.
const EVENT_PERIOD: Duration = Duration::from_micros(16_667);

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted.get(((sorted.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(f64::NAN)
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else is understood.
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/stanford-bunny.obj"));
    let mut document = Document::open(Path::new(&path), ShapeModel::StrainBending).unwrap();
    let n = document.num_vertices();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|&a, &b| document.positions()[a as usize].y.total_cmp(&document.positions()[b as usize].y));
    let k = n / 20;
    for part in [&order[..k], &order[n - k..]] {
        document.apply(Command::Select { vertices: part.to_vec(), mode: SelectMode::Replace }).unwrap();
        document.apply(Command::FixSelection).unwrap();
    }
    let top = document.handles().last().unwrap().key;
    let (lo, hi) = document.rest_mesh().bounding_box();
    let step = 0.002 * (hi - lo).length();

    let mut harness = Harness::builder()
        .with_size(egui::vec2(1280.0, 800.0))
        // The window's renderer settings (kittest's default filters textures in the shader, for
        // reproducible snapshots, which the window does not).
        .renderer(egui_kittest::wgpu::WgpuTestRenderer::with_render_options(egui_wgpu::RendererOptions {
            dithering: false,
            ..Default::default()
        }))
        .build_eframe(|cc| EditorApp::new(cc, document, path.clone()));
    harness.run_steps(3);
    let _ = harness.render();

    // Wait for the first convergence to settle, then time frames that redraw the mesh while
    // the solver is idle (a selection change re-uploads colours and rasterizes).
    let waited = Instant::now();
    while !harness.state().is_converged() && waited.elapsed() < Duration::from_secs(120) {
        harness.step();
        std::thread::sleep(FRAME);
    }
    let mut idle_ms = Vec::new();
    for _ in 0..10 {
        let t = Instant::now();
        harness.state_mut().apply_commands(vec![Command::ClearSelection]);
        harness.step();
        let _ = harness.render();
        idle_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    idle_ms.sort_by(f64::total_cmp);
    let mut static_ms = Vec::new();
    for _ in 0..10 {
        let t = Instant::now();
        harness.step();
        let _ = harness.render();
        static_ms.push(t.elapsed().as_secs_f64() * 1e3);
    }
    static_ms.sort_by(f64::total_cmp);
    println!("  frame with nothing changed (composite only): median {:.0} ms", percentile(&static_ms, 0.5));
    println!("  redraw with the solver idle: median {:.0} ms", percentile(&idle_ms, 0.5));
    let mut frame_ms = Vec::new();
    let mut ui_pass_ms = Vec::new();
    // Change (taken in at a frame's start) to the end of the frame that draws it.
    let mut visible = Vec::new();
    // Mouse event (arriving at 60 Hz, on its own clock) to the end of the frame that draws it:
    // events that arrive while a frame is under way wait for the next one, which takes them
    // all in as one change (as egui gathers input at the start of a frame).
    let mut event_to_screen = Vec::new();
    // The same for every event, not only the oldest of each frame's batch.
    let mut each_event = Vec::new();
    let mut unshown: Vec<Instant> = Vec::new();
    harness.state_mut().begin_drag();
    let start = Instant::now();
    let mut next_event = start;
    let mut oldest_unshown: Option<Instant> = None;
    let mut i = 0u32;
    while start.elapsed().as_secs_f64() < DRAG_SECONDS {
        if let Some(wait) = next_event.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        let frame_start = Instant::now();
        let mut delta = DVec3::ZERO;
        while next_event <= frame_start {
            // Back and forth, a small circle's worth of mouse motion.
            let phase = f64::from(i) * 0.15;
            delta += DVec3::new(phase.cos(), 0.5 * phase.sin(), 0.0) * step;
            oldest_unshown.get_or_insert(next_event);
            unshown.push(next_event);
            next_event += EVENT_PERIOD;
            i += 1;
        }
        harness.state_mut().apply_commands(vec![Command::MoveHandle { handle: top, delta }]);
        let shown_before = harness.state().latencies().count();
        harness.step();
        let ui_ms = frame_start.elapsed().as_secs_f64() * 1e3;
        let _ = harness.render();
        let render_ms = frame_start.elapsed().as_secs_f64() * 1e3 - ui_ms;
        // The editor times a change to the end of the UI pass that shows it; on screen it is
        // once that frame is rendered.
        if let Some(latency) = harness.state().latencies().nth(shown_before) {
            visible.push(latency + render_ms);
            if let Some(oldest) = oldest_unshown.take() {
                event_to_screen.push(oldest.elapsed().as_secs_f64() * 1e3);
            }
            each_event.extend(unshown.drain(..).map(|t| t.elapsed().as_secs_f64() * 1e3));
        }
        frame_ms.push(frame_start.elapsed().as_secs_f64() * 1e3);
        ui_pass_ms.push(ui_ms);
    }
    let changes = i;
    harness.state_mut().end_drag();
    harness.state_mut().apply_commands(Vec::new());
    let mut latencies: Vec<f64> = harness.state().latencies().collect();
    // Convergence after the drag stops.
    let released = Instant::now();
    while !harness.state().is_converged() && released.elapsed() < Duration::from_secs(20) {
        harness.step();
        std::thread::sleep(FRAME);
    }
    let settle = released.elapsed().as_secs_f64();
    latencies.sort_by(f64::total_cmp);
    frame_ms.sort_by(f64::total_cmp);
    ui_pass_ms.sort_by(f64::total_cmp);
    println!(
        "editor drag, bunny {n} vertices, strain + bending: {changes} drag events, {} updates shown",
        latencies.len()
    );
    visible.sort_by(f64::total_cmp);
    println!(
        "  drag event to the end of the UI pass that shows it: median {:.0} ms, p90 {:.0} ms, max {:.0} ms",
        percentile(&latencies, 0.5),
        percentile(&latencies, 0.9),
        percentile(&latencies, 1.0)
    );
    println!(
        "  drag event to its first rendered frame: median {:.0} ms, p90 {:.0} ms ({} updates)",
        percentile(&visible, 0.5),
        percentile(&visible, 0.9),
        visible.len()
    );
    event_to_screen.sort_by(f64::total_cmp);
    each_event.sort_by(f64::total_cmp);
    println!(
        "  mouse event (60 Hz, waiting for the frame under way included) to the first rendered frame showing it: every event: median {:.0} ms, p90 {:.0} ms ({} events); the oldest of each frame's batch: median {:.0} ms, p90 {:.0} ms, max {:.0} ms",
        percentile(&each_event, 0.5),
        percentile(&each_event, 0.9),
        each_event.len(),
        percentile(&event_to_screen, 0.5),
        percentile(&event_to_screen, 0.9),
        percentile(&event_to_screen, 1.0)
    );
    println!(
        "  frame (UI pass + 3D render + composite): median {:.0} ms, p90 {:.0} ms",
        percentile(&frame_ms, 0.5),
        percentile(&frame_ms, 0.9)
    );
    println!(
        "  of which the UI pass (solver results taken, mesh uploaded and rasterized): median {:.0} ms",
        percentile(&ui_pass_ms, 0.5)
    );
    println!(
        "  after release: {} in {settle:.1} s ({})",
        if harness.state().is_converged() { "converged" } else { "still converging" },
        harness.state().solve_status()
    );
}
