// Refinement, step 1 of 3: lists the pixels the discontinuity filter cannot serve: those whose
// unfiltered visibility changes at or around them and whose window is cut (a silhouette, a
// crease, the image border, a neighbour more than one ray apart: the filter averages fewer
// than the 16 sample sets there, or over a real change) or whose own 16 rays agree (the
// window would blur a penumbra's edge into them).
// refine_gather, the shadow tracer and refine_resolve then give each of them all 256 samples.
// Each listed pixel also gets a score, the expected error of its filtered visibility; under a
// ray budget the host keeps the highest-scoring pixels.
// Dispatched by the renderer after the filter, ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP) workgroups.
// CPU twin: src/reference/refine.rs (needs_refinement).

#import shared/filter_window
#import shared/groups

// The filter's parameters with the refinement's visibility tolerance (one ray: tighter than
// the filter's), so a window is cut wherever a neighbour differs by more than one ray.
@group(0) @binding(0) var<uniform> filter_params: FilterParams;
// The filter's input textures (shaders/filter.wgsl): (irradiance rgb, unfiltered visibility),
// and (normal xyz, depth w; depth 0 = no hit).
@group(0) @binding(1) var values: texture_2d<f32>;
@group(0) @binding(2) var normal: texture_2d<f32>;
// [0]: pixels listed; [1]: pixels with geometry (the ray budget's unit);
// [2 + i]: the index of the i-th pixel listed (in no particular order). Cleared by the host.
@group(0) @binding(3) var<storage, read_write> list: array<atomic<u32>>;
// The filter's output (visibility in w) at every pixel.
@group(0) @binding(4) var<storage, read> filtered: array<vec4<f32>>;
// [i]: the score of the i-th pixel listed (refine_score).
@group(0) @binding(5) var<storage, read_write> scores: array<f32>;

// Whether the unfiltered visibility changes at or around (x, y): the pixel is neither fully lit
// nor in umbra, or a neighbour of its window with geometry has another visibility.
fn visibility_varies(x: u32, y: u32) -> bool {
    let v_c = textureLoad(values, vec2<u32>(x, y), 0).w;
    if v_c > 0.0 && v_c < 1.0 {
        return true;
    }
    // A row of 5 taps without a branch (clamped_texel: a tap beyond the border reads the
    // border, a pixel inside the window too, so the answer is the same), then an exit if it
    // found a change; a branch per tap made this kernel up to twice as slow on Mesa 22.3.
    for (var dy = -2; dy <= 2; dy++) {
        var varies = false;
        for (var dx = -2; dx <= 2; dx++) {
            let t = clamped_texel(i32(x) + dx, i32(y) + dy);
            varies = varies | ((textureLoad(normal, t, 0).w > 0.0) & (textureLoad(values, t, 0).w != v_c));
        }
        if varies {
            return true;
        }
    }
    return false;
}

// The expected error of the pixel's filtered visibility: the standard error of its window's
// weighted mean (each accepted tap (weight w, unfiltered visibility u) a binomial estimate of 16
// rays, variance u(1 − u)/16), plus, where its own 16 rays agree, how far the window pulled it
// from them (the blur of a penumbra's edge). `taps`: the window's paired taps at the
// refinement's visibility tolerance. Sums in the twin's order (taps k = 0..25).
fn refine_score(x: u32, y: u32, taps: u32) -> f32 {
    var weight = 0.0;
    var variance = 0.0;
    for (var k = 0; k < 25; k++) {
        if (taps & (1u << u32(k))) == 0u {
            continue;
        }
        let dy = k / 5 - 2;
        let dx = k % 5 - 2;
        let u = textureLoad(values, vec2<i32>(i32(x) + dx, i32(y) + dy), 0).w;
        let w = select(1.0, 0.5, abs(dx) == 2) * select(1.0, 0.5, abs(dy) == 2);
        weight += w;
        variance += w * w * (u * (1.0 - u) / 16.0);
    }
    let pixel = y * filter_params.width + x;
    let v_c = textureLoad(values, vec2<u32>(x, y), 0).w;
    var score = sqrt(variance) / weight;
    if v_c == 0.0 || v_c == 1.0 {
        score += abs(filtered[pixel].w - v_c);
    }
    return score;
}

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= filter_params.width || gid.y >= filter_params.height {
        return;
    }
    let pixel = gid.y * filter_params.width + gid.x;
    if textureLoad(normal, gid.xy, 0).w <= 0.0 {
        return;
    }
    atomicAdd(&list[1], 1u);
    if !visibility_varies(gid.x, gid.y) {
        return;
    }
    let v_c = textureLoad(values, gid.xy, 0).w;
    let agree = v_c == 0.0 || v_c == 1.0;
    let taps = paired_taps(gid.x, gid.y);
    if !agree && taps == FULL_WINDOW {
        return;
    }
    let slot = atomicAdd(&list[0], 1u);
    atomicStore(&list[2u + slot], pixel);
    scores[slot] = refine_score(gid.x, gid.y, taps);
}
