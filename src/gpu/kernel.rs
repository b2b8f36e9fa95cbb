//! Compute pipelines with explicit bind group layouts (with `layout: None`,
//! wgpu drops bindings a kernel does not use and bind groups stop matching). The
//! layout is read from the kernel's own declarations ([`reflect_bindings`]), so no
//! binding list is typed by hand.

use std::sync::OnceLock;

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
    /// `acceleration_structure` (a TLAS, for ray queries).
    AccelerationStructure,
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
            Binding::AccelerationStructure => {
                wgpu::BindingType::AccelerationStructure { vertex_return: false }
            }
        }
    }
}

/// What group 0 of a kernel declares, in binding order: each binding's kind and the name
/// of its variable. Errors name the variable whose kind [`Binding`] has no case for,
/// a binding outside group 0, or a gap in the numbers (binding `i` must be the `i`-th).
pub fn reflect_bindings(module: &naga::Module) -> std::result::Result<Vec<(Binding, String)>, String> {
    use naga::{
        AddressSpace, ImageClass, ImageDimension, ScalarKind, StorageAccess, StorageFormat, TypeInner,
    };
    let mut found = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(rb) = &var.binding else { continue };
        let name = var.name.clone().unwrap_or_default();
        if rb.group != 0 {
            return Err(format!(
                "`{name}` is in group {}; kernels use group 0 only",
                rb.group
            ));
        }
        let binding = match (var.space, &module.types[var.ty].inner) {
            (AddressSpace::Uniform, _) => Binding::Uniform,
            (AddressSpace::Storage { access }, _) if access.contains(StorageAccess::STORE) => {
                Binding::ReadWrite
            }
            (AddressSpace::Storage { .. }, _) => Binding::ReadOnly,
            (
                AddressSpace::Handle,
                &TypeInner::Image {
                    dim: ImageDimension::D2,
                    arrayed: false,
                    class,
                },
            ) => match class {
                ImageClass::Depth { multi: false } => Binding::DepthTexture,
                ImageClass::Sampled {
                    kind: ScalarKind::Float,
                    multi: false,
                } => Binding::FloatTexture,
                ImageClass::Storage {
                    format: StorageFormat::R32Float,
                    access,
                } if access == StorageAccess::STORE => Binding::StorageTexture(wgpu::TextureFormat::R32Float),
                other => return Err(format!("`{name}`: no bind group layout for a {other:?} texture")),
            },
            (AddressSpace::Handle, TypeInner::AccelerationStructure { vertex_return: false }) => {
                Binding::AccelerationStructure
            }
            (space, inner) => return Err(format!("`{name}`: no bind group layout for {space:?} {inner:?}")),
        };
        found.push((rb.binding, binding, name));
    }
    found.sort_by_key(|f| f.0);
    if let Some((i, f)) = found.iter().enumerate().find(|(i, f)| f.0 != *i as u32) {
        return Err(format!(
            "binding {i} is missing (the next is `{}` at {})",
            f.2, f.0
        ));
    }
    Ok(found.into_iter().map(|(_, b, n)| (b, n)).collect())
}

/// A compute pipeline for entry point `main` and the layout of its group 0.
#[derive(Debug)]
pub struct Kernel {
    /// The pipeline.
    pub pipeline: wgpu::ComputePipeline,
    /// Layout of bind group 0, as [`Kernel::bindings`] says.
    pub layout: wgpu::BindGroupLayout,
    /// The kernel's name (its file under `shaders/`).
    pub name: String,
    /// Binding `i` of group 0: its kind and its variable's name in the kernel.
    pub bindings: Vec<(Binding, String)>,
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
    /// Assembles `main` with `aliases`, validates it with naga and builds its pipeline,
    /// with the bind group layout its declarations give ([`reflect_bindings`]).
    pub fn new(
        ctx: &GpuContext,
        main: &str,
        aliases: Aliases<'_>,
        constants: &[(&str, f64)],
        checks: Checks,
    ) -> Result<Kernel> {
        let source =
            shaders::assemble(main, aliases).map_err(|e| Error::Gpu(format!("shader {main}: {e}")))?;
        let module = shaders::validate(&source).map_err(|e| Error::Gpu(format!("shader {main}: {e}")))?;
        let bindings = reflect_bindings(&module).map_err(|e| Error::Gpu(format!("shader {main}: {e}")))?;
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
                .map(|(i, (b, _))| wgpu::BindGroupLayoutEntry {
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
                bindings,
            }
        })
    }

    /// A bind group from `(variable name, resource)` pairs, given in binding order: pair
    /// `i` must name the kernel's binding `i` ([`Kernel::bindings`]), so a call site reads
    /// like the shader's declarations and a mismatch is an error naming both sides
    /// ([`check_binding_names`]), not a wrong buffer bound.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &[(&str, wgpu::BindingResource<'_>)],
    ) -> Result<wgpu::BindGroup> {
        let given: Vec<&str> = resources.iter().map(|(name, _)| *name).collect();
        check_binding_names(&self.name, &self.bindings, &given).map_err(Error::Gpu)?;
        let entries: Vec<wgpu::BindGroupEntry> = (0u32..)
            .zip(resources)
            .map(|(binding, (_, resource))| wgpu::BindGroupEntry {
                binding,
                resource: resource.clone(),
            })
            .collect();
        Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&self.name),
            layout: &self.layout,
            entries: &entries,
        }))
    }
}

/// A tracing kernel in two builds: without the alpha test, which scenes without
/// alpha-tested triangles run, and with it, built the first time such a scene needs it.
/// The first has `ALPHA_TEST` false (the override every tracing kernel declares in
/// `shared/layout`; the driver removes the test's code) and, in the shadow kernels that
/// bind the alpha words, [`crate::shaders::NO_ALPHA`] in place of that binding. So opaque
/// scenes run the kernels as if masks did not exist: on lavapipe, which runs both sides of
/// a branch that lanes take differently, the test's code cost 4.5–8.8× where no triangle
/// had a mask, and on Mesa 25 a ninth binding alone cost the per-ray kernel about 30 %.
#[derive(Debug)]
pub struct AlphaKernels {
    opaque: Kernel,
    alpha: OnceLock<Kernel>,
    main: &'static str,
    aliases: Vec<(&'static str, &'static str)>,
    constants: Vec<(&'static str, f64)>,
    checks: Checks,
    device: wgpu::Device,
    queue: wgpu::Queue,
}

impl AlphaKernels {
    /// Builds the kernel without the alpha test ([`Kernel::new`]'s arguments).
    pub fn new(
        ctx: &GpuContext,
        main: &'static str,
        aliases: Aliases<'static>,
        constants: &[(&'static str, f64)],
        checks: Checks,
    ) -> Result<AlphaKernels> {
        let mut opaque_constants = constants.to_vec();
        opaque_constants.push(("ALPHA_TEST", 0.0));
        let mut opaque_aliases = aliases.to_vec();
        opaque_aliases.push(crate::shaders::NO_ALPHA);
        Ok(AlphaKernels {
            opaque: Kernel::new(ctx, main, &opaque_aliases, &opaque_constants, checks)?,
            alpha: OnceLock::new(),
            main,
            aliases: aliases.to_vec(),
            constants: constants.to_vec(),
            checks,
            device: ctx.device.clone(),
            queue: ctx.queue.clone(),
        })
    }

    /// The build that `scene` needs: with the alpha test when it has alpha-tested triangles.
    pub fn for_scene(&self, scene: &super::GpuScene) -> Result<&Kernel> {
        if scene.alpha_triangles == 0 {
            return Ok(&self.opaque);
        }
        if let Some(kernel) = self.alpha.get() {
            return Ok(kernel);
        }
        let mut constants = self.constants.clone();
        constants.push(("ALPHA_TEST", 1.0));
        let ctx = GpuContext::from_device(&self.device, &self.queue);
        let kernel = Kernel::new(&ctx, self.main, &self.aliases, &constants, self.checks)?;
        // Another thread may have built it meanwhile: either build is the same pipeline.
        Ok(self.alpha.get_or_init(|| kernel))
    }
}

/// `(name, whole buffer)` for [`Kernel::bind`].
pub fn buffer<'a>(name: &'a str, buffer: &'a wgpu::Buffer) -> (&'a str, wgpu::BindingResource<'a>) {
    (name, buffer.as_entire_binding())
}

/// `(name, texture view)` for [`Kernel::bind`].
pub fn texture<'a>(name: &'a str, view: &'a wgpu::TextureView) -> (&'a str, wgpu::BindingResource<'a>) {
    (name, wgpu::BindingResource::TextureView(view))
}

/// Checks that `given[i]` is the name of `kernel`'s binding `i` for every binding, and
/// that no binding is missing or extra; the error names the kernel, the binding number and
/// both names.
pub fn check_binding_names(
    kernel: &str,
    bindings: &[(Binding, String)],
    given: &[&str],
) -> std::result::Result<(), String> {
    for (i, (declared, host)) in bindings.iter().map(|(_, n)| n.as_str()).zip(given).enumerate() {
        if declared != *host {
            return Err(format!(
                "kernel {kernel}: binding {i} is `{declared}` in the shader but `{host}` on the host"
            ));
        }
    }
    if given.len() != bindings.len() {
        let declared: Vec<&str> = bindings.iter().map(|(_, n)| n.as_str()).collect();
        return Err(format!(
            "kernel {kernel}: the shader declares {} bindings ({}), the host gives {} ({})",
            bindings.len(),
            declared.join(", "),
            given.len(),
            given.join(", ")
        ));
    }
    Ok(())
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The binding kinds [`reflect_bindings`] reads from `wgsl`.
    fn kinds(wgsl: &str) -> std::result::Result<Vec<Binding>, String> {
        let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.to_string())?;
        Ok(reflect_bindings(&module)?.into_iter().map(|(b, _)| b).collect())
    }

    /// [`kinds`] of a kernel as the passes assemble it.
    fn kernel_kinds(kernel: &str, aliases: Aliases<'_>) -> std::result::Result<Vec<Binding>, String> {
        let source = crate::shaders::assemble(kernel, aliases)?;
        crate::shaders::validate(&source)?;
        kinds(&source)
    }

    /// Every binding kind is read from its declaration, in binding order whatever the
    /// order of the declarations; a gap or an unsupported kind is an error naming it.
    #[test]
    fn bindings_are_read_from_the_declarations() {
        let wgsl = "
            @group(0) @binding(2) var<storage, read_write> out: array<u32>;
            @group(0) @binding(0) var<uniform> params: vec4<u32>;
            @group(0) @binding(1) var<storage, read> input: array<u32>;
            @group(0) @binding(3) var depth: texture_depth_2d;
            @group(0) @binding(4) var colour: texture_2d<f32>;
            @group(0) @binding(5) var target_: texture_storage_2d<r32float, write>;
            @compute @workgroup_size(1) fn main() {}
        ";
        use Binding::*;
        assert_eq!(
            kinds(wgsl).unwrap(),
            [
                Uniform,
                ReadOnly,
                ReadWrite,
                DepthTexture,
                FloatTexture,
                StorageTexture(wgpu::TextureFormat::R32Float)
            ]
        );
        let err = kinds(
            "@group(0) @binding(1) var<uniform> p: vec4<u32>; @compute @workgroup_size(1) fn main() {}",
        )
        .unwrap_err();
        assert!(
            err.contains("binding 0 is missing") && err.contains("`p`"),
            "{err}"
        );
        let err =
            kinds("@group(0) @binding(0) var t: texture_2d<u32>; @compute @workgroup_size(1) fn main() {}")
                .unwrap_err();
        assert!(err.contains("`t`"), "{err}");
    }

    /// Names given in binding order pass; a swapped pair, a missing or an extra name
    /// fails naming the kernel and both sides.
    #[test]
    fn binding_names_are_checked_against_the_shader() {
        let module = naga::front::wgsl::parse_str(
            "@group(0) @binding(0) var<uniform> params: vec4<u32>;
             @group(0) @binding(1) var<storage, read_write> masks: array<u32>;
             @compute @workgroup_size(1) fn main() {}",
        )
        .unwrap();
        let bindings = reflect_bindings(&module).unwrap();
        assert_eq!(check_binding_names("k", &bindings, &["params", "masks"]), Ok(()));
        let err = check_binding_names("k", &bindings, &["masks", "params"]).unwrap_err();
        assert_eq!(
            err,
            "kernel k: binding 0 is `params` in the shader but `masks` on the host"
        );
        let err = check_binding_names("k", &bindings, &["params"]).unwrap_err();
        assert!(
            err.contains("declares 2 bindings (params, masks)") && err.contains("gives 1 (params)"),
            "{err}"
        );
        let err = check_binding_names("k", &bindings, &["params", "masks", "extra"]).unwrap_err();
        assert!(err.contains("gives 3"), "{err}");
    }

    /// Every kernel variant the passes build has a layout the reflection can make.
    #[test]
    fn every_kernel_variant_has_a_bind_group_layout() {
        for &(kernel, variants) in crate::shaders::KERNELS {
            for &aliases in variants {
                let bindings =
                    kernel_kinds(kernel, aliases).unwrap_or_else(|e| panic!("{kernel} {aliases:?}: {e}"));
                assert!(!bindings.is_empty(), "{kernel}: no bindings");
            }
        }
        // The embedded pass's storage texture is the format its targets are made in.
        let kinds = kernel_kinds("visibility_to_texture", &[]).unwrap();
        assert!(
            kinds.contains(&Binding::StorageTexture(crate::gpu::VISIBILITY_FORMAT)),
            "{kinds:?}"
        );
    }
}
