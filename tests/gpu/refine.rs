//! The refinement pass against its CPU twin (`penumbra::reference::refine`): which pixels
//! it picks, and their 256-ray values, whole and tiled; the errors it gives for settings
//! it cannot serve; and that it brings the built-in scenes closer to exact visibility.
//!
//! On lavapipe set `LP_NATIVE_VECTOR_WIDTH=512` to run with 16-wide subgroups too.

use crate::support;

use std::time::Instant;

use penumbra::assets;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::MASK_SKY;
use penumbra::gpu::{Frame, FrameSettings, GpuScene, Renderer, RendererOptions, Tracer};
use penumbra::quality::metrics::ImageMetrics;
use penumbra::reference::exact::exact_visibility_image;
use penumbra::reference::filter::discontinuity_filter;
use penumbra::reference::refine::refine_image;
use penumbra::reference::shade::shade_params;
use penumbra::reference::shadow_per_ray::{reference_counts, reference_visibility, shadow_params};
use penumbra::sampling;
use penumbra::scene::view::View;
use support::gpu::{ctx, embedded};

/// A frame with the refinement and the G-buffer.
fn refined_settings(w: u32, h: u32) -> FrameSettings {
    FrameSettings {
        keep_gbuffer: true,
        refine: true,
        ..FrameSettings::new(w, h)
    }
}

/// The same frame as [`refined_settings`] asks for, without the refinement.
fn unrefined(renderer: &Renderer, scene: &GpuScene, view: &View, w: u32, h: u32) -> Frame {
    let settings = FrameSettings {
        refine: false,
        ..refined_settings(w, h)
    };
    renderer.render(ctx(), scene, view, &settings).unwrap()
}

/// The CPU twin's filtered-and-refined image for a GPU frame, from the frame's own
/// G-buffer, masks and unfiltered values (each checked against its twin by other tests),
/// and which pixels it refined.
fn cpu_refined(frame: &Frame, bvh: &Bvh, view: &View) -> (Vec<[f32; 4]>, Vec<bool>) {
    let (w, h) = (frame.width, frame.height);
    let gbuffer = frame.gbuffer.as_ref().expect("kept G-buffer");
    let params = FilterParams::new(w, h);
    let depth: Vec<f32> = gbuffer.iter().map(|t| t.depth).collect();
    let normal: Vec<[f32; 3]> = gbuffer.iter().map(|t| t.normal.to_array()).collect();
    let mut filtered = discontinuity_filter(&params, &frame.unfiltered, &depth, &normal);
    let refined = refine_image(
        bvh,
        gbuffer,
        &frame.masks,
        &frame.unfiltered,
        &params,
        &sampling::light_points(&view.light),
        &shadow_params(&view.light, w, h),
        &shade_params(&view.light, w, h),
        &mut filtered,
    );
    (filtered, refined)
}

#[test]
fn refinement_matches_cpu_twin() {
    let start = Instant::now();
    let (w, h) = (64, 48);
    // The refinement traces its sample images with the frame's own tracer.
    let renderers: Vec<Renderer> = [Tracer::Mft, Tracer::Packet, Tracer::PerRay]
        .into_iter()
        .map(|tracer| {
            Renderer::new(
                ctx(),
                RendererOptions {
                    tracer,
                    ..RendererOptions::default()
                },
            )
            .unwrap()
        })
        .collect();
    // Every tracer on the playground, the multi-frusta one on the lattice too (the
    // lattice's deep penumbrae make the baselines slow on lavapipe).
    let runs = renderers
        .iter()
        .map(|r| (&assets::EMBEDDED_SCENES[0], r))
        .chain(assets::EMBEDDED_SCENES[1..].iter().map(|s| (s, &renderers[0])));
    for (s, renderer) in runs {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let frame = renderer
            .render(ctx(), &gpu_scene, &view, &refined_settings(w, h))
            .unwrap_or_else(|e| panic!("{}: {e}", s.name));
        let (cpu, cpu_refined) = cpu_refined(&frame, &bvh, &view);
        let refined = frame.refined.iter().filter(|&&r| r).count();
        let geometry = frame.masks.iter().filter(|&&m| m & MASK_SKY == 0).count();
        eprintln!(
            "{} ({}): {refined} of {geometry} pixels with geometry refined; GPU refine {:.1} ms",
            s.name,
            renderer.tracer(),
            frame.pass_ms("refine")
        );
        assert_eq!(frame.refined, cpu_refined, "{}: refined pixels differ", s.name);
        assert!(refined > 0 && refined < geometry, "{}: {refined} refined", s.name);
        for (p, (gpu, cpu)) in frame.filtered.iter().zip(&cpu).enumerate() {
            // Visibility is a count of 256 on both sides: exact. Irradiance is O(1) and
            // computed in the same order (1e-6 as the filter's test).
            assert_eq!(gpu[3], cpu[3], "{}: pixel {p} visibility", s.name);
            for k in 0..3 {
                let err = (gpu[k] - cpu[k]).abs() / cpu[k].abs().max(1.0);
                assert!(err <= 1e-6, "{}: pixel {p}: GPU {gpu:?} vs CPU {cpu:?}", s.name);
            }
        }
        for p in (0..frame.refined.len()).filter(|&p| frame.refined[p]) {
            let v = frame.filtered[p][3] * 256.0;
            assert_eq!(v, v.round(), "{}: pixel {p}: visibility {v}/256", s.name);
        }

        // Tiled (tile side 16 with the filter's margin): the same pixels, bit for bit.
        let tiled = FrameSettings {
            max_tile: Some(16),
            ..refined_settings(w, h)
        };
        let tiles = renderer.render(ctx(), &gpu_scene, &view, &tiled).unwrap();
        assert_eq!(tiles.refined, frame.refined, "{}: tiled refined pixels", s.name);
        assert_eq!(tiles.filtered, frame.filtered, "{}: tiled values", s.name);

        // Without refinement: the same filtered image except at the refined pixels.
        let plain = unrefined(renderer, &gpu_scene, &view, w, h);
        assert!(plain.refined.iter().all(|&r| !r));
        for p in 0..plain.filtered.len() {
            if !frame.refined[p] {
                assert_eq!(
                    plain.filtered[p], frame.filtered[p],
                    "{}: pixel {p} changed",
                    s.name
                );
            }
        }
        assert_eq!(plain.pass_ms("refine"), 0.0);
    }
    eprintln!(
        "refinement_matches_cpu_twin: {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

#[test]
fn refinement_brings_the_image_closer_to_exact() {
    // Against exact visibility, or 256 rays per pixel on the alpha-masked screen.
    let (w, h) = (96, 96);
    let renderer = Renderer::new(ctx(), None).unwrap();
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let frame = renderer
            .render(ctx(), &gpu_scene, &view, &refined_settings(w, h))
            .unwrap();
        let plain = unrefined(&renderer, &gpu_scene, &view, w, h);
        let gbuffer = frame.gbuffer.as_ref().unwrap();
        // Exact visibility clips polygons, which alpha masks are not: there the yardstick is
        // the per-ray oracle's 256 rays per pixel.
        let exact = if bvh.alpha.triangles == 0 {
            exact_visibility_image(&bvh, gbuffer, w, h, &view.light)
        } else {
            let points = sampling::reference_light_points(&view.light, 256);
            reference_counts(&bvh, gbuffer, &points, &shadow_params(&view.light, w, h))
                .iter()
                .map(|&c| reference_visibility(c, 256))
                .collect()
        };
        let hit: Vec<usize> = (0..frame.masks.len())
            .filter(|&p| frame.masks[p] & MASK_SKY == 0)
            .collect();
        let rmse = |f: &Frame| {
            let v: Vec<f32> = hit.iter().map(|&p| f.filtered[p][3]).collect();
            let e: Vec<f32> = hit.iter().map(|&p| exact[p]).collect();
            ImageMetrics::of_values(&v, &e).rmse
        };
        let (refined, filtered) = (rmse(&frame), rmse(&plain));
        eprintln!(
            "{}: RMSE against exact, filtered {filtered:.5}, filtered + refined {refined:.5}",
            s.name
        );
        assert!(refined < 0.8 * filtered, "{}: {refined} vs {filtered}", s.name);
    }
}

#[test]
fn refinement_needs_the_filter_and_an_interleaved_tracer() {
    let (scene, view) = embedded(assets::EMBEDDED_SCENES[0].name);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let renderer = Renderer::new(ctx(), None).unwrap();
    let no_filter = FrameSettings {
        filter: None,
        ..refined_settings(16, 16)
    };
    let err = renderer.render(ctx(), &gpu_scene, &view, &no_filter).unwrap_err();
    assert!(err.to_string().contains("needs the filter"), "{err}");
    let reference = Renderer::new(
        ctx(),
        RendererOptions {
            tracer: Tracer::Reference { rays: 64 },
            ..RendererOptions::default()
        },
    )
    .unwrap();
    let err = reference
        .render(ctx(), &gpu_scene, &view, &refined_settings(16, 16))
        .unwrap_err();
    assert!(err.to_string().contains("interleaved tracer"), "{err}");

    // Nothing to refine (the camera sees only sky): no pixel refined, no error.
    let mut sky = view;
    sky.camera.target = sky.camera.eye + (sky.camera.eye - view.camera.target);
    let frame = renderer
        .render(ctx(), &gpu_scene, &sky, &refined_settings(16, 16))
        .unwrap();
    assert!(
        frame.masks.iter().all(|&m| m & MASK_SKY != 0),
        "the camera sees geometry"
    );
    assert!(frame.refined.iter().all(|&r| !r));
}
