//! The shadow pass for applications that draw their own frame with wgpu: built on the
//! host's device, recorded into the host's command encoder, fed by the host's G-buffer
//! textures, writing visibility textures the host samples when it shades.
//!
//! Per frame, [`ShadowPass::record`] records (no submission, no waiting):
//!
//! 1. `embed/gbuffer`: the host's depth (or world-position) and normal textures →
//!    penumbra's G-buffer (`shaders/gbuffer_from_depth.wgsl` or `_position.wgsl`);
//! 2. `shadow/trace`: multi-frusta tracing, 16 rays per pixel towards the pixel's
//!    interleaved set of light samples (the standalone renderer's kernel), with a fixed
//!    number of resume rounds ([`ShadowSettings::resume_rounds`]);
//! 3. `embed/visibility`: masks → unfiltered visibility texture;
//! 4. `filter` (optional): the 4×4 discontinuity filter → filtered visibility texture.
//!
//! Nothing is global: several passes, scenes and targets can live on one device, and one
//! pass can serve several scenes (the scene is an argument of `record`).
//!
//! ```no_run
//! use penumbra::gpu::{GpuContext, GpuScene, NormalEncoding, ShadowInputs, ShadowPass, ShadowSettings, ShadowTargets, SurfaceInput};
//! use penumbra::{assets, bvh::{Bvh, BvhSettings}, scene::Scene};
//! # fn frame(device: &wgpu::Device, queue: &wgpu::Queue, depth: &wgpu::Texture,
//! #          normals: &wgpu::Texture, view: glam::Mat4, projection: glam::Mat4) -> penumbra::Result<()> {
//! // Once: wrap the host's device, upload the scene, build the pass and its targets.
//! let ctx = GpuContext::from_device(device, queue);
//! let default = assets::default_scene();
//! let scene = Scene::from_bytes(default.glb, std::path::Path::new(default.file_name))?;
//! let gpu_scene = GpuScene::new(&ctx, &scene, &Bvh::build(&scene, &BvhSettings::default())?)?;
//! let pass = ShadowPass::new(&ctx, ShadowSettings::default())?;
//! let targets = ShadowTargets::new(&ctx, 1280, 720)?;
//!
//! // Every frame, after the host's G-buffer pass and before its lighting pass:
//! let mut encoder = device.create_command_encoder(&Default::default());
//! // ... the host renders `depth` and `normals` here ...
//! let light = default.view().light;
//! let inputs = ShadowInputs {
//!     surface: SurfaceInput::Depth { texture: depth, view, projection, background_depth: 1.0 },
//!     normal: normals,
//!     geometric_normal: None,
//!     normal_encoding: NormalEncoding::Signed,
//!     light: &light,
//! };
//! pass.record(&mut encoder, &gpu_scene, &inputs, &targets)?;
//! // ... the host's lighting pass samples targets.filtered ...
//! queue.submit([encoder.finish()]);
//! # Ok(()) }
//! ```
//!
//! `examples/embed/` is a complete headless application doing exactly this.

mod inputs;
mod targets;

pub use inputs::{NormalEncoding, ShadowInputs, SurfaceInput};
pub use targets::{ShadowTargets, VISIBILITY_FORMAT};

use super::kernel::{Checks, Kernel, buffer, texture, uniform_buffer_on};
use super::shadow_stages::{ShadowStages, VisibilityStage};
use super::{GpuContext, GpuScene, LeafMode, ShadowImage, TracerOptions, VectorVariant};
use crate::contract::ITERATION_BUDGET;
use crate::contract::filter::FilterParams;
use crate::contract::groups::PIXEL_GROUP;
use crate::contract::layout::{ImageSize, NORMALS_BIASED, NORMALS_SIGNED, SurfaceParams};
use crate::contract::shadow::shadow_params;
use crate::pass_inputs::RAY_OFFSET_FRACTION;
use crate::{Error, Result};

/// How the embedded pass traces and filters. Rays per pixel are fixed at 16 (one sample
/// set of the 256-point pattern; the filter's 4-pixel box gathers all 256).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowSettings {
    /// The discontinuity filter's `(depth_tolerance, normal_tolerance)` (see
    /// [`FilterParams`]), or `None` to skip it: the filtered texture then repeats the
    /// unfiltered one. The filter turns 16 rays per pixel into an image close to 256 for
    /// one cheap pass; skip it only when the host filters or accumulates itself.
    pub filter: Option<(f32, f32)>,
    /// The 16-wide vector's implementation, or `None` for the device's best
    /// ([`VectorVariant::choose`]): subgroups where they are a fixed multiple of 16 wide
    /// (needs [`wgpu::Features::SUBGROUP`]), else workgroup memory, which every device runs.
    pub variant: Option<VectorVariant>,
    /// How the kernel's leaves use the lanes (same masks either way; speed differs).
    pub leaf_mode: LeafMode,
    /// Dispatches after the first that resume tiles which reached the per-dispatch
    /// iteration budget (lavapipe ends longer loops, DESIGN.md). Each costs one early
    /// exit per tile when nothing is left; too few leave tiles unfinished: their pixels
    /// keep the masks the targets held before (all rays unblocked in fresh targets), and
    /// [`ShadowTargets::unfinished_tiles`] counts them. With the default, 4, no tile of the
    /// shipped scenes even suspends in the tests and the example (46×38 to 512×384 on
    /// lavapipe); dense scenes, and smaller images of them, need more.
    pub resume_rounds: u32,
    /// Loop iterations a tile's vector may run in one dispatch before it saves its state
    /// and waits for the next round. The default, [`ITERATION_BUDGET`] (60,000), stays
    /// below lavapipe's limit of 65,535 per invocation; a device without such a limit may
    /// raise it (fewer rounds needed), a host that wants short dispatches may lower it
    /// (more rounds needed).
    pub iteration_budget: u32,
}

impl Default for ShadowSettings {
    fn default() -> Self {
        ShadowSettings {
            filter: Some((
                FilterParams::DEFAULT_DEPTH_TOLERANCE,
                FilterParams::DEFAULT_NORMAL_TOLERANCE,
            )),
            variant: None,
            leaf_mode: LeafMode::default(),
            resume_rounds: 4,
            iteration_budget: ITERATION_BUDGET,
        }
    }
}

/// The embedded shadow pass: pipelines for one device and settings (see the module docs).
#[derive(Debug)]
pub struct ShadowPass {
    device: wgpu::Device,
    settings: ShadowSettings,
    stages: ShadowStages,
    from_depth: Kernel,
    from_position: Kernel,
    to_texture: Kernel,
}

impl ShadowPass {
    /// Features the device must have: none. [`wgpu::Features::SUBGROUP`] is used when the
    /// device has it (and its subgroups are a fixed multiple of 16 wide), and required only
    /// when [`ShadowSettings::variant`] forces a subgroup variant
    /// ([`VectorVariant::uses_subgroups`]).
    pub fn required_features() -> wgpu::Features {
        wgpu::Features::empty()
    }

    /// Limits the device must have: small, every WebGPU device's defaults
    /// ([`wgpu::Limits::default`]) exceed them; `downlevel_defaults` (4 storage buffers
    /// per stage) do not. The shadow kernel binds 8 storage buffers (the maximum WebGPU
    /// guarantees; the 8th holds the alpha masks) and 9 bindings; the per-pixel kernels
    /// read 3 textures and write one storage texture; workgroups are at most 64
    /// invocations (8×8, or 4 subgroup vectors of 16) with under 2 KiB of workgroup
    /// memory; a dispatch has at most 128×128 workgroups along x. Storage bindings of
    /// 128 MiB hold a 64-byte G-buffer texel per pixel up to 1920×1080 and 2.8 M
    /// triangles; bigger images or scenes need a larger
    /// `max_storage_buffer_binding_size` ([`ShadowTargets::new`] and [`GpuScene::new`]
    /// report [`Error::BufferTooLarge`]).
    pub fn required_limits() -> wgpu::Limits {
        wgpu::Limits {
            max_bindings_per_bind_group: 9,
            max_storage_buffers_per_shader_stage: 8,
            max_sampled_textures_per_shader_stage: 3,
            max_storage_textures_per_shader_stage: 1,
            max_storage_buffer_binding_size: 128 << 20,
            max_compute_workgroup_storage_size: 2048,
            max_compute_invocations_per_workgroup: 64,
            max_compute_workgroup_size_x: 64,
            max_compute_workgroup_size_y: 8,
            max_compute_workgroup_size_z: 1,
            max_compute_workgroups_per_dimension: 128 * 128,
            ..wgpu::Limits::downlevel_webgl2_defaults()
        }
    }

    /// Builds the pipelines on `ctx`'s device ([`GpuContext::from_device`] wraps a host's).
    ///
    /// Errors: [`Error::DeviceUnsupported`] listing every missing feature and too-small
    /// limit (checked before any pipeline is made); [`Error::Gpu`] when a forced subgroup
    /// variant does not fit the device's subgroup size or a pipeline fails to build.
    pub fn new(ctx: &GpuContext, settings: ShadowSettings) -> Result<ShadowPass> {
        ShadowPass::check_device(&ctx.device, &settings)?;
        let kernel = |name: &str| Kernel::new(ctx, name, &[], &[], Checks::Checked);
        Ok(ShadowPass {
            device: ctx.device.clone(),
            settings,
            stages: ShadowStages::new(
                ctx,
                &TracerOptions {
                    variant: settings.variant,
                    leaf_mode: settings.leaf_mode,
                    ..TracerOptions::default()
                },
                VisibilityStage::Values,
            )?,
            from_depth: kernel("gbuffer_from_depth")?,
            from_position: kernel("gbuffer_from_position")?,
            to_texture: kernel("visibility_to_texture")?,
        })
    }

    /// Whether `device` has what a pass with `settings` needs (subgroups too when `settings`
    /// force the subgroup variant): [`Error::DeviceUnsupported`] listing every missing
    /// feature and too-small limit, as [`ShadowPass::new`] reports it. For hosts that check
    /// before they build (Bevy's `Plugin::finish`).
    pub fn check_device(device: &wgpu::Device, settings: &ShadowSettings) -> Result<()> {
        let mut missing = Vec::new();
        let mut features = ShadowPass::required_features();
        if settings.variant.is_some_and(VectorVariant::uses_subgroups) {
            features |= wgpu::Features::SUBGROUP;
        }
        let absent = features - device.features();
        for (name, _) in absent.iter_names() {
            missing.push(format!("feature {name}"));
        }
        ShadowPass::required_limits().check_limits_with_fail_fn(
            &device.limits(),
            false,
            |name, needed, has| missing.push(format!("{name} {has} (needs {needed})")),
        );
        if missing.is_empty() {
            Ok(())
        } else {
            Err(Error::DeviceUnsupported {
                what: "the embedded shadow pass".to_owned(),
                missing,
            })
        }
    }

    /// The settings the pass was built with.
    pub fn settings(&self) -> &ShadowSettings {
        &self.settings
    }

    /// The vector variant the shadow kernel runs.
    pub fn variant(&self) -> VectorVariant {
        self.stages.tracer.variant
    }

    /// Records the pass into the host's `encoder`: `inputs` (the host's textures, written
    /// earlier in the same encoder or before) → `targets.unfiltered` and
    /// `targets.filtered`, tracing against `scene` as it is on the GPU when the encoder
    /// is submitted. Creates small uniform buffers and bind groups; submits nothing.
    ///
    /// Errors ([`Error::InvalidInput`], nothing recorded): a texture of another size than
    /// `targets`, without `TEXTURE_BINDING`, multisampled, of a format the kernels cannot
    /// read, or a singular camera matrix.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        inputs: &ShadowInputs<'_>,
        targets: &ShadowTargets,
    ) -> Result<()> {
        let (w, h) = (targets.width(), targets.height());
        inputs.check(w, h)?;
        let (eye, clip_to_eye) = inputs.camera()?;
        let groups = (w.div_ceil(PIXEL_GROUP), h.div_ceil(PIXEL_GROUP));
        let device = &self.device;

        let (kernel, surface_name, surface_view, background_depth) = match inputs.surface {
            SurfaceInput::Depth {
                texture,
                background_depth,
                ..
            } => (
                &self.from_depth,
                "depth_texture",
                texture.create_view(&wgpu::TextureViewDescriptor {
                    aspect: wgpu::TextureAspect::DepthOnly,
                    ..Default::default()
                }),
                background_depth,
            ),
            SurfaceInput::Position { texture, .. } => (
                &self.from_position,
                "position_texture",
                texture.create_view(&Default::default()),
                0.0,
            ),
        };
        let normal_view = inputs.normal.create_view(&Default::default());
        let geo_view = inputs
            .geometric_normal
            .map(|t| t.create_view(&Default::default()))
            .unwrap_or_else(|| normal_view.clone());
        let params = SurfaceParams {
            clip_to_eye: clip_to_eye.to_cols_array_2d(),
            eye,
            ray_offset: scene.diagonal * RAY_OFFSET_FRACTION,
            width: w,
            height: h,
            background_depth,
            has_geo_normal: u32::from(inputs.geometric_normal.is_some()),
            origin: scene.origin,
            normal_encoding: match inputs.normal_encoding {
                NormalEncoding::Signed => NORMALS_SIGNED,
                NormalEncoding::Biased => NORMALS_BIASED,
            },
        };
        let params_buf = uniform_buffer_on(device, "surface params", &params);
        let pixels = &targets.pixels;
        let bind = kernel.bind(
            device,
            &[
                buffer("params", &params_buf),
                texture(surface_name, &surface_view),
                texture("normal_texture", &normal_view),
                texture("geo_normal_texture", &geo_view),
                buffer("gbuffer", &pixels.gbuffer),
                buffer("normal", &pixels.normal),
            ],
        )?;
        kernel.record(encoder, "embed/gbuffer", &bind, None, groups);

        // Relative to the scene's origin, as its BVH and the texels are.
        let light = crate::scene::view::QuadLight {
            corner: inputs.light.corner - scene.origin,
            ..*inputs.light
        };
        let light_points = self.stages.tracer.light_points_buffer(device, &light);
        let mut shadow = shadow_params(&light, w, h);
        shadow.iteration_budget = self.settings.iteration_budget.max(1);
        let image = ShadowImage {
            gbuffer: &pixels.gbuffer,
            light_points: &light_points,
            masks: &pixels.masks,
        };
        self.stages.tracer.record(
            device,
            encoder,
            scene,
            &image,
            &targets.scratch,
            &shadow,
            self.settings.resume_rounds,
        )?;

        let size = uniform_buffer_on(
            device,
            "image size",
            &ImageSize {
                width: w,
                height: h,
                ..Default::default()
            },
        );
        let filter = self.settings.filter.map(|(depth_tolerance, normal_tolerance)| {
            FilterParams::with_tolerances(w, h, depth_tolerance, normal_tolerance)
        });
        let filtered_values = self.stages.record_visibility_and_filter(
            device,
            encoder,
            pixels,
            &size,
            filter.as_ref(),
            None,
        )?;
        self.copy_to_texture(encoder, &size, &pixels.values, &targets.unfiltered_view, groups)?;
        self.copy_to_texture(encoder, &size, filtered_values, &targets.filtered_view, groups)?;
        Ok(())
    }

    /// Records `visibility_to_texture`: channel a of `values` → `texture`.
    fn copy_to_texture(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        size: &wgpu::Buffer,
        values: &wgpu::Buffer,
        visibility: &wgpu::TextureView,
        groups: (u32, u32),
    ) -> Result<()> {
        let bind = self.to_texture.bind(
            &self.device,
            &[
                buffer("size", size),
                buffer("values", values),
                texture("visibility", visibility),
            ],
        )?;
        self.to_texture
            .record(encoder, "embed/visibility", &bind, None, groups);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_webgpu_device_meets_the_requirements_and_downlevel_ones_do_not() {
        let required = ShadowPass::required_limits();
        assert!(required.check_limits(&wgpu::Limits::default()));
        assert!(!required.check_limits(&wgpu::Limits::downlevel_defaults()));
        assert!(ShadowPass::required_features().is_empty());
    }
}
