// Stands in for shared/alpha_words in the shadow kernels' build for scenes without
// alpha-tested triangles (gpu::AlphaKernels): no alpha binding, and no ray ever passes a
// triangle. The binding is left out, not merely unused: on Mesa 25 lavapipe the ninth
// binding alone made the per-ray kernel about 30 % slower.

// As shared/alpha's, so that the kernels' ALPHA_TEST branches type-check; never read.
struct AlphaRecord {
    uv0: vec2<f32>,
    uv1: vec2<f32>,
    uv2: vec2<f32>,
    width: u32,
    height: u32,
    bits: u32,
}

fn alpha_record(record: u32) -> AlphaRecord {
    return AlphaRecord(vec2<f32>(0.0), vec2<f32>(0.0), vec2<f32>(0.0), 1u, 1u, 0u);
}

fn record_passes(r: AlphaRecord, w: vec3<f32>) -> bool {
    return false;
}

fn alpha_passes(record: u32, w: vec3<f32>) -> bool {
    return false;
}
