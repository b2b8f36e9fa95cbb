//! What a standalone frame is rendered with: per-frame settings ([`FrameSettings`]), the
//! renderer's build options ([`RendererOptions`]) and the phases its progress reports name.

use super::{LeafMode, PrimaryTracer, Tracer, TracerOptions, VectorVariant};
use crate::contract::ITERATION_BUDGET;
use crate::contract::filter::FilterParams;

/// Per-frame choices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Image width in pixels (any size ≥ 1; tiles at the right and bottom edges are partial).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The discontinuity filter's tolerances, or `None` to skip the filter.
    pub filter: Option<(f32, f32)>,
    /// Read the G-buffer back too (tests compare it with the CPU twin).
    pub keep_gbuffer: bool,
    /// Largest tile side (a multiple of 4) to render the image in, or `None` for the
    /// largest whose buffers fit the adapter's storage-buffer limit (tests force tiling).
    pub max_tile: Option<u32>,
    /// After the filter, trace all 256 light samples for the pixels where visibility
    /// changes around them and their window is cut (at a one-ray visibility tolerance) or
    /// their own rays agree (the CPU twin: `crate::reference::refine`). Needs the filter and an interleaved tracer (not
    /// [`Tracer::Reference`]).
    pub refine: bool,
    /// With [`Self::refine`]: trace on average at most this many rays per pixel with
    /// geometry, the frame's 16 included (each refined pixel costs 256), refining the
    /// pixels whose filtered value is furthest from the mean of the unfiltered ones around
    /// them first (`crate::reference::refine::refine_score`). `None`: refine every pixel
    /// the rule picks. At least 16 and finite; applies per tile of a tiled frame.
    pub ray_budget: Option<f32>,
    /// With [`Self::refine`]: how many of the 16 sample sets (16 rays each) a refined pixel
    /// traces, 1, 2, 4, 8 or 16 (the default: all 256 light samples). Fewer sets refine
    /// twice as many pixels per halving within a [`Self::ray_budget`], each with a noisier
    /// value (16 · sets rays, none from its neighbours).
    pub refine_sets: u32,
}

impl FrameSettings {
    /// A `width`×`height` frame with the default filter.
    pub fn new(width: u32, height: u32) -> FrameSettings {
        FrameSettings {
            width,
            height,
            filter: Some((
                FilterParams::DEFAULT_DEPTH_TOLERANCE,
                FilterParams::DEFAULT_NORMAL_TOLERANCE,
            )),
            keep_gbuffer: false,
            max_tile: None,
            refine: false,
            ray_budget: None,
            refine_sets: 16,
        }
    }
}

/// What a frame's progress report is about ([`super::Renderer::render_with_progress`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// The shadow pass, in tiles (or pixels, for the per-ray tracers) of the image.
    Shadow,
    /// The refinement's tracing, in units of its sample image.
    Refine,
}

/// How the renderer builds its shadow pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RendererOptions {
    /// Force a vector variant, or `None` for the adapter's best (see [`VectorVariant::choose`]).
    pub variant: Option<VectorVariant>,
    /// How the shadow kernel's leaves use the lanes.
    pub leaf_mode: LeafMode,
    /// The shadow tracer. [`Tracer::Reference`] frames should be rendered without the
    /// filter (the reference is the unfiltered yardstick); the renderer does not enforce it.
    pub tracer: Tracer,
    /// Count the shadow kernel's work
    /// ([`ShadowStats::counters`](crate::gpu::ShadowStats::counters)).
    pub counters: bool,
    /// MFT frustum shrinking ([`TracerOptions::shrink`]; on by default).
    pub shrink: bool,
    /// Which kernel traces the camera rays.
    pub primary: PrimaryTracer,
    /// Loop iterations a multi-frusta primary vector may run (at least 1; 60,000 by
    /// default, below lavapipe's loop limit); a frame where one runs out is traced again
    /// by the per-ray kernel (tests lower it), one where the driver ends a loop (a budget
    /// above its limit) is an [`Error::LoopCut`](crate::Error::LoopCut).
    pub primary_iteration_budget: u32,
}

impl Default for RendererOptions {
    fn default() -> RendererOptions {
        let t = TracerOptions::default();
        RendererOptions {
            variant: t.variant,
            leaf_mode: t.leaf_mode,
            tracer: t.tracer,
            counters: t.counters,
            shrink: t.shrink,
            primary: PrimaryTracer::default(),
            primary_iteration_budget: ITERATION_BUDGET,
        }
    }
}

/// A forced (or automatic) vector variant with the default leaf mode, so that
/// `Renderer::new(ctx, None)` and `Renderer::new(ctx, Some(variant))` read as before.
impl From<Option<VectorVariant>> for RendererOptions {
    fn from(variant: Option<VectorVariant>) -> RendererOptions {
        RendererOptions {
            variant,
            ..RendererOptions::default()
        }
    }
}
