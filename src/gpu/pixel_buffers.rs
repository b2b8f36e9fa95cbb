//! The per-pixel buffers of a frame, listed once: the standalone renderer and the
//! embedded pass allocate from [`PIXEL_BUFFERS`], and [`super::memory`] sizes frames
//! from the same list.

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
pub const PIXEL_BUFFERS: [PixelBuffer; 7] = [
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
        label: "depth",
        bytes_per_pixel: 4,
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
    /// `array<f32>`: eye distance per pixel (0: no hit), for the filter.
    pub depth: wgpu::Buffer,
    /// `array<vec4<f32>>`: shading normal (xyz) and eye distance again (w) per pixel, for the filter.
    pub normal: wgpu::Buffer,
    /// `array<vec4<f32>>`: `values` after the filter (and the refinement).
    pub filtered: wgpu::Buffer,
    /// `array<vec4<f32>>`: albedo / π per pixel; `None` in the embedded pass.
    pub brdf: Option<wgpu::Buffer>,
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
        Ok(PixelBuffers {
            size: (width, height),
            gbuffer: next(),
            masks: next(),
            values: next(),
            depth: next(),
            normal: next(),
            filtered: next(),
            brdf: with_brdf.then(next),
        })
    }
}
