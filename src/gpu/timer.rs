//! GPU-timeline timings of labelled compute passes, from timestamp queries.
//!
//! ```no_run
//! # fn demo(ctx: &penumbra::gpu::GpuContext) -> penumbra::Result<()> {
//! use penumbra::gpu::GpuTimer;
//! let mut timer = GpuTimer::new(ctx, 4);
//! let mut encoder = ctx.device.create_command_encoder(&Default::default());
//! {
//!     let pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
//!         label: Some("shadow/trace"),
//!         timestamp_writes: timer.pass_writes("shadow/trace"),
//!     });
//!     // ... set pipeline, bind groups, dispatch ...
//! }
//! timer.resolve(&mut encoder);
//! ctx.queue.submit([encoder.finish()]);
//! for (label, ms) in timer.read(ctx)? {
//!     println!("{label}: {ms:.3} ms");
//! }
//! # Ok(())
//! # }
//! ```

use super::GpuContext;
use super::buffers::map_read;
use crate::{Error, Result};

/// Timestamps at the start and end of up to `capacity` labelled compute passes.
///
/// Without `TIMESTAMP_QUERY` on the device every method is a no-op and [`GpuTimer::read`]
/// returns an empty list, so callers need no second code path.
#[derive(Debug)]
pub struct GpuTimer {
    /// `None` when the device has no timestamp queries.
    queries: Option<Queries>,
    /// Labels of the passes recorded since the last read, in query order.
    labels: Vec<String>,
    capacity: u32,
    /// Passes asked for since the last read that found every slot taken.
    dropped: u32,
}

#[derive(Debug)]
struct Queries {
    set: wgpu::QuerySet,
    /// `QUERY_RESOLVE` target; query results cannot be mapped directly.
    resolve: wgpu::Buffer,
    /// `MAP_READ` copy of `resolve`.
    readback: wgpu::Buffer,
    /// Number of passes whose queries were resolved and copied to `readback`.
    n_resolved: u32,
}

impl GpuTimer {
    /// A timer for up to `capacity` passes (at most 2048: a query set holds 4096 queries).
    pub fn new(ctx: &GpuContext, capacity: u32) -> GpuTimer {
        let capacity = capacity.clamp(1, wgpu::QUERY_SET_MAX_QUERIES / 2);
        let queries = ctx.info.has_timestamps.then(|| {
            let n_queries = 2 * capacity;
            let bytes = u64::from(n_queries) * u64::from(wgpu::QUERY_SIZE);
            Queries {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: n_queries,
                }),
                resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp resolve"),
                    size: bytes,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp readback"),
                    size: bytes,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                n_resolved: 0,
            }
        });
        GpuTimer {
            queries,
            labels: Vec::new(),
            capacity,
            dropped: 0,
        }
    }

    /// True when the device records timestamps (otherwise [`GpuTimer::read`] returns nothing).
    pub fn is_enabled(&self) -> bool {
        self.queries.is_some()
    }

    /// Timestamp writes for a compute pass named `label`, to put in its
    /// [`wgpu::ComputePassDescriptor`]. `None` when timestamps are unsupported or all
    /// `capacity` slots are taken: that pass is then not timed, and [`GpuTimer::read`]
    /// fails rather than return timings that leave it out.
    pub fn pass_writes(&mut self, label: &str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let queries = self.queries.as_ref()?;
        let index = u32::try_from(self.labels.len()).unwrap_or(u32::MAX);
        if index >= self.capacity {
            self.dropped += 1;
            return None;
        }
        self.labels.push(label.to_owned());
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &queries.set,
            beginning_of_pass_write_index: Some(2 * index),
            end_of_pass_write_index: Some(2 * index + 1),
        })
    }

    /// Timestamp writes that time a span of commands as one pass named `label`: the first
    /// half for an (empty) compute pass before the span's first command, the second for the
    /// compute pass that ends it. So copies, which no compute pass holds, are timed with
    /// the pass they feed. `None` as for [`GpuTimer::pass_writes`].
    pub fn span_writes(
        &mut self,
        label: &str,
    ) -> Option<(
        wgpu::ComputePassTimestampWrites<'_>,
        wgpu::ComputePassTimestampWrites<'_>,
    )> {
        let whole = self.pass_writes(label)?;
        let start = wgpu::ComputePassTimestampWrites {
            end_of_pass_write_index: None,
            ..whole.clone()
        };
        let end = wgpu::ComputePassTimestampWrites {
            beginning_of_pass_write_index: None,
            ..whole
        };
        Some((start, end))
    }

    /// Records, after the timed passes, the commands that make their timestamps readable.
    pub fn resolve(&mut self, encoder: &mut wgpu::CommandEncoder) {
        let n_passes = self.labels.len() as u32;
        let Some(queries) = self.queries.as_mut() else {
            return;
        };
        if n_passes == 0 {
            return;
        }
        encoder.resolve_query_set(&queries.set, 0..2 * n_passes, &queries.resolve, 0);
        let bytes = u64::from(2 * n_passes) * u64::from(wgpu::QUERY_SIZE);
        encoder.copy_buffer_to_buffer(&queries.resolve, 0, &queries.readback, 0, bytes);
        queries.n_resolved = n_passes;
    }

    /// Waits for the GPU and returns `(label, milliseconds)` per resolved pass, in the order
    /// the passes were labelled; then forgets them, so the timer can time the next frame.
    ///
    /// Call after submitting the encoder given to [`GpuTimer::resolve`]. An end timestamp
    /// before its start (allowed by WebGPU, e.g. after a clock change) reads as 0 ms.
    ///
    /// Errors ([`Error::InvalidValue`]) when more passes asked for timestamps than the
    /// timer holds: sums over the timings would silently leave those passes out.
    pub fn read(&mut self, ctx: &GpuContext) -> Result<Vec<(String, f64)>> {
        let dropped = std::mem::take(&mut self.dropped);
        if dropped > 0 {
            let asked = self.labels.len() as u64 + u64::from(dropped);
            self.labels.clear();
            if let Some(q) = self.queries.as_mut() {
                q.n_resolved = 0;
            }
            return Err(Error::value(
                "timed passes",
                asked,
                format!(
                    "this timer holds {} (at most 2048); {dropped} passes were not timed",
                    self.capacity
                ),
            ));
        }
        let labels = std::mem::take(&mut self.labels);
        let Some(queries) = self.queries.as_mut() else {
            return Ok(Vec::new());
        };
        let n_resolved = std::mem::take(&mut queries.n_resolved) as usize;
        if n_resolved == 0 {
            return Ok(Vec::new());
        }
        let ticks: Vec<u64> = map_read(ctx, &queries.readback, bytemuck::pod_collect_to_vec)?;
        let ns_per_tick = f64::from(ctx.queue.get_timestamp_period());
        Ok(labels
            .into_iter()
            .take(n_resolved)
            .enumerate()
            .map(|(i, label)| {
                let elapsed = ticks[2 * i + 1].saturating_sub(ticks[2 * i]);
                (label, elapsed as f64 * ns_per_tick / 1e6)
            })
            .collect())
    }
}
