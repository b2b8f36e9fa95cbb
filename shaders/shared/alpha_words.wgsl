// The alpha test of the shadow kernels that bind the alpha words as binding 8 (shadow_mft,
// shadow_packet, shadow_per_ray), in their build for scenes with alpha-tested triangles;
// the other build imports shared/alpha_none in its place (gpu::AlphaKernels).

#import shared/alpha

// The words of bvh::AlphaMasks.
@group(0) @binding(8) var<storage, read> alpha: array<u32>;
