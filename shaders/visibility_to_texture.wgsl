// Copies the visibility (channel a) of a per-pixel value buffer into the host's R32Float texture.
// Recorded by ShadowPass::record (src/gpu/embed/mod.rs) for the unfiltered and the filtered visibility.
// CPU twin: src/reference/visibility.rs.

#import shared/groups
#import shared/surface

@group(0) @binding(0) var<uniform> size: ImageSize;
@group(0) @binding(1) var<storage, read> values: array<vec4<f32>>;
@group(0) @binding(2) var visibility: texture_storage_2d<r32float, write>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= size.width || gid.y >= size.height {
        return;
    }
    let v = values[gid.y * size.width + gid.x].a;
    textureStore(visibility, vec2<i32>(gid.xy), vec4<f32>(v, 0.0, 0.0, 1.0));
}
