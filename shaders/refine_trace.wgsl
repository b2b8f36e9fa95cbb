// Refinement, step 2 of 2: every pixel refine_select listed traces the 240 light samples of the
// other 15 sample sets (one workgroup per pixel, one ray per invocation, as shadow_per_ray),
// adds the 16 rays of its own set from the shadow pass's mask, and overwrites the filter's
// output with irradiance × (rays that reach the light) / 256: the whole interleaved pattern that
// the filter's window could not gather there, and no averaging across the cut.
// Dispatched by the renderer after refine_select, one workgroup per listed pixel (2D grid).
// CPU twin: penumbra::reference::refine::refined_value.

#import shared/bvh
#import shared/frame
#import shared/intersect
#import shared/occluded

// Rays of the other 15 sets: invocation j traces sample j mod 16 of set own + 1 + j / 16 (mod 16).
const OTHER_RAYS: u32 = 240u;

@group(0) @binding(0) var<uniform> params: ShadowParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<BvhTriangle>;
@group(0) @binding(3) var<storage, read> gbuffer: array<GBufferTexel>;
// All 256 points in set order: [16 k + j] = sample j of set k.
@group(0) @binding(4) var<storage, read> light_points: array<vec4<f32>>;
// The shadow pass's masks: bit j = ray j of the pixel's own set blocked.
@group(0) @binding(5) var<storage, read> masks: array<u32>;
@group(0) @binding(6) var<uniform> shade: ShadeParams;
// As refine_select left it; [1] counts the rays that ran out of iterations (the host reports them).
@group(0) @binding(7) var<storage, read_write> list: array<atomic<u32>>;
// The filter's output; a listed pixel's value is replaced.
@group(0) @binding(8) var<storage, read_write> filtered: array<vec4<f32>>;

var<workgroup> blocked_rays: atomic<u32>;
var<workgroup> ran_out: atomic<u32>;

@compute @workgroup_size(OTHER_RAYS)
fn main(
    @builtin(local_invocation_index) j: u32,
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if j == 0u {
        // Workgroup memory is not zeroed for us (the pipelines skip it).
        atomicStore(&blocked_rays, 0u);
        atomicStore(&ran_out, 0u);
    }
    workgroupBarrier();
    let slot = wg.x + wg.y * groups.x;
    let listed = slot < atomicLoad(&list[0]);
    var pixel = 0u;
    if listed {
        pixel = atomicLoad(&list[2u + slot]);
        let x = pixel % params.width;
        let y = pixel / params.width;
        let sample_set = ((x & 3u) + 4u * (y & 3u) + 1u + j / 16u) % 16u;
        let blocked = ray_blocked(gbuffer[pixel], light_points[sample_set * 16u + j % 16u].xyz);
        if blocked < 0 {
            atomicAdd(&ran_out, 1u);
        } else if blocked == 1 {
            atomicAdd(&blocked_rays, 1u);
        }
    }
    workgroupBarrier();
    if j != 0u || !listed {
        return;
    }
    let out_of_budget = atomicLoad(&ran_out);
    if out_of_budget > 0u {
        atomicAdd(&list[1], out_of_budget);
        return;
    }
    let blocked = atomicLoad(&blocked_rays) + countOneBits(masks[pixel] & 0xffffu);
    let visibility = f32(256u - blocked) / 256.0;
    filtered[pixel] = vec4<f32>(unshadowed_irradiance(shade, gbuffer[pixel]) * visibility, visibility);
}
