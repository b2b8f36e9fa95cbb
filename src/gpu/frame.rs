//! A rendered frame as the standalone renderer returns it: read back to the CPU, with its
//! timings and statistics.

use super::ShadowStats;
use crate::contract::layout::GBufferTexel;

/// A rendered frame, read back to the CPU (row-major, row 0 at the top).
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Shadow masks: bit j = ray j blocked; `1 << 16` marks sky pixels.
    pub masks: Vec<u32>,
    /// Shadowed irradiance (rgb) and visibility (a) before the filter.
    pub unfiltered: Vec<[f32; 4]>,
    /// The same after the filter (equal to `unfiltered` when the filter is off), and
    /// after the refinement at the refined pixels.
    pub filtered: Vec<[f32; 4]>,
    /// Per pixel, whether the refinement traced its 256 light samples (all false
    /// without [`super::FrameSettings::refine`]).
    pub refined: Vec<bool>,
    /// Diffuse BRDF, albedo / π (rgb; a unused); 0 for sky pixels.
    pub brdf: Vec<[f32; 4]>,
    /// The G-buffer, when [`super::FrameSettings::keep_gbuffer`] asked for it; positions are
    /// relative to [`GpuScene::origin`] (the world's for a scene near the origin).
    pub gbuffer: Option<Vec<GBufferTexel>>,
    /// GPU milliseconds per pass: `primary`, `shadow` (all its dispatches), `shade`, `filter`.
    pub timings: Vec<(String, f64)>,
    /// Dispatches and suspensions of the shadow pass.
    pub shadow_stats: ShadowStats,
    /// Work counted by the primary kernel (zero unless built with
    /// [`super::RendererOptions::counters`]).
    pub primary_counters: crate::contract::counters::Counters,
    /// Pixels whose multi-frusta primary vectors ran out of loop iterations, after which
    /// the per-ray kernel traced the frame's camera rays again (0: it did not happen).
    pub primary_fallback_pixels: u32,
}

impl Frame {
    /// Outgoing radiance per pixel: BRDF × filtered irradiance (the image).
    pub fn radiance(&self) -> Vec<[f32; 3]> {
        self.brdf
            .iter()
            .zip(&self.filtered)
            .map(|(b, e)| [b[0] * e[0], b[1] * e[1], b[2] * e[2]])
            .collect()
    }

    /// GPU milliseconds of the pass `name`, summed over its dispatches (0 when not timed).
    pub fn pass_ms(&self, name: &str) -> f64 {
        self.timed_ms(name).unwrap_or(0.0)
    }

    /// [`Frame::pass_ms`], or `None` when no dispatch of `name` was timed (the adapter has
    /// no timestamp queries, or the pass did not run).
    pub fn timed_ms(&self, name: &str) -> Option<f64> {
        let mut times = self.timings.iter().filter(|(n, _)| n == name).peekable();
        times.peek()?;
        Some(times.map(|(_, ms)| ms).sum())
    }
}
