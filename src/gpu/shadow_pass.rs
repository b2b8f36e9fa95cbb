//! The multi-frusta shadow pass: a 16-wide vector per 4×4 tile traces the
//! tile's 16 frusta (`shaders/shadow_mft.wgsl`).
//!
//! Lavapipe ends every loop after 65,535 iterations per invocation, counted
//! across all loops (DESIGN.md). The kernel counts its steps; a vector that
//! reaches its budget saves its traversal state and stops, and the pass
//! dispatches again to resume the suspended tiles until none is left. So a
//! tile with any amount of work gets the same answer as an uninterrupted one.

use super::kernel::{Binding, Checks, Kernel, uniform_buffer};
use super::{AdapterSummary, GpuContext, GpuScene, GpuTimer, empty_storage_buffer, read_buffer};
use crate::layout::ShadowParams;
use crate::{Error, Result};

/// 32-bit words of one tile's suspended state (see the kernel).
const STATE_WORDS: u64 = 160;
/// Tiles per dispatch along each axis: 128×128 tiles = 512×512 pixels, so
/// the state buffer stays at 10 MiB and no dispatch runs for long.
const CHUNK_TILES: u32 = 128;
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
/// `penumbra render`, Mesa 22.3.6 lavapipe on 2 AVX-512 cores:
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
/// form reuses directions held in registers; and its ballots cost barriers in the
/// workgroup vector. On a GPU, whose loads and ballots are cheap, the balance may differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum LeafMode {
    /// Lane `j` culls the triangle against its own frustum and, if it survives, tests the
    /// frustum's 16 rays itself (unrolled): no cross-lane traffic, one loop step per triangle.
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
    /// Dispatches (one per chunk plus one per resume round).
    pub dispatches: u32,
    /// Tile suspensions (tiles that ran out of their iteration budget, summed over rounds).
    pub suspensions: u64,
}

/// The shadow pass's pipeline for one vector variant and leaf mode.
#[derive(Debug)]
pub struct ShadowPass {
    kernel: Kernel,
    /// The vector variant this pass runs.
    pub variant: VectorVariant,
    /// How its leaves use the lanes.
    pub leaf_mode: LeafMode,
    vectors_per_workgroup: u32,
}

impl ShadowPass {
    /// Builds the pipeline; `variant` as in [`VectorVariant::choose`], `leaf_mode` sets the
    /// kernel's `LEAF_TRANSPOSED` override.
    pub fn new(ctx: &GpuContext, variant: Option<VectorVariant>, leaf_mode: LeafMode) -> Result<ShadowPass> {
        let (variant, vectors_per_workgroup) = VectorVariant::choose(&ctx.info, variant)?;
        let transposed = f64::from(u8::from(leaf_mode == LeafMode::Transposed));
        let mut constants: Vec<(&str, f64)> = vec![("LEAF_TRANSPOSED", transposed)];
        if variant == VectorVariant::Subgroup {
            constants.push(("VEC16_PER_WG", f64::from(vectors_per_workgroup)));
        }
        use Binding::*;
        let kernel = Kernel::new(
            ctx,
            "shadow_mft",
            &[("shared/vec16", variant.module())],
            &[
                Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadWrite, ReadWrite, ReadWrite,
            ],
            &constants,
            // Indices: BVH ranges validated by GpuScene::new, stack indices clamped,
            // pixel and state slots bounded by the parameters the host sets here; the
            // transposed leaves index the 256 light points and the workgroup's origins
            // with lane numbers (< 16) and the vector's index in its workgroup.
            Checks::Unchecked,
        )?;
        Ok(ShadowPass {
            kernel,
            variant,
            leaf_mode,
            vectors_per_workgroup,
        })
    }

    /// Traces the shadow masks of a whole image: `gbuffer` (`array<GBufferTexel>`,
    /// width × height) and `light_points` (256 `vec4`s) in, `masks` (`array<u32>`) out.
    /// `params` gives the light and image size; its tile fields are set here.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        gbuffer: &wgpu::Buffer,
        light_points: &wgpu::Buffer,
        masks: &wgpu::Buffer,
        params: &ShadowParams,
        mut timer: Option<&mut GpuTimer>,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<ShadowStats> {
        let tiles_x = params.width.div_ceil(4);
        let tiles_y = params.height.div_ceil(4);
        let chunk = CHUNK_TILES.min(tiles_x).max(1) as u64 * CHUNK_TILES.min(tiles_y).max(1) as u64;
        let state = empty_storage_buffer(
            ctx,
            "shadow state",
            chunk * STATE_WORDS * 4,
            wgpu::BufferUsages::empty(),
        )?;
        let status = empty_storage_buffer(
            ctx,
            "shadow status",
            16,
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
        let mut stats = ShadowStats::default();
        let total_tiles = u64::from(tiles_x) * u64::from(tiles_y);
        let mut tiles_done = 0u64;
        for ty0 in (0..tiles_y).step_by(CHUNK_TILES as usize) {
            for tx0 in (0..tiles_x).step_by(CHUNK_TILES as usize) {
                let mut p = *params;
                p.tile_origin_x = tx0;
                p.tile_origin_y = ty0;
                p.tiles_x = CHUNK_TILES.min(tiles_x - tx0);
                p.tiles_y = CHUNK_TILES.min(tiles_y - ty0);
                let tiles = p.tiles_x * p.tiles_y;
                let groups = tiles.div_ceil(self.vectors_per_workgroup);
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
                    let writes = timer.as_deref_mut().and_then(|t| t.pass_writes("shadow"));
                    self.kernel
                        .record(&mut encoder, "shadow/trace", &bind, writes, (groups, 1));
                    ctx.queue.submit([encoder.finish()]);
                    stats.dispatches += 1;
                    let suspended = read_buffer::<u32>(ctx, &status, 0..4)?[0];
                    if suspended == 0 {
                        break;
                    }
                    stats.suspensions += u64::from(suspended);
                }
                tiles_done += u64::from(tiles);
                progress(tiles_done, total_tiles);
            }
        }
        Ok(stats)
    }
}
