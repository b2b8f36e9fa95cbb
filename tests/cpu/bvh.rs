//! BVH properties on generated scenes and random meshes: every triangle in
//! exactly one leaf, children inside parents, and closest-hit / any-hit over the
//! BVH equal to brute force over all triangles on random rays.

use crate::support;

use std::path::Path;

use glam::Vec3;
use penumbra::bvh::{BuildQuality, Bvh, BvhSettings};
use penumbra::{assets, scene::Scene};
use support::bvh::{check_queries, check_structure, random_rays};
use support::{Rng, flat_grid, random_soup};

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
    assert!(
        matches!(e, penumbra::Error::InvalidValue { .. }) && e.to_string().contains("max_leaf_size = 0"),
        "{e}"
    );
}

#[test]
fn structure_check_can_fail() {
    let mut rng = Rng::new(3);
    let corners = random_soup(&mut rng, 200, 0.1);
    let mut bvh = Bvh::build_from_corners(&corners, &BvhSettings::default()).unwrap();
    // Shrink a leaf's box: the containment check must notice.
    let leaf = bvh.nodes.iter().position(|n| n.is_leaf()).unwrap();
    let max_leaf = BvhSettings::default().max_leaf_size;
    assert!(
        check_structure(&corners, &bvh, max_leaf).is_ok(),
        "the built tree passes"
    );
    bvh.nodes[leaf].bmax = bvh.nodes[leaf].bmin;
    assert!(check_structure(&corners, &bvh, max_leaf).is_err());
}
