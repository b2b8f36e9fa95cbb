//! CPU twin of the refinement (`shaders/refine_select.wgsl`, `refine_gather.wgsl`,
//! `refine_resolve.wgsl`, with the frame's shadow tracer between the last two): where the
//! discontinuity filter cannot average the 16 sample sets of its window, the pixel traces
//! all 256 light samples itself.
//!
//! The filter turns 16 rays per pixel into ~256 only where its window is whole. Where a
//! silhouette, a crease, a sharp shadow edge or the image border cuts it, the filter keeps
//! a smaller, noisier or more biased average, and those pixels hold most of its error
//! against exact visibility (`penumbra quality`, README "Quality"). And where a pixel's 16
//! rays agree (lit or in umbra) next to a neighbour whose rays do not, the window blurs
//! the penumbra's edge into it. A pixel is refined when its unfiltered visibility is not
//! the same all around it (the centre is partly lit, or a neighbour with geometry has
//! another visibility) and either its window is cut ([`paired_taps`] is not
//! [`FULL_WINDOW`], with the visibility test at [`REFINE_VISIBILITY_TOLERANCE`], one ray,
//! instead of the filter's two) or its own rays agree. Uniformly lit or shadowed regions
//! need no more rays, and inside an open penumbra whose neighbours differ by at most one
//! ray a whole window averages all 16 sets. Measured with `penumbra quality --size
//! 512x512` (RMSE against exact, rays per pixel): refining cut windows only gave
//! playground 0.00299 (55.5 rays), Sponza atrium 0.0022 (53.2), bunny 0.0030 (47.1);
//! adding the pixels whose rays agree, 0.00259 (62.2), 0.00193 (58.0), 0.00270 (54.0);
//! with the one-ray tolerance too, bunny 0.00197 (58.4) and duck 0.00217 (64.4, was
//! 0.0030 with 54.2). The refined value replaces the filtered one:
//! `irradiance · (256 − blocked) / 256` over the whole interleaved pattern. (The GPU
//! traces all 16 sets, its own again, as one 4×4 tile of a sample image; the twin takes
//! the own set's rays from the frame's mask, which is the same.)
//!
//! Two knobs trade the refinement's rays for its error ([`refined_pixels`],
//! [`refined_value`]): a ray budget keeps only the listed pixels with the highest
//! [`refine_score`] that fit it, and a refined pixel may trace only sets `0..sets` (1, 2, 4
//! or 8 of the 16), `16 · sets` rays of its own instead of 256.

use glam::{Vec3, Vec4};

use crate::bvh::Bvh;
use crate::contract::filter::FULL_WINDOW;
use crate::contract::filter::FilterParams;
use crate::contract::layout::MASK_FULL;
use crate::contract::layout::{GBufferTexel, RefineParams, ShadeParams, ShadowParams};
use crate::reference::filter::{depths_and_normals, paired_taps, tap_weight};
use crate::reference::shade::unshadowed_irradiance;
use crate::reference::shadow_per_ray::per_ray_mask;
use crate::sampling::{SAMPLES_PER_SET, pixel_set};

pub use crate::contract::refine::{
    REFINE_VISIBILITY_TOLERANCE, budget_pixels, pixels_per_tile, selection_params, within_budget,
};

/// Whether pixel `(x, y)` is refined (the filter's inputs as for
/// [`crate::reference::filter::filter_pixel`]): it has geometry, its unfiltered visibility is not the
/// same all around it, and its window (with the filter's geometry tolerances from `params`
/// and [`REFINE_VISIBILITY_TOLERANCE`]) is cut or its own 16 rays agree.
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
    let v_c = values[c][3];
    let selection = selection_params(params);
    depth[c] > 0.0
        && visibility_varies(params, values, depth, x, y)
        && (v_c == 0.0 || v_c == 1.0 || paired_taps(&selection, values, depth, normal, x, y) != FULL_WINDOW)
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

/// The refined `(irradiance rgb, visibility)` of pixel `(x, y)` from the sample sets
/// `sets` (16 sets, `0..16`: all 256 `light_points`, set order,
/// [`crate::sampling::light_points`]): its own set's rays from `mask` (bit j = ray j
/// blocked) if it is one of them, the others traced alone. The oracle for the GPU's gather, trace and resolve together: the shadow tracers'
/// masks are the per-ray oracle's, so a sample image's masks count the same rays.
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
    sets: std::ops::Range<usize>,
) -> Vec4 {
    let own = pixel_set(x, y);
    let tile: Vec<u32> = sets
        .map(|set| {
            if set == own {
                mask
            } else {
                per_ray_mask(bvh, texel, set, light_points, shadow)
            }
        })
        .collect();
    resolve(texel, &tile, shade)
}

/// The score `refine_select` gives a listed pixel, the expected error of its filtered
/// visibility (the filter's inputs and `params` as for [`needs_refinement`], `filtered` the
/// filter's output): the standard error of the weighted mean over its window's
/// [`paired_taps`] at the refinement's visibility tolerance, each tap (weight w, unfiltered
/// visibility u) a binomial estimate from 16 rays (variance u(1 − u)/16), so
/// √(Σ w²·u(1 − u)/16) / Σ w; plus, where the pixel's own 16 rays agree (u is 0 or 1), how
/// far the window pulled it from them, |filtered − u| (the blur of a penumbra's edge).
///
/// Chosen at 512² against exact visibility (the frames of `penumbra quality`, README
/// "Quality"), refining all 16 sets within a budget of 24 rays per pixel, RMSE: this score
/// gave playground 0.0054 and 2CylinderEngine 0.0024; the standard error alone 0.0053
/// and 0.0026; |filtered − mean unfiltered of the 3×3 pixels| 0.0075 and 0.0050; the
/// spread, standard deviation or |filtered − mean| of the unfiltered 5×5 window 0.0083–0.0090
/// on the playground.
/// Summed in the kernel's order (taps k = 0..25).
pub fn refine_score(
    params: &FilterParams,
    values: &[[f32; 4]],
    filtered: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    x: u32,
    y: u32,
) -> f32 {
    let width = params.width as usize;
    let taps = paired_taps(&selection_params(params), values, depth, normal, x, y);
    let (mut weight, mut variance) = (0.0f32, 0.0f32);
    for k in (0..25i32).filter(|k| taps & (1 << k) != 0) {
        let (dy, dx) = (k / 5 - 2, k % 5 - 2);
        let u = values[(y as i32 + dy) as usize * width + (x as i32 + dx) as usize][3];
        let w = tap_weight(k as u32);
        weight += w;
        variance += w * w * (u * (1.0 - u) / 16.0);
    }
    let c = y as usize * width + x as usize;
    let v_c = values[c][3];
    let mut score = variance.sqrt() / weight;
    if v_c == 0.0 || v_c == 1.0 {
        score += (filtered[c][3] - v_c).abs();
    }
    score
}

/// The pixels the refinement traces (row-major indices, sorted): those [`needs_refinement`]
/// picks, and with a ray budget (average rays per pixel with geometry, the frame's 16
/// included) only the [`crate::contract::refine::budget_pixels`] of them with the highest
/// [`refine_score`], each refined pixel costing `16 · sets` rays. `filtered` is the
/// filter's output, before the refinement.
pub fn refined_pixels(
    params: &FilterParams,
    values: &[[f32; 4]],
    filtered: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    budget: Option<f32>,
    sets: u32,
) -> Vec<u32> {
    let mut listed = Vec::new();
    let mut geometry = 0;
    for y in 0..params.height {
        for x in 0..params.width {
            let p = y * params.width + x;
            geometry += u32::from(depth[p as usize] > 0.0);
            if needs_refinement(params, values, depth, normal, x, y) {
                listed.push((p, refine_score(params, values, filtered, depth, normal, x, y)));
            }
        }
    }
    match budget {
        Some(budget) => within_budget(&listed, budget_pixels(budget, geometry, sets)),
        None => listed.into_iter().map(|(p, _)| p).collect(),
    }
}

/// The refinement of a whole filtered image: every pixel [`refined_pixels`] picks gets its
/// [`refined_value`] in `filtered`. `gbuffer`, `masks`, `values` (the filter's input) and
/// `filtered` as the frame's passes left them, row-major; depth and normal are the
/// G-buffer's, as the shade pass passes them on; `budget` and `sets` as for
/// [`refined_pixels`] and [`refined_value`]. Returns which pixels were refined.
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
    budget: Option<f32>,
    sets: u32,
    filtered: &mut [[f32; 4]],
) -> Vec<bool> {
    let (depth, normal) = depths_and_normals(gbuffer);
    let mut refined = vec![false; gbuffer.len()];
    let per_tile = pixels_per_tile(sets) as usize;
    let pixels = refined_pixels(filter, values, filtered, &depth, &normal, budget, sets);
    for (i, p) in pixels.into_iter().enumerate() {
        let (x, y) = (p % filter.width, p / filter.width);
        let p = p as usize;
        // The i-th pixel of the list traces block i mod (16 / sets) of its tile.
        let first = (i % per_tile) * sets as usize;
        let block = first..first + sets as usize;
        let v = refined_value(
            bvh,
            &gbuffer[p],
            masks[p],
            x,
            y,
            light_points,
            shadow,
            shade,
            block,
        );
        filtered[p] = v.to_array();
        refined[p] = true;
    }
    refined
}

/// The sample image `refine_gather` builds for `params` (row-major,
/// [`RefineParams::image_size`]; tiles `tiles_x` per row, row-major): tile pixel `t`
/// (which traces set `t`) of tile `s` is a copy of `gbuffer[list[first_slot + e]]` for slot
/// `e = s · (16 / sets) + t / sets`, sky (no hit) past the last slot.
pub fn sample_image(gbuffer: &[GBufferTexel], list: &[u32], params: &RefineParams) -> Vec<GBufferTexel> {
    let (w, h) = params.image_size();
    let sky = GBufferTexel {
        triangle: u32::MAX,
        ..GBufferTexel::default()
    };
    let per_tile = params.pixels_per_tile();
    (0..h)
        .flat_map(|y| (0..w).map(move |x| ((y / 4) * params.tiles_x + x / 4, pixel_set(x, y) as u32)))
        .map(|(tile, set)| tile * per_tile + set / params.sets)
        .map(|slot| {
            if slot < params.slots {
                gbuffer[list[(params.first_slot + slot) as usize] as usize]
            } else {
                sky
            }
        })
        .collect()
}

/// What `refine_resolve` writes for a pixel with G-buffer `texel` whose sample-image tile
/// traced the masks `tile` (sets `0..tile.len()`, 16 rays each): the irradiance times the
/// fraction of those rays that reach the light, and that fraction.
pub fn resolve(texel: &GBufferTexel, tile: &[u32], shade: &ShadeParams) -> Vec4 {
    let blocked: u32 = tile.iter().map(|m| (m & MASK_FULL).count_ones()).sum();
    let rays = (SAMPLES_PER_SET * tile.len()) as u32;
    let visibility = (rays - blocked) as f32 / rays as f32;
    (unshadowed_irradiance(shade, texel) * visibility).extend(visibility)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The filter's inputs: params, values, depth, normal.
    type Image = (FilterParams, Vec<[f32; 4]>, Vec<f32>, Vec<[f32; 3]>);

    /// A flat `w × h` image facing the camera, unfiltered visibility `v(x, y)`.
    fn image(w: u32, h: u32, v: impl Fn(u32, u32) -> f32) -> Image {
        let values = (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| [0.0, 0.0, 0.0, v(x, y)]);
        let n = (w * h) as usize;
        (
            FilterParams::new(w, h),
            values.collect(),
            vec![2.0; n],
            vec![[0.0, 0.0, 1.0]; n],
        )
    }

    #[test]
    fn refines_where_the_window_is_cut_and_visibility_changes() {
        // A sharp shadow edge at x = 6: the visibility test cuts the windows beside it.
        let (p, values, depth, normal) = image(12, 12, |x, _| if x < 6 { 0.0 } else { 1.0 });
        let refined = |x, y| needs_refinement(&p, &values, &depth, &normal, x, y);
        assert!(refined(5, 6) && refined(6, 6) && refined(4, 6) && refined(7, 6));
        // Two pixels from the edge the window is whole (it reaches x + 2 only).
        assert!(!refined(3, 6) && !refined(8, 6));
        // At the image border the window is cut, but nothing changes there.
        assert!(!refined(0, 6) && !refined(11, 0));

        // Uniform penumbra (0.5 everywhere): whole windows inside, cut windows at the
        // border, where the pixel is partly lit: refined.
        let (p, values, depth, normal) = image(12, 12, |_, _| 0.5);
        assert!(!needs_refinement(&p, &values, &depth, &normal, 6, 6));
        assert!(needs_refinement(&p, &values, &depth, &normal, 0, 6));

        // The fringe of a penumbra: a lit pixel beside one with a blocked ray is
        // refined (whole window: 1/16 is within the visibility tolerance); the
        // partly lit pixel, whose window is whole, is not.
        let (p, values, depth, normal) =
            image(12, 12, |x, y| if (x, y) == (6, 6) { 15.0 / 16.0 } else { 1.0 });
        assert_eq!(paired_taps(&p, &values, &depth, &normal, 5, 6), FULL_WINDOW);
        assert!(needs_refinement(&p, &values, &depth, &normal, 5, 6));
        assert!(!needs_refinement(&p, &values, &depth, &normal, 6, 6));
        assert!(!needs_refinement(&p, &values, &depth, &normal, 3, 6));

        // Inside a penumbra, a neighbour two rays away: the filter averages it, the
        // refinement's one-ray tolerance cuts the window there.
        let (p, values, depth, normal) = image(12, 12, |x, _| if x < 6 { 0.5 } else { 0.625 });
        assert_eq!(paired_taps(&p, &values, &depth, &normal, 5, 6), FULL_WINDOW);
        assert!(needs_refinement(&p, &values, &depth, &normal, 5, 6));
        assert!(!needs_refinement(&p, &values, &depth, &normal, 2, 6));

        // A pixel without geometry is never refined; a silhouette cuts the window.
        let (p, values, mut depth, normal) = image(12, 12, |x, _| if x < 6 { 0.25 } else { 0.5 });
        depth[6 * 12 + 3] = 0.0;
        assert!(!needs_refinement(&p, &values, &depth, &normal, 3, 6));
        assert!(needs_refinement(&p, &values, &depth, &normal, 2, 6));
    }

    #[test]
    fn sample_image_tiles_hold_copies_of_the_listed_texels() {
        let texel = |i: u32| GBufferTexel {
            origin: Vec3::splat(i as f32),
            depth: 1.0,
            triangle: i,
            ..GBufferTexel::default()
        };
        let gbuffer: Vec<GBufferTexel> = (0..10).map(texel).collect();
        let list = [7, 2, 9, 4, 0];
        let params = RefineParams {
            tiles_x: 2,
            first_slot: 1,
            slots: 3,
            sets: 16,
        };
        assert_eq!(params.image_size(), (8, 8));
        let image = sample_image(&gbuffer, &list, &params);
        for y in 0..8 {
            for x in 0..8 {
                let slot = (y / 4) * 2 + x / 4;
                let t = image[(y * 8 + x) as usize];
                match slot {
                    0 => assert_eq!(t.triangle, 2),
                    1 => assert_eq!(t.triangle, 9),
                    2 => assert_eq!(t.triangle, 4),
                    _ => assert!(!t.is_hit(), "({x}, {y}) past the last slot is sky"),
                }
            }
        }
        // Four sets: each row of a tile (sets 4r .. 4r + 4) holds a listed pixel, so the
        // first tile holds the three slots and the rest is sky.
        let params = RefineParams { sets: 4, ..params };
        assert_eq!(params.image_size(), (8, 4));
        let image = sample_image(&gbuffer, &list, &params);
        for y in 0..4 {
            for x in 0..8 {
                let t = image[(y * 8 + x) as usize];
                match (x / 4, y) {
                    (0, 0) => assert_eq!(t.triangle, 2),
                    (0, 1) => assert_eq!(t.triangle, 9),
                    (0, 2) => assert_eq!(t.triangle, 4),
                    _ => assert!(!t.is_hit(), "({x}, {y}) past the last slot is sky"),
                }
            }
        }
    }

    #[test]
    fn resolve_counts_the_traced_rays() {
        let shade = ShadeParams {
            light_center: Vec3::new(0.0, 10.0, 0.0),
            light_area: 1.0,
            light_normal: Vec3::NEG_Y,
            width: 1,
            radiance: Vec3::ONE,
            height: 1,
        };
        let texel = GBufferTexel {
            normal: Vec3::Y,
            depth: 1.0,
            ..GBufferTexel::default()
        };
        let mut tile = [0u32; 16];
        tile[0] = 0xffff;
        tile[3] = 0b1011 | (1 << 16); // bits above the 16 rays do not count
        let v = resolve(&texel, &tile, &shade);
        assert_eq!(v.w, (256.0 - 19.0) / 256.0);
        // Four sets traced: 64 rays.
        assert_eq!(resolve(&texel, &tile[..4], &shade).w, (64.0 - 19.0) / 64.0);
        let lit = unshadowed_irradiance(&shade, &texel);
        assert_eq!(v.truncate(), lit * v.w);
        assert!(
            (lit.x - 0.01).abs() < 1e-6,
            "area 1 at distance 10, both cosines 1: {lit}"
        );
    }
}
