//! GPU memory a render needs, computed from counts before anything is allocated.
//!
//! Two parts: the scene's buffers ([`scene_buffers`], uploaded once by
//! [`super::GpuScene::new`]) and one frame's buffers ([`frame_buffers`],
//! allocated by [`super::Renderer::render`] for each image). `penumbra info`
//! prints both; [`check_frame_fits`] refuses, before allocating, an image whose
//! largest per-pixel buffer exceeds the adapter's limit for one storage-buffer
//! binding, and says which image size would fit.
//!
//! The per-pixel sizes are the list the frame allocates from
//! ([`super::pixel_buffers::PIXEL_BUFFERS`]); the scene's mirror `scene_buffers.rs`, the
//! shadow pass's state buffer `shadow_tracer.rs` ([`crate::contract::shadow::STATE_WORDS`] words per tile
//! of a chunk of at most [`SHADOW_CHUNK_TILES`]² tiles); the buffer helpers pad every
//! buffer to at least 16 bytes and a multiple of 4.
//! Uniform buffers, the 4 KiB of light points, status words and timestamp
//! queries (under 100 KiB together) are not counted.

use super::pixel_buffers::{FILTER_INPUT_TEXTURES, PIXEL_BUFFERS};
use crate::bvh::Bvh;
use crate::contract::layout::{BvhNode, BvhTriangle, GpuMaterial, GpuTexture, ShadingTriangle};
use crate::scene::Scene;
use crate::{Error, Result};

/// Tiles per shadow-pass dispatch along each axis.
pub const SHADOW_CHUNK_TILES: u64 = super::shadow_tracer::CHUNK_TILES as u64;

/// One GPU buffer: its label (as given to wgpu) and its size in bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferSize {
    /// The buffer's label.
    pub label: &'static str,
    /// Bytes, padded as the buffer helpers pad them.
    pub bytes: u64,
}

/// The element counts that decide a scene's GPU memory.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneCounts {
    /// BVH nodes.
    pub nodes: u64,
    /// BVH triangles (= shading triangles).
    pub triangles: u64,
    /// Materials.
    pub materials: u64,
    /// Images (one texture record each).
    pub textures: u64,
    /// Texels of all textures together.
    pub texels: u64,
    /// 32-bit words of the alpha masks ([`crate::bvh::AlphaMasks::words`]).
    pub alpha_words: u64,
}

impl SceneCounts {
    /// The counts of `scene` and its `bvh`, with `texels` texels in all its textures
    /// (see [`crate::pass_inputs::texture_dimensions`] to count them without decoding).
    pub fn new(scene: &Scene, bvh: &Bvh, texels: u64) -> SceneCounts {
        SceneCounts {
            nodes: bvh.nodes.len() as u64,
            triangles: bvh.triangles.len() as u64,
            materials: scene.materials.len() as u64,
            textures: scene.images.len() as u64,
            texels,
            alpha_words: bvh.alpha.words.len() as u64,
        }
    }
}

/// The scene's buffers, as [`super::GpuScene::new`] creates them.
pub fn scene_buffers(c: &SceneCounts) -> Vec<BufferSize> {
    let size = |label, count: u64, elem: usize| BufferSize {
        label,
        bytes: padded(count.saturating_mul(elem as u64)),
    };
    vec![
        size("BVH nodes", c.nodes, size_of::<BvhNode>()),
        size("BVH triangles", c.triangles, size_of::<BvhTriangle>()),
        size("shading triangles", c.triangles, size_of::<ShadingTriangle>()),
        size("materials", c.materials, size_of::<GpuMaterial>()),
        size("textures", c.textures, size_of::<GpuTexture>()),
        // At least one texel: a bindable buffer needs an element.
        size("texels", c.texels.max(1), 16),
        size("alpha", c.alpha_words, 4),
    ]
}

/// One `width`×`height` frame's buffers: the per-pixel buffers, the filter's
/// input textures (as large as the values they copy, so no larger than the
/// largest buffer), the shadow pass's state for one chunk of tiles, and the
/// largest read-back staging buffer (one exists at a time; the G-buffer is not
/// read back unless asked).
pub fn frame_buffers(width: u32, height: u32) -> Vec<BufferSize> {
    let pixels = u64::from(width) * u64::from(height);
    let mut out: Vec<BufferSize> = PIXEL_BUFFERS
        .iter()
        .chain(&FILTER_INPUT_TEXTURES)
        .map(|b| BufferSize {
            label: b.label,
            bytes: padded(pixels * b.bytes_per_pixel),
        })
        .collect();
    let chunk = |side: u32| SHADOW_CHUNK_TILES.min(u64::from(side.div_ceil(4))).max(1);
    out.push(BufferSize {
        label: "shadow state",
        bytes: padded(chunk(width) * chunk(height) * crate::gpu::shadow_tracer::STATE_WORDS * 4),
    });
    out.push(BufferSize {
        label: "readback staging",
        bytes: padded(pixels * 16),
    });
    out
}

/// The sum of `buffers`' sizes.
pub fn total_bytes(buffers: &[BufferSize]) -> u64 {
    buffers.iter().map(|b| b.bytes).sum()
}

/// The largest of `buffers` (the first of equals), if any.
pub fn largest(buffers: &[BufferSize]) -> Option<BufferSize> {
    buffers
        .iter()
        .copied()
        .reduce(|a, b| if b.bytes > a.bytes { b } else { a })
}

/// The size limit of one storage buffer on `ctx`'s device: the smaller of
/// the binding limit and the buffer limit.
pub fn storage_limit(ctx: &super::GpuContext) -> u64 {
    let limits = ctx.device.limits();
    limits.max_storage_buffer_binding_size.min(limits.max_buffer_size)
}

/// [`Error::ImageTooLarge`] when a `width`×`height` frame needs a buffer
/// larger than `limit` bytes (see [`storage_limit`]); the error names the
/// buffer, the limit and the largest image of the same aspect ratio that fits.
pub fn check_frame_fits(limit: u64, width: u32, height: u32) -> Result<()> {
    let buffers = frame_buffers(width, height);
    let Some(big) = largest(&buffers).filter(|b| b.bytes > limit) else {
        return Ok(());
    };
    let (largest_width, largest_height) = largest_image(limit, width, height);
    Err(Error::ImageTooLarge {
        width,
        height,
        what: big.label.to_owned(),
        bytes: big.bytes,
        limit,
        largest_width,
        largest_height,
    })
}

/// The largest image with (about) the aspect ratio of `width`×`height` whose
/// frame buffers each fit in `limit` bytes; at least 1×1.
pub fn largest_image(limit: u64, width: u32, height: u32) -> (u32, u32) {
    let bpp = PIXEL_BUFFERS.iter().map(|b| b.bytes_per_pixel).max().unwrap_or(1);
    let max_pixels = (limit / bpp).max(1);
    let fits = |w: u64, h: u64| w * h <= max_pixels;
    let (w, h) = (u64::from(width.max(1)), u64::from(height.max(1)));
    if fits(w, h) {
        return (width.max(1), height.max(1));
    }
    let scale = (max_pixels as f64 / (w * h) as f64).sqrt();
    let mut lw = ((w as f64 * scale).floor() as u64).clamp(1, w);
    let mut lh = ((h as f64 * scale).floor() as u64).clamp(1, h);
    // A thin image may reach 1 pixel on one side: the other takes what is left.
    if lw == 1 {
        lh = (max_pixels).min(h);
    } else if lh == 1 {
        lw = (max_pixels).min(w);
    }
    // Rounding in the square root may overshoot by a pixel.
    while !fits(lw, lh) {
        if lw >= lh { lw -= 1 } else { lh -= 1 }
    }
    (lw as u32, lh as u32)
}

/// `bytes` in binary units with two decimals, e.g. `1.50 MiB`.
pub fn format_bytes(bytes: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} B")
    } else {
        format!("{value:.2} {}", UNITS[unit])
    }
}

/// What the buffer helpers allocate for `bytes`: at least 16, a multiple of 4.
fn padded(bytes: u64) -> u64 {
    bytes.max(16).div_ceil(4).saturating_mul(4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_buffers_at_1024_square() {
        let buffers = frame_buffers(1024, 1024);
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        let get = |label: &str| buffers.iter().find(|b| b.label == label).unwrap().bytes;
        assert_eq!(mib(get("G-buffer")), 64.0);
        assert_eq!(mib(get("shadow masks")), 4.0);
        assert_eq!(
            get("shadow state"),
            128 * 128 * crate::gpu::shadow_tracer::STATE_WORDS * 4
        );
        assert_eq!(mib(get("shaded values texture")), 16.0);
        assert_eq!(mib(get("normals texture")), 16.0);
        // 64 + 4 + 16 + 16 + 16 + 16 buffer and 16 + 16 texture bytes per pixel, 16
        // staging, 11 MiB of state (176 words).
        assert_eq!(mib(total_bytes(&buffers)), 132.0 + 32.0 + 16.0 + 11.0);
        assert_eq!(largest(&buffers).unwrap().label, "G-buffer");
    }

    #[test]
    fn tiny_frames_are_padded_and_state_shrinks() {
        let buffers = frame_buffers(1, 7);
        assert!(buffers.iter().all(|b| b.bytes >= 16 && b.bytes % 4 == 0));
        let state = buffers.iter().find(|b| b.label == "shadow state").unwrap();
        assert_eq!(
            state.bytes,
            2 * crate::gpu::shadow_tracer::STATE_WORDS * 4,
            "1x7 pixels = 1x2 tiles"
        );
    }

    #[test]
    fn scene_buffers_follow_the_counts() {
        let c = SceneCounts {
            nodes: 3,
            triangles: 2,
            materials: 1,
            textures: 0,
            texels: 0,
            alpha_words: 8,
        };
        let bytes: Vec<u64> = scene_buffers(&c).iter().map(|b| b.bytes).collect();
        assert_eq!(bytes, [96, 96, 160, 32, 16, 16, 32]);
    }

    #[test]
    fn too_large_an_image_names_the_limit_and_what_fits() {
        let limit = 128 << 20; // the WebGPU default binding limit, 128 MiB
        assert!(check_frame_fits(limit, 1448, 1448).is_ok());
        let err = check_frame_fits(limit, 4096, 2048).unwrap_err();
        assert_eq!(
            err.to_string(),
            "image 4096x2048 needs a 536870912-byte `G-buffer` buffer, more than this adapter's \
             limit of 134217728 bytes per storage buffer; the largest image of this shape that \
             fits is 2048x1024 (render smaller, or use an adapter with a larger limit)"
        );
        assert_eq!(largest_image(limit, 1, 100_000_000), (1, 2_097_152));
        assert_eq!(largest_image(limit, 100_000_000, 1), (2_097_152, 1));
        assert_eq!(largest_image(limit, 3000, 3000), (1448, 1448));
        assert_eq!(largest_image(63, 9, 9), (1, 1));
        for (w, h) in [(4097, 4095), (700_000, 3), (12_345, 6_789)] {
            let (lw, lh) = largest_image(limit, w, h);
            assert!(check_frame_fits(limit, lw, lh).is_ok(), "{w}x{h} -> {lw}x{lh}");
            assert!(
                check_frame_fits(limit, lw + 1, lh + 1).is_err(),
                "{w}x{h} -> {lw}x{lh} is not the largest"
            );
        }
    }

    #[test]
    fn bytes_print_in_binary_units() {
        assert_eq!(format_bytes(512), "512 B");
        assert_eq!(format_bytes(1536), "1.50 KiB");
        assert_eq!(format_bytes(136 << 20), "136.00 MiB");
    }
}
