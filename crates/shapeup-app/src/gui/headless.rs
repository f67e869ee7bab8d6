//! Headless rendering: one frame of a mesh to a PNG, with no window (for docs, tests and
//! `shapeup view MESH --screenshot out.png`).

use super::renderer::{BASE_COLOR, FrameParams, MeshRenderer};
use crate::camera::OrbitCamera;
use glam::{Vec2, Vec3};
use shapeup_core::mesh::Mesh;
use std::path::Path;

/// Why a headless frame could not be made.
#[derive(Debug, thiserror::Error)]
pub enum ScreenshotError {
    /// No GPU adapter (install Mesa's lavapipe/llvmpipe drivers for software rendering).
    #[error("no graphics adapter found ({0}); on Linux without a GPU install mesa-vulkan-drivers")]
    NoAdapter(String),
    /// The device could not be created.
    #[error("cannot create a graphics device: {0}")]
    Device(String),
    /// Reading the frame back failed.
    #[error("cannot read the rendered frame back")]
    Readback,
    /// Writing the PNG failed.
    #[error(transparent)]
    Write(#[from] shapeup_core::io::IoError),
}

/// A GPU device for offscreen rendering (any adapter, software ones included).
pub fn headless_device() -> Result<(wgpu::Device, wgpu::Queue), ScreenshotError> {
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))
        .map_err(|e| ScreenshotError::NoAdapter(e.to_string()))?;
    pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor::default()))
        .map_err(|e| ScreenshotError::Device(e.to_string()))
}

/// Renders `positions` of `mesh` (colours per vertex, default grey-blue) framed by an orbit
/// camera from the front, `size` pixels, and returns RGBA8 rows.
pub fn render_rgba(
    mesh: &Mesh,
    positions: &[glam::DVec3],
    colors: &[[f32; 3]],
    size: (u32, u32),
    wireframe: bool,
) -> Result<(u32, u32, Vec<u8>), ScreenshotError> {
    let (device, queue) = headless_device()?;
    let p: Vec<Vec3> = positions.iter().map(|p| p.as_vec3()).collect();
    let colors: Vec<[f32; 3]> = if colors.len() == p.len() { colors.to_vec() } else { vec![BASE_COLOR; p.len()] };
    let mut renderer = MeshRenderer::new(&device);
    renderer.set_mesh(&device, &p, &mesh.triangles, &colors);
    let mut camera = OrbitCamera::default();
    camera.frame_front(&mesh.positions, &mesh.triangles);
    let viewport = Vec2::new(size.0 as f32, size.1 as f32);
    let frame = FrameParams {
        view_proj: camera.view_projection(viewport),
        light_dir: camera.eye() - camera.target + Vec3::Y * camera.distance * 0.5,
        wireframe,
        background: [1.0, 1.0, 1.0],
    };
    renderer.render(&device, &queue, size, &frame).ok_or(ScreenshotError::Readback)?;
    renderer.read_pixels(&device, &queue).ok_or(ScreenshotError::Readback)
}

/// Writes RGBA8 rows as a PNG (atomically).
pub fn write_png(path: &Path, w: u32, h: u32, pixels: &[u8]) -> Result<(), ScreenshotError> {
    shapeup_core::io::write_atomic(path, |out| {
        let mut encoder = png::Encoder::new(out, w, h);
        encoder.set_color(png::ColorType::Rgba);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
        writer.write_image_data(pixels).map_err(std::io::Error::other)?;
        writer.finish().map_err(std::io::Error::other)
    })?;
    Ok(())
}

/// Renders one frame of a mesh and writes it as a PNG.
pub fn screenshot(mesh: &Mesh, path: &Path, size: (u32, u32)) -> Result<(), ScreenshotError> {
    let (w, h, pixels) = render_rgba(mesh, &mesh.positions, &[], size, false)?;
    write_png(path, w, h, &pixels)
}
