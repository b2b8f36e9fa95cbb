//! Frames whose traversal exceeds lavapipe's loop limit: a shadow tile that suspends and
//! resumes (against the oracle and the twin's counters), and primary frusta past the
//! limit (an error or the CPU's G-buffer).

use crate::support;

use std::time::Instant;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::MASK_FULL;
use penumbra::contract::layout::{GBufferTexel, ShadowParams};
use penumbra::gpu::{FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions};
use penumbra::reference::shadow_mft::{Counters, Frustum, TileOptions, mft_masks, trace_tile};
use penumbra::reference::shadow_per_ray::{ITERATION_BUDGET, per_ray_masks, shadow_params};
use penumbra::sampling;
use penumbra::scene::Scene;
use penumbra::scene::view::{QuadLight, View};
use support::gpu::{ctx, variants};
use support::{Rng, compare_masks, edge_tolerance, near_miss_stack, own_triangle, scene_from_triangles};

use super::frame::{cpu_gbuffer, horizontal_square, render, top_down_camera};

/// lavapipe (Mesa 22.3) ends every loop of an invocation after this many
/// iterations, counted across all its loops. Measured here: a loop nested in
/// another costs one more iteration each time the outer body reaches it, even
/// in a branch no lane takes, so a loop with a nested loop gets only ~32,767.
const LAVAPIPE_LOOP_LIMIT: u64 = 65_535;

/// The CPU twin's counters of every 4×4 tile (row-major), traced without a
/// budget as the default renderer's kernel with `leaf_mode` runs: what one
/// uninterrupted vector does.
fn tile_counters(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    leaf_mode: LeafMode,
) -> Vec<Counters> {
    let (w, h) = (params.width as usize, params.height as usize);
    let mut tiles = Vec::new();
    for ty in 0..h.div_ceil(4) {
        for tx in 0..w.div_ceil(4) {
            let frusta: [Frustum; 16] = std::array::from_fn(|i| {
                let (x, y) = (tx * 4 + i % 4, ty * 4 + i / 4);
                let texel = if x < w && y < h {
                    gbuffer[y * w + x]
                } else {
                    // Outside the image: a sky lane, done from the start.
                    GBufferTexel {
                        triangle: u32::MAX,
                        ..Default::default()
                    }
                };
                Frustum::new(&texel, i, light_points, params)
            });
            let mut c = Counters::default();
            let options = TileOptions {
                budget: u32::MAX,
                shrink: RendererOptions::default().shrink,
                transposed: leaf_mode == LeafMode::Transposed,
            };
            trace_tile(bvh, frusta, params, &options, &mut c);
            tiles.push(c);
        }
    }
    tiles
}

/// A 2 × 2 ground, a 4 × 4 light at y = 2 and a thin layer (y 0.9..1.1) of
/// `occluders` randomly oriented triangles `size` across over [-0.6, 0.6]², all inside
/// every frustum of every pixel (the camera sees [-0.35, 0.35]² of ground
/// from below the layer), and sparse enough that no frustum is ever fully
/// blocked: every tile walks the whole tree, ~1.7 steps per triangle.
fn occluder_layer_scene(occluders: usize, size: f32) -> (Scene, View) {
    let mut rng = Rng::new(0x5eed_f00d);
    let mut tris: Vec<([Vec3; 3], u32)> = horizontal_square(0.0, 1.0, 0).to_vec();
    for _ in 0..occluders {
        let c = rng.in_box(Vec3::new(-0.6, 0.9, -0.6), Vec3::new(0.6, 1.1, 0.6));
        tris.push(([c, c + rng.direction() * size, c + rng.direction() * size], 1));
    }
    let scene = scene_from_triangles(&tris, &[[0.8, 0.8, 0.8], [0.3, 0.3, 0.3]]);
    let view = View {
        camera: top_down_camera(0.6, Vec3::ZERO, 60.0),
        light: QuadLight::from_center(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 4.0),
        ),
        ground_y: None,
    };
    view.validate().unwrap();
    (scene, view)
}

#[test]
fn loop_limit_tile_still_matches_oracle() {
    let start = Instant::now();
    let mut failures = Vec::new();
    // Transposed leaves take ~17 steps per triangle here (one per surviving
    // frustum): a sparser layer (of larger triangles, for as much shadow) exceeds
    // the limit as well and keeps lavapipe fast.
    for (leaf_mode, occluders, size) in [
        (LeafMode::PerLane, 130_000, 0.0056),
        (LeafMode::Transposed, 4_000, 0.025),
    ] {
        let (scene, view) = occluder_layer_scene(occluders, size);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (8, 8);
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();

        // The CPU side, on the CPU twin's G-buffer (the GPU's is checked against it below).
        let gbuffer = cpu_gbuffer(&scene, &bvh, &view, w, h);
        assert!(
            gbuffer.iter().all(|t| t.is_hit() && t.origin.y < 0.01),
            "every pixel must see the ground"
        );
        let tiles = tile_counters(&bvh, &gbuffer, &points, &params, leaf_mode);
        let steps: Vec<u64> = tiles.iter().map(|c| c.traversal_steps).collect();
        let busiest = *steps.iter().max().unwrap();
        let predicted: u64 = steps
            .iter()
            .map(|&s| s.saturating_sub(1) / u64::from(ITERATION_BUDGET))
            .sum();
        let shrink = RendererOptions::default().shrink;
        let (twin, counters) = mft_masks(
            &bvh,
            &gbuffer,
            &points,
            &params,
            &TileOptions {
                shrink,
                ..TileOptions::with_budget(ITERATION_BUDGET)
            },
        );
        if leaf_mode == LeafMode::PerLane {
            // Suspending and resuming adds no step.
            assert_eq!(
                counters.traversal_steps,
                tiles.iter().map(|c| c.traversal_steps).sum::<u64>()
            );
        }
        let oracle = per_ray_masks(&bvh, &gbuffer, &points, &params);
        let occluded: u32 = oracle.iter().map(|m| (m & MASK_FULL).count_ones()).sum();
        let rays = gbuffer.len() * 16;
        let twin_differing = compare_masks(
            &oracle,
            &twin,
            &gbuffer,
            w,
            &points,
            &params,
            &corners,
            &own_triangle(&bvh),
            0.0,
        )
        .differing;
        eprintln!(
            "{leaf_mode}: {} triangles, BVH of {} nodes (depth {}); kernel steps per tile {steps:?} \
             (lavapipe limit {LAVAPIPE_LOOP_LIMIT}, budget {ITERATION_BUDGET}) predict {predicted} \
             suspensions; twin {counters:?}; oracle: {occluded} of {rays} rays occluded, \
             {twin_differing} differ from the twin",
            scene.triangles.len(),
            bvh.nodes.len(),
            bvh.stats().max_depth,
        );
        assert!(
            busiest > LAVAPIPE_LOOP_LIMIT,
            "{leaf_mode}: the scene must give a tile more than {LAVAPIPE_LOOP_LIMIT} steps, the busiest has {busiest}"
        );
        assert!(
            occluded as usize > rays / 50 && (occluded as usize) < rays * 19 / 20,
            "{leaf_mode}: the layer must block some rays but not all ({occluded} of {rays})"
        );

        for variant in variants() {
            let options = RendererOptions {
                variant: Some(variant),
                leaf_mode,
                ..RendererOptions::default()
            };
            let renderer = Renderer::new(ctx(), options).unwrap();
            let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
            let gpu_gbuffer = frame.gbuffer.as_ref().unwrap();
            let other_triangle = gpu_gbuffer
                .iter()
                .zip(&gbuffer)
                .filter(|(g, c)| g.triangle != c.triangle)
                .count();
            assert_eq!(
                other_triangle, 0,
                "{variant}: the G-buffer differs from the CPU twin's"
            );
            // The oracle on the GPU's own G-buffer, as in tests/gpu/shadow_mft.rs.
            let oracle = per_ray_masks(&bvh, gpu_gbuffer, &points, &params);
            let c = compare_masks(
                &oracle,
                &frame.masks,
                gpu_gbuffer,
                w,
                &points,
                &params,
                &corners,
                &own_triangle(&bvh),
                edge_tolerance(&scene),
            );
            eprintln!("{variant} {leaf_mode}: against the per-ray oracle: {c}");
            let (differing, total, unexplained) = (c.differing, c.total, c.unexplained);
            let twin_bits: u32 = twin
                .iter()
                .zip(&frame.masks)
                .map(|(a, b)| (a ^ b).count_ones())
                .sum();
            let gpu_occluded: u32 = frame.masks.iter().map(|m| (m & MASK_FULL).count_ones()).sum();
            let stats = frame.shadow_stats;
            eprintln!(
                "{variant} {leaf_mode}: GPU {stats:?}; {differing} of {total} rays differ from the \
                 oracle ({} unexplained), {twin_bits} mask bits from the twin, {gpu_occluded} rays \
                 occluded; frame {ms:.0} ms, shadow {:.1} ms",
                unexplained.len(),
                frame.pass_ms("shadow"),
            );
            let mut fail = |m: String| failures.push(format!("{variant} {leaf_mode}: {m}"));
            if stats.suspensions == 0 {
                fail(format!("no tile was suspended: {stats:?}"));
            }
            // The kernel counts its steps as the twin does: the same budget gives the same suspensions.
            if stats.suspensions != predicted {
                fail(format!(
                    "{} suspensions, the twin's step counts give {predicted}",
                    stats.suspensions
                ));
            }
            if !unexplained.is_empty() {
                fail(format!(
                    "{} rays differ from the oracle unexplained, e.g. {:?}",
                    unexplained.len(),
                    &unexplained[..unexplained.len().min(4)]
                ));
            }
            if differing * 1000 > total {
                fail(format!("{differing} of {total} rays differ from the oracle"));
            }
        }
    }
    eprintln!(
        "loop_limit_tile_still_matches_oracle: {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        failures.is_empty(),
        "tiles past lavapipe's loop limit are traced wrong:\n{}",
        failures.join("\n")
    );
}

/// A camera ray that passes through the boxes of a stack of `n` horizontal
/// triangles without touching any (each one's long edge passes 0.05 beside the
/// ray) before it hits the ground: the primary kernel visits every node.
fn near_miss_stack_scene(n: usize) -> (Scene, View) {
    let mut tris: Vec<([Vec3; 3], u32)> = horizontal_square(0.0, 2.0, 0).to_vec();
    tris.extend(near_miss_stack(n));
    let scene = scene_from_triangles(&tris, &[[0.8, 0.8, 0.8], [0.3, 0.3, 0.3]]);
    // A light low to the side, so that shadow rays pass under the stack.
    let view = View {
        camera: top_down_camera(10.0, Vec3::ZERO, 1.0),
        light: QuadLight::from_center(
            Vec3::new(5.0, 0.5, 0.0),
            Vec3::new(0.0, 0.0, 0.2),
            Vec3::new(0.0, 0.2, 0.0),
        ),
        ground_y: None,
    };
    view.validate().unwrap();
    (scene, view)
}

/// The primary kernel counts its loop steps and reports an overflow; on
/// lavapipe a ray that needs more steps than the loop limit allows must give
/// that error or, if it was not cut, the CPU twin's texel — never a silent miss.
#[test]
fn primary_pass_past_the_loop_limit_errors_or_matches_cpu() {
    let start = Instant::now();
    let (scene, view) = near_miss_stack_scene(40_000);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (1, 1);
    let cpu = cpu_gbuffer(&scene, &bvh, &view, w, h);
    let ground: Vec<u32> = (0..bvh.triangles.len() as u32)
        .filter(|&i| bvh.triangles[i as usize].scene_index < 2)
        .collect();
    assert!(ground.contains(&cpu[0].triangle), "the CPU ray hits the ground");
    // Every box holds the ray, so the kernel pops every node and tests every triangle.
    let kernel_steps = bvh.nodes.len() + bvh.triangles.len();
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    let result = Renderer::new(ctx(), None)
        .unwrap()
        .render(ctx(), &gpu_scene, &view, &settings);
    let outcome = match &result {
        Err(e) => format!("error: {e}"),
        Ok(frame) => format!("texel {:?}", frame.gbuffer.as_ref().unwrap()[0]),
    };
    eprintln!(
        "{} triangles, {} nodes: the camera ray needs {kernel_steps} kernel steps \
         (the kernel reports an error past 60000); CPU hits triangle {} at depth {}; GPU {outcome}; {:.1} s",
        bvh.triangles.len(),
        bvh.nodes.len(),
        cpu[0].triangle,
        cpu[0].depth,
        start.elapsed().as_secs_f64()
    );
    if let Ok(frame) = result {
        let g = frame.gbuffer.as_ref().unwrap()[0];
        assert_eq!(
            g.triangle, cpu[0].triangle,
            "the primary pass silently returned a wrong hit (or a miss) for a ray of \
             {kernel_steps} steps instead of the ground or an overflow error"
        );
    }
}
