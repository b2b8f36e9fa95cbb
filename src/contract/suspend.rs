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
/// [`ST_STATUS`] of a suspended tile.
pub const STATUS_SUSPENDED: u32 = 1;
