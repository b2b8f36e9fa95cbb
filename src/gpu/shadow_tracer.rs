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

use super::kernel::{Checks, Kernel, uniform_buffer, uniform_buffer_on};
pub use super::tracer::Tracer;
use super::{AdapterSummary, GpuContext, GpuScene, GpuTimer, empty_storage_buffer, read_buffer};
use crate::counters::{Counters, STATUS_WORDS};
use crate::counters::{WORD_LOOP_CUT, WORD_STATUS};
use crate::layout::ShadowParams;
use crate::{Error, Result};

/// 32-bit words of one tile's suspended state ([`crate::contract::shadow::STATE_WORDS`];
/// the packet kernel uses the first 160).
pub(crate) const STATE_WORDS: u64 = crate::contract::shadow::STATE_WORDS as u64;
/// Tiles per dispatch along each axis: 128×128 tiles = 512×512 pixels, so
/// the state buffer stays at 10 MiB and no dispatch runs for long.
pub(crate) const CHUNK_TILES: u32 = 128;
/// `u32` counts per chunk in [`ShadowScratch::unfinished`]: tiles still suspended after
/// the last resume round, tiles whose loop the driver ended.
pub const UNFINISHED_WORDS: u64 = 2;
/// Resume rounds after which the pass gives up (a bug, not a scene, could cause it).
const MAX_ROUNDS: u32 = 10_000;

/// How the kernel's 16-wide vector is built from invocations (DESIGN.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum VectorVariant {
    /// 16 lanes of a subgroup; needs subgroups of a fixed size that is a multiple of 16.
    Subgroup,
    /// A 16-invocation workgroup exchanging through workgroup memory; works everywhere.
    Workgroup,
}

impl std::fmt::Display for VectorVariant {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            VectorVariant::Subgroup => "subgroup",
            VectorVariant::Workgroup => "workgroup",
        })
    }
}

impl VectorVariant {
    /// The variant for an adapter: `forced` if given (an error when the adapter cannot run it),
    /// else subgroups when they are a fixed multiple of 16 wide, else workgroups.
    /// Returns the variant and the number of vectors per workgroup.
    pub fn choose(info: &AdapterSummary, forced: Option<VectorVariant>) -> Result<(VectorVariant, u32)> {
        let size = info.subgroup_min_size;
        let subgroup_ok = info.has_subgroups
            && info.subgroup_min_size == info.subgroup_max_size
            && size.is_multiple_of(16)
            && (16..=64).contains(&size);
        match forced {
            Some(VectorVariant::Workgroup) => Ok((VectorVariant::Workgroup, 1)),
            Some(VectorVariant::Subgroup) if !subgroup_ok => Err(Error::Gpu(format!(
                "the subgroup vector needs subgroups of one fixed size that is a multiple of 16; \
                 {} has {}subgroups of {}..{} lanes (on lavapipe set LP_NATIVE_VECTOR_WIDTH=512 \
                 for 16-wide subgroups, or use --vector workgroup)",
                info.name,
                if info.has_subgroups { "" } else { "no " },
                info.subgroup_min_size,
                info.subgroup_max_size
            ))),
            Some(VectorVariant::Subgroup) => Ok((VectorVariant::Subgroup, size / 16)),
            None if subgroup_ok => Ok((VectorVariant::Subgroup, size / 16)),
            None => Ok((VectorVariant::Workgroup, 1)),
        }
    }

    fn module(self) -> &'static str {
        match self {
            VectorVariant::Subgroup => "shared/vec16_subgroup",
            VectorVariant::Workgroup => "shared/vec16_workgroup",
        }
    }
}

/// How the kernel spends the vector's 16 lanes on a leaf triangle (DESIGN.md, "MFT in
/// WGSL"). Both give the same masks bit for bit; only the speed differs.
///
/// `PerLane` is the default because it is the faster one on lavapipe, by 1.2–2.2×.
/// Shadow pass, GPU ms, min / median of 3 runs (Mrays/s at the median), 256×256,
/// `penumbra render`, Mesa 22.3.6 lavapipe on 2 AVX-512 cores (measured before the per-lane
/// form took two triangles per loop step, which made it faster still):
///
/// | scene, vector                          | per-lane          | transposed        |
/// |----------------------------------------|-------------------|-------------------|
/// | Sponza atrium (1.01 M rays), subgroup  | 378 / 415 (2.44)  | 898 / 903 (1.12)  |
/// | lattice (0.67 M rays), subgroup        | 205 / 205 (3.25)  | 247 / 252 (2.64)  |
/// | Sponza atrium, workgroup               | 3053 / 3442 (0.29)| 6783 / 6976 (0.15)|
/// | lattice, workgroup                     | 1163 / 1187 (0.56)| 1798 / 1829 (0.36)|
///
/// (subgroup: `LP_NATIVE_VECTOR_WIDTH=512`, 16-wide subgroups; workgroup: the default
/// 8-wide build.) Lavapipe loads memory one lane at a time, so the transposed form
/// pays two gathers (an origin, a light point) per surviving frustum where the per-lane
/// form reuses the samples' light coordinates held in registers; and its ballots cost barriers in the
/// workgroup vector. On a GPU, whose loads and ballots are cheap, the balance may differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LeafMode {
    /// Lane `j` culls the triangle against its own frustum and, if it survives, tests the
    /// frustum's 16 rays itself (unrolled): no cross-lane traffic, up to two triangles per
    /// loop step.
    #[default]
    PerLane,
    /// The paper's form: lane `j` only culls; then for each frustum `f` that survives (a
    /// ballot, bit-scanned lowest first, in an inner loop whose every pass counts towards
    /// the iteration budget) lane `i` tests ray `i` of `f`, from `f`'s origin in workgroup
    /// memory, and a ballot of the hits is OR-ed into `f`'s mask.
    Transposed,
}

impl std::fmt::Display for LeafMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LeafMode::PerLane => "per-lane",
            LeafMode::Transposed => "transposed",
        })
    }
}

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

/// What a shadow tracer is built with besides the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TracerOptions {
    /// The tracer.
    pub tracer: Tracer,
    /// Force a vector variant, or `None` for the adapter's best (vector tracers only).
    pub variant: Option<VectorVariant>,
    /// How the MFT kernel's leaves use the lanes.
    pub leaf_mode: LeafMode,
    /// Count work as Table 1 does (MFT and packet; see [`Counters`]). Off, the kernels
    /// are compiled without the counting code.
    pub counters: bool,
    /// MFT: shrink frusta to their own samples at the start and after leaves that
    /// blocked rays (the paper's "CR", §5.3; see
    /// [`crate::reference::mft::Frustum::shrink_to`]). Same masks, fewer triangle
    /// tests, a little more work per leaf. On by default: on Sponza's atrium at
    /// 1024×1024 it cuts the triangle tests 11× and the shadow pass takes 0.3×
    /// the time (`penumbra bench --without-cr`).
    pub shrink: bool,
}

impl Default for TracerOptions {
    fn default() -> TracerOptions {
        TracerOptions {
            tracer: Tracer::default(),
            variant: None,
            leaf_mode: LeafMode::default(),
            counters: false,
            shrink: true,
        }
    }
}

/// The shadow pass's pipeline for one tracer, vector variant and leaf mode.
#[derive(Debug)]
pub struct ShadowTracer {
    kernel: Kernel,
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

/// Invocations per workgroup of the per-ray kernel.
const PER_RAY_WG_SIZE: u32 = 64;
/// Workgroups along x of a per-ray dispatch (the rest go along y).
const PER_RAY_GROUPS_X: u32 = 4096;

impl ShadowTracer {
    /// The MFT pipeline; `variant` as in [`VectorVariant::choose`], `leaf_mode` sets the
    /// kernel's `LEAF_TRANSPOSED` override.
    pub fn new(
        ctx: &GpuContext,
        variant: Option<VectorVariant>,
        leaf_mode: LeafMode,
    ) -> Result<ShadowTracer> {
        ShadowTracer::with_options(
            ctx,
            &TracerOptions {
                variant,
                leaf_mode,
                ..TracerOptions::default()
            },
        )
    }

    /// The pipeline of any tracer.
    pub fn with_options(ctx: &GpuContext, options: &TracerOptions) -> Result<ShadowTracer> {
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
        }
        let aliases: &[(&str, &str)] = if tracer.uses_vector() {
            if variant == VectorVariant::Subgroup {
                constants.push(("VEC16_PER_WG", f64::from(vectors_per_workgroup)));
            }
            &[("shared/vec16", variant.module())]
        } else {
            &[]
        };
        let kernel = Kernel::new(
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
            let groups = (units * self.tracer.rays_per_pixel()).div_ceil(PER_RAY_WG_SIZE);
            (groups.min(PER_RAY_GROUPS_X), groups.div_ceil(PER_RAY_GROUPS_X))
        }
    }

    /// Traces the shadow masks of a whole image: `gbuffer` (`array<GBufferTexel>`,
    /// width × height) and `light_points` ([`ShadowTracer::light_point_count`] `vec4`s)
    /// in, `masks` (`array<u32>`, `COPY_DST`) out. `params` gives the light and image
    /// size; its tile fields are set here.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        gbuffer: &wgpu::Buffer,
        light_points: &wgpu::Buffer,
        masks: &wgpu::Buffer,
        params: &ShadowParams,
        timer: Option<&mut GpuTimer>,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<ShadowStats> {
        self.run_timed_as(
            ctx,
            scene,
            gbuffer,
            light_points,
            masks,
            params,
            timer,
            "shadow",
            progress,
        )
    }

    /// [`ShadowTracer::run`] with its dispatches timed as `label` (the refinement traces
    /// its sample images with the frame's tracer, timed as `refine`).
    #[allow(clippy::too_many_arguments)]
    pub fn run_timed_as(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        gbuffer: &wgpu::Buffer,
        light_points: &wgpu::Buffer,
        masks: &wgpu::Buffer,
        params: &ShadowParams,
        mut timer: Option<&mut GpuTimer>,
        label: &str,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<ShadowStats> {
        let unit = self.tracer.unit();
        let units_x = params.width.div_ceil(unit);
        let units_y = params.height.div_ceil(unit);
        let chunk = CHUNK_TILES.min(units_x).max(1) as u64 * CHUNK_TILES.min(units_y).max(1) as u64;
        let state = if self.tracer.uses_vector() {
            empty_storage_buffer(
                ctx,
                "shadow state",
                chunk * STATE_WORDS * 4,
                wgpu::BufferUsages::empty(),
            )?
        } else {
            empty_storage_buffer(ctx, "shadow state (unused)", 4, wgpu::BufferUsages::empty())?
        };
        let status = empty_storage_buffer(
            ctx,
            "shadow status",
            (STATUS_WORDS * 4) as u64,
            wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        )?;
        let params_buf = uniform_buffer(ctx, "shadow params", params);
        let bind = self.kernel.bind(
            ctx,
            &[
                &params_buf,
                &scene.nodes,
                &scene.triangles,
                gbuffer,
                light_points,
                masks,
                &state,
                &status,
            ],
        );
        if !self.tracer.uses_vector() {
            // The per-ray kernel ORs (or adds) each ray into its pixel's word.
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(masks, 0, None);
            ctx.queue.submit([encoder.finish()]);
        }
        let mut stats = ShadowStats::default();
        let total_units = u64::from(units_x) * u64::from(units_y);
        let mut units_done = 0u64;
        for mut p in self.chunk_params(params) {
            let units = p.tiles_x * p.tiles_y;
            let groups = self.groups(units);
            for round in 0.. {
                if round == MAX_ROUNDS {
                    return Err(Error::Gpu(format!(
                        "shadow pass: tiles still suspended after {MAX_ROUNDS} rounds"
                    )));
                }
                p.resume = u32::from(round > 0);
                ctx.queue.write_buffer(&params_buf, 0, bytemuck::bytes_of(&p));
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.clear_buffer(&status, 0, None);
                let writes = timer.as_deref_mut().and_then(|t| t.pass_writes(label));
                self.kernel
                    .record(&mut encoder, "shadow/trace", &bind, writes, groups);
                ctx.queue.submit([encoder.finish()]);
                stats.dispatches += 1;
                let words = read_buffer::<u32>(ctx, &status, 0..(STATUS_WORDS * 4) as u64)?;
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
            units_done += u64::from(units);
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
        gbuffer: &wgpu::Buffer,
        light_points: &wgpu::Buffer,
        masks: &wgpu::Buffer,
        scratch: &ShadowScratch,
        params: &ShadowParams,
        resume_rounds: u32,
    ) {
        let resume_rounds = if self.tracer.uses_vector() {
            resume_rounds
        } else {
            encoder.clear_buffer(masks, 0, None);
            0
        };
        let word = |w: usize| (w * 4) as u64;
        for (chunk_index, mut p) in (0u64..).zip(self.chunk_params(params)) {
            let groups = self.groups(p.tiles_x * p.tiles_y);
            // Loops cut short add up over the chunk's rounds; suspensions count only in
            // its last round (what is left then stays unfinished).
            encoder.clear_buffer(&scratch.status, 0, None);
            for round in 0..=resume_rounds {
                p.resume = u32::from(round > 0);
                if round == resume_rounds {
                    encoder.clear_buffer(&scratch.status, word(WORD_STATUS), Some(4));
                }
                let params_buf = uniform_buffer_on(device, "shadow params", &p);
                let bind = self.kernel.bind_on(
                    device,
                    &[
                        &params_buf,
                        &scene.nodes,
                        &scene.triangles,
                        gbuffer,
                        light_points,
                        masks,
                        &scratch.state,
                        &scratch.status,
                    ],
                );
                self.kernel.record(encoder, "shadow/trace", &bind, None, groups);
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
    }

    /// Chunks of tiles a `width`×`height` image is traced in by the MFT tracer
    /// ([`UNFINISHED_WORDS`] `unfinished` counts each; the one-pixel tracers need more, see
    /// [`ShadowScratch::new`]).
    pub fn chunks(width: u32, height: u32) -> u64 {
        let (tiles_x, tiles_y) = (width.div_ceil(4), height.div_ceil(4));
        u64::from(tiles_x.div_ceil(CHUNK_TILES)) * u64::from(tiles_y.div_ceil(CHUNK_TILES))
    }
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
        let tiles = u64::from(CHUNK_TILES.min(width).max(1)) * u64::from(CHUNK_TILES.min(height).max(1));
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
                tiles * STATE_WORDS * 4,
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
                u64::from(width.div_ceil(CHUNK_TILES))
                    * u64::from(height.div_ceil(CHUNK_TILES))
                    * UNFINISHED_WORDS
                    * 4,
                wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
        }
    }
}
