//! The GPU side: choosing an adapter, creating buffers, reading them back, timing passes.
//!
//! Tests and the CLI get a [`GpuContext`] from [`GpuContext::new`]; the adapter comes from
//! [`GpuOptions::adapter`], else the `PENUMBRA_ADAPTER` environment variable, else the best
//! one found (Vulkan first, so lavapipe serves machines without a GPU). Everything that can
//! fail for reasons outside the caller's control returns [`crate::Error`] instead of
//! panicking: a missing driver, a buffer over the adapter's limit, a failed mapping.
//!
//! An application with its own device embeds the shadow pass through [`embed`]
//! ([`ShadowPass`]).

pub mod animate;
mod buffers;
mod context;
pub mod embed;
mod frame;
pub mod kernel;
pub mod memory;
mod motion;
mod pixel_buffers;
pub mod primary_pass;
mod ray_query;
pub mod refine;
pub mod render;
mod render_settings;
mod scene_buffers;
mod shadow_options;
mod shadow_stages;
pub mod shadow_tracer;
mod tiling;
mod timer;
mod vector_variant;

pub use buffers::{empty_storage_buffer, read_buffer, read_texture, storage_buffer};
pub use context::{
    ADAPTER_ENV, AdapterSummary, GpuContext, GpuOptions, LAVAPIPE_VECTOR_WIDTH_ENV, NO_DEVICE_SELECT_ENV,
    SHADER_CACHE_DIR_ENV, lavapipe_shader_cache_dir, set_driver_defaults, set_driver_defaults_for_drawing,
};
pub use embed::{
    NormalEncoding, ShadowInputs, ShadowPass, ShadowSettings, ShadowTargets, SurfaceInput, VISIBILITY_FORMAT,
};
pub use frame::{Ambient, Frame, image_of_lights};
pub use motion::{MotionSettings, MotionUpdate};
pub use pixel_buffers::{
    FILTER_INPUT_FORMAT, FILTER_INPUT_TEXTURES, PIXEL_BUFFERS, PixelBuffer, PixelBuffers,
};
pub use primary_pass::{PrimaryOptions, PrimaryPass, PrimaryStatus, PrimaryTracer};
pub use ray_query::RayQueryScene;
pub use render::{CpuShadows, Renderer};
pub use render_settings::{FrameSettings, Phase, RendererOptions};
pub use scene_buffers::{GpuScene, validate_for_gpu};
pub use shadow_options::{DEFAULT_REFERENCE_RAYS, LeafMode, Tracer, TracerOptions};
pub use shadow_tracer::{ShadowImage, ShadowScratch, ShadowStats, ShadowTracer};
pub use timer::GpuTimer;
pub use vector_variant::VectorVariant;
