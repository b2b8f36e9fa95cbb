//! The multi-frusta shadow pass: a 16-wide vector per 4×4 tile traces the
//! tile's 16 frusta (`shaders/shadow_mft.wgsl`).
//!
//! Lavapipe ends every loop after 65,535 iterations per invocation, counted
//! across all loops (DESIGN.md). The kernel counts its steps; a vector that
//! reaches its budget saves its traversal state and stops, and the pass
//! dispatches again to resume the suspended tiles until none is left. So a
//! tile with any amount of work gets the same answer as an uninterrupted one.
//! A loop that ends any other way (a budget above the driver's limit) is counted
//! in the status word [`WORD_LOOP_CUT`] and the pass fails with [`Error::LoopCut`].

use super::kernel::{AlphaKernels, Checks, buffer, uniform_buffer_on};
use super::{GpuContext, GpuScene, GpuTimer, LeafMode, Tracer, TracerOptions, VectorVariant, read_buffer};
use crate::contract::counters::{Counters, STATUS_WORDS};
use crate::contract::counters::{WORD_LOOP_CUT, WORD_STATUS};
use crate::contract::groups::LINE_GROUP;
use crate::contract::layout::ShadowParams;
use crate::scene::view::QuadLight;
use crate::{Error, Result};

/// 32-bit words of one tile's suspended state (the packet kernel uses fewer).
pub(crate) const STATE_WORDS: u64 = crate::contract::shadow::STATE_WORDS as u64;
/// Tiles per dispatch along each axis: 128×128 tiles = 512×512 pixels, so
/// the state buffer stays at 10 MiB and no dispatch runs for long.
pub(crate) const CHUNK_TILES: u32 = 128;
/// `u32` counts per chunk in [`ShadowScratch::unfinished`]: tiles still suspended after
/// the last resume round, tiles whose loop the driver ended.
pub const UNFINISHED_WORDS: u64 = 2;
/// Resume rounds after which the pass gives up (a bug, not a scene, could cause it).
const MAX_ROUNDS: u32 = 10_000;

/// What a shadow pass did besides writing masks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ShadowStats {
    /// Work counted by the kernel (zero unless built with [`TracerOptions::counters`]).
    pub counters: Counters,
    /// Dispatches (one per chunk plus one per resume round).
    pub dispatches: u32,
    /// Tile suspensions (tiles that ran out of their iteration budget, summed over rounds).
    pub suspensions: u64,
}

/// The shadow pass's pipeline for one tracer, vector variant and leaf mode.
#[derive(Debug)]
pub struct ShadowTracer {
    kernel: AlphaKernels,
    /// The tracer this pass runs.
    pub tracer: Tracer,
    /// The vector variant this pass runs (meaningless for the per-ray tracers).
    pub variant: VectorVariant,
    /// How its leaves use the lanes.
    pub leaf_mode: LeafMode,
    /// Whether the kernel counts its work.
    pub counters: bool,
    /// Whether the MFT kernel shrinks its frusta.
    pub shrink: bool,
    vectors_per_workgroup: u32,
}

/// Workgroups along x of a per-ray dispatch (the rest go along y).
const PER_RAY_GROUPS_X: u32 = 4096;

impl ShadowTracer {
    /// The pipeline of the tracer that `options` describe.
    pub fn new(ctx: &GpuContext, options: &TracerOptions) -> Result<ShadowTracer> {
        let tracer = options.tracer;
        let (variant, vectors_per_workgroup) = if tracer.uses_vector() {
            VectorVariant::choose(&ctx.info, options.variant)?
        } else {
            (VectorVariant::Workgroup, 1)
        };
        let counters = f64::from(u8::from(options.counters));
        let mut constants: Vec<(&str, f64)> = Vec::new();
        match tracer {
            Tracer::Mft => {
                let transposed = f64::from(u8::from(options.leaf_mode == LeafMode::Transposed));
                constants.push(("LEAF_TRANSPOSED", transposed));
                constants.push(("COUNTERS", counters));
                constants.push(("SHRINK", f64::from(u8::from(options.shrink))));
            }
            Tracer::Packet => constants.push(("COUNTERS", counters)),
            Tracer::PerRay | Tracer::Reference { .. } => {
                constants.push(("RAYS_PER_PIXEL", f64::from(tracer.rays_per_pixel())));
            }
            Tracer::RayQuery => {
                if !ctx
                    .device
                    .features()
                    .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
                {
                    let info = &ctx.info;
                    return Err(super::context::ray_queries_missing(
                        &info.name,
                        &info.driver,
                        &info.driver_info,
                    ));
                }
            }
        }
        let aliases: &[(&str, &str)] = if tracer.uses_vector() {
            constants.extend(variant.constants(vectors_per_workgroup));
            variant.aliases()
        } else {
            &[]
        };
        let kernel = AlphaKernels::new(
            ctx,
            tracer.kernel(),
            aliases,
            &constants,
            // Indices: BVH ranges validated by GpuScene::new, stack indices clamped,
            // pixel and state slots bounded by the parameters the host sets here; the
            // transposed leaves index the 256 light points and the workgroup's origins
            // with lane numbers (< 16) and the vector's index in its workgroup; the
            // per-ray kernel indexes the light points below RAYS_PER_PIXEL (or 256).
            Checks::Unchecked,
        )?;
        Ok(ShadowTracer {
            kernel,
            tracer,
            variant,
            leaf_mode: options.leaf_mode,
            counters: options.counters,
            shrink: options.shrink && tracer == Tracer::Mft,
            vectors_per_workgroup,
        })
    }

    /// Light points the kernel reads: 256 (16 interleaved sets) or the reference's own.
    pub fn light_point_count(&self) -> u32 {
        match self.tracer {
            Tracer::Reference { rays } => rays,
            _ => crate::sampling::SAMPLES as u32,
        }
    }

    /// The light points of `light` that the kernel reads, uploaded: the 16 interleaved
    /// sets of [`crate::sampling::light_points`], or the reference tracer's own
    /// ([`crate::sampling::reference_light_points`]); `vec4` each, w unused. The 256 of
    /// the interleaved sets are also a uniform buffer (the MFT kernel reads them as one).
    pub fn light_points_buffer(&self, device: &wgpu::Device, light: &QuadLight) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        let (points, usage) = match self.tracer {
            Tracer::Reference { rays } => (
                crate::sampling::reference_light_points(light, rays),
                wgpu::BufferUsages::STORAGE,
            ),
            _ => (
                crate::sampling::light_points(light),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::UNIFORM,
            ),
        };
        let points: Vec<[f32; 4]> = points.iter().map(|p| p.extend(0.0).to_array()).collect();
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("light points"),
            contents: bytemuck::cast_slice(&points),
            usage,
        })
    }

    /// The parameters of each dispatch chunk of the image `params` describes: its first
    /// unit (tile or pixel) and its size in units, at most `CHUNK_TILES` a side.
    fn chunk_params(&self, params: &ShadowParams) -> Vec<ShadowParams> {
        let unit = self.tracer.unit();
        let (units_x, units_y) = (params.width.div_ceil(unit), params.height.div_ceil(unit));
        let mut out = Vec::new();
        for ty0 in (0..units_y).step_by(CHUNK_TILES as usize) {
            for tx0 in (0..units_x).step_by(CHUNK_TILES as usize) {
                out.push(ShadowParams {
                    tile_origin_x: tx0,
                    tile_origin_y: ty0,
                    tiles_x: CHUNK_TILES.min(units_x - tx0),
                    tiles_y: CHUNK_TILES.min(units_y - ty0),
                    ..*params
                });
            }
        }
        out
    }

    /// Workgroups of a dispatch over `units` units (tiles or pixels).
    fn groups(&self, units: u32) -> (u32, u32) {
        if self.tracer.uses_vector() {
            (units.div_ceil(self.vectors_per_workgroup), 1)
        } else {
            let groups = (units * self.tracer.rays_per_pixel()).div_ceil(LINE_GROUP);
            (groups.min(PER_RAY_GROUPS_X), groups.div_ceil(PER_RAY_GROUPS_X))
        }
    }

    /// The bind group of one dispatch: `params` (its chunk and round) and the image's buffers.
    fn bind(
        &self,
        device: &wgpu::Device,
        scene: &GpuScene,
        image: &ShadowImage<'_>,
        scratch: &ShadowScratch,
        params: &ShadowParams,
    ) -> Result<wgpu::BindGroup> {
        let params = uniform_buffer_on(device, "shadow params", params);
        if self.tracer == Tracer::RayQuery {
            let tlas = scene.ray_query.as_ref().ok_or_else(|| {
                Error::Gpu(
                    "the ray-query tracer needs a GpuScene made on a device with ray queries \
                     (GpuOptions::ray_query)"
                        .into(),
                )
            })?;
            return self.kernel.for_scene(scene)?.bind(
                device,
                &[
                    buffer("params", &params),
                    ("scene_tlas", tlas.tlas.as_binding()),
                    buffer("gbuffer", image.gbuffer),
                    buffer("light_points", image.light_points),
                    buffer("masks", image.masks),
                    buffer("triangles", &scene.triangles),
                    buffer("alpha", &scene.alpha),
                ],
            );
        }
        let kernel = self.kernel.for_scene(scene)?;
        let mut resources = vec![
            buffer("params", &params),
            buffer("nodes", &scene.nodes),
            buffer("triangles", &scene.triangles),
            buffer("gbuffer", image.gbuffer),
            buffer("light_points", image.light_points),
            buffer("masks", image.masks),
            buffer("state", &scratch.state),
            buffer("status", &scratch.status),
        ];
        // Only the build for scenes with alpha-tested triangles binds them (AlphaKernels).
        if kernel.bindings.iter().any(|(_, name)| name == "alpha") {
            resources.push(buffer("alpha", &scene.alpha));
        }
        kernel.bind(device, &resources)
    }

    /// Records round `round` of the chunk `chunk` (round 0 starts its tiles afresh, later
    /// rounds resume those that saved their state in `scratch.state`). Both drivers,
    /// [`ShadowTracer::run`] and [`ShadowTracer::record`], dispatch through here.
    #[allow(clippy::too_many_arguments)]
    fn record_round(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        image: &ShadowImage<'_>,
        scratch: &ShadowScratch,
        chunk: &ShadowParams,
        round: u32,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<()> {
        let params = ShadowParams {
            resume: u32::from(round > 0),
            ..*chunk
        };
        let bind = self.bind(device, scene, image, scratch, &params)?;
        let groups = self.groups(chunk.tiles_x * chunk.tiles_y);
        self.kernel
            .for_scene(scene)?
            .record(encoder, "shadow/trace", &bind, timestamp_writes, groups);
        Ok(())
    }

    /// Traces the shadow masks of a whole image and waits for them: `image.gbuffer`
    /// (width × height texels) and `image.light_points` ([`ShadowTracer::light_point_count`]
    /// `vec4`s) in, `image.masks` (`COPY_DST`) out. `params` gives the light and image
    /// size; its tile fields are set here. Each chunk is dispatched, and resumed while
    /// tiles are suspended, one submission at a time, each timed as `label` when a timer is
    /// given (the frame's shadow pass is `shadow`; the refinement's sample images `refine`);
    /// `progress(units done, units)` follows the chunks.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        image: &ShadowImage<'_>,
        params: &ShadowParams,
        mut timer: Option<&mut GpuTimer>,
        label: &str,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<ShadowStats> {
        let unit = self.tracer.unit();
        let units_x = params.width.div_ceil(unit);
        let units_y = params.height.div_ceil(unit);
        let state_bytes = if self.tracer.uses_vector() {
            let chunk =
                u64::from(CHUNK_TILES.min(units_x).max(1)) * u64::from(CHUNK_TILES.min(units_y).max(1));
            chunk * STATE_WORDS * 4
        } else {
            4
        };
        let scratch = ShadowScratch::sized(&ctx.device, state_bytes, 1);
        if !self.tracer.uses_vector() {
            // The per-ray kernel ORs (or adds) each ray into its pixel's word.
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(image.masks, 0, None);
            ctx.queue.submit([encoder.finish()]);
        }
        let mut stats = ShadowStats::default();
        let total_units = u64::from(units_x) * u64::from(units_y);
        let mut units_done = 0u64;
        for chunk in self.chunk_params(params) {
            for round in 0.. {
                if round == MAX_ROUNDS {
                    return Err(Error::Gpu(format!(
                        "shadow pass: tiles still suspended after {MAX_ROUNDS} rounds"
                    )));
                }
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.clear_buffer(&scratch.status, 0, None);
                let writes = timer.as_deref_mut().and_then(|t| t.pass_writes(label));
                self.record_round(
                    &ctx.device,
                    &mut encoder,
                    scene,
                    image,
                    &scratch,
                    &chunk,
                    round,
                    writes,
                )?;
                ctx.queue.submit([encoder.finish()]);
                stats.dispatches += 1;
                let words = read_buffer::<u32>(ctx, &scratch.status, 0..(STATUS_WORDS * 4) as u64)?;
                stats.counters += Counters::from_status_words(&words);
                if words[WORD_LOOP_CUT] != 0 {
                    return Err(Error::LoopCut {
                        pass: format!("shadow pass ({})", self.tracer),
                        count: words[WORD_LOOP_CUT].into(),
                        units: if self.tracer.uses_vector() {
                            "vectors"
                        } else {
                            "rays"
                        }
                        .into(),
                        budget: params.iteration_budget,
                    });
                }
                if words[WORD_STATUS] == 0 {
                    break;
                }
                if !self.tracer.uses_vector() {
                    return Err(Error::Gpu(format!(
                        "shadow pass ({}): {} rays ran out of their {} loop iterations \
                             (BVH too deep or degenerate)",
                        self.tracer, words[WORD_STATUS], params.iteration_budget
                    )));
                }
                stats.suspensions += u64::from(words[WORD_STATUS]);
            }
            units_done += u64::from(chunk.tiles_x * chunk.tiles_y);
            progress(units_done, total_units);
        }
        stats.counters.suspensions = stats.suspensions;
        Ok(stats)
    }

    /// Records the whole shadow pass into `encoder` without waiting on the GPU, for hosts
    /// that submit it with their own frame: each chunk of tiles gets its first dispatch and
    /// then `resume_rounds` resume dispatches (a resume dispatch over a chunk with nothing
    /// suspended costs one early exit per tile). The first dispatch starts every tile
    /// afresh, whatever earlier records left in `scratch`. Per chunk (see
    /// [`ShadowTracer::chunks`]), two `u32`s of `unfinished` count the tiles still
    /// suspended after the chunk's last round (`resume_rounds` was too small for this
    /// scene and view) and the tiles whose loop the driver ended (an iteration budget
    /// above its limit); a non-zero count means the masks of those tiles are incomplete.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        image: &ShadowImage<'_>,
        scratch: &ShadowScratch,
        params: &ShadowParams,
        resume_rounds: u32,
    ) -> Result<()> {
        let resume_rounds = if self.tracer.uses_vector() {
            resume_rounds
        } else {
            encoder.clear_buffer(image.masks, 0, None);
            0
        };
        let word = |w: usize| (w * 4) as u64;
        for (chunk_index, chunk) in (0u64..).zip(self.chunk_params(params)) {
            // Loops cut short add up over the chunk's rounds; suspensions count only in
            // its last round (what is left then stays unfinished).
            encoder.clear_buffer(&scratch.status, 0, None);
            for round in 0..=resume_rounds {
                if round == resume_rounds {
                    encoder.clear_buffer(&scratch.status, word(WORD_STATUS), Some(4));
                }
                self.record_round(device, encoder, scene, image, scratch, &chunk, round, None)?;
            }
            let out = chunk_index * UNFINISHED_WORDS * 4;
            encoder.copy_buffer_to_buffer(&scratch.status, word(WORD_STATUS), &scratch.unfinished, out, 4);
            encoder.copy_buffer_to_buffer(
                &scratch.status,
                word(WORD_LOOP_CUT),
                &scratch.unfinished,
                out + 4,
                4,
            );
        }
        Ok(())
    }

    /// Chunks of tiles a `width`×`height` image is traced in by the MFT tracer
    /// ([`UNFINISHED_WORDS`] `unfinished` counts each; the one-pixel tracers need more, see
    /// [`ShadowScratch::new`]).
    pub fn chunks(width: u32, height: u32) -> u64 {
        let (tiles_x, tiles_y) = (width.div_ceil(4), height.div_ceil(4));
        u64::from(tiles_x.div_ceil(CHUNK_TILES)) * u64::from(tiles_y.div_ceil(CHUNK_TILES))
    }
}

/// The buffers a shadow pass reads and writes for one image.
#[derive(Clone, Copy, Debug)]
pub struct ShadowImage<'a> {
    /// `array<GBufferTexel>`, width × height.
    pub gbuffer: &'a wgpu::Buffer,
    /// [`ShadowTracer::light_point_count`] `vec4`s (w unused), as
    /// [`ShadowTracer::light_points_buffer`] makes them: the MFT kernel binds them as a
    /// uniform buffer, so its buffer needs `UNIFORM` as well as `STORAGE`.
    pub light_points: &'a wgpu::Buffer,
    /// `array<u32>`, one mask per pixel (`COPY_DST`: the per-ray tracers clear it first).
    pub masks: &'a wgpu::Buffer,
}

/// The buffers [`ShadowTracer::record`] needs besides its inputs and outputs, sized for
/// one image size: suspended-tile state, the per-dispatch suspension counter, and the
/// per-chunk count of tiles left unfinished (`COPY_SRC`, for the host to read).
#[derive(Debug)]
pub struct ShadowScratch {
    /// Suspended state of one chunk's tiles.
    pub state: wgpu::Buffer,
    /// `[0]`: tiles suspended by the dispatch just run.
    pub status: wgpu::Buffer,
    /// [`UNFINISHED_WORDS`] `u32`s per chunk: tiles still suspended after the chunk's last
    /// round, tiles whose loop the driver ended.
    pub unfinished: wgpu::Buffer,
}

impl ShadowScratch {
    /// Scratch buffers for `width`×`height` images, on `device`, sized for any tracer
    /// (the one-pixel tracers' chunks are the largest).
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> ShadowScratch {
        let units = u64::from(CHUNK_TILES.min(width).max(1)) * u64::from(CHUNK_TILES.min(height).max(1));
        let chunks = u64::from(width.div_ceil(CHUNK_TILES)) * u64::from(height.div_ceil(CHUNK_TILES));
        ShadowScratch::sized(device, units * STATE_WORDS * 4, chunks)
    }

    /// Scratch with `state_bytes` of suspended state and room for `chunks` chunks' counts.
    fn sized(device: &wgpu::Device, state_bytes: u64, chunks: u64) -> ShadowScratch {
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        ShadowScratch {
            state: buffer(
                "shadow state",
                state_bytes,
                // Readable so that tests can compare the saved state with the CPU twin's.
                wgpu::BufferUsages::COPY_SRC,
            ),
            status: buffer(
                "shadow status",
                (STATUS_WORDS * 4) as u64,
                wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
            unfinished: buffer(
                "shadow unfinished tiles",
                chunks * UNFINISHED_WORDS * 4,
                wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }
}
