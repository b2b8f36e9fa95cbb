// Stands in for shared/alpha_words in the shadow kernels' build for scenes without
// alpha-tested triangles (gpu::AlphaKernels): no alpha binding, and no ray ever passes a
// triangle. The binding is left out, not merely unused: on Mesa 25 lavapipe the ninth
// binding alone made the per-ray kernel about 30 % slower.

fn alpha_passes(record: u32, w: vec3<f32>) -> bool {
    return false;
}
