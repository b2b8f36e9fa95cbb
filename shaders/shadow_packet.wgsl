// Packet-traced soft shadows, the paper's baseline: one 16-wide vector per pixel, lane = one of its 16 rays.
// Dispatched by the shadow tracer (src/gpu/shadow_tracer.rs, Tracer::Packet); CPU twin: src/reference/shadow_packet.rs.

#import shared/alpha_words
#import shared/bvh
#import shared/counters
#import shared/descend
#import shared/layout
#import shared/suspend
#import shared/intersect
#import shared/vec16
#import shared/bvh_vec16

// Suspended-state slot of a pixel: shared/suspend (status, node,
// mask, cursor, end, alive, stack depth, popping, 16 lane words, 64 stack
// nodes, 64 stack masks); a lane word is 1 when the lane's ray is blocked.
const PACKET_STATE_WORDS: u32 = 160u;


@group(0) @binding(0) var<uniform> params: ShadowParams;
// The BVH as 32-bit words (shared/bvh layouts), read through shared/bvh_vec16.
@group(0) @binding(1) var<storage, read> nodes: array<u32>;
@group(0) @binding(2) var<storage, read> triangles: array<u32>;
@group(0) @binding(3) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(4) var<storage, read> light_points: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> masks: array<u32>;
@group(0) @binding(6) var<storage, read_write> state: array<u32>;
// [WORD_STATUS]: pixels suspended by this dispatch; [1..6]: the Table 1 counters
// (shared/counters, when COUNTERS); [WORD_LOOP_CUT]: pixels whose loop the driver ended.
@group(0) @binding(7) var<storage, read_write> status: array<atomic<u32>>;

@compute @workgroup_size(VEC16_WG_SIZE)
fn main(ids: Vec16Ids) {
    vec16_init(ids);
    // The dispatch's pixels ("tiles" of one pixel), one vector each.
    let slot = g_vector;
    let x = params.tile_origin_x + slot % params.tiles_x;
    let y = params.tile_origin_y + slot / params.tiles_x;
    let base = slot * PACKET_STATE_WORDS;
    // Whether this vector traces a pixel: one of the dispatch's, and on a resume round one
    // that was suspended. A vector that does not still runs the loop's vector operations
    // while others of its workgroup need them (shadow_mft.wgsl), and writes nothing.
    var traces = slot < params.tiles_x * params.tiles_y;
    if traces && params.resume != 0u {
        traces = state[base + ST_STATUS] == STATUS_SUSPENDED;
    }
    if traces && params.resume == 0u && g_lane == 0u {
        // A fresh start: whatever an earlier dispatch left in this slot (another
        // chunk's pixel, another frame's) must not be resumed.
        state[base + ST_STATUS] = 0u;
    }
    let pixel = y * params.width + x;
    let texel = gbuffer[min(pixel, arrayLength(&gbuffer) - 1u)];
    let sky = texel.depth <= 0.0;  // the same in every lane: they read one texel
    if traces && sky && g_lane == 0u {
        masks[pixel] = MASK_SKY;
    }
    let traces_rays = traces && !sky;
    let origin = texel.origin;
    let set_ix = (x & 3u) + 4u * (y & 3u);
    let dir = light_points[set_ix * 16u + g_lane].xyz - origin;
    let inv_dir = safe_inverse(dir);
    let c0 = params.light_corners[0].xyz;
    // Same rules as reference::shadow_per_ray::initial_mask; an idle vector's rays count
    // as blocked, so that no ballot counts them.
    var blocked = !traces_rays || dot(params.light_normal, origin - c0) <= 0.0 || dot(texel.geo_normal, dir) <= 0.0;

    var node = 0u;
    var children = 0u;  // the first child of `node` (when it is an inner node), read when entering it
    var mask = 0u;
    var cursor = 0u;
    var end = 0u;
    var alive = 0u;
    var depth = 0u;
    var popping = 0u;
    var running = false;
    var cut = false;  // a loop of this invocation was ended by the driver
    var n_nodes = 0u;
    var n_boxes = 0u;
    var n_tris = 0u;
    if params.resume != 0u {
        if traces_rays {
            node = state[base + 1u];
            mask = state[base + 2u];
            cursor = state[base + 3u];
            end = state[base + 4u];
            alive = state[base + 5u];
            depth = state[base + 6u];
            popping = state[base + 7u];
            blocked = state[base + ST_LANES + g_lane] != 0u;
            // At most STACK_SIZE passes, counted by lavapipe with the others.
            // Ended by the driver before the stack was read: report it, trace nothing.
            cut = !restore_stack(base, depth);
            running = !cut;
        }
        children = load_node(node).first;
    } else {
        alive = ballot16(!blocked);
        let root = load_node(0u);
        children = root.first;
        mask = ballot16(!blocked & (intersect_box(origin, inv_dir, root, params.t_max) >= 0.0));
        n_boxes = u32(traces_rays);
        running = mask != 0u;
        if root.count > 0u {
            cursor = root.first;
            end = root.first + root.count;
        }
    }

    // One step per iteration, as in shadow_mft.wgsl: a leaf triangle, a stack
    // pop, or an inner node (lavapipe counts every loop pass, so one loop). The
    // loop runs while any vector of the workgroup runs, as there.
    var iterations = 0u;
    var suspended = false;
    loop {
        if !group_any(running) {
            break;
        }
        if iterations >= params.iteration_budget {
            suspended = running;
            break;
        }
        iterations += 1u;
        var enter = false;
        let in_leaf = running && cursor < end;
        let pops = running && !in_leaf && popping != 0u;
        let visits = running && !in_leaf && popping == 0u;
        if group_may(in_leaf) {
            let tri = load_triangle(select(0u, cursor, in_leaf));
            if in_leaf {
                cursor += 1u;
                n_tris += 1u;
                let mine = (mask & alive & (1u << g_lane)) != 0u;
                if mine {
                    let h = intersect_triangle(tri, origin, dir, params.t_max);
                    if h.x > 0.0 && !alpha_passes(tri.alpha, hit_weights(h)) {
                        blocked = true;
                    }
                }
            }
            let leaf_ends = in_leaf && cursor == end;
            if group_any(leaf_ends) {
                let a = ballot16(!blocked);
                if leaf_ends {
                    alive = a;
                    running = a != 0u;
                    popping = 1u;
                }
            }
        }
        if pops {
            if depth == 0u {
                running = false;
            } else {
                depth -= 1u;
                let m = stack_mask[depth] & alive;
                if m != 0u {
                    node = stack_node[depth];
                    mask = m;
                    popping = 0u;
                    enter = true;
                }
            }
        }
        if group_any(visits) {
            // Nodes 0 and 1 for a vector with nothing to visit (GpuScene holds two nodes at least).
            let l = select(0u, children, visits);
            let pair = load_node_pair(l);
            let mine = visits & ((mask & alive & (1u << g_lane)) != 0u);
            let ml = ballot16(mine & (intersect_box(origin, inv_dir, pair[0], params.t_max) >= 0.0));
            let mr = ballot16(mine & (intersect_box(origin, inv_dir, pair[1], params.t_max) >= 0.0));
            if visits {
                n_nodes += 1u;
                n_boxes += 2u;
                // Into the child more rays want first.
                let d = descend(l, ml, mr, countOneBits(mr) > countOneBits(ml));
                if d.later_mask != 0u {
                    // The host checked that the BVH is shallower than the stack.
                    stack_node[min(depth, STACK_SIZE - 1u)] = d.later;
                    stack_mask[min(depth, STACK_SIZE - 1u)] = d.later_mask;
                    depth += 1u;
                }
                if d.mask != 0u {
                    node = d.node;
                    mask = d.mask;
                    enter = true;
                } else {
                    popping = 1u;
                }
            }
        }
        if group_may(enter) {
            let c = load_node(select(0u, node, enter));
            if enter {
                children = c.first;
                if c.count > 0u {
                    cursor = c.first;
                    end = c.first + c.count;
                }
            }
        }
    }
    let bits = ballot16(blocked);
    // The loop stops only by finishing (running = false) or by suspending; left any
    // other way, lavapipe ended it (its per-invocation iteration limit).
    cut = cut || (running && !suspended);
    if COUNTERS && g_lane == 0u {
        // A packet test is one 16-wide test: no culling, every triangle accessed is tested.
        atomicAdd(&status[WORD_NODES_VISITED], n_nodes);
        atomicAdd(&status[WORD_BOX_TESTS], n_boxes);
        atomicAdd(&status[WORD_TRIANGLES_ACCESSED], n_tris);
        atomicAdd(&status[WORD_TRIANGLES_AFTER_CULLING], n_tris);
        atomicAdd(&status[WORD_TRIANGLE_TESTS], n_tris);
    }
    if !traces_rays {
        return;
    }
    if cut {
        // This pixel's mask is incomplete: write none, and let the host fail the pass.
        if g_lane == 0u {
            atomicAdd(&status[WORD_LOOP_CUT], 1u);
        }
        return;
    }
    if suspended {
        state[base + ST_LANES + g_lane] = u32(blocked);
        if g_lane == 0u {
            state[base + ST_STATUS] = STATUS_SUSPENDED;
            state[base + 1u] = node;
            state[base + 2u] = mask;
            state[base + 3u] = cursor;
            state[base + 4u] = end;
            state[base + 5u] = alive;
            state[base + 6u] = depth;
            state[base + 7u] = popping;
            if !save_stack(base, depth) {
                // Ended by the driver: the saved stack is incomplete.
                state[base + ST_STATUS] = 0u;
                atomicAdd(&status[WORD_LOOP_CUT], 1u);
            } else {
                atomicAdd(&status[WORD_STATUS], 1u);
            }
        }
        return;
    }
    if g_lane == 0u {
        masks[pixel] = bits;
        if params.resume != 0u {
            state[base + ST_STATUS] = 0u;
        }
    }
}
