// Refinement, step 3 of 3: after the shadow tracer traced the sample image of refine_gather,
// each listed pixel of the chunk counts the blocked rays of the `sets` masks of its block of its
// tile (16 rays each) and overwrites the filter's output with irradiance × (n − blocked) / n, n = 16 sets
// rays: with 16 sets the whole interleaved pattern that the filter's window could not gather there.
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
    let per_tile = 16u / params.sets;
    let tile = slot / per_tile;
    let x0 = (tile % params.tiles_x) * 4u;
    let y0 = (tile / params.tiles_x) * 4u;
    let first_set = (slot % per_tile) * params.sets;
    var blocked = 0u;
    for (var s = first_set; s < first_set + params.sets; s++) {
        blocked += countOneBits(sample_masks[(y0 + s / 4u) * width + x0 + s % 4u] & 0xffffu);
    }
    let pixel = list[2u + params.first_slot + slot];
    let rays = 16u * params.sets;
    let visibility = f32(rays - blocked) / f32(rays);
    filtered[pixel] = vec4<f32>(unshadowed_irradiance(shade, gbuffer[pixel]) * visibility, visibility);
}
