//! The tone map of PNG output: linear radiance → 8-bit sRGB (formulas in the
//! [module docs](super)).

/// How linear radiance becomes 8-bit sRGB for PNG output.
///
/// Per channel: `t = 1 − exp(−exposure · c)`, then the sRGB transfer function,
/// then rounding to 8 bits (see the [module docs](super) for the exact
/// formulas). The exponential map keeps 0 at 0, is close to linear
/// (`≈ exposure · c`) in the shadows, and approaches white smoothly instead of
/// clipping, so bright lit areas keep their gradients. It works per channel, so
/// very bright saturated colours drift toward white.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Scale applied to linear values before the map. Larger brightens; 1.0
    /// maps radiance 1 to `1 − e⁻¹ ≈ 0.63` (sRGB byte 208). 0 gives black.
    pub exposure: f32,
}

impl Default for ToneMap {
    /// Exposure 1.0.
    fn default() -> Self {
        ToneMap { exposure: 1.0 }
    }
}

impl ToneMap {
    /// The 8-bit sRGB value of the linear channel value `c`.
    ///
    /// Negative values and NaN map to 0, +∞ to 255.
    pub fn apply(&self, c: f32) -> u8 {
        let t = 1.0 - (-self.exposure * c).exp();
        let s = srgb_encode(t.clamp(0.0, 1.0));
        // `as u8` saturates and maps NaN to 0, which is the documented result for NaN.
        (s * 255.0).round() as u8
    }

    /// The 8-bit sRGB pixel of a linear RGB pixel ([`ToneMap::apply`] per channel).
    pub fn apply_rgb(&self, rgb: [f32; 3]) -> [u8; 3] {
        rgb.map(|c| self.apply(c))
    }

    /// [`ToneMap::apply_rgb`] of every pixel, as consecutive R, G, B bytes. Large images
    /// are split over the CPU's threads: a megapixel is three million `exp` and `powf`,
    /// tens of milliseconds on one core.
    pub fn apply_pixels(&self, pixels: &[[f32; 3]]) -> Vec<u8> {
        const MIN_CHUNK: usize = 1 << 16;
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let chunk = pixels.len().div_ceil(threads).max(MIN_CHUNK);
        let mut bytes = vec![0u8; 3 * pixels.len()];
        std::thread::scope(|s| {
            for (out, input) in bytes.chunks_mut(3 * chunk).zip(pixels.chunks(chunk)) {
                s.spawn(move || {
                    for (o, &p) in out.chunks_exact_mut(3).zip(input) {
                        o.copy_from_slice(&self.apply_rgb(p));
                    }
                });
            }
        });
        bytes
    }
}

/// The sRGB transfer function (linear → encoded), for `t` in 0..=1.
pub(super) fn srgb_encode(t: f32) -> f32 {
    if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    }
}
