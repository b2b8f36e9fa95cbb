//! A small wgpu application that adds penumbra's soft shadows to its own frame:
//! it creates its own device, rasterizes the default scene into its own G-buffer
//! (depth, normals, albedo), records [`ShadowPass`] into its command encoder, shades
//! with the filtered visibility texture in its own pass, and saves a PNG. Headless:
//! it runs on lavapipe.
//!
//! ```text
//! cargo run --release --example embed -- [OUT.png] [WIDTHxHEIGHT]
//! ```
//!
//! Defaults: `embed.png`, 512x384.

mod raster;

use std::path::PathBuf;
use std::time::Instant;

use glam::Mat4;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{
    GpuContext, GpuScene, NormalEncoding, ShadowInputs, ShadowPass, ShadowSettings, ShadowTargets,
    SurfaceInput, read_texture,
};
use penumbra::output::{HdrImage, ToneMap, write_image};
use penumbra::scene::Scene;
use penumbra::{assets, scene::view::QuadLight};
use raster::{HostGBuffer, Rasterizer, camera_matrices};
use wgpu::util::DeviceExt;

/// The composite pass's uniform (WGSL `Lighting` in composite.wgsl), 112 bytes.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Lighting {
    clip_to_world: [[f32; 4]; 4],
    eye: [f32; 3],
    light_area: f32,
    light_center: [f32; 3],
    ambient: f32,
    light_normal: [f32; 3],
    width: f32,
    radiance: [f32; 3],
    height: f32,
}

const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

fn main() {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists. This host
    // rasterizes, so lavapipe keeps its 8 lanes (see the function's docs).
    unsafe { penumbra::gpu::set_driver_defaults_for_drawing() };
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn parse_args() -> Result<(PathBuf, u32, u32), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() > 2 {
        return Err("usage: embed [OUT.png] [WIDTHxHEIGHT]".into());
    }
    let path = PathBuf::from(args.first().map_or("embed.png", String::as_str));
    let (w, h) = match args.get(1) {
        None => (512, 384),
        Some(size) => size
            .split_once('x')
            .and_then(|(w, h)| Some((w.parse().ok()?, h.parse().ok()?)))
            .filter(|&(w, h)| w > 0 && h > 0)
            .ok_or_else(|| format!("size '{size}': expected WIDTHxHEIGHT, e.g. 512x384"))?,
    };
    Ok((path, w, h))
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (path, width, height) = parse_args()?;

    // The host's device: its own choice of adapter, with what the shadow pass needs on top
    // of what the host's rendering needs (here: WebGPU's downlevel defaults).
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("embed example"),
        required_features: ShadowPass::required_features() | (adapter.features() & wgpu::Features::SUBGROUP),
        required_limits:
            wgpu::Limits::downlevel_defaults().or_better_values_from(&ShadowPass::required_limits()),
        ..Default::default()
    }))?;

    // Once: the scene (CPU and GPU), the pass, its targets, the host's pipelines.
    let default = assets::default_scene();
    let scene = Scene::from_bytes(default.glb, std::path::Path::new(default.file_name))?;
    let view = default.view();
    let ctx = GpuContext::from_device(&device, &queue);
    let gpu_scene = GpuScene::new(&ctx, &scene, &Bvh::build(&scene, &BvhSettings::default())?)?;
    let pass = ShadowPass::new(&ctx, ShadowSettings::default())?;
    let targets = ShadowTargets::new(&ctx, width, height)?;
    let rasterizer = Rasterizer::new(&device, &scene);
    let gbuffer = HostGBuffer::new(&device, width, height);
    let compositor = Compositor::new(&device);
    let output = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("embed output"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: OUTPUT_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });

    // One frame: G-buffer → shadows → shading, in one encoder, one submission.
    let start = Instant::now();
    let (view_matrix, projection) = camera_matrices(&view.camera, scene.bounds().diagonal(), width, height);
    let mut encoder = device.create_command_encoder(&Default::default());
    rasterizer.record(&device, &mut encoder, projection * view_matrix, &gbuffer, false);
    let inputs = ShadowInputs {
        surface: SurfaceInput::Depth {
            texture: &gbuffer.depth,
            view: view_matrix,
            projection,
            background_depth: 1.0,
        },
        normal: &gbuffer.normal,
        geometric_normal: Some(&gbuffer.face_normal),
        normal_encoding: NormalEncoding::Signed,
        light: &view.light,
    };
    pass.record(&mut encoder, &gpu_scene, &inputs, &targets)?;
    compositor.record(
        &device,
        &mut encoder,
        &gbuffer,
        &targets.filtered,
        &output,
        &lighting(
            &view.light,
            view.camera.eye,
            projection * view_matrix,
            width,
            height,
        ),
    );
    queue.submit([encoder.finish()]);
    let pixels: Vec<[f32; 4]> = read_texture(&ctx, &output)?;
    let frame_ms = start.elapsed().as_secs_f64() * 1e3;

    let unfinished = targets.unfinished_tiles(&ctx)?;
    if unfinished > 0 {
        eprintln!("warning: {unfinished} tiles unfinished; raise ShadowSettings::resume_rounds");
    }
    let image = HdrImage {
        width,
        height,
        pixels: pixels.iter().map(|p| [p[0], p[1], p[2]]).collect(),
    };
    write_image(&path, &image, &ToneMap::default())?;
    println!(
        "{}: {width}x{height}, {} vector, frame {frame_ms:.0} ms (wall, incl. readback), on {}",
        path.display(),
        pass.variant(),
        ctx.info.name
    );
    Ok(())
}

/// The composite pass's uniform for `light`, seen from `eye` through `view_proj`.
fn lighting(light: &QuadLight, eye: glam::Vec3, view_proj: Mat4, width: u32, height: u32) -> Lighting {
    let normal = light.area_normal();
    Lighting {
        clip_to_world: view_proj.inverse().to_cols_array_2d(),
        eye: eye.to_array(),
        light_area: normal.length(),
        light_center: light.center().to_array(),
        ambient: 0.08,
        light_normal: normal.normalize().to_array(),
        width: width as f32,
        radiance: (light.color * light.intensity).to_array(),
        height: height as f32,
    }
}

/// The host's lighting pass: a full-screen triangle reading its G-buffer and penumbra's
/// visibility texture.
struct Compositor {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

impl Compositor {
    fn new(device: &wgpu::Device) -> Compositor {
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
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("composite"),
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
                texture(2, float),
                texture(3, float),
                // penumbra's visibility: R32Float, read with textureLoad (unfilterable).
                texture(4, float),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("composite"),
            source: wgpu::ShaderSource::Wgsl(include_str!("composite.wgsl").into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("composite"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("composite"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(OUTPUT_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        Compositor { pipeline, layout }
    }

    fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        gbuffer: &HostGBuffer,
        visibility: &wgpu::Texture,
        output: &wgpu::Texture,
        lighting: &Lighting,
    ) {
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("lighting"),
            contents: bytemuck::bytes_of(lighting),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let views = [&gbuffer.depth, &gbuffer.normal, &gbuffer.albedo, visibility]
            .map(|t| t.create_view(&Default::default()));
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }];
        entries.extend(views.iter().enumerate().map(|(i, v)| wgpu::BindGroupEntry {
            binding: i as u32 + 1,
            resource: wgpu::BindingResource::TextureView(v),
        }));
        let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("composite"),
            layout: &self.layout,
            entries: &entries,
        });
        let target = output.create_view(&Default::default());
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("composite"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &target,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..Default::default()
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.draw(0..3, 0..1);
    }
}
