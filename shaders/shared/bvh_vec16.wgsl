// BVH reads of the 16-wide kernels (shadow_mft, shadow_packet, primary_mft), where every
// lane of a vector reads the same node or triangle. The kernel binds the nodes and the
// triangles (bindings 1 and 2, the buffers every kernel gets) as arrays of u32,
// `nodes` and `triangles`, in the layouts of shared/bvh.
//
// Why: lavapipe (Mesa 22.3) cannot see that such an address is the same in every lane,
// so it runs each load as a loop over the 16 lanes, and those loops were most of the
// traversal loop's time. Where the vector is a subgroup (VEC16_LANE_WORDS), lane i loads
// word i alone (one such loop) and vec16_words hands every lane all 16 words; elsewhere
// every lane loads the words itself. Either way the values are the stored ones, bit for bit.

const NODE_WORDS: u32 = 8u;
const TRIANGLE_WORDS: u32 = 12u;

// Node `n`, loaded by this lane alone (any lane, any n).
fn node_from_memory(n: u32) -> BvhNode {
    let b = n * NODE_WORDS;
    return node_of_words(
        nodes[b], nodes[b + 1u], nodes[b + 2u], nodes[b + 3u],
        nodes[b + 4u], nodes[b + 5u], nodes[b + 6u], nodes[b + 7u],
    );
}

// Triangle `t`, loaded by this lane alone (any lane, any t).
fn triangle_from_memory(t: u32) -> BvhTriangle {
    let b = t * TRIANGLE_WORDS;
    return triangle_of_words(
        triangles[b], triangles[b + 1u], triangles[b + 2u], triangles[b + 3u],
        triangles[b + 4u], triangles[b + 5u], triangles[b + 6u], triangles[b + 7u],
        triangles[b + 8u], triangles[b + 9u], triangles[b + 10u], triangles[b + 11u],
    );
}

// Node `n`; every lane of the vector must call this with the same `n`.
fn load_node(n: u32) -> BvhNode {
    if VEC16_LANE_WORDS {
        let w = vec16_words(nodes[n * NODE_WORDS + (g_lane & 7u)]);
        return node_of_words(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]);
    }
    return node_from_memory(n);
}

// Nodes `l` and `l + 1` (an inner node's children, 64 bytes: one word per lane); every
// lane of the vector must call this with the same `l`.
fn load_node_pair(l: u32) -> array<BvhNode, 2> {
    if VEC16_LANE_WORDS {
        let w = vec16_words(nodes[l * NODE_WORDS + g_lane]);
        return array<BvhNode, 2>(
            node_of_words(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]),
            node_of_words(w[8], w[9], w[10], w[11], w[12], w[13], w[14], w[15]),
        );
    }
    return array<BvhNode, 2>(node_from_memory(l), node_from_memory(l + 1u));
}

// Triangle `t` (lanes 12..15 read word 11 again); every lane of the vector must call
// this with the same `t`.
fn load_triangle(t: u32) -> BvhTriangle {
    if VEC16_LANE_WORDS {
        let w = vec16_words(triangles[t * TRIANGLE_WORDS + min(g_lane, 11u)]);
        return triangle_of_words(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7], w[8], w[9], w[10], w[11]);
    }
    return triangle_from_memory(t);
}
