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
use penumbra::reference::refine::{budget_pixels, refine_image, refine_score, refined_pixels, refined_value};
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
fn cpu_refined(
    frame: &Frame,
    bvh: &Bvh,
    view: &View,
    settings: &FrameSettings,
) -> (Vec<[f32; 4]>, Vec<bool>) {
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
        settings.ray_budget,
        settings.refine_sets,
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
        let (cpu, cpu_refined) = cpu_refined(&frame, &bvh, &view, &refined_settings(w, h));
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
fn refinement_with_fewer_sets_matches_cpu_twin() {
    let (w, h) = (64, 48);
    let renderer = Renderer::new(ctx(), None).unwrap();
    let (scene, view) = embedded(assets::EMBEDDED_SCENES[0].name);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let all = renderer
        .render(ctx(), &gpu_scene, &view, &refined_settings(w, h))
        .unwrap();
    for sets in [1, 4, 8] {
        let settings = FrameSettings {
            refine_sets: sets,
            ..refined_settings(w, h)
        };
        let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
        let (cpu, cpu_refined) = cpu_refined(&frame, &bvh, &view, &settings);
        // Without a budget the same pixels as with all 16 sets.
        assert_eq!(frame.refined, all.refined, "{sets} sets: refined pixels");
        assert_eq!(
            frame.refined, cpu_refined,
            "{sets} sets: refined pixels against the twin"
        );
        let rays = 16.0 * sets as f32;
        let mut changed = 0;
        for p in (0..frame.refined.len()).filter(|&p| frame.refined[p]) {
            // A count of 16 · sets rays on both sides: exact.
            assert_eq!(
                frame.filtered[p][3], cpu[p][3],
                "{sets} sets: pixel {p} visibility"
            );
            let v = frame.filtered[p][3] * rays;
            assert_eq!(v, v.round(), "{sets} sets: pixel {p}: visibility {v}/{rays}");
            changed += usize::from(frame.filtered[p][3] != all.filtered[p][3]);
        }
        assert!(
            changed > 0,
            "{sets} sets: every refined value equals the 256-ray one"
        );
    }
    let err = renderer
        .render(
            ctx(),
            &gpu_scene,
            &view,
            &FrameSettings {
                refine_sets: 3,
                ..refined_settings(16, 16)
            },
        )
        .unwrap_err();
    assert!(err.to_string().contains("1, 2, 4, 8 or 16"), "{err}");
}

#[test]
fn budgeted_refinement_keeps_the_highest_scores_within_the_budget() {
    let (w, h) = (64, 48);
    let budget = 40.0;
    let renderer = Renderer::new(ctx(), None).unwrap();
    for s in &assets::EMBEDDED_SCENES[..2] {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let plain = unrefined(&renderer, &gpu_scene, &view, w, h);
        let gbuffer = plain.gbuffer.as_ref().unwrap();
        let params = FilterParams::new(w, h);
        let depth: Vec<f32> = gbuffer.iter().map(|t| t.depth).collect();
        let normal: Vec<[f32; 3]> = gbuffer.iter().map(|t| t.normal.to_array()).collect();
        let geometry = depth.iter().filter(|&&d| d > 0.0).count() as u32;
        let score = |p: u32| {
            refine_score(
                &params,
                &plain.unfiltered,
                &plain.filtered,
                &depth,
                &normal,
                p % w,
                p / w,
            )
        };
        for sets in [16, 8] {
            let unbudgeted = FrameSettings {
                refine_sets: sets,
                ..refined_settings(w, h)
            };
            let settings = FrameSettings {
                ray_budget: Some(budget),
                ..unbudgeted
            };
            let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
            let full = renderer.render(ctx(), &gpu_scene, &view, &unbudgeted).unwrap();
            let listed = refined_pixels(
                &params,
                &plain.unfiltered,
                &plain.filtered,
                &depth,
                &normal,
                None,
                sets,
            );
            let keep = budget_pixels(budget, geometry, sets) as usize;
            let what = format!("{}, {sets} sets", s.name);
            // The budget must bind for the test to test it.
            assert!(
                keep > 0 && keep < listed.len(),
                "{what}: keep {keep} of {}",
                listed.len()
            );
            let gpu: Vec<u32> = (0..w * h).filter(|&p| frame.refined[p as usize]).collect();
            assert_eq!(gpu.len(), keep, "{what}: refined pixels against the budget");
            assert!(16.0 + (16 * sets) as f32 * keep as f32 / geometry as f32 <= budget);
            assert!(
                gpu.iter().all(|p| full.refined[*p as usize]),
                "{what}: a pixel outside the rule's list"
            );
            // The twin's choice, except that pixels scored within rounding of the last kept
            // score may swap: the filtered visibility matches the twin's within 1e-6 (the
            // filter's test), and the GPU's square root and division may be a few ulp off
            // (< 1e-6 for scores ≤ 1), so a score may differ by 2e-6.
            let cpu = refined_pixels(
                &params,
                &plain.unfiltered,
                &plain.filtered,
                &depth,
                &normal,
                Some(budget),
                sets,
            );
            let cut = cpu.iter().map(|&p| score(p)).fold(f32::INFINITY, f32::min);
            for p in gpu
                .iter()
                .filter(|p| !cpu.contains(p))
                .chain(cpu.iter().filter(|p| !gpu.contains(p)))
            {
                assert!(
                    (score(*p) - cut).abs() <= 2e-6,
                    "{what}: pixel {p} (score {}) chosen differently, last kept score {cut}",
                    score(*p)
                );
            }
            // The others keep the filter's value; the i-th refined pixel (pixel order) gets
            // the twin's value over block i mod (16 / sets) of the sets, a count of rays:
            // exact (irradiance as in `refinement_matches_cpu_twin`).
            let per_tile = 16 / sets as usize;
            let (points, shadow, shade) = (
                sampling::light_points(&view.light),
                shadow_params(&view.light, w, h),
                shade_params(&view.light, w, h),
            );
            for p in (0..(w * h) as usize).filter(|&p| !frame.refined[p]) {
                assert_eq!(frame.filtered[p], plain.filtered[p], "{what}: pixel {p}");
            }
            for (i, &p) in gpu.iter().enumerate() {
                let first = (i % per_tile) * sets as usize;
                let (x, y) = (p % w, p / w);
                let p = p as usize;
                let mask = plain.masks[p];
                let v = refined_value(
                    &bvh,
                    &gbuffer[p],
                    mask,
                    x,
                    y,
                    &points,
                    &shadow,
                    &shade,
                    first..first + sets as usize,
                );
                assert_eq!(frame.filtered[p][3], v.w, "{what}: pixel {p} visibility");
                for k in 0..3 {
                    let err = (frame.filtered[p][k] - v[k]).abs() / v[k].abs().max(1.0);
                    assert!(
                        err <= 1e-6,
                        "{what}: pixel {p}: GPU {:?} vs CPU {v}",
                        frame.filtered[p]
                    );
                }
            }
            eprintln!(
                "{what}: budget {budget}: {keep} of {} listed pixels refined ({} chosen as the twin)",
                listed.len(),
                gpu.iter().filter(|p| cpu.contains(p)).count()
            );
        }
    }
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
    // A ray budget needs the refinement, and at least the frame's own 16 rays.
    for (refine, budget, message) in [
        (false, 24.0, "set FrameSettings::refine"),
        (true, 15.0, "≥ 16"),
        (true, f32::NAN, "≥ 16"),
    ] {
        let settings = FrameSettings {
            refine,
            ray_budget: Some(budget),
            ..refined_settings(16, 16)
        };
        let err = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap_err();
        assert!(err.to_string().contains(message), "{budget}: {err}");
    }

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

/// Sky is no change of visibility: a pixel in umbra whose window holds sky (depth 0,
/// visibility 1) and otherwise only umbra is not refined (`visibility_varies` counts
/// neighbours with geometry only). The light is moved under the playground's ground,
/// facing down, so every surface above it is behind it (umbra), and the camera looks
/// at the horizon, so umbra meets sky.
#[test]
fn umbra_beside_the_sky_is_not_refined() {
    let (w, h) = (64, 48);
    let (scene, mut view) = embedded(assets::EMBEDDED_SCENES[0].name);
    view.light.corner.y = -2.0;
    assert!(
        view.light.edge_u.cross(view.light.edge_v).y < 0.0,
        "the playground's light faces down"
    );
    view.camera.eye = glam::Vec3::new(6.0, 1.0, 7.0);
    view.camera.target = glam::Vec3::new(0.0, 1.0, 0.0);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let renderer = Renderer::new(ctx(), RendererOptions::default()).unwrap();
    let frame = renderer
        .render(ctx(), &gpu_scene, &view, &refined_settings(w, h))
        .unwrap();
    let sky = |p: usize| frame.masks[p] & MASK_SKY != 0;
    let geometry = (0..frame.masks.len()).filter(|&p| !sky(p)).count();
    assert!(
        geometry > 0 && geometry < frame.masks.len(),
        "the view shows ground and sky"
    );
    assert!(
        (0..frame.masks.len()).all(|p| sky(p) || frame.unfiltered[p][3] == 0.0),
        "every surface is in umbra"
    );
    // Umbra pixels with sky in their 5×5 window.
    let beside_sky = (0..frame.masks.len())
        .filter(|&p| !sky(p))
        .filter(|&p| {
            let (x, y) = ((p % w as usize) as i64, (p / w as usize) as i64);
            (-2..=2).any(|dy| {
                (-2..=2).any(|dx| {
                    let (nx, ny) = (x + dx, y + dy);
                    nx >= 0 && ny >= 0 && nx < w as i64 && ny < h as i64 && sky((ny * w as i64 + nx) as usize)
                })
            })
        })
        .count();
    assert!(beside_sky > 0, "no umbra pixel has sky in its window");
    let (_, cpu_refined) = cpu_refined(&frame, &bvh, &view, &refined_settings(w, h));
    assert!(cpu_refined.iter().all(|&r| !r), "the twin refines a pixel");
    let refined: Vec<usize> = (0..frame.refined.len()).filter(|&p| frame.refined[p]).collect();
    assert!(
        refined.is_empty(),
        "{} of {beside_sky} umbra pixels beside the sky refined, e.g. {:?}",
        refined.len(),
        &refined[..refined.len().min(5)]
    );
}
