//! The standalone frame: primary pass → shadow pass → shade pass → filter,
//! on the GPU, read back for output.

use std::sync::OnceLock;

use glam::Vec3;

use super::kernel::{Checks, Kernel, uniform_buffer};
use super::primary_pass::{PrimaryPass, PrimaryStatus, PrimaryTracer};
use super::refine::{RefineBuffers, Refinement};
use super::shadow_tracer::{LeafMode, ShadowStats, ShadowTracer, Tracer, TracerOptions, VectorVariant};
use super::{GpuContext, GpuScene, GpuTimer, empty_storage_buffer, read_buffer, storage_buffer};
use crate::contract::ITERATION_BUDGET;
use crate::contract::refine::selection_params;
use crate::contract::shade::shade_params;
use crate::contract::shadow::shadow_params;
use crate::filter::{FILTER_KERNEL, FilterParams};
use crate::frame::{RAY_OFFSET_FRACTION, camera_params, tile_camera};
use crate::layout::{CameraParams, GBufferTexel};
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
    /// Largest tile side (a multiple of 4) to render the image in, or `None` for the
    /// largest whose buffers fit the adapter's storage-buffer limit (tests force tiling).
    pub max_tile: Option<u32>,
    /// After the filter, trace all 256 light samples for the pixels where visibility
    /// changes around them and their window is cut (at a one-ray visibility tolerance) or
    /// their own rays agree ([`crate::reference::refine`]). Needs the filter and an interleaved tracer (not
    /// [`Tracer::Reference`]).
    pub refine: bool,
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
            max_tile: None,
            refine: false,
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
    /// The same after the filter (equal to `unfiltered` when the filter is off), and
    /// after the refinement at the refined pixels.
    pub filtered: Vec<[f32; 4]>,
    /// Per pixel, whether the refinement traced its 256 light samples (all false
    /// without [`FrameSettings::refine`]).
    pub refined: Vec<bool>,
    /// Diffuse BRDF, albedo / π (rgb; a unused); 0 for sky pixels.
    pub brdf: Vec<[f32; 4]>,
    /// The G-buffer, when [`FrameSettings::keep_gbuffer`] asked for it; positions are
    /// relative to [`GpuScene::origin`] (the world's for a scene near the origin).
    pub gbuffer: Option<Vec<GBufferTexel>>,
    /// GPU milliseconds per pass: `primary`, `shadow` (all its dispatches), `shade`, `filter`.
    pub timings: Vec<(String, f64)>,
    /// Dispatches and suspensions of the shadow pass.
    pub shadow_stats: ShadowStats,
    /// Work counted by the primary kernel (zero unless built with
    /// [`RendererOptions::counters`]).
    pub primary_counters: crate::counters::Counters,
    /// Pixels whose multi-frusta primary vectors ran out of loop iterations, after which
    /// the per-ray kernel traced the frame's camera rays again (0: it did not happen).
    pub primary_fallback_pixels: u32,
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
        self.timed_ms(name).unwrap_or(0.0)
    }

    /// [`Frame::pass_ms`], or `None` when no dispatch of `name` was timed (the adapter has
    /// no timestamp queries, or the pass did not run).
    pub fn timed_ms(&self, name: &str) -> Option<f64> {
        let mut times = self.timings.iter().filter(|(n, _)| n == name).peekable();
        times.peek()?;
        Some(times.map(|(_, ms)| ms).sum())
    }
}

/// What a frame's progress report is about ([`Renderer::render_with_phases`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The shadow pass, in tiles (or pixels, for the per-ray tracers) of the image.
    Shadow,
    /// The refinement's tracing, in units of its sample image.
    Refine,
}

/// How the renderer builds its shadow pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RendererOptions {
    /// Force a vector variant, or `None` for the adapter's best (see [`VectorVariant::choose`]).
    pub variant: Option<VectorVariant>,
    /// How the shadow kernel's leaves use the lanes.
    pub leaf_mode: LeafMode,
    /// The shadow tracer. [`Tracer::Reference`] frames should be rendered without the
    /// filter (the reference is the unfiltered yardstick); the renderer does not enforce it.
    pub tracer: Tracer,
    /// Count the shadow kernel's work ([`ShadowStats::counters`]).
    pub counters: bool,
    /// MFT frustum shrinking ([`TracerOptions::shrink`]; on by default).
    pub shrink: bool,
    /// Which kernel traces the camera rays.
    pub primary: PrimaryTracer,
    /// Loop iterations a multi-frusta primary vector may run (at least 1; 60,000 by
    /// default, below lavapipe's loop limit); a frame where one runs out is traced again
    /// by the per-ray kernel (tests lower it), one where the driver ends a loop (a budget
    /// above its limit) is an [`Error::LoopCut`].
    pub primary_iteration_budget: u32,
}

impl Default for RendererOptions {
    fn default() -> RendererOptions {
        let t = TracerOptions::default();
        RendererOptions {
            variant: t.variant,
            leaf_mode: t.leaf_mode,
            tracer: t.tracer,
            counters: t.counters,
            shrink: t.shrink,
            primary: PrimaryTracer::default(),
            primary_iteration_budget: ITERATION_BUDGET,
        }
    }
}

/// A forced (or automatic) vector variant with the default leaf mode, so that
/// `Renderer::new(ctx, None)` and `Renderer::new(ctx, Some(variant))` read as before.
impl From<Option<VectorVariant>> for RendererOptions {
    fn from(variant: Option<VectorVariant>) -> RendererOptions {
        RendererOptions {
            variant,
            ..RendererOptions::default()
        }
    }
}

/// The pipelines of the standalone frame.
#[derive(Debug)]
pub struct Renderer {
    primary: PrimaryPass,
    /// The per-ray kernel that traces a frame again when a multi-frusta primary vector ran
    /// out of loop iterations (`None` when `primary` is per-ray already).
    primary_fallback: Option<PrimaryPass>,
    shadow: ShadowTracer,
    shade: Kernel,
    filter: Kernel,
    /// Built on the first frame that asks for it.
    refinement: OnceLock<Refinement>,
}

impl Renderer {
    /// Builds every pipeline; `options` (or just an `Option<VectorVariant>`) choose the
    /// shadow pass's vector variant and leaf mode.
    pub fn new(ctx: &GpuContext, options: impl Into<RendererOptions>) -> Result<Renderer> {
        let options = options.into();
        Ok(Renderer {
            primary: PrimaryPass::with_iteration_budget(
                ctx,
                options.primary,
                options.variant,
                options.counters,
                match options.primary {
                    PrimaryTracer::Mft => options.primary_iteration_budget,
                    PrimaryTracer::PerRay => ITERATION_BUDGET,
                },
            )?,
            primary_fallback: match options.primary {
                PrimaryTracer::Mft => Some(PrimaryPass::new(
                    ctx,
                    PrimaryTracer::PerRay,
                    None,
                    options.counters,
                )?),
                PrimaryTracer::PerRay => None,
            },
            shadow: ShadowTracer::with_options(
                ctx,
                &TracerOptions {
                    tracer: options.tracer,
                    variant: options.variant,
                    leaf_mode: options.leaf_mode,
                    counters: options.counters,
                    shrink: options.shrink,
                },
            )?,
            shade: Kernel::new(
                ctx,
                "shade",
                &[],
                &[("REFERENCE_RAYS", f64::from(reference_rays(options.tracer)))],
                Checks::Checked,
            )?,
            filter: Kernel::new(ctx, FILTER_KERNEL, &[], &[], Checks::Checked)?,
            refinement: OnceLock::new(),
        })
    }

    /// The shadow pass's vector variant.
    pub fn variant(&self) -> VectorVariant {
        self.shadow.variant
    }

    /// The primary (camera-ray) tracer.
    pub fn primary_tracer(&self) -> PrimaryTracer {
        self.primary.tracer()
    }

    /// The shadow tracer.
    pub fn tracer(&self) -> Tracer {
        self.shadow.tracer
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
        self.render_with_phases(ctx, scene, view, settings, &mut |phase, done, total| {
            if phase == Phase::Shadow {
                progress(done, total)
            }
        })
    }

    /// [`Renderer::render`], calling `progress(phase, done, total)` as the shadow pass
    /// ([`Phase::Shadow`]: tiles of the image) and the refinement ([`Phase::Refine`]: tiles
    /// of its sample image, for each tile of a tiled image) advance.
    ///
    /// An image whose per-pixel buffers would not fit one storage-buffer binding is
    /// rendered in square tiles (sides a multiple of 4, so every pixel keeps its sample
    /// set) with a 4-pixel margin for the filter, and stitched: the same pixels as one
    /// big frame, bit for bit. Sides up to the device's 2D texture limit are accepted.
    pub fn render_with_phases(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Frame> {
        let (w, h) = (settings.width, settings.height);
        if w == 0 || h == 0 {
            return Err(Error::value(
                "FrameSettings image size",
                format!("{w}x{h}"),
                "both sides must be at least 1",
            ));
        }
        view.validate()
            .map_err(|message| Error::invalid("Renderer::render view", message))?;
        // The kernels work relative to the scene's origin (GpuScene::origin).
        let moved;
        let view = if scene.origin == Vec3::ZERO {
            view
        } else {
            moved = view.translated(-scene.origin);
            &moved
        };
        if settings.refine && settings.filter.is_none() {
            return Err(Error::invalid(
                "FrameSettings::refine",
                "refinement needs the filter: it refines the pixels whose filter window is cut",
            ));
        }
        if settings.refine && matches!(self.shadow.tracer, Tracer::Reference { .. }) {
            return Err(Error::invalid(
                "FrameSettings::refine",
                "refinement needs an interleaved tracer (mft, packet or per-ray), not the reference tracer",
            ));
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
            return self.render_tile(ctx, scene, view, settings, &whole, progress);
        }
        let regions = tile_regions(w, h, side);
        let unit = self.shadow.tracer.unit();
        let units = |r: &TileRegion| u64::from(r.w.div_ceil(unit)) * u64::from(r.h.div_ceil(unit));
        let total: u64 = regions.iter().map(units).sum();
        let mut done = 0u64;
        let mut out: Option<Frame> = None;
        for r in &regions {
            let tile_settings = FrameSettings {
                width: r.w,
                height: r.h,
                ..*settings
            };
            let camera = tile_camera(&whole, r.x, r.y, r.w, r.h);
            let tile =
                self.render_tile(
                    ctx,
                    scene,
                    view,
                    &tile_settings,
                    &camera,
                    &mut |phase, d, t| match phase {
                        Phase::Shadow => progress(phase, done + d, total),
                        Phase::Refine => progress(phase, d, t),
                    },
                )?;
            done += units(r);
            let frame = out.get_or_insert_with(|| Frame::empty(w, h, settings.keep_gbuffer));
            frame.paste(&tile, r);
        }
        Ok(out.expect("an image has at least one tile"))
    }

    /// One frame (or tile) of the image `camera` projects, `settings`-sized.
    fn render_tile(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        view: &View,
        settings: &FrameSettings,
        camera: &CameraParams,
        progress: &mut dyn FnMut(Phase, u64, u64),
    ) -> Result<Frame> {
        let (w, h) = (settings.width, settings.height);
        // Tiles are sized to fit; this catches a forced `max_tile` that does not.
        super::memory::check_frame_fits(super::memory::storage_limit(ctx), w, h)?;
        let pixels = u64::from(w) * u64::from(h);
        let rw = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let gbuffer = empty_storage_buffer(ctx, "G-buffer", pixels * size_of::<GBufferTexel>() as u64, rw)?;
        let masks = empty_storage_buffer(ctx, "shadow masks", pixels * 4, rw)?;
        let values = empty_storage_buffer(ctx, "shaded values", pixels * 16, rw)?;
        let depth = empty_storage_buffer(ctx, "depth", pixels * 4, rw)?;
        let normal = empty_storage_buffer(ctx, "normals", pixels * 16, rw)?;
        let filtered = empty_storage_buffer(ctx, "filtered values", pixels * 16, rw)?;
        let brdf = empty_storage_buffer(ctx, "brdf", pixels * 16, rw)?;
        let status = PrimaryPass::status_buffer(&ctx.device);
        let points = match self.shadow.tracer {
            Tracer::Reference { rays } => sampling::reference_light_points(&view.light, rays),
            _ => sampling::light_points(&view.light),
        };
        let points: Vec<[f32; 4]> = points.iter().map(|p: &Vec3| p.extend(0.0).to_array()).collect();
        let light_points = storage_buffer(ctx, "light points", &points, wgpu::BufferUsages::empty())?;

        let camera_buf = uniform_buffer(ctx, "camera", camera);
        let shade_buf = uniform_buffer(ctx, "shade params", &shade_params(&view.light, w, h));
        let mut timer = GpuTimer::new(ctx, TIMER_CAPACITY);
        let groups = (w.div_ceil(8), h.div_ceil(8));
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
                &gbuffer,
                &status,
                groups,
                writes,
            );
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

        let shadow = shadow_params(&view.light, w, h);
        let shadow_stats = self.shadow.run(
            ctx,
            scene,
            &gbuffer,
            &light_points,
            &masks,
            &shadow,
            Some(&mut timer),
            &mut |done, total| progress(Phase::Shadow, done, total),
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
        let filter = settings.filter.map(|(depth_tolerance, normal_tolerance)| {
            FilterParams::with_tolerances(w, h, depth_tolerance, normal_tolerance)
        });
        if let Some(params) = &filter {
            let params_buf = uniform_buffer(ctx, "filter params", params);
            let bind = self
                .filter
                .bind(ctx, &[&params_buf, &values, &depth, &normal, &filtered]);
            let writes = timer.pass_writes("filter");
            self.filter.record(&mut encoder, "filter", &bind, writes, groups);
        }
        ctx.queue.submit([encoder.finish()]);

        let mut refined = vec![false; pixels as usize];
        // `render_with_phases` checked that a refined frame has the filter.
        if let Some(filter) = filter.filter(|_| settings.refine) {
            let refinement = match self.refinement.get() {
                Some(r) => r,
                None => {
                    let built = Refinement::new(ctx)?;
                    self.refinement.get_or_init(|| built)
                }
            };
            let selection = uniform_buffer(ctx, "refine selection params", &selection_params(&filter));
            let buffers = RefineBuffers {
                size: (w, h),
                selection_params: &selection,
                shadow_params: &shadow,
                shade_params: &shade_buf,
                values: &values,
                depth: &depth,
                normal: &normal,
                gbuffer: &gbuffer,
                light_points: &light_points,
                filtered: &filtered,
            };
            let mut refine_progress = |done, total| progress(Phase::Refine, done, total);
            for p in refinement.run(
                ctx,
                scene,
                &self.shadow,
                &buffers,
                &mut timer,
                &mut refine_progress,
            )? {
                refined[p as usize] = true;
            }
        }
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
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
            refined,
            gbuffer,
            timings: timer.read(ctx)?,
            shadow_stats,
            primary_counters,
            primary_fallback_pixels,
        })
    }
}

/// Bytes of the largest per-pixel buffer (the G-buffer).
const LARGEST_PIXEL_BYTES: u64 = size_of::<GBufferTexel>() as u64;
/// Margin around a tile, for the filter's window (reaches 2 pixels out; a multiple of 4: sample sets).
const TILE_MARGIN: u32 = 4;

/// The largest tile side (a multiple of 4) whose margined G-buffer fits `limit` bytes.
fn tile_side(limit: u64) -> u32 {
    let side = ((limit / LARGEST_PIXEL_BYTES) as f64).sqrt() as u32;
    (side.saturating_sub(2 * TILE_MARGIN) / 4 * 4).max(4)
}

/// A tile: the pixels `[x, x + w) × [y, y + h)` rendered (margin included), of which
/// `[keep_x0, keep_x1) × [keep_y0, keep_y1)` (image coordinates) go into the image.
#[derive(Clone, Copy, Debug)]
struct TileRegion {
    x: u32,
    y: u32,
    w: u32,
    h: u32,
    keep_x0: u32,
    keep_x1: u32,
    keep_y0: u32,
    keep_y1: u32,
}

/// Tiles of side `side` covering a `width`×`height` image, each with its margin.
fn tile_regions(width: u32, height: u32, side: u32) -> Vec<TileRegion> {
    let mut out = Vec::new();
    for y0 in (0..height).step_by(side as usize) {
        for x0 in (0..width).step_by(side as usize) {
            let (x1, y1) = ((x0 + side).min(width), (y0 + side).min(height));
            let (rx, ry) = (x0.saturating_sub(TILE_MARGIN), y0.saturating_sub(TILE_MARGIN));
            let (rx1, ry1) = ((x1 + TILE_MARGIN).min(width), (y1 + TILE_MARGIN).min(height));
            out.push(TileRegion {
                x: rx,
                y: ry,
                w: rx1 - rx,
                h: ry1 - ry,
                keep_x0: x0,
                keep_x1: x1,
                keep_y0: y0,
                keep_y1: y1,
            });
        }
    }
    out
}

impl Frame {
    /// A `width`×`height` frame with nothing in it yet, to paste tiles into.
    fn empty(width: u32, height: u32, keep_gbuffer: bool) -> Frame {
        let n = width as usize * height as usize;
        Frame {
            width,
            height,
            masks: vec![0; n],
            unfiltered: vec![[0.0; 4]; n],
            filtered: vec![[0.0; 4]; n],
            refined: vec![false; n],
            brdf: vec![[0.0; 4]; n],
            gbuffer: keep_gbuffer.then(|| vec![GBufferTexel::default(); n]),
            timings: Vec::new(),
            shadow_stats: ShadowStats::default(),
            primary_counters: crate::counters::Counters::default(),
            primary_fallback_pixels: 0,
        }
    }

    /// Copies the kept part of `tile` (rendered over `r`) into this frame, and adds
    /// its timings and statistics.
    fn paste(&mut self, tile: &Frame, r: &TileRegion) {
        let (w, tw) = (self.width as usize, r.w as usize);
        for y in r.keep_y0..r.keep_y1 {
            let src = (y - r.y) as usize * tw + (r.keep_x0 - r.x) as usize;
            let dst = y as usize * w + r.keep_x0 as usize;
            let n = (r.keep_x1 - r.keep_x0) as usize;
            self.masks[dst..dst + n].copy_from_slice(&tile.masks[src..src + n]);
            self.unfiltered[dst..dst + n].copy_from_slice(&tile.unfiltered[src..src + n]);
            self.filtered[dst..dst + n].copy_from_slice(&tile.filtered[src..src + n]);
            self.refined[dst..dst + n].copy_from_slice(&tile.refined[src..src + n]);
            self.brdf[dst..dst + n].copy_from_slice(&tile.brdf[src..src + n]);
            if let (Some(g), Some(t)) = (self.gbuffer.as_mut(), tile.gbuffer.as_ref()) {
                g[dst..dst + n].copy_from_slice(&t[src..src + n]);
            }
        }
        self.timings.extend(tile.timings.iter().cloned());
        self.shadow_stats.dispatches += tile.shadow_stats.dispatches;
        self.shadow_stats.suspensions += tile.shadow_stats.suspensions;
        self.shadow_stats.counters += tile.shadow_stats.counters;
        self.primary_counters += tile.primary_counters;
        self.primary_fallback_pixels += tile.primary_fallback_pixels;
    }
}

/// The shade kernel's `REFERENCE_RAYS`: 0 unless the masks are reference counts.
fn reference_rays(tracer: Tracer) -> u32 {
    match tracer {
        Tracer::Reference { rays } => rays,
        _ => 0,
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
