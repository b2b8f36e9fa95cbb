// Refinement, step 3 of 3: after the shadow tracer traced the sample image of refine_gather,
// each listed pixel of the chunk counts the blocked rays of its tile's 16 masks (its 256
// light samples) and overwrites the filter's output with irradiance × (256 − blocked) / 256:
// the whole interleaved pattern that the filter's window could not gather there.
// Dispatched by the renderer, ceil(slots / LINE_GROUP) workgroups.
// CPU twin: src/reference/refine.rs (resolve).

#import shared/groups
#import shared/layout
#import shared/refine

@group(0) @binding(0) var<uniform> params: RefineParams;
@group(0) @binding(1) var<uniform> shade: ShadeParams;
@group(0) @binding(2) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(3) var<storage, read> list: array<u32>;
// The shadow tracer's masks of the sample image (bit j = ray j of the pixel's set blocked).
@group(0) @binding(4) var<storage, read> sample_masks: array<u32>;
// The filter's output; a listed pixel's value is replaced.
@group(0) @binding(5) var<storage, read_write> filtered: array<vec4<f32>>;

@compute @workgroup_size(LINE_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let slot = gid.x;
    if slot >= params.slots {
        return;
    }
    let width = 4u * params.tiles_x;
    let x0 = (slot % params.tiles_x) * 4u;
    let y0 = (slot / params.tiles_x) * 4u;
    var blocked = 0u;
    for (var y = y0; y < y0 + 4u; y++) {
        for (var x = x0; x < x0 + 4u; x++) {
            blocked += countOneBits(sample_masks[y * width + x] & 0xffffu);
        }
    }
    let pixel = list[2u + params.first_slot + slot];
    let visibility = f32(256u - blocked) / 256.0;
    filtered[pixel] = vec4<f32>(unshadowed_irradiance(shade, gbuffer[pixel]) * visibility, visibility);
}
