//! What the shadow kernels (`shaders/shadow_mft.wgsl`, `shadow_packet.wgsl`,
//! `shadow_per_ray.wgsl`) and their CPU twins agree on besides the structs of
//! [`crate::contract::layout`]: the shadow ray's extent and mask bits, the parameters a dispatch
//! gets, and the multi-frusta kernel's constants and its words of the suspended state.

use crate::contract::layout::ShadowParams;
use crate::scene::view::QuadLight;

/// Shadow rays end at `t_max = 1 − 2⁻¹²`, just short of the light sample, so
/// geometry that holds the light (a luminaire's own mesh) does not block it.
pub const SHADOW_T_MAX: f32 = 1.0 - 1.0 / 4096.0;

/// Widening of a shrunk frustum's light rectangle, in light-edge units: samples
/// lie at odd multiples of 1/512, so this keeps every active sample 1/1024 of an
/// edge inside, far above the rounding of the (s, t) arithmetic.
pub const SHRINK_MARGIN: f32 = 1.0 / 1024.0;
/// Marks a frustum's `shrunk_for` as set.
pub const SHRINK_FLAG: u32 = 1 << 31;
/// Widening of a frustum's bounding box, relative to the size of its
/// coordinates: its corners are rounded to f32, so the box of the rounded
/// corners may miss a few ulps of the exact pyramid; 2⁻¹⁸ is far above that.
pub const BOUNDS_PAD: f32 = 1.0 / 262_144.0;

/// 32-bit words of one tile's saved state in `shaders/shadow_mft.wgsl` (its `STATE_WORDS`):
/// the words of [`crate::contract::suspend`] (status, first child to visit, mask, cursor,
/// end, alive, stack depth, flags (1: popping, 2: traversal done), 16 lane masks, 64 stack
/// nodes, 64 stack masks), then the kernel's own: the transposed leaf's candidates, the
/// current leaf's frusta, the pending leaf (first, end, frusta; end 0: none), 3 unused
/// words, and 16 lane words of `shrunk_for`.
pub const STATE_WORDS: usize = 176;
/// 32-bit words of one pixel's saved state in `shaders/shadow_packet.wgsl` (its
/// `PACKET_STATE_WORDS`): the shared words of [`crate::contract::suspend`], padded to 160.
pub const PACKET_STATE_WORDS: usize = 160;
/// The transposed leaf's candidate frusta.
pub const ST_CAND: usize = 152;
/// The current leaf's frusta.
pub const ST_LEAF_MASK: usize = 153;
/// First of the pending leaf's three words.
pub const ST_PENDING: usize = 154;
/// First of the 16 lane words of `shrunk_for`.
pub const ST_SHRUNK: usize = 160;

/// Shadow parameters for a light and image size (one dispatch over the whole image).
pub fn shadow_params(light: &QuadLight, width: u32, height: u32) -> ShadowParams {
    let c = light.corner;
    let corners = [
        c,
        c + light.edge_u,
        c + light.edge_u + light.edge_v,
        c + light.edge_v,
    ];
    ShadowParams {
        light_corners: corners.map(|p| p.extend(0.0).to_array()),
        light_normal: light.area_normal(),
        t_max: SHADOW_T_MAX,
        width,
        height,
        tile_origin_x: 0,
        tile_origin_y: 0,
        tiles_x: width.div_ceil(4),
        resume: 0,
        iteration_budget: super::ITERATION_BUDGET,
        tiles_y: height.div_ceil(4),
    }
}
