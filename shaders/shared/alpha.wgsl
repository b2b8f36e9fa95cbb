// The shadow kernels' alpha test: whether a shadow ray passes an alpha-tested triangle
// (glTF MASK or BLEND material) where it hits it. Reads an `alpha` binding, the words of
// bvh::AlphaMasks (shared/layout: AlphaTriangle, AlphaMask), which shared/alpha_words
// declares (or the ray-query kernel itself). Twin: AlphaMasks::passes.

// Whether a ray passes the triangle whose BvhTriangle.alpha is `record` at the point with
// barycentric weights `w` (corners 0, 1, 2): never for ALPHA_OPAQUE (nor in a build
// without ALPHA_TEST), else where the mask bit of the texel nearest to the interpolated
// texture coordinate is clear.
fn alpha_passes(record: u32, w: vec3<f32>) -> bool {
    if !ALPHA_TEST || record == ALPHA_OPAQUE {
        return false;
    }
    let uv0 = vec2<f32>(bitcast<f32>(alpha[record]), bitcast<f32>(alpha[record + 1u]));
    let uv1 = vec2<f32>(bitcast<f32>(alpha[record + 2u]), bitcast<f32>(alpha[record + 3u]));
    let uv2 = vec2<f32>(bitcast<f32>(alpha[record + 4u]), bitcast<f32>(alpha[record + 5u]));
    let m = alpha[record + 6u];
    let uv = uv0 * w.x + uv1 * w.y + uv2 * w.z;
    let i = texel_index(alpha[m], alpha[m + 1u], uv);
    return (alpha[alpha[m + 2u] + i / 32u] & (1u << (i % 32u))) == 0u;
}
