// Primary visibility with multi-frusta: one 16-wide vector per 16x16 pixel block, lane = 4x4-pixel frustum, closest hit per ray.
// Dispatched by the primary pass (src/gpu/primary_pass.rs, PrimaryTracer::Mft); CPU twin: src/reference/primary_mft.rs.

#import shared/bvh
#import shared/counters
#import shared/descend
#import shared/layout
#import shared/intersect
#import shared/primary
#import shared/vec16
#import shared/bvh_vec16

// Lane i owns frustum i: the 16 pixels (x0 + k % 4, y0 + k / 4), k = 0..16, with
// x0 = 16 bx + 4 (i % 4), y0 = 16 by + 4 (i / 4). Its rays share the eye, so its
// frustum is the pyramid from the eye through the four pixel-edge corners of
// the 4x4 footprint (clipped to the image): every pixel-centre ray lies inside
// it by half a pixel, a margin far above f32 rounding, so the plane tests
// below never cull a box or triangle one of its rays hits.
//
// Depth: forward is a unit vector and right, up are orthogonal to it, so every
// camera ray has dot(dir, forward) = 1 and reaches a point p at
// t = dot(p - eye, forward). No ray can meet a box (triangle) before its
// nearest corner's (vertex's) depth, so once every ray of a frustum has a hit
// nearer than that, the frustum drops it. DEPTH_SLACK keeps that conservative
// against the rounding of the hit's t (Moller-Trumbore's t is exact to far
// better than 1e-3 except at grazing angles that no test scene reaches).
//
// Ties: each ray keeps the first hit with a strictly smaller t, as the
// per-ray kernel does; the traversal order differs, so where two triangles
// give one ray exactly the same t the two kernels may keep different ones.

// Bindings 1 and 2 of the primary pass (shared/primary), as words: read by shared/bvh_vec16.
@group(0) @binding(1) var<storage, read> nodes: array<u32>;
@group(0) @binding(2) var<storage, read> triangles: array<u32>;

// The triangle a lane's ray hit, for shared/primary's texel (lanes differ).
fn hit_triangle(t: u32) -> BvhTriangle {
    return triangle_from_memory(t);
}

const DEPTH_SLACK: f32 = 1.001;
const T_NONE: f32 = 3.4028234663852886e38;
const NO_TRIANGLE: u32 = 0xffffffffu;

// This lane's frustum and its 16 rays (indexed only with constants, so that
// they stay in registers: the code that touches them is unrolled by hand).
var<private> f_dirs: array<vec3<f32>, 16>;
var<private> f_best: array<vec3<f32>, 16>;  // (t, u, v) of the closest hit so far
var<private> f_tri: array<u32, 16>;         // its triangle, NO_TRIANGLE for none
var<private> f_t: array<f32, 16>;           // its t: T_NONE, or 0 for a ray outside the image
var<private> f_t_max: f32;                  // max of f_t
var<private> f_side: array<vec3<f32>, 4>;   // inward normals of the side planes through the eye
var<private> f_corner: array<vec3<f32>, 4>; // the corner-ray directions
var<private> f_x0: u32;
var<private> f_y0: u32;

// The vector's traversal stack (the same in every lane): a node's first child or
// triangle and its triangle count (as in BvhNode, so a pop needs no node load), the
// frusta that want it, and its box's depth (to drop frusta whose rays have all hit nearer).
var<private> stack_first: array<u32, 64>;
var<private> stack_count: array<u32, 64>;
var<private> stack_mask: array<u32, 64>;
var<private> stack_depth: array<f32, 64>;

// The direction through the pixel-edge point (ex, ey) of the image.
fn edge_dir(ex: u32, ey: u32) -> vec3<f32> {
    let sx = 2.0 * f32(ex + camera.origin_x) / f32(camera.image_width) - 1.0;
    let sy = 1.0 - 2.0 * f32(ey + camera.origin_y) / f32(camera.image_height);
    return camera.forward + sx * camera.right + sy * camera.up;
}

// Ray k of this lane; a bit of the returned mask when its pixel is in the image.
fn setup_ray(k: u32) -> u32 {
    let x = f_x0 + (k & 3u);
    let y = f_y0 + (k >> 2u);
    let inside = x < camera.width && y < camera.height;
    f_dirs[k] = pixel_dir(x, y);
    f_best[k] = vec3<f32>(-1.0, 0.0, 0.0);
    f_tri[k] = NO_TRIANGLE;
    f_t[k] = select(0.0, T_NONE, inside);
    return select(0u, 1u << k, inside);
}

fn side_plane(k: u32, centre: vec3<f32>) {
    let n = cross(f_corner[k], f_corner[(k + 1u) % 4u]);
    f_side[k] = select(n, -n, dot(n, centre) < 0.0);
}

// Sets up this lane's frustum; returns the mask of its rays inside the image.
fn setup_frustum(x0: u32, y0: u32) -> u32 {
    f_x0 = x0;
    f_y0 = y0;
    let inside = setup_ray(0u) | setup_ray(1u) | setup_ray(2u) | setup_ray(3u)
        | setup_ray(4u) | setup_ray(5u) | setup_ray(6u) | setup_ray(7u)
        | setup_ray(8u) | setup_ray(9u) | setup_ray(10u) | setup_ray(11u)
        | setup_ray(12u) | setup_ray(13u) | setup_ray(14u) | setup_ray(15u);
    f_t_max = select(0.0, T_NONE, inside != 0u);
    // Clipped to the image; meaningless (and never used) for a lane with no pixel.
    let x1 = min(x0 + 4u, camera.width);
    let y1 = min(y0 + 4u, camera.height);
    f_corner[0] = edge_dir(x0, y0);
    f_corner[1] = edge_dir(x1, y0);
    f_corner[2] = edge_dir(x1, y1);
    f_corner[3] = edge_dir(x0, y1);
    let centre = f_corner[0] + f_corner[2];
    side_plane(0u, centre);
    side_plane(1u, centre);
    side_plane(2u, centre);
    side_plane(3u, centre);
    return inside;
}

// Depth of the box's nearest corner along the view direction (see the top).
fn box_depth(node: BvhNode) -> f32 {
    let p = select(node.bmax, node.bmin, camera.forward > vec3<f32>(0.0));
    return dot(camera.forward, p - camera.eye);
}

// The traversal order: the child whose centre lies nearer along `order_dir` first.
fn order_key(node: BvhNode, order_dir: vec3<f32>) -> f32 {
    return dot((node.bmin + node.bmax) * 0.5 - camera.eye, order_dir);
}

fn box_outside(n: vec3<f32>, node: BvhNode) -> bool {
    let p = select(node.bmin, node.bmax, n > vec3<f32>(0.0));
    return dot(n, p - camera.eye) < 0.0;
}

// Whether a ray of this frustum may meet the box before its closest hit so far.
// Branch-free (`&`, `|`, not `&&`, `||`): it is a ballot's predicate, and a short-circuit
// operator is a lane-divergent branch right before the ballot.
fn frustum_may_hit_box(node: BvhNode, depth: f32) -> bool {
    return (depth <= f_t_max * DEPTH_SLACK)
        & !(box_outside(f_side[0], node) | box_outside(f_side[1], node)
            | box_outside(f_side[2], node) | box_outside(f_side[3], node));
}

fn all_outside(n: vec3<f32>, a0: vec3<f32>, a1: vec3<f32>, a2: vec3<f32>) -> bool {
    return dot(n, a0) < 0.0 && dot(n, a1) < 0.0 && dot(n, a2) < 0.0;
}

// All four corner rays lie strictly outside the edge plane with normal m
// (d: the orientation of the triangle seen from the eye).
fn edge_culls(m: vec3<f32>, d: f32) -> bool {
    let s = vec4<f32>(dot(m, f_corner[0]), dot(m, f_corner[1]), dot(m, f_corner[2]), dot(m, f_corner[3]));
    return select(all(s > vec4<f32>(0.0)), all(s < vec4<f32>(0.0)), d > 0.0);
}

// No ray of this frustum can hit the triangle before its closest hit so far:
// the triangle is nearer than no ray's hit, outside a side plane, or (corner
// rays) the whole frustum passes outside one of its edges.
fn frustum_culls_triangle(tri: BvhTriangle) -> bool {
    let a0 = tri.v0 - camera.eye;
    let a1 = tri.v1 - camera.eye;
    let a2 = tri.v2 - camera.eye;
    let f = camera.forward;
    let near = min(min(dot(f, a0), dot(f, a1)), dot(f, a2));
    if near > f_t_max * DEPTH_SLACK {
        return true;
    }
    if all_outside(f_side[0], a0, a1, a2) || all_outside(f_side[1], a0, a1, a2)
        || all_outside(f_side[2], a0, a1, a2) || all_outside(f_side[3], a0, a1, a2) {
        return true;
    }
    let m0 = cross(a0, a1);
    let m1 = cross(a1, a2);
    let m2 = cross(a2, a0);
    let d = dot(m0, a2);
    if d == 0.0 {
        // The eye lies in the triangle's plane (as far as f32 can tell): left to the ray tests.
        return false;
    }
    return edge_culls(m0, d) || edge_culls(m1, d) || edge_culls(m2, d);
}

// The ray-independent part of the per-ray kernel's Moller-Trumbore test
// (shared/intersect) for rays from the eye: the same values in the same order.
struct EyeTriangle {
    e1: vec3<f32>,
    e2: vec3<f32>,
    s: vec3<f32>,
    q: vec3<f32>,
}

// Ray k against triangle `ix` (its alpha test's record `a`, read when `alpha_tested`):
// exactly the per-ray kernel's test and update, with selects instead of its early returns
// (the same result; of 16 unrolled copies only the alpha test's texel load branches).
fn test_ray(k: u32, et: EyeTriangle, alpha_tested: bool, a: SurfaceAlpha, ix: u32) {
    let dir = f_dirs[k];
    let p = cross(dir, et.e2);
    let det = dot(et.e1, p);
    let inv_det = 1.0 / det;
    let u = dot(et.s, p) * inv_det;
    let v = dot(dir, et.q) * inv_det;
    let t = dot(et.e2, et.q) * inv_det;
    // The negations of shared/intersect's early-return conditions (a NaN fails every compare).
    let hit = (det != 0.0) & !((u < 0.0) | (u > 1.0)) & !((v < 0.0) | (u + v > 1.0))
        & (t > 0.0) & (t < f_t[k]);
    let h = vec3<f32>(t, u, v);
    var passes = false;
    if alpha_tested & hit {
        passes = surface_passes(a, h);
    }
    let keep = hit & !passes;
    f_t[k] = select(f_t[k], t, keep);
    f_best[k] = select(f_best[k], h, keep);
    f_tri[k] = select(f_tri[k], ix, keep);
}

// All 16 rays (unrolled: every loop iteration counts towards lavapipe's limit).
fn test_rays(tri: BvhTriangle, ix: u32) {
    var et: EyeTriangle;
    et.e1 = tri.v1 - tri.v0;
    et.e2 = tri.v2 - tri.v0;
    et.s = camera.eye - tri.v0;
    et.q = cross(et.s, et.e1);
    // The alpha test's record read once per triangle, each ray's test one texel load: 16
    // copies of the whole test, each loading the record behind two branches, made Mesa 25
    // lavapipe's first compile of this kernel take over a minute (LLVM's coroutine split).
    // (Without the rays' branch, the load for every ray: faster on Mesa 22.3, slower on 25.0.)
    let alpha_tested = ALPHA_TEST && tri.alpha != ALPHA_OPAQUE;
    var a = SurfaceAlpha(vec2<f32>(0.0), vec2<f32>(0.0), vec2<f32>(0.0), 1.0, 0.0, false, 0u, 1u, 1u);
    if alpha_tested {
        a = surface_alpha(ix);
    }
    test_ray(0u, et, alpha_tested, a, ix);
    test_ray(1u, et, alpha_tested, a, ix);
    test_ray(2u, et, alpha_tested, a, ix);
    test_ray(3u, et, alpha_tested, a, ix);
    test_ray(4u, et, alpha_tested, a, ix);
    test_ray(5u, et, alpha_tested, a, ix);
    test_ray(6u, et, alpha_tested, a, ix);
    test_ray(7u, et, alpha_tested, a, ix);
    test_ray(8u, et, alpha_tested, a, ix);
    test_ray(9u, et, alpha_tested, a, ix);
    test_ray(10u, et, alpha_tested, a, ix);
    test_ray(11u, et, alpha_tested, a, ix);
    test_ray(12u, et, alpha_tested, a, ix);
    test_ray(13u, et, alpha_tested, a, ix);
    test_ray(14u, et, alpha_tested, a, ix);
    test_ray(15u, et, alpha_tested, a, ix);
    f_t_max = max(max(max(max(f_t[0], f_t[1]), max(f_t[2], f_t[3])), max(max(f_t[4], f_t[5]), max(f_t[6], f_t[7]))),
        max(max(max(f_t[8], f_t[9]), max(f_t[10], f_t[11])), max(max(f_t[12], f_t[13]), max(f_t[14], f_t[15]))));
}

// Ray k's texel. The rays' arrays are read with constant indices only (selects), so that
// they stay registers; the texel's code, with its loads, then exists once, in main's loop
// over k: 16 unrolled copies made lavapipe 25.0's compile of this kernel several times
// slower (LLVM's coroutine split).
fn write_texel(k: u32) {
    var tri = f_tri[0];
    var best = f_best[0];
    var dir = f_dirs[0];
    tri = select(tri, f_tri[1], k == 1u);
    best = select(best, f_best[1], k == 1u);
    dir = select(dir, f_dirs[1], k == 1u);
    tri = select(tri, f_tri[2], k == 2u);
    best = select(best, f_best[2], k == 2u);
    dir = select(dir, f_dirs[2], k == 2u);
    tri = select(tri, f_tri[3], k == 3u);
    best = select(best, f_best[3], k == 3u);
    dir = select(dir, f_dirs[3], k == 3u);
    tri = select(tri, f_tri[4], k == 4u);
    best = select(best, f_best[4], k == 4u);
    dir = select(dir, f_dirs[4], k == 4u);
    tri = select(tri, f_tri[5], k == 5u);
    best = select(best, f_best[5], k == 5u);
    dir = select(dir, f_dirs[5], k == 5u);
    tri = select(tri, f_tri[6], k == 6u);
    best = select(best, f_best[6], k == 6u);
    dir = select(dir, f_dirs[6], k == 6u);
    tri = select(tri, f_tri[7], k == 7u);
    best = select(best, f_best[7], k == 7u);
    dir = select(dir, f_dirs[7], k == 7u);
    tri = select(tri, f_tri[8], k == 8u);
    best = select(best, f_best[8], k == 8u);
    dir = select(dir, f_dirs[8], k == 8u);
    tri = select(tri, f_tri[9], k == 9u);
    best = select(best, f_best[9], k == 9u);
    dir = select(dir, f_dirs[9], k == 9u);
    tri = select(tri, f_tri[10], k == 10u);
    best = select(best, f_best[10], k == 10u);
    dir = select(dir, f_dirs[10], k == 10u);
    tri = select(tri, f_tri[11], k == 11u);
    best = select(best, f_best[11], k == 11u);
    dir = select(dir, f_dirs[11], k == 11u);
    tri = select(tri, f_tri[12], k == 12u);
    best = select(best, f_best[12], k == 12u);
    dir = select(dir, f_dirs[12], k == 12u);
    tri = select(tri, f_tri[13], k == 13u);
    best = select(best, f_best[13], k == 13u);
    dir = select(dir, f_dirs[13], k == 13u);
    tri = select(tri, f_tri[14], k == 14u);
    best = select(best, f_best[14], k == 14u);
    dir = select(dir, f_dirs[14], k == 14u);
    tri = select(tri, f_tri[15], k == 15u);
    best = select(best, f_best[15], k == 15u);
    dir = select(dir, f_dirs[15], k == 15u);
    let x = f_x0 + (k & 3u);
    let y = f_y0 + (k >> 2u);
    if x < camera.width && y < camera.height {
        gbuffer[y * camera.width + x] = gbuffer_texel(tri, best, dir);
    }
}

@compute @workgroup_size(VEC16_WG_SIZE)
fn main(ids: Vec16Ids) {
    vec16_init(ids);
    // A 2-D dispatch: x = block column (VEC16_WG_SIZE / 16 per workgroup), y = block row.
    let bx = ids.workgroup.x * (VEC16_WG_SIZE / 16u) + g_vector_in_wg;
    let by = ids.workgroup.y;
    // A vector past the last block column has no pixel inside (inside = 0): it never runs,
    // but takes part in the loop's vector operations while others of its workgroup need
    // them (see the loop), and writes nothing.
    let inside = setup_frustum(bx * 16u + (g_lane & 3u) * 4u, by * 16u + (g_lane >> 2u) * 4u);
    let order_dir = edge_dir(bx * 16u + 8u, by * 16u + 8u);

    // The traversal state; every lane holds the same values.
    var children = 0u;    // the first child of the inner node to visit next (when not in a leaf)
    var mask = 0u;        // frusta that entered the node being traced
    var cursor = 0u;      // next triangle of the current leaf
    var end = 0u;         // end of the current leaf's triangles
    var depth = 0u;       // stack depth
    var popping = false;  // the next step pops the stack
    // Work counters (shared/counters), uniform; dead code unless COUNTERS.
    var n_steps = 0u;
    var n_box_tests = u32(inside != 0u);  // the root's (a vector with no pixel tests nothing)
    var n_accessed = 0u;
    var n_after_culling = 0u;
    var n_triangle_tests = 0u;

    let root = load_node(0u);
    children = root.first;
    mask = ballot16((inside != 0u) & frustum_may_hit_box(root, box_depth(root)));
    var running = mask != 0u;
    if root.count > 0u {
        cursor = root.first;
        end = root.first + root.count;
    }
    // Each iteration is one pass: a leaf triangle, a stack pop and an inner node's
    // visit, each where the state the one before left calls for it. Mesa 22.3 lavapipe
    // runs all three (masked) at every pass whatever the vector needs, so it pays for
    // fewer passes when one pass may do all three. No other loop in
    // here: lavapipe counts every iteration of every loop an invocation runs, nested
    // ones included, against one limit. The loop runs while any vector of the
    // workgroup runs (group_any), and each step's vector operations run where any
    // vector needs them (group_may), so that they stay in control flow uniform across
    // the workgroup.
    var iterations = 0u;
    var overflow = false;
    loop {
        if !group_any(running) {
            break;
        }
        iterations += 1u;
        if iterations > ITERATION_BUDGET {
            overflow = running;
            break;
        }
        let in_leaf = running && cursor < end;
        if group_may(in_leaf) {
            let tri = load_triangle(select(0u, cursor, in_leaf));
            let tested = in_leaf & ((mask & (1u << g_lane)) != 0u) & !frustum_culls_triangle(tri);
            if COUNTERS {
                let survivors = ballot16(tested);
                n_accessed += u32(in_leaf);
                n_after_culling += select(0u, 1u, survivors != 0u);
                n_triangle_tests += countOneBits(survivors);
            }
            if tested {
                test_rays(tri, cursor);
            }
            if in_leaf {
                cursor += 1u;
                if cursor == end {
                    popping = true;
                }
            }
        }
        let pops = running && cursor >= end && popping;
        if group_any(pops) {
            // Frusta whose rays have all hit nearer than the box drop it
            // (a compare with the stored depth, not a box test).
            let top = select(0u, depth - 1u, pops & (depth > 0u));
            let near = ballot16(pops & (depth > 0u) & (stack_depth[top] <= f_t_max * DEPTH_SLACK));
            if pops {
                if depth == 0u {
                    running = false;
                } else {
                    depth -= 1u;
                    let m = stack_mask[depth] & near;
                    if m != 0u {
                        mask = m;
                        popping = false;
                        children = stack_first[depth];
                        let count = stack_count[depth];
                        if count > 0u {
                            cursor = children;
                            end = children + count;
                        }
                    }
                }
            }
        }
        let visits = running && cursor >= end && !popping;
        if group_any(visits) {
            // Nodes 0 and 1 for a vector with nothing to visit (GpuScene holds two nodes at least).
            let l = select(0u, children, visits);
            let pair = load_node_pair(l);
            let left = pair[0];
            let right = pair[1];
            let dl = box_depth(left);
            let dr = box_depth(right);
            let mine = visits & ((mask & (1u << g_lane)) != 0u);
            let ml = ballot16(mine & frustum_may_hit_box(left, dl));
            let mr = ballot16(mine & frustum_may_hit_box(right, dr));
            if visits {
                n_steps += 1u;
                n_box_tests += 2u;
                // Nearer child first; the other waits on the stack with its frusta.
                let d = descend(l, ml, mr, order_key(right, order_dir) < order_key(left, order_dir));
                if d.later_mask != 0u {
                    // The host checked that the BVH is shallower than the stack.
                    let top = min(depth, STACK_SIZE - 1u);
                    let later_left = d.later == l;
                    stack_first[top] = select(right.first, left.first, later_left);
                    stack_count[top] = select(right.count, left.count, later_left);
                    stack_mask[top] = d.later_mask;
                    stack_depth[top] = select(dr, dl, later_left);
                    depth += 1u;
                }
                if d.mask != 0u {
                    mask = d.mask;
                    let now_left = d.node == l;
                    children = select(right.first, left.first, now_left);
                    let count = select(right.count, left.count, now_left);
                    if count > 0u {
                        cursor = children;
                        end = children + count;
                    }
                } else {
                    popping = true;
                }
            }
        }
    }
    if overflow && inside != 0u {
        // The host turns this into an error: the texels below are incomplete.
        atomicAdd(&status[WORD_STATUS], countOneBits(inside));
    }
    if running && !overflow && g_lane == 0u {
        // Left the loop neither way: the driver ended it (lavapipe's iteration limit);
        // the host turns this into an error.
        atomicAdd(&status[WORD_LOOP_CUT], 1u);
    }
    if COUNTERS && g_lane == 0u {
        atomicAdd(&status[WORD_NODES_VISITED], n_steps);
        atomicAdd(&status[WORD_BOX_TESTS], n_box_tests);
        atomicAdd(&status[WORD_TRIANGLES_ACCESSED], n_accessed);
        atomicAdd(&status[WORD_TRIANGLES_AFTER_CULLING], n_after_culling);
        atomicAdd(&status[WORD_TRIANGLE_TESTS], n_triangle_tests);
    }
    for (var k = 0u; k < 16u; k++) {
        write_texel(k);
    }
}
