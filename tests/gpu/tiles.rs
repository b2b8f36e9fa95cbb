//! Big images are rendered in tiles with a margin for the filter and stitched:
//! the stitched frame equals the one-piece frame bit for bit, and sizes past the
//! device's limit are refused with the limit named.

use crate::support;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{FrameSettings, GpuScene, PrimaryTracer, Renderer, RendererOptions, Tracer};
use support::gpu::{ctx, embedded, variants};

#[test]
fn tiled_frames_equal_one_piece_frames() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (70, 54);
    for (tracer, primary) in [
        (Tracer::Mft, PrimaryTracer::PerRay),
        (Tracer::Mft, PrimaryTracer::Mft),
        (Tracer::Packet, PrimaryTracer::PerRay),
    ] {
        let options = RendererOptions {
            variant: variants().last().copied(),
            tracer,
            primary,
            ..RendererOptions::default()
        };
        let renderer = Renderer::new(ctx(), options).unwrap();
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let whole = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
        for tile in [16, 20, 32] {
            settings.max_tile = Some(tile);
            let mut calls = 0;
            let tiled = renderer
                .render_with_progress(ctx(), &gpu_scene, &view, &settings, &mut |phase, done, total| {
                    assert_eq!(phase, penumbra::gpu::Phase::Shadow);
                    calls += 1;
                    assert!(done <= total);
                })
                .unwrap();
            let label = format!("{tracer} {primary:?} tile {tile}");
            assert!(calls >= (w / tile) as usize, "{label}: progress per tile");
            assert!(tiled.gbuffer == whole.gbuffer, "{label}: G-buffers differ");
            assert!(tiled.masks == whole.masks, "{label}: masks differ");
            assert!(
                tiled.unfiltered == whole.unfiltered,
                "{label}: unfiltered values differ"
            );
            assert!(
                tiled.filtered == whole.filtered,
                "{label}: filtered values differ"
            );
            assert!(tiled.brdf == whole.brdf, "{label}: BRDFs differ");
        }
    }
}

#[test]
fn images_past_the_device_limit_are_refused_with_the_limit() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let limit = ctx().device.limits().max_texture_dimension_2d;
    let renderer = Renderer::new(ctx(), None).unwrap();
    let err = renderer
        .render(ctx(), &gpu_scene, &view, &FrameSettings::new(limit + 1, 4))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&format!("{limit} pixels")) && err.contains("max_texture_dimension_2d"),
        "{err}"
    );
}
