//! The primary pass: camera rays to a G-buffer, with one of two kernels that
//! bind alike and write alike (`shaders/shared/primary.wgsl`): per-ray
//! (`shaders/primary.wgsl`, one invocation per pixel) or multi-frusta
//! (`shaders/primary_mft.wgsl`, one 16-wide vector per 16×16 pixel block).
//!
//! Either kernel counts its loop iterations and stops a ray (per-ray) or a
//! vector (multi-frusta) before lavapipe's loop limit would cut it silently;
//! it then adds its pixels to status word 0 and the pass returns an error.
//! For primary rays that takes a big scene seen through wide frusta (the whole
//! block's rays crossing tens of thousands of boxes: an 8×8 image of Sponza), so
//! the pass reports it rather than suspending and resuming as the shadow pass
//! does, and the [`Renderer`](super::Renderer) then traces the frame's camera
//! rays again with the per-ray kernel, whose loop bound is per ray. A loop that
//! ends any other way (the driver ended it: a budget above its limit) is counted
//! in status word [`WORD_LOOP_CUT`] and is an [`Error::LoopCut`].

use super::kernel::{AlphaKernels, Checks, buffer, uniform_buffer};
use super::{GpuContext, GpuScene, GpuTimer, VectorVariant, read_buffer};
use crate::contract::ITERATION_BUDGET;
use crate::contract::counters::{Counters, STATUS_WORDS, WORD_LOOP_CUT, WORD_STATUS};
use crate::contract::groups::PIXEL_GROUP;
use crate::contract::layout::CameraParams;
use crate::contract::primary::BLOCK;
use crate::{Error, Result};

/// Which kernel traces the camera rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PrimaryTracer {
    /// One invocation per pixel, each with its own traversal stack.
    PerRay,
    /// One 16-wide vector per 16×16 pixel block; lane `i` traces the frustum of
    /// 4×4 pixels `i` (the paper's primary frusta), culling boxes and triangles
    /// for all 16 of its rays at once. The default: the faster of the two (README
    /// "Performance"); the renderer traces the pixels of a block that runs out of loop
    /// iterations again per ray.
    #[default]
    Mft,
}

impl std::fmt::Display for PrimaryTracer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            PrimaryTracer::PerRay => "per-ray",
            PrimaryTracer::Mft => "mft",
        })
    }
}

/// What a primary dispatch reported besides the G-buffer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PrimaryStatus {
    /// Pixels whose rays ran out of loop iterations (their texels are incomplete).
    pub overflow_pixels: u32,
    /// Rays (per-ray) or vectors (multi-frusta) whose loop the driver ended before it
    /// finished or ran out of budget (their texels are incomplete).
    pub loop_cut: u32,
    /// The pass's name and iteration budget, for the errors.
    pub pass: PrimaryTracer,
    /// The iteration budget the pass ran with.
    pub budget: u32,
    /// The work counters, when the pass was built with counters on.
    pub counters: Option<Counters>,
}

impl PrimaryStatus {
    /// The counters, or an error when a loop was ended by the driver or a ray ran out of
    /// loop iterations.
    pub fn check(self) -> Result<Option<Counters>> {
        if self.loop_cut != 0 {
            return Err(Error::LoopCut {
                pass: format!("primary pass ({})", self.pass),
                count: self.loop_cut.into(),
                units: match self.pass {
                    PrimaryTracer::PerRay => "rays",
                    PrimaryTracer::Mft => "vectors",
                }
                .into(),
                budget: self.budget,
            });
        }
        if self.overflow_pixels != 0 {
            return Err(Error::Gpu(format!(
                "primary pass: the camera rays of {} pixels ran out of their loop iterations \
                 (BVH too deep or degenerate for this view)",
                self.overflow_pixels
            )));
        }
        Ok(self.counters)
    }
}

/// What a [`PrimaryPass`] is built for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PrimaryOptions {
    /// The kernel.
    pub tracer: PrimaryTracer,
    /// The multi-frusta kernel's vector variant, chosen as in [`VectorVariant::choose`]
    /// (the per-ray kernel has no vectors and ignores it).
    pub variant: Option<VectorVariant>,
    /// Compile the work counters in.
    pub counters: bool,
    /// Loop iterations a ray (per-ray) or a vector (multi-frusta) may run, at least 1:
    /// lower, tests drive the overflow report on small scenes; above the driver's loop
    /// limit (lavapipe: 65,535), a loop it ends is reported as [`Error::LoopCut`].
    pub iteration_budget: u32,
}

impl Default for PrimaryOptions {
    /// The default tracer, no counters, [`ITERATION_BUDGET`].
    fn default() -> Self {
        PrimaryOptions {
            tracer: PrimaryTracer::default(),
            variant: None,
            counters: false,
            iteration_budget: ITERATION_BUDGET,
        }
    }
}

/// The primary pass's pipeline for one tracer.
#[derive(Debug)]
pub struct PrimaryPass {
    kernel: AlphaKernels,
    tracer: PrimaryTracer,
    variant: Option<VectorVariant>,
    vectors_per_workgroup: u32,
    counters: bool,
    budget: u32,
}

impl PrimaryPass {
    /// Builds the pipeline that `options` describe.
    pub fn new(ctx: &GpuContext, options: &PrimaryOptions) -> Result<PrimaryPass> {
        let PrimaryOptions {
            tracer,
            variant,
            counters,
            iteration_budget: budget,
        } = *options;
        if budget == 0 {
            return Err(Error::value(
                "primary pass iteration budget",
                budget,
                "must be at least 1",
            ));
        }
        let mut constants: Vec<(&str, f64)> = vec![
            ("COUNTERS", f64::from(u8::from(counters))),
            ("ITERATION_BUDGET", f64::from(budget)),
        ];
        let (name, aliases, variant, vectors_per_workgroup) = match tracer {
            PrimaryTracer::PerRay => ("primary", &[][..], None, 1),
            PrimaryTracer::Mft => {
                let (variant, per_wg) = VectorVariant::choose(&ctx.info, variant)?;
                constants.extend(variant.constants(per_wg));
                ("primary_mft", variant.aliases(), Some(variant), per_wg)
            }
        };
        let kernel = AlphaKernels::new(
            ctx,
            name,
            aliases,
            &constants,
            // Indices: BVH ranges validated by GpuScene::new, stack indices clamped,
            // pixels bounded by the camera's size (the G-buffer the host binds must
            // hold width × height texels), private ray arrays indexed by constants.
            Checks::Unchecked,
        )?;
        Ok(PrimaryPass {
            kernel,
            tracer,
            variant,
            vectors_per_workgroup,
            counters,
            budget,
        })
    }

    /// The tracer this pass runs.
    pub fn tracer(&self) -> PrimaryTracer {
        self.tracer
    }

    /// The vector variant of the multi-frusta kernel (`None` for per-ray).
    pub fn variant(&self) -> Option<VectorVariant> {
        self.variant
    }

    /// Whether the work counters are compiled in.
    pub fn has_counters(&self) -> bool {
        self.counters
    }

    /// A status buffer for [`PrimaryPass::record`]: [`STATUS_WORDS`] `u32`s,
    /// `STORAGE | COPY_SRC | COPY_DST`.
    pub fn status_buffer(device: &wgpu::Device) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("primary status"),
            size: (STATUS_WORDS * 4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Workgroups of a `width`×`height` dispatch, or an error naming the device's limit.
    pub fn workgroups(&self, ctx: &GpuContext, width: u32, height: u32) -> Result<(u32, u32)> {
        let (x, y, unit) = match self.tracer {
            PrimaryTracer::PerRay => (
                width.div_ceil(PIXEL_GROUP),
                height.div_ceil(PIXEL_GROUP),
                "8x8 pixels",
            ),
            PrimaryTracer::Mft => (
                width.div_ceil(BLOCK).div_ceil(self.vectors_per_workgroup),
                height.div_ceil(BLOCK),
                "16x16-pixel blocks",
            ),
        };
        let limit = ctx.info.max_compute_workgroups_per_dimension;
        if x > limit || y > limit {
            return Err(Error::Gpu(format!(
                "image {width}x{height} needs {x}x{y} workgroups of {unit}; the device allows {limit} per dimension"
            )));
        }
        Ok((x, y))
    }

    /// Records the pass into `encoder`: clears `status` (see [`PrimaryPass::status_buffer`]),
    /// then one dispatch over `groups` (from [`PrimaryPass::workgroups`] for the camera's
    /// size). `camera` is a uniform [`CameraParams`] buffer, `gbuffer` holds
    /// `width × height` texels. Binds exactly what the renderer's primary kernel always bound.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        camera: &wgpu::Buffer,
        gbuffer: &wgpu::Buffer,
        status: &wgpu::Buffer,
        groups: (u32, u32),
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) -> Result<()> {
        encoder.clear_buffer(status, 0, None);
        let kernel = self.kernel.for_scene(scene)?;
        let bind = kernel.bind(
            device,
            &[
                buffer("camera", camera),
                buffer("nodes", &scene.nodes),
                buffer("triangles", &scene.triangles),
                buffer("shading", &scene.shading),
                buffer("materials", &scene.materials),
                buffer("gbuffer", gbuffer),
                buffer("status", status),
                buffer("textures", &scene.textures),
                buffer("texels", &scene.texels),
            ],
        )?;
        kernel.record(encoder, "primary", &bind, timestamp_writes, groups);
        Ok(())
    }

    /// Reads a status buffer back after the pass was submitted.
    pub fn read_status(&self, ctx: &GpuContext, status: &wgpu::Buffer) -> Result<PrimaryStatus> {
        let words: Vec<u32> = read_buffer(ctx, status, 0..(STATUS_WORDS * 4) as u64)?;
        let words: [u32; STATUS_WORDS] = words
            .try_into()
            .map_err(|_| Error::Gpu("primary status: short read".into()))?;
        Ok(PrimaryStatus {
            overflow_pixels: words[WORD_STATUS],
            loop_cut: words[WORD_LOOP_CUT],
            pass: self.tracer,
            budget: self.budget,
            counters: self.counters.then(|| Counters::from_status_words(&words)),
        })
    }

    /// Traces `camera`'s image into `gbuffer` (`array<GBufferTexel>`, at least
    /// width × height), waits, and returns the status: rays that ran out of loop
    /// iterations are counted in it ([`PrimaryStatus::check`] makes them an error) with the
    /// counters when compiled in. Timed as `"primary"` when a timer is given.
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        camera: &CameraParams,
        gbuffer: &wgpu::Buffer,
        timer: Option<&mut GpuTimer>,
    ) -> Result<PrimaryStatus> {
        let pixels = u64::from(camera.width) * u64::from(camera.height);
        if pixels == 0 || gbuffer.size() < pixels * size_of::<crate::contract::layout::GBufferTexel>() as u64
        {
            return Err(Error::Gpu(format!(
                "primary pass: a {}x{} image needs a G-buffer of {} texels, got {} bytes",
                camera.width,
                camera.height,
                pixels,
                gbuffer.size()
            )));
        }
        let groups = self.workgroups(ctx, camera.width, camera.height)?;
        let camera_buf = uniform_buffer(ctx, "camera", camera);
        let status = PrimaryPass::status_buffer(&ctx.device);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let mut timer = timer;
        let writes = timer.as_deref_mut().and_then(|t| t.pass_writes("primary"));
        self.record(
            &ctx.device,
            &mut encoder,
            scene,
            &camera_buf,
            gbuffer,
            &status,
            groups,
            writes,
        )?;
        if let Some(t) = timer {
            t.resolve(&mut encoder);
        }
        ctx.queue.submit([encoder.finish()]);
        self.read_status(ctx, &status)
    }
}
