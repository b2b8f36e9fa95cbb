// The shadow kernels' alpha test: whether a shadow ray passes an alpha-tested triangle
// (glTF MASK or BLEND material) where it hits it. Reads an `alpha` binding, the words of
// bvh::AlphaMasks (shared/layout: AlphaTriangle, AlphaMask), which shared/alpha_words
// declares (or the ray-query kernel itself). Twin: AlphaMasks::passes.

// An alpha-tested triangle's texture coordinates and mask, read once for all the rays of
// a frustum that hit it.
struct AlphaRecord {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    width: u32,   // the mask's texels per row
    height: u32,  // its rows
    bits: u32,    // its first word of bits (bit set: opaque)
}

// The record of a triangle whose BvhTriangle.alpha is `record` (not ALPHA_OPAQUE).
fn alpha_record(record: u32) -> AlphaRecord {
    let m = alpha[record + 6u];
    return AlphaRecord(
        vec2<f32>(bitcast<f32>(alpha[record]), bitcast<f32>(alpha[record + 1u])),
        vec2<f32>(bitcast<f32>(alpha[record + 2u]), bitcast<f32>(alpha[record + 3u])),
        vec2<f32>(bitcast<f32>(alpha[record + 4u]), bitcast<f32>(alpha[record + 5u])),
        alpha[m], alpha[m + 1u], alpha[m + 2u],
    );
}

// Whether a ray passes the triangle of record `r` at the point with barycentric weights
// `w` (corners 0, 1, 2): where the mask bit of the texel nearest to the interpolated
// texture coordinate is clear. Any `w`, NaN included, reads a word of the mask
// (texel_index clamps to it).
fn record_passes(r: AlphaRecord, w: vec3<f32>) -> bool {
    let uv = r.uv0 * w.x + r.uv1 * w.y + r.uv2 * w.z;
    let i = texel_index(r.width, r.height, uv);
    return (alpha[r.bits + i / 32u] & (1u << (i % 32u))) == 0u;
}

// Whether a ray passes the triangle whose BvhTriangle.alpha is `record` at the point with
// barycentric weights `w`: never for ALPHA_OPAQUE (nor in a build without ALPHA_TEST),
// else as record_passes.
fn alpha_passes(record: u32, w: vec3<f32>) -> bool {
    if !ALPHA_TEST || record == ALPHA_OPAQUE {
        return false;
    }
    return record_passes(alpha_record(record), w);
}
