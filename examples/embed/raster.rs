//! The example host's own G-buffer: a plain wgpu render pipeline that rasterizes a
//! penumbra scene into depth, normals and albedo textures — what a game engine already
//! has before it adds penumbra's shadows. `tests/gpu/embed.rs` rasterizes with it too.

use glam::{Mat4, Vec3};
use penumbra::scene::Scene;
use penumbra::scene::view::Camera;
use wgpu::util::DeviceExt;

/// Depth format of the G-buffer (full precision: the shadow pass unprojects it).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Format of the normal textures (signed xyz).
pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// Format of the albedo texture (linear).
pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Format of the optional world-position texture.
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Near and far planes, as fractions of the scene's diagonal.
const NEAR: f32 = 0.002;
const FAR: f32 = 4.0;

/// One vertex: world position, shading normal, face normal, albedo (48 bytes).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 3],
    normal: [f32; 3],
    face_normal: [f32; 3],
    albedo: [f32; 3],
}

/// The host's G-buffer textures for one frame size.
pub struct HostGBuffer {
    /// Depth, cleared to 1.
    pub depth: wgpu::Texture,
    /// Interpolated shading normals (xyz).
    pub normal: wgpu::Texture,
    /// Face normals (xyz).
    pub face_normal: wgpu::Texture,
    /// Material base colour (rgb).
    pub albedo: wgpu::Texture,
    /// World positions (xyz, w = 1 on geometry, 0 elsewhere).
    pub position: wgpu::Texture,
}

impl HostGBuffer {
    /// Textures for `width`×`height` frames.
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> HostGBuffer {
        let texture = |label: &str, format: wgpu::TextureFormat| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        HostGBuffer {
            depth: texture("host depth", DEPTH_FORMAT),
            normal: texture("host normals", NORMAL_FORMAT),
            face_normal: texture("host face normals", NORMAL_FORMAT),
            albedo: texture("host albedo", ALBEDO_FORMAT),
            position: texture("host positions", POSITION_FORMAT),
        }
    }
}

/// The view and projection matrices of `camera` for a `width`×`height` image, in wgpu's
/// conventions: the same pixel rays as penumbra's own pinhole camera.
pub fn camera_matrices(camera: &Camera, scene_diagonal: f32, width: u32, height: u32) -> (Mat4, Mat4) {
    let view = glam::camera::rh::view::look_at_mat4(camera.eye, camera.target, camera.up);
    let projection = glam::camera::rh::proj::directx::perspective(
        camera.fov_y_degrees.to_radians(),
        width as f32 / height as f32,
        NEAR * scene_diagonal,
        FAR * scene_diagonal,
    );
    (view, projection)
}

/// The G-buffer pipelines and the scene's vertices.
pub struct Rasterizer {
    gbuffer: wgpu::RenderPipeline,
    position: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    vertices: wgpu::Buffer,
    vertex_count: u32,
}

impl Rasterizer {
    /// Pipelines for `device` and a vertex buffer with every triangle of `scene` (flat
    /// albedo: each material's base colour factor; textures are ignored).
    pub fn new(device: &wgpu::Device, scene: &Scene) -> Rasterizer {
        let vertices: Vec<Vertex> = scene
            .triangles
            .iter()
            .flat_map(|t| {
                let [a, b, c] = t.positions;
                let face = (b - a).cross(c - a).normalize_or(Vec3::Y);
                let m = scene.materials[t.material as usize].base_color_factor;
                (0..3).map(move |k| Vertex {
                    position: t.positions[k].to_array(),
                    normal: t.normals[k].to_array(),
                    face_normal: face.to_array(),
                    albedo: [m[0], m[1], m[2]],
                })
            })
            .collect();
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("host vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("host raster"),
            source: wgpu::ShaderSource::Wgsl(include_str!("raster.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("host camera"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("host raster"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let attributes =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3];
        let pipeline = |entry: &str,
                        targets: &[Option<wgpu::ColorTargetState>],
                        depth_compare: wgpu::CompareFunction| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[Some(wgpu::VertexBufferLayout {
                        array_stride: size_of::<Vertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &attributes,
                    })],
                },
                // No culling: penumbra's camera rays hit back faces too.
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_compare == wgpu::CompareFunction::Less),
                    depth_compare: Some(depth_compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let target = |format: wgpu::TextureFormat| Some(wgpu::ColorTargetState::from(format));
        Rasterizer {
            gbuffer: pipeline(
                "fs_gbuffer",
                &[
                    target(NORMAL_FORMAT),
                    target(NORMAL_FORMAT),
                    target(ALBEDO_FORMAT),
                ],
                wgpu::CompareFunction::Less,
            ),
            // Drawn after the G-buffer pass over its depth: only the nearest surface passes
            // (the clip position is @invariant, so equal depths compare equal).
            position: pipeline(
                "fs_position",
                &[target(POSITION_FORMAT)],
                wgpu::CompareFunction::LessEqual,
            ),
            layout,
            vertices: vertex_buffer,
            vertex_count: vertices.len() as u32,
        }
    }

    /// Records the G-buffer pass (depth, normals, albedo) and, with `positions`, the
    /// world-position pass into `encoder`, seen through `view_proj = projection × view`.
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        view_proj: Mat4,
        target: &HostGBuffer,
        positions: bool,
    ) {
        let camera = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("host camera"),
            contents: bytemuck::cast_slice(&view_proj.to_cols_array()),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("host camera"),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        let view = |t: &wgpu::Texture| t.create_view(&Default::default());
        let depth = view(&target.depth);
        fn clear(v: &wgpu::TextureView) -> Option<wgpu::RenderPassColorAttachment<'_>> {
            Some(wgpu::RenderPassColorAttachment {
                view: v,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        }
        let (normal, face, albedo, position) = (
            view(&target.normal),
            view(&target.face_normal),
            view(&target.albedo),
            view(&target.position),
        );
        let mut passes = vec![(
            &self.gbuffer,
            vec![clear(&normal), clear(&face), clear(&albedo)],
            wgpu::LoadOp::Clear(1.0),
        )];
        if positions {
            passes.push((&self.position, vec![clear(&position)], wgpu::LoadOp::Load));
        }
        for (pipeline, colors, depth_load) in passes {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host G-buffer"),
                color_attachments: &colors,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: depth_load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.set_vertex_buffer(0, self.vertices.slice(..));
            pass.draw(0..self.vertex_count, 0..1);
        }
    }
}
