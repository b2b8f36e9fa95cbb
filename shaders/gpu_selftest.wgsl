// GPU self-test: copies the `count` field of every BVH node into a u32 buffer.
// Run by tests/gpu/smoke.rs to check adapter, buffers, timer and `#import` end to end.
// CPU twin: none (the test compares with the BVH's own counts).

#import shared/bvh
#import shared/groups

@group(0) @binding(0) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(1) var<storage, read_write> counts: array<u32>;

@compute @workgroup_size(LINE_GROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let node_ix = gid.x;
    // The last workgroup runs past the end; buffers may also be padded, so bound by both.
    if node_ix < arrayLength(&nodes) && node_ix < arrayLength(&counts) {
        counts[node_ix] = nodes[node_ix].count;
    }
}
