//! The GPU frame on lavapipe (or any adapter) against the CPU oracles: shadow
//! masks from both vector variants, the primary pass, the filter, exact
//! lit/umbra values, and a tile whose work exceeds lavapipe's loop limit.

mod support;

use std::path::Path;
use std::sync::OnceLock;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{FrameSettings, GpuContext, GpuOptions, GpuScene, Renderer, VectorVariant};
use penumbra::reference::shadow::{per_ray_masks, shadow_params};
use penumbra::{assets, sampling, scene::Scene, view::View};
use support::compare_masks;

/// One context per test binary; a missing adapter fails every test with the reason.
fn ctx() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| {
        let ctx = GpuContext::new(&GpuOptions::default())
            .unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
        eprintln!("adapter: {}", ctx.info);
        ctx
    })
}

/// The variants this adapter can run: always workgroup, subgroup when it has fixed 16k-wide subgroups.
fn variants() -> Vec<VectorVariant> {
    let mut v = vec![VectorVariant::Workgroup];
    if VectorVariant::choose(&ctx().info, Some(VectorVariant::Subgroup)).is_ok() {
        v.push(VectorVariant::Subgroup);
    }
    v
}

fn embedded(name: &str) -> (Scene, View) {
    let s = assets::embedded_scene(name).unwrap();
    (
        Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap(),
        s.view(),
    )
}

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
        let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
        let mut first: Option<Vec<u32>> = None;
        for &variant in &vs {
            let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
            let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
            let gbuffer = frame.gbuffer.as_ref().unwrap();
            let params = shadow_params(&view.light, w, h);
            let points = sampling::light_points(&view.light);
            let oracle = per_ray_masks(&bvh, gbuffer, &points, &params);
            let (differing, total, unexplained) = compare_masks(
                &oracle,
                &frame.masks,
                gbuffer,
                w,
                &points,
                &params,
                &corners,
                1e-4 * scene.bounds().diagonal(),
            );
            eprintln!(
                "{} {variant}: {differing} of {total} rays differ from the oracle; timings {:?}",
                s.name, frame.timings
            );
            assert!(
                unexplained.is_empty(),
                "{} {variant}: {:?}",
                s.name,
                &unexplained[..unexplained.len().min(10)]
            );
            assert!(
                differing * 1000 <= total,
                "{} {variant}: {differing} of {total}",
                s.name
            );
            match &first {
                None => first = Some(frame.masks.clone()),
                Some(m) => assert_eq!(m, &frame.masks, "{}: variants differ", s.name),
            }
        }
    }
}
