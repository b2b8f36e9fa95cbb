//! The CPU twin of the multi-frusta kernel against the per-ray oracle on the
//! generated scenes: the same occlusion masks up to rays that graze an edge,
//! and the same masks whether or not a tile is suspended and resumed.

mod support;

use std::path::Path;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::frame::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::mft::{mft_masks, mft_masks_with};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow::{ITERATION_BUDGET, shadow_params};
use penumbra::{assets, sampling, scene::Scene};
use support::assert_masks_match_oracle;

#[test]
fn mft_twin_matches_per_ray_oracle_on_generated_scenes() {
    for s in assets::EMBEDDED_SCENES {
        let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
        let view = s.view();
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let diag = scene.bounds().diagonal();
        let (w, h) = (90, 70); // not a multiple of 4 on purpose: edge tiles are partial
        let cam = camera_params(&view.camera, w, h, diag * RAY_OFFSET_FRACTION);
        let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let (mft, counters) = mft_masks(&bvh, &gbuffer, &points, &params, ITERATION_BUDGET);
        let (differing, total, oracle) =
            assert_masks_match_oracle(s.name, &scene, &bvh, &view, &gbuffer, &mft, w, h);
        let occluded: u32 = oracle.iter().map(|m| (m & 0xffff).count_ones()).sum();
        println!(
            "{}: {differing} of {total} rays differ, {occluded} occluded; {counters:?}",
            s.name
        );
        assert!(
            occluded as usize > total / 20 && (occluded as usize) < total * 19 / 20,
            "{}: the view must have both light and shadow",
            s.name
        );
    }
}

#[test]
fn suspending_and_resuming_gives_the_same_masks() {
    let s = assets::default_scene();
    let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
    let view = s.view();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let (w, h) = (32, 32);
    let cam = camera_params(
        &view.camera,
        w,
        h,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
    let params = shadow_params(&view.light, w, h);
    let points = sampling::light_points(&view.light);
    let (whole, c1) = mft_masks(&bvh, &gbuffer, &points, &params, u32::MAX);
    let (pieces, c2) = mft_masks(&bvh, &gbuffer, &points, &params, 7);
    assert_eq!(c1.suspensions, 0);
    assert!(c2.suspensions > 10, "a budget of 7 iterations must suspend often");
    assert_eq!(whole, pieces);
}

#[test]
fn frustum_shrinking_keeps_the_masks_and_saves_triangle_tests() {
    for s in assets::EMBEDDED_SCENES {
        let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
        let view = s.view();
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let (w, h) = (64, 48);
        let cam = camera_params(
            &view.camera,
            w,
            h,
            scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
        );
        let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let (plain, c0) = mft_masks_with(&bvh, &gbuffer, &points, &params, ITERATION_BUDGET, false);
        let (shrunk, c1) = mft_masks_with(&bvh, &gbuffer, &points, &params, ITERATION_BUDGET, true);
        println!(
            "{}: triangle tests {} → {} with CR; {c0:?} {c1:?}",
            s.name, c0.triangle_tests, c1.triangle_tests
        );
        assert_eq!(plain, shrunk, "{}: shrinking changed a mask", s.name);
        assert!(
            c1.triangle_tests < c0.triangle_tests,
            "{}: shrinking saved no triangle test",
            s.name
        );
        assert!(c1.nodes_visited <= c0.nodes_visited && c1.box_tests <= c0.box_tests);
    }
}
