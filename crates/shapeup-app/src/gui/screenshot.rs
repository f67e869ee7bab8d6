//! The Screenshot button: the 3D view as it is on screen (overlays included, panels left out)
//! to a PNG beside the Save row's scene, through egui's own screenshot of the window.

use super::app::EditorApp;
use super::headless::write_png;
use eframe::egui;
use std::path::{Path, PathBuf};
use std::sync::{Arc, PoisonError};

impl EditorApp {
    /// Asks egui for the window's pixels; the 3D view's part is written to the first free
    /// `STEM-view-N.png` beside the Save row's path (STEM: the opened file's), and the status
    /// says which file, or why not, once it is done ([`EditorApp::poll_screenshot`]).
    pub(super) fn request_screenshot(&mut self, ctx: &egui::Context) {
        let folder = Path::new(self.files.scene_input.trim()).parent().map(Path::to_path_buf).unwrap_or_default();
        let stem = self.mesh_path.file_stem().map_or_else(|| "shapeup".into(), |s| s.to_string_lossy().into_owned());
        let path = free_name(&folder, &stem);
        // Points to pixels, as egui renders the window.
        let rect = self.viewport.rect * ctx.pixels_per_point();
        let slot = Arc::clone(&self.viewport.screenshot);
        let repaint = ctx.clone();
        let callback = egui::ScreenshotCallback::new(move |image| {
            let done = write_region(&image, rect, &path).map(|()| path);
            *slot.lock().unwrap_or_else(PoisonError::into_inner) = Some(done);
            repaint.request_repaint();
        });
        ctx.send_viewport_cmd(egui::ViewportCommand::Screenshot(callback));
        self.view.status = "taking a screenshot of the view…".into();
    }

    /// Says where the last screenshot went, once it has.
    pub(super) fn poll_screenshot(&mut self) {
        let done = self.viewport.screenshot.lock().unwrap_or_else(PoisonError::into_inner).take();
        match done {
            Some(Ok(path)) => self.view.status = format!("saved the view to {}", path.display()),
            Some(Err(why)) => self.view.status = format!("screenshot not saved: {why}"),
            None => {}
        }
    }
}

/// `FOLDER/STEM-view-N.png` for the first N from 1 that names no file yet.
fn free_name(folder: &Path, stem: &str) -> PathBuf {
    (1u32..).map(|n| folder.join(format!("{stem}-view-{n}.png"))).find(|p| !p.exists()).unwrap_or_default()
}

/// Writes the pixels of `image` inside `rect` (pixels, clipped to the image) as a PNG.
fn write_region(image: &egui::ColorImage, rect: egui::Rect, path: &Path) -> Result<(), String> {
    let [w, h] = image.size;
    // Whole pixels inside both the rect and the image.
    let clip = |v: f32, n: usize| (v.round().max(0.0) as usize).min(n);
    let (x0, x1) = (clip(rect.min.x, w), clip(rect.max.x, w));
    let (y0, y1) = (clip(rect.min.y, h), clip(rect.max.y, h));
    if x1 <= x0 || y1 <= y0 {
        return Err("the 3D view is not on screen".into());
    }
    let mut rgba = Vec::with_capacity(4 * (x1 - x0) * (y1 - y0));
    for y in y0..y1 {
        rgba.extend(image.pixels[y * w + x0..y * w + x1].iter().flat_map(|c| c.to_array()));
    }
    let size = |n: usize| u32::try_from(n).map_err(|_| "the view is too large".to_string());
    write_png(path, size(x1 - x0)?, size(y1 - y0)?, &rgba).map_err(|e| e.to_string())
}
