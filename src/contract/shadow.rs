//! What the shadow kernels (`shaders/shadow_mft.wgsl`, `shadow_packet.wgsl`,
//! `shadow_per_ray.wgsl`) and their CPU twins agree on besides the structs of
//! [`crate::contract::layout`]: the shadow ray's extent and mask bits, the parameters a dispatch
//! gets, and the multi-frusta kernel's constants and suspended-state layout.

use crate::contract::layout::ShadowParams;
use crate::scene::view::QuadLight;

/// Shadow rays end at `t_max = 1 − 2⁻¹²`, just short of the light sample, so
/// geometry that holds the light (a luminaire's own mesh) does not block it.
pub const SHADOW_T_MAX: f32 = 1.0 - 1.0 / 4096.0;
/// All 16 rays blocked.
pub const MASK_FULL: u32 = 0xffff;
/// Marks a pixel without geometry.
pub const MASK_SKY: u32 = 1 << 16;

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

/// 32-bit words of one tile's saved state, in the layout of `shaders/shadow_mft.wgsl`
/// (its `STATE_WORDS` and `ST_*` offsets): status, first child to visit, mask,
/// cursor, end, alive, stack depth, flags (1: popping, 2: traversal done), 16 lane
/// masks, 64 stack nodes, 64 stack masks, the transposed leaf's candidates, the
/// current leaf's frusta, the pending leaf (first, end, frusta; end 0: none), 3
/// unused words, and 16 lane words of `shrunk_for`.
pub const STATE_WORDS: usize = 176;
/// Word of the status ([`STATUS_SUSPENDED`] while a tile waits to be resumed).
pub const ST_STATUS: usize = 0;
/// First of the 16 lane masks.
pub const ST_LANES: usize = 8;
/// First of the stack's nodes.
pub const ST_STACK_NODE: usize = 24;
/// First of the stack's frustum masks.
pub const ST_STACK_MASK: usize = 88;
/// The transposed leaf's candidate frusta.
pub const ST_CAND: usize = 152;
/// The current leaf's frusta.
pub const ST_LEAF_MASK: usize = 153;
/// First of the pending leaf's three words.
pub const ST_PENDING: usize = 154;
/// First of the 16 lane words of `shrunk_for`.
pub const ST_SHRUNK: usize = 160;
/// [`ST_STATUS`] of a suspended tile.
pub const STATUS_SUSPENDED: u32 = 1;

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

#[cfg(test)]
mod tests {
    use super::super::tests::wgsl_constant;
    use super::*;

    /// The suspended-state layout and the constants the twin shares with
    /// `shaders/shadow_mft.wgsl` (the kernel's saved words are compared with the twin's
    /// in tests/gpu/shadow_tracers.rs; this names a mismatch on the CPU).
    #[test]
    fn the_kernel_has_the_twins_constants() {
        use naga::Literal::{F32, U32};
        let u = |v: usize| U32(v as u32);
        for aliases in [
            [("shared/vec16", "shared/vec16_subgroup")],
            [("shared/vec16", "shared/vec16_workgroup")],
        ] {
            for (name, value) in [
                ("STATE_WORDS", u(STATE_WORDS)),
                ("ST_STATUS", u(ST_STATUS)),
                ("ST_LANES", u(ST_LANES)),
                ("ST_STACK_NODE", u(ST_STACK_NODE)),
                ("ST_STACK_MASK", u(ST_STACK_MASK)),
                ("ST_CAND", u(ST_CAND)),
                ("ST_LEAF_MASK", u(ST_LEAF_MASK)),
                ("ST_PENDING", u(ST_PENDING)),
                ("ST_SHRUNK", u(ST_SHRUNK)),
                ("STATUS_SUSPENDED", U32(STATUS_SUSPENDED)),
                ("STACK_SIZE", u(super::super::STACK_SIZE)),
                ("MASK_FULL", U32(MASK_FULL)),
                ("MASK_SKY", U32(MASK_SKY)),
                ("SHRINK_FLAG", U32(SHRINK_FLAG)),
                ("SHRINK_MARGIN", F32(SHRINK_MARGIN)),
                ("BOUNDS_PAD", F32(BOUNDS_PAD)),
                ("WORD_LOOP_CUT", u(crate::contract::counters::WORD_LOOP_CUT)),
            ] {
                assert_eq!(
                    wgsl_constant("shadow_mft", &aliases, name),
                    value,
                    "{name} with {aliases:?}"
                );
            }
        }
    }

    /// The packet kernel's suspended state shares the MFT layout's first 160 words.
    #[test]
    fn the_packet_kernel_shares_the_state_layout() {
        use naga::Literal::U32;
        for aliases in [
            [("shared/vec16", "shared/vec16_subgroup")],
            [("shared/vec16", "shared/vec16_workgroup")],
        ] {
            for (name, value) in [
                ("STATE_WORDS", ST_SHRUNK),
                ("ST_STATUS", ST_STATUS),
                ("ST_LANES", ST_LANES),
                ("ST_STACK_NODE", ST_STACK_NODE),
                ("ST_STACK_MASK", ST_STACK_MASK),
                ("STATUS_SUSPENDED", STATUS_SUSPENDED as usize),
            ] {
                assert_eq!(
                    wgsl_constant("shadow_packet", &aliases, name),
                    U32(value as u32),
                    "{name}"
                );
            }
        }
    }
}
