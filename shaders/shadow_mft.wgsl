// Multi-frusta soft shadows: one 16-wide vector per 4x4 tile, lane = pixel = frustum of 16 rays.
// One kernel, long because traversal, culling, both leaf modes and suspension are its one job.
// Dispatched by the shadow pass (src/gpu/shadow_tracer.rs); CPU twin: src/reference/shadow_mft.rs.

#import shared/alpha_words
#import shared/bvh
#import shared/counters
#import shared/descend
#import shared/layout
#import shared/suspend
#import shared/vec16
#import shared/bvh_vec16

// Suspended-state slot of a tile: status, children, mask, cursor, end, alive,
// stack depth, popping (| 2: traversal done), 16 lane masks, the 64 stack
// entries' node firsts, their 64 masks with counts (STACK_COUNT_SHIFT), the
// candidate frusta of a transposed leaf (`cand`), the current leaf's frusta, the
// pending leaf (first, end, frusta), 3 words unused, and 16 lane words of
// `f_shrunk_for`.
const STATE_WORDS: u32 = 176u;
const ST_SHRUNK: u32 = 160u;
const ST_CAND: u32 = 152u;
const ST_LEAF_MASK: u32 = 153u;
const ST_PENDING: u32 = 154u;

// How a leaf triangle spends the 16 lanes (LeafMode in src/gpu/shadow_tracer.rs).
// false, per lane: lane j culls the triangle against its own frustum and tests
// its 16 rays itself. true, transposed (the paper's): lane j only culls; then
// for each frustum f that is left, lane i tests ray i of f and a ballot gives
// f's 16 bits. Both modes compute every bit with the same arithmetic.
override LEAF_TRANSPOSED: bool = false;
// Set in a per-lane test_triangle result when the frustum survived culling.
const TESTED: u32 = 0x20000u;
// Frustum shrinking, the paper's "CR": at the start, and after a leaf that
// blocked rays of a frustum, its corner rays go through the corners of the
// light rectangle that holds its still-active samples
// (reference::shadow_mft::Frustum::shrink_to).
override SHRINK: bool = false;
const SHRINK_MARGIN: f32 = 0.0009765625;  // 1/1024 of a light edge
const SHRINK_FLAG: u32 = 0x80000000u;
// Widening of a frustum's bounding box, relative to its coordinates' size: its
// corners are rounded to f32, so the box of the rounded corners may miss a few
// ulps of the exact pyramid; 2^-18 is far above that.
const BOUNDS_PAD: f32 = 1.0 / 262144.0;  // 2^-18

@group(0) @binding(0) var<uniform> params: ShadowParams;
// The BVH as 32-bit words (shared/bvh layouts), read through shared/bvh_vec16.
@group(0) @binding(1) var<storage, read> nodes: array<u32>;
@group(0) @binding(2) var<storage, read> triangles: array<u32>;
@group(0) @binding(3) var<storage, read> gbuffer: array<GBufferTexel>;
// The 16 sets' light points, set j at [16 j, 16 j + 16) (sampling::light_points). A uniform
// buffer, not storage: Mesa 22.3 lavapipe gathers a uniform array's per-lane elements with
// vector code, where it runs a storage load that differs per lane as a loop over the lanes
// (README "Setting up the frusta").
const LIGHT_SAMPLES: u32 = 256u;
@group(0) @binding(4) var<uniform> light_points: array<vec4<f32>, LIGHT_SAMPLES>;
@group(0) @binding(5) var<storage, read_write> masks: array<u32>;
@group(0) @binding(6) var<storage, read_write> state: array<u32>;
// [WORD_STATUS]: tiles suspended by this dispatch; [1..6]: the Table 1 counters
// (shared/counters, when COUNTERS); [WORD_LOOP_CUT]: tiles whose loop the driver ended.
@group(0) @binding(7) var<storage, read_write> status: array<atomic<u32>>;

// This lane's frustum.
var<private> f_origin: vec3<f32>;
var<private> f_geo: vec3<f32>;
var<private> f_side: array<vec3<f32>, 4>;
var<private> f_occluded: u32;
// The light rectangle this frustum bounds (shrunk or the whole light): its
// corners, and its (s, t) ranges on the light.
var<private> f_corner: array<vec3<f32>, 4>;
var<private> f_lo: vec2<f32>;
var<private> f_hi: vec2<f32>;
// SHRINK_FLAG | the mask the corners were shrunk for; 0: not shrunk.
var<private> f_shrunk_for: u32;
// The box around the origin and f_corner, widened by BOUNDS_PAD (relative).
var<private> f_bmin: vec3<f32>;
var<private> f_bmax: vec3<f32>;
var<private> f_initial: u32;

// Traversal and leaves are two stages with one leaf between them: the
// traversal walks on to the next leaf (`p_*`) while the leaf stage tests the
// current one, so that one pass of the loop can do work in both. Every lane
// holds the same values. Twin: reference::shadow_mft::VectorState.
var<private> t_children: u32;  // first child of the inner node to visit next (when not popping)
var<private> t_mask: u32;      // frusta that entered that node
var<private> t_depth: u32;     // stack depth
var<private> t_popping: bool;  // the next traversal step pops the stack
var<private> t_done: bool;     // the stack ran empty: every leaf was found
var<private> running: bool;    // the vector still traces (false: done, or no tile to trace)
var<private> alive: u32;       // frusta not yet done
var<private> p_first: u32;     // the pending leaf's triangles, first ..
var<private> p_end: u32;       // .. end; 0: no leaf pending
var<private> p_mask: u32;      // frusta that entered the pending leaf
var<private> cursor: u32;      // next triangle of the current leaf
var<private> end: u32;         // end of the current leaf's triangles
var<private> leaf_mask: u32;   // frusta that entered the current leaf
var<private> cand: u32;        // transposed leaves: frusta still to test against triangle cursor - 1
var<private> n_nodes: u32;     // counters (COUNTERS)
var<private> n_boxes: u32;
var<private> n_tris: u32;
var<private> n_after_culling: u32;
var<private> n_tests: u32;

// Transposed leaves: every lane's ray origin, 16 per vector of the workgroup,
// so that any lane can build the rays of any frustum of its vector.
var<workgroup> wg_origins: array<vec3<f32>, VEC16_WG_SIZE>;

fn corner(k: u32) -> vec3<f32> {
    return params.light_corners[k].xyz;
}

// Branch-free (`|`, not `||`), like every predicate a ballot takes here: a short-circuit
// operator is a lane-divergent branch, and a ballot right after one would depend on the
// driver reconverging the lanes.
fn is_done() -> bool {
    return ((f_occluded & MASK_SKY) != 0u) | ((f_occluded & MASK_FULL) == MASK_FULL);
}

// Same rules as reference::shadow_per_ray::initial_mask.
fn setup_frustum(texel: GBufferTexel, inside: bool) {
    f_origin = texel.origin;
    f_geo = texel.geo_normal;
    let o = f_origin;
    f_corner[0] = corner(0u);
    f_corner[1] = corner(1u);
    f_corner[2] = corner(2u);
    f_corner[3] = corner(3u);
    f_shrunk_for = 0u;
    f_lo = vec2<f32>(0.0);
    f_hi = vec2<f32>(1.0);
    set_sides();
    let lf = light_frame();
    // Unrolled on purpose: every loop iteration counts towards lavapipe's limit.
    let below = setup_sample(0u, lf) | setup_sample(1u, lf) | setup_sample(2u, lf)
        | setup_sample(3u, lf) | setup_sample(4u, lf) | setup_sample(5u, lf)
        | setup_sample(6u, lf) | setup_sample(7u, lf) | setup_sample(8u, lf)
        | setup_sample(9u, lf) | setup_sample(10u, lf) | setup_sample(11u, lf)
        | setup_sample(12u, lf) | setup_sample(13u, lf) | setup_sample(14u, lf)
        | setup_sample(15u, lf);
    if !inside || texel.depth <= 0.0 {
        f_occluded = MASK_SKY;
    } else if dot(params.light_normal, o - corner(0u)) <= 0.0 {
        f_occluded = MASK_FULL;
    } else {
        f_occluded = below;
    }
    f_initial = f_occluded;
}

// Sample j of this lane's set (set g_lane): its light coordinates into f_st[j], and bit j
// if its ray starts below the receiver's tangent plane (reference::shadow_per_ray::initial_mask).
fn setup_sample(j: u32, lf: LightFrame) -> u32 {
    let p = light_points[g_lane * 16u + j].xyz;
    f_st[j] = point_st(p, lf);
    return select(0u, 1u << j, dot(f_geo, p - f_origin) <= 0.0);
}

// The side planes through the origin and the edges of f_corner (inward
// normals), and the frustum's bounding box.
fn set_sides() {
    let o = f_origin;
    let centre = (f_corner[0] + f_corner[2]) * 0.5;
    // Unrolled on purpose: every loop iteration counts towards lavapipe's limit, and
    // this runs at every shrink.
    f_side[0] = side_plane(f_corner[0], f_corner[1], centre);
    f_side[1] = side_plane(f_corner[1], f_corner[2], centre);
    f_side[2] = side_plane(f_corner[2], f_corner[3], centre);
    f_side[3] = side_plane(f_corner[3], f_corner[0], centre);
    let lo = min(min(o, min(f_corner[0], f_corner[1])), min(f_corner[2], f_corner[3]));
    let hi = max(max(o, max(f_corner[0], f_corner[1])), max(f_corner[2], f_corner[3]));
    let pad = max(abs(lo), abs(hi)) * BOUNDS_PAD;
    f_bmin = lo - pad;
    f_bmax = hi + pad;
}

// The inward normal of the plane through the origin, a and b (`centre` is inside).
fn side_plane(a: vec3<f32>, b: vec3<f32>, centre: vec3<f32>) -> vec3<f32> {
    let o = f_origin;
    let n = cross(a - o, b - o);
    return select(n, -n, dot(n, centre - o) < 0.0);
}

// Light coordinates (s, t) of this lane's 16 samples: its rays go from the
// origin to c0 + s eu + t ev (reference::shadow_mft::Frustum::st).
var<private> f_st: array<vec2<f32>, 16>;
// The light rectangle shrink_to grows over the samples not yet blocked.
var<private> shrink_lo: vec2<f32>;
var<private> shrink_hi: vec2<f32>;

// The light's edge vectors and the duals that give a point's (s, t) on it.
struct LightFrame {
    c0: vec3<f32>,
    eu: vec3<f32>,
    ev: vec3<f32>,
    du: vec3<f32>,
    dv: vec3<f32>,
}

fn light_frame() -> LightFrame {
    let c0 = corner(0u);
    let eu = corner(1u) - c0;
    let ev = corner(3u) - c0;
    let n = cross(eu, ev);
    let inv = 1.0 / dot(n, n);
    return LightFrame(c0, eu, ev, cross(ev, n) * inv, cross(n, eu) * inv);
}

fn point_st(p: vec3<f32>, lf: LightFrame) -> vec2<f32> {
    let q = p - lf.c0;
    return vec2<f32>(dot(q, lf.du), dot(q, lf.dv));
}

// Grows the rectangle by sample j's light coordinates if its ray is not in `blocked`.
fn stretch(j: u32, blocked: u32) {
    if (blocked & (1u << j)) == 0u {
        shrink_lo = min(shrink_lo, f_st[j]);
        shrink_hi = max(shrink_hi, f_st[j]);
    }
}

fn shrink_to(blocked: u32) {
    shrink_lo = vec2<f32>(1.0);
    shrink_hi = vec2<f32>(0.0);
    // Unrolled on purpose: every loop iteration counts towards lavapipe's limit.
    stretch(0u, blocked); stretch(1u, blocked); stretch(2u, blocked); stretch(3u, blocked);
    stretch(4u, blocked); stretch(5u, blocked); stretch(6u, blocked); stretch(7u, blocked);
    stretch(8u, blocked); stretch(9u, blocked); stretch(10u, blocked); stretch(11u, blocked);
    stretch(12u, blocked); stretch(13u, blocked); stretch(14u, blocked); stretch(15u, blocked);
    let lf = light_frame();
    let lo = max(shrink_lo - SHRINK_MARGIN, vec2<f32>(0.0));
    let hi = min(shrink_hi + SHRINK_MARGIN, vec2<f32>(1.0));
    f_corner[0] = lf.c0 + lf.eu * lo.x + lf.ev * lo.y;
    f_corner[1] = lf.c0 + lf.eu * hi.x + lf.ev * lo.y;
    f_corner[2] = lf.c0 + lf.eu * hi.x + lf.ev * hi.y;
    f_corner[3] = lf.c0 + lf.eu * lo.x + lf.ev * hi.y;
    f_lo = lo;
    f_hi = hi;
    set_sides();
    f_shrunk_for = blocked | SHRINK_FLAG;
}

// After a leaf: shrink if a ray was blocked since the last shrink (or the start).
fn shrink_after_leaf() {
    let last = select(f_initial, f_shrunk_for & MASK_FULL, (f_shrunk_for & SHRINK_FLAG) != 0u);
    if !is_done() && f_occluded != last {
        shrink_to(f_occluded);
    }
}

fn box_outside(n: vec3<f32>, p0: vec3<f32>, node: BvhNode) -> bool {
    let p = select(node.bmin, node.bmax, n > vec3<f32>(0.0));
    return dot(n, p - p0) < 0.0;
}

// Twin: reference::shadow_mft::frustum_may_hit_box.
fn frustum_may_hit_box(node: BvhNode) -> bool {
    // The boxes' axes too: this catches boxes beside a thin frustum's apex
    // that straddle two of its planes (Sponza atrium 512²: 7 % fewer box tests).
    let apart = any(node.bmin > f_bmax) | any(node.bmax < f_bmin);
    return !(apart | box_outside(f_side[0], f_origin, node) | box_outside(f_side[1], f_origin, node)
        | box_outside(f_side[2], f_origin, node) | box_outside(f_side[3], f_origin, node)
        | box_outside(f_geo, f_origin, node) | box_outside(params.light_normal, corner(0u), node));
}

fn all_outside(n: vec3<f32>, b0: vec3<f32>, b1: vec3<f32>, b2: vec3<f32>) -> bool {
    return (dot(n, b0) < 0.0) & (dot(n, b1) < 0.0) & (dot(n, b2) < 0.0);
}

// A triangle's edge planes through a ray origin `o`: normals m0, m1, m2 of
// the planes through `o` and each edge, and d = det(a0, a1, a2) (a_k = v_k - o).
struct Wedge {
    m0: vec3<f32>,
    m1: vec3<f32>,
    m2: vec3<f32>,
    d: f32,
}

fn triangle_wedge(tri: BvhTriangle, o: vec3<f32>) -> Wedge {
    let a0 = tri.v0 - o;
    let a1 = tri.v1 - o;
    let a2 = tri.v2 - o;
    let m0 = cross(a0, a1);
    return Wedge(m0, cross(a1, a2), cross(a2, a0), dot(m0, a2));
}

// The wedge's three edge functions over the light, E(s, t) = a + b s + c t
// (one component per edge): m_k . (c0 + s eu + t ev - o), negated when d < 0
// so that the ray to (s, t) passes through the triangle when all three are
// >= 0, and reaches it before t_max when |d| < t_max (E.x + E.y + E.z).
struct EdgeFunctions {
    a: vec3<f32>,
    b: vec3<f32>,
    c: vec3<f32>,
    limit: f32,
}

fn edge_functions(w: Wedge, o: vec3<f32>) -> EdgeFunctions {
    let c0 = corner(0u);
    let q = c0 - o;
    let eu = corner(1u) - c0;
    let ev = corner(3u) - c0;
    let sg = select(-1.0, 1.0, w.d > 0.0);
    return EdgeFunctions(
        vec3<f32>(dot(w.m0, q), dot(w.m1, q), dot(w.m2, q)) * sg,
        vec3<f32>(dot(w.m0, eu), dot(w.m1, eu), dot(w.m2, eu)) * sg,
        vec3<f32>(dot(w.m0, ev), dot(w.m1, ev), dot(w.m2, ev)) * sg,
        abs(w.d),
    );
}

fn edge_values(e: EdgeFunctions, st: vec2<f32>) -> vec3<f32> {
    return e.a + e.b * st.x + e.c * st.y;
}

// Whether the ray to light coordinates `st` hits the triangle (before t_max).
fn st_hit(e: EdgeFunctions, st: vec2<f32>) -> bool {
    let v = edge_values(e, st);
    return all(v >= vec3<f32>(0.0)) & (e.limit < params.t_max * (v.x + v.y + v.z));
}

fn ray_bit(j: u32, e: EdgeFunctions) -> u32 {
    return select(0u, 1u << j, st_hit(e, f_st[j]));
}

// The triangle lies wholly outside one of this lane's six frustum planes.
fn planes_cull(tri: BvhTriangle) -> bool {
    let o = f_origin;
    let v0 = tri.v0;
    let v1 = tri.v1;
    let v2 = tri.v2;
    let a0 = v0 - o;
    let a1 = v1 - o;
    let a2 = v2 - o;
    let c0 = corner(0u);
    return all_outside(f_side[0], a0, a1, a2) | all_outside(f_side[1], a0, a1, a2)
        | all_outside(f_side[2], a0, a1, a2) | all_outside(f_side[3], a0, a1, a2)
        | all_outside(f_geo, a0, a1, a2)
        | all_outside(params.light_normal, v0 - c0, v1 - c0, v2 - c0);
}

// Seen from this lane's origin the triangle is edge-on (d == 0), or the
// lane's light rectangle lies wholly outside one of its edge planes (the
// corner-ray test; an edge function is monotonic in s and t, also as rounded,
// so no sample inside the rectangle is then inside the plane): no ray can hit.
fn wedge_culls(w: Wedge, e: EdgeFunctions) -> bool {
    let v0 = edge_values(e, f_lo);
    let v1 = edge_values(e, vec2<f32>(f_hi.x, f_lo.y));
    let v2 = edge_values(e, f_hi);
    let v3 = edge_values(e, vec2<f32>(f_lo.x, f_hi.y));
    return (w.d == 0.0) | any(max(max(v0, v1), max(v2, v3)) < vec3<f32>(0.0));
}

// No ray of this lane's frustum can hit the triangle (the culling half of
// test_triangle), computed branch-free: it is a ballot's predicate.
fn frustum_culls_triangle(tri: BvhTriangle) -> bool {
    let w = triangle_wedge(tri, f_origin);
    return planes_cull(tri) | wedge_culls(w, edge_functions(w, f_origin));
}

// Per-lane leaves: culls the triangle against this lane's frustum, else tests
// its 16 rays (hit bits | TESTED); the arithmetic of
// reference::shadow_mft::frustum_test_triangle, in the same order.
fn test_triangle(tri: BvhTriangle) -> u32 {
    if planes_cull(tri) {
        return 0u;
    }
    let w = triangle_wedge(tri, f_origin);
    let e = edge_functions(w, f_origin);
    if wedge_culls(w, e) {
        return 0u;
    }
    // Unrolled on purpose: every loop iteration counts towards lavapipe's limit.
    var bits = ray_bit(0u, e) | ray_bit(1u, e) | ray_bit(2u, e) | ray_bit(3u, e)
        | ray_bit(4u, e) | ray_bit(5u, e) | ray_bit(6u, e) | ray_bit(7u, e)
        | ray_bit(8u, e) | ray_bit(9u, e) | ray_bit(10u, e) | ray_bit(11u, e)
        | ray_bit(12u, e) | ray_bit(13u, e) | ray_bit(14u, e) | ray_bit(15u, e);
    if ALPHA_TEST && tri.alpha != ALPHA_OPAQUE && bits != 0u {
        // Branch-free per ray, the record read once: 16 copies of the whole test, each
        // loading the record behind two branches, made Mesa 25 lavapipe's first compile of
        // this kernel take over a minute (LLVM's coroutine split) and ran 1.6-2x slower.
        let r = alpha_record(tri.alpha);
        bits &= ~(passed_bit(0u, r, e, bits) | passed_bit(1u, r, e, bits)
            | passed_bit(2u, r, e, bits) | passed_bit(3u, r, e, bits)
            | passed_bit(4u, r, e, bits) | passed_bit(5u, r, e, bits)
            | passed_bit(6u, r, e, bits) | passed_bit(7u, r, e, bits)
            | passed_bit(8u, r, e, bits) | passed_bit(9u, r, e, bits)
            | passed_bit(10u, r, e, bits) | passed_bit(11u, r, e, bits)
            | passed_bit(12u, r, e, bits) | passed_bit(13u, r, e, bits)
            | passed_bit(14u, r, e, bits) | passed_bit(15u, r, e, bits));
    }
    return TESTED | bits;
}

// The barycentric weights (corners 0, 1, 2) of the point where the ray to light
// coordinates `st` meets the triangle's plane: edge function k is opposite corner k + 2.
fn st_weights(e: EdgeFunctions, st: vec2<f32>) -> vec3<f32> {
    let v = edge_values(e, st);
    let inv = 1.0 / (v.x + v.y + v.z);
    return vec3<f32>(v.y, v.z, v.x) * inv;
}

// Bit j if ray j is in `bits` (it hits the alpha-tested triangle of record `r`) but passes
// it. The mask is read for every ray, hit or not (a clamped texel of the mask).
fn passed_bit(j: u32, r: AlphaRecord, e: EdgeFunctions, bits: u32) -> u32 {
    let passes = record_passes(r, st_weights(e, f_st[j]));
    return select(0u, 1u << j, ((bits & (1u << j)) != 0u) & passes);
}

// Transposed leaves: whether ray g_lane of frustum f (a lane of this vector)
// hits the triangle. Same origin, direction and arithmetic as lane f's own
// test_triangle, so the ballot of this is bit for bit lane f's ray mask.
fn transposed_ray_hits(tri: BvhTriangle, f: u32) -> bool {
    let o = wg_origins[g_vector_in_wg * 16u + f];
    let w = triangle_wedge(tri, o);
    let e = edge_functions(w, o);
    let st = point_st(light_points[f * 16u + g_lane].xyz, light_frame());
    let hit = (w.d != 0.0) & st_hit(e, st);
    if ALPHA_TEST && hit && tri.alpha != ALPHA_OPAQUE {
        return !alpha_passes(tri.alpha, st_weights(e, st));
    }
    return hit;
}

// Moves the traversal to a node (first child or triangle `first`, `count`
// triangles) with frusta `m`; a leaf waits for the leaf stage and the
// traversal goes on from the stack.
fn enter(m: u32, first: u32, count: u32) {
    t_mask = m;
    if count > 0u {
        p_first = first;
        p_end = first + count;
        p_mask = m;
        t_popping = true;
    } else {
        t_children = first;
    }
}

// The area of a box's shadow along the light's normal: the area it covers seen
// from the light, which a shadow ray is the likelier to cross the larger it is.
fn shadow_area(n: BvhNode) -> f32 {
    let e = n.bmax - n.bmin;
    let a = abs(params.light_normal);
    return a.x * e.y * e.z + a.y * e.x * e.z + a.z * e.x * e.y;
}

// The traversal's order: the child with the larger shadow area first (on a
// tie, the one whose centre is nearer the light's plane). Blockers found early
// stop rays and shrink the frusta sooner. Steps of the CPU twin at 512², this
// order against "the child more frusta want first": Sponza atrium 273K vs
// 602K, columns 190K vs 362K, bunny 187K vs 218K, playground 86K vs 90K,
// engine 73K vs 56K, Cornell box, duck and lattice within 3 %. The packet
// kernel, which cannot shrink, keeps the latter. Twin:
// reference::shadow_mft::right_first.
fn right_first(nl: BvhNode, nr: BvhNode) -> bool {
    let al = shadow_area(nl);
    let ar = shadow_area(nr);
    if ar != al {
        return ar > al;
    }
    let kl = dot(params.light_normal, (nl.bmin + nl.bmax) * 0.5);
    let kr = dot(params.light_normal, (nr.bmin + nr.bmax) * 0.5);
    return kr < kl;
}

// One step of the traversal stage, unless the vector is done, a found leaf waits
// or the traversal is over: pop the stack if it must, then visit the inner node it
// is at (both child boxes against every frustum that entered it), into the child
// right_first picks. The node loads and ballots run where any vector of the
// workgroup needs them (group_may), with the others' lanes idle, so that they stay
// in control flow uniform across the workgroup.
fn traversal_step() {
    let pops = running && !t_done && p_end == 0u && t_popping;
    if pops {
        if t_depth == 0u {
            t_done = true;
        } else {
            t_depth -= 1u;
            // An entry holds the node's first and count (see the push below): a pop
            // needs no node load.
            let popped = stack_mask[t_depth] & alive;
            if popped != 0u {
                t_popping = false;
                enter(popped, stack_node[t_depth], stack_mask[t_depth] >> STACK_COUNT_SHIFT);
            }
        }
    }
    let visits = running && !t_done && p_end == 0u && !t_popping;
    if group_any(visits) {
        // Nodes 0 and 1 for a vector with nothing to visit (GpuScene holds two nodes at least).
        let l = select(0u, t_children, visits);
        let pair = load_node_pair(l);
        let nl = pair[0];
        let nr = pair[1];
        let mine = visits & ((t_mask & (1u << g_lane)) != 0u) & !is_done();
        let ml = ballot16(mine & frustum_may_hit_box(nl));
        let mr = ballot16(mine & frustum_may_hit_box(nr));
        if visits {
            n_nodes += 1u;
            n_boxes += 2u;
            let d = descend(l, ml, mr, right_first(nl, nr));
            if d.later_mask != 0u {
                // The entry is the child's first and, above its 16 frusta's bits, its
                // count (a leaf holds at most 255 triangles, MAX_LEAF_TRIANGLES), taken
                // from the pair already loaded. The host checked that the BVH is
                // shallower than the stack.
                let later_right = d.later != l;
                stack_node[min(t_depth, STACK_SIZE - 1u)] = select(nl.first, nr.first, later_right);
                stack_mask[min(t_depth, STACK_SIZE - 1u)] =
                    d.later_mask | (select(nl.count, nr.count, later_right) << STACK_COUNT_SHIFT);
                t_depth += 1u;
            }
            if d.mask != 0u {
                let right = d.node != l;
                enter(d.mask, select(nl.first, nr.first, right), select(nl.count, nr.count, right));
            } else {
                t_popping = true;
            }
        }
    }
}

// Per-lane leaves: the next triangle of the current leaf against this lane's
// frustum and its 16 rays.
fn per_lane_triangle() {
    let tests = running && cursor < end;
    if group_may(tests) {
        let tri = load_triangle(select(0u, cursor, tests));
        var r = 0u;
        if tests && (leaf_mask & (1u << g_lane)) != 0u && !is_done() {
            r = test_triangle(tri);
        }
        f_occluded |= r & MASK_FULL;
        if COUNTERS {
            let tested = ballot16((r & TESTED) != 0u);
            n_tests += countOneBits(tested);
            n_after_culling += u32(tested != 0u);
        }
        if tests {
            cursor += 1u;
            n_tris += 1u;
        }
    }
}

// The leaf stage takes the pending leaf when it has none.
fn take_pending() {
    if cand == 0u && cursor >= end && p_end != 0u {
        cursor = p_first;
        end = p_end;
        leaf_mask = p_mask;
        p_first = 0u;
        p_end = 0u;
        p_mask = 0u;
    }
}

@compute @workgroup_size(VEC16_WG_SIZE)
fn main(ids: Vec16Ids) {
    vec16_init(ids);
    let slot = g_vector;
    let tx = params.tile_origin_x + slot % params.tiles_x;
    let ty = params.tile_origin_y + slot / params.tiles_x;
    let x = tx * 4u + (g_lane & 3u);
    let y = ty * 4u + (g_lane >> 2u);
    let base = slot * STATE_WORDS;
    // Whether this vector traces a tile: one of the dispatch's, and on a resume round one
    // that was suspended. A vector that does not still runs the loop's vector operations
    // while others of its workgroup need them, with its lanes idle, and writes nothing.
    var traces = slot < params.tiles_x * params.tiles_y;
    if traces && params.resume != 0u {
        traces = state[base + ST_STATUS] == STATUS_SUSPENDED;
    }
    let inside = traces && x < params.width && y < params.height;
    let pixel = y * params.width + x;
    let texel = gbuffer[min(pixel, arrayLength(&gbuffer) - 1u)];
    if LEAF_TRANSPOSED {
        wg_origins[g_vector_in_wg * 16u + g_lane] = texel.origin;
        workgroupBarrier();
    }
    if traces && params.resume == 0u && g_lane == 0u {
        // A fresh start: whatever an earlier dispatch left in this slot (another
        // chunk's tile, another frame's) must not be resumed.
        state[base + ST_STATUS] = 0u;
    }
    // Outside the image or idle: every lane done (MASK_SKY), so no ballot counts it.
    setup_frustum(texel, inside);

    var cand_tri: BvhTriangle;  // transposed leaves: triangle cursor - 1, loaded once for all its candidates
    var cut = false;  // a loop of this invocation was ended by the driver
    if params.resume != 0u {
        if traces {
            t_children = state[base + 1u];
            t_mask = state[base + 2u];
            cursor = state[base + 3u];
            end = state[base + 4u];
            alive = state[base + 5u];
            t_depth = state[base + 6u];
            let flags = state[base + 7u];
            t_popping = (flags & 1u) != 0u;
            t_done = (flags & 2u) != 0u;
            cand = state[base + ST_CAND];
            leaf_mask = state[base + ST_LEAF_MASK];
            p_first = state[base + ST_PENDING];
            p_end = state[base + ST_PENDING + 1u];
            p_mask = state[base + ST_PENDING + 2u];
            f_occluded = state[base + ST_LANES + g_lane];
            let shrunk_for = state[base + ST_SHRUNK + g_lane];
            if SHRINK && (shrunk_for & SHRINK_FLAG) != 0u {
                shrink_to(shrunk_for & MASK_FULL);
            }
            // At most STACK_SIZE passes, counted by lavapipe with the others (ITERATION_BUDGET).
            // Ended by the driver before the stack was read: report it, trace nothing.
            cut = !restore_stack(base, t_depth);
            running = !cut;
        }
        let has_cand = running && cand != 0u;
        if group_may(has_cand) {
            let t = load_triangle(select(0u, cursor - 1u, has_cand));
            if has_cand {
                cand_tri = t;
            }
        }
    } else {
        if SHRINK && !is_done() {
            // Start from the rectangle of the samples themselves (rays below
            // the horizon left out): 1–7 % fewer steps on the shared scenes.
            shrink_to(f_occluded);
        }
        alive = ballot16(!is_done());
        let root = load_node(0u);
        let m = ballot16(!is_done() & frustum_may_hit_box(root));
        n_boxes = u32(traces);
        running = m != 0u;
        enter(m, root.first, root.count);
    }

    // Each pass of the loop may do, in this order: two traversal steps (each a
    // stack pop and an inner node), one or two triangles of the current leaf
    // (with transposed leaves, one, then the inner loop over its candidate
    // frusta) and the end of a leaf. Mesa 22.3 lavapipe runs every branch of the
    // body (masked) at every pass, so a pass pays for all of it whatever it does
    // (Mesa 25 skips a branch no lane takes; README "The bunny, tile by tile"):
    // the two stages let it do work in both, and two traversal steps match the
    // traversal's steps to the leaves' (Sponza: 948K passes with one stage,
    // 849K with two, 648K with two traversal steps). lavapipe also counts every
    // pass of either loop towards its limit: a loop nested in another costs it
    // a pass each time the outer body runs, even when no lane enters it. So
    // nothing else loops in here (the state is saved after the loop).
    // The loop runs while any vector of the workgroup runs (group_any), so that its
    // vector operations stay in uniform control flow; the others idle along.
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
        take_pending();
        traversal_step();
        traversal_step();
        take_pending();
        let in_leaf = running && (cand != 0u || cursor < end);
        // With cand != 0 a resumed tile goes on with the candidates of triangle cursor - 1.
        if LEAF_TRANSPOSED {
            let starts = running && cand == 0u && cursor < end;
            if group_any(starts) {
                let t = load_triangle(select(0u, cursor, starts));
                let mine = starts & ((leaf_mask & (1u << g_lane)) != 0u) & !is_done();
                let c = ballot16(mine & !frustum_culls_triangle(t));
                if starts {
                    cand_tri = t;
                    cursor += 1u;
                    n_tris += 1u;
                    cand = c;
                    n_tests += countOneBits(c);
                    n_after_culling += u32(c != 0u);
                }
            }
        }
        if !LEAF_TRANSPOSED {
            per_lane_triangle();
            per_lane_triangle();
        }
        if LEAF_TRANSPOSED {
            // The candidate frusta, lowest first: frustum f meets the triangle
            // with all 16 lanes, one ray each. An inner loop rather than a step
            // each, because lavapipe runs the whole body above (every branch,
            // masked) at every step. `cand` and `f` come from ballots: the same
            // in every lane of the vector.
            loop {
                iterations += 1u;
                if !group_any(cand != 0u) || iterations >= params.iteration_budget {
                    break;  // out of budget: the rest wait in `cand`
                }
                let has = cand != 0u;
                let f = select(0u, firstTrailingBit(cand), has);
                cand &= cand - 1u;
                let bits = ballot16(has & transposed_ray_hits(cand_tri, f));
                f_occluded |= select(0u, bits, has && g_lane == f);
            }
        }
        let leaf_ends = in_leaf && cand == 0u && cursor == end;
        if SHRINK && leaf_ends {
            shrink_after_leaf();
        }
        if group_any(leaf_ends) {
            let a = ballot16(!is_done());
            if leaf_ends {
                alive = a;
                running = a != 0u;
            }
        }
        if t_done && p_end == 0u && cand == 0u && cursor >= end {
            running = false;
        }
    }
    // The loop stops only by finishing (running = false) or by suspending; left any
    // other way, lavapipe ended it (its per-invocation iteration limit).
    cut = cut || (running && !suspended);
    if COUNTERS && g_lane == 0u {
        atomicAdd(&status[WORD_NODES_VISITED], n_nodes);
        atomicAdd(&status[WORD_BOX_TESTS], n_boxes);
        atomicAdd(&status[WORD_TRIANGLES_ACCESSED], n_tris);
        atomicAdd(&status[WORD_TRIANGLES_AFTER_CULLING], n_after_culling);
        atomicAdd(&status[WORD_TRIANGLE_TESTS], n_tests);
    }
    if !traces {
        return;
    }
    if cut {
        // The masks of this tile are incomplete: write none, and let the host fail the pass.
        if g_lane == 0u {
            atomicAdd(&status[WORD_LOOP_CUT], 1u);
        }
        return;
    }
    if suspended {
        // Out of budget: save the state; the next dispatch resumes this tile.
        state[base + ST_LANES + g_lane] = f_occluded;
        state[base + ST_SHRUNK + g_lane] = f_shrunk_for;
        if g_lane == 0u {
            state[base + ST_STATUS] = STATUS_SUSPENDED;
            state[base + 1u] = t_children;
            state[base + 2u] = t_mask;
            state[base + 3u] = cursor;
            state[base + 4u] = end;
            state[base + 5u] = alive;
            state[base + 6u] = t_depth;
            state[base + 7u] = u32(t_popping) | (u32(t_done) << 1u);
            state[base + ST_CAND] = cand;
            state[base + ST_LEAF_MASK] = leaf_mask;
            state[base + ST_PENDING] = p_first;
            state[base + ST_PENDING + 1u] = p_end;
            state[base + ST_PENDING + 2u] = p_mask;
            if !save_stack(base, t_depth) {
                // Ended by the driver: the saved stack is incomplete.
                state[base + ST_STATUS] = 0u;
                atomicAdd(&status[WORD_LOOP_CUT], 1u);
            } else {
                atomicAdd(&status[WORD_STATUS], 1u);
            }
        }
        return;
    }
    if inside {
        masks[pixel] = f_occluded;
    }
    if g_lane == 0u && params.resume != 0u {
        state[base + ST_STATUS] = 0u;
    }
}
