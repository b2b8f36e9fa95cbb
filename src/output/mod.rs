//! Writing (and reading back) the renderer's images: linear HDR as EXR,
//! tone-mapped sRGB as PNG.
//!
//! The format follows the file's extension, case-insensitive: `.png` or `.exr`
//! ([`SUPPORTED_EXTENSIONS`]); anything else is an [`Error::Output`](crate::Error::Output).
//!
//! # PNG tone map
//!
//! A PNG holds 8-bit sRGB, so linear radiance goes through [`ToneMap`] per
//! channel:
//!
//! ```text
//! t = 1 − exp(−exposure · c)          exponential map: 0 stays 0, ∞ → 1, no hard clip
//! s = 12.92 · t                        if t ≤ 0.0031308   (sRGB transfer function)
//!   = 1.055 · t^(1/2.4) − 0.055        otherwise
//! byte = round(255 · clamp(s, 0, 1))   NaN → 0
//! ```
//!
//! EXR files hold the linear values as 32-bit floats, untouched.
//!
//! # Whole or not at all
//!
//! Every writer encodes the image into memory first, writes it to a temporary
//! file beside the target (`.NAME.tmp-PID-N`), syncs it, and renames it onto
//! the target. A reader of the target sees the old file or the new one, never
//! half of one; on failure the temporary file is removed and an existing
//! target is left as it was.

mod atomic_file;
mod codecs;
mod tone_map;

pub use atomic_file::write_bytes_atomically;
pub use codecs::{
    read_float_image, read_hdr_image, read_rgba_image, write_display_image, write_float_image, write_image,
};
pub use tone_map::ToneMap;

/// The file extensions the writers and readers understand (lower case, without the dot).
pub const SUPPORTED_EXTENSIONS: [&str; 2] = ["png", "exr"];

/// A linear RGB image (radiance or irradiance), row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` linear RGB triples; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<[f32; 3]>,
}

/// A one-channel float image (for example the visibility AOV), row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct FloatImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` values; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<f32>,
}

/// A four-channel float image as read from a file, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` RGBA values; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<[f32; 4]>,
}

#[cfg(test)]
mod tests;
