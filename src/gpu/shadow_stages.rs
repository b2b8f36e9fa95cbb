//! The stages every frame runs after its G-buffer exists — shadow rays → visibility →
//! discontinuity filter (→ refinement) — built and recorded by one piece of code for the
//! standalone renderer ([`super::Renderer`], which adds its primary pass, the waiting
//! resume loop and the read-back) and the embedded pass ([`super::ShadowPass`], which adds
//! the G-buffer from the host's textures and the copies into its visibility textures).

use std::sync::OnceLock;

use super::kernel::{Checks, Kernel, buffer, texture, uniform_buffer_on};
use super::pixel_buffers::PixelBuffers;
use super::refine::{RefineBuffers, Refinement};
use super::{GpuContext, GpuScene, GpuTimer, ShadowTracer, Tracer, TracerOptions};
use crate::contract::filter::{FILTER_KERNEL, FILTER_PIXELS_PER_INVOCATION, FilterParams};
use crate::contract::groups::PIXEL_GROUP;
use crate::contract::layout::ShadowParams;
use crate::contract::refine::selection_params;
use crate::{Error, Result};

/// What turns masks into the values the filter smooths.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisibilityStage {
    /// `shaders/shade.wgsl` (the renderer): masks and G-buffer → irradiance and visibility,
    /// and the depth, normal and BRDF per pixel. Its uniform is a `ShadeParams`.
    Shade,
    /// `shaders/visibility_values.wgsl` (the embedded pass): masks → visibility; depth and
    /// normal were written with the G-buffer. Its uniform is an `ImageSize`.
    Values,
}

/// The pipelines of the stages: the shadow tracer, the visibility kernel, the filter, and
/// (built on first use) the refinement's.
#[derive(Debug)]
pub struct ShadowStages {
    /// The shadow tracer (also the refinement's).
    pub tracer: ShadowTracer,
    stage: VisibilityStage,
    visibility: Kernel,
    filter: Kernel,
    refinement: OnceLock<Refinement>,
}

impl ShadowStages {
    /// Builds the tracer `options` describe, the `stage` kernel and the filter.
    pub fn new(ctx: &GpuContext, options: &TracerOptions, stage: VisibilityStage) -> Result<ShadowStages> {
        let visibility = match stage {
            VisibilityStage::Shade => {
                // 0 unless the masks are reference counts rather than bits.
                let reference_rays = match options.tracer {
                    Tracer::Reference { rays } => rays,
                    _ => 0,
                };
                let constants = [("REFERENCE_RAYS", f64::from(reference_rays))];
                Kernel::new(ctx, "shade", &[], &constants, Checks::Checked)?
            }
            VisibilityStage::Values => Kernel::new(ctx, "visibility_values", &[], &[], Checks::Checked)?,
        };
        Ok(ShadowStages {
            tracer: ShadowTracer::new(ctx, options)?,
            stage,
            visibility,
            filter: Kernel::new(ctx, FILTER_KERNEL, &[], &[], Checks::Checked)?,
            refinement: OnceLock::new(),
        })
    }

    /// Records the visibility stage (`params`: its uniform, see [`VisibilityStage`]) and,
    /// with `filter`, the copies of the filter's inputs into textures and the filter (the
    /// visibility stage one invocation per pixel, the filter one per
    /// [`FILTER_PIXELS_PER_INVOCATION`] pixels of a row, in 8×8 workgroups), timed as `shade` and `filter` (with the
    /// copies) when a timer is given. Returns the buffer that holds the final values:
    /// `pixels.filtered`, or `pixels.values` without the filter.
    pub fn record_visibility_and_filter<'p>(
        &self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        pixels: &'p PixelBuffers,
        params: &wgpu::Buffer,
        filter: Option<&FilterParams>,
        mut timer: Option<&mut GpuTimer>,
    ) -> Result<&'p wgpu::Buffer> {
        let groups = (
            pixels.size.0.div_ceil(PIXEL_GROUP),
            pixels.size.1.div_ceil(PIXEL_GROUP),
        );
        let (bind, label) = match (self.stage, &pixels.brdf) {
            (VisibilityStage::Shade, Some(brdf)) => (
                self.visibility.bind(
                    device,
                    &[
                        buffer("params", params),
                        buffer("gbuffer", &pixels.gbuffer),
                        buffer("masks", &pixels.masks),
                        buffer("values", &pixels.values),
                        buffer("normal", &pixels.normal),
                        buffer("brdf", brdf),
                    ],
                )?,
                "shade",
            ),
            (VisibilityStage::Shade, None) => {
                return Err(Error::Gpu("the shade stage needs the frame's brdf buffer".into()));
            }
            (VisibilityStage::Values, _) => (
                self.visibility.bind(
                    device,
                    &[
                        buffer("size", params),
                        buffer("masks", &pixels.masks),
                        buffer("values", &pixels.values),
                    ],
                )?,
                "embed/visibility",
            ),
        };
        let writes = timer.as_deref_mut().and_then(|t| t.pass_writes("shade"));
        self.visibility.record(encoder, label, &bind, writes, groups);
        let Some(filter) = filter else {
            return Ok(&pixels.values);
        };
        let params = uniform_buffer_on(device, "filter params", filter);
        let values = pixels.values_texture.create_view(&Default::default());
        let normal = pixels.normal_texture.create_view(&Default::default());
        let bind = self.filter.bind(
            device,
            &[
                buffer("filter_params", &params),
                texture("values", &values),
                texture("normal", &normal),
                buffer("filtered", &pixels.filtered),
            ],
        )?;
        // The copies into the filter's textures are timed with it, as `filter`.
        let (start, end) = timer
            .and_then(|t| t.span_writes("filter"))
            .map_or((None, None), |(s, e)| (Some(s), Some(e)));
        if start.is_some() {
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("filter input copies"),
                timestamp_writes: start,
            });
        }
        pixels.record_filter_input_copies(encoder);
        let filter_groups = (
            pixels.size.0.div_ceil(PIXEL_GROUP * FILTER_PIXELS_PER_INVOCATION),
            pixels.size.1.div_ceil(PIXEL_GROUP),
        );
        self.filter.record(encoder, "filter", &bind, end, filter_groups);
        Ok(&pixels.filtered)
    }

    /// Runs the refinement on a frame whose filter was submitted (see [`Refinement::run`]):
    /// `shadow` and `shade_params` are the frame's, `filter` its filter's parameters,
    /// `budget` the ray budget ([`super::FrameSettings::ray_budget`]), `sets` the sample sets
    /// each refined pixel traces ([`super::FrameSettings::refine_sets`]).
    /// Returns the refined pixels' indices, sorted.
    #[allow(clippy::too_many_arguments)]
    pub fn refine(
        &self,
        ctx: &GpuContext,
        scene: &GpuScene,
        pixels: &PixelBuffers,
        light_points: &wgpu::Buffer,
        shadow: &ShadowParams,
        shade_params: &wgpu::Buffer,
        filter: &FilterParams,
        budget: Option<f32>,
        sets: u32,
        timer: &mut GpuTimer,
        progress: &mut dyn FnMut(u64, u64),
    ) -> Result<Vec<u32>> {
        let refinement = match self.refinement.get() {
            Some(r) => r,
            None => {
                let built = Refinement::new(ctx)?;
                self.refinement.get_or_init(|| built)
            }
        };
        let selection = uniform_buffer_on(&ctx.device, "refine selection params", &selection_params(filter));
        let buffers = RefineBuffers {
            selection_params: &selection,
            shadow_params: shadow,
            shade_params,
            pixels,
            light_points,
        };
        refinement.run(ctx, scene, &self.tracer, &buffers, budget, sets, timer, progress)
    }
}
