//! The CPU reference tracers: closest-hit and any-hit queries over the flat
//! BVH, reading exactly the data the GPU reads ([`BvhNode`](crate::contract::layout::BvhNode)s
//! and [`BvhTriangle`](crate::contract::layout::BvhTriangle)s in leaf order) with the same
//! intersection arithmetic, the per-ray shadow oracle, and the CPU twin of the
//! multi-frusta shadow kernel and of the primary kernels, and the twin of the embedded
//! pass's G-buffer kernels. They are the oracles for the GPU kernels.

pub mod counters;
mod descend;
pub mod exact;
pub mod filter;
pub mod gbuffer_from_surface;
mod intersect;
pub(crate) mod parallel;
mod polygon;
pub mod primary;
pub mod primary_mft;
pub mod refine;
pub mod shade;
pub mod shadow_mft;
pub mod shadow_packet;
pub mod shadow_per_ray;
mod traverse;
pub mod visibility;

pub use intersect::{RayBox, intersect_box, intersect_triangle, safe_inverse};
pub use traverse::{Hit, any_hit, closest_hit, closest_hit_counted, intersect_surface};
