// BVH reads of the 16-wide kernels (shadow_mft, shadow_packet, primary_mft), where every lane of a
// vector reads the same node or triangle. The kernel declares `nodes` and `triangles`,
// and `node_words` and `triangle_words`: the same two buffers as arrays of u32.
//
// Why: lavapipe (Mesa 22.3) cannot see that such an address is the same in every lane,
// so it runs each load as a loop over the 16 lanes, and the kernels' loop bodies spent
// most of their time there. Where the vector is a subgroup (VEC16_LANE_WORDS), lane i
// loads word i alone (one such loop) and vec16_words hands every lane all 16 words.
// The values are the same as the plain loads', bit for bit.

fn node_of_words(w0: u32, w1: u32, w2: u32, w3: u32, w4: u32, w5: u32, w6: u32, w7: u32) -> BvhNode {
    return BvhNode(
        vec3<f32>(bitcast<f32>(w0), bitcast<f32>(w1), bitcast<f32>(w2)), w3,
        vec3<f32>(bitcast<f32>(w4), bitcast<f32>(w5), bitcast<f32>(w6)), w7,
    );
}

// Node `n`.
fn load_node(n: u32) -> BvhNode {
    if VEC16_LANE_WORDS {
        let w = vec16_words(node_words[n * 8u + (g_lane & 7u)]);
        return node_of_words(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]);
    }
    return nodes[n];
}

// Nodes `l` and `l + 1` (an inner node's children): 64 bytes, one word per lane.
fn load_node_pair(l: u32) -> array<BvhNode, 2> {
    if VEC16_LANE_WORDS {
        let w = vec16_words(node_words[l * 8u + g_lane]);
        return array<BvhNode, 2>(
            node_of_words(w[0], w[1], w[2], w[3], w[4], w[5], w[6], w[7]),
            node_of_words(w[8], w[9], w[10], w[11], w[12], w[13], w[14], w[15]),
        );
    }
    return array<BvhNode, 2>(nodes[l], nodes[l + 1u]);
}

// Triangle `t` (12 words; lanes 12..15 read word 11 again).
fn load_triangle(t: u32) -> BvhTriangle {
    if VEC16_LANE_WORDS {
        let w = vec16_words(triangle_words[t * 12u + min(g_lane, 11u)]);
        return BvhTriangle(
            vec3<f32>(bitcast<f32>(w[0]), bitcast<f32>(w[1]), bitcast<f32>(w[2])), w[3],
            vec3<f32>(bitcast<f32>(w[4]), bitcast<f32>(w[5]), bitcast<f32>(w[6])), w[7],
            vec3<f32>(bitcast<f32>(w[8]), bitcast<f32>(w[9]), bitcast<f32>(w[10])), w[11],
        );
    }
    return triangles[t];
}
