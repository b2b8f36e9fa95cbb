//! Stack-based traversal of the flat BVH: closest hit (primary rays) and any
//! hit (shadow rays).

use glam::Vec3;

use super::intersect::{RayBox, intersect_box, intersect_triangle, safe_inverse};
use crate::bvh::Bvh;
use crate::contract::counters::Counters;
use crate::contract::layout::BvhTriangle;

/// The nearest intersection along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray direction (in units of its length).
    pub t: f32,
    /// Index into [`Bvh::triangles`] (leaf order).
    pub triangle: u32,
    /// Barycentric weight of corner 1.
    pub u: f32,
    /// Barycentric weight of corner 2.
    pub v: f32,
}

/// Möller–Trumbore's hit `(t, u, v)` of `tri` with `0 < t < t_max` where the surface is
/// there: not where an alpha-tested triangle's mask lets the ray pass
/// ([`crate::bvh::AlphaMasks::passes`]). What every per-ray test of the kernels computes.
pub fn intersect_surface(
    bvh: &Bvh,
    tri: &BvhTriangle,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    intersect_triangle(tri, origin, dir, t_max)
        .filter(|&(_, u, v)| !bvh.alpha.passes(tri, [1.0 - u - v, u, v]))
}

/// The nearest hit with `0 < t < t_max`, or `None`. Children are visited
/// nearer-first; a box farther than the best hit so far is skipped.
pub fn closest_hit(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
    closest_hit_counted(bvh, origin, dir, t_max, &mut Counters::default())
}

/// [`closest_hit`], adding its work to `counters` as the per-ray primary
/// kernel counts it: the root's box test, then per inner node one step and
/// two box tests, per leaf triangle one access and one test (no culling).
pub fn closest_hit_counted(
    bvh: &Bvh,
    origin: Vec3,
    dir: Vec3,
    t_max: f32,
    counters: &mut Counters,
) -> Option<Hit> {
    let ray = RayBox {
        origin,
        inv_dir: safe_inverse(dir),
    };
    let mut best: Option<Hit> = None;
    let mut t_best = t_max;
    let mut stack = Vec::with_capacity(64);
    counters.box_tests += 1;
    if intersect_box(&ray, &bvh.nodes[0], t_best).is_some() {
        stack.push(0u32);
    }
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes[i as usize];
        if node.is_leaf() {
            for ix in node.first..node.first + node.count {
                counters.triangles_accessed += 1;
                counters.triangles_after_culling += 1;
                counters.triangle_tests += 1;
                if let Some((t, u, v)) =
                    intersect_surface(bvh, &bvh.triangles[ix as usize], origin, dir, t_best)
                {
                    t_best = t;
                    best = Some(Hit {
                        t,
                        triangle: ix,
                        u,
                        v,
                    });
                }
            }
            continue;
        }
        counters.nodes_visited += 1;
        counters.box_tests += 2;
        let (l, r) = (node.first, node.first + 1);
        let tl = intersect_box(&ray, &bvh.nodes[l as usize], t_best);
        let tr = intersect_box(&ray, &bvh.nodes[r as usize], t_best);
        match (tl, tr) {
            (Some(a), Some(b)) => {
                // Push the farther child first so the nearer one is popped next.
                let (near, far) = if a <= b { (l, r) } else { (r, l) };
                stack.push(far);
                stack.push(near);
            }
            (Some(_), None) => stack.push(l),
            (None, Some(_)) => stack.push(r),
            (None, None) => {}
        }
    }
    best
}

/// Whether any triangle is hit with `0 < t < t_max` (a shadow ray: origin at
/// the shade point, `dir` to the light sample, `t_max` just under 1).
pub fn any_hit(bvh: &Bvh, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
    let ray = RayBox {
        origin,
        inv_dir: safe_inverse(dir),
    };
    let mut stack = Vec::with_capacity(64);
    if intersect_box(&ray, &bvh.nodes[0], t_max).is_some() {
        stack.push(0u32);
    }
    while let Some(i) = stack.pop() {
        let node = &bvh.nodes[i as usize];
        if node.is_leaf() {
            let tris = &bvh.triangles[node.first as usize..(node.first + node.count) as usize];
            if tris
                .iter()
                .any(|t| intersect_surface(bvh, t, origin, dir, t_max).is_some())
            {
                return true;
            }
            continue;
        }
        for c in [node.first, node.first + 1] {
            if intersect_box(&ray, &bvh.nodes[c as usize], t_max).is_some() {
                stack.push(c);
            }
        }
    }
    false
}
