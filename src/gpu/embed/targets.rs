//! What the embedded shadow pass writes, sized for one image: the visibility textures the
//! host samples, and the pass's own per-pixel buffers.

use super::super::buffers::texture_2d;
use super::super::pixel_buffers::PixelBuffers;
use super::super::{GpuContext, ShadowScratch, ShadowTracer, read_buffer};
use crate::{Error, Result};

/// Format of both visibility textures: one 32-bit float per pixel.
///
/// Core WebGPU can write it from compute shaders. It is not filterable unless the device
/// has [`wgpu::Features::FLOAT32_FILTERABLE`]: read it with `textureLoad`, or bind it as
/// `texture_2d<f32>` with `sample_type: Float { filterable: false }` and a non-filtering
/// sampler.
pub const VISIBILITY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// The visibility textures and scratch buffers of one `width`×`height` frame. Create one
/// per image size (and per frame in flight); reuse it every frame.
///
/// Both textures are [`VISIBILITY_FORMAT`] with `TEXTURE_BINDING | STORAGE_BINDING |
/// COPY_SRC` usage. A texel holds the fraction of the pixel's 16 shadow rays that reach
/// the light, in `0..=1` (steps of 1/16 before the filter); 1 where the pixel sees no
/// geometry, 0 where the surface is behind the light's plane.
///
/// Memory: about 120 bytes per pixel of buffers (the 64-byte G-buffer texel, the mask,
/// depth, normal and two value vectors for the filter) plus 8 bytes of textures and 10 MiB
/// of suspended-tile state at most.
#[derive(Debug)]
pub struct ShadowTargets {
    width: u32,
    height: u32,
    /// Visibility before the 4×4 discontinuity filter.
    pub unfiltered: wgpu::Texture,
    /// Visibility after the filter (a copy of `unfiltered` when the filter is off).
    pub filtered: wgpu::Texture,
    pub(super) unfiltered_view: wgpu::TextureView,
    pub(super) filtered_view: wgpu::TextureView,
    /// The per-pixel buffers (`COPY_SRC`, for inspection): the G-buffer made from the
    /// host's textures, the shadow masks (bit j = ray j blocked, `1 << 16` = no geometry),
    /// and what the filter reads and writes; no `brdf` (the host shades).
    pub pixels: PixelBuffers,
    pub(super) scratch: ShadowScratch,
}

impl ShadowTargets {
    /// Targets for `width`×`height` frames on `ctx`'s device.
    ///
    /// Errors: a zero or too large size ([`Error::InvalidInput`]), a buffer over the
    /// device's storage-buffer limit ([`Error::BufferTooLarge`]).
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<ShadowTargets> {
        let max = ctx.device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 || width > max || height > max {
            return Err(Error::invalid(
                "ShadowTargets::new",
                format!("size {width}x{height}: each side must be in 1..={max} on this device"),
            ));
        }
        let texture = |label: &str| {
            let usage = wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC;
            let texture = texture_2d(ctx, label, (width, height), VISIBILITY_FORMAT, usage)?;
            let view = texture.create_view(&Default::default());
            Ok::<_, Error>((texture, view))
        };
        let (unfiltered, unfiltered_view) = texture("unfiltered visibility")?;
        let (filtered, filtered_view) = texture("filtered visibility")?;
        Ok(ShadowTargets {
            width,
            height,
            unfiltered,
            filtered,
            unfiltered_view,
            filtered_view,
            pixels: PixelBuffers::new(ctx, width, height, false)?,
            scratch: ShadowScratch::new(&ctx.device, width, height),
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Two `u32`s per chunk of 128×128 tiles: tiles (4×4 pixels) whose rays were still
    /// being traced when the pass's last resume round ended (see
    /// [`super::ShadowSettings::resume_rounds`]), and tiles whose loop the driver ended
    /// (an [`super::ShadowSettings::iteration_budget`] above its limit) (`COPY_SRC`). All
    /// zero means every mask is complete. A
    /// host that must not stall copies it into its own mappable buffer and reads it a
    /// frame later; [`ShadowTargets::unfinished_tiles`] does it the blocking way.
    pub fn unfinished(&self) -> &wgpu::Buffer {
        &self.scratch.unfinished
    }

    /// Tiles left unfinished by the last recorded pass (both counts, summed over chunks).
    /// Waits for the
    /// GPU to finish all submitted work (for tests and diagnostics, not every frame).
    pub fn unfinished_tiles(&self, ctx: &GpuContext) -> Result<u64> {
        let chunks = ShadowTracer::chunks(self.width, self.height);
        let bytes = chunks * super::super::shadow_tracer::UNFINISHED_WORDS * 4;
        let counts: Vec<u32> = read_buffer(ctx, &self.scratch.unfinished, 0..bytes)?;
        Ok(counts.iter().map(|&c| u64::from(c)).sum())
    }
}
