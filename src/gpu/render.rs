//! The standalone renderer: primary pass → the shadow stages (`ShadowStages`: shadow
//! rays, shading, filter, refinement) on the GPU, read back as a [`Frame`]; images too
//! large for one buffer are rendered in tiles (`gpu::tiling`).

use glam::Vec3;

use super::kernel::uniform_buffer;
use super::pixel_buffers::PixelBuffers;
use super::primary_pass::{PrimaryOptions, PrimaryPass, PrimaryStatus, PrimaryTracer};
use super::shadow_stages::{ShadowStages, VisibilityStage};
use super::tiling::{TileRegion, tile_regions, tile_side};
use super::{
    Frame, FrameSettings, GpuContext, GpuScene, GpuTimer, LeafMode, Phase, RendererOptions, ShadowImage,
    ShadowStats, Tracer, TracerOptions, VectorVariant, read_buffer,
};
use crate::contract::ITERATION_BUDGET;
use crate::contract::filter::FilterParams;
use crate::contract::groups::PIXEL_GROUP;
use crate::contract::layout::{CameraParams, GBufferTexel};
use crate::contract::refine::REFINE_SET_COUNTS;
use crate::contract::shade::shade_params;
use crate::contract::shadow::shadow_params;
use crate::pass_inputs::{RAY_OFFSET_FRACTION, camera_params, tile_camera};
use crate::sampling::SAMPLES_PER_SET;
use crate::scene::view::{MIN_FOV_Y_DEGREES, View};
use crate::{Error, Result};

/// Enough timestamp slots for every dispatch of a frame, resume rounds included.
const TIMER_CAPACITY: u32 = 4096;

/// The side of [`Renderer::warm_up`]'s square frame, in pixels.
const WARM_UP_SIDE: u32 = 8;

/// `view` with its field of view narrowed around its centre so that a pixel of a
/// [`WARM_UP_SIDE`]-high frame covers the angle of a pixel of a `height`-high frame
/// (never wider than `view`, never below [`MIN_FOV_Y_DEGREES`]).
fn warm_up_view(view: &View, height: u32) -> View {
    let scale = WARM_UP_SIDE as f32 / height.max(WARM_UP_SIDE) as f32;
    let tan = (view.camera.fov_y_degrees.to_radians() * 0.5).tan() * scale;
    let mut narrow = *view;
    narrow.camera.fov_y_degrees = (2.0 * tan.atan().to_degrees()).max(MIN_FOV_Y_DEGREES);
    narrow
}

/// The pipelines of the standalone frame.
#[derive(Debug)]
pub struct Renderer {
    primary: PrimaryPass,
    /// The per-ray kernel that traces a frame again when a multi-frusta primary vector ran
    /// out of loop iterations (`None` when `primary` is per-ray already).
    primary_fallback: Option<PrimaryPass>,
    stages: ShadowStages,
}

/// A shadow tracer on the CPU for [`Renderer::render_with_cpu_shadows`]: the masks of a
/// `width`×`height` G-buffer.
pub type CpuShadows<'a> = dyn Fn(&[GBufferTexel], u32, u32) -> Vec<u32> + 'a;

impl Renderer {
    /// Builds every pipeline; `options` (or just an `Option<VectorVariant>`) choose the
    /// shadow pass's vector variant and leaf mode.
    pub fn new(ctx: &GpuContext, options: impl Into<RendererOptions>) -> Result<Renderer> {
        let options = options.into();
        let primary_options = PrimaryOptions {
            tracer: options.primary,
            variant: options.variant,
            counters: options.counters,
            iteration_budget: match options.primary {
                PrimaryTracer::Mft => options.primary_iteration_budget,
                PrimaryTracer::PerRay => ITERATION_BUDGET,
            },
        };
        let tracer_options = TracerOptions {
            tracer: options.tracer,
            variant: options.variant,
            leaf_mode: options.leaf_mode,
            counters: options.counters,
            shrink: options.shrink,
        };
        // The shadow stages' pipelines are made on a second thread while this one makes the
        // primary pass's: each takes tens of milliseconds of the driver's compiler (error
        // scopes are per thread in wgpu, so each thread's errors stay its own).
        let (stages, primary) = std::thread::scope(|s| {
            let stages = s.spawn(|| ShadowStages::new(ctx, &tracer_options, VisibilityStage::Shade));
            let primary = Self::primary_passes(ctx, &primary_options);
            let stages = stages
                .join()
                .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
            (stages, primary)
        });
        let (primary, primary_fallback) = primary?;
        Ok(Renderer {
            primary,
            primary_fallback,
            stages: stages?,
        })
    }

    /// The primary pass of `options`, and the per-ray fallback a multi-frusta one needs.
    fn primary_passes(
        ctx: &GpuContext,
        options: &PrimaryOptions,
    ) -> Result<(PrimaryPass, Option<PrimaryPass>)> {
        let primary = PrimaryPass::new(ctx, options)?;
        let fallback = match options.tracer {
            PrimaryTracer::Mft => Some(PrimaryPass::new(
                ctx,
                &PrimaryOptions {
                    tracer: PrimaryTracer::PerRay,
                    counters: options.counters,
                    ..PrimaryOptions::default()
                },
            )?),
            PrimaryTracer::PerRay => None,
        };
        Ok((primary, fallback))
    }

    /// The shadow pass's vector variant.
    pub fn variant(&self) -> VectorVariant {
        self.stages.tracer.variant
    }

    /// The primary (camera-ray) tracer.
    pub fn primary_tracer(&self) -> PrimaryTracer {
        self.primary.tracer()
    }

    /// The shadow tracer.
    pub fn tracer(&self) -> Tracer {
        self.stages.tracer.tracer
    }

    /// The shadow pass's leaf mode.
    pub fn leaf_mode(&self) -> LeafMode {
        self.stages.tracer.leaf_mode
    }

    /// Renders one frame of `scene` seen through `view`.
    pub fn render(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
    ) -> Result<Frame> {
        self.render_with_progress(ctx, scene, view, settings, &mut |_, _, _| {})
    }

    /// Renders an 8×8 frame with `settings`' stages (filter, refinement) so that the
    /// driver compiles the kernels a `settings` frame runs before frames that are timed:
    /// lavapipe compiles a pipeline at its first dispatch, inside that dispatch's GPU time.
    ///
    /// The small frame looks at the centre of `view` through a field of view narrowed so
    /// that its pixels are as large as those of a `settings.height`-pixel-high frame:
    /// frusta as narrow as the real frame's. Over the whole view, 8×8 pixels make frusta
    /// so wide that the primary vectors run out of loop iterations and the per-ray
    /// fallback traces the frame again.
    pub fn warm_up(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
    ) -> Result<()> {
        let small = FrameSettings {
            width: WARM_UP_SIDE,
            height: WARM_UP_SIDE,
            keep_gbuffer: false,
            max_tile: None,
            ..*settings
        };
        self.render(ctx, scene, &warm_up_view(view, settings.height), &small)
            .map(drop)
    }

    /// [`Renderer::render`], calling `progress(phase, done, total)` as the shadow pass
    /// ([`Phase::Shadow`]: tiles of the image) and the refinement ([`Phase::Refine`]: tiles
    /// of its sample image, for each tile of a tiled image) advance.
    ///
    /// An image whose per-pixel buffers would not fit one storage-buffer binding is
    /// rendered in square tiles (sides a multiple of 4, so every pixel keeps its sample
    /// set) with a 4-pixel margin for the filter, and stitched: the same pixels as one
    /// big frame, bit for bit. Sides up to the device's 2D texture limit are accepted.
    pub fn render_with_progress(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Frame> {
        let frames = self.render_frame(ctx, scene, std::slice::from_ref(view), settings, None, progress)?;
        Ok(frames.into_iter().next().expect("one frame per view"))
    }

    /// One frame per light: `views` share one camera and ground plane and differ in their
    /// light (as [`crate::scene::view::ViewFile::views`] makes them). The primary pass runs
    /// once, and its G-buffer serves every light's shadow pass, shading, filter and
    /// refinement; frame `i` holds light `i`'s results, and the primary pass's time is in
    /// the first frame's timings. The image of all lights together is
    /// [`super::image_of_lights`]. `progress` as in [`Renderer::render_with_progress`],
    /// restarting for each light.
    pub fn render_lights(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        views: &[View],
        settings: &FrameSettings,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Vec<Frame>> {
        let Some(first) = views.first() else {
            return Err(Error::invalid(
                "Renderer::render_lights",
                "no view: give at least one light",
            ));
        };
        if views
            .iter()
            .any(|v| v.camera != first.camera || v.ground_y != first.ground_y)
        {
            return Err(Error::invalid(
                "Renderer::render_lights",
                "the views differ in more than their light: one camera for all lights",
            ));
        }
        self.render_frame(ctx, scene, views, settings, None, progress)
    }

    /// [`Renderer::render_with_progress`] with the shadow masks made on the CPU by
    /// `shadows(gbuffer, width, height)` instead of by the GPU tracer: it gets each frame's
    /// (or tile's) G-buffer, row-major, positions relative to [`GpuScene::origin`], and
    /// returns its masks (bit j = ray j of the pixel's interleaved set blocked,
    /// [`crate::contract::layout::MASK_SKY`] for no geometry). Shading, the filter and the
    /// refinement (which traces its extra samples with this renderer's GPU tracer) follow
    /// as usual. Its time is in [`Frame::timings`] as `shadow-cpu` (wall ms).
    pub fn render_with_cpu_shadows(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        shadows: &CpuShadows<'_>,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Frame> {
        let frames = self.render_frame(
            ctx,
            scene,
            std::slice::from_ref(view),
            settings,
            Some(shadows),
            progress,
        )?;
        Ok(frames.into_iter().next().expect("one frame per view"))
    }

    /// One frame per view (the views share their camera; `cpu_shadows` only with one view).
    fn render_frame(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        views: &[View],
        settings: &FrameSettings,
        cpu_shadows: Option<&CpuShadows<'_>>,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Vec<Frame>> {
        debug_assert!(cpu_shadows.is_none() || views.len() == 1);
        let (w, h) = (settings.width, settings.height);
        if w == 0 || h == 0 {
            return Err(Error::value(
                "FrameSettings image size",
                format!("{w}x{h}"),
                "both sides must be at least 1",
            ));
        }
        for view in views {
            view.validate()
                .map_err(|message| Error::invalid("Renderer::render view", message))?;
        }
        // The kernels work relative to the scene's origin (GpuScene::origin).
        let views: Vec<View> = if scene.origin == Vec3::ZERO {
            views.to_vec()
        } else {
            views.iter().map(|v| v.translated(-scene.origin)).collect()
        };
        let view = &views[0];
        if settings.refine && settings.filter.is_none() {
            return Err(Error::invalid(
                "FrameSettings::refine",
                "refinement needs the filter: it refines the pixels whose filter window is cut",
            ));
        }
        if settings.refine && matches!(self.tracer(), Tracer::Reference { .. }) {
            return Err(Error::invalid(
                "FrameSettings::refine",
                "refinement needs an interleaved tracer (mft, packet or per-ray), not the reference tracer",
            ));
        }
        if !REFINE_SET_COUNTS.contains(&settings.refine_sets) {
            return Err(Error::invalid(
                "FrameSettings::refine_sets",
                format!(
                    "{} sample sets: a refined pixel traces 1, 2, 4, 8 or 16 of the 16 sets",
                    settings.refine_sets
                ),
            ));
        }
        if let Some(budget) = settings.ray_budget {
            if !settings.refine {
                return Err(Error::invalid(
                    "FrameSettings::ray_budget",
                    "a ray budget limits the refinement: set FrameSettings::refine too",
                ));
            }
            if !(budget.is_finite() && budget >= SAMPLES_PER_SET as f32) {
                return Err(Error::invalid(
                    "FrameSettings::ray_budget",
                    format!(
                        "{budget} rays per pixel: the budget must be a number ≥ {SAMPLES_PER_SET}, the frame's own rays"
                    ),
                ));
            }
        }
        let limit = ctx.device.limits().max_texture_dimension_2d;
        if w > limit || h > limit {
            return Err(Error::Gpu(format!(
                "image size {w}x{h}: this adapter's largest image side (max_texture_dimension_2d) \
                 is {limit} pixels"
            )));
        }
        let whole = camera_params(&view.camera, w, h, scene.diagonal * RAY_OFFSET_FRACTION);
        let side = settings
            .max_tile
            .unwrap_or_else(|| tile_side(ctx.info.max_storage_buffer_binding_size));
        if w <= side && h <= side {
            return self.render_tile(ctx, scene, &views, settings, &whole, cpu_shadows, progress);
        }
        let regions = tile_regions(w, h, side);
        let unit = self.tracer().unit();
        let units = |r: &TileRegion| u64::from(r.w.div_ceil(unit)) * u64::from(r.h.div_ceil(unit));
        let total: u64 = regions.iter().map(units).sum();
        let mut done = 0u64;
        let mut out: Vec<Frame> = Vec::new();
        for r in &regions {
            let tile_settings = FrameSettings {
                width: r.w,
                height: r.h,
                ..*settings
            };
            let camera = tile_camera(&whole, r.x, r.y, r.w, r.h);
            let tiles = self.render_tile(
                ctx,
                scene,
                &views,
                &tile_settings,
                &camera,
                cpu_shadows,
                &mut |phase, d, t| match phase {
                    Phase::Shadow => progress(phase, done + d, total),
                    Phase::Refine => progress(phase, d, t),
                },
            )?;
            done += units(r);
            out.resize_with(tiles.len(), || Frame::empty(w, h, settings.keep_gbuffer));
            for (frame, tile) in out.iter_mut().zip(&tiles) {
                frame.paste(tile, r);
            }
        }
        Ok(out)
    }

    /// One frame (or tile) of the image `camera` projects, `settings`-sized, per view (the
    /// views differ only in their light): one primary pass, then each light's stages.
    #[allow(clippy::too_many_arguments)]
    fn render_tile(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        views: &[View],
        settings: &FrameSettings,
        camera: &CameraParams,
        cpu_shadows: Option<&CpuShadows<'_>>,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Vec<Frame>> {
        let (w, h) = (settings.width, settings.height);
        // Tiles are sized to fit; this catches a forced `max_tile` that does not.
        super::memory::check_frame_fits(super::memory::storage_limit(ctx), w, h)?;
        let pixels = PixelBuffers::new(ctx, w, h, true)?;
        let status = PrimaryPass::status_buffer(&ctx.device);

        let camera_buf = uniform_buffer(ctx, "camera", camera);
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let groups = (w.div_ceil(PIXEL_GROUP), h.div_ceil(PIXEL_GROUP));
        check_groups(ctx, groups)?;

        // One primary dispatch, timed as "primary", waited for.
        let mut trace_primary = |pass: &PrimaryPass| -> Result<PrimaryStatus> {
            let groups = pass.workgroups(ctx, w, h)?;
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            let writes = timer.pass_writes("primary");
            pass.record(
                &ctx.device,
                &mut encoder,
                scene,
                &camera_buf,
                &pixels.gbuffer,
                &status,
                groups,
                writes,
            )?;
            ctx.queue.submit([encoder.finish()]);
            pass.read_status(ctx, &status)
        };
        let mut primary_status = trace_primary(&self.primary)?;
        let mut primary_fallback_pixels = 0;
        if let Some(fallback) = self
            .primary_fallback
            .as_ref()
            .filter(|_| primary_status.overflow_pixels > 0 && primary_status.loop_cut == 0)
        {
            // Frusta as wide as a small image's blocks can meet most of a big scene; the
            // per-ray kernel's loop bound is per ray, so it still traces them.
            primary_fallback_pixels = primary_status.overflow_pixels;
            primary_status = trace_primary(fallback)?;
        }
        let primary_counters = primary_status.check()?.unwrap_or_default();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let primary_timings = timer.read(ctx)?;

        let mut frames = Vec::with_capacity(views.len());
        for view in views {
            let mut frame = self.light_stages(
                ctx,
                scene,
                view,
                settings,
                &pixels,
                &mut timer,
                cpu_shadows,
                progress,
            )?;
            if frames.is_empty() {
                frame.timings.splice(0..0, primary_timings.iter().cloned());
                frame.primary_counters = primary_counters;
                frame.primary_fallback_pixels = primary_fallback_pixels;
            }
            frames.push(frame);
        }
        Ok(frames)
    }

    /// One light's stages over the G-buffer in `pixels` (shadow pass, shading, filter,
    /// refinement), read back as its frame (without the primary pass's figures).
    #[allow(clippy::too_many_arguments)]
    fn light_stages(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        pixels: &PixelBuffers,
        timer: &mut GpuTimer,
        cpu_shadows: Option<&CpuShadows<'_>>,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Frame> {
        let (w, h) = (settings.width, settings.height);
        let pixel_count = u64::from(w) * u64::from(h);
        let light_points = self.stages.tracer.light_points_buffer(&ctx.device, &view.light);
        let shade_buf = uniform_buffer(ctx, "shade params", &shade_params(&view.light, w, h));
        let shadow = shadow_params(&view.light, w, h);
        let image = ShadowImage {
            gbuffer: &pixels.gbuffer,
            light_points: &light_points,
            masks: &pixels.masks,
        };
        let mut cpu_ms = None;
        let shadow_stats = match cpu_shadows {
            None => self.stages.tracer.run(
                ctx,
                scene,
                &image,
                &shadow,
                Some(&mut *timer),
                "shadow",
                &mut |done, total| progress(Phase::Shadow, done, total),
            )?,
            Some(shadows) => {
                let texels: Vec<GBufferTexel> = read_buffer(
                    ctx,
                    &pixels.gbuffer,
                    0..pixel_count * size_of::<GBufferTexel>() as u64,
                )?;
                let start = std::time::Instant::now();
                let masks = shadows(&texels, w, h);
                cpu_ms = Some(start.elapsed().as_secs_f64() * 1e3);
                if masks.len() != texels.len() {
                    return Err(Error::invalid(
                        "Renderer::render_with_cpu_shadows",
                        format!("{} masks for {} pixels", masks.len(), texels.len()),
                    ));
                }
                ctx.queue
                    .write_buffer(&pixels.masks, 0, bytemuck::cast_slice(&masks));
                ShadowStats::default()
            }
        };

        let filter = settings.filter.map(|(depth_tolerance, normal_tolerance)| {
            FilterParams::with_tolerances(w, h, depth_tolerance, normal_tolerance)
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        self.stages.record_visibility_and_filter(
            &ctx.device,
            &mut encoder,
            pixels,
            &shade_buf,
            filter.as_ref(),
            Some(&mut *timer),
        )?;
        ctx.queue.submit([encoder.finish()]);

        let mut refined = vec![false; pixel_count as usize];
        // `render_with_progress` checked that a refined frame has the filter.
        if let Some(filter) = filter.filter(|_| settings.refine) {
            let mut refine_progress = |done, total| progress(Phase::Refine, done, total);
            for p in self.stages.refine(
                ctx,
                scene,
                pixels,
                &light_points,
                &shadow,
                &shade_buf,
                &filter,
                settings.ray_budget,
                settings.refine_sets,
                timer,
                &mut refine_progress,
            )? {
                refined[p as usize] = true;
            }
        }
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);

        let values = 0..pixel_count * 16;
        let unfiltered: Vec<[f32; 4]> = read_buffer(ctx, &pixels.values, values.clone())?;
        let filtered = if settings.filter.is_some() {
            read_buffer(ctx, &pixels.filtered, values.clone())?
        } else {
            unfiltered.clone()
        };
        let gbuffer = if settings.keep_gbuffer {
            Some(read_buffer(
                ctx,
                &pixels.gbuffer,
                0..pixel_count * size_of::<GBufferTexel>() as u64,
            )?)
        } else {
            None
        };
        let brdf = pixels
            .brdf
            .as_ref()
            .expect("the renderer allocates the brdf buffer");
        Ok(Frame {
            brdf: read_buffer(ctx, brdf, values)?,
            width: w,
            height: h,
            masks: read_buffer(ctx, &pixels.masks, 0..pixel_count * 4)?,
            unfiltered,
            filtered,
            refined,
            gbuffer,
            timings: {
                let mut t = timer.read(ctx)?;
                t.extend(cpu_ms.map(|ms| ("shadow-cpu".to_owned(), ms)));
                t
            },
            shadow_stats,
            primary_counters: Default::default(),
            primary_fallback_pixels: 0,
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The warm-up frame's pixels subtend the angle of the real frame's (its frusta are as
    /// narrow), and a frame no higher than it keeps the view's field of view.
    #[test]
    fn warm_up_pixels_are_as_large_as_the_frames() {
        let view = crate::assets::EMBEDDED_SCENES[0].view();
        for height in [512, 1024, 4096] {
            let full = crate::pass_inputs::camera_params(&view.camera, height, height, 0.0);
            let small = crate::pass_inputs::camera_params(
                &warm_up_view(&view, height).camera,
                WARM_UP_SIDE,
                WARM_UP_SIDE,
                0.0,
            );
            let full_pixel = full.up.length() / height as f32;
            let small_pixel = small.up.length() / WARM_UP_SIDE as f32;
            // tan, atan and degrees in f32: a few ulps each.
            assert!(
                (small_pixel / full_pixel - 1.0).abs() < 1e-5,
                "height {height}: {small_pixel} vs {full_pixel}"
            );
        }
        assert_eq!(warm_up_view(&view, WARM_UP_SIDE).camera, view.camera);
        assert_eq!(warm_up_view(&view, 4).camera, view.camera);
    }
}
