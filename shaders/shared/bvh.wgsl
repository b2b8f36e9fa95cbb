// The flattened BVH as the GPU reads it: 32-byte nodes and 48-byte triangles.
// Mirrors `src/contract/layout.rs` (BvhNode, BvhTriangle); a naga test checks sizes and offsets.

// Entries of every traversal stack (a BVH deeper than this is refused on the CPU;
// src/contract/mod.rs STACK_SIZE, checked by a naga test).
const STACK_SIZE: u32 = 64u;

// One BVH node, 32 bytes. Inner node (count == 0): its children are nodes
// `first` and `first + 1`, so one 64-byte read brings both child boxes.
// Leaf (count > 0): triangles `first .. first + count`, stored in leaf order.
struct BvhNode {
    bmin: vec3<f32>,  // bytes 0..12: box minimum
    first: u32,       // bytes 12..16: first child node (inner) or first triangle (leaf)
    bmax: vec3<f32>,  // bytes 16..28: box maximum
    count: u32,       // bytes 28..32: triangle count; 0 marks an inner node
}

// One triangle, 48 bytes: its three corners as the scene gives them, so that the
// copies of a vertex that several triangles share are the same bits (the frusta's edge
// functions are then exactly negated across a shared edge). Shading data lives in other
// buffers, indexed alike.
struct BvhTriangle {
    v0: vec3<f32>,         // bytes 0..12: corner 0
    scene_index: u32,      // bytes 12..16: index of the triangle in the loaded scene
    v1: vec3<f32>,         // bytes 16..28: corner 1
    alpha: u32,            // bytes 28..32: its AlphaTriangle's word offset, ALPHA_OPAQUE for none
    v2: vec3<f32>,         // bytes 32..44: corner 2
    pad2: u32,             // bytes 44..48: unused
}

// A node and a triangle from their 32-bit words, in the layouts above: the
// kernels that bind `nodes` and `triangles` as arrays of u32 (shared/bvh_vec16)
// build them so.
fn node_of_words(w0: u32, w1: u32, w2: u32, w3: u32, w4: u32, w5: u32, w6: u32, w7: u32) -> BvhNode {
    return BvhNode(
        vec3<f32>(bitcast<f32>(w0), bitcast<f32>(w1), bitcast<f32>(w2)), w3,
        vec3<f32>(bitcast<f32>(w4), bitcast<f32>(w5), bitcast<f32>(w6)), w7,
    );
}

fn triangle_of_words(
    w0: u32, w1: u32, w2: u32, w3: u32, w4: u32, w5: u32,
    w6: u32, w7: u32, w8: u32, w9: u32, w10: u32, w11: u32,
) -> BvhTriangle {
    return BvhTriangle(
        vec3<f32>(bitcast<f32>(w0), bitcast<f32>(w1), bitcast<f32>(w2)), w3,
        vec3<f32>(bitcast<f32>(w4), bitcast<f32>(w5), bitcast<f32>(w6)), w7,
        vec3<f32>(bitcast<f32>(w8), bitcast<f32>(w9), bitcast<f32>(w10)), w11,
    );
}
