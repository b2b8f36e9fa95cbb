// 4×4 discontinuity filter: each pixel averages the values of the 4-pixel box centred on it, using only neighbours at a similar
// depth, normal and visibility whose mirror image through the pixel is used too.
// Each invocation filters FILTER_PIXELS_PER_INVOCATION = 4 horizontally adjacent pixels, whose windows share most taps: 40 taps
// fetched for four pixels instead of 100 (the filter 1.6-2x faster on both lavapipe drivers, README "Performance"). Dispatched by
// the filter pass after shading, ceil(width / (4 · PIXEL_GROUP)) × ceil(height / PIXEL_GROUP) workgroups.
// CPU twin: src/reference/filter.rs.

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

// Horizontally adjacent pixels one invocation filters (mirrors `FILTER_PIXELS_PER_INVOCATION` in
// `src/contract/filter.rs`; a naga test checks). The kernel below is written for 4.
const FILTER_PIXELS_PER_INVOCATION: u32 = 4u;

// One tap of a window: its normal and depth, its value, and whether it lies inside the image.
struct Tap {
    normal: vec4<f32>,
    value: vec4<f32>,
    inside: bool,
}

// The taps x - 2 ..= x + 5 of one row: every column the windows of pixels x ..= x + 3 reach.
struct Row {
    t0: Tap,
    t1: Tap,
    t2: Tap,
    t3: Tap,
    t4: Tap,
    t5: Tap,
    t6: Tap,
    t7: Tap,
}

// The tap at (x, y), read clamped onto the image (no branch per tap).
fn load_tap(x: i32, y: i32) -> Tap {
    let t = clamped_texel(x, y);
    return Tap(textureLoad(normal, t, 0), textureLoad(values, t, 0), inside_image(x, y));
}

// Taps x - 2 ..= x + 5 of row y.
fn load_row(x: i32, y: i32) -> Row {
    return Row(
        load_tap(x - 2, y),
        load_tap(x - 1, y),
        load_tap(x, y),
        load_tap(x + 1, y),
        load_tap(x + 2, y),
        load_tap(x + 3, y),
        load_tap(x + 4, y),
        load_tap(x + 5, y),
    );
}

// One pixel's running sums: its centre's depth, normal and unfiltered visibility, whether
// it has a hit, and the weighted sums of the used taps' values and of their weights.
struct Pixel {
    d: f32,
    n: vec3<f32>,
    vis: f32,
    has_hit: bool,
    sum: vec4<f32>,
    weight_sum: f32,
}

// A pixel whose centre tap is `c`, its sums holding the centre alone (weight 1).
fn start_pixel(c: Tap) -> Pixel {
    return Pixel(c.normal.w, c.normal.xyz, c.value.w, c.normal.w > 0.0, c.value, 1.0);
}

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let x = i32(gid.x * FILTER_PIXELS_PER_INVOCATION);
    let y = i32(gid.y);
    if x >= i32(filter_params.width) || y >= i32(filter_params.height) {
        return;
    }
    // Pixels p0 ..= p3 are (x, y) ..= (x + 3, y). A pixel's window is the 4-pixel box
    // centred on it: 5×5 taps, the outer ring at half weight (a quarter in the corners).
    // Every one of the 16 sample sets then has weight 1 in a full window, and a gradient
    // across the window averages to the centre's value (an uncentred 4×4 window is half a
    // pixel off). Weights are powers of two: every product is exact. The taps go in mirror
    // pairs through the centre (tap k = (dy + 2) · 5 + dx + 2 and tap 24 - k, k < 12): a
    // pair counts when both are similar (the rule of shared/filter_window's paired_taps).
    // Each pixel's sum, as the CPU twin's: its centre first, then pair by pair, k
    // increasing: rows y - 2 with y + 2, then y - 1 with y + 1, then row y; the rows
    // loaded when they are needed, so that at most three are live.
    let m = load_row(x, y);
    var p0 = start_pixel(m.t2);
    var p1 = start_pixel(m.t3);
    var p2 = start_pixel(m.t4);
    var p3 = start_pixel(m.t5);
    add_row_pairs_of_four(&p0, &p1, &p2, &p3, load_row(x, y - 2), load_row(x, y + 2), 0.5);
    add_row_pairs_of_four(&p0, &p1, &p2, &p3, load_row(x, y - 1), load_row(x, y + 1), 1.0);
    // Row y: dx = -2 (weight 1/2) and dx = -1 (weight 1), each with its mirror.
    add_pair(&p0, m.t0, m.t4, 0.5);
    add_pair(&p0, m.t1, m.t3, 1.0);
    add_pair(&p1, m.t1, m.t5, 0.5);
    add_pair(&p1, m.t2, m.t4, 1.0);
    add_pair(&p2, m.t2, m.t6, 0.5);
    add_pair(&p2, m.t3, m.t5, 1.0);
    add_pair(&p3, m.t3, m.t7, 0.5);
    add_pair(&p3, m.t4, m.t6, 1.0);
    let first = u32(y) * filter_params.width + u32(x);
    filtered[first] = p0.sum / p0.weight_sum;
    // The pixels beyond the image's right edge are computed from clamped taps and not written.
    if x + 1 < i32(filter_params.width) {
        filtered[first + 1u] = p1.sum / p1.weight_sum;
    }
    if x + 2 < i32(filter_params.width) {
        filtered[first + 2u] = p2.sum / p2.weight_sum;
    }
    if x + 3 < i32(filter_params.width) {
        filtered[first + 3u] = p3.sum / p3.weight_sum;
    }
}

// Adds to pixels p0 ..= p3 (x ..= x + 3) the pairs of rows `a` (y + dy, dy < 0) and `b`
// (y - dy) of their windows, `w` the rows' weight (see add_row_pairs).
fn add_row_pairs_of_four(
    p0: ptr<function, Pixel>,
    p1: ptr<function, Pixel>,
    p2: ptr<function, Pixel>,
    p3: ptr<function, Pixel>,
    a: Row,
    b: Row,
    w: f32,
) {
    add_row_pairs(p0, a.t0, a.t1, a.t2, a.t3, a.t4, b.t0, b.t1, b.t2, b.t3, b.t4, w);
    add_row_pairs(p1, a.t1, a.t2, a.t3, a.t4, a.t5, b.t1, b.t2, b.t3, b.t4, b.t5, w);
    add_row_pairs(p2, a.t2, a.t3, a.t4, a.t5, a.t6, b.t2, b.t3, b.t4, b.t5, b.t6, w);
    add_row_pairs(p3, a.t3, a.t4, a.t5, a.t6, a.t7, b.t3, b.t4, b.t5, b.t6, b.t7, w);
}

// Adds to pixel `p` the five pairs of one row pair of its window, dx = -2 ..= 2: `a0 ..= a4`
// are the taps (x + dx, y + dy) of the upper row (dy < 0) and `b0 ..= b4` the taps
// (x + dx, y - dy) of the lower, so tap aJ pairs with b(4 - J). `w`: the row's weight (1/2
// for |dy| = 2, else 1), halved again at dx = ±2.
fn add_row_pairs(
    p: ptr<function, Pixel>,
    a0: Tap,
    a1: Tap,
    a2: Tap,
    a3: Tap,
    a4: Tap,
    b0: Tap,
    b1: Tap,
    b2: Tap,
    b3: Tap,
    b4: Tap,
    w: f32,
) {
    add_pair(p, a0, b4, 0.5 * w);
    add_pair(p, a1, b3, w);
    add_pair(p, a2, b2, w);
    add_pair(p, a3, b1, w);
    add_pair(p, a4, b0, 0.5 * w);
}

// Adds the mirror pair of taps `a` and `b` (weight `w` each) to pixel `p`'s sums where both
// lie inside the image and are similar to its centre, else weight 0. No branch (measured
// 1.2-1.5x faster on both lavapipe drivers than skipping pairs): a pair not used — beyond
// the border, or any pair of a centre without a hit — adds 0 · value (finite), which
// leaves the sums exactly what skipping it would (so a centre without a hit keeps
// v_c / 1 = v_c).
fn add_pair(p: ptr<function, Pixel>, a: Tap, b: Tap, w: f32) {
    let used = (*p).has_hit & a.inside & b.inside
        & similar(a.normal, a.value.w, (*p).d, (*p).n, (*p).vis)
        & similar(b.normal, b.value.w, (*p).d, (*p).n, (*p).vis);
    let weight = select(0.0, w, used);
    (*p).sum += a.value * weight;
    (*p).sum += b.value * weight;
    (*p).weight_sum += 2.0 * weight;
}
