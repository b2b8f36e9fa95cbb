// The 16-wide vector as 16 invocations of a workgroup exchanging through workgroup memory.
// Works on every device; kernels use vec16_init, ballot16, group_any and the g_* ids below.
//
// A workgroup holds VEC16_PER_WG vectors (1 on a CPU, where a workgroup runs as one loop
// over its invocations; more on a GPU, so that its warps are full). Every function here
// that exchanges values is a barrier, which WGSL allows only in control flow uniform across
// the workgroup: naga's uniformity analysis checks every call site when it validates a
// kernel, and the subgroup variant makes the same calls.

const MAX_VEC16_PER_WG: u32 = 4u;
// Vectors per workgroup, 1..=MAX_VEC16_PER_WG (src/gpu/vector_variant.rs chooses it).
override VEC16_PER_WG: u32 = 1u;
override VEC16_WG_SIZE: u32 = 16u * VEC16_PER_WG;

// The builtins a kernel entry point takes to know its lane and vector.
struct Vec16Ids {
    @builtin(local_invocation_index) local_index: u32,
    @builtin(workgroup_id) workgroup: vec3<u32>,
}

var<private> g_lane: u32;    // 0..16: this invocation's lane in its vector
var<private> g_vector: u32;  // index of this vector in the dispatch
var<private> g_vector_in_wg: u32;  // index of this vector in its workgroup

var<workgroup> sh_vote: array<u32, VEC16_WG_SIZE>;
var<workgroup> sh_any: array<u32, MAX_VEC16_PER_WG>;

fn vec16_init(ids: Vec16Ids) {
    g_lane = ids.local_index & 15u;
    g_vector_in_wg = ids.local_index >> 4u;
    g_vector = ids.workgroup.x * VEC16_PER_WG + g_vector_in_wg;
}

// The first of this vector's 16 slots in workgroup memory (a constant 0 with one vector).
fn vector_slots() -> u32 {
    return select(g_vector_in_wg * 16u, 0u, VEC16_PER_WG == 1u);
}

// Bit i set when lane i of this vector has `pred`; every lane of the vector gets it.
fn ballot16(pred: bool) -> u32 {
    let b = vector_slots();
    sh_vote[b + g_lane] = select(0u, 1u << g_lane, pred);
    workgroupBarrier();
    let v = sh_vote[b] | sh_vote[b + 1u] | sh_vote[b + 2u] | sh_vote[b + 3u]
        | sh_vote[b + 4u] | sh_vote[b + 5u] | sh_vote[b + 6u] | sh_vote[b + 7u]
        | sh_vote[b + 8u] | sh_vote[b + 9u] | sh_vote[b + 10u] | sh_vote[b + 11u]
        | sh_vote[b + 12u] | sh_vote[b + 13u] | sh_vote[b + 14u] | sh_vote[b + 15u];
    // The next ballot writes sh_vote again only after every lane has read it.
    workgroupBarrier();
    return v;
}

// Whether `b` holds for any vector of the workgroup; `b` must be the same in all 16 lanes
// of a vector. Uniform across the workgroup (a workgroupUniformLoad), so a branch on it
// may hold barriers.
fn group_any(b: bool) -> bool {
    if g_lane == 0u {
        sh_any[g_vector_in_wg] = u32(b);
    }
    let v = workgroupUniformLoad(&sh_any);
    // Slots past VEC16_PER_WG are never written (workgroup memory is not zeroed).
    return (v[0] | select(0u, v[1], VEC16_PER_WG > 1u) | select(0u, v[2], VEC16_PER_WG > 2u)
        | select(0u, v[3], VEC16_PER_WG > 3u)) != 0u;
}

// A branch guard for work without ballots (loads) that a vector with `b` false may skip:
// always taken here, since the loads are plain (VEC16_LANE_WORDS is false) and cheaper
// than the two barriers of finding out. Work with ballots is guarded by group_any.
fn group_may(b: bool) -> bool {
    return true;
}

// Whether BVH reads go through vec16_words (shared/bvh_vec16): not here. Reading
// the words back from workgroup memory costs a barrier and, on lavapipe, the
// same per-lane loads that it would save, so the kernels load nodes and
// triangles directly.
const VEC16_LANE_WORDS: bool = false;

var<workgroup> sh_words: array<u32, VEC16_WG_SIZE>;

// The 16 lanes' `word`s, in lane order, in every lane of the vector.
fn vec16_words(word: u32) -> array<u32, 16> {
    let b = vector_slots();
    sh_words[b + g_lane] = word;
    workgroupBarrier();
    let w = array<u32, 16>(
        sh_words[b], sh_words[b + 1u], sh_words[b + 2u], sh_words[b + 3u],
        sh_words[b + 4u], sh_words[b + 5u], sh_words[b + 6u], sh_words[b + 7u],
        sh_words[b + 8u], sh_words[b + 9u], sh_words[b + 10u], sh_words[b + 11u],
        sh_words[b + 12u], sh_words[b + 13u], sh_words[b + 14u], sh_words[b + 15u],
    );
    workgroupBarrier();
    return w;
}
