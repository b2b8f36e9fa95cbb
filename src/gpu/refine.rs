//! The refinement pass: after the filter, the pixels where visibility changes around them
//! and the filter's window is cut or their own rays agree get all 256 light samples (or the
//! first [`super::FrameSettings::refine_sets`] of the 16 sets), and their filtered value
//! becomes the one of those rays (see [`crate::reference::refine`], the CPU twin, for why
//! and which pixels).
//!
//! Three kernels and the frame's own shadow tracer: `refine_select` lists the pixels (one
//! invocation per pixel); the host reads how many; per chunk of the list, `refine_gather`
//! builds a *sample image* in which each listed pixel is a 4×4 tile of copies of its
//! G-buffer texel (so the tile's 16 pixels trace the 16 sample sets; with fewer sets the
//! rest of the tile is sky), the shadow tracer
//! (multi-frusta, packet or per-ray, as for the frame) traces it like any image, and
//! `refine_resolve` sums each tile's masks into its pixel's value. The multi-frusta
//! kernel then traces a pixel's 256 rays as one vector of 16 frusta that share their
//! origin, and its masks are the oracle's, as for every frame.
//!
//! Under a ray budget ([`super::FrameSettings::ray_budget`]) the host reads the list and the
//! score `refine_select` gave each pixel, keeps the [`budget_pixels`] with the highest scores
//! ([`within_budget`]) and writes them back before the gather.

use super::kernel::{Checks, Kernel, buffer, texture, uniform_buffer};
use super::pixel_buffers::PixelBuffers;
use super::{GpuContext, GpuScene, GpuTimer, ShadowImage, ShadowTracer, empty_storage_buffer, read_buffer};
use crate::contract::groups::{LINE_GROUP, PIXEL_GROUP};
use crate::contract::layout::{GBufferTexel, RefineParams, ShadowParams};
use crate::contract::refine::{budget_pixels, pixels_per_tile, within_budget};
use crate::sampling::SETS;
use crate::{Error, Result};

/// Tiles per row of a sample image (1,024 pixels wide): wide enough that the shadow
/// tracer's chunks of 128×128 tiles are full, narrow enough that a short list wastes
/// little of its last row.
const SAMPLE_TILES_X: u32 = 256;

/// The buffers of one frame (or tile) the refinement reads and writes.
pub struct RefineBuffers<'a> {
    /// `FilterParams` uniform for `refine_select`: the filter's, with the refinement's
    /// visibility tolerance ([`crate::contract::refine::selection_params`]).
    pub selection_params: &'a wgpu::Buffer,
    /// The frame's `ShadowParams` (light, `t_max`, budget); its size fields are replaced.
    pub shadow_params: &'a ShadowParams,
    /// `ShadeParams` uniform of the frame's shade pass.
    pub shade_params: &'a wgpu::Buffer,
    /// The frame's per-pixel buffers: the shade pass's outputs and the G-buffer are read,
    /// `filtered` is overwritten at the refined pixels.
    pub pixels: &'a PixelBuffers,
    /// The 256 interleaved light points, set order
    /// ([`crate::gpu::ShadowTracer::light_points_buffer`]: `STORAGE | UNIFORM`).
    pub light_points: &'a wgpu::Buffer,
}

/// The refinement's three pipelines (the tracer is the frame's).
#[derive(Debug)]
pub struct Refinement {
    select: Kernel,
    gather: Kernel,
    resolve: Kernel,
}

impl Refinement {
    /// Builds the pipelines.
    pub fn new(ctx: &GpuContext) -> Result<Refinement> {
        let kernel = |name| Kernel::new(ctx, name, &[], &[], Checks::Checked);
        Ok(Refinement {
            select: kernel("refine_select")?,
            gather: kernel("refine_gather")?,
            resolve: kernel("refine_resolve")?,
        })
    }

    /// Refines the frame of `b` (its filter submitted), tracing with
    /// `tracer`, each refined pixel tracing sample sets `0..sets`; with a ray `budget`
    /// (average rays per pixel with geometry, the frame's 16 included) only the
    /// highest-scoring pixels it allows. Returns the refined pixels'
    /// indices (row-major), sorted. Every dispatch,
    /// the tracer's included, is timed as `refine`; `progress` gets the tracer's progress
    /// over each chunk's sample image.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        tracer: &ShadowTracer,
        b: &RefineBuffers<'_>,
        budget: Option<f32>,
        sets: u32,
        timer: &mut GpuTimer,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Vec<u32>> {
        let (width, height) = b.pixels.size;
        let pixels = u64::from(width) * u64::from(height);
        let rw = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let list = empty_storage_buffer(ctx, "refine list", (2 + pixels) * 4, rw)?;
        let scores = empty_storage_buffer(ctx, "refine scores", pixels * 4, wgpu::BufferUsages::COPY_SRC)?;

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let p = b.pixels;
        // The filter's input textures, filled for this frame's filter (a refined frame has one).
        let values = p.values_texture.create_view(&Default::default());
        let normal = p.normal_texture.create_view(&Default::default());
        let bind = self.select.bind(
            &ctx.device,
            &[
                buffer("filter_params", b.selection_params),
                texture("values", &values),
                texture("normal", &normal),
                buffer("list", &list),
                buffer("filtered", &p.filtered),
                buffer("scores", &scores),
            ],
        )?;
        let writes = timer.pass_writes("refine");
        let groups = (width.div_ceil(PIXEL_GROUP), height.div_ceil(PIXEL_GROUP));
        self.select
            .record(&mut encoder, "refine select", &bind, writes, groups);
        ctx.queue.submit([encoder.finish()]);
        let header = read_buffer::<u32>(ctx, &list, 0..8)?;
        let (mut listed, geometry) = (header[0], header[1]);
        let keep = budget.map_or(listed, |b| budget_pixels(b, geometry, sets).min(listed));
        // Under a budget that binds, or when a tile holds several pixels (each tracing the
        // sets of its place in the list), the list is cut and put in pixel order.
        if listed > 0 && (keep < listed || sets < SETS as u32) {
            let slots = u64::from(listed) * 4;
            let pixels = read_buffer::<u32>(ctx, &list, 8..8 + slots)?;
            let scores = read_buffer::<f32>(ctx, &scores, 0..slots)?;
            let pairs: Vec<(u32, f32)> = pixels.into_iter().zip(scores).collect();
            let kept = within_budget(&pairs, keep);
            listed = kept.len() as u32;
            ctx.queue.write_buffer(&list, 0, bytemuck::bytes_of(&listed));
            if listed > 0 {
                ctx.queue.write_buffer(&list, 8, bytemuck::cast_slice(&kept));
            }
        }
        if listed == 0 {
            return Ok(Vec::new());
        }

        // Chunks whose sample image (16 texels per tile) fits one storage binding, whole
        // rows of whole tiles (so every chunk's first slot starts a tile).
        let per_tile = pixels_per_tile(sets);
        let tiles = listed.div_ceil(per_tile);
        let texel = size_of::<GBufferTexel>() as u64;
        let tiles_x = SAMPLE_TILES_X.min(tiles);
        let fit = ctx.info.max_storage_buffer_binding_size / (SETS as u64 * texel);
        // The resolve dispatch has one invocation per slot, 64 per workgroup, along x.
        let fit =
            fit.min(u64::from(ctx.info.max_compute_workgroups_per_dimension) * 64 / u64::from(per_tile));
        let chunk_tiles = (fit.min(u64::from(tiles)) as u32 / tiles_x * tiles_x).max(tiles_x);
        if u64::from(tiles_x) > fit {
            return Err(Error::Gpu(format!(
                "refinement: a sample image row of {tiles_x} tiles does not fit one storage buffer"
            )));
        }
        let chunk = chunk_tiles * per_tile;
        for first_slot in (0..listed).step_by(chunk as usize) {
            let params = RefineParams {
                tiles_x,
                first_slot,
                slots: chunk.min(listed - first_slot),
                sets,
            };
            self.trace_chunk(ctx, scene, tracer, b, &list, &params, timer, progress)?;
        }
        let mut refined = read_buffer::<u32>(ctx, &list, 8..(2 + u64::from(listed)) * 4)?;
        refined.sort_unstable();
        Ok(refined)
    }

    /// Gathers, traces and resolves the sample image of one chunk of the list.
    #[allow(clippy::too_many_arguments)]
    fn trace_chunk(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        tracer: &ShadowTracer,
        b: &RefineBuffers<'_>,
        list: &wgpu::Buffer,
        params: &RefineParams,
        timer: &mut GpuTimer,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<()> {
        let (w, h) = params.image_size();
        let n = u64::from(w) * u64::from(h);
        let texel = size_of::<GBufferTexel>() as u64;
        let usage = wgpu::BufferUsages::COPY_DST;
        let samples = empty_storage_buffer(ctx, "refine sample image", n * texel, usage)?;
        let masks = empty_storage_buffer(ctx, "refine sample masks", n * 4, usage)?;
        let params_buf = uniform_buffer(ctx, "refine params", params);

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let bind = self.gather.bind(
            &ctx.device,
            &[
                buffer("params", &params_buf),
                buffer("gbuffer", &b.pixels.gbuffer),
                buffer("list", list),
                buffer("samples", &samples),
            ],
        )?;
        let writes = timer.pass_writes("refine");
        let groups = (w.div_ceil(PIXEL_GROUP), h.div_ceil(PIXEL_GROUP));
        self.gather
            .record(&mut encoder, "refine gather", &bind, writes, groups);
        ctx.queue.submit([encoder.finish()]);

        let shadow = ShadowParams {
            width: w,
            height: h,
            tiles_x: w.div_ceil(4),
            tiles_y: h.div_ceil(4),
            ..*b.shadow_params
        };
        let image = ShadowImage {
            gbuffer: &samples,
            light_points: b.light_points,
            masks: &masks,
        };
        tracer.run(ctx, scene, &image, &shadow, Some(timer), "refine", progress)?;

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let bind = self.resolve.bind(
            &ctx.device,
            &[
                buffer("params", &params_buf),
                buffer("shade", b.shade_params),
                buffer("gbuffer", &b.pixels.gbuffer),
                buffer("list", list),
                buffer("sample_masks", &masks),
                buffer("filtered", &b.pixels.filtered),
            ],
        )?;
        let writes = timer.pass_writes("refine");
        self.resolve.record(
            &mut encoder,
            "refine resolve",
            &bind,
            writes,
            (params.slots.div_ceil(LINE_GROUP), 1),
        );
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    }
}
