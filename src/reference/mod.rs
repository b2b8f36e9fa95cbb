//! The CPU reference tracer: closest-hit and any-hit queries over the flat BVH,
//! reading exactly the data the GPU reads ([`BvhNode`](crate::layout::BvhNode)s
//! and [`BvhTriangle`](crate::layout::BvhTriangle)s in leaf order) with the same
//! intersection arithmetic. It is the oracle for the GPU kernels.

mod intersect;
mod traverse;

pub use intersect::{RayBox, intersect_box, intersect_triangle, safe_inverse};
pub use traverse::{Hit, any_hit, closest_hit};
