// The 16-wide vector as 16 lanes of one subgroup (ballot masked to the lane's 16-lane segment).
// Needs Features::SUBGROUP and a fixed subgroup size that is a multiple of 16.
//
// Every function here is a subgroup operation, so the kernels call them only where control
// flow is uniform across the workgroup (= the subgroup): branches that hold them test
// group_any, never a per-vector value, when a subgroup holds several vectors. The workgroup
// variant (shared/vec16_workgroup) makes the same calls barriers, so naga's uniformity
// analysis checks every call site of both variants.

// Vectors per workgroup = subgroup size / 16; the workgroup is meant to be one subgroup.
override VEC16_PER_WG: u32 = 1u;
override VEC16_WG_SIZE: u32 = 16u * VEC16_PER_WG;

struct Vec16Ids {
    @builtin(subgroup_invocation_id) subgroup_index: u32,
    @builtin(workgroup_id) workgroup: vec3<u32>,
    // The vector's index comes from the workgroup, not the subgroup: a driver may split
    // the workgroup into smaller subgroups than it reports (lavapipe with
    // LP_NATIVE_VECTOR_WIDTH=1024 reports 32 lanes and runs two subgroups of 16, whose
    // subgroup_invocation_id both count 0..15). Lane bits stay subgroup-relative.
    @builtin(local_invocation_index) local_index: u32,
}

var<private> g_lane: u32;     // 0..16: this invocation's lane in its vector
var<private> g_vector: u32;   // index of this vector in the dispatch
var<private> g_sid: u32;      // lane in the subgroup
var<private> g_vector_in_wg: u32;  // index of this vector in its workgroup

fn vec16_init(ids: Vec16Ids) {
    g_sid = ids.subgroup_index;
    g_lane = ids.subgroup_index & 15u;
    g_vector_in_wg = ids.local_index >> 4u;
    g_vector = ids.workgroup.x * VEC16_PER_WG + g_vector_in_wg;
}

fn ballot16(pred: bool) -> u32 {
    let b = subgroupBallot(pred);
    return (b[g_sid >> 5u] >> (g_sid & 16u)) & 0xffffu;
}

// Whether `b` holds for any vector of the workgroup; `b` must be the same in all 16 lanes
// of a vector. The result is the same in every invocation of the subgroup, so a branch on
// it keeps the subgroup's control flow uniform. With one vector per subgroup that is `b`.
fn group_any(b: bool) -> bool {
    if VEC16_PER_WG == 1u {
        return b;
    }
    return subgroupAny(b);
}

// A branch guard for work without ballots (loads through vec16_words) that a vector with
// `b` false may skip: here exactly group_any. (The workgroup variant takes it always.)
fn group_may(b: bool) -> bool {
    return group_any(b);
}

// Whether BVH reads go through vec16_words (shared/bvh_vec16): here, yes.
const VEC16_LANE_WORDS: bool = true;

// How vec16_words hands the lanes each other's words when a subgroup holds one vector:
// false, one broadcast per lane (subgroupBroadcast with a constant lane); true, one
// reduction per lane (subgroupMax of the word in its own lane and 0 in the others). naga
// writes a broadcast as a SPIR-V shuffle, which lavapipe runs at 16 lanes as a loop over
// the lanes; its reductions are unrolled vector code from Mesa 24.3 on and loops before.
// Same bits either way; the host picks by driver (VectorVariant::SubgroupReduce).
override VEC16_WORDS_BY_REDUCTION: bool = false;

// The 16 lanes' `word`s, in lane order, in every lane of the vector.
fn vec16_words(word: u32) -> array<u32, 16> {
    if VEC16_PER_WG == 1u && VEC16_WORDS_BY_REDUCTION {
        return array<u32, 16>(
            subgroupMax(select(0u, word, g_lane == 0u)), subgroupMax(select(0u, word, g_lane == 1u)),
            subgroupMax(select(0u, word, g_lane == 2u)), subgroupMax(select(0u, word, g_lane == 3u)),
            subgroupMax(select(0u, word, g_lane == 4u)), subgroupMax(select(0u, word, g_lane == 5u)),
            subgroupMax(select(0u, word, g_lane == 6u)), subgroupMax(select(0u, word, g_lane == 7u)),
            subgroupMax(select(0u, word, g_lane == 8u)), subgroupMax(select(0u, word, g_lane == 9u)),
            subgroupMax(select(0u, word, g_lane == 10u)), subgroupMax(select(0u, word, g_lane == 11u)),
            subgroupMax(select(0u, word, g_lane == 12u)), subgroupMax(select(0u, word, g_lane == 13u)),
            subgroupMax(select(0u, word, g_lane == 14u)), subgroupMax(select(0u, word, g_lane == 15u)),
        );
    }
    if VEC16_PER_WG == 1u {
        return array<u32, 16>(
            subgroupBroadcast(word, 0u), subgroupBroadcast(word, 1u), subgroupBroadcast(word, 2u),
            subgroupBroadcast(word, 3u), subgroupBroadcast(word, 4u), subgroupBroadcast(word, 5u),
            subgroupBroadcast(word, 6u), subgroupBroadcast(word, 7u), subgroupBroadcast(word, 8u),
            subgroupBroadcast(word, 9u), subgroupBroadcast(word, 10u), subgroupBroadcast(word, 11u),
            subgroupBroadcast(word, 12u), subgroupBroadcast(word, 13u), subgroupBroadcast(word, 14u),
            subgroupBroadcast(word, 15u),
        );
    }
    let b = g_sid & ~15u;
    return array<u32, 16>(
        subgroupShuffle(word, b), subgroupShuffle(word, b | 1u), subgroupShuffle(word, b | 2u),
        subgroupShuffle(word, b | 3u), subgroupShuffle(word, b | 4u), subgroupShuffle(word, b | 5u),
        subgroupShuffle(word, b | 6u), subgroupShuffle(word, b | 7u), subgroupShuffle(word, b | 8u),
        subgroupShuffle(word, b | 9u), subgroupShuffle(word, b | 10u), subgroupShuffle(word, b | 11u),
        subgroupShuffle(word, b | 12u), subgroupShuffle(word, b | 13u), subgroupShuffle(word, b | 14u),
        subgroupShuffle(word, b | 15u),
    );
}
