// Refinement, step 1 of 3: lists the pixels the discontinuity filter cannot serve: those whose
// unfiltered visibility changes at or around them and whose window is cut (a silhouette, a
// crease, the image border, a neighbour more than one ray apart: the filter averages fewer
// than the 16 sample sets there, or over a real change) or whose own 16 rays agree (the
// window would blur a penumbra's edge into them).
// refine_gather, the shadow tracer and refine_resolve then give each of them all 256 samples.
// Dispatched by the renderer after the filter, ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP) workgroups.
// CPU twin: src/reference/refine.rs (needs_refinement).

#import shared/filter_window
#import shared/groups

// The filter's parameters with the refinement's visibility tolerance (one ray: tighter than
// the filter's), so a window is cut wherever a neighbour differs by more than one ray.
@group(0) @binding(0) var<uniform> filter_params: FilterParams;
// The filter's inputs: (irradiance rgb, unfiltered visibility), depth (0 = no hit), normal.
@group(0) @binding(1) var<storage, read> values: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> depth: array<f32>;
@group(0) @binding(3) var<storage, read> normal: array<vec4<f32>>;
// [0]: pixels listed; [1]: rays that ran out of iterations (refine_trace adds them);
// [2 + i]: the index of the i-th pixel listed (in no particular order). Cleared by the host.
@group(0) @binding(4) var<storage, read_write> list: array<atomic<u32>>;

// Whether the unfiltered visibility changes at or around (x, y): the pixel is neither fully lit
// nor in umbra, or a neighbour of its window with geometry has another visibility.
fn visibility_varies(x: u32, y: u32) -> bool {
    let v_c = values[y * filter_params.width + x].w;
    if v_c > 0.0 && v_c < 1.0 {
        return true;
    }
    for (var dy = -2; dy <= 2; dy++) {
        let ny = i32(y) + dy;
        if ny < 0 || ny >= i32(filter_params.height) {
            continue;
        }
        for (var dx = -2; dx <= 2; dx++) {
            let nx = i32(x) + dx;
            if nx < 0 || nx >= i32(filter_params.width) {
                continue;
            }
            let ix = u32(ny) * filter_params.width + u32(nx);
            if depth[ix] > 0.0 && values[ix].w != v_c {
                return true;
            }
        }
    }
    return false;
}

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= filter_params.width || gid.y >= filter_params.height {
        return;
    }
    let pixel = gid.y * filter_params.width + gid.x;
    if depth[pixel] <= 0.0 || !visibility_varies(gid.x, gid.y) {
        return;
    }
    let v_c = values[pixel].w;
    let agree = v_c == 0.0 || v_c == 1.0;
    if !agree && paired_taps(gid.x, gid.y) == FULL_WINDOW {
        return;
    }
    let slot = atomicAdd(&list[0], 1u);
    atomicStore(&list[2u + slot], pixel);
}
