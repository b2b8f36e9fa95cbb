//! Ray–box and ray–triangle tests shared by every CPU traversal; the WGSL
//! kernels use the same formulas in the same order.

use glam::Vec3;

use crate::contract::intersect::BOX_EXIT_SCALE;
use crate::contract::layout::{BvhNode, BvhTriangle};

/// Reciprocal direction with zero components replaced by a tiny same-signed
/// value, so slab distances are ±huge instead of NaN (0·∞) for axis-parallel rays.
pub fn safe_inverse(d: Vec3) -> Vec3 {
    const TINY: f32 = 1e-30;
    let fix = |c: f32| if c.abs() < TINY { TINY.copysign(c) } else { c };
    Vec3::new(1.0 / fix(d.x), 1.0 / fix(d.y), 1.0 / fix(d.z))
}

/// A ray prepared for box tests.
#[derive(Clone, Copy, Debug)]
pub struct RayBox {
    /// Origin.
    pub origin: Vec3,
    /// [`safe_inverse`] of the direction.
    pub inv_dir: Vec3,
}

/// Entry distance of the ray into the node's box within `[0, t_max]`, or `None` when it misses.
pub fn intersect_box(ray: &RayBox, node: &BvhNode, t_max: f32) -> Option<f32> {
    let t0 = (node.bmin - ray.origin) * ray.inv_dir;
    let t1 = (node.bmax - ray.origin) * ray.inv_dir;
    let t_near = t0.min(t1).max_element().max(0.0);
    let t_far = t0.max(t1).min_element().min(t_max) * BOX_EXIT_SCALE;
    (t_near <= t_far).then_some(t_near)
}

/// Möller–Trumbore: distance `t` and barycentrics `(u, v)` of the hit with
/// `0 < t < t_max`, both faces, or `None`. Edges count as inside (`u, v ≥ 0`,
/// `u + v ≤ 1`), but the two triangles of a shared edge round their barycentrics
/// differently, so a ray through the edge itself can miss both: it is not
/// watertight (`tests/cpu/shadow_mft.rs` aims 4,096 rays at a shared edge and counts
/// those that pass; the multi-frusta test lets none through).
pub fn intersect_triangle(tri: &BvhTriangle, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(f32, f32, f32)> {
    let (e1, e2) = (tri.v1 - tri.v0, tri.v2 - tri.v0);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0;
    let u = s.dot(p) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv_det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv_det;
    (t > 0.0 && t < t_max).then_some((t, u, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(a: Vec3, b: Vec3, c: Vec3) -> BvhTriangle {
        BvhTriangle {
            v0: a,
            v1: b,
            v2: c,
            ..Default::default()
        }
    }

    #[test]
    fn triangle_hit_and_miss() {
        let t = tri(Vec3::ZERO, Vec3::X, Vec3::Y);
        let (d, u, v) =
            intersect_triangle(&t, Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z, f32::INFINITY).unwrap();
        assert_eq!((d, u, v), (1.0, 0.25, 0.25));
        assert!(intersect_triangle(&t, Vec3::new(0.75, 0.75, 1.0), Vec3::NEG_Z, f32::INFINITY).is_none());
        assert!(
            intersect_triangle(&t, Vec3::new(0.25, 0.25, 1.0), Vec3::NEG_Z, 1.0).is_none(),
            "t_max is exclusive"
        );
        assert!(
            intersect_triangle(&t, Vec3::new(0.25, 0.25, 1.0), Vec3::Z, f32::INFINITY).is_none(),
            "behind"
        );
    }

    #[test]
    fn axis_parallel_ray_in_flat_box() {
        let node = BvhNode {
            bmin: Vec3::new(0.0, 0.0, 0.0),
            bmax: Vec3::new(1.0, 0.0, 1.0),
            ..Default::default()
        };
        let ray = RayBox {
            origin: Vec3::new(0.5, 1.0, 0.5),
            inv_dir: safe_inverse(Vec3::NEG_Y),
        };
        assert_eq!(intersect_box(&ray, &node, f32::INFINITY), Some(1.0));
        // A ray with a zero direction component on the face of a thick box still enters it.
        let thick = BvhNode {
            bmax: Vec3::new(1.0, 1.0, 1.0),
            ..node
        };
        let on_face = RayBox {
            origin: Vec3::new(-1.0, 0.0, 0.5),
            inv_dir: safe_inverse(Vec3::X),
        };
        assert_eq!(intersect_box(&on_face, &thick, f32::INFINITY), Some(1.0));
        let beside = RayBox {
            origin: Vec3::new(-1.0, 1.001, 0.5),
            inv_dir: safe_inverse(Vec3::X),
        };
        assert_eq!(intersect_box(&beside, &thick, f32::INFINITY), None);
        // In the plane of a zero-thickness box the slab is [0, 0] and the ray misses:
        // harmless, since any triangle in that box is edge-on to the ray (det = 0).
    }
}
