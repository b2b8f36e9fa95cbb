//! CPU twin of the 16-ray packet shadow kernel (`shaders/shadow_packet.wgsl`),
//! the paper's baseline: one 16-lane vector holds one pixel's 16 shadow rays,
//! which traverse the BVH together. A node is entered when any still-active
//! ray's slab test hits it; at a leaf every active ray is tested against every
//! triangle (Möller–Trumbore, as the per-ray oracle) and a ray that hits drops
//! out (early termination). The traversal order and step structure are those
//! of the MFT kernel (see [`super::shadow_mft`]), so the two differ only in what a
//! lane is: a ray here, a frustum there.

use glam::Vec3;

use super::counters::Counters;
use super::descend::descend;
use super::shadow_per_ray::initial_mask;
use super::{RayBox, intersect_box, intersect_surface, safe_inverse};
use crate::bvh::Bvh;
use crate::contract::bvh::STACK_SIZE;
use crate::contract::layout::MASK_SKY;
use crate::contract::layout::{GBufferTexel, ShadowParams};
use crate::sampling::{SAMPLES_PER_SET, pixel_set};

/// Traces one pixel's 16 rays as a packet; returns its mask (bits of blocked
/// rays, or [`MASK_SKY`]). `budget` mimics the kernel's per-dispatch iteration
/// budget (a suspension is counted each time it runs out).
pub fn trace_packet(
    bvh: &Bvh,
    texel: &GBufferTexel,
    set: usize,
    light_points: &[Vec3],
    params: &ShadowParams,
    budget: u32,
    counters: &mut Counters,
) -> u32 {
    let initial = initial_mask(texel, set, light_points, params);
    if initial & MASK_SKY != 0 {
        return initial;
    }
    let dirs: [Vec3; SAMPLES_PER_SET] =
        std::array::from_fn(|j| light_points[set * SAMPLES_PER_SET + j] - texel.origin);
    let rays = dirs.map(|d| RayBox {
        origin: texel.origin,
        inv_dir: safe_inverse(d),
    });
    let mut blocked = initial;
    let hits_box =
        |j: usize, node: u32| intersect_box(&rays[j], &bvh.nodes[node as usize], params.t_max).is_some();
    let ballot = |pred: &dyn Fn(usize) -> bool| {
        (0..SAMPLES_PER_SET)
            .filter(|&j| pred(j))
            .fold(0u32, |m, j| m | 1 << j)
    };

    let mut alive = !blocked & 0xffff;
    counters.box_tests += 1;
    let mut mask = ballot(&|j| alive & (1 << j) != 0 && hits_box(j, 0));
    let mut running = mask != 0;
    let (mut node, mut cursor, mut end) = (0u32, 0u32, 0u32);
    let mut stack: Vec<(u32, u32)> = Vec::with_capacity(STACK_SIZE);
    let mut popping = false;
    let enter = |c: u32, cursor: &mut u32, end: &mut u32| {
        let n = &bvh.nodes[c as usize];
        if n.is_leaf() {
            *cursor = n.first;
            *end = n.first + n.count;
        }
    };
    enter(0, &mut cursor, &mut end);
    let mut iterations = 0u32;
    while running {
        if iterations == budget {
            counters.suspensions += 1;
            iterations = 0;
        }
        iterations += 1;
        counters.traversal_steps += 1;
        if cursor < end {
            let tri = &bvh.triangles[cursor as usize];
            cursor += 1;
            counters.triangles_accessed += 1;
            counters.triangles_after_culling += 1;
            counters.triangle_tests += 1;
            let active = mask & alive;
            let hits = ballot(&|j| {
                active & (1 << j) != 0
                    && intersect_surface(bvh, tri, texel.origin, dirs[j], params.t_max).is_some()
            });
            blocked |= hits;
            alive &= !hits;
            if cursor == end {
                running = alive != 0;
                popping = true;
            }
        } else if popping {
            match stack.pop() {
                None => running = false,
                Some((c, m)) if m & alive != 0 => {
                    popping = false;
                    node = c;
                    mask = m & alive;
                    enter(c, &mut cursor, &mut end);
                }
                Some(_) => {}
            }
        } else {
            let l = bvh.nodes[node as usize].first;
            counters.nodes_visited += 1;
            counters.box_tests += 2;
            let active = mask & alive;
            let ml = ballot(&|j| active & (1 << j) != 0 && hits_box(j, l));
            let mr = ballot(&|j| active & (1 << j) != 0 && hits_box(j, l + 1));
            // Into the child more rays want first.
            let d = descend(l, ml, mr, mr.count_ones() > ml.count_ones());
            if let Some(later) = d.later {
                assert!(stack.len() < STACK_SIZE, "BVH deeper than the traversal stack");
                stack.push(later);
            }
            match d.now {
                Some((c, m)) => {
                    node = c;
                    mask = m;
                    enter(c, &mut cursor, &mut end);
                }
                None => popping = true,
            }
        }
    }
    blocked
}

/// Occlusion masks of a whole G-buffer (row-major) traced as 16-ray packets,
/// rows spread over all cores, and the summed counters.
pub fn packet_masks(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    budget: u32,
) -> (Vec<u32>, Counters) {
    let per_pixel = super::parallel::per_texel(gbuffer, params, |x, y, texel| {
        let mut c = Counters::default();
        let m = trace_packet(bvh, texel, pixel_set(x, y), light_points, params, budget, &mut c);
        (m, c)
    });
    let mut counters = Counters::default();
    let masks = per_pixel
        .into_iter()
        .map(|(m, c)| {
            counters += c;
            m
        })
        .collect();
    (masks, counters)
}
