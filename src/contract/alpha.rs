//! What the alpha test of masked triangles (`shaders/shared/alpha.wgsl`, the primary
//! kernels' `passes_alpha`, and the CPU twins through [`crate::bvh::AlphaMasks`]) agrees on;
//! the records themselves are [`crate::contract::layout::AlphaTriangle`] and
//! [`crate::contract::layout::AlphaMask`].

use crate::contract::layout::{AlphaMask, AlphaTriangle};

/// [`crate::contract::layout::BvhTriangle::alpha`] of a triangle that always blocks
/// (`ALPHA_OPAQUE`). Word 0 of the alpha words is never a record, so no record has it.
pub const OPAQUE: u32 = 0;

/// Words at the start of the alpha words that hold no record: a
/// record's offset is then never [`OPAQUE`], and the buffer is never empty.
pub const HEADER_WORDS: usize = 8;

/// 32-bit words of an [`AlphaTriangle`].
pub const TRIANGLE_WORDS: usize = size_of::<AlphaTriangle>() / 4;

/// 32-bit words of an [`AlphaMask`].
pub const MASK_WORDS: usize = size_of::<AlphaMask>() / 4;

/// The cutoff rays test glTF `BLEND` materials with (a ray is blocked or not; there is no
/// partial transmission): Bevy's `PREMULTIPLIED_ALPHA_CUTOFF`, below which its prepass and
/// shadow passes discard blended fragments, so a scene's shadows here match Bevy's.
pub const BLEND_ALPHA_CUTOFF: f32 = 0.05;

/// The index of the texel nearest to texture coordinate `uv` in a `width`×`height`
/// texture, row-major, coordinates wrapping (glTF's default `REPEAT`); the kernels'
/// `texel_index` (`shaders/shared/layout.wgsl`) computes the same expression, for shading
/// and the alpha test alike.
pub fn texel_index(width: u32, height: u32, uv: glam::Vec2) -> u32 {
    let u = uv.x - uv.x.floor();
    let v = uv.y - uv.y.floor();
    let x = ((u * width as f32) as u32).min(width - 1);
    let y = ((v * height as f32) as u32).min(height - 1);
    y * width + x
}
