// The 16-wide vector as one 16-invocation workgroup exchanging through workgroup memory.
// Works on every device; kernels use vec16_init, ballot16, uniform16 and the g_* ids below.

// One workgroup is one vector.
const VEC16_WG_SIZE: u32 = 16u;

// The builtins a kernel entry point takes to know its lane and vector.
struct Vec16Ids {
    @builtin(local_invocation_index) local_index: u32,
    @builtin(workgroup_id) workgroup: vec3<u32>,
}

var<private> g_lane: u32;    // 0..16: this invocation's lane in its vector
var<private> g_vector: u32;  // index of this vector in the dispatch
var<private> g_vector_in_wg: u32;  // index of this vector in its workgroup: always 0 here

var<workgroup> sh_vote: array<u32, 16>;
var<workgroup> sh_word: u32;

fn vec16_init(ids: Vec16Ids) {
    g_lane = ids.local_index;
    g_vector = ids.workgroup.x;
    g_vector_in_wg = 0u;
}

// Bit i set when lane i's `pred` holds. Every lane gets the same value, and
// the result is uniform, so it may steer loops that contain barriers.
fn ballot16(pred: bool) -> u32 {
    sh_vote[g_lane] = select(0u, 1u << g_lane, pred);
    let v = workgroupUniformLoad(&sh_vote);
    return v[0] | v[1] | v[2] | v[3] | v[4] | v[5] | v[6] | v[7]
        | v[8] | v[9] | v[10] | v[11] | v[12] | v[13] | v[14] | v[15];
}

// Lane 0's value, as a uniform value every lane can branch on.
fn uniform16(value: u32) -> u32 {
    if g_lane == 0u {
        sh_word = value;
    }
    return workgroupUniformLoad(&sh_word);
}

// Whether BVH reads go through vec16_words (shared/bvh_vec16): not here. Reading
// the words back from workgroup memory costs a barrier and, on lavapipe, the
// same per-lane loads that it would save, so the kernels load nodes and
// triangles directly.
const VEC16_LANE_WORDS: bool = false;

var<workgroup> sh_words: array<u32, 16>;

// The 16 lanes' `word`s, in lane order, in every lane (uniform).
fn vec16_words(word: u32) -> array<u32, 16> {
    sh_words[g_lane] = word;
    return workgroupUniformLoad(&sh_words);
}
