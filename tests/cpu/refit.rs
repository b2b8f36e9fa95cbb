//! Refitting the flattened BVH after triangles move: the refitted tree has the tight
//! boxes of the moved geometry, answers queries like brute force, reports every change in
//! its upload ranges, and its SAH cost grows when moved triangles scatter.

use crate::support;

use glam::{Mat4, Quat, Vec3};
use penumbra::bvh::{Bvh, BvhSettings, MERGE_GAP_BYTES};
use penumbra::contract::layout::BvhNode;
use support::bvh::{check_queries, check_structure, random_rays};
use support::{Rng, random_soup};

/// A soup whose first `k` triangles form an "object", moved by `m`.
fn moved(corners: &[[Vec3; 3]], k: usize, m: Mat4) -> Vec<[Vec3; 3]> {
    corners
        .iter()
        .enumerate()
        .map(|(i, c)| {
            if i < k {
                c.map(|p| m.transform_point3(p))
            } else {
                *c
            }
        })
        .collect()
}

/// Leaf-order slots of the scene triangles `0..k`.
fn slots_of_first(bvh: &Bvh, k: usize) -> Vec<u32> {
    (0..bvh.triangles.len() as u32)
        .filter(|&s| (bvh.triangles[s as usize].scene_index as usize) < k)
        .collect()
}

/// Every box is exactly the bounds of what it holds (not merely containing it).
fn assert_tight(bvh: &Bvh, corners: &[[Vec3; 3]]) {
    for i in (0..bvh.nodes.len()).rev() {
        let n = bvh.nodes[i];
        let (lo, hi) = if n.is_leaf() {
            bvh.triangles[n.first as usize..(n.first + n.count) as usize]
                .iter()
                .flat_map(|t| corners[t.scene_index as usize])
                .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p), hi.max(p))
                })
        } else {
            let (a, b) = (bvh.nodes[n.first as usize], bvh.nodes[n.first as usize + 1]);
            (a.bmin.min(b.bmin), a.bmax.max(b.bmax))
        };
        assert_eq!((n.bmin, n.bmax), (lo, hi), "node {i} is not tight");
    }
}

#[test]
fn refitted_tree_is_tight_and_matches_brute_force() {
    let mut rng = Rng::new(11);
    let corners = random_soup(&mut rng, 3000, 0.05);
    let k = 400;
    for (label, m) in [
        ("small shift", Mat4::from_translation(Vec3::new(0.01, 0.0, -0.02))),
        (
            "rotated and moved out of the cube",
            Mat4::from_rotation_translation(Quat::from_rotation_y(0.8), Vec3::new(1.5, 0.3, 0.0)),
        ),
        ("scaled to a point", Mat4::from_scale(Vec3::splat(1e-3))),
    ] {
        let mut bvh = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
        let now = moved(&corners, k, m);
        bvh.refit(&now, &slots_of_first(&bvh, k));
        check_structure(&now, &bvh, BvhSettings::default().max_leaf_size)
            .unwrap_or_else(|e| panic!("{label}: {e}"));
        assert_tight(&bvh, &now);
        let rays = random_rays(&now, 3000, 5);
        let hits = check_queries(&bvh, &rays).unwrap_or_else(|e| panic!("{label}: {e}"));
        assert!(hits > 500, "{label}: only {hits} hits; the test is not testing");
    }
}

#[test]
fn upload_ranges_cover_every_change_and_nothing_far_from_one() {
    let mut rng = Rng::new(12);
    let corners = random_soup(&mut rng, 5000, 0.03);
    let mut bvh = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
    let before = bvh.clone();
    let k = 50;
    let now = moved(&corners, k, Mat4::from_translation(Vec3::new(0.2, 0.1, 0.0)));
    let refit = bvh.refit(&now, &slots_of_first(&bvh, k));
    let inside = |ranges: &[std::ops::Range<usize>], i: usize| ranges.iter().any(|r| r.contains(&i));
    for i in 0..bvh.nodes.len() {
        if bvh.nodes[i] != before.nodes[i] {
            assert!(inside(&refit.nodes, i), "changed node {i} is not uploaded");
        }
    }
    for i in 0..bvh.triangles.len() {
        if bvh.triangles[i] != before.triangles[i] {
            assert!(
                inside(&refit.triangles, i),
                "changed triangle {i} is not uploaded"
            );
        }
    }
    // Ranges are sorted, disjoint, separated by more than the merge gap, and start and
    // end on changed entries.
    let gap = MERGE_GAP_BYTES / size_of::<BvhNode>();
    for w in refit.nodes.windows(2) {
        assert!(
            w[1].start > w[0].end + gap,
            "{:?} and {:?} should have merged",
            w[0],
            w[1]
        );
    }
    for r in &refit.nodes {
        assert_ne!(bvh.nodes[r.start], before.nodes[r.start]);
        assert_ne!(bvh.nodes[r.end - 1], before.nodes[r.end - 1]);
    }
    let uploaded: usize = refit.nodes.iter().map(|r| r.len()).sum();
    eprintln!(
        "{k} of 5000 triangles moved: {uploaded} of {} nodes uploaded in {} ranges, \
         {} triangle ranges",
        bvh.nodes.len(),
        refit.nodes.len(),
        refit.triangles.len()
    );
    assert!(
        uploaded * 4 < bvh.nodes.len(),
        "a small move uploads a small part of the tree"
    );
}

#[test]
fn refit_then_refit_back_restores_the_tree() {
    let mut rng = Rng::new(13);
    let corners = random_soup(&mut rng, 1000, 0.05);
    let built = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
    let mut bvh = built.clone();
    let slots = slots_of_first(&bvh, 300);
    bvh.refit(&moved(&corners, 300, Mat4::from_translation(Vec3::X)), &slots);
    assert_ne!(bvh.nodes, built.nodes);
    bvh.refit(&corners, &slots);
    assert_eq!(bvh.triangles, built.triangles);
    // The builder's boxes are the tight ones, so refitting back gives them exactly.
    assert_eq!(bvh.nodes, built.nodes);
}

#[test]
fn sah_cost_grows_as_moved_triangles_scatter() {
    let mut rng = Rng::new(14);
    let corners = random_soup(&mut rng, 4000, 0.02);
    let mut bvh = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
    let built = bvh.sah_cost();
    assert!(
        (built - bvh.stats().sah_cost).abs() < 1e-9 * built,
        "sah_cost agrees with stats"
    );
    // Scatter a quarter of the triangles: each moves by its own offset.
    let mut now = corners.clone();
    for c in now.iter_mut().take(1000) {
        let d = rng.in_box(Vec3::splat(-1.0), Vec3::ONE);
        *c = c.map(|p| p + d);
    }
    bvh.refit(&now, &slots_of_first(&bvh, 1000));
    let refitted = bvh.sah_cost();
    let rebuilt = Bvh::build_from_corners(&now, &BvhSettings::default())
        .unwrap()
        .sah_cost();
    eprintln!("SAH: built {built:.1}, refitted after scattering {refitted:.1}, rebuilt {rebuilt:.1}");
    assert!(
        refitted > 1.5 * rebuilt,
        "refitting a scattered soup is much worse than rebuilding"
    );
}
