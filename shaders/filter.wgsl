// 4×4 discontinuity filter: each pixel averages the values of the 4-pixel box centred on it, using only neighbours at a similar
// depth, normal and visibility whose mirror image through the pixel is used too.
// Dispatched by the filter pass after shading, ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP) workgroups; CPU twin: src/reference/filter.rs.

#import shared/filter_window
#import shared/groups

@group(0) @binding(0) var<uniform> filter_params: FilterParams;
// The filter's inputs as width×height textures, copied from the frame's buffers just before
// the filter (PixelBuffers::record_filter_input_copies). Textures, not storage buffers: Mesa 22.3
// lavapipe runs every storage load at a lane-varying index as a loop over the lanes with a
// branch per lane, texel fetches without one (with textures the filter is 3× faster there
// with AVX2 code, README "Performance").
// Per pixel: rgb = irradiance, a = visibility (filtered together).
@group(0) @binding(1) var values: texture_2d<f32>;
// Per pixel: the unit shading normal in xyz, the distance to the camera in w; w ≤ 0 = no hit:
// never a neighbour, and the pixel's value passes through unchanged.
@group(0) @binding(2) var normal: texture_2d<f32>;
@group(0) @binding(3) var<storage, read_write> filtered: array<vec4<f32>>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= filter_params.width || gid.y >= filter_params.height {
        return;
    }
    let centre = vec2<i32>(gid.xy);
    let normal_c = textureLoad(normal, centre, 0);
    let n_c = normal_c.xyz;
    let d_c = normal_c.w;
    let v_c = textureLoad(values, centre, 0);
    // The window is a 4-pixel box centred on the pixel: 5×5 taps, the outer
    // ring at half weight (a quarter in the corners). Every one of the 16
    // sample sets then has weight 1 in a full window, and a gradient across
    // the window averages to the centre's value (an uncentred 4×4 window is
    // half a pixel off). Weights are powers of two: every product is exact.
    // The taps go in mirror pairs through the centre (tap k = (dy + 2) · 5 + dx + 2 and
    // tap 24 - k, k < 12): a pair counts when both are similar (the rule of
    // shared/filter_window's paired_taps), so each tap is loaded once. The sum: centre first,
    // then pair by pair, k increasing.
    var sum = v_c;
    var weight_sum = 1.0;
    let has_hit = d_c > 0.0;
    // The 12 pairs written out rather than looped: lavapipe then folds each pair's offsets
    // and weight into constants (the filter 1.2x faster than with the loop on Mesa 22.3
    // with AVX2 code, the same image).
    add_pair(gid.xy, -2, -2, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, -1, -2, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 0, -2, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 1, -2, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 2, -2, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, -2, -1, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, -1, -1, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 0, -1, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 1, -1, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, 2, -1, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, -2, 0, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    add_pair(gid.xy, -1, 0, has_hit, d_c, n_c, v_c.w, &sum, &weight_sum);
    filtered[gid.y * filter_params.width + gid.x] = sum / weight_sum;
}

// Adds the mirror pair of taps (dx, dy) and (-dx, -dy) of the window around pixel `c` to `sum`
// and `weight_sum`, with the pair's weight where both taps are similar to the centre (depth
// `d_c`, normal `n_c`, unfiltered visibility `vis_c`; `has_hit`: the centre has a hit), else
// weight 0. No branch (clamped_texel; measured 1.2-1.5x faster on both lavapipe drivers than
// skipping pairs): a pair not used — beyond the border, or any pair of a centre without a
// hit — adds 0 · value (finite), which leaves the sums exactly what skipping it would (so a
// centre without a hit keeps v_c / 1 = v_c). `dy <= 0`: tap a is never below the centre
// and b never above it.
fn add_pair(
    c: vec2<u32>,
    dx: i32,
    dy: i32,
    has_hit: bool,
    d_c: f32,
    n_c: vec3<f32>,
    vis_c: f32,
    sum: ptr<function, vec4<f32>>,
    weight_sum: ptr<function, f32>,
) {
    let ax = i32(c.x) + dx;
    let ay = i32(c.y) + dy;
    let bx = i32(c.x) - dx;
    let by = i32(c.y) - dy;
    let inside = (ay >= 0) & (by < i32(filter_params.height)) & (min(ax, bx) >= 0)
        & (max(ax, bx) < i32(filter_params.width));
    let a = clamped_texel(ax, ay);
    let b = clamped_texel(bx, by);
    let v_a = textureLoad(values, a, 0);
    let v_b = textureLoad(values, b, 0);
    let used = has_hit & inside & similar(textureLoad(normal, a, 0), v_a.w, d_c, n_c, vis_c)
        & similar(textureLoad(normal, b, 0), v_b.w, d_c, n_c, vis_c);
    let w = select(0.0, select(1.0, 0.5, abs(dy) == 2) * select(1.0, 0.5, abs(dx) == 2), used);
    *sum += v_a * w;
    *sum += v_b * w;
    *weight_sum += 2.0 * w;
}
