// Refinement, step 2 of 3: builds the sample image of a chunk of the pixels refine_select
// listed (shared/refine: one 4×4 tile of copies of the pixel's G-buffer texel per pixel),
// which the frame's own shadow tracer then traces like any image (step 3 is refine_resolve).
// Tile pixels past the chunk's last slot get sky texels (no rays).
// Dispatched by the renderer, ceil(width / PIXEL_GROUP) × ceil(height / PIXEL_GROUP) workgroups over the sample image.
// CPU twin: src/reference/refine.rs (sample_image).

#import shared/groups
#import shared/layout
#import shared/refine

@group(0) @binding(0) var<uniform> params: RefineParams;
@group(0) @binding(1) var<storage, read> gbuffer: array<GBufferTexel>;
// As refine_select left it: [0] pixels listed, [2 + i] the i-th pixel's index.
@group(0) @binding(2) var<storage, read> list: array<u32>;
// The sample image, 4 tiles_x wide, row-major.
@group(0) @binding(3) var<storage, read_write> samples: array<GBufferTexel>;

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let per_tile = 16u / params.sets;
    let tiles = (params.slots + per_tile - 1u) / per_tile;
    let width = 4u * params.tiles_x;
    let height = 4u * ((tiles + params.tiles_x - 1u) / params.tiles_x);
    if gid.x >= width || gid.y >= height {
        return;
    }
    let tile = (gid.y / 4u) * params.tiles_x + gid.x / 4u;
    let sample_set = (gid.x % 4u) + 4u * (gid.y % 4u);
    let slot = tile * per_tile + sample_set / params.sets;
    var texel = GBufferTexel();
    texel.triangle = 0xffffffffu;
    if slot < params.slots {
        texel = gbuffer[list[2u + params.first_slot + slot]];
    }
    samples[gid.y * width + gid.x] = texel;
}
