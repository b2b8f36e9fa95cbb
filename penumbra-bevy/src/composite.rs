//! Adds each quad light's diffuse light, times penumbra's visibility, to the camera's HDR
//! target after Bevy's main pass (`composite.wgsl`, additive blending). A raw wgpu
//! pipeline on Bevy's device: the shader is plain WGSL and needs none of Bevy's imports.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

/// Bevy's HDR view format (`ViewTarget::TEXTURE_FORMAT_HDR`), the one target format the
/// composite draws into.
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// `Params` of `composite.wgsl`, 128 bytes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct Params {
    world_from_clip: [[f32; 4]; 4],
    corner: [f32; 3],
    has_visibility: u32,
    edge_u: [f32; 3],
    width: f32,
    edge_v: [f32; 3],
    height: f32,
    scale: [f32; 3],
    pad: f32,
}

const _: () = assert!(size_of::<Params>() == 128);

/// What one light's composite reads.
pub struct CompositeInputs<'a> {
    /// Bevy's depth prepass texture (reversed Z, `Depth32Float`).
    pub depth: &'a wgpu::Texture,
    /// Bevy's normal prepass texture (`n · ½ + ½`).
    pub normal: &'a wgpu::Texture,
    /// penumbra's filtered visibility, or `None` for a light nothing blocks (no casters).
    pub visibility: Option<&'a wgpu::Texture>,
    /// Clip space to world space, penumbra's glam.
    pub world_from_clip: glam::Mat4,
    /// The light, world space.
    pub light: &'a penumbra::scene::view::QuadLight,
    /// The camera's exposure (Bevy's `ExtractedCamera::exposure`).
    pub exposure: f32,
    /// Diffuse albedo of every surface for this light.
    pub albedo: f32,
}

/// The composite pipeline.
pub struct Composite {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// Bound when no visibility texture is (never read then).
    white: wgpu::TextureView,
}

impl Composite {
    /// Builds the pipeline on `device`.
    pub fn new(device: &wgpu::Device) -> Composite {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("penumbra-bevy composite"),
            source: wgpu::ShaderSource::Wgsl(include_str!("composite.wgsl").into()),
        });
        let texture = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let unfiltered = wgpu::TextureSampleType::Float { filterable: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("penumbra-bevy composite"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                texture(1, wgpu::TextureSampleType::Depth),
                texture(2, unfiltered),
                texture(3, unfiltered),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("penumbra-bevy composite"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let keep = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Zero,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("penumbra-bevy composite"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: wgpu::MultisampleState::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: HDR_FORMAT,
                    blend: Some(wgpu::BlendState {
                        color: add,
                        alpha: keep,
                    }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let white = device
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("penumbra-bevy no visibility"),
                size: wgpu::Extent3d::default(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: penumbra::gpu::VISIBILITY_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
            .create_view(&Default::default());
        Composite {
            pipeline,
            layout,
            white,
        }
    }

    /// Records one light's composite into `encoder`, drawing into `target` (an
    /// [`HDR_FORMAT`] view the size of the inputs).
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        inputs: &CompositeInputs<'_>,
    ) {
        let light = inputs.light;
        let size = inputs.depth.size();
        let scale = light.color * light.intensity * inputs.albedo / std::f32::consts::PI * inputs.exposure;
        let params = Params {
            world_from_clip: inputs.world_from_clip.to_cols_array_2d(),
            corner: light.corner.to_array(),
            has_visibility: u32::from(inputs.visibility.is_some()),
            edge_u: light.edge_u.to_array(),
            width: size.width as f32,
            edge_v: light.edge_v.to_array(),
            height: size.height as f32,
            scale: scale.to_array(),
            pad: 0.0,
        };
        let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("penumbra-bevy composite params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let depth = inputs.depth.create_view(&wgpu::TextureViewDescriptor {
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let normal = inputs.normal.create_view(&Default::default());
        let visibility = inputs.visibility.map(|t| t.create_view(&Default::default()));
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("penumbra-bevy composite"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: buffer.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&depth),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::TextureView(&normal),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: wgpu::BindingResource::TextureView(visibility.as_ref().unwrap_or(&self.white)),
                },
            ],
        });
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("penumbra-bevy composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }
}
