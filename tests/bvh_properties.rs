//! BVH properties on generated scenes and random meshes: every triangle in
//! exactly one leaf, children inside parents, and closest-hit / any-hit over the
//! BVH equal to brute force over all triangles on random rays.

mod support;

use std::path::Path;

use glam::Vec3;
use penumbra::bvh::{BuildQuality, Bvh, BvhSettings};
use penumbra::layout::BvhNode;
use penumbra::reference::{any_hit, closest_hit, intersect_triangle};
use penumbra::{assets, scene::Scene};
use support::{Rng, flat_grid, random_soup};

fn contains(outer: &BvhNode, bmin: Vec3, bmax: Vec3) -> bool {
    outer.bmin.cmple(bmin).all() && bmax.cmple(outer.bmax).all()
}

/// Structure checks; returns a description of the first violation.
fn check_structure(corners: &[[Vec3; 3]], bvh: &Bvh, max_leaf: u32) -> Result<(), String> {
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
                if t.v0 != c[0] || t.e1 != c[1] - c[0] || t.e2 != c[2] - c[0] {
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
fn random_rays(corners: &[[Vec3; 3]], n: usize, seed: u64) -> Vec<(Vec3, Vec3)> {
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
fn check_queries(bvh: &Bvh, rays: &[(Vec3, Vec3)]) -> Result<usize, String> {
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

fn check_all(name: &str, corners: &[[Vec3; 3]], n_rays: usize) {
    for (leaf, quality) in [
        (1, BuildQuality::Fast),
        (4, BuildQuality::Medium),
        (8, BuildQuality::High),
    ] {
        let settings = BvhSettings {
            max_leaf_size: leaf,
            quality,
        };
        let bvh = Bvh::build_from_corners(corners, &settings).expect("build");
        check_structure(corners, &bvh, leaf).unwrap_or_else(|e| panic!("{name} {settings:?}: {e}"));
        let rays = random_rays(corners, n_rays, 7 + leaf as u64);
        let hits = check_queries(&bvh, &rays).unwrap_or_else(|e| panic!("{name} {settings:?}: {e}"));
        // Half the rays aim at triangles, so a working test sees many hits.
        assert!(
            hits > n_rays / 4,
            "{name}: only {hits} of {n_rays} rays hit; the test is not testing"
        );
    }
}

#[test]
fn random_soups_match_brute_force() {
    let mut rng = Rng::new(1);
    check_all(
        "soup of 3000 small triangles",
        &random_soup(&mut rng, 3000, 0.05),
        10_000,
    );
    check_all(
        "soup of 500 large triangles",
        &random_soup(&mut rng, 500, 0.6),
        10_000,
    );
}

#[test]
fn generated_scenes_match_brute_force() {
    for s in assets::EMBEDDED_SCENES {
        let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).expect("embedded scene loads");
        let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
        check_all(s.name, &corners, 10_000);
    }
}

#[test]
fn degenerate_inputs() {
    let one = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
    check_all("single triangle", &one, 1000);
    check_all("flat grid (zero-thickness boxes)", &flat_grid(40), 10_000);
    // Many copies of the same triangle: the builder cannot split them by position.
    let same = vec![[Vec3::ZERO, Vec3::X, Vec3::Z]; 300];
    check_all("300 identical triangles", &same, 2000);
}

#[test]
fn empty_input_and_bad_leaf_size_are_errors() {
    let e = Bvh::build_from_corners(&[], &BvhSettings::default()).unwrap_err();
    assert!(e.to_string().contains("no triangles"), "{e}");
    let one = [[Vec3::ZERO, Vec3::X, Vec3::Y]];
    let e = Bvh::build_from_corners(
        &one,
        &BvhSettings {
            max_leaf_size: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("leaf size"), "{e}");
}

#[test]
fn structure_check_can_fail() {
    let mut rng = Rng::new(3);
    let corners = random_soup(&mut rng, 200, 0.1);
    let mut bvh = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
    // Shrink a leaf's box: the containment check must notice.
    let leaf = bvh.nodes.iter().position(|n| n.is_leaf()).unwrap();
    bvh.nodes[leaf].bmax = bvh.nodes[leaf].bmin;
    assert!(check_structure(&corners, &bvh, 4).is_err());
}
