// Shading: irradiance from the light centre times the visible fraction (filtered next), and albedo / pi.
// Dispatched by the renderer before the filter; CPU twin: src/reference/shade.rs.

#import shared/groups
#import shared/layout

const PI: f32 = 3.14159265358979;
// 0: masks hold 16 ray bits. Otherwise the reference tracer's count of blocked
// rays out of REFERENCE_RAYS.
override REFERENCE_RAYS: u32 = 0u;

@group(0) @binding(0) var<uniform> params: ShadeParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(2) var<storage, read> masks: array<u32>;
// Outputs for the filter: (radiance rgb, visibility), and the normal with the depth in w.
@group(0) @binding(3) var<storage, read_write> values: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> normal: array<vec4<f32>>;
// Diffuse BRDF albedo / pi (rgb); radiance = brdf * filtered irradiance.
@group(0) @binding(5) var<storage, read_write> brdf: array<vec4<f32>>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let p = gid.y * params.width + gid.x;
    let texel = gbuffer[p];
    let mask = masks[p];
    normal[p] = vec4<f32>(texel.normal, texel.depth);
    brdf[p] = vec4<f32>(texel.albedo / PI, 0.0);
    if (mask & MASK_SKY) != 0u {
        values[p] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return;
    }
    var visibility = f32(16u - countOneBits(mask & 0xffffu)) / 16.0;
    if REFERENCE_RAYS != 0u {
        visibility = 1.0 - f32(mask) / f32(REFERENCE_RAYS);
    }
    values[p] = vec4<f32>(unshadowed_irradiance(params, texel) * visibility, visibility);
}
