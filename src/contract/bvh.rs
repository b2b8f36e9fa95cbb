//! What the traversal kernels share with Rust about the flattened BVH
//! (`shaders/shared/bvh.wgsl`, `shaders/shared/bvh_vec16.wgsl`): the stack depth and the
//! node and triangle sizes in words; the structs themselves are in [`crate::contract::layout`].

use crate::contract::layout::{BvhNode, BvhTriangle};

/// Depth of every kernel's traversal stack (`STACK_SIZE`); a BVH deeper than this cannot
/// be traced ([`crate::gpu::validate_for_gpu`]).
pub const STACK_SIZE: usize = 64;

/// 32-bit words of a [`BvhNode`] (`NODE_WORDS`, the vector kernels read nodes word by word).
pub const NODE_WORDS: usize = size_of::<BvhNode>() / 4;

/// 32-bit words of a [`BvhTriangle`] (`TRIANGLE_WORDS`).
pub const TRIANGLE_WORDS: usize = size_of::<BvhTriangle>() / 4;
