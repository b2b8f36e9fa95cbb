// 4×4 discontinuity filter: each pixel averages the values of the 4-pixel box centred on it, using only neighbours at a similar
// depth, normal and visibility whose mirror image through the pixel is used too.
// Dispatched by the filter pass after shading, ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP) workgroups; CPU twin: src/reference/filter.rs.

#import shared/filter_window
#import shared/groups

@group(0) @binding(0) var<uniform> filter_params: FilterParams;
// Per pixel, row-major, top row first: rgb = irradiance, a = visibility (filtered together).
@group(0) @binding(1) var<storage, read> values: array<vec4<f32>>;
// Distance to the camera; 0 (or less) = no hit: never a neighbour, passed through unchanged.
@group(0) @binding(2) var<storage, read> depth: array<f32>;
// Unit shading normal in xyz, the depth again in w: a tap's depth and normal in one load (on
// Mesa 22.3 lavapipe every storage load is a loop over the lanes).
@group(0) @binding(3) var<storage, read> normal: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> filtered: array<vec4<f32>>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= filter_params.width || gid.y >= filter_params.height {
        return;
    }
    let c_ix = gid.y * filter_params.width + gid.x;
    let d_c = depth[c_ix];
    if d_c <= 0.0 {
        filtered[c_ix] = values[c_ix];
        return;
    }
    // The window is a 4-pixel box centred on the pixel: 5×5 taps, the outer
    // ring at half weight (a quarter in the corners). Every one of the 16
    // sample sets then has weight 1 in a full window, and a gradient across
    // the window averages to the centre's value (an uncentred 4×4 window is
    // half a pixel off). Weights are powers of two: every product is exact.
    // The taps go in mirror pairs through the centre (tap k and tap 24 - k,
    // k < 12): a pair counts when both are similar (paired_taps' rule), so each
    // tap is loaded once. The sum: centre first, then pair by pair, k increasing.
    let n_c = normal[c_ix].xyz;
    let v_c = values[c_ix];
    var sum = v_c;
    var weight_sum = 1.0;
    // No branch in the loop (clamped_pixel; measured 1.2-1.5x faster on both lavapipe
    // drivers than skipping pairs): a pair not used, perhaps beyond the border, gets weight
    // 0, and adding 0 · value (finite) leaves the sums exactly what skipping it would.
    for (var k = 0; k < 12; k++) {
        let dy = k / 5 - 2;
        let dx = k % 5 - 2;
        let ax = i32(gid.x) + dx;
        let ay = i32(gid.y) + dy;
        let bx = i32(gid.x) - dx;
        let by = i32(gid.y) - dy;
        let a = clamped_pixel(ax, ay);
        let b = clamped_pixel(bx, by);
        // dy <= 0 here, so a is never below the centre and b never above it.
        let inside = (ay >= 0) & (by < i32(filter_params.height)) & (min(ax, bx) >= 0)
            & (max(ax, bx) < i32(filter_params.width));
        let v_a = values[a];
        let v_b = values[b];
        let used = inside & similar(normal[a], v_a.w, d_c, n_c, v_c.w) & similar(normal[b], v_b.w, d_c, n_c, v_c.w);
        let w = select(0.0, select(1.0, 0.5, abs(dy) == 2) * select(1.0, 0.5, abs(dx) == 2), used);
        sum += v_a * w;
        sum += v_b * w;
        weight_sum += 2.0 * w;
    }
    filtered[c_ix] = sum / weight_sum;
}
