//! What the discontinuity filter's kernel (`shaders/filter.wgsl`) shares with Rust:
//! its name, workgroup size and uniform ([`FilterParams`]); the filter itself and its
//! CPU twin are described in `crate::reference::filter`.

use bytemuck::{Pod, Zeroable};

/// The filter kernel is `shaders/filter.wgsl` (entry point `main`, workgroup
/// [`WORKGROUP_SIZE`]² invocations, [`FILTER_PIXELS_PER_INVOCATION`] pixels each), assembled with the window of
/// `shaders/shared/filter_window.wgsl` by [`crate::shaders::assemble`].
///
/// Bindings, group 0: 0 `filter_params: FilterParams` (uniform), 1 `values:
/// texture_2d<f32>`, 2 `normal: texture_2d<f32>` (the normal in xyz and the depth in w;
/// see [`normals_for_gpu`](crate::reference::filter::normals_for_gpu)), both width×height
/// `Rgba32Float` textures
/// ([`crate::gpu::FILTER_INPUT_TEXTURES`]), and 3 `filtered: array<vec4<f32>>`
/// (read-write storage, the output, row-major).
pub const FILTER_KERNEL: &str = "filter";

/// Horizontally adjacent pixels each invocation of the filter kernel filters (their windows
/// share most taps: 40 texel pairs fetched for 4 pixels instead of 100): dispatch
/// `ceil(width / (8 · 4)) × ceil(height / 8)` workgroups. The kernel is written for 4 (a
/// naga test checks its constant of this name).
pub const FILTER_PIXELS_PER_INVOCATION: u32 = 4;

/// Every tap of the window: bit `(dy + 2)·5 + (dx + 2)` for `dx, dy` in `−2 ..= 2`
/// (`FULL_WINDOW` of `shaders/shared/filter_window.wgsl`).
pub const FULL_WINDOW: u32 = (1 << 25) - 1;

/// The kernel's workgroup is `WORKGROUP_SIZE × WORKGROUP_SIZE` invocations (see
/// [`FILTER_PIXELS_PER_INVOCATION`] for the dispatch). Equal to `WG_SIZE` in the WGSL
/// (a test checks).
pub const WORKGROUP_SIZE: u32 = super::groups::PIXEL_GROUP;

/// The filter's settings, 32 bytes; also the kernel's uniform (WGSL
/// `FilterParams`, same member names; a test compares the layouts).
#[repr(C)]
#[derive(Pod, Zeroable, Clone, Copy, Debug, PartialEq)]
pub struct FilterParams {
    /// Image width in pixels (bytes 0..4).
    pub width: u32,
    /// Image height in pixels (bytes 4..8).
    pub height: u32,
    /// Relative depth tolerance (bytes 8..12): neighbour `n` is accepted by the
    /// centre `c` only if `|d_n − d_c| ≤ depth_tolerance · d_c`. Too tight
    /// (near 0) rejects neighbours on the same surface seen at a grazing angle,
    /// and their noise stays; too loose lets shadow bleed across silhouettes
    /// onto surfaces behind or in front.
    pub depth_tolerance: f32,
    /// Normal tolerance (bytes 12..16), a cosine: neighbour `n` is accepted only
    /// if `dot(n_n, n_c) ≥ normal_tolerance`. Too tight (near 1) rejects
    /// neighbours on curved surfaces, and their noise stays; too loose lets
    /// shadow bleed around creases and corners (a wall's shadow onto the floor
    /// beside it).
    pub normal_tolerance: f32,
    /// Visibility tolerance (bytes 16..20): neighbour `n` is accepted only if its
    /// unfiltered visibility (the values' fourth component) differs from the
    /// centre's by at most this. Averaging is for noise, not for real changes of
    /// visibility: without this test the 4×4 window blurs contact shadows and
    /// silhouettes, and the filtered image is further from the exact one than the
    /// unfiltered (`penumbra quality`). 1 or more turns the test off.
    pub visibility_tolerance: f32,
    /// Unused (bytes 20..24; a uniform's size is a multiple of 16).
    pub pad0: u32,
    /// Unused (bytes 24..28).
    pub pad1: u32,
    /// Unused (bytes 28..32).
    pub pad2: u32,
}

const _: () = assert!(size_of::<FilterParams>() == 32);

impl FilterParams {
    /// Default [`FilterParams::depth_tolerance`]: 5 % of the centre's depth.
    pub const DEFAULT_DEPTH_TOLERANCE: f32 = 0.05;
    /// Default [`FilterParams::normal_tolerance`]: cosine 0.9, about 26°.
    pub const DEFAULT_NORMAL_TOLERANCE: f32 = 0.9;
    /// Default [`FilterParams::visibility_tolerance`]: 2 of 16 rays. Measured with
    /// `penumbra quality --size 256x256` (RMSE against exact visibility, filtered /
    /// unfiltered 16 spp): without the test 0.0468 / 0.0155 on the playground and
    /// 0.0361 / 0.0120 on Sponza's atrium (512²); with 0.125, 0.0145 and 0.0103 / 0.0121
    /// (all with the earlier `x−1 ..= x+2` window). With the centred window, 256²
    /// playground / lattice: 0.1875 gives 0.0141 / 0.0323, 0.25 gives 0.0155 / 0.0340,
    /// 0.375 gives 0.0187 / 0.0366, against 0.0136 / 0.0330 with 0.125 (kept: 3 %
    /// better on the playground, 2 % worse on the lattice than 0.1875).
    pub const DEFAULT_VISIBILITY_TOLERANCE: f32 = 0.125;

    /// These tolerances and the default visibility tolerance for a `width × height` image.
    pub fn with_tolerances(width: u32, height: u32, depth_tolerance: f32, normal_tolerance: f32) -> Self {
        FilterParams {
            width,
            height,
            depth_tolerance,
            normal_tolerance,
            visibility_tolerance: Self::DEFAULT_VISIBILITY_TOLERANCE,
            pad0: 0,
            pad1: 0,
            pad2: 0,
        }
    }

    /// Settings for a `width × height` image with the default tolerances.
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_tolerances(
            width,
            height,
            Self::DEFAULT_DEPTH_TOLERANCE,
            Self::DEFAULT_NORMAL_TOLERANCE,
        )
    }

    /// Number of pixels, `width · height`.
    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }
}
