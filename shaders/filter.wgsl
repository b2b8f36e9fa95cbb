// 4×4 discontinuity filter: each pixel averages the values of the 4-pixel box centred on it, using only neighbours at a similar
// depth, normal and visibility whose mirror image through the pixel is used too.
// Dispatched by the filter pass after shading, ceil(width/8) × ceil(height/8) workgroups; its CPU twin is `penumbra::filter::filter_pixel`.

// Mirrors `FilterParams` in `src/filter.rs`, 32 bytes; a naga test checks size and offsets.
struct FilterParams {
    width: u32,             // bytes 0..4: image width in pixels
    height: u32,            // bytes 4..8: image height in pixels
    depth_tolerance: f32,   // bytes 8..12: a neighbour is accepted when |d_n - d_c| <= depth_tolerance * d_c
    normal_tolerance: f32,  // bytes 12..16: ... and dot(n_n, n_c) >= normal_tolerance
    visibility_tolerance: f32,  // bytes 16..20: ... and |v_n - v_c| <= visibility_tolerance (v = values.w)
    pad0: u32,              // bytes 20..32: unused (a uniform's size is a multiple of 16)
    pad1: u32,
    pad2: u32,
}

const WG_SIZE: u32 = 8u;

@group(0) @binding(0) var<uniform> params: FilterParams;
// Per pixel, row-major, top row first: rgb = irradiance, a = visibility (filtered together).
@group(0) @binding(1) var<storage, read> values: array<vec4<f32>>;
// Distance to the camera; 0 (or less) = no hit: never a neighbour, passed through unchanged.
@group(0) @binding(2) var<storage, read> depth: array<f32>;
// Unit shading normal in xyz; w unused (vec4 for a 16-byte stride).
@group(0) @binding(3) var<storage, read> normal: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> filtered: array<vec4<f32>>;

@compute @workgroup_size(WG_SIZE, WG_SIZE)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let c_ix = gid.y * params.width + gid.x;
    let d_c = depth[c_ix];
    if d_c <= 0.0 {
        filtered[c_ix] = values[c_ix];
        return;
    }
    let n_c = normal[c_ix].xyz;
    // Same order as the CPU twin (dy outer, dx inner, increasing), so the f32 sums match.
    // First the taps the centre accepts, one bit each: bit (dy + 2) * 5 + (dx + 2).
    var accepted = 0u;
    for (var dy = -2; dy <= 2; dy++) {
        let y = i32(gid.y) + dy;
        if y < 0 || y >= i32(params.height) {
            continue;
        }
        for (var dx = -2; dx <= 2; dx++) {
            let x = i32(gid.x) + dx;
            if x < 0 || x >= i32(params.width) {
                continue;
            }
            let ix = u32(y) * params.width + u32(x);
            let d_n = depth[ix];
            let n_n = normal[ix].xyz;
            // Written out rather than dot() to fix the order of the products' sum.
            let cos_nc = n_n.x * n_c.x + n_n.y * n_c.y + n_n.z * n_c.z;
            let similar = d_n > 0.0 && abs(d_n - d_c) <= params.depth_tolerance * d_c
                && cos_nc >= params.normal_tolerance
                && abs(values[ix].w - values[c_ix].w) <= params.visibility_tolerance;
            // The centre always counts, whatever the tolerances, so weight_sum >= 1.
            if (dx == 0 && dy == 0) || similar {
                accepted |= 1u << u32((dy + 2) * 5 + dx + 2);
            }
        }
    }
    // Only taps whose mirror image through the centre is accepted too: the
    // used taps stay symmetric about the pixel where a silhouette, crease,
    // sharp shadow edge or the image border cuts the window, so the mean is
    // not pulled towards one side (bit k's mirror is bit 24 - k).
    let paired = accepted & (reverseBits(accepted) >> 7u);
    // The window is a 4-pixel box centred on the pixel: 5×5 taps, the outer
    // ring at half weight (a quarter in the corners). Every one of the 16
    // sample sets then has weight 1 in a full window, and a gradient across
    // the window averages to the centre's value (an uncentred 4×4 window is
    // half a pixel off). Weights are powers of two: every product is exact.
    var sum = vec4<f32>(0.0);
    var weight_sum = 0.0;
    for (var dy = -2; dy <= 2; dy++) {
        let wy = select(1.0, 0.5, abs(dy) == 2);
        for (var dx = -2; dx <= 2; dx++) {
            if (paired & (1u << u32((dy + 2) * 5 + dx + 2))) == 0u {
                continue;
            }
            let ix = u32(i32(gid.y) + dy) * params.width + u32(i32(gid.x) + dx);
            let w = wy * select(1.0, 0.5, abs(dx) == 2);
            sum += values[ix] * w;
            weight_sum += w;
        }
    }
    filtered[c_ix] = sum / weight_sum;
}
