//! The shadow tracers on lavapipe (or any adapter): packet, per-ray and reference
//! masks against the CPU oracles, and the Table-1 counters of the MFT and packet
//! kernels against their CPU twins and against counts made by hand.

use crate::support;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::contract::layout::MASK_FULL;
use penumbra::gpu::{
    FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions, ShadowTracer, Tracer, TracerOptions,
    VectorVariant,
};
use penumbra::reference::counters::Counters;
use penumbra::reference::shadow_mft::{TileOptions, mft_masks};
use penumbra::reference::shadow_packet::packet_masks;
use penumbra::reference::shadow_per_ray::{ITERATION_BUDGET, reference_counts, shadow_params};
use penumbra::scene::Scene;
use penumbra::scene::view::{QuadLight, View};
use penumbra::{assets, sampling};
use support::gpu::{
    assert_same_rays, ctx, embedded, every_tracer, exact_arithmetic, shadow_tracer, trace_masks,
    try_trace_masks, variants,
};
use support::{
    assert_masks_match_oracle, closed_room, near_miss_column, rays_through_a_shared_edge,
    scene_from_triangles,
};

fn options(tracer: Tracer, variant: VectorVariant) -> RendererOptions {
    RendererOptions {
        variant: Some(variant),
        tracer,
        ..RendererOptions::default()
    }
}

#[test]
fn packet_and_per_ray_masks_match_the_oracle() {
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (61, 43);
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        for tracer in [Tracer::Packet, Tracer::PerRay] {
            for variant in variants() {
                let renderer = Renderer::new(ctx(), options(tracer, variant)).unwrap();
                let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
                let gbuffer = frame.gbuffer.as_ref().unwrap();
                let label = format!("{} {tracer} {variant}", s.name);
                let (differing, total, _) =
                    assert_masks_match_oracle(&label, &scene, &bvh, &view, gbuffer, &frame.masks, w, h);
                eprintln!("{label}: {differing} of {total} rays differ from the oracle");
                if tracer == Tracer::Packet {
                    // The twin traces the same rays with the same arithmetic in the same order.
                    let params = shadow_params(&view.light, w, h);
                    let points = sampling::light_points(&view.light);
                    let (twin, _) = packet_masks(&bvh, gbuffer, &points, &params, ITERATION_BUDGET);
                    let bits: u32 = twin
                        .iter()
                        .zip(&frame.masks)
                        .map(|(a, b)| (a ^ b).count_ones())
                        .sum();
                    assert!(
                        bits as usize * 1000 <= total,
                        "{label}: {bits} bits differ from the packet twin"
                    );
                }
                if !tracer.uses_vector() {
                    break; // the per-ray kernel has no vector variant
                }
            }
        }
    }
}

#[test]
fn reference_counts_match_the_oracle() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (40, 30);
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    settings.filter = None;
    for rays in [64, 256] {
        let tracer = Tracer::Reference { rays };
        let renderer = Renderer::new(ctx(), options(tracer, VectorVariant::Workgroup)).unwrap();
        let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
        let gbuffer = frame.gbuffer.as_ref().unwrap();
        let params = shadow_params(&view.light, w, h);
        let points = sampling::reference_light_points(&view.light, rays);
        let oracle = reference_counts(&bvh, gbuffer, &points, &params);
        // Rays grazing an edge may round either way (as in the 16-ray tracers): allow
        // a count off by one in at most 1 % of the pixels, nothing more.
        let mut off = 0;
        for (p, (&a, &b)) in oracle.iter().zip(&frame.masks).enumerate() {
            assert!(
                a.abs_diff(b) <= 1,
                "reference:{rays} pixel {p}: oracle {a}, GPU {b}"
            );
            off += usize::from(a != b);
        }
        assert!(off * 100 <= oracle.len(), "reference:{rays}: {off} pixels differ");
        let shaded = frame
            .unfiltered
            .iter()
            .zip(&oracle)
            .filter(|(_, m)| **m < 0x10000);
        for (v, &count) in shaded {
            let expected = 1.0 - count as f32 / rays as f32;
            assert!(
                (v[3] - expected).abs() <= 1.0 / rays as f32 + 1e-6,
                "visibility {} vs {expected}",
                v[3]
            );
        }
        let lit = oracle.iter().filter(|&&c| c == 0).count();
        let dark = oracle.iter().filter(|&&c| c == rays).count();
        assert!(
            lit > 0 && dark > 0 && lit + dark < oracle.len(),
            "the view has lit, umbra and penumbra pixels"
        );
    }
}

/// Runs one tracer with counters over a given G-buffer; returns the masks and counters.
#[allow(clippy::too_many_arguments)]
fn run_counted(
    tracer: Tracer,
    shrink: bool,
    variant: VectorVariant,
    leaf_mode: LeafMode,
    gpu_scene: &GpuScene,
    texels: &[GBufferTexel],
    view: &View,
    (w, h): (u32, u32),
) -> (Vec<u32>, Counters) {
    let pass = ShadowTracer::new(
        ctx(),
        &TracerOptions {
            tracer,
            variant: Some(variant),
            leaf_mode,
            counters: true,
            shrink,
        },
    )
    .unwrap();
    let (masks, stats) = trace_masks(&pass, gpu_scene, texels, view, &shadow_params(&view.light, w, h));
    (masks, stats.counters)
}

/// A built-in scene, its view, BVH and GPU copy, and the G-buffer the renderer traces
/// for a `w`×`h` image of it.
fn traced_gbuffer(name: &str, w: u32, h: u32) -> (Scene, View, Bvh, GpuScene, Vec<GBufferTexel>) {
    let (scene, view) = embedded(name);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    let frame = Renderer::new(ctx(), None)
        .unwrap()
        .render(ctx(), &gpu_scene, &view, &settings)
        .unwrap();
    let texels = frame.gbuffer.unwrap();
    (scene, view, bvh, gpu_scene, texels)
}

#[test]
fn counters_equal_the_cpu_twins() {
    for s in assets::EMBEDDED_SCENES {
        let (w, h) = (48, 36);
        let (scene, view, bvh, gpu_scene, texels) = traced_gbuffer(s.name, w, h);
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let (mft_plain, _) = mft_masks(
            &bvh,
            &texels,
            &points,
            &params,
            &TileOptions::with_budget(ITERATION_BUDGET),
        );
        // The twin's counters as the kernel runs: shrinking and leaf mode.
        let twin = |shrink, transposed| {
            let options = TileOptions {
                budget: ITERATION_BUDGET,
                shrink,
                transposed,
            };
            mft_masks(&bvh, &texels, &points, &params, &options).1
        };
        let (_, packet_twin) = packet_masks(&bvh, &texels, &points, &params, ITERATION_BUDGET);
        for variant in variants() {
            for (tracer, shrink, leaf_mode, twin) in [
                (Tracer::Mft, false, LeafMode::PerLane, twin(false, false)),
                (Tracer::Mft, false, LeafMode::Transposed, twin(false, true)),
                (Tracer::Mft, true, LeafMode::PerLane, twin(true, false)),
                (Tracer::Mft, true, LeafMode::Transposed, twin(true, true)),
                (Tracer::Packet, false, LeafMode::PerLane, packet_twin),
            ] {
                let (masks, gpu) = run_counted(
                    tracer,
                    shrink,
                    variant,
                    leaf_mode,
                    &gpu_scene,
                    &texels,
                    &view,
                    (w, h),
                );
                let label = format!("{} {tracer} shrink {shrink} {variant} {leaf_mode}", s.name);
                if tracer == Tracer::Mft {
                    assert_same_rays(&label, &mft_plain, &masks, &scene, &bvh, &view, &texels, w);
                }
                eprintln!("{label}: GPU {gpu:?}");
                // Culling decisions are the same arithmetic on both sides: exact where the
                // arithmetic is (exact_arithmetic); a fused multiply-add elsewhere could flip
                // one in a million, so allow 0.1 % there.
                let slack = if exact_arithmetic() { 0 } else { 1 };
                for (name, g, c) in [
                    ("nodes", gpu.nodes_visited, twin.nodes_visited),
                    ("boxes", gpu.box_tests, twin.box_tests),
                    ("tris", gpu.triangles_accessed, twin.triangles_accessed),
                    (
                        "after culling",
                        gpu.triangles_after_culling,
                        twin.triangles_after_culling,
                    ),
                    ("tests", gpu.triangle_tests, twin.triangle_tests),
                ] {
                    assert!(c > 0, "{label}: the twin counted no {name}");
                    assert!(
                        g.abs_diff(c) * 1000 <= c * slack,
                        "{label}: {name} GPU {g} vs twin {c}"
                    );
                }
            }
        }
    }
}

/// A 4×4 tile of ground points `spacing` apart around the origin at height `y`, facing
/// up, under a square light `2·half` wide at height `light_y`, facing down.
fn tile_under_a_light(spacing: f32, y: f32, half: f32, light_y: f32) -> (Vec<GBufferTexel>, View) {
    let texels = (0..16)
        .map(|i| GBufferTexel {
            origin: Vec3::new(
                ((i % 4) as f32 - 1.5) * spacing,
                y,
                ((i / 4) as f32 - 1.5) * spacing,
            ),
            depth: 1.0,
            normal: Vec3::Y,
            geo_normal: Vec3::Y,
            triangle: GBufferTexel::UNKNOWN_TRIANGLE,
            ..GBufferTexel::default()
        })
        .collect();
    let light = QuadLight {
        corner: Vec3::new(-half, light_y, -half),
        // Facing down: cross(edge_u, edge_v) = -y.
        edge_u: Vec3::new(2.0 * half, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 2.0 * half),
        color: Vec3::ONE,
        intensity: 1.0,
    };
    let view = View {
        light,
        ..embedded("playground").1
    };
    (texels, view)
}

/// A 4×4 tile of shade points on the floor at y = 0 under a light at y = 3.
fn floor_tile() -> (Vec<GBufferTexel>, View) {
    tile_under_a_light(0.2, 0.0, 0.5, 3.0)
}

#[test]
fn counters_match_hand_counts() {
    let (texels, view) = floor_tile();
    // A big occluder between the tile and the light, and a far-away triangle.
    let cover = [
        Vec3::new(-10.0, 1.0, -10.0),
        Vec3::new(0.0, 1.0, 20.0),
        Vec3::new(20.0, 1.0, -10.0),
    ];
    let far = [
        Vec3::new(100.0, 1.0, 0.0),
        Vec3::new(101.0, 1.0, 0.0),
        Vec3::new(100.0, 1.0, 1.0),
    ];
    let leaf_one = BvhSettings {
        max_leaf_size: 1,
        ..BvhSettings::default()
    };
    // (triangles, expected MFT counters, expected packet counters): every ray is blocked.
    let one_leaf = Counters {
        box_tests: 1,
        triangles_accessed: 1,
        triangles_after_culling: 1,
        triangle_tests: 16,
        ..Counters::default()
    };
    let two_leaves = Counters {
        nodes_visited: 1,
        box_tests: 3,
        ..one_leaf
    };
    // Packet: the same per pixel, but a triangle test is one 16-ray test per pixel.
    let per_pixel = |c: Counters| Counters {
        nodes_visited: 16 * c.nodes_visited,
        box_tests: 16 * c.box_tests,
        triangles_accessed: 16,
        triangles_after_culling: 16,
        triangle_tests: 16,
        ..Counters::default()
    };
    for (tris, mft, packet) in [
        (vec![(cover, 0)], one_leaf, per_pixel(one_leaf)),
        (vec![(cover, 0), (far, 0)], two_leaves, per_pixel(two_leaves)),
    ] {
        let scene = scene_from_triangles(&tris, &[[1.0; 3]]);
        let bvh = Bvh::build(&scene, &leaf_one).unwrap();
        assert_eq!(bvh.nodes.len(), 2 * tris.len() - 1);
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let params = shadow_params(&view.light, 4, 4);
        let points = sampling::light_points(&view.light);
        let (_, twin_mft) = mft_masks(
            &bvh,
            &texels,
            &points,
            &params,
            &TileOptions::with_budget(ITERATION_BUDGET),
        );
        let (_, twin_packet) = packet_masks(&bvh, &texels, &points, &params, ITERATION_BUDGET);
        assert_eq!(twin_mft.gpu_view(), mft, "MFT twin, {} triangles", tris.len());
        assert_eq!(
            twin_packet.gpu_view(),
            packet,
            "packet twin, {} triangles",
            tris.len()
        );
        for variant in variants() {
            for (tracer, expected) in [(Tracer::Mft, mft), (Tracer::Packet, packet)] {
                let (masks, counters) = run_counted(
                    tracer,
                    false,
                    variant,
                    LeafMode::PerLane,
                    &gpu_scene,
                    &texels,
                    &view,
                    (4, 4),
                );
                assert!(
                    masks.iter().all(|&m| m == MASK_FULL),
                    "{tracer}: every ray is blocked"
                );
                assert_eq!(counters, expected, "{tracer} {variant}, {} triangles", tris.len());
            }
        }
    }
}

/// A 4×4 tile of ground points within 0.0075 of the origin (the ray offset above it)
/// under a 0.02-wide light at y = 10, facing down: every shadow ray stays within 0.02 of
/// the y axis.
fn column_tile() -> (Vec<GBufferTexel>, View) {
    tile_under_a_light(0.005, 1e-4, 0.01, 10.0)
}

/// A tile whose rays need more loop passes than lavapipe allows (a column of 200,000
/// near misses before the blocker, [`near_miss_column`]), traced with an iteration
/// budget far above that limit so that no kernel suspends: where the driver ends a
/// loop early, the pass must say so in an error naming the pass; where it does not,
/// the masks must be the oracle's (every ray blocked). Never masks from a traversal cut
/// short. The blocker sits once below the column and once above it, so that whichever
/// child a kernel visits first, in one of the two it meets the blocker last.
#[test]
fn a_loop_the_driver_ends_is_an_error_never_wrong_masks() {
    let (texels, view) = column_tile();
    let points = sampling::light_points(&view.light);
    let mut params = shadow_params(&view.light, 4, 4);
    params.iteration_budget = 1 << 30;
    let mut failures = Vec::new();
    for blocker_y in [0.5, 9.5] {
        let scene = scene_from_triangles(&near_miss_column(200_000, blocker_y), &[[0.8; 3], [0.3; 3]]);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let oracle = penumbra::reference::shadow_per_ray::per_ray_masks(&bvh, &texels, &points, &params);
        assert!(
            oracle.iter().all(|&m| m == MASK_FULL),
            "blocker at {blocker_y}: the blocker must block every ray: {oracle:x?}"
        );
        for (tracer, leaf_mode, variant) in every_tracer() {
            let pass = shadow_tracer(tracer, leaf_mode, variant);
            let label = format!("blocker at {blocker_y}, {tracer} {leaf_mode} {variant}");
            match try_trace_masks(&pass, &gpu_scene, &texels, &view, &params) {
                Err(e) => {
                    let message = e.to_string();
                    eprintln!("{label}: {message}");
                    if !(message.contains("shadow pass") && message.contains("ended")) {
                        failures.push(format!(
                            "{label}: the error must name the pass and say its loop was ended: {message}"
                        ));
                    }
                }
                Ok((masks, stats)) => {
                    let wrong = masks.iter().zip(&oracle).filter(|(a, b)| a != b).count();
                    eprintln!(
                        "{label}: the driver did not end the loop; {wrong} of 16 masks wrong; {stats:?}"
                    );
                    if wrong > 0 {
                        failures.push(format!("{label}: {wrong} masks from a traversal cut short"));
                    }
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Watertightness: a closed room of 25,392 triangles (a turned box, each face a 46×46
/// grid), lit from outside and seen from inside, is dark at every pixel: no shadow ray
/// of any tracer slips between two triangles that share an edge or a vertex.
#[test]
fn a_closed_room_lit_from_outside_is_dark_for_every_tracer() {
    let centre = Vec3::new(0.3, 0.2, -0.1);
    let scene = scene_from_triangles(&closed_room(46, 2.0, centre), &[[0.8; 3]]);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let view = View {
        camera: penumbra::scene::view::Camera {
            eye: centre + Vec3::new(0.1, -0.2, 0.3),
            target: centre + Vec3::new(2.0, 1.0, -1.5),
            up: Vec3::Y,
            fov_y_degrees: 100.0,
        },
        light: QuadLight::from_center(
            centre + Vec3::new(0.5, 6.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, -2.0),
        ),
        ground_y: None,
    };
    view.validate().unwrap();
    let (w, h) = (64, 64);
    let mut settings = FrameSettings::new(w, h);
    settings.filter = None;
    for (tracer, leaf_mode, variant) in every_tracer() {
        let options = RendererOptions {
            leaf_mode,
            ..options(tracer, variant)
        };
        let frame = Renderer::new(ctx(), options)
            .unwrap()
            .render(ctx(), &gpu_scene, &view, &settings)
            .unwrap();
        let lit: Vec<usize> = (0..frame.masks.len())
            .filter(|&p| frame.masks[p] != MASK_FULL)
            .collect();
        let rays: u32 = frame.masks.iter().map(|m| (!m & MASK_FULL).count_ones()).sum();
        eprintln!(
            "{tracer} {leaf_mode} {variant}: {} of {} pixels see the light ({rays} rays)",
            lit.len(),
            frame.masks.len()
        );
        assert!(
            lit.is_empty(),
            "{tracer} {leaf_mode} {variant}: {} pixels see light through the closed room \
             ({rays} rays), e.g. pixel {} mask {:#x}",
            lit.len(),
            lit[0],
            frame.masks[lit[0]]
        );
    }
}

/// A tile that runs out of its budget saves what the CPU twin saves, word for word
/// ([`penumbra::reference::shadow_mft::dispatch_tile`]): the state of its traversal (node,
/// masks, cursor, pending leaf, stack), every lane's mask and shrunk rectangle. Checked
/// after one dispatch of the embedded recording path, whose scratch the test can read.
/// Not for transposed leaves with four vectors per workgroup: there the inner loop over a
/// triangle's frusta runs for the workgroup's vectors together and counts its passes
/// against all of them, so a vector suspends at another point than alone (its masks
/// after resuming are the oracle's all the same: tests/gpu/shadow_mft.rs).
#[test]
fn a_suspended_tile_saves_the_state_the_twin_saves() {
    use penumbra::contract::shadow::STATE_WORDS;
    use penumbra::contract::suspend::STATUS_SUSPENDED;
    use penumbra::gpu::ShadowScratch;
    use penumbra::reference::shadow_mft::{Frustum, TileOptions, TileRun, dispatch_tile};
    let (w, h) = (24, 20);
    let (_, view, bvh, gpu_scene, texels) = traced_gbuffer("lattice", w, h);
    let points = sampling::light_points(&view.light);
    let light: Vec<[f32; 4]> = points.iter().map(|p| p.extend(0.0).to_array()).collect();
    let usage = wgpu::BufferUsages::empty();
    let gbuffer = penumbra::gpu::storage_buffer(ctx(), "G-buffer", &texels, usage).unwrap();
    let light_points =
        penumbra::gpu::storage_buffer(ctx(), "light points", &light, wgpu::BufferUsages::UNIFORM).unwrap();
    let masks = penumbra::gpu::empty_storage_buffer(ctx(), "masks", u64::from(w * h) * 4, usage).unwrap();
    let (tiles_x, tiles_y) = (w.div_ceil(4), h.div_ceil(4));
    for budget in [3, 40] {
        let mut params = shadow_params(&view.light, w, h);
        params.iteration_budget = budget;
        for (leaf_mode, variant) in variants()
            .into_iter()
            .flat_map(|v| [(LeafMode::PerLane, v), (LeafMode::Transposed, v)])
            .filter(|&(mode, v)| !(mode == LeafMode::Transposed && v == VectorVariant::Workgroup4))
        {
            let options = TracerOptions {
                variant: Some(variant),
                leaf_mode,
                ..TracerOptions::default()
            };
            let pass = ShadowTracer::new(ctx(), &options).unwrap();
            let scratch = ShadowScratch::new(&ctx().device, w, h);
            let mut encoder = ctx().device.create_command_encoder(&Default::default());
            let image = penumbra::gpu::ShadowImage {
                gbuffer: &gbuffer,
                light_points: &light_points,
                masks: &masks,
            };
            pass.record(
                &ctx().device,
                &mut encoder,
                &gpu_scene,
                &image,
                &scratch,
                &params,
                0,
            )
            .unwrap();
            ctx().queue.submit([encoder.finish()]);
            let bytes = u64::from(tiles_x * tiles_y) * STATE_WORDS as u64 * 4;
            let state: Vec<u32> = penumbra::gpu::read_buffer(ctx(), &scratch.state, 0..bytes).unwrap();
            let tile_options = TileOptions {
                budget,
                shrink: options.shrink,
                transposed: leaf_mode == LeafMode::Transposed,
            };
            let mut suspended = 0;
            for ty in 0..tiles_y {
                for tx in 0..tiles_x {
                    let frusta = std::array::from_fn(|i| {
                        let (x, y) = (tx * 4 + i as u32 % 4, ty * 4 + i as u32 / 4);
                        if x < w && y < h {
                            Frustum::new(&texels[(y * w + x) as usize], i, &points, &params)
                        } else {
                            Frustum::outside()
                        }
                    });
                    let slot = (ty * tiles_x + tx) as usize;
                    let gpu = &state[slot * STATE_WORDS..(slot + 1) * STATE_WORDS];
                    let label = format!("budget {budget} {leaf_mode} {variant} tile ({tx},{ty})");
                    let mut counters = Counters::default();
                    match dispatch_tile(&bvh, &frusta, None, &params, &tile_options, &mut counters) {
                        TileRun::Suspended(words) => {
                            suspended += 1;
                            if exact_arithmetic() {
                                assert_eq!(gpu, &words[..], "{label}: saved state");
                            } else {
                                // A ray flipped by a fused multiply-add changes the words after it.
                                assert_eq!(
                                    gpu[0], STATUS_SUSPENDED,
                                    "{label}: the twin suspended, the kernel did not"
                                );
                            }
                        }
                        TileRun::Finished(_) => {
                            assert_ne!(
                                gpu[0], STATUS_SUSPENDED,
                                "{label}: the twin finished, the kernel suspended"
                            );
                        }
                    }
                }
            }
            eprintln!(
                "budget {budget} {leaf_mode} {variant}: {suspended} of {} tiles suspended, states equal",
                tiles_x * tiles_y
            );
            assert!(suspended > 0, "budget {budget}: some tile must suspend");
        }
    }
}

/// The MFT kernel lets no ray slip through an edge two triangles share: 4,096 rays aimed
/// at points of such an edge (corners that `v0 + e1` would not rebuild exactly) are all
/// blocked, in both leaf modes and every vector variant, as in the CPU twin
/// (tests/cpu/shadow_mft.rs). The Möller–Trumbore tracers (packet, per-ray) are not
/// watertight there; their counts are printed, not asserted.
#[test]
fn no_ray_slips_through_a_shared_edge_on_the_gpu() {
    let (scene, view, texels, w, h) = rays_through_a_shared_edge();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let params = shadow_params(&view.light, w, h);
    for (tracer, leaf_mode, variant) in every_tracer() {
        let pass = shadow_tracer(tracer, leaf_mode, variant);
        let (masks, _) = trace_masks(&pass, &gpu_scene, &texels, &view, &params);
        let through = masks.iter().filter(|&&m| m & 1 == 0).count();
        eprintln!(
            "{tracer} {leaf_mode} {variant}: {through} of {} aimed rays pass",
            masks.len()
        );
        if tracer == Tracer::Mft {
            assert_eq!(
                through, 0,
                "{tracer} {leaf_mode} {variant}: rays slip through a shared edge"
            );
        }
    }
}
