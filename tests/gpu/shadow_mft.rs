//! The MFT shadow pass in a frame on lavapipe (or any adapter): masks from both
//! vector variants against the per-ray oracle, transposed leaves against per-lane
//! ones, and tiles suspended at every kind of step resumed to the same masks. (The
//! primary pass, the filter, exact lit/umbra values and a tile past lavapipe's loop
//! limit are in tests/gpu/frame.rs.)

use crate::support;

use penumbra::assets;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{
    FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions, ShadowTracer, TracerOptions,
};
use penumbra::reference::shadow_per_ray::{ITERATION_BUDGET, shadow_params};
use support::assert_masks_match_oracle;
use support::gpu::{assert_same_rays, ctx, embedded, trace_masks, variants};

#[test]
fn shadow_masks_match_the_per_ray_oracle_for_every_variant() {
    let vs = variants();
    eprintln!("variants tested: {vs:?}");
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (90, 70); // not a multiple of 4: edge tiles are partial
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let mut first: Option<Vec<u32>> = None;
        for &variant in &vs {
            let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
            let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
            let gbuffer = frame.gbuffer.as_ref().unwrap();
            let label = format!("{} {variant}", s.name);
            let (differing, total, _) =
                assert_masks_match_oracle(&label, &scene, &bvh, &view, gbuffer, &frame.masks, w, h);
            eprintln!(
                "{label}: {differing} of {total} rays differ from the oracle; timings {:?}",
                frame.timings
            );
            match &first {
                None => first = Some(frame.masks.clone()),
                Some(m) => assert_same_rays(
                    &format!("{}: subgroup vs workgroup", s.name),
                    m,
                    &frame.masks,
                    &scene,
                    &bvh,
                    &view,
                    gbuffer,
                    w,
                ),
            }
        }
    }
}

#[test]
fn transposed_leaves_give_the_per_lane_masks_bit_for_bit() {
    let vs = variants();
    eprintln!("variants tested: {vs:?}");
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (90, 70); // not a multiple of 4: edge tiles are partial
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        for &variant in &vs {
            let mut per_lane: Option<Vec<u32>> = None;
            for leaf_mode in [LeafMode::PerLane, LeafMode::Transposed] {
                let options = RendererOptions {
                    variant: Some(variant),
                    leaf_mode,
                    ..RendererOptions::default()
                };
                let renderer = Renderer::new(ctx(), options).unwrap();
                assert_eq!((renderer.variant(), renderer.leaf_mode()), (variant, leaf_mode));
                let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
                let gbuffer = frame.gbuffer.as_ref().unwrap();
                let label = format!("{} {variant} {leaf_mode}", s.name);
                let (differing, total, _) =
                    assert_masks_match_oracle(&label, &scene, &bvh, &view, gbuffer, &frame.masks, w, h);
                eprintln!(
                    "{label}: {differing} of {total} rays differ from the oracle; shadow {:.1} ms",
                    frame.pass_ms("shadow")
                );
                match &per_lane {
                    None => per_lane = Some(frame.masks.clone()),
                    Some(m) => assert_same_rays(
                        &format!("{} {variant}: transposed vs per-lane", s.name),
                        m,
                        &frame.masks,
                        &scene,
                        &bvh,
                        &view,
                        gbuffer,
                        w,
                    ),
                }
            }
        }
    }
}

/// Suspension in the middle of a transposed leaf (and of shrunk frusta) (the candidate frusta of a triangle are
/// loop steps too, saved with the tile) resumes to the same masks as an uninterrupted run.
#[test]
fn transposed_leaves_resume_after_suspension_with_the_same_masks() {
    let (scene, view) = embedded("lattice");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (46, 38);
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    let frame = Renderer::new(ctx(), None)
        .unwrap()
        .render(ctx(), &gpu_scene, &view, &settings)
        .unwrap();
    let texels = frame.gbuffer.as_ref().unwrap();
    for variant in variants() {
        for (leaf_mode, shrink) in [
            (LeafMode::PerLane, false),
            (LeafMode::Transposed, false),
            (LeafMode::PerLane, true),
            (LeafMode::Transposed, true),
        ] {
            let options = TracerOptions {
                variant: Some(variant),
                leaf_mode,
                shrink,
                ..TracerOptions::default()
            };
            let pass = ShadowTracer::new(ctx(), &options).unwrap();
            // An odd budget far below a tile's work: tiles stop at every kind of step.
            let mut uninterrupted: Option<Vec<u32>> = None;
            for budget in [ITERATION_BUDGET, 97] {
                let mut params = shadow_params(&view.light, w, h);
                params.iteration_budget = budget;
                let (got, stats) = trace_masks(&pass, &gpu_scene, texels, &view, &params);
                eprintln!("{variant} {leaf_mode} shrink {shrink} budget {budget}: {stats:?}");
                if budget < ITERATION_BUDGET {
                    assert!(stats.suspensions > 0, "{variant} {leaf_mode}: nothing suspended");
                }
                let label = format!("{variant} {leaf_mode} shrink {shrink} budget {budget}");
                match &uninterrupted {
                    // Another pipeline than the frame's: bit for bit where the arithmetic is exact.
                    None => {
                        assert_same_rays(&label, &frame.masks, &got, &scene, &bvh, &view, texels, w);
                        uninterrupted = Some(got);
                    }
                    // The same pipeline resumed: the same bits on any adapter.
                    Some(whole) => assert!(
                        got == *whole,
                        "{label}: resumed masks differ from the uninterrupted run's in {} bits",
                        got.iter()
                            .zip(whole)
                            .map(|(a, b)| (a ^ b).count_ones())
                            .sum::<u32>()
                    ),
                }
            }
        }
    }
}
