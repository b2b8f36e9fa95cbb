// Visibility per pixel from the shadow masks, as the filter's input: (0, 0, 0, unblocked rays / 16); 1 where no geometry.
// Recorded by ShadowPass::record (src/gpu/embed/mod.rs) after the shadow pass; CPU twin: src/reference/visibility.rs.

#import shared/groups
#import shared/surface


@group(0) @binding(0) var<uniform> size: ImageSize;
@group(0) @binding(1) var<storage, read> masks: array<u32>;
@group(0) @binding(2) var<storage, read_write> values: array<vec4<f32>>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= size.width || gid.y >= size.height {
        return;
    }
    let p = gid.y * size.width + gid.x;
    let mask = masks[p];
    var visibility = 1.0;
    if (mask & MASK_SKY) == 0u {
        visibility = f32(16u - countOneBits(mask & MASK_FULL)) / 16.0;
    }
    values[p] = vec4<f32>(0.0, 0.0, 0.0, visibility);
}
