//! What the primary kernels (`shaders/primary.wgsl`, `shaders/primary_mft.wgsl`) and their
//! twins agree on besides [`crate::contract::layout::CameraParams`].

/// Side of the pixel block one multi-frusta vector traces.
pub const BLOCK: u32 = 16;

/// The multi-frusta kernel drops a box or triangle when its depth exceeds every ray's
/// closest `t` by this factor (`DEPTH_SLACK`).
pub const DEPTH_SLACK: f32 = 1.001;
/// A ray's `t` before it hits anything (`T_NONE`; the per-ray kernel's initial `t_best`).
pub const T_NONE: f32 = f32::MAX;
