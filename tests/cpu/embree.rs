//! Embree (cargo feature `embree`) as an oracle nobody here wrote: its masks against the
//! per-ray Möller–Trumbore oracle's on the generated scenes and on Sponza, with the
//! comparison of `support::compare_masks` (a differing ray is excused only within the
//! edge tolerance of a triangle other than its origin's own; at most 0.1 % differ).

use crate::support;

use std::path::Path;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::embree::EmbreeScene;
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_per_ray::shadow_params;
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use penumbra::{assets, sampling};

/// Embree's masks of `scene` seen through `view` at `w`×`h`, checked against the oracle.
fn embree_matches_the_oracle(label: &str, scene: &Scene, view: &View, w: u32, h: u32) {
    let bvh = Bvh::build(scene, &BvhSettings::default()).unwrap();
    let cam = camera_params(
        &view.camera,
        w,
        h,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(scene, &bvh).unwrap(), &cam);
    let params = shadow_params(&view.light, w, h);
    let points = sampling::light_points(&view.light);
    let embree = EmbreeScene::new(&bvh).unwrap();
    let masks = embree.masks(&gbuffer, &points, &params);
    let (differing, total, oracle) =
        support::assert_masks_match_oracle(label, scene, &bvh, view, &gbuffer, &masks, w, h);
    // Not a vacuous pass: the view has shadows and lit pixels.
    let blocked: u32 = oracle.iter().map(|m| (m & 0xffff).count_ones()).sum();
    assert!(
        blocked > 0 && (blocked as usize) < total,
        "{label}: {blocked} of {total} rays blocked"
    );
    eprintln!("{label}: Embree differs from the oracle in {differing} of {total} rays");
}

#[test]
fn embree_matches_the_per_ray_oracle_on_generated_scenes() {
    for s in assets::EMBEDDED_SCENES {
        let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
        embree_matches_the_oracle(s.name, &scene, &s.view(), 90, 70);
    }
}

#[test]
fn embree_matches_the_per_ray_oracle_on_sponza() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = root.join("../shared/scenes/dabrovic_sponza/sponza.gltf");
    let scene = Scene::load(&file)
        .unwrap_or_else(|e| panic!("{}: {e} (the shared scenes are needed)", file.display()));
    let view = View::load(&root.join("assets/views/sponza-atrium.json")).unwrap();
    embree_matches_the_oracle("sponza atrium", &scene, &view, 64, 64);
}
