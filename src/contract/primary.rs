//! What the primary kernels (`shaders/primary.wgsl`, `shaders/primary_mft.wgsl`) and their
//! twins agree on besides [`crate::contract::layout::CameraParams`].

/// Side of the pixel block one multi-frusta vector traces.
pub const BLOCK: u32 = 16;
