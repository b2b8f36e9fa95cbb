//! The refinement pass: after the filter, the pixels whose filter window is cut and whose
//! visibility changes around them trace the 240 rays of the other 15 sample sets, and
//! their filtered value becomes the 256-ray one (see [`crate::reference::refine`], the
//! CPU twin, for why and which pixels).
//!
//! Two kernels: `refine_select` lists the pixels (one invocation per pixel), the host reads
//! how many, then `refine_trace` runs one 240-invocation workgroup per listed pixel, one
//! ray per invocation (lavapipe bounds the iterations of one invocation's loops, so 240
//! rays in one invocation could hit its limit).

use super::kernel::{Binding, Checks, Kernel};
use super::{GpuContext, GpuScene, GpuTimer, empty_storage_buffer, read_buffer};
use crate::{Error, Result};

/// The buffers of one frame (or tile) the refinement reads and writes.
pub struct RefineBuffers<'a> {
    /// `FilterParams` uniform of the frame's filter (same tolerances: same window).
    pub filter_params: &'a wgpu::Buffer,
    /// `ShadowParams` uniform of the frame's shadow pass (light, `t_max`, width).
    pub shadow_params: &'a wgpu::Buffer,
    /// `ShadeParams` uniform of the frame's shade pass.
    pub shade_params: &'a wgpu::Buffer,
    /// The shade pass's outputs, the filter's inputs.
    pub values: &'a wgpu::Buffer,
    /// Eye distance per pixel (0: no hit).
    pub depth: &'a wgpu::Buffer,
    /// Shading normal per pixel (vec4).
    pub normal: &'a wgpu::Buffer,
    /// The G-buffer.
    pub gbuffer: &'a wgpu::Buffer,
    /// The 256 interleaved light points, set order.
    pub light_points: &'a wgpu::Buffer,
    /// The shadow pass's masks (16 ray bits per pixel).
    pub masks: &'a wgpu::Buffer,
    /// The filter's output, overwritten at the refined pixels.
    pub filtered: &'a wgpu::Buffer,
}

/// The refinement's two pipelines.
#[derive(Debug)]
pub struct Refinement {
    select: Kernel,
    trace: Kernel,
}

impl Refinement {
    /// Builds both pipelines.
    pub fn new(ctx: &GpuContext) -> Result<Refinement> {
        use Binding::*;
        Ok(Refinement {
            select: Kernel::new(
                ctx,
                "refine_select",
                &[],
                &[Uniform, ReadOnly, ReadOnly, ReadOnly, ReadWrite],
                &[],
                Checks::Checked,
            )?,
            // Unchecked like the per-ray shadow kernel: node and triangle indices come from
            // the validated BVH, the stack index is clamped, list slots are below the count
            // the kernel reads (at most one per pixel, and the list has a word per pixel),
            // listed pixels are below width × height and light points below 256.
            trace: Kernel::new(
                ctx,
                "refine_trace",
                &[],
                &[
                    Uniform, ReadOnly, ReadOnly, ReadOnly, ReadOnly, ReadOnly, Uniform, ReadWrite, ReadWrite,
                ],
                &[],
                Checks::Unchecked,
            )?,
        })
    }

    /// Refines a `width × height` frame whose filter has been submitted: lists the pixels,
    /// traces their other 240 rays, overwrites their filtered values. Returns the listed
    /// pixel indices (row-major), sorted. Both dispatches are timed as `refine`.
    pub fn run(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        b: &RefineBuffers<'_>,
        (width, height): (u32, u32),
        timer: &mut GpuTimer,
    ) -> Result<Vec<u32>> {
        let pixels = u64::from(width) * u64::from(height);
        let rw = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let list = empty_storage_buffer(ctx, "refine list", (2 + pixels) * 4, rw)?;

        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let bind = self
            .select
            .bind(ctx, &[b.filter_params, b.values, b.depth, b.normal, &list]);
        let writes = timer.pass_writes("refine");
        self.select.record(
            &mut encoder,
            "refine select",
            &bind,
            writes,
            (width.div_ceil(8), height.div_ceil(8)),
        );
        ctx.queue.submit([encoder.finish()]);
        let listed = read_buffer::<u32>(ctx, &list, 0..4)?[0];
        if listed == 0 {
            return Ok(Vec::new());
        }

        // One workgroup per listed pixel, as a 2D grid within the per-dimension limit.
        let limit = ctx.info.max_compute_workgroups_per_dimension;
        let groups_x = listed.min(limit);
        let groups = (groups_x, listed.div_ceil(groups_x));
        if groups.1 > limit {
            return Err(Error::Gpu(format!(
                "refinement of {listed} pixels needs {}x{} workgroups; the device allows {limit} per dimension",
                groups.0, groups.1
            )));
        }
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let bind = self.trace.bind(
            ctx,
            &[
                b.shadow_params,
                &scene.nodes,
                &scene.triangles,
                b.gbuffer,
                b.light_points,
                b.masks,
                b.shade_params,
                &list,
                b.filtered,
            ],
        );
        let writes = timer.pass_writes("refine");
        self.trace
            .record(&mut encoder, "refine trace", &bind, writes, groups);
        ctx.queue.submit([encoder.finish()]);
        let words = read_buffer::<u32>(ctx, &list, 0..(2 + u64::from(listed)) * 4)?;
        if words[1] > 0 {
            return Err(Error::Gpu(format!(
                "refinement: {} shadow rays ran out of their loop iterations",
                words[1]
            )));
        }
        let mut refined = words[2..].to_vec();
        refined.sort_unstable();
        Ok(refined)
    }
}
