//! The 4×4 discontinuity filter, CPU twin of `shaders/filter.wgsl` (its uniform and
//! constants: [`crate::contract::filter`]). One concept: the twin and, below it, its tests.
//!
//! Pixel `(x, y)` traced the 16 shadow rays of sample set
//! `(x mod 4) + 4·(y mod 4)`, so any 4×4 window holds all 16 sets — 256 light
//! samples. Averaging a window turns 16 rays per pixel into an estimate close
//! to 256, as long as the neighbours see the same light: the filter takes only
//! those whose depth and normal are close to the centre's, so shadows do not
//! bleed across silhouettes and creases.
//!
//! The window is the 4-pixel box centred on the pixel: taps `x−2 ..= x+2`,
//! `y−2 ..= y+2`, the outer ring at half weight (corners a quarter), clipped to
//! the image. Each of the 16 sets then weighs 1 in a full window, and a linear
//! change of visibility across it averages to the centre's value; the plain
//! 4×4 window `x−1 ..= x+2` is half a pixel off centre, and measured 3–6 %
//! higher RMSE against exact visibility (`penumbra quality`, 256², playground
//! 0.0144 → 0.0136, lattice 0.0339 → 0.0330).
//!
//! Where a silhouette, a crease, a sharp shadow edge or the image border cuts
//! the window, the filter uses a tap only if its mirror image through the
//! centre is used too: the taps left stay symmetric about the pixel, so their
//! mean is not pulled towards the side that is left (a one-sided window over a
//! gradient is biased by up to a pixel's worth of it, and at a contact shadow
//! by far more). It averages fewer rays there, but the bias it removes was the
//! larger error (`penumbra quality --size 512x512`, filtered RMSE against exact
//! visibility, without / with the rule: playground 0.0098 / 0.0093, lattice
//! 0.0253 / 0.0263, Sponza atrium 0.0084 / 0.0055, Sponza columns 0.0076 /
//! 0.0059, Cornell box 0.0046 / 0.0035, bunny 0.0111 / 0.0096, duck 0.0082 /
//! 0.0065, engine 0.0071 / 0.0051). [`filter_pixel`] is written the
//! way the WGSL kernel is — one output pixel from its neighbours, the centre and then
//! the taps in mirror pairs, sums in `f32` in that order (the weights are powers
//! of two, so every product is exact) — so that the GPU's result matches it to rounding
//! (within 1e-6 for values of order 1). Accept/reject decisions compare floats
//! against the tolerances; inputs that sit within rounding of a threshold may
//! be decided differently on a GPU (which may fuse multiply-adds), so tests
//! keep their inputs away from the thresholds.

use crate::contract::filter::FilterParams;
use crate::contract::layout::GBufferTexel;

/// Filters a whole image: [`filter_pixel`] for every pixel, row-major, top row first.
///
/// Per pixel, row-major: `values` = (r, g, b) irradiance and a = visibility
/// (filtered together), `depth` = distance to the camera, 0 (or less) for
/// "no hit", `normal` = unit shading normal.
///
/// # Panics
///
/// If a slice's length is not `params.width · params.height` (a caller bug).
pub fn discontinuity_filter(
    params: &FilterParams,
    values: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
) -> Vec<[f32; 4]> {
    let n = params.pixel_count();
    assert!(
        values.len() == n && depth.len() == n && normal.len() == n,
        "discontinuity_filter: {}×{} image needs {n} values, depths and normals, got {}, {}, {}",
        params.width,
        params.height,
        values.len(),
        depth.len(),
        normal.len()
    );
    let mut filtered = Vec::with_capacity(n);
    for y in 0..params.height {
        for x in 0..params.width {
            filtered.push(filter_pixel(params, values, depth, normal, x, y));
        }
    }
    filtered
}

/// The filtered value of pixel `(x, y)`: the weighted mean of `values` over the
/// pixels of the centred window `x−2 ..= x+2`, `y−2 ..= y+2` (outer ring at
/// half weight, corners a quarter) whose depth, normal and unfiltered
/// visibility are close to the centre's (see [`FilterParams`]) and whose
/// mirror image through `(x, y)` is inside the image and close too.
///
/// Neighbours with no hit (depth ≤ 0) are never used. A centre with no hit is
/// returned unchanged. The centre always counts itself, whatever the
/// tolerances, so the mean is never of nothing.
///
/// The GPU kernel computes exactly this, in the same order (the normal buffer
/// there holds the depth too: [`normals_for_gpu`]).
///
/// # Panics
///
/// If `(x, y)` is outside the image or a slice is shorter than the image (a caller bug).
pub fn filter_pixel(
    params: &FilterParams,
    values: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    x: u32,
    y: u32,
) -> [f32; 4] {
    assert!(
        x < params.width && y < params.height,
        "filter_pixel: ({x}, {y}) outside the {}×{} image",
        params.width,
        params.height
    );
    let width = params.width as usize;
    let c_ix = y as usize * width + x as usize;
    let d_c = depth[c_ix];
    if d_c <= 0.0 {
        return values[c_ix];
    }
    let v_c = values[c_ix];
    let similar = |ix: usize| similar_tap(params, values, depth, normal, c_ix, ix);
    // The window is the 4-pixel box centred on the pixel: 5×5 taps, the outer
    // ring at half weight (see the kernel). Its taps go in mirror pairs through the
    // centre, tap k = (dy + 2)·5 + (dx + 2) with tap 24 − k for k < 12, and a pair
    // counts when both taps are inside and similar — the taps of [`paired_taps`]. The
    // sum, as the kernel's: the centre, then pair by pair, k increasing; component
    // by component, as its vec4 arithmetic. i32 like the kernel.
    let mut sum = v_c;
    let mut weight_sum = 1.0f32;
    for k in 0i32..12 {
        let (dy, dx) = (k / 5 - 2, k % 5 - 2);
        let (ax, ay) = (x as i32 + dx, y as i32 + dy);
        let (bx, by) = (x as i32 - dx, y as i32 - dy);
        let inside =
            |px: i32, py: i32| px >= 0 && py >= 0 && px < params.width as i32 && py < params.height as i32;
        if !(inside(ax, ay) && inside(bx, by)) {
            continue;
        }
        let a = ay as usize * width + ax as usize;
        let b = by as usize * width + bx as usize;
        if !(similar(a) && similar(b)) {
            continue;
        }
        let w = tap_weight(k as u32);
        for v in [values[a], values[b]] {
            sum[0] += v[0] * w;
            sum[1] += v[1] * w;
            sum[2] += v[2] * w;
            sum[3] += v[3] * w;
        }
        weight_sum += 2.0 * w;
    }
    let n = weight_sum;
    [sum[0] / n, sum[1] / n, sum[2] / n, sum[3] / n]
}

/// The weight of tap `k` of the window (bit `(dy + 2)·5 + (dx + 2)`): 1, on the outer ring
/// (|dx| or |dy| = 2) a half, on its corners a quarter, so that in a full window each of
/// the 16 sample sets weighs 1. Powers of two: a weight times a value is exact.
pub fn tap_weight(k: u32) -> f32 {
    let ring = |d: u32| if d == 0 || d == 4 { 0.5 } else { 1.0 };
    ring(k / 5) * ring(k % 5)
}

/// The G-buffer's depths and shading normals, row-major, as the twin's slices.
pub fn depths_and_normals(gbuffer: &[GBufferTexel]) -> (Vec<f32>, Vec<[f32; 3]>) {
    (
        gbuffer.iter().map(|t| t.depth).collect(),
        gbuffer.iter().map(|t| t.normal.to_array()).collect(),
    )
}

/// The taps of `(x, y)`'s window that [`filter_pixel`] averages, one bit each
/// (`(dy + 2)·5 + (dx + 2)`): inside the image, at a similar depth, normal and
/// unfiltered visibility, and with their mirror image through the centre too;
/// the centre always. [`FULL_WINDOW`](crate::contract::filter::FULL_WINDOW) when nothing cuts
/// the window. The centre
/// must have a hit. WGSL twin: `paired_taps` in `shaders/shared/filter_window.wgsl`.
///
/// # Panics
///
/// If `(x, y)` is outside the image or a slice is shorter than the image (a caller bug).
pub fn paired_taps(
    params: &FilterParams,
    values: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    x: u32,
    y: u32,
) -> u32 {
    let width = params.width as usize;
    let c_ix = y as usize * width + x as usize;
    // First the taps the centre accepts, one bit each: bit (dy + 2)·5 + (dx + 2).
    let mut accepted = 0u32;
    for dy in -2i32..=2 {
        let ny = y as i32 + dy;
        if ny < 0 || ny >= params.height as i32 {
            continue;
        }
        for dx in -2i32..=2 {
            let nx = x as i32 + dx;
            if nx < 0 || nx >= params.width as i32 {
                continue;
            }
            let ix = ny as usize * width + nx as usize;
            if (dx == 0 && dy == 0) || similar_tap(params, values, depth, normal, c_ix, ix) {
                accepted |= 1 << ((dy + 2) * 5 + dx + 2);
            }
        }
    }
    // Then the taps whose mirror image through the centre is accepted too
    // (bit k's mirror is bit 24 − k; reversing 32 bits moves k to 31 − k).
    accepted & (accepted.reverse_bits() >> 7)
}

/// Whether tap `ix` may be averaged with the centre `c_ix`: on the same surface
/// ([`same_surface`]) and with a similar unfiltered visibility (`values[..][3]`).
/// WGSL twin: `similar_tap` in `shaders/shared/filter_window.wgsl`.
fn similar_tap(
    params: &FilterParams,
    values: &[[f32; 4]],
    depth: &[f32],
    normal: &[[f32; 3]],
    c_ix: usize,
    ix: usize,
) -> bool {
    same_surface(params, depth[c_ix], normal[c_ix], depth[ix], normal[ix])
        && (values[ix][3] - values[c_ix][3]).abs() <= params.visibility_tolerance
}

/// The filter's geometry test: a neighbour with depth `d_n` and normal `n_n`
/// lies on the same surface as a centre with `d_c`, `n_c` when it has a hit,
/// its depth is within `depth_tolerance · d_c` and its normal within
/// `normal_tolerance` (a cosine) of the centre's (see [`FilterParams`]).
pub fn same_surface(params: &FilterParams, d_c: f32, n_c: [f32; 3], d_n: f32, n_n: [f32; 3]) -> bool {
    // Written out rather than glam's dot to fix the order of the sum (the kernel's too).
    let cos_nc = n_n[0] * n_c[0] + n_n[1] * n_c[1] + n_n[2] * n_c[2];
    d_n > 0.0 && (d_n - d_c).abs() <= params.depth_tolerance * d_c && cos_nc >= params.normal_tolerance
}

/// The normals as the kernel's `normal` buffer wants them: `vec4<f32>` per
/// pixel (16-byte stride, WGSL's alignment for `array<vec3<f32>>` too) with the
/// pixel's depth in w, so that the kernel reads a tap's depth and normal in one load.
pub fn normals_for_gpu(normal: &[[f32; 3]], depth: &[f32]) -> Vec<[f32; 4]> {
    normal
        .iter()
        .zip(depth)
        .map(|(&[x, y, z], &d)| [x, y, z, d])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contract::filter::{FILTER_KERNEL, WORKGROUP_SIZE};
    use std::mem::offset_of;

    const UP: [f32; 3] = [0.0, 1.0, 0.0];

    /// A `width × height` image of one plane facing the camera at depth 2.
    struct Frame {
        params: FilterParams,
        values: Vec<[f32; 4]>,
        depth: Vec<f32>,
        normal: Vec<[f32; 3]>,
    }

    impl Frame {
        fn plane(width: u32, height: u32, value: impl Fn(u32, u32) -> [f32; 4]) -> Frame {
            // These tests are about depth, normals and borders: their values are not
            // visibilities, so the visibility test is off (it has its own test).
            let params = FilterParams {
                visibility_tolerance: f32::INFINITY,
                ..FilterParams::new(width, height)
            };
            let n = params.pixel_count();
            let values = (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| value(x, y));
            Frame {
                params,
                values: values.collect(),
                depth: vec![2.0; n],
                normal: vec![UP; n],
            }
        }

        fn ix(&self, x: u32, y: u32) -> usize {
            (y * self.params.width + x) as usize
        }

        fn filter(&self) -> Vec<[f32; 4]> {
            discontinuity_filter(&self.params, &self.values, &self.depth, &self.normal)
        }
    }

    /// The taps of `(x, y)`'s window whose pixel and mirror image through
    /// `(x, y)` both lie in the image and pass `usable`, with their weights (an
    /// independent statement of the footprint, not the kernel's loop).
    fn window_where(
        params: &FilterParams,
        x: u32,
        y: u32,
        usable: impl Fn(u32, u32) -> bool,
    ) -> Vec<((u32, u32), f32)> {
        let (w, h) = (params.width as i64, params.height as i64);
        let inside =
            |a: i64, b: i64| (0..w).contains(&a) && (0..h).contains(&b) && usable(a as u32, b as u32);
        let weight = |d: i64| if d.abs() == 2 { 0.5 } else { 1.0 };
        let (x, y) = (x as i64, y as i64);
        (-2..=2i64)
            .flat_map(|dy| (-2..=2i64).map(move |dx| (dx, dy)))
            .filter(|&(dx, dy)| inside(x + dx, y + dy) && inside(x - dx, y - dy))
            .map(|(dx, dy)| (((x + dx) as u32, (y + dy) as u32), weight(dx) * weight(dy)))
            .collect()
    }

    /// [`window_where`] with every pixel usable: only the image border cuts it.
    fn window(params: &FilterParams, x: u32, y: u32) -> Vec<((u32, u32), f32)> {
        window_where(params, x, y, |_, _| true)
    }

    /// The weighted mean of `values` over `taps`.
    fn weighted_mean(frame: &Frame, taps: &[((u32, u32), f32)]) -> [f32; 4] {
        let total: f32 = taps.iter().map(|t| t.1).sum();
        [0, 1, 2, 3].map(|k| {
            taps.iter()
                .map(|&((wx, wy), w)| frame.values[frame.ix(wx, wy)][k] * w)
                .sum::<f32>()
                / total
        })
    }

    fn close(a: [f32; 4], b: [f32; 4], tolerance: f32) -> bool {
        a.iter()
            .zip(&b)
            .all(|(p, q)| (p - q).abs() <= tolerance * q.abs().max(1.0))
    }

    /// The filter averages exactly the taps [`paired_taps`] names (its mirror-pair loop
    /// and the refinement's window test must agree): on a rugged 9×7 image with depth
    /// and normal edges, a tap's red channel set to 1 (all else 0; red is not tested)
    /// reaches the output of a pixel exactly when that pixel's `paired_taps` has the tap.
    #[test]
    fn the_filter_averages_the_paired_taps() {
        let (w, h) = (9u32, 7u32);
        let mut f = Frame::plane(w, h, |_, _| [0.0, 0.0, 0.0, 0.5]);
        for (i, (d, n)) in f.depth.iter_mut().zip(f.normal.iter_mut()).enumerate() {
            // A depth step, a crease, a hole and a visibility edge, none near a tolerance.
            let (x, y) = (i as u32 % w, i as u32 / w);
            *d = if x >= 6 { 4.0 } else { 2.0 };
            *n = if y >= 5 { [1.0, 0.0, 0.0] } else { UP };
            if (x, y) == (2, 2) {
                *d = 0.0;
            }
        }
        f.values[3 * w as usize + 4][3] = 1.0;
        f.params.visibility_tolerance = FilterParams::DEFAULT_VISIBILITY_TOLERANCE;
        let (mut used, mut cut) = (0, 0);
        for tap in 0..(w * h) as usize {
            let mut one = f.values.clone();
            one[tap][0] = 1.0;
            let out = discontinuity_filter(&f.params, &one, &f.depth, &f.normal);
            for y in 0..h {
                for x in 0..w {
                    let c = (y * w + x) as usize;
                    if f.depth[c] <= 0.0 {
                        continue;
                    }
                    let (dx, dy) = (tap as i32 % w as i32 - x as i32, tap as i32 / w as i32 - y as i32);
                    let paired = paired_taps(&f.params, &one, &f.depth, &f.normal, x, y);
                    let named =
                        dx.abs() <= 2 && dy.abs() <= 2 && paired & (1 << ((dy + 2) * 5 + dx + 2)) != 0;
                    assert_eq!(out[c][0] > 0.0, named, "tap {tap} at pixel ({x}, {y})");
                    let in_window = dx.abs() <= 2 && dy.abs() <= 2 && (dx, dy) != (0, 0);
                    used += usize::from(in_window && named);
                    cut += usize::from(in_window && !named);
                }
            }
        }
        // Not vacuous: both outcomes occur.
        assert!(used > 0 && cut > 0, "{used} taps used, {cut} cut");
    }

    #[test]
    fn params_defaults() {
        let p = FilterParams::new(640, 480);
        assert_eq!((p.width, p.height, p.pixel_count()), (640, 480, 640 * 480));
        assert_eq!(p.depth_tolerance, 0.05);
        assert_eq!(p.normal_tolerance, 0.9);
        assert_eq!(p.visibility_tolerance, 0.125);
        assert_eq!(bytemuck::bytes_of(&p).len(), 32);
    }

    #[test]
    fn a_visibility_edge_on_one_surface_stays_sharp() {
        // One plane, visibility 1 left of x = 4 and 0 from there on: noise-free
        // values that differ by more than the tolerance are not averaged.
        let mut f = Frame::plane(8, 4, |x, _| if x < 4 { [1.0; 4] } else { [0.0; 4] });
        f.params.visibility_tolerance = FilterParams::DEFAULT_VISIBILITY_TOLERANCE;
        let out = discontinuity_filter(&f.params, &f.values, &f.depth, &f.normal);
        assert_eq!(out, f.values, "the edge was blurred");
        // Within the tolerance (one ray of 16 apart), neighbours are averaged.
        let mut g = Frame::plane(8, 4, |x, _| [(x % 2) as f32 / 16.0; 4]);
        g.params.visibility_tolerance = FilterParams::DEFAULT_VISIBILITY_TOLERANCE;
        let out = discontinuity_filter(&g.params, &g.values, &g.depth, &g.normal);
        let mean = weighted_mean(&g, &window(&g.params, 1, 1));
        assert!((out[9][3] - mean[3]).abs() < 1e-6, "{:?} vs {mean:?}", out[9]);
        assert!(mean[3] > 0.0 && mean[3] < 1.0 / 16.0);
    }

    #[test]
    fn a_ramp_beside_a_silhouette_keeps_its_value() {
        // A surface at depth 1 whose visibility rises linearly in x and y, next
        // to one at depth 2 (rejected) from x = 6 on. Every used tap has its
        // mirror image used too, so each pixel's mean is its own ramp value,
        // also where the silhouette or the image border cuts the window; a
        // one-sided mean would be pulled towards the inside.
        let ramp = |x: u32, y: u32| 0.25 + 0.02 * x as f32 + 0.01 * y as f32;
        let mut f = Frame::plane(10, 7, |x, y| [ramp(x, y); 4]);
        f.params.visibility_tolerance = FilterParams::DEFAULT_VISIBILITY_TOLERANCE;
        for y in 0..7 {
            for x in 6..10 {
                let ix = f.ix(x, y);
                f.depth[ix] = 2.0;
                f.values[ix] = [0.0; 4];
            }
        }
        let out = f.filter();
        for y in 0..7 {
            for x in 0..6 {
                let got = out[f.ix(x, y)][3];
                assert!(
                    (got - ramp(x, y)).abs() < 1e-6,
                    "({x},{y}): {got} vs {}",
                    ramp(x, y)
                );
            }
        }
        // The pixel beside the silhouette averages only its own column (the
        // mirrors of x = 6, 7 are rejected with them); one column further in,
        // x − 1 ..= x + 1 (weight 3 × 4 of the full 16).
        let column = window_where(&f.params, 5, 3, |a, _| a < 6);
        assert!(column.iter().all(|t| t.0.0 == 5) && column.len() == 5);
        let used: f32 = window_where(&f.params, 4, 3, |a, _| a < 6)
            .iter()
            .map(|t| t.1)
            .sum();
        assert_eq!(used, 12.0);
    }

    #[test]
    fn constant_image_stays_constant() {
        let c = [0.3, 1.7, 0.01, 0.625];
        let frame = Frame::plane(9, 6, |_, _| c);
        for (i, out) in frame.filter().into_iter().enumerate() {
            assert!(close(out, c, 1e-6), "pixel {i}: {out:?}");
        }
    }

    #[test]
    fn single_bright_pixel_spreads_over_its_window_footprint() {
        for (bx, by) in [(3, 4), (0, 0), (7, 6)] {
            let frame = Frame::plane(8, 7, |x, y| {
                if (x, y) == (bx, by) {
                    [16.0, 32.0, 8.0, 1.0]
                } else {
                    [0.0; 4]
                }
            });
            let out = frame.filter();
            for y in 0..7 {
                for x in 0..8 {
                    let win = window(&frame.params, x, y);
                    let got = out[frame.ix(x, y)];
                    // (x, y) sees the bright pixel iff bx ∈ [x−2, x+2], by ∈ [y−2, y+2]
                    // and its mirror image (2x − bx, 2y − by) lies in the image.
                    let sees = (x as i32 - 2..=x as i32 + 2).contains(&(bx as i32))
                        && (y as i32 - 2..=y as i32 + 2).contains(&(by as i32))
                        && (0..8).contains(&(2 * x as i32 - bx as i32))
                        && (0..7).contains(&(2 * y as i32 - by as i32));
                    let tap = win.iter().find(|t| t.0 == (bx, by));
                    assert_eq!(sees, tap.is_some());
                    let total: f32 = win.iter().map(|t| t.1).sum();
                    let w = tap.map_or(0.0, |t| t.1 / total);
                    let expected = [16.0 * w, 32.0 * w, 8.0 * w, w];
                    assert!(
                        close(got, expected, 1e-6),
                        "bright ({bx},{by}), pixel ({x},{y}): {got:?}"
                    );
                }
            }
        }
        // In the interior a full window weighs 16: footprint x, y ∈ [2, 6],
        // 16 × (1, ½ on the outer ring, ¼ in its corners) / 16.
        let frame = Frame::plane(9, 9, |x, y| if (x, y) == (4, 4) { [16.0; 4] } else { [0.0; 4] });
        let out = frame.filter();
        let lit: Vec<(u32, u32)> = (0..9u32)
            .flat_map(|y| (0..9u32).map(move |x| (x, y)))
            .filter(|&(x, y)| out[frame.ix(x, y)] != [0.0; 4])
            .collect();
        let footprint: Vec<(u32, u32)> = (2..=6).flat_map(|y| (2..=6).map(move |x| (x, y))).collect();
        assert_eq!(lit, footprint);
        for &(x, y) in &footprint {
            let w = |a: u32, b: u32| if a.abs_diff(b) == 2 { 0.5 } else { 1.0 };
            assert_eq!(out[frame.ix(x, y)], [w(x, 4) * w(y, 4); 4], "({x},{y})");
        }
    }

    #[test]
    fn depth_discontinuity_does_not_bleed() {
        // Left half at depth 1 in shadow, right half at depth 1.5 lit: both face the camera.
        let mut frame = Frame::plane(10, 6, |x, _| if x < 5 { [0.0; 4] } else { [1.0; 4] });
        for y in 0..6 {
            for x in 0..10 {
                let ix = frame.ix(x, y);
                frame.depth[ix] = if x < 5 { 1.0 } else { 1.5 };
            }
        }
        let out = frame.filter();
        for (i, v) in out.iter().enumerate() {
            assert_eq!(*v, frame.values[i], "pixel {i}");
        }
        // Within the tolerance (4 % < 5 %) the same step is smoothed.
        for y in 0..6 {
            for x in 5..10 {
                let ix = frame.ix(x, y);
                frame.depth[ix] = 1.04;
            }
        }
        let out = frame.filter();
        let (edge, inside) = (out[frame.ix(4, 2)], out[frame.ix(1, 2)]);
        assert!(edge[0] > 0.0 && edge[0] < 1.0, "{edge:?}");
        assert_eq!(inside, [0.0; 4]);
    }

    #[test]
    fn normal_discontinuity_does_not_bleed() {
        // A crease at one depth: floor (up) on the left, wall (facing +x) on the right.
        let mut frame = Frame::plane(10, 6, |x, _| if x < 5 { [0.25; 4] } else { [0.75; 4] });
        for y in 0..6 {
            for x in 5..10 {
                let ix = frame.ix(x, y);
                frame.normal[ix] = [1.0, 0.0, 0.0];
            }
        }
        let out = frame.filter();
        for (i, v) in out.iter().enumerate() {
            assert_eq!(*v, frame.values[i], "pixel {i}");
        }
        // A gentle bend (cos 0.95 > 0.9) is smoothed.
        let bent = [0.0, 0.95, (1.0f32 - 0.95 * 0.95).sqrt()];
        for y in 0..6 {
            for x in 5..10 {
                let ix = frame.ix(x, y);
                frame.normal[ix] = bent;
            }
        }
        let edge = frame.filter()[frame.ix(4, 2)];
        assert!(edge[0] > 0.25 && edge[0] < 0.75, "{edge:?}");
    }

    #[test]
    fn sky_pixels_are_left_unchanged_and_not_used() {
        // Sky (depth 0) carries a huge value that must never show up elsewhere.
        let mut frame = Frame::plane(7, 5, |x, y| [x as f32, y as f32, 1.0, 0.5]);
        let sky = [(0, 0), (3, 2), (4, 2), (6, 4), (2, 4)];
        for &(x, y) in &sky {
            let ix = frame.ix(x, y);
            frame.depth[ix] = 0.0;
            frame.values[ix] = [1e6, -1e6, 1e6, 1e6];
            // A normal equal to everyone else's: only the depth marks it as sky.
            frame.normal[ix] = UP;
        }
        let out = frame.filter();
        for y in 0..5 {
            for x in 0..7 {
                let got = out[frame.ix(x, y)];
                if sky.contains(&(x, y)) {
                    assert_eq!(got, frame.values[frame.ix(x, y)]);
                    continue;
                }
                // A tap counts only when its mirror image is no sky either.
                let used = window_where(&frame.params, x, y, |a, b| !sky.contains(&(a, b)));
                let mean = weighted_mean(&frame, &used);
                assert!(close(got, mean, 1e-6), "({x},{y}): {got:?} vs {mean:?}");
            }
        }
    }

    #[test]
    fn borders_of_small_images() {
        for (width, height) in [(1, 1), (2, 3), (3, 2), (5, 7), (4, 1)] {
            let frame = Frame::plane(width, height, |x, y| {
                [x as f32 + 0.5, y as f32 * 0.25, 1.0, (x * y) as f32]
            });
            let out = frame.filter();
            assert_eq!(out.len(), (width * height) as usize);
            for y in 0..height {
                for x in 0..width {
                    let mean = weighted_mean(&frame, &window(&frame.params, x, y));
                    let got = out[frame.ix(x, y)];
                    assert!(
                        close(got, mean, 1e-6),
                        "{width}×{height} ({x},{y}): {got:?} vs {mean:?}"
                    );
                }
            }
        }
        let one = Frame::plane(1, 1, |_, _| [0.1, 0.2, 0.3, 0.4]);
        assert_eq!(one.filter(), vec![[0.1, 0.2, 0.3, 0.4]]);
    }

    #[test]
    fn periodic_pattern_of_the_16_sets_becomes_its_mean() {
        // Set s = (x mod 4) + 4 (y mod 4) holds values that sum exactly in f32 in any order.
        let set_value = |s: u32| {
            [
                s as f32,
                0.25 * s as f32,
                (15 - s) as f32 * 2.0,
                if s.is_multiple_of(3) { 1.0 } else { 0.0 },
            ]
        };
        let frame = Frame::plane(12, 10, |x, y| set_value(x % 4 + 4 * (y % 4)));
        let mean = [0, 1, 2, 3].map(|k| (0..16).map(|s| set_value(s)[k]).sum::<f32>() / 16.0);
        let out = frame.filter();
        // The window x−2 ..= x+2 fits inside the image for x ∈ [2, width − 3].
        for y in 2..=7 {
            for x in 2..=9 {
                assert_eq!(out[frame.ix(x, y)], mean, "({x},{y})");
            }
        }
    }

    #[test]
    fn strict_tolerances_still_keep_the_centre() {
        // Tolerances no neighbour can meet (and a non-unit normal): the centre alone, unchanged.
        let mut frame = Frame::plane(5, 5, |x, y| [x as f32, y as f32, 0.0, 1.0]);
        frame.params.depth_tolerance = -1.0;
        frame.params.normal_tolerance = 2.0;
        frame.normal[12] = [0.0, 0.1, 0.0];
        assert_eq!(frame.filter(), frame.values);
    }

    #[test]
    #[should_panic(expected = "needs 6 values")]
    fn wrong_buffer_length_is_a_caller_bug() {
        let params = FilterParams::new(2, 3);
        discontinuity_filter(&params, &[[0.0; 4]; 5], &[1.0; 6], &[UP; 6]);
    }

    #[test]
    fn normals_for_gpu_have_a_16_byte_stride_and_the_depth_in_w() {
        let packed = normals_for_gpu(&[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], &[7.0, 8.0]);
        assert_eq!(packed, [[1.0, 2.0, 3.0, 7.0], [4.0, 5.0, 6.0, 8.0]]);
        assert_eq!(bytemuck::cast_slice::<_, u8>(&packed).len(), 32);
    }

    fn parse_and_validate() -> naga::Module {
        let source = &crate::shaders::assemble(FILTER_KERNEL, &[]).expect("filter.wgsl assembles");
        let module = naga::front::wgsl::parse_str(source)
            .unwrap_or_else(|e| panic!("filter.wgsl does not parse:\n{}", e.emit_to_string(source)));
        naga::valid::Validator::new(
            naga::valid::ValidationFlags::all(),
            naga::valid::Capabilities::all(),
        )
        .validate(&module)
        .unwrap_or_else(|e| panic!("filter.wgsl does not validate:\n{}", e.emit_to_string(source)));
        module
    }

    #[test]
    fn wgsl_validates_with_naga() {
        let module = parse_and_validate();
        let entry = module
            .entry_points
            .iter()
            .find(|e| e.name == "main")
            .expect("entry point `main`");
        assert_eq!(entry.stage, naga::ShaderStage::Compute);
        assert_eq!(entry.workgroup_size, [WORKGROUP_SIZE, WORKGROUP_SIZE, 1]);
    }

    #[test]
    fn wgsl_bindings_are_as_documented() {
        use naga::{AddressSpace, StorageAccess};
        let module = parse_and_validate();
        let mut bindings: Vec<(u32, u32, String, AddressSpace)> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| {
                let b = g.binding.as_ref()?;
                Some((b.group, b.binding, g.name.clone().unwrap_or_default(), g.space))
            })
            .collect();
        bindings.sort_by_key(|b| (b.0, b.1));
        let read_write = AddressSpace::Storage {
            access: StorageAccess::LOAD | StorageAccess::STORE,
        };
        let expected = [
            (0, 0, "filter_params", AddressSpace::Uniform),
            (0, 1, "values", AddressSpace::Handle),
            (0, 2, "normal", AddressSpace::Handle),
            (0, 3, "filtered", read_write),
        ];
        let expected: Vec<(u32, u32, String, AddressSpace)> = expected
            .iter()
            .map(|&(g, b, n, s)| (g, b, n.to_owned(), s))
            .collect();
        assert_eq!(bindings, expected);
    }

    #[test]
    fn filter_params_layout_matches_wgsl() {
        let module = parse_and_validate();
        let ty = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("FilterParams"))
            .expect("struct FilterParams in filter.wgsl")
            .1;
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            panic!("FilterParams is not a struct: {:?}", ty.inner);
        };
        let wgsl: Vec<(String, u32)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect();
        let rust: Vec<(String, u32)> = [
            ("width", offset_of!(FilterParams, width)),
            ("height", offset_of!(FilterParams, height)),
            ("depth_tolerance", offset_of!(FilterParams, depth_tolerance)),
            ("normal_tolerance", offset_of!(FilterParams, normal_tolerance)),
            (
                "visibility_tolerance",
                offset_of!(FilterParams, visibility_tolerance),
            ),
            ("pad0", offset_of!(FilterParams, pad0)),
            ("pad1", offset_of!(FilterParams, pad1)),
            ("pad2", offset_of!(FilterParams, pad2)),
        ]
        .iter()
        .map(|&(n, o)| (n.to_owned(), o as u32))
        .collect();
        assert_eq!(*span as usize, size_of::<FilterParams>());
        assert_eq!(*span, 32);
        assert_eq!(wgsl, rust, "WGSL members (left) differ from Rust fields (right)");
        assert_eq!(
            rust.iter().map(|m| m.1).collect::<Vec<_>>(),
            [0, 4, 8, 12, 16, 20, 24, 28]
        );
    }
}
