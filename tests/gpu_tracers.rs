//! The shadow tracers on lavapipe (or any adapter): packet, per-ray and reference
//! masks against the CPU oracles, and the Table-1 counters of the MFT and packet
//! kernels against their CPU twins and against counts made by hand.

mod support;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{
    FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions, ShadowTracer, Tracer, TracerOptions,
    VectorVariant,
};
use penumbra::layout::GBufferTexel;
use penumbra::reference::counters::Counters;
use penumbra::reference::mft::{TileOptions, mft_masks, mft_masks_with_options};
use penumbra::reference::packet::packet_masks;
use penumbra::reference::shadow::{ITERATION_BUDGET, MASK_FULL, reference_counts, shadow_params};
use penumbra::view::{QuadLight, View};
use penumbra::{assets, sampling};
use support::gpu::{ctx, embedded, trace_masks, variants};
use support::{assert_masks_match_oracle, scene_from_triangles};

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
    let pass = ShadowTracer::with_options(
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

#[test]
fn counters_equal_the_cpu_twins() {
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (48, 36);
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let frame = Renderer::new(ctx(), None)
            .unwrap()
            .render(ctx(), &gpu_scene, &view, &settings)
            .unwrap();
        let texels = frame.gbuffer.unwrap();
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let (mft_plain, _) = mft_masks(&bvh, &texels, &points, &params, ITERATION_BUDGET);
        // The twin's counters as the kernel runs: shrinking and leaf mode.
        let twin = |shrink, transposed| {
            let options = TileOptions {
                budget: ITERATION_BUDGET,
                shrink,
                transposed,
            };
            mft_masks_with_options(&bvh, &texels, &points, &params, &options).1
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
                    let bits: u32 = mft_plain
                        .iter()
                        .zip(&masks)
                        .map(|(a, b)| (a ^ b).count_ones())
                        .sum();
                    assert!(bits <= 2, "{label}: masks differ from the twin's in {bits} bits");
                }
                eprintln!("{label}: GPU {gpu:?}");
                // Culling decisions are the same arithmetic on both sides; a fused
                // multiply-add on the GPU could flip one in a million, so allow 0.1 %.
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
                    assert!(g.abs_diff(c) * 1000 <= c, "{label}: {name} GPU {g} vs twin {c}");
                }
            }
        }
    }
}

/// A 4×4 tile of shade points on the floor at y = 0 under a light at y = 3.
fn floor_tile() -> (Vec<GBufferTexel>, View) {
    let texels = (0..16)
        .map(|i| GBufferTexel {
            origin: Vec3::new((i % 4) as f32 * 0.2 - 0.3, 0.0, (i / 4) as f32 * 0.2 - 0.3),
            depth: 1.0,
            normal: Vec3::Y,
            geo_normal: Vec3::Y,
            ..GBufferTexel::default()
        })
        .collect();
    let light = QuadLight {
        corner: Vec3::new(-0.5, 3.0, -0.5),
        // Facing down: cross(edge_u, edge_v) = -y.
        edge_u: Vec3::new(1.0, 0.0, 0.0),
        edge_v: Vec3::new(0.0, 0.0, 1.0),
        color: Vec3::ONE,
        intensity: 1.0,
    };
    let view = View {
        light,
        ..embedded("playground").1
    };
    (texels, view)
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
        let (_, twin_mft) = mft_masks(&bvh, &texels, &points, &params, ITERATION_BUDGET);
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
