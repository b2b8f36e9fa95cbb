//! CPU twin of the refinement (`shaders/refine_select.wgsl`, `shaders/refine_trace.wgsl`):
//! where the discontinuity filter cannot average the 16 sample sets of its window, the
//! pixel traces the 240 rays of the other 15 sets itself.
//!
//! The filter turns 16 rays per pixel into ~256 only where its window is whole. Where a
//! silhouette, a crease, a sharp shadow edge or the image border cuts it, the filter keeps
//! a smaller, noisier or more biased average, and those pixels hold most of its error
//! against exact visibility (`penumbra quality`, README "Quality"). A pixel is refined when
//! its window is cut ([`paired_taps`] is not [`FULL_WINDOW`]) and its unfiltered
//! visibility is not the same all around it (the centre is partly lit, or a neighbour with
//! geometry has another visibility): a cut window in a uniformly lit or shadowed region
//! needs no more rays. The refined value replaces the filtered one:
//! `irradiance · (256 − blocked) / 256` over the whole interleaved pattern — the pixel's
//! own 16 rays (its shadow mask) and the other 240 traced alone.

use glam::{Vec3, Vec4};

use crate::bvh::Bvh;
use crate::filter::{FULL_WINDOW, FilterParams, paired_taps};
use crate::layout::{GBufferTexel, ShadeParams, ShadowParams};
use crate::reference::shade::unshadowed_irradiance;
use crate::reference::shadow::{MASK_FULL, ray_blocked};
use crate::sampling::{SAMPLES, SAMPLES_PER_SET, SETS, pixel_set};

/// Whether pixel `(x, y)` is refined (the filter's inputs as for
/// [`crate::filter::filter_pixel`]): it has geometry, the filter's window around it is
/// cut, and its unfiltered visibility is not the same all around it.
pub fn needs_refinement(
    params: &FilterParams,
    values: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    x: u32,
    y: u32,
) -> bool {
    let width = params.width as usize;
    let c = y as usize * width + x as usize;
    depth[c] > 0.0
        && paired_taps(params, values, depth, normal, x, y) != FULL_WINDOW
        && visibility_varies(params, values, depth, x, y)
}

/// The centre is neither fully lit nor in umbra, or a neighbour of its window with
/// geometry has another unfiltered visibility.
fn visibility_varies(params: &FilterParams, values: &[[f32; 4]], depth: &[f32], x: u32, y: u32) -> bool {
    let width = params.width as usize;
    let v_c = values[y as usize * width + x as usize][3];
    if v_c > 0.0 && v_c < 1.0 {
        return true;
    }
    let (x, y) = (x as i32, y as i32);
    (-2..=2)
        .flat_map(|dy| (-2..=2).map(move |dx| (x + dx, y + dy)))
        .filter(|&(nx, ny)| nx >= 0 && ny >= 0 && nx < params.width as i32 && ny < params.height as i32)
        .map(|(nx, ny)| ny as usize * width + nx as usize)
        .any(|ix| depth[ix] > 0.0 && values[ix][3] != v_c)
}

/// The refined `(irradiance rgb, visibility)` of pixel `(x, y)`: its own set's rays
/// from `mask` (bit j = ray j blocked) and the other 15 sets' rays traced alone, over
/// all 256 `light_points` (set order, [`crate::sampling::light_points`]).
#[allow(clippy::too_many_arguments)] // the kernel's inputs, one each
pub fn refined_value(
    bvh: &Bvh,
    texel: &GBufferTexel,
    mask: u32,
    x: u32,
    y: u32,
    light_points: &[Vec3],
    shadow: &ShadowParams,
    shade: &ShadeParams,
) -> Vec4 {
    let own = pixel_set(x, y);
    let others = (1..SETS).flat_map(|k| {
        let set = (own + k) % SETS;
        light_points[set * SAMPLES_PER_SET..(set + 1) * SAMPLES_PER_SET].iter()
    });
    let blocked = (mask & MASK_FULL).count_ones() as usize
        + others.filter(|&&p| ray_blocked(bvh, texel, p, shadow)).count();
    let visibility = (SAMPLES - blocked) as f32 / SAMPLES as f32;
    (unshadowed_irradiance(shade, texel) * visibility).extend(visibility)
}

/// The refinement of a whole filtered image: every pixel [`needs_refinement`] picks gets its
/// [`refined_value`] in `filtered`. `gbuffer`, `masks`, `values` (the filter's input) and
/// `filtered` as the frame's passes left them, row-major; depth and normal are the
/// G-buffer's, as the shade pass passes them on. Returns which pixels were refined.
#[allow(clippy::too_many_arguments)] // the two kernels' inputs
pub fn refine_image(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    masks: &[u32],
    values: &[[f32; 4]],
    filter: &FilterParams,
    light_points: &[Vec3],
    shadow: &ShadowParams,
    shade: &ShadeParams,
    filtered: &mut [[f32; 4]],
) -> Vec<bool> {
    let depth: Vec<f32> = gbuffer.iter().map(|t| t.depth).collect();
    let normal: Vec<[f32; 3]> = gbuffer.iter().map(|t| t.normal.to_array()).collect();
    let mut refined = vec![false; gbuffer.len()];
    for y in 0..filter.height {
        for x in 0..filter.width {
            if needs_refinement(filter, values, &depth, &normal, x, y) {
                let p = (y * filter.width + x) as usize;
                let v = refined_value(bvh, &gbuffer[p], masks[p], x, y, light_points, shadow, shade);
                filtered[p] = v.to_array();
                refined[p] = true;
            }
        }
    }
    refined
}
