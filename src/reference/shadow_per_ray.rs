//! What a shadow ray is, shared by every shadow tracer (CPU and GPU): the
//! per-ray oracle here traces each of a pixel's 16 rays alone with
//! Möller–Trumbore over the BVH.
//!
//! Pixel `(x, y)` with a G-buffer hit traces 16 rays from its `origin` to the
//! light points of its set `k = (x mod 4) + 4·(y mod 4)`: ray `j` is
//! `origin + t·(p[16k + j] − origin)`, `0 < t < t_max`. Bit `j` of the
//! pixel's mask is set when the ray is blocked:
//! - by a triangle hit in that range;
//! - by the surface itself: the sample is not above the tangent plane of the
//!   geometric normal (`dot(geo_normal, d) ≤ 0`);
//! - by the light's back: the origin is not on the emitting side of the light
//!   (`dot(light_normal, origin − corner) ≤ 0`): all 16 bits.
//!
//! Pixels that see no geometry get [`MASK_SKY`] (no bit of 0..16 set):
//! visibility is undefined there and the shade pass shows the background.

use glam::{Vec3, Vec4Swizzles};

use crate::bvh::Bvh;
use crate::contract::layout::{GBufferTexel, ShadowParams};
use crate::reference::any_hit;
use crate::sampling::{SAMPLES_PER_SET, pixel_set};

pub use crate::contract::ITERATION_BUDGET;
use crate::contract::layout::{MASK_FULL, MASK_SKY};
pub use crate::contract::shadow::{SHADOW_T_MAX, shadow_params};

/// The light's corners as points.
pub fn light_corners(params: &ShadowParams) -> [Vec3; 4] {
    params.light_corners.map(|c| glam::Vec4::from_array(c).xyz())
}

/// Whether `origin` is on the emitting side of the light.
pub fn faces_light(params: &ShadowParams, origin: Vec3) -> bool {
    params.light_normal.dot(origin - light_corners(params)[0]) > 0.0
}

/// Bits of the rays of `set` that start below the surface's tangent plane.
pub fn below_horizon_mask(texel: &GBufferTexel, set: usize, light_points: &[Vec3]) -> u32 {
    (0..SAMPLES_PER_SET)
        .filter(|&j| {
            texel
                .geo_normal
                .dot(light_points[set * SAMPLES_PER_SET + j] - texel.origin)
                <= 0.0
        })
        .fold(0, |m, j| m | (1 << j))
}

/// The mask a pixel starts from before any triangle is tested: sky, back of
/// the light, or the rays below the horizon.
pub fn initial_mask(texel: &GBufferTexel, set: usize, light_points: &[Vec3], params: &ShadowParams) -> u32 {
    if !texel.is_hit() {
        MASK_SKY
    } else if !faces_light(params, texel.origin) {
        MASK_FULL
    } else {
        below_horizon_mask(texel, set, light_points)
    }
}

/// One pixel's occlusion mask, each ray traced alone (Möller–Trumbore any-hit).
pub fn per_ray_mask(
    bvh: &Bvh,
    texel: &GBufferTexel,
    set: usize,
    light_points: &[Vec3],
    params: &ShadowParams,
) -> u32 {
    let mut mask = initial_mask(texel, set, light_points, params);
    if mask & MASK_SKY != 0 {
        return mask;
    }
    for j in 0..SAMPLES_PER_SET {
        if mask & (1 << j) == 0 {
            let d = light_points[set * SAMPLES_PER_SET + j] - texel.origin;
            if any_hit(bvh, texel.origin, d, params.t_max) {
                mask |= 1 << j;
            }
        }
    }
    mask
}

/// Occlusion masks of a whole G-buffer (row-major), rows spread over all cores.
pub fn per_ray_masks(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
) -> Vec<u32> {
    super::parallel::per_texel(gbuffer, params, |x, y, texel| {
        per_ray_mask(bvh, texel, pixel_set(x, y), light_points, params)
    })
}

/// The reference tracer's oracle: per pixel, the number of the `points` (the same
/// for every pixel, see [`crate::sampling::reference_light_points`]) whose ray is
/// blocked, under the rules of [`initial_mask`] (below the horizon or behind the
/// light counts as blocked), or [`MASK_SKY`].
pub fn reference_counts(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    points: &[Vec3],
    params: &ShadowParams,
) -> Vec<u32> {
    super::parallel::per_texel(gbuffer, params, |_, _, texel| {
        if !texel.is_hit() {
            return MASK_SKY;
        }
        let behind = !faces_light(params, texel.origin);
        points
            .iter()
            .filter(|&&q| {
                let d = q - texel.origin;
                behind || texel.geo_normal.dot(d) <= 0.0 || any_hit(bvh, texel.origin, d, params.t_max)
            })
            .count() as u32
    })
}

/// Visible fraction of a reference tracer's pixel word (1 for sky pixels).
pub fn reference_visibility(count: u32, rays: u32) -> f32 {
    if count & MASK_SKY != 0 {
        1.0
    } else {
        1.0 - count as f32 / rays as f32
    }
}
