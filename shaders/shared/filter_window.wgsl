// The discontinuity filter's window: which taps of a pixel's 5×5 window the filter averages.
// Shared by the filter kernel and by the refinement's pixel selection (refine_select), so that
// both see the same window; they declare `filter_params` and the input textures `values`
// and `normal` (shaders/filter.wgsl). CPU twin: `paired_taps` in src/reference/filter.rs.

// Mirrors `FilterParams` in `src/reference/filter.rs`, 32 bytes; a naga test checks size and offsets.
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

// Every tap of the window: bit (dy + 2) * 5 + (dx + 2) for dx, dy in -2..=2.
const FULL_WINDOW: u32 = 0x1ffffffu;

// Whether (x, y) lies inside the image.
fn inside_image(x: i32, y: i32) -> bool {
    return (x >= 0) & (y >= 0) & (x < i32(filter_params.width)) & (y < i32(filter_params.height));
}

// Pixel (x, y) clamped onto the image: the window loops read every tap, one beyond the
// border at the border, and leave out what they must without a branch per tap (lavapipe
// runs such a branch as divergent control flow).
fn clamped_texel(x: i32, y: i32) -> vec2<i32> {
    return vec2<i32>(clamp(x, 0, i32(filter_params.width) - 1), clamp(y, 0, i32(filter_params.height) - 1));
}

// Whether a tap whose normal (xyz) and depth (w) are `tap` and whose unfiltered visibility is
// `v_n` may be averaged with a centre of depth `d_c`, normal `n_c` and unfiltered visibility
// `v_c`: a hit at a similar depth, normal and visibility (the tolerances of `filter_params`).
// Every test is evaluated (`&`, not `&&`): no branch per tap.
fn similar(tap: vec4<f32>, v_n: f32, d_c: f32, n_c: vec3<f32>, v_c: f32) -> bool {
    let d_n = tap.w;
    // Written out rather than dot() to fix the order of the products' sum.
    let cos_nc = tap.x * n_c.x + tap.y * n_c.y + tap.z * n_c.z;
    return (d_n > 0.0) & (abs(d_n - d_c) <= filter_params.depth_tolerance * d_c)
        & (cos_nc >= filter_params.normal_tolerance)
        & (abs(v_n - v_c) <= filter_params.visibility_tolerance);
}

// [`similar`] for the tap at texel `t` (inside the image): one fetch of its normal and depth
// (the depth rides in w), one of its visibility.
fn similar_tap(t: vec2<i32>, d_c: f32, n_c: vec3<f32>, v_c: f32) -> bool {
    return similar(textureLoad(normal, t, 0), textureLoad(values, t, 0).w, d_c, n_c, v_c);
}

// The taps of the window around (x, y) the filter uses: those at a similar depth, normal and
// unfiltered visibility whose mirror image through the centre is used too (the centre always
// is). The centre must have a hit (depth > 0).
fn paired_taps(x: u32, y: u32) -> u32 {
    let centre = textureLoad(normal, vec2<u32>(x, y), 0);
    let d_c = centre.w;
    let n_c = centre.xyz;
    let v_c = textureLoad(values, vec2<u32>(x, y), 0).w;
    // Same order as the CPU twin (dy outer, dx inner, increasing); a tap beyond the border is
    // read clamped and not counted.
    var accepted = 1u << 12u; // the centre always counts, whatever the tolerances
    for (var dy = -2; dy <= 2; dy++) {
        for (var dx = -2; dx <= 2; dx++) {
            let nx = i32(x) + dx;
            let ny = i32(y) + dy;
            let similar = similar_tap(clamped_texel(nx, ny), d_c, n_c, v_c);
            accepted |= select(0u, 1u << u32((dy + 2) * 5 + dx + 2), inside_image(nx, ny) & similar);
        }
    }
    // Only taps whose mirror image through the centre is accepted too: the
    // used taps stay symmetric about the pixel where a silhouette, crease,
    // sharp shadow edge or the image border cuts the window, so the mean is
    // not pulled towards one side (bit k's mirror is bit 24 - k).
    return accepted & (reverseBits(accepted) >> 7u);
}
