//! The standalone frame: primary pass → shadow pass → shade pass → filter,
//! on the GPU, read back for output.

use glam::Vec3;

use super::kernel::{Binding, Checks, Kernel, uniform_buffer};
use super::shadow_pass::{LeafMode, ShadowPass, ShadowStats, VectorVariant};
use super::{GpuContext, GpuScene, GpuTimer, empty_storage_buffer, read_buffer, storage_buffer};
use crate::filter::FilterParams;
use crate::frame::{RAY_OFFSET_FRACTION, camera_params};
use crate::layout::GBufferTexel;
use crate::reference::shade::shade_params;
use crate::reference::shadow::shadow_params;
use crate::sampling;
use crate::view::View;
use crate::{Error, Result};

/// Enough timestamp slots for every dispatch of a frame, resume rounds included.
const TIMER_CAPACITY: u32 = 4096;

/// Per-frame choices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Image width in pixels (any size ≥ 1; tiles at the right and bottom edges are partial).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The discontinuity filter's tolerances, or `None` to skip the filter.
    pub filter: Option<(f32, f32)>,
    /// Read the G-buffer back too (tests compare it with the CPU twin).
    pub keep_gbuffer: bool,
}

impl FrameSettings {
    /// A `width`×`height` frame with the default filter.
    pub fn new(width: u32, height: u32) -> FrameSettings {
        FrameSettings {
            width,
            height,
            filter: Some((
                FilterParams::DEFAULT_DEPTH_TOLERANCE,
                FilterParams::DEFAULT_NORMAL_TOLERANCE,
            )),
            keep_gbuffer: false,
        }
    }
}

/// A rendered frame, read back to the CPU (row-major, row 0 at the top).
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Shadow masks: bit j = ray j blocked; `1 << 16` marks sky pixels.
    pub masks: Vec<u32>,
    /// Shadowed irradiance (rgb) and visibility (a) before the filter.
    pub unfiltered: Vec<[f32; 4]>,
    /// The same after the filter (equal to `unfiltered` when the filter is off).
    pub filtered: Vec<[f32; 4]>,
    /// Diffuse BRDF, albedo / π (rgb; a unused); 0 for sky pixels.
    pub brdf: Vec<[f32; 4]>,
    /// The G-buffer, when [`FrameSettings::keep_gbuffer`] asked for it.
    pub gbuffer: Option<Vec<GBufferTexel>>,
    /// GPU milliseconds per pass: `primary`, `shadow` (all its dispatches), `shade`, `filter`.
    pub timings: Vec<(String, f64)>,
    /// Dispatches and suspensions of the shadow pass.
    pub shadow_stats: ShadowStats,
}

impl Frame {
    /// Outgoing radiance per pixel: BRDF × filtered irradiance (the image).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.brdf
            .iter()
            .zip(&self.filtered)
            .map(|(b, e)| [b[0] * e[0], b[1] * e[1], b[2] * e[2]])
            .collect()
    }

    /// GPU milliseconds of the pass `name`, summed over its dispatches (0 when not timed).
    pub fn pass_ms(&self, name: &str) -> f64 {
        self.timings
            .iter()
            .filter(|(n, _)| n == name)
            .map(|(_, ms)| ms)
            .sum()
    }
}

/// How the renderer builds its shadow pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RendererOptions {
    /// Force a vector variant, or `None` for the adapter's best (see [`VectorVariant::choose`]).
    pub variant: Option<VectorVariant>,
    /// How the shadow kernel's leaves use the lanes.
    pub leaf_mode: LeafMode,
}

/// A forced (or automatic) vector variant with the default leaf mode, so that
/// `Renderer::new(ctx, None)` and `Renderer::new(ctx, Some(variant))` read as before.
impl From<Option<VectorVariant>> for RendererOptions {
    fn from(variant: Option<VectorVariant>) -> RendererOptions {
        RendererOptions {
            variant,
            leaf_mode: LeafMode::default(),
        }
    }
}

/// The pipelines of the standalone frame.
#[derive(Debug)]
pub struct Renderer {
    primary: Kernel,
    shadow: ShadowPass,
    shade: Kernel,
    filter: Kernel,
}

impl Renderer {
    /// Builds every pipeline; `options` (or just an `Option<VectorVariant>`) choose the
    /// shadow pass's vector variant and leaf mode.
    pub fn new(ctx: &GpuContext, options: impl Into<RendererOptions>) -> Result<Renderer> {
        let options = options.into();
        use Binding::*;
        Ok(Renderer {
            // Indices: BVH ranges validated by GpuScene::new, the stack index is clamped.
            primary: Kernel::new(
                ctx,
                "primary",
                &[],
                &[
                    Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadOnly, ReadOnly,
                ],
                &[],
                Checks::Unchecked,
            )?,
            shadow: ShadowPass::new(ctx, options.variant, options.leaf_mode)?,
            shade: Kernel::new(
                ctx,
                "shade",
                &[],
                &[
                    Uniform, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
                ],
                &[],
                Checks::Checked,
            )?,
            filter: Kernel::new(
                ctx,
                "filter",
                &[],
                &[Uniform, ReadOnly, ReadOnly, ReadOnly, ReadWrite],
                &[],
                Checks::Checked,
            )?,
        })
    }

    /// The shadow pass's vector variant.
    pub fn variant(&self) -> VectorVariant {
        self.shadow.variant
    }

    /// The shadow pass's leaf mode.
    pub fn leaf_mode(&self) -> LeafMode {
        self.shadow.leaf_mode
    }

    /// Renders one frame of `scene` seen through `view`.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
    ) -> Result<Frame> {
        self.render_with_progress(ctx, scene, view, settings, &mut |_, _| {})
    }

    /// [`Renderer::render`], calling `progress(tiles done, tiles)` as the shadow pass advances.
    pub fn render_with_progress(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Frame> {
        let (w, h) = (settings.width, settings.height);
        if w == 0 || h == 0 {
            return Err(Error::Gpu(format!(
                "image size {w}x{h}: both sides must be at least 1"
            )));
        }
        super::memory::check_frame_fits(super::memory::storage_limit(ctx), w, h)?;
        let pixels = u64::from(w) * u64::from(h);
        let rw = wgpu::BufferUsages::COPY_SRC;
        let gbuffer = empty_storage_buffer(ctx, "G-buffer", pixels * size_of::<GBufferTexel>() as u64, rw)?;
        let masks = empty_storage_buffer(ctx, "shadow masks", pixels * 4, rw)?;
        let values = empty_storage_buffer(ctx, "shaded values", pixels * 16, rw)?;
        let depth = empty_storage_buffer(ctx, "depth", pixels * 4, rw)?;
        let normal = empty_storage_buffer(ctx, "normals", pixels * 16, rw)?;
        let filtered = empty_storage_buffer(ctx, "filtered values", pixels * 16, rw)?;
        let brdf = empty_storage_buffer(ctx, "brdf", pixels * 16, rw)?;
        let status = empty_storage_buffer(ctx, "primary status", 16, rw | wgpu::BufferUsages::COPY_DST)?;
        let points: Vec<[f32; 4]> = sampling::light_points(&view.light)
            .iter()
            .map(|p: &Vec3| p.extend(0.0).to_array())
            .collect();
        let light_points = storage_buffer(ctx, "light points", &points, wgpu::BufferUsages::empty())?;

        let camera = camera_params(&view.camera, w, h, scene.diagonal * RAY_OFFSET_FRACTION);
        let camera_buf = uniform_buffer(ctx, "camera", &camera);
        let shade_buf = uniform_buffer(ctx, "shade params", &shade_params(&view.light, w, h));
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let groups = (w.div_ceil(8), h.div_ceil(8));
        check_groups(ctx, groups)?;

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let bind = self.primary.bind(
                ctx,
                &[
                    &camera_buf,
                    &scene.nodes,
                    &scene.triangles,
                    &scene.shading,
                    &scene.materials,
                    &gbuffer,
                    &status,
                    &scene.textures,
                    &scene.texels,
                ],
            );
            let writes = timer.pass_writes("primary");
            self.primary
                .record(&mut encoder, "primary", &bind, writes, groups);
        }
        ctx.queue.submit([encoder.finish()]);
        if read_buffer::<u32>(ctx, &status, 0..4)?[0] != 0 {
            return Err(Error::Gpu(
                "primary pass: a camera ray ran out of its loop iterations (BVH too deep or degenerate)"
                    .into(),
            ));
        }

        let shadow_stats = self.shadow.run(
            ctx,
            scene,
            &gbuffer,
            &light_points,
            &masks,
            &shadow_params(&view.light, w, h),
            Some(&mut timer),
            progress,
        )?;

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let bind = self.shade.bind(
                ctx,
                &[&shade_buf, &gbuffer, &masks, &values, &depth, &normal, &brdf],
            );
            let writes = timer.pass_writes("shade");
            self.shade.record(&mut encoder, "shade", &bind, writes, groups);
        }
        if let Some((depth_tolerance, normal_tolerance)) = settings.filter {
            let params = FilterParams {
                width: w,
                height: h,
                depth_tolerance,
                normal_tolerance,
            };
            let params_buf = uniform_buffer(ctx, "filter params", &params);
            let bind = self
                .filter
                .bind(ctx, &[&params_buf, &values, &depth, &normal, &filtered]);
            let writes = timer.pass_writes("filter");
            self.filter.record(&mut encoder, "filter", &bind, writes, groups);
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);

        let unfiltered: Vec<[f32; 4]> = read_buffer(ctx, &values, 0..pixels * 16)?;
        let filtered = if settings.filter.is_some() {
            read_buffer(ctx, &filtered, 0..pixels * 16)?
        } else {
            unfiltered.clone()
        };
        let gbuffer = if settings.keep_gbuffer {
            Some(read_buffer(
                ctx,
                &gbuffer,
                0..pixels * size_of::<GBufferTexel>() as u64,
            )?)
        } else {
            None
        };
        Ok(Frame {
            brdf: read_buffer(ctx, &brdf, 0..pixels * 16)?,
            width: w,
            height: h,
            masks: read_buffer(ctx, &masks, 0..pixels * 4)?,
            unfiltered,
            filtered,
            gbuffer,
            timings: timer.read(ctx)?,
            shadow_stats,
        })
    }
}

fn check_groups(ctx: &GpuContext, (x, y): (u32, u32)) -> Result<()> {
    let limit = ctx.info.max_compute_workgroups_per_dimension;
    if x > limit || y > limit {
        return Err(Error::Gpu(format!(
            "image needs {x}x{y} workgroups of 8x8 pixels; the device allows {limit} per dimension"
        )));
    }
    Ok(())
}
