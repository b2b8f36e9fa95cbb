// The suspended state of a vector's traversal, shared by shadow_mft and shadow_packet:
// a tile (MFT) or pixel (packet) that reaches its iteration budget saves it in its
// slot of `state` and the next dispatch resumes from it. Word offsets in a slot; the
// MFT kernel adds its own after ST_STACK_MASK + STACK_SIZE (src/contract/shadow.rs holds
// the same layout; naga tests check both kernels against it). The kernel binds the slots
// as `state: array<u32>` (read_write), which the functions below read and write.

#import shared/bvh
const ST_STATUS: u32 = 0u;       // STATUS_SUSPENDED while the slot waits to be resumed
const ST_LANES: u32 = 8u;        // 16 lane words
const ST_STACK_NODE: u32 = 24u;  // STACK_SIZE stack nodes
const ST_STACK_MASK: u32 = 88u;  // STACK_SIZE stack masks
const STATUS_SUSPENDED: u32 = 1u;
// The MFT kernel's stack entry: the node's first (stack_node) and its frusta with its
// count above them, count << STACK_COUNT_SHIFT (stack_mask); the packet kernel's: the
// node's index and its rays.
const STACK_COUNT_SHIFT: u32 = 16u;

// The vector's traversal stack (the same in every lane): node and frusta (MFT) or rays
// (packet) that want it (STACK_COUNT_SHIFT says how each kernel writes them).
var<private> stack_node: array<u32, STACK_SIZE>;
var<private> stack_mask: array<u32, STACK_SIZE>;

// Reads stack entries 0 .. depth from the slot at `base`. Whether it read all of them:
// lavapipe may end this loop early (its iteration limit counts these passes too), and a
// stack cut short must not be traced from.
fn restore_stack(base: u32, depth: u32) -> bool {
    var i = 0u;
    loop {
        if i >= depth {
            break;
        }
        stack_node[i] = state[base + ST_STACK_NODE + i];
        stack_mask[i] = state[base + ST_STACK_MASK + i];
        i += 1u;
    }
    return i >= depth;
}

// Writes stack entries 0 .. depth to the slot at `base`; whether it wrote all of them (as
// restore_stack).
fn save_stack(base: u32, depth: u32) -> bool {
    var i = 0u;
    loop {
        if i >= depth {
            break;
        }
        state[base + ST_STACK_NODE + i] = stack_node[i];
        state[base + ST_STACK_MASK + i] = stack_mask[i];
        i += 1u;
    }
    return i >= depth;
}
