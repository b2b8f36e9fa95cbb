// The suspended state of a vector's traversal, shared by shadow_mft and shadow_packet:
// a tile (MFT) or pixel (packet) that reaches its iteration budget saves it in its
// slot of `state` and the next dispatch resumes from it. Word offsets in a slot; the
// MFT kernel adds its own after ST_STACK_MASK + STACK_SIZE (src/contract/shadow.rs holds
// the same layout; naga tests check both kernels against it).
const ST_STATUS: u32 = 0u;       // STATUS_SUSPENDED while the slot waits to be resumed
const ST_LANES: u32 = 8u;        // 16 lane words
const ST_STACK_NODE: u32 = 24u;  // STACK_SIZE stack nodes
const ST_STACK_MASK: u32 = 88u;  // STACK_SIZE stack masks
const STATUS_SUSPENDED: u32 = 1u;
