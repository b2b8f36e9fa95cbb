//! Compute pipelines with explicit bind group layouts (with `layout: None`,
//! wgpu drops bindings a kernel does not use and bind groups stop matching).

use super::GpuContext;
use crate::shaders::{self, Aliases};
use crate::{Error, Result};

/// What a binding of group 0 holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    ReadOnly,
    /// `var<storage, read_write>`.
    ReadWrite,
    /// `texture_depth_2d`, read with `textureLoad` (any depth format, single-sampled).
    DepthTexture,
    /// `texture_2d<f32>`, read with `textureLoad` (unfilterable float: any float or
    /// normalized colour format, `Rgba32Float` included).
    FloatTexture,
    /// `texture_storage_2d<FORMAT, write>`.
    StorageTexture(wgpu::TextureFormat),
}

impl Binding {
    fn layout_type(self) -> wgpu::BindingType {
        let buffer = |ty| wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        };
        let texture = |sample_type| wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        match self {
            Binding::Uniform => buffer(wgpu::BufferBindingType::Uniform),
            Binding::ReadOnly => buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            Binding::ReadWrite => buffer(wgpu::BufferBindingType::Storage { read_only: false }),
            Binding::DepthTexture => texture(wgpu::TextureSampleType::Depth),
            Binding::FloatTexture => texture(wgpu::TextureSampleType::Float { filterable: false }),
            Binding::StorageTexture(format) => wgpu::BindingType::StorageTexture {
                access: wgpu::StorageTextureAccess::WriteOnly,
                format,
                view_dimension: wgpu::TextureViewDimension::D2,
            },
        }
    }
}

/// A compute pipeline for entry point `main` and the layout of its group 0.
#[derive(Debug)]
pub struct Kernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Layout of bind group 0: binding `i` is `bindings[i]`.
    pub layout: wgpu::BindGroupLayout,
    /// The kernel's name (its file under `shaders/`).
    pub name: String,
}

/// How much naga may guard a kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Checks {
    /// Bounds checks and loop bounding, as wgpu does by default.
    Checked,
    /// No runtime checks: only for kernels whose every index the host has
    /// validated (the BVH's node and triangle ranges, buffer sizes) or the
    /// kernel clamps itself. Loop bounding doubles the cost of tight loops on
    /// lavapipe (DESIGN.md).
    Unchecked,
}

impl Kernel {
    /// Assembles `main` with `aliases`, validates it with naga and builds its pipeline.
    pub fn new(
        ctx: &GpuContext,
        main: &str,
        aliases: Aliases<'_>,
        bindings: &[Binding],
        constants: &[(&str, f64)],
        checks: Checks,
    ) -> Result<Kernel> {
        let source =
            shaders::assemble(main, aliases).map_err(|e| Error::Gpu(format!("shader {main}: {e}")))?;
        shaders::validate(&source).map_err(|e| Error::Gpu(format!("shader {main}: {e}")))?;
        ctx.capture_errors(main, || {
            let desc = wgpu::ShaderModuleDescriptor {
                label: Some(main),
                source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
            };
            let module = match checks {
                Checks::Checked => ctx.device.create_shader_module(desc),
                // SAFETY: the caller vouches for the kernel's indices (see `Checks::Unchecked`).
                Checks::Unchecked => unsafe {
                    ctx.device
                        .create_shader_module_trusted(desc, wgpu::ShaderRuntimeChecks::unchecked())
                },
            };
            let entries: Vec<wgpu::BindGroupLayoutEntry> = bindings
                .iter()
                .enumerate()
                .map(|(i, b)| wgpu::BindGroupLayoutEntry {
                    binding: i as u32,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: b.layout_type(),
                    count: None,
                })
                .collect();
            let layout = ctx
                .device
                .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(main),
                    entries: &entries,
                });
            let pipeline_layout = ctx
                .device
                .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                    label: Some(main),
                    bind_group_layouts: &[Some(&layout)],
                    immediate_size: 0,
                });
            let pipeline = ctx
                .device
                .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(main),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some("main"),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants,
                        zero_initialize_workgroup_memory: false,
                    },
                    cache: None,
                });
            Kernel {
                pipeline,
                layout,
                name: main.to_owned(),
            }
        })
    }

    /// A bind group with `buffers[i]` (whole) at binding `i`.
    pub fn bind(&self, ctx: &GpuContext, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        self.bind_on(&ctx.device, buffers)
    }

    /// [`Kernel::bind`] on a bare device (for passes recorded into a host's encoder).
    pub fn bind_on(&self, device: &wgpu::Device, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
        let resources: Vec<wgpu::BindingResource> = buffers.iter().map(|b| b.as_entire_binding()).collect();
        self.bind_resources(device, resources)
    }

    /// A bind group with `resources[i]` at binding `i`, for kernels that bind textures.
    pub fn bind_resources(
        &self,
        device: &wgpu::Device,
        resources: Vec<wgpu::BindingResource<'_>>,
    ) -> wgpu::BindGroup {
        let entries: Vec<wgpu::BindGroupEntry> = resources
            .into_iter()
            .enumerate()
            .map(|(i, resource)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource,
            })
            .collect();
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.name),
            layout: &self.layout,
            entries: &entries,
        })
    }
}

impl Kernel {
    /// Records one compute pass named `label` that runs this kernel over
    /// `groups` workgroups with `bind` as group 0.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        bind: &wgpu::BindGroup,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
        groups: (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, bind, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }
}

/// A uniform buffer holding `value`.
pub fn uniform_buffer<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    uniform_buffer_on(&ctx.device, label, value)
}

/// [`uniform_buffer`] on a bare device.
pub fn uniform_buffer_on<T: bytemuck::Pod>(device: &wgpu::Device, label: &str, value: &T) -> wgpu::Buffer {
    use wgpu::util::DeviceExt;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}
