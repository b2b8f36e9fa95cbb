// Per-ray soft shadows, the usual GPU compute tracer: every invocation traces one shadow ray alone with its own stack.
// Dispatched by the shadow tracer (src/gpu/shadow_tracer.rs, Tracer::PerRay and Tracer::Reference);
// CPU twin: src/reference/shadow_per_ray.rs (per_ray_masks for 16 rays, reference_counts).

#import shared/alpha_words
#import shared/bvh
#import shared/counters
#import shared/groups
#import shared/intersect
#import shared/layout
#import shared/pixel_rays

@group(0) @binding(0) var<uniform> params: ShadowParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<BvhTriangle>;
@group(0) @binding(3) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(4) var<storage, read> light_points: array<vec4<f32>>;
// Cleared by the host before the first dispatch; rays OR (or add) into their pixel's word.
@group(0) @binding(5) var<storage, read_write> masks: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> state: array<u32>;
// [WORD_STATUS]: rays that ran out of iterations, [WORD_LOOP_CUT]: rays whose loop the
// driver ended (the host reports either as an error).
@group(0) @binding(7) var<storage, read_write> status: array<atomic<u32>>;

var<private> stack: array<u32, 64>;

// Any hit along origin + t dir, 0 < t < t_max: 1 for a hit, 0 for none; -1 when the
// budget ran out, -2 when the driver ended the loop (lavapipe's iteration limit).
fn occluded(origin: vec3<f32>, dir: vec3<f32>) -> i32 {
    let inv_dir = safe_inverse(dir);
    var depth = 0u;
    if intersect_box(origin, inv_dir, nodes[0], params.t_max) >= 0.0 {
        stack[0] = 0u;
        depth = 1u;
    }
    var cursor = 0u;
    var end = 0u;
    var iterations = 0u;
    var result = 0;
    // One step per iteration (a node popped, or one leaf triangle): one loop for lavapipe.
    loop {
        if cursor == end && depth == 0u {
            break;
        }
        if iterations >= params.iteration_budget {
            result = -1;
            break;
        }
        iterations += 1u;
        if cursor < end {
            let h = intersect_triangle(triangles[cursor], origin, dir, params.t_max);
            if h.x > 0.0 {
                if !alpha_passes(triangles[cursor].alpha, hit_weights(h)) {
                    result = 1;
                    break;
                }
            }
            cursor += 1u;
            continue;
        }
        depth -= 1u;
        let node = nodes[stack[depth]];
        if node.count > 0u {
            cursor = node.first;
            end = node.first + node.count;
            continue;
        }
        // Pushed in the CPU oracle's order, unrolled (a nested loop would count
        // against lavapipe's iteration limit); the host checked the depth fits the stack.
        let l = node.first;
        if intersect_box(origin, inv_dir, nodes[l], params.t_max) >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l;
            depth += 1u;
        }
        if intersect_box(origin, inv_dir, nodes[l + 1u], params.t_max) >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l + 1u;
            depth += 1u;
        }
    }
    // Every break above sets `result` or leaves nothing to visit; anything else means the
    // driver ended the loop. (The test reads the loop's own state, not a flag set at the
    // breaks, which a compiler could prove always set.)
    if result == 0 && (cursor != end || depth != 0u) {
        return -2;
    }
    return result;
}

@compute @workgroup_size(LINE_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let ray = start_pixel_ray(gid.x + gid.y * groups.x * LINE_GROUP);
    if !ray.live {
        return;
    }
    var blocked = ray.blocked;
    if !blocked {
        let hit = occluded(ray.origin, ray.dir);
        if hit == -1 {
            atomicAdd(&status[WORD_STATUS], 1u);
            return;
        }
        if hit == -2 {
            atomicAdd(&status[WORD_LOOP_CUT], 1u);
            return;
        }
        blocked = hit == 1;
    }
    if blocked {
        record_blocked(ray);
    }
}
