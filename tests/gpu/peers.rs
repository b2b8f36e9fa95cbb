//! The peers as oracles nobody here wrote: the ray-query tracer (the driver's own BVH
//! and traversal, on adapters with ray queries: Mesa 25 lavapipe in CI) and, with the
//! `embree` feature, Embree 3. Every GPU tracer's masks are compared with theirs ray for
//! ray on the generated scenes and on Sponza, on one G-buffer (the CPU twin's), with the
//! comparison of `support::compare_masks`: a differing ray is excused only within the
//! edge tolerance of a triangle other than its origin's own, and at most 0.1 % differ.
//!
//! Run with `--nocapture` to see how many rays each pair decides differently.

use crate::support;

use std::path::Path;

use glam::{Mat4, Vec3};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::gpu::{GpuContext, GpuScene, MotionSettings, ShadowTracer, Tracer, TracerOptions};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_per_ray::shadow_params;
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use penumbra::{Error, assets};
use support::gpu::{ctx, embedded, ray_query_ctx, try_trace_masks_on};

/// One scene, view and image size, with its BVH and the CPU twin's G-buffer.
struct Case {
    label: String,
    scene: Scene,
    bvh: Bvh,
    view: View,
    gbuffer: Vec<GBufferTexel>,
    size: (u32, u32),
}

impl Case {
    fn new(label: &str, scene: Scene, view: View, (w, h): (u32, u32)) -> Case {
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let cam = camera_params(
            &view.camera,
            w,
            h,
            scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
        );
        let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
        Case {
            label: label.to_owned(),
            scene,
            bvh,
            view,
            gbuffer,
            size: (w, h),
        }
    }

    /// `tracer`'s masks of this case on `ctx`.
    fn masks(&self, ctx: &GpuContext, gpu_scene: &GpuScene, tracer: Tracer) -> Vec<u32> {
        let pass = ShadowTracer::new(
            ctx,
            &TracerOptions {
                tracer,
                ..TracerOptions::default()
            },
        )
        .unwrap();
        let params = shadow_params(&self.view.light, self.size.0, self.size.1);
        try_trace_masks_on(ctx, &pass, gpu_scene, &self.gbuffer, &self.view, &params)
            .unwrap_or_else(|e| panic!("{} {tracer}: {e}", self.label))
            .0
    }

    /// Asserts that `a` and `b` (named in `what`) decide the same rays within the oracle
    /// comparison's tolerance; returns the rays that differ.
    fn assert_agree(&self, what: &str, a: &[u32], b: &[u32]) -> usize {
        let c = support::compare_view_masks(
            a,
            b,
            &self.scene,
            &self.bvh,
            &self.view,
            &self.gbuffer,
            self.size.0,
        );
        eprintln!("{} {what}: {c}", self.label);
        assert!(
            c.unexplained.is_empty(),
            "{} {what}: {c}: {:?}",
            self.label,
            &c.unexplained[..c.unexplained.len().min(10)]
        );
        assert!(c.differing * 1000 <= c.total, "{} {what}: {c}", self.label);
        // Not a vacuous pass: the view has shadows and lit pixels.
        let blocked: u32 = a.iter().map(|m| (m & 0xffff).count_ones()).sum();
        assert!(
            blocked > 0 && (blocked as usize) < c.total,
            "{}: {blocked} of {} rays blocked",
            self.label,
            c.total
        );
        c.differing
    }
}

/// The generated scenes at 61×43 and Sponza's atrium at 64×64 (when `../shared/scenes` is
/// there; the README's test command runs without it, `.ci/run` has it and says so if not).
fn cases() -> Vec<Case> {
    let mut cases: Vec<Case> = assets::EMBEDDED_SCENES
        .iter()
        .map(|s| {
            let (scene, view) = embedded(s.name);
            Case::new(s.name, scene, view, (61, 43))
        })
        .collect();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = root.join("../shared/scenes/dabrovic_sponza/sponza.gltf");
    if !file.exists() {
        eprintln!(
            "{} is missing: the peers are compared on the generated scenes only",
            file.display()
        );
        return cases;
    }
    let scene = Scene::load(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    let view = View::load(&root.join("assets/views/sponza-atrium.json")).unwrap();
    cases.push(Case::new("sponza atrium", scene, view, (64, 64)));
    cases
}

/// The error an adapter without ray queries gives: one line that names the feature.
fn assert_one_line_ray_query_error(message: &str) {
    assert!(
        !message.contains('\n') && message.contains("EXPERIMENTAL_RAY_QUERY"),
        "{message}"
    );
}

#[test]
fn ray_query_masks_match_the_oracle_and_every_tracer() {
    let ctx = match ray_query_ctx() {
        Ok(ctx) => ctx,
        Err(message) => {
            // Nothing to trace with: what is checked is that the user hears why.
            assert_one_line_ray_query_error(message);
            eprintln!("this adapter has no ray queries; checked its error instead: {message}");
            return;
        }
    };
    for case in cases() {
        let gpu_scene = GpuScene::new(ctx, &case.scene, &case.bvh).unwrap();
        let rq = gpu_scene
            .ray_query
            .as_ref()
            .expect("structures on a device with ray queries");
        eprintln!("{}: BLAS and TLAS built in {:.1} ms", case.label, rq.build_ms);
        let ray_query = case.masks(ctx, &gpu_scene, Tracer::RayQuery);
        let (w, h) = case.size;
        support::assert_masks_match_oracle(
            &format!("{} ray-query", case.label),
            &case.scene,
            &case.bvh,
            &case.view,
            &case.gbuffer,
            &ray_query,
            w,
            h,
        );
        for tracer in [Tracer::Mft, Tracer::Packet, Tracer::PerRay] {
            let masks = case.masks(ctx, &gpu_scene, tracer);
            case.assert_agree(&format!("{tracer} against ray-query"), &ray_query, &masks);
        }
    }
}

#[test]
fn ray_query_tracer_on_a_device_without_ray_queries_is_a_one_line_error() {
    // The shared context never asks for ray queries, whatever the adapter has.
    let err = ShadowTracer::new(
        ctx(),
        &TracerOptions {
            tracer: Tracer::RayQuery,
            ..TracerOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, Error::RayQueryUnsupported { .. }), "{err:?}");
    assert_one_line_ray_query_error(&err.to_string());
    // And a GPU scene on it builds no structures.
    let (scene, _) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    assert!(GpuScene::new(ctx(), &scene, &bvh).unwrap().ray_query.is_none());
}

#[test]
fn ray_query_structures_follow_moving_objects() {
    let Ok(ctx) = ray_query_ctx() else {
        // ray_query_masks_match_the_oracle_and_every_tracer checks the error there.
        eprintln!("this adapter has no ray queries: nothing moves");
        return;
    };
    let (scene, view) = embedded("playground");
    let sphere = scene
        .instances
        .iter()
        .position(|i| i.name.as_deref() == Some("sphere"))
        .expect("the playground's sphere") as u32;
    let start = scene.instances[sphere as usize].world_from_object;
    let case = Case::new("playground", scene, view, (61, 43));
    let mut gpu_scene =
        GpuScene::with_motion(ctx, &case.scene, &case.bvh, MotionSettings::default()).unwrap();
    let before = case.masks(ctx, &gpu_scene, Tracer::RayQuery);
    // Far out of the light's way: the G-buffer stays the unmoved scene's (the CPU twin's),
    // so the sphere's shadow vanishes from the ground, and from the pixels that saw the
    // sphere itself, whose rays the sphere blocked.
    let moved = Mat4::from_translation(Vec3::new(0.0, 0.0, 60.0)) * start;
    gpu_scene.set_transform(&ctx.queue, sphere, moved).unwrap();
    let after = case.masks(ctx, &gpu_scene, Tracer::RayQuery);
    // MFT over the refitted BVH, on the same rays.
    let mft = case.masks(ctx, &gpu_scene, Tracer::Mft);
    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    let mft_changed = before.iter().zip(&mft).filter(|(a, b)| a != b).count();
    eprintln!("moving the sphere away changed {changed} ray-query masks, {mft_changed} MFT masks");
    // Without rebuilt structures the ray queries would still see the sphere: no change.
    assert!(
        changed > 0 && mft_changed > 0,
        "moving the sphere changed no masks"
    );
    case.assert_agree("after a move, mft against ray-query", &after, &mft);
}

/// Embree 3 (Debian's libembree-dev) against every GPU tracer on this adapter, the ray
/// queries included where it has them.
#[cfg(feature = "embree")]
#[test]
fn every_gpu_tracer_matches_embree() {
    use penumbra::embree::EmbreeScene;
    use penumbra::sampling;
    let (ctx, mut tracers) = match ray_query_ctx() {
        Ok(ctx) => (ctx, vec![Tracer::RayQuery]),
        Err(_) => (ctx(), vec![]),
    };
    tracers.extend([Tracer::Mft, Tracer::Packet, Tracer::PerRay]);
    for case in cases() {
        let params = shadow_params(&case.view.light, case.size.0, case.size.1);
        let points = sampling::light_points(&case.view.light);
        let embree = EmbreeScene::new(&case.bvh)
            .unwrap()
            .masks(&case.gbuffer, &points, &params);
        let gpu_scene = GpuScene::new(ctx, &case.scene, &case.bvh).unwrap();
        for &tracer in &tracers {
            let masks = case.masks(ctx, &gpu_scene, tracer);
            case.assert_agree(&format!("{tracer} against embree"), &embree, &masks);
        }
    }
}
