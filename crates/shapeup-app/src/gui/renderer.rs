//! The 3D viewport's renderer: a shaded mesh (per-vertex normals recomputed as it deforms,
//! per-vertex colours for selection and handles) and an optional wireframe, drawn into an
//! offscreen colour + depth texture. The same code renders the window's viewport (the texture is
//! shown by egui) and headless screenshots.

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use wgpu::util::DeviceExt;

/// Colour format of the offscreen target (also what screenshots are written from).
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// One vertex as the GPU sees it.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuVertex {
    position: [f32; 3],
    normal: [f32; 3],
    color: [f32; 3],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Uniforms {
    view_proj: [[f32; 4]; 4],
    light: [f32; 4],
    line_color: [f32; 4],
}

/// What to draw in a frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameParams {
    /// Clip-from-world matrix (wgpu depth range 0..1).
    pub view_proj: Mat4,
    /// Direction towards the light, world space.
    pub light_dir: Vec3,
    /// Draw the edges on top of the shaded surface.
    pub wireframe: bool,
    /// Background colour (linear RGB).
    pub background: [f64; 3],
}

struct Target {
    size: (u32, u32),
    color: wgpu::Texture,
    color_view: wgpu::TextureView,
    depth_view: wgpu::TextureView,
}

/// GPU resources for drawing one mesh; built once, then only the vertex buffer and uniforms are
/// rewritten per frame.
pub struct MeshRenderer {
    shaded: wgpu::RenderPipeline,
    lines: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    vertex_buffer: Option<wgpu::Buffer>,
    triangle_buffer: Option<wgpu::Buffer>,
    edge_buffer: Option<wgpu::Buffer>,
    num_vertices: usize,
    num_triangle_indices: u32,
    num_edge_indices: u32,
    triangles: Vec<[u32; 3]>,
    target: Option<Target>,
}

impl MeshRenderer {
    /// Builds the pipelines.
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("shapeup mesh shader"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shader.wgsl").into()),
        });
        let bind_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shapeup uniforms"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("shapeup mesh layout"),
            bind_group_layouts: &[Some(&bind_layout)],
            immediate_size: 0,
        });
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shapeup uniforms"),
            size: std::mem::size_of::<Uniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shapeup uniforms"),
            layout: &bind_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniforms.as_entire_binding() }],
        });
        let attributes = wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3];
        let buffers = [Some(wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<GpuVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &attributes,
        })];
        let pipeline = |topology: wgpu::PrimitiveTopology, fragment: &str, bias: i32| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(fragment),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &buffers,
                },
                primitive: wgpu::PrimitiveState { topology, cull_mode: None, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::LessEqual),
                    stencil: Default::default(),
                    // Pull the shaded surface back a little so the wireframe wins the depth test.
                    bias: wgpu::DepthBiasState { constant: bias, slope_scale: bias as f32 * 0.5, clamp: 0.0 },
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: COLOR_FORMAT,
                        blend: None,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        MeshRenderer {
            shaded: pipeline(wgpu::PrimitiveTopology::TriangleList, "fs_shaded", 2),
            lines: pipeline(wgpu::PrimitiveTopology::LineList, "fs_lines", 0),
            uniforms,
            bind_group,
            vertex_buffer: None,
            triangle_buffer: None,
            edge_buffer: None,
            num_vertices: 0,
            num_triangle_indices: 0,
            num_edge_indices: 0,
            triangles: Vec::new(),
            target: None,
        }
    }

    /// Uploads a new mesh (connectivity and first positions).
    pub fn set_mesh(&mut self, device: &wgpu::Device, positions: &[Vec3], triangles: &[[u32; 3]], colors: &[[f32; 3]]) {
        self.triangles = triangles.to_vec();
        let flat: Vec<u32> = triangles.iter().flatten().copied().collect();
        let (edges, _) = shapeup_core::topology::unique_edges(triangles);
        let edge_flat: Vec<u32> = edges.iter().flatten().copied().collect();
        self.triangle_buffer = Some(device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shapeup triangles"),
            contents: bytemuck::cast_slice(&flat),
            usage: wgpu::BufferUsages::INDEX,
        }));
        self.edge_buffer = Some(device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shapeup edges"),
            contents: bytemuck::cast_slice(&edge_flat),
            usage: wgpu::BufferUsages::INDEX,
        }));
        self.num_triangle_indices = flat.len() as u32;
        self.num_edge_indices = edge_flat.len() as u32;
        self.num_vertices = positions.len();
        let vertices = self.vertices(positions, colors);
        self.vertex_buffer = Some(device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("shapeup vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        }));
    }

    /// Rewrites positions (normals are recomputed) and colours of the current mesh.
    pub fn update(&mut self, queue: &wgpu::Queue, positions: &[Vec3], colors: &[[f32; 3]]) {
        if positions.len() != self.num_vertices {
            return;
        }
        let vertices = self.vertices(positions, colors);
        if let Some(buffer) = &self.vertex_buffer {
            queue.write_buffer(buffer, 0, bytemuck::cast_slice(&vertices));
        }
    }

    fn vertices(&self, positions: &[Vec3], colors: &[[f32; 3]]) -> Vec<GpuVertex> {
        let normals = vertex_normals(positions, &self.triangles);
        positions
            .iter()
            .zip(&normals)
            .enumerate()
            .map(|(i, (p, n))| GpuVertex {
                position: p.to_array(),
                normal: n.to_array(),
                color: colors.get(i).copied().unwrap_or(BASE_COLOR),
            })
            .collect()
    }

    /// Renders a frame of `size` pixels into the offscreen target and returns its view.
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        size: (u32, u32),
        frame: &FrameParams,
    ) -> Option<&wgpu::TextureView> {
        let size = (size.0.max(1), size.1.max(1));
        if self.target.as_ref().is_none_or(|t| t.size != size) {
            self.target = Some(create_target(device, size));
        }
        let uniforms = Uniforms {
            view_proj: frame.view_proj.to_cols_array_2d(),
            light: [frame.light_dir.x, frame.light_dir.y, frame.light_dir.z, 0.25],
            line_color: [0.12, 0.14, 0.18, 1.0],
        };
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(&uniforms));
        let mut encoder =
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("shapeup frame") });
        if let Some(target) = &self.target {
            let [r, g, b] = frame.background;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("shapeup mesh pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target.color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let (Some(vertices), Some(triangles)) = (&self.vertex_buffer, &self.triangle_buffer) {
                pass.set_bind_group(0, &self.bind_group, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..));
                pass.set_pipeline(&self.shaded);
                pass.set_index_buffer(triangles.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..self.num_triangle_indices, 0, 0..1);
                if frame.wireframe
                    && let Some(edges) = &self.edge_buffer
                {
                    pass.set_pipeline(&self.lines);
                    pass.set_index_buffer(edges.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(0..self.num_edge_indices, 0, 0..1);
                }
            }
        }
        queue.submit([encoder.finish()]);
        self.target.as_ref().map(|t| &t.color_view)
    }

    /// Copies the last rendered frame to RGBA8 bytes (rows top to bottom), for screenshots.
    pub fn read_pixels(&self, device: &wgpu::Device, queue: &wgpu::Queue) -> Option<(u32, u32, Vec<u8>)> {
        let target = self.target.as_ref()?;
        let (w, h) = target.size;
        let row = (w * 4).div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shapeup readback"),
            size: u64::from(row) * u64::from(h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("readback") });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture: &target.color,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(row), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
        );
        queue.submit([encoder.finish()]);
        let slice = buffer.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device.poll(wgpu::PollType::wait_indefinitely()).ok()?;
        rx.recv().ok()?.ok()?;
        let data = slice.get_mapped_range().ok()?;
        let mut pixels = Vec::with_capacity((w * h * 4) as usize);
        for y in 0..h as usize {
            let start = y * row as usize;
            pixels.extend_from_slice(&data[start..start + (w * 4) as usize]);
        }
        drop(data);
        buffer.unmap();
        Some((w, h, pixels))
    }
}

/// The default surface colour (a light grey-blue).
pub const BASE_COLOR: [f32; 3] = [0.70, 0.76, 0.86];

fn create_target(device: &wgpu::Device, size: (u32, u32)) -> Target {
    let extent = wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 };
    let color = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shapeup colour"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: COLOR_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let depth = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("shapeup depth"),
        size: extent,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    Target {
        size,
        color_view: color.create_view(&Default::default()),
        depth_view: depth.create_view(&Default::default()),
        color,
    }
}

/// Per-vertex normals for shading: n_i = normalize(Σ_{t ∋ i} (b − a) × (c − a)), the
/// area-weighted sum of the face normals around i.
pub fn vertex_normals(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        let n = (b - a).cross(c - a);
        for &v in t {
            normals[v as usize] += n;
        }
    }
    normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    normals
}
