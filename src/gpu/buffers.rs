//! Storage buffers with size checks, 2-D textures, and reading buffers back to the CPU.

use std::ops::Range;

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use super::GpuContext;
use crate::{Error, Result};

/// Smallest buffer created: a zero-sized buffer cannot be bound, so empty data still gets one.
const MIN_BUFFER_BYTES: u64 = 16;

/// A `STORAGE | extra_usage` buffer holding `data`, checked against the adapter's limits.
///
/// An empty slice gives a 16-byte zeroed buffer (bindable; WGSL `arrayLength` is then 0 for
/// elements of 16 bytes or more). Sizes are padded to a multiple of 4 bytes.
pub fn storage_buffer<T: Pod>(
    ctx: &GpuContext,
    label: &str,
    data: &[T],
    extra_usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    if bytes.is_empty() {
        return empty_storage_buffer(ctx, label, 0, extra_usage);
    }
    check_size(ctx, label, padded(bytes.len() as u64))?;
    ctx.capture_errors(label, || {
        ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage: wgpu::BufferUsages::STORAGE | extra_usage,
        })
    })
}

/// A `width`×`height` 2-D texture of `format` with `usage`, one mip level, single-sampled;
/// wgpu's validation and out-of-memory errors come back as [`Error::Gpu`] naming `label`.
pub fn texture_2d(
    ctx: &GpuContext,
    label: &str,
    (width, height): (u32, u32),
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> Result<wgpu::Texture> {
    ctx.capture_errors(label, || {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    })
}

/// A zeroed `STORAGE | extra_usage` buffer of at least `bytes` bytes (at least 16, padded to 4).
pub fn empty_storage_buffer(
    ctx: &GpuContext,
    label: &str,
    bytes: u64,
    extra_usage: wgpu::BufferUsages,
) -> Result<wgpu::Buffer> {
    let size = padded(bytes);
    check_size(ctx, label, size)?;
    ctx.capture_errors(label, || {
        ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE | extra_usage,
            mapped_at_creation: false,
        })
    })
}

/// Copies `byte_range` of `buffer` (which needs `COPY_SRC`) to the CPU as a `Vec<T>`.
///
/// Blocks until the GPU has finished all work submitted so far. The range must start and
/// end on a multiple of 4 bytes and hold a whole number of `T`s.
pub fn read_buffer<T: Pod>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    byte_range: Range<u64>,
) -> Result<Vec<T>> {
    let len = byte_range.end.saturating_sub(byte_range.start);
    let elem = size_of::<T>() as u64;
    if byte_range.start > byte_range.end
        || byte_range.end > buffer.size()
        || !byte_range.start.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        || !len.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        || (elem > 0 && !len.is_multiple_of(elem))
    {
        return Err(Error::Gpu(format!(
            "cannot read bytes {byte_range:?} of a {}-byte buffer as {}-byte elements \
             (the range must lie in the buffer, be 4-byte aligned and hold whole elements)",
            buffer.size(),
            elem
        )));
    }
    if !buffer.usage().contains(wgpu::BufferUsages::COPY_SRC) {
        return Err(Error::Gpu(
            "cannot read back a buffer created without COPY_SRC usage".to_owned(),
        ));
    }
    if len == 0 {
        return Ok(Vec::new());
    }

    let staging = ctx.capture_errors("readback staging", || {
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback staging"),
            size: len,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("readback"),
            });
        encoder.copy_buffer_to_buffer(buffer, byte_range.start, &staging, 0, len);
        ctx.queue.submit([encoder.finish()]);
        staging
    })?;
    map_read(ctx, &staging, bytemuck::pod_collect_to_vec)
}

/// Copies a 2-D, single-layer, single-sampled colour `texture` (which needs `COPY_SRC`) to
/// the CPU as one `T` per texel, rows top to bottom: `T` must be the size of one texel of
/// the texture's format (e.g. `f32` for `R32Float`, `[f32; 4]` for `Rgba32Float`).
///
/// Blocks until the GPU has finished all work submitted so far.
pub fn read_texture<T: Pod>(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Vec<T>> {
    let size = texture.size();
    let texel = texture.format().block_copy_size(None);
    if texel != Some(size_of::<T>() as u32)
        || texture.dimension() != wgpu::TextureDimension::D2
        || size.depth_or_array_layers != 1
        || texture.sample_count() != 1
        || !texture.usage().contains(wgpu::TextureUsages::COPY_SRC)
    {
        return Err(Error::Gpu(format!(
            "cannot read back a {:?} texture ({}x{}x{}, {} samples, usage {:?}) as {}-byte texels \
             (read_texture takes 2-D, one-layer, single-sampled COPY_SRC textures, T one texel)",
            texture.format(),
            size.width,
            size.height,
            size.depth_or_array_layers,
            texture.sample_count(),
            texture.usage(),
            size_of::<T>()
        )));
    }
    let row = size.width * size_of::<T>() as u32;
    let padded = row.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = ctx.capture_errors("texture readback staging", || {
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("texture readback staging"),
            size: u64::from(padded) * u64::from(size.height),
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut encoder = ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("texture readback"),
            });
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: None,
                },
            },
            size,
        );
        ctx.queue.submit([encoder.finish()]);
        staging
    })?;
    map_read(ctx, &staging, |bytes| {
        bytes
            .chunks(padded as usize)
            .flat_map(|r| bytemuck::pod_collect_to_vec::<u8, T>(&r[..row as usize]))
            .collect()
    })
}

/// Maps all of `buffer` (a `MAP_READ` buffer), waits for it and returns what `read` makes
/// of its bytes: read straight from the mapping, as a second copy of a frame's 16 MB
/// buffers cost several milliseconds each on lavapipe.
pub(crate) fn map_read<R>(
    ctx: &GpuContext,
    buffer: &wgpu::Buffer,
    read: impl FnOnce(&[u8]) -> R,
) -> Result<R> {
    let (sender, receiver) = std::sync::mpsc::channel();
    buffer.map_async(wgpu::MapMode::Read, .., move |result| {
        // The receiver outlives this callback: we block on it below.
        let _ = sender.send(result);
    });
    ctx.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| Error::Gpu(format!("waiting for the GPU failed: {e}")))?;
    match receiver.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(Error::Gpu(format!("mapping a readback buffer failed: {e}"))),
        Err(_) => {
            return Err(Error::Gpu(
                "mapping a readback buffer never completed (device lost?)".to_owned(),
            ));
        }
    }
    let value = read(
        &buffer
            .get_mapped_range(..)
            .map_err(|e| Error::Gpu(format!("reading a mapped buffer failed: {e}")))?,
    );
    buffer.unmap();
    Ok(value)
}

/// `bytes` rounded up to a multiple of 4, and at least [`MIN_BUFFER_BYTES`].
fn padded(bytes: u64) -> u64 {
    bytes
        .max(MIN_BUFFER_BYTES)
        .checked_next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
        .unwrap_or(u64::MAX)
}

/// [`Error::BufferTooLarge`] unless a storage buffer of `bytes` fits the device's limits.
fn check_size(ctx: &GpuContext, label: &str, bytes: u64) -> Result<()> {
    let limits = ctx.device.limits();
    let limit = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    if bytes > limit {
        return Err(Error::BufferTooLarge {
            what: label.to_owned(),
            bytes,
            limit,
        });
    }
    Ok(())
}
