// One shadow ray traced alone with its own stack (any hit), for the kernels that trace rays
// one per invocation: shadow_per_ray and refine_trace. They declare `params: ShadowParams`,
// `nodes` and `triangles`. CPU twin: reference::shadow::ray_blocked (reference::any_hit).

const STACK_SIZE: u32 = 64u;

var<private> stack: array<u32, 64>;

// Any hit along origin + t dir, 0 < t < t_max; -1 when the budget ran out.
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
    // One step per iteration (a node popped, or one leaf triangle): one loop for lavapipe.
    loop {
        if cursor == end && depth == 0u {
            return 0;
        }
        if iterations >= params.iteration_budget {
            return -1;
        }
        iterations += 1u;
        if cursor < end {
            if intersect_triangle(triangles[cursor], origin, dir, params.t_max).x > 0.0 {
                return 1;
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
    return 0;  // not reached: the loop only returns
}

// Whether the ray from the pixel's shadow-ray origin to `point` is blocked: 1 blocked, 0 free,
// -1 ran out of iterations. Same rules as reference::shadow::initial_mask: a pixel behind the
// light, or a point below the surface's tangent plane, blocks without tracing.
fn ray_blocked(texel: GBufferTexel, point: vec3<f32>) -> i32 {
    let dir = point - texel.origin;
    if dot(params.light_normal, texel.origin - params.light_corners[0].xyz) <= 0.0
        || dot(texel.geo_normal, dir) <= 0.0 {
        return 1;
    }
    return occluded(texel.origin, dir);
}
