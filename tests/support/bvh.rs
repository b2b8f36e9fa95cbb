//! BVH checks shared by the BVH tests: structure (every triangle in exactly one leaf,
//! children inside parents) and queries against brute force on random rays.

use glam::Vec3;
use penumbra::bvh::Bvh;
use penumbra::contract::layout::BvhNode;
use penumbra::reference::{any_hit, closest_hit, intersect_triangle};

use super::Rng;

/// Whether `outer` contains the box `bmin..bmax`.
pub fn contains(outer: &BvhNode, bmin: Vec3, bmax: Vec3) -> bool {
    outer.bmin.cmple(bmin).all() && bmax.cmple(outer.bmax).all()
}

/// Structure checks; returns a description of the first violation.
pub fn check_structure(corners: &[[Vec3; 3]], bvh: &Bvh, max_leaf: u32) -> Result<(), String> {
    let mut seen = vec![0u32; corners.len()];
    let mut reached_nodes = vec![false; bvh.nodes.len()];
    let mut stack = vec![0usize];
    let mut leaf_slots = 0usize;
    while let Some(i) = stack.pop() {
        if std::mem::replace(&mut reached_nodes[i], true) {
            return Err(format!("node {i} reached twice"));
        }
        let n = &bvh.nodes[i];
        if n.is_leaf() {
            if n.count > max_leaf {
                return Err(format!("leaf {i} holds {} > {max_leaf} triangles", n.count));
            }
            for ix in n.first..n.first + n.count {
                let t = bvh
                    .triangles
                    .get(ix as usize)
                    .ok_or(format!("leaf {i} points past the triangles"))?;
                let c = corners[t.scene_index as usize];
                let (lo, hi) = (c[0].min(c[1]).min(c[2]), c[0].max(c[1]).max(c[2]));
                if !contains(n, lo, hi) {
                    return Err(format!(
                        "leaf {i} box does not contain triangle {}",
                        t.scene_index
                    ));
                }
                if t.v0 != c[0] || t.v1 != c[1] || t.v2 != c[2] {
                    return Err(format!(
                        "triangle slot {ix} does not hold scene triangle {}",
                        t.scene_index
                    ));
                }
                seen[t.scene_index as usize] += 1;
            }
            leaf_slots += n.count as usize;
        } else {
            let (l, r) = (n.first as usize, n.first as usize + 1);
            if r >= bvh.nodes.len() {
                return Err(format!("node {i} children {l},{r} out of range"));
            }
            for c in [l, r] {
                let child = &bvh.nodes[c];
                if !contains(n, child.bmin, child.bmax) {
                    return Err(format!("child {c} is not inside its parent {i}"));
                }
                stack.push(c);
            }
        }
    }
    if let Some(i) = seen.iter().position(|&s| s != 1) {
        return Err(format!("triangle {i} is in {} leaves", seen[i]));
    }
    if leaf_slots != bvh.triangles.len() || bvh.triangles.len() != corners.len() {
        return Err("leaf triangle ranges do not cover the triangle array exactly".into());
    }
    if let Some(i) = reached_nodes.iter().position(|r| !r) {
        return Err(format!("node {i} is unreachable"));
    }
    Ok(())
}

/// Random rays: half from random points in the (expanded) bounds in random
/// directions, half aimed at random points on random triangles.
pub fn random_rays(corners: &[[Vec3; 3]], n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(seed);
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for c in corners.iter().flatten() {
        lo = lo.min(*c);
        hi = hi.max(*c);
    }
    let pad = (hi - lo).max(Vec3::splat(1e-3)) * 0.25;
    (0..n)
        .map(|k| {
            let o = rng.in_box(lo - pad, hi + pad);
            let d = if k % 2 == 0 {
                rng.direction()
            } else {
                let c = corners[(rng.next_u32() as usize) % corners.len()];
                let (a, b) = (rng.f32(), rng.f32());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let target = c[0] + a * (c[1] - c[0]) + b * (c[2] - c[0]);
                // Not normalised: t = 1 at the target, so segment ends around 1 cut some rays short.
                target - o
            };
            (o, d)
        })
        .collect()
}

/// Closest and any hit over the BVH against a loop over all triangles.
pub fn check_queries(bvh: &Bvh, rays: &[(Vec3, Vec3)]) -> Result<usize, String> {
    let mut hits = 0;
    for (k, &(o, d)) in rays.iter().enumerate() {
        // Shadow-style segments end at a random-ish distance so both outcomes occur.
        let t_max = if k % 3 == 0 {
            f32::INFINITY
        } else {
            0.3 + (k % 7) as f32 * 0.2
        };
        let brute = bvh
            .triangles
            .iter()
            .enumerate()
            .filter_map(|(i, t)| intersect_triangle(t, o, d, t_max).map(|(t, _, _)| (t, i)))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        let got = closest_hit(bvh, o, d, t_max);
        match (brute, got) {
            (None, None) => {}
            (Some((t, _)), Some(h)) if h.t == t => hits += 1,
            _ => {
                return Err(format!(
                    "ray {k} o={o} d={d} t_max={t_max}: brute force {brute:?}, BVH {got:?}"
                ));
            }
        }
        if any_hit(bvh, o, d, t_max) != brute.is_some() {
            return Err(format!(
                "ray {k} o={o} d={d} t_max={t_max}: any_hit disagrees with brute force"
            ));
        }
    }
    Ok(hits)
}
