//! What the traversal kernels share with Rust about the flattened BVH
//! (`shaders/shared/bvh.wgsl`, `shaders/shared/bvh_vec16.wgsl`): the stack depth and the
//! node and triangle sizes in words; the structs themselves are in [`crate::contract::layout`].

use crate::contract::layout::{BvhNode, BvhTriangle};

/// Depth of every kernel's traversal stack (`STACK_SIZE`); a BVH deeper than this cannot
/// be traced ([`crate::gpu::validate_for_gpu`]).
pub const STACK_SIZE: usize = 64;

/// Most triangles one leaf holds ([`crate::bvh::BvhSettings::max_leaf_size`] at most; checked
/// by [`crate::gpu::validate_for_gpu`]): the MFT shadow kernel keeps a stack entry's count in
/// the 8 bits above its 16 frusta ([`crate::contract::suspend::STACK_COUNT_SHIFT`]).
pub const MAX_LEAF_TRIANGLES: u32 = 255;

/// 32-bit words of a [`BvhNode`] (`NODE_WORDS`, the vector kernels read nodes word by word).
pub const NODE_WORDS: usize = size_of::<BvhNode>() / 4;

/// 32-bit words of a [`BvhTriangle`] (`TRIANGLE_WORDS`).
pub const TRIANGLE_WORDS: usize = size_of::<BvhTriangle>() / 4;
