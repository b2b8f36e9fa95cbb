//! The CPU reference tracers: closest-hit and any-hit queries over the flat
//! BVH, reading exactly the data the GPU reads ([`BvhNode`](crate::layout::BvhNode)s
//! and [`BvhTriangle`](crate::layout::BvhTriangle)s in leaf order) with the same
//! intersection arithmetic, the per-ray shadow oracle, and the CPU twin of the
//! multi-frusta shadow kernel and of the primary kernels, and the twin of the embedded
//! pass's G-buffer kernels. They are the oracles for the GPU kernels.

pub mod counters;
mod descend;
pub mod exact;
mod intersect;
pub mod mft;
pub mod packet;
mod parallel;
mod polygon;
pub mod primary;
pub mod primary_mft;
pub mod refine;
pub mod shade;
pub mod shadow;
pub mod surface;
mod traverse;

pub use intersect::{RayBox, intersect_box, intersect_triangle, safe_inverse};
pub use traverse::{Hit, any_hit, closest_hit, closest_hit_counted};
