// G-buffer from a host's depth and normal textures: world position by unprojecting the depth.
// Recorded by ShadowPass::record (src/gpu/embed/mod.rs) before the shadow pass; CPU twin: src/reference/gbuffer_from_surface.rs.

#import shared/groups
#import shared/layout
#import shared/surface

@group(0) @binding(0) var<uniform> params: SurfaceParams;
@group(0) @binding(1) var depth_texture: texture_depth_2d;
// xyz: world-space shading normal (any length; flipped to the camera's side here).
@group(0) @binding(2) var normal_texture: texture_2d<f32>;
// xyz: world-space geometric normal, or the shading normal again when has_geo_normal == 0.
@group(0) @binding(3) var geo_normal_texture: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> gbuffer: array<GBufferTexel>;
// For the filter: the unit shading normal per pixel, and in w the eye distance (0 = no
// geometry).
@group(0) @binding(5) var<storage, read_write> normal: array<vec4<f32>>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let pixel = vec2<i32>(gid.xy);
    let z = textureLoad(depth_texture, pixel, 0);
    var texel = background_texel();
    if z != params.background_depth {
        let relative = params.clip_to_eye * pixel_clip(params, gid.xy, z);
        let shading = decode_normal(params, textureLoad(normal_texture, pixel, 0).xyz);
        var geometric = shading;
        if params.has_geo_normal != 0u {
            geometric = decode_normal(params, textureLoad(geo_normal_texture, pixel, 0).xyz);
        }
        texel = surface_texel(params, params.eye + relative.xyz / relative.w, shading, geometric);
    }
    let p = gid.y * params.width + gid.x;
    gbuffer[p] = texel;
    normal[p] = vec4<f32>(texel.normal, texel.depth);
}
