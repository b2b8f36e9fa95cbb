// Primary visibility: one closest-hit camera ray per pixel, written as a G-buffer texel.
// Dispatched by the primary pass (src/gpu/primary_pass.rs, PrimaryTracer::PerRay); CPU twin: src/reference/primary.rs.

#import shared/bvh
#import shared/counters
#import shared/groups
#import shared/intersect
#import shared/layout
#import shared/primary

@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<BvhTriangle>;

// The triangle a ray hit, for shared/primary's texel.
fn hit_triangle(t: u32) -> BvhTriangle {
    return triangles[t];
}

// Pushes both children of a node: the stack holds at most depth + 1 entries.

@compute @workgroup_size(PIXEL_GROUP, PIXEL_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= camera.width || gid.y >= camera.height {
        return;
    }
    let dir = pixel_dir(gid.x, gid.y);
    let origin = camera.eye;
    let inv_dir = safe_inverse(dir);

    var best = vec3<f32>(-1.0, 0.0, 0.0);
    var best_tri = 0xffffffffu;
    var t_best = 3.4028234663852886e38;
    var stack: array<u32, 64>;
    var depth = 0u;
    var cursor = 0u;  // next triangle of the current leaf
    var end = 0u;     // end of the current leaf's triangles
    // Work counters (shared/counters); dead code unless COUNTERS.
    var n_steps = 0u;
    var n_box_tests = 1u;  // the root's
    var n_triangles = 0u;
    if intersect_box(origin, inv_dir, nodes[0], t_best) >= 0.0 {
        stack[0] = 0u;
        depth = 1u;
    }
    // One loop, one step per iteration (a leaf triangle or a node): lavapipe
    // counts iterations of every loop an iteration reaches, nested ones too,
    // so a nested leaf loop would let its limit strike before ours.
    var iterations = 0u;
    loop {
        if cursor >= end && depth == 0u {
            break;
        }
        iterations += 1u;
        if iterations > ITERATION_BUDGET {
            break;
        }
        if cursor < end {
            let tri = triangles[cursor];
            let h = intersect_triangle(tri, origin, dir, t_best);
            n_triangles += 1u;
            if h.x >= 0.0 && !passes_alpha(tri, cursor, h) {
                t_best = h.x;
                best = h;
                best_tri = cursor;
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
        n_steps += 1u;
        n_box_tests += 2u;
        let l = node.first;
        let tl = intersect_box(origin, inv_dir, nodes[l], t_best);
        let tr = intersect_box(origin, inv_dir, nodes[l + 1u], t_best);
        if tl >= 0.0 && tr >= 0.0 {
            // Farther child below, nearer on top.
            let near_left = tl <= tr;
            stack[min(depth, STACK_SIZE - 1u)] = select(l, l + 1u, near_left);
            stack[min(depth + 1u, STACK_SIZE - 1u)] = select(l + 1u, l, near_left);
            depth += 2u;
        } else if tl >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l;
            depth += 1u;
        } else if tr >= 0.0 {
            stack[min(depth, STACK_SIZE - 1u)] = l + 1u;
            depth += 1u;
        }
    }
    // From the loop's own state (a flag set at the breaks a compiler could prove set):
    // work left and budget left means the driver ended the loop (lavapipe's limit).
    let overflow = iterations > ITERATION_BUDGET;
    if overflow {
        atomicAdd(&status[WORD_STATUS], 1u);
    } else if cursor < end || depth != 0u {
        atomicAdd(&status[WORD_LOOP_CUT], 1u);
    }
    if COUNTERS {
        // No culling here: every triangle fetched is tested.
        atomicAdd(&status[WORD_NODES_VISITED], n_steps);
        atomicAdd(&status[WORD_BOX_TESTS], n_box_tests);
        atomicAdd(&status[WORD_TRIANGLES_ACCESSED], n_triangles);
        atomicAdd(&status[WORD_TRIANGLES_AFTER_CULLING], n_triangles);
        atomicAdd(&status[WORD_TRIANGLE_TESTS], n_triangles);
    }
    gbuffer[gid.y * camera.width + gid.x] = gbuffer_texel(best_tri, best, dir);
}
