//! The suspended state of a vector's traversal (`shaders/shared/suspend.wgsl`), shared by
//! the MFT and packet shadow kernels and their twins: a tile (MFT) or pixel (packet) that
//! reaches its iteration budget saves its traversal in its slot of the state buffer and
//! the next dispatch resumes from it. Word offsets in a slot; the MFT kernel's own words
//! follow ([`crate::contract::shadow::STATE_WORDS`]).

/// Word of the status ([`STATUS_SUSPENDED`] while a tile waits to be resumed).
pub const ST_STATUS: usize = 0;
/// First of the 16 lane masks.
pub const ST_LANES: usize = 8;
/// First of the stack's [`crate::contract::bvh::STACK_SIZE`] nodes.
pub const ST_STACK_NODE: usize = 24;
/// First of the stack's [`crate::contract::bvh::STACK_SIZE`] frustum masks.
pub const ST_STACK_MASK: usize = 88;
/// Where the MFT kernel's stack mask word keeps the node's triangle count (`STACK_COUNT_SHIFT`):
/// the MFT kernel's entry is the node's `first` (in the node word) and its 16 frusta with
/// `count << STACK_COUNT_SHIFT` (in the mask word), so that a pop needs no node load; the
/// packet kernel's is the node's index and its rays.
pub const STACK_COUNT_SHIFT: u32 = 16;
/// [`ST_STATUS`] of a suspended tile.
pub const STATUS_SUSPENDED: u32 = 1;
