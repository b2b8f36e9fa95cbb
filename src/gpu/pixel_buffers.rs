//! The per-pixel buffers of a frame, listed once: the standalone renderer and the
//! embedded pass allocate from [`PIXEL_BUFFERS`] (and the filter's input textures from
//! [`FILTER_INPUT_TEXTURES`]), and [`super::memory`] sizes frames from the same lists.

use super::buffers::texture_2d;
use super::{GpuContext, empty_storage_buffer};
use crate::Result;
use crate::contract::layout::GBufferTexel;

/// One per-pixel buffer: its label (as given to wgpu) and its bytes per pixel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelBuffer {
    /// The buffer's label.
    pub label: &'static str,
    /// Bytes per pixel.
    pub bytes_per_pixel: u64,
}

/// Every per-pixel buffer of a frame, in [`PixelBuffers`]' field order; the embedded pass
/// has all but the last, `brdf` (it does not shade).
pub const PIXEL_BUFFERS: [PixelBuffer; 6] = [
    PixelBuffer {
        label: "G-buffer",
        bytes_per_pixel: size_of::<GBufferTexel>() as u64,
    },
    PixelBuffer {
        label: "shadow masks",
        bytes_per_pixel: 4,
    },
    PixelBuffer {
        label: "shaded values",
        bytes_per_pixel: 16,
    },
    PixelBuffer {
        label: "normals",
        bytes_per_pixel: 16,
    },
    PixelBuffer {
        label: "filtered values",
        bytes_per_pixel: 16,
    },
    PixelBuffer {
        label: "brdf",
        bytes_per_pixel: 16,
    },
];

/// The discontinuity filter's inputs as textures, in [`PixelBuffers`]' field order
/// (`values_texture`, `normal_texture`): copies of `values` and `normal`, texel (x, y) =
/// element y · width + x, which `shaders/filter.wgsl` reads (it says why textures).
pub const FILTER_INPUT_TEXTURES: [PixelBuffer; 2] = [
    PixelBuffer {
        label: "shaded values texture",
        bytes_per_pixel: 16,
    },
    PixelBuffer {
        label: "normals texture",
        bytes_per_pixel: 16,
    },
];

/// The format of [`FILTER_INPUT_TEXTURES`]: one `vec4<f32>` per texel, as in the buffers.
pub const FILTER_INPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// A frame's per-pixel buffers (`COPY_SRC | COPY_DST`, so tests and the renderer read them
/// back and the per-ray tracers clear the masks).
#[derive(Debug)]
pub struct PixelBuffers {
    /// Width and height of the frame in pixels.
    pub size: (u32, u32),
    /// `array<GBufferTexel>`: what the shadow pass traces from.
    pub gbuffer: wgpu::Buffer,
    /// `array<u32>`: bit j = ray j blocked, `1 << 16` = no geometry.
    pub masks: wgpu::Buffer,
    /// `array<vec4<f32>>`: shaded irradiance (rgb) and visibility (a) before the filter.
    pub values: wgpu::Buffer,
    /// `array<vec4<f32>>`: shading normal (xyz) and eye distance (w; 0: no hit) per pixel,
    /// for the filter.
    pub normal: wgpu::Buffer,
    /// `array<vec4<f32>>`: `values` after the filter (and the refinement).
    pub filtered: wgpu::Buffer,
    /// `array<vec4<f32>>`: albedo / π per pixel; `None` in the embedded pass.
    pub brdf: Option<wgpu::Buffer>,
    /// `values` as a texture for the filter ([`PixelBuffers::record_filter_input_copies`]).
    pub values_texture: wgpu::Texture,
    /// `normal` as a texture for the filter ([`PixelBuffers::record_filter_input_copies`]).
    pub normal_texture: wgpu::Texture,
}

impl PixelBuffers {
    /// [`PIXEL_BUFFERS`] for a `width`×`height` frame, `brdf` only `with_brdf`.
    pub fn new(ctx: &GpuContext, width: u32, height: u32, with_brdf: bool) -> Result<PixelBuffers> {
        let count = PIXEL_BUFFERS.len() - usize::from(!with_brdf);
        let pixels = u64::from(width) * u64::from(height);
        let usage = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let mut made = PIXEL_BUFFERS[..count]
            .iter()
            .map(|b| empty_storage_buffer(ctx, b.label, pixels * b.bytes_per_pixel, usage))
            .collect::<Result<Vec<_>>>()?
            .into_iter();
        let mut next = || made.next().expect("one buffer per field");
        let texture = |t: &PixelBuffer| {
            let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
            texture_2d(ctx, t.label, (width, height), FILTER_INPUT_FORMAT, usage)
        };
        Ok(PixelBuffers {
            size: (width, height),
            gbuffer: next(),
            masks: next(),
            values: next(),
            normal: next(),
            filtered: next(),
            brdf: with_brdf.then(next),
            values_texture: texture(&FILTER_INPUT_TEXTURES[0])?,
            normal_texture: texture(&FILTER_INPUT_TEXTURES[1])?,
        })
    }

    /// Records the copies of `values` and `normal` into `values_texture` and
    /// `normal_texture`, for a filter recorded after them.
    pub fn record_filter_input_copies(&self, encoder: &mut wgpu::CommandEncoder) {
        copy_pixels_to_texture(encoder, &self.values, &self.values_texture, self.size);
        copy_pixels_to_texture(encoder, &self.normal, &self.normal_texture, self.size);
    }
}

/// Records the copy of `buffer` (`width`×`height` texels of 16 bytes, row-major, rows
/// packed) into `texture`: one copy where a row's bytes are a multiple of wgpu's row
/// alignment (256 bytes: widths that are multiples of 16), one copy per row otherwise
/// (a one-row copy needs no row pitch).
fn copy_pixels_to_texture(
    encoder: &mut wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
    texture: &wgpu::Texture,
    (width, height): (u32, u32),
) {
    let row_bytes = width * 16;
    let rows_per_copy = if row_bytes % wgpu::COPY_BYTES_PER_ROW_ALIGNMENT == 0 {
        height
    } else {
        1
    };
    for y in (0..height).step_by(rows_per_copy.max(1) as usize) {
        encoder.copy_buffer_to_texture(
            wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: u64::from(y) * u64::from(row_bytes),
                    bytes_per_row: (rows_per_copy > 1).then_some(row_bytes),
                    rows_per_image: None,
                },
            },
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y, z: 0 },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::Extent3d {
                width,
                height: rows_per_copy,
                depth_or_array_layers: 1,
            },
        );
    }
}
