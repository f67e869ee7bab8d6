//! `shapeup view`: the interactive editor, or one headless frame with `--screenshot`.

use anyhow::{Result, anyhow};
use shapeup_app::document::Document;
use shapeup_app::group::DEFAULT_SHAPE_MODEL;
use shapeup_app::gui::app::{WindowOptions, run_window};
use shapeup_app::gui::headless::{render_rgba, write_png};
use shapeup_app::gui::renderer::BASE_COLOR;
use shapeup_app::gui::viewport::HANDLE_COLOR;
use shapeup_core::scene::Scene;
use std::io::Write as _;
use std::path::PathBuf;

fn is_scene(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("toml") || e.eq_ignore_ascii_case("json"))
}

/// Opens `input` (default: data/stanford-bunny.obj from the working directory, else the bundled
/// bunny) as a document, and the path it came from (the scene's, for a scene; `NAME.obj` for a
/// bundled sample).
fn open(input: Option<PathBuf>) -> Result<(Document, PathBuf)> {
    let local = PathBuf::from("data/stanford-bunny.obj");
    let path = match input {
        Some(path) => path,
        None if local.exists() => local,
        None => PathBuf::from(crate::samples::DEFAULT),
    };
    if let Some(sample) = crate::samples::resolve(&path) {
        let name = PathBuf::from(sample.file_name());
        let document =
            Document::open_sample(&sample, DEFAULT_SHAPE_MODEL).map_err(|e| anyhow!("{}: {e}", name.display()))?;
        Ok((document, name))
    } else if is_scene(&path) {
        let scene = Scene::from_file(&path)?;
        let document = Document::from_scene(&scene).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        Ok((document, path))
    } else {
        let document = Document::open(&path, DEFAULT_SHAPE_MODEL).map_err(|e| anyhow!("{e}"))?;
        Ok((document, path))
    }
}

/// Runs the editor, or writes one frame to `screenshot`.
pub fn run(input: Option<PathBuf>, screenshot: Option<PathBuf>, size: (u32, u32), stats: bool) -> Result<()> {
    if let Some(out) = &screenshot
        && !out.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png"))
    {
        return Err(anyhow!("{}: the screenshot must be a .png file", out.display()));
    }
    let (mut document, path) = open(input)?;
    if let Some(out) = screenshot {
        // The converged shape, as the window shows it once the solver settles.
        if document.state().has_handles() {
            // As the window shows it once settled: to the tolerance, which can take many plain
            // iterations on a large mesh, so say what runs.
            // Notes, not log records; -q silences them.
            let note = |text: String| {
                if !crate::logging::quiet() {
                    let _ = writeln!(std::io::stderr().lock(), "shapeup: {text}");
                }
            };
            note(format!(
                "converging {} to a relative energy change of {:e} (at most {} iterations)…",
                path.display(),
                document.tolerance(),
                document.iterations()
            ));
            let started = std::time::Instant::now();
            let report = document.converge().map_err(|e| anyhow!("{}: {e}", path.display()))?;
            let n = report.energies.len();
            let how = if n < document.iterations() { "converged" } else { "stopped at the cap" };
            let iterations = if n == 1 { "1 iteration".to_string() } else { format!("{n} iterations") };
            note(format!("{how} after {iterations} ({:.1} s)", started.elapsed().as_secs_f64()));
        }
        let mesh = document.current_mesh();
        // Handles in green, as in the editor.
        let mut colors = vec![BASE_COLOR; mesh.num_vertices()];
        for handle in document.handles() {
            for &v in handle.vertices().unwrap_or(&[]) {
                colors[v] = HANDLE_COLOR;
            }
        }
        let (w, h, pixels) = render_rgba(&mesh, &mesh.positions, &colors, size, false).map_err(|e| anyhow!("{e}"))?;
        write_png(&out, w, h, &pixels).map_err(|e| anyhow!("{e}"))?;
        return Ok(());
    }
    run_window(document, path, WindowOptions { print_stats: stats })
        .map_err(|e| anyhow!("cannot open the editor window: {e}"))
}
