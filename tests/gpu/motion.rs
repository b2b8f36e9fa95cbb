//! Moving objects on the GPU: after `GpuScene::set_transform`, the frame traced over the
//! refitted (or rebuilt) BVH equals the CPU oracle on a BVH built from scratch over the
//! moved triangles.
//!
//! Run with `--nocapture` to see the figures measured.

use crate::support;

use glam::{Mat4, Quat, Vec3};
use penumbra::Error;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::gpu::{FrameSettings, GpuScene, MotionSettings, Renderer};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use support::assert_masks_match_oracle;
use support::gpu::{ctx, embedded};

const SIZE: (u32, u32) = (96, 72);

/// The scene with its triangles where the GPU scene has them now.
fn moved_scene(scene: &Scene, gpu: &GpuScene) -> Scene {
    let mut moved = scene.clone();
    let corners = gpu.world_corners().expect("a scene made with motion");
    for (t, c) in moved.triangles.iter_mut().zip(corners) {
        t.positions = *c;
    }
    moved
}

/// Renders `gpu` and checks masks and G-buffer against the CPU oracles on a BVH built
/// from scratch over `moved` (the scene as the GPU has it). Returns the masks.
fn check_frame(label: &str, renderer: &Renderer, gpu: &GpuScene, moved: &Scene, view: &View) -> Vec<u32> {
    let (w, h) = SIZE;
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    let frame = renderer.render(ctx(), gpu, view, &settings).unwrap();
    let gbuffer = frame.gbuffer.as_ref().unwrap();
    let rebuilt = Bvh::build(moved, &BvhSettings::default()).unwrap();

    // Primary hits: the same scene triangle at the same distance as the CPU twin over the
    // rebuilt tree (leaf orders differ, so compare scene indices).
    let cam = camera_params(
        &view.camera,
        w,
        h,
        moved.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let cpu = primary_gbuffer(&rebuilt, &ShadingData::new(moved, &rebuilt).unwrap(), &cam);
    let gpu_bvh = gpu.cpu_bvh().unwrap();
    let scene_index =
        |bvh: &Bvh, t: &GBufferTexel| t.is_hit().then(|| bvh.triangles[t.triangle as usize].scene_index);
    let primary_diffs = cpu
        .iter()
        .zip(gbuffer)
        .filter(|(c, g)| {
            scene_index(&rebuilt, c) != scene_index(gpu_bvh, g) || (c.depth - g.depth).abs() > 1e-5 * c.depth
        })
        .count();
    assert!(
        primary_diffs * 1000 <= cpu.len(),
        "{label}: {primary_diffs} primary hits differ from the CPU twin"
    );

    let (differing, total, _) =
        assert_masks_match_oracle(label, moved, &rebuilt, view, gbuffer, &frame.masks, w, h);
    eprintln!(
        "{label}: {primary_diffs} primary hits and {differing} of {total} shadow rays differ \
         from the oracle on a rebuilt BVH"
    );
    frame.masks
}

fn instance_named(scene: &Scene, name: &str) -> u32 {
    scene
        .instances
        .iter()
        .position(|i| i.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no instance '{name}'")) as u32
}

#[test]
fn frames_after_moving_an_object_match_the_oracle_on_a_rebuilt_bvh() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let renderer = Renderer::new(ctx(), None).unwrap();
    let sphere = instance_named(&scene, "sphere");
    let start = scene.instances[sphere as usize].world_from_object;
    // Into the shadow of the box and rotated: the sphere's shadow and the ground's change.
    let step =
        Mat4::from_rotation_translation(Quat::from_rotation_y(0.7), Vec3::new(-1.2, 0.3, -0.6)) * start;
    // Across the scene and lifted: the boxes above the sphere's leaves span the scene.
    let far = Mat4::from_translation(Vec3::new(4.0, 2.5, -5.0)) * start;

    // Refit only: an infinite rebuild ratio.
    let refit_only = MotionSettings {
        rebuild_ratio: f64::INFINITY,
        ..Default::default()
    };
    let mut gpu = GpuScene::with_motion(ctx(), &scene, &bvh, refit_only).unwrap();
    let before = check_frame("not moved", &renderer, &gpu, &scene, &view);
    let update = gpu.set_transform(&ctx().queue, sphere, step).unwrap();
    eprintln!("step: {update:?}");
    assert!(!update.rebuilt && update.triangles_moved > 0);
    let after = check_frame("refitted", &renderer, &gpu, &moved_scene(&scene, &gpu), &view);
    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    assert!(changed > 100, "moving the sphere changed only {changed} masks");
    let update = gpu.set_transform(&ctx().queue, sphere, far).unwrap();
    eprintln!("far, refit only: {update:?}");
    assert!(
        !update.rebuilt && update.sah_ratio > 1.0,
        "a far move degrades the tree"
    );
    check_frame("refitted far", &renderer, &gpu, &moved_scene(&scene, &gpu), &view);

    // A rebuild ratio of 0 rebuilds on every update: the whole tree is uploaded.
    let always = MotionSettings {
        rebuild_ratio: 0.0,
        ..Default::default()
    };
    let mut gpu = GpuScene::with_motion(ctx(), &scene, &bvh, always).unwrap();
    gpu.set_transform(&ctx().queue, sphere, step).unwrap();
    let update = gpu.set_transform(&ctx().queue, sphere, far).unwrap();
    eprintln!("far, rebuilt: {update:?}");
    assert!(update.rebuilt && update.sah_ratio == 1.0);
    let bvh_now = gpu.cpu_bvh().unwrap();
    assert_eq!(
        update.bytes_uploaded as usize,
        bvh_now.nodes.len() * 32 + bvh_now.triangles.len() * (48 + 80)
    );
    check_frame("rebuilt", &renderer, &gpu, &moved_scene(&scene, &gpu), &view);

    // Back to the start: the oracle of the unmoved scene again.
    gpu.set_transform(&ctx().queue, sphere, start).unwrap();
    let back = check_frame("moved back", &renderer, &gpu, &moved_scene(&scene, &gpu), &view);
    let changed = before.iter().zip(&back).filter(|(a, b)| a != b).count();
    assert!(
        changed * 1000 <= before.len(),
        "moved back, yet {changed} masks differ"
    );
}

#[test]
fn bad_moves_are_refused_and_change_nothing() {
    let (scene, _) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let queue = &ctx().queue;
    let mut fixed = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let e = fixed.set_transform(queue, 0, Mat4::IDENTITY).unwrap_err();
    assert!(e.to_string().contains("GpuScene::with_motion"), "{e}");

    let mut gpu = GpuScene::with_motion(ctx(), &scene, &bvh, MotionSettings::default()).unwrap();
    let n = scene.instances.len() as u32;
    let corners = gpu.world_corners().unwrap().to_vec();
    let mut projective = Mat4::IDENTITY;
    projective.x_axis.w = 0.5;
    for (instance, m, expected) in [
        (n, Mat4::IDENTITY, "does not exist"),
        (
            0,
            Mat4::from_translation(Vec3::NAN),
            "not a finite affine transform",
        ),
        (0, projective, "not a finite affine transform"),
    ] {
        match gpu.set_transform(queue, instance, m) {
            Err(e @ Error::InvalidInput { .. }) => assert!(e.to_string().contains(expected), "{e}"),
            other => panic!("expected InvalidInput '{expected}', got {other:?}"),
        }
    }
    assert_eq!(gpu.world_corners().unwrap(), corners.as_slice());
}

/// The benchmark that `examples/animate.rs` prints: every frame moves the instance's
/// triangles, and the circle ends where it started.
#[test]
fn the_animation_benchmark_moves_the_default_instance_every_frame() {
    let (scene, _) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let instance = penumbra::gpu::animate::default_moving_instance(&scene).unwrap();
    assert_eq!(
        instance,
        instance_named(&scene, "sphere"),
        "the largest object, not the ground"
    );
    let report =
        penumbra::gpu::animate::animate_instance(ctx(), &scene, &bvh, instance, 8, MotionSettings::default())
            .unwrap();
    eprintln!("{}", report.summary());
    assert_eq!(report.frames.len(), 8);
    assert!(report.instance_triangles > 0);
    for f in &report.frames {
        assert_eq!(f.update.triangles_moved, report.instance_triangles);
        assert!(f.update.bytes_uploaded > 0);
    }
}
