// Multi-frusta soft shadows: one 16-wide vector per 4x4 tile, lane = pixel = frustum of 16 rays.
// Dispatched by the shadow pass (src/gpu/shadow_pass.rs); CPU twin: src/reference/mft.rs.

#import shared/bvh
#import shared/frame
#import shared/vec16

const STACK_SIZE: u32 = 64u;
const MASK_FULL: u32 = 0xffffu;
const MASK_SKY: u32 = 0x10000u;
// Suspended-state slot of a tile: status, node, mask, cursor, end, alive,
// stack depth, popping, 16 lane masks, 64 stack nodes, 64 stack masks.
const STATE_WORDS: u32 = 160u;
const ST_STATUS: u32 = 0u;
const ST_LANES: u32 = 8u;
const ST_STACK_NODE: u32 = 24u;
const ST_STACK_MASK: u32 = 88u;
const STATUS_SUSPENDED: u32 = 1u;

@group(0) @binding(0) var<uniform> params: ShadowParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> triangles: array<BvhTriangle>;
@group(0) @binding(3) var<storage, read> gbuffer: array<GBufferTexel>;
@group(0) @binding(4) var<storage, read> light_points: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> masks: array<u32>;
@group(0) @binding(6) var<storage, read_write> state: array<u32>;
// [0]: tiles suspended by this dispatch.
@group(0) @binding(7) var<storage, read_write> status: array<atomic<u32>>;

// This lane's frustum.
var<private> f_origin: vec3<f32>;
var<private> f_geo: vec3<f32>;
var<private> f_side: array<vec3<f32>, 4>;
var<private> f_dirs: array<vec3<f32>, 16>;
var<private> f_occluded: u32;

// The vector's traversal stack (the same in every lane).
var<private> stack_node: array<u32, 64>;
var<private> stack_mask: array<u32, 64>;

fn corner(k: u32) -> vec3<f32> {
    return params.light_corners[k].xyz;
}

fn is_done() -> bool {
    return (f_occluded & MASK_SKY) != 0u || (f_occluded & MASK_FULL) == MASK_FULL;
}

// Same rules as reference::shadow::initial_mask.
fn setup_frustum(texel: GBufferTexel, sample_set: u32, inside: bool) {
    f_origin = texel.origin;
    f_geo = texel.geo_normal;
    let o = f_origin;
    let centre = (corner(0u) + corner(2u)) * 0.5;
    for (var k = 0u; k < 4u; k++) {
        let n = cross(corner(k) - o, corner((k + 1u) % 4u) - o);
        f_side[k] = select(n, -n, dot(n, centre - o) < 0.0);
    }
    var below = 0u;
    for (var j = 0u; j < 16u; j++) {
        let d = light_points[sample_set * 16u + j].xyz - o;
        f_dirs[j] = d;
        below |= select(0u, 1u << j, dot(f_geo, d) <= 0.0);
    }
    if !inside || texel.depth <= 0.0 {
        f_occluded = MASK_SKY;
    } else if dot(params.light_normal, o - corner(0u)) <= 0.0 {
        f_occluded = MASK_FULL;
    } else {
        f_occluded = below;
    }
}

fn box_outside(n: vec3<f32>, p0: vec3<f32>, node: BvhNode) -> bool {
    let p = select(node.bmin, node.bmax, n > vec3<f32>(0.0));
    return dot(n, p - p0) < 0.0;
}

fn frustum_may_hit_box(node: BvhNode) -> bool {
    return !(box_outside(f_side[0], f_origin, node) || box_outside(f_side[1], f_origin, node)
        || box_outside(f_side[2], f_origin, node) || box_outside(f_side[3], f_origin, node)
        || box_outside(f_geo, f_origin, node) || box_outside(params.light_normal, corner(0u), node));
}

fn all_outside(n: vec3<f32>, b0: vec3<f32>, b1: vec3<f32>, b2: vec3<f32>) -> bool {
    return dot(n, b0) < 0.0 && dot(n, b1) < 0.0 && dot(n, b2) < 0.0;
}

fn edge_culls(m: vec3<f32>, d: f32, k0: vec3<f32>, k1: vec3<f32>, k2: vec3<f32>, k3: vec3<f32>) -> bool {
    let s = vec4<f32>(dot(m, k0), dot(m, k1), dot(m, k2), dot(m, k3));
    return select(all(s > vec4<f32>(0.0)), all(s < vec4<f32>(0.0)), d > 0.0);
}

fn ray_bit(j: u32, m0: vec3<f32>, m1: vec3<f32>, m2: vec3<f32>, d: f32, limit: f32) -> u32 {
    let dir = f_dirs[j];
    let s0 = dot(m0, dir);
    let s1 = dot(m1, dir);
    let s2 = dot(m2, dir);
    let inside = select(s0 <= 0.0 && s1 <= 0.0 && s2 <= 0.0, s0 >= 0.0 && s1 >= 0.0 && s2 >= 0.0, d > 0.0);
    return select(0u, 1u << j, inside && limit < params.t_max * abs(s0 + s1 + s2));
}

// Culls the triangle against this lane's frustum, else tests its 16 rays;
// the arithmetic of reference::mft::frustum_test_triangle, in the same order.
fn test_triangle(tri: BvhTriangle) -> u32 {
    let o = f_origin;
    let v0 = tri.v0;
    let v1 = tri.v0 + tri.e1;
    let v2 = tri.v0 + tri.e2;
    let a0 = v0 - o;
    let a1 = v1 - o;
    let a2 = v2 - o;
    let c0 = corner(0u);
    if all_outside(f_side[0], a0, a1, a2) || all_outside(f_side[1], a0, a1, a2)
        || all_outside(f_side[2], a0, a1, a2) || all_outside(f_side[3], a0, a1, a2)
        || all_outside(f_geo, a0, a1, a2)
        || all_outside(params.light_normal, v0 - c0, v1 - c0, v2 - c0) {
        return 0u;
    }
    let m0 = cross(a0, a1);
    let m1 = cross(a1, a2);
    let m2 = cross(a2, a0);
    let d = dot(m0, a2);
    if d == 0.0 {
        return 0u;
    }
    let k0 = c0 - o;
    let k1 = corner(1u) - o;
    let k2 = corner(2u) - o;
    let k3 = corner(3u) - o;
    if edge_culls(m0, d, k0, k1, k2, k3) || edge_culls(m1, d, k0, k1, k2, k3) || edge_culls(m2, d, k0, k1, k2, k3) {
        return 0u;
    }
    let limit = abs(d);
    // Unrolled on purpose: every loop iteration counts towards lavapipe's limit.
    return ray_bit(0u, m0, m1, m2, d, limit) | ray_bit(1u, m0, m1, m2, d, limit)
        | ray_bit(2u, m0, m1, m2, d, limit) | ray_bit(3u, m0, m1, m2, d, limit)
        | ray_bit(4u, m0, m1, m2, d, limit) | ray_bit(5u, m0, m1, m2, d, limit)
        | ray_bit(6u, m0, m1, m2, d, limit) | ray_bit(7u, m0, m1, m2, d, limit)
        | ray_bit(8u, m0, m1, m2, d, limit) | ray_bit(9u, m0, m1, m2, d, limit)
        | ray_bit(10u, m0, m1, m2, d, limit) | ray_bit(11u, m0, m1, m2, d, limit)
        | ray_bit(12u, m0, m1, m2, d, limit) | ray_bit(13u, m0, m1, m2, d, limit)
        | ray_bit(14u, m0, m1, m2, d, limit) | ray_bit(15u, m0, m1, m2, d, limit);
}

@compute @workgroup_size(VEC16_WG_SIZE)
fn main(ids: Vec16Ids) {
    vec16_init(ids);
    let slot = g_vector;
    if slot >= params.tiles_x * params.tiles_y {
        return;  // past the last tile of the dispatch (uniform: per vector)
    }
    let tx = params.tile_origin_x + slot % params.tiles_x;
    let ty = params.tile_origin_y + slot / params.tiles_x;
    let x = tx * 4u + (g_lane & 3u);
    let y = ty * 4u + (g_lane >> 2u);
    let inside = x < params.width && y < params.height;
    let pixel = y * params.width + x;
    let base = slot * STATE_WORDS;
    if params.resume != 0u && uniform16(state[base + ST_STATUS]) != STATUS_SUSPENDED {
        return;
    }
    setup_frustum(gbuffer[min(pixel, arrayLength(&gbuffer) - 1u)], g_lane, inside);

    // The traversal state; every lane holds the same values.
    var node = 0u;      // inner node to visit next (when not in a leaf)
    var mask = 0u;      // frusta that entered `node`
    var cursor = 0u;    // next triangle of the current leaf
    var end = 0u;       // end of the current leaf's triangles
    var alive = 0u;     // frusta not yet done
    var depth = 0u;     // stack depth
    var popping = 0u;   // 1: the next step pops the stack
    var running = true;
    if params.resume != 0u {
        node = uniform16(state[base + 1u]);
        mask = uniform16(state[base + 2u]);
        cursor = uniform16(state[base + 3u]);
        end = uniform16(state[base + 4u]);
        alive = uniform16(state[base + 5u]);
        depth = uniform16(state[base + 6u]);
        popping = uniform16(state[base + 7u]);
        f_occluded = state[base + ST_LANES + g_lane];
        for (var i = 0u; i < depth; i++) {
            stack_node[i] = uniform16(state[base + ST_STACK_NODE + i]);
            stack_mask[i] = uniform16(state[base + ST_STACK_MASK + i]);
        }
    } else {
        alive = ballot16(!is_done());
        let root = nodes[0];
        mask = ballot16(!is_done() && frustum_may_hit_box(root));
        running = mask != 0u;
        if root.count > 0u {
            cursor = root.first;
            end = root.first + root.count;
        }
    }

    // One step per iteration: one triangle of a leaf, one stack pop, or one
    // inner node; steps are counted so no loop runs into lavapipe's limit.
    var iterations = 0u;
    loop {
        if !running {
            break;
        }
        if iterations == params.iteration_budget {
            // Out of budget: save the state; the next dispatch resumes this tile.
            state[base + ST_LANES + g_lane] = f_occluded;
            if g_lane == 0u {
                state[base + ST_STATUS] = STATUS_SUSPENDED;
                state[base + 1u] = node;
                state[base + 2u] = mask;
                state[base + 3u] = cursor;
                state[base + 4u] = end;
                state[base + 5u] = alive;
                state[base + 6u] = depth;
                state[base + 7u] = popping;
                for (var i = 0u; i < depth; i++) {
                    state[base + ST_STACK_NODE + i] = stack_node[i];
                    state[base + ST_STACK_MASK + i] = stack_mask[i];
                }
                atomicAdd(&status[0], 1u);
            }
            return;
        }
        iterations += 1u;
        var enter = false;
        if cursor < end {
            let tri = triangles[cursor];
            cursor += 1u;
            if (mask & (1u << g_lane)) != 0u && !is_done() {
                f_occluded |= test_triangle(tri);
            }
            if cursor == end {
                alive = ballot16(!is_done());
                running = alive != 0u;
                popping = 1u;
            }
        } else if popping != 0u {
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
        } else {
            let l = nodes[node].first;
            let mine = (mask & (1u << g_lane)) != 0u && !is_done();
            let ml = ballot16(mine && frustum_may_hit_box(nodes[l]));
            let mr = ballot16(mine && frustum_may_hit_box(nodes[l + 1u]));
            if ml != 0u && mr != 0u {
                // Descend into the child more frusta want; keep the other for later.
                let right_first = countOneBits(mr) > countOneBits(ml);
                node = select(l, l + 1u, right_first);
                mask = select(ml, mr, right_first);
                // The host checked that the BVH is shallower than the stack.
                stack_node[min(depth, STACK_SIZE - 1u)] = select(l + 1u, l, right_first);
                stack_mask[min(depth, STACK_SIZE - 1u)] = select(mr, ml, right_first);
                depth += 1u;
                enter = true;
            } else if ml != 0u {
                node = l;
                mask = ml;
                enter = true;
            } else if mr != 0u {
                node = l + 1u;
                mask = mr;
                enter = true;
            } else {
                popping = 1u;
            }
        }
        if enter {
            let c = nodes[node];
            if c.count > 0u {
                cursor = c.first;
                end = c.first + c.count;
            }
        }
    }
    if inside {
        masks[pixel] = f_occluded;
    }
    if g_lane == 0u && params.resume != 0u {
        state[base + ST_STATUS] = 0u;
    }
}
