//! Scenes far from the origin: traced as their stored geometry would be at the origin,
//! and re-centred scenes keep their shadows.

use crate::support;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{FrameSettings, GpuScene, Renderer, RendererOptions, Tracer};
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use support::gpu::{ctx, embedded};
use support::scaled_and_moved;

/// Unfiltered visibility of `scene` seen through `view` with `tracer`, 256×256, its GPU
/// buffers relative to `origin` (`None`: the one [`GpuScene::new`] picks).
fn visibility_image(scene: &Scene, view: &View, tracer: Tracer, origin: Option<Vec3>) -> Vec<f32> {
    let bvh = Bvh::build(scene, &BvhSettings::default()).unwrap();
    let gpu_scene = match origin {
        None => GpuScene::new(ctx(), scene, &bvh).unwrap(),
        Some(o) => GpuScene::with_origin(ctx(), scene, &bvh, o).unwrap(),
    };
    let options = RendererOptions {
        tracer,
        ..RendererOptions::default()
    };
    let mut settings = FrameSettings::new(256, 256);
    settings.filter = None;
    let frame = Renderer::new(ctx(), options)
        .unwrap()
        .render(ctx(), &gpu_scene, view, &settings)
        .unwrap();
    frame
        .masks
        .iter()
        .map(|&m| penumbra::reference::visibility::visibility(m))
        .collect()
}

/// Pixels of `a` and `b` whose visibility differs by more than 1/16, and pixels lit in
/// `a` (all 16 rays) that are more than half dark in `b`.
fn differences(a: &[f32], b: &[f32]) -> (usize, usize) {
    let off = a
        .iter()
        .zip(b)
        .filter(|(x, y)| (*x - *y).abs() > 1.0 / 16.0)
        .count();
    let darkened = a.iter().zip(b).filter(|(x, y)| **x == 1.0 && **y < 0.5).count();
    (off, darkened)
}

/// Traced where it lies, without moving it to the origin (`GpuScene::with_origin` zero,
/// as a host's far world positions are), a far scene still shows no self-shadowing: the
/// playground made ten times larger (120 m) and moved by 1e5 and 1e6 along x and z (its
/// view alike) renders, for every tracer, like the same stored (rounded) geometry moved
/// back to the origin: at most 0.1 % of the pixels lit there are more than half dark out
/// there. A fixed ray offset (10⁻⁴ of the diagonal, 17 mm) is below a few f32 steps at
/// 1e6 (6.25 cm each), so rays started inside their own surface and 0.7 % of the pixels
/// darkened; origins now clear the surface by 4 f32 steps of the point
/// (pass_inputs::shadow_ray_origin), above the rounding of a hit point (at most ~2.6 steps).
#[test]
fn far_scenes_trace_as_their_stored_geometry_does_at_the_origin() {
    let (base_scene, base_view) = embedded("playground");
    let mut failures = Vec::new();
    for tracer in [Tracer::Mft, Tracer::Packet, Tracer::PerRay] {
        for offset in [1e5f32, 1e6] {
            let t = Vec3::new(offset, 0.0, offset);
            let (far_scene, far_view) = scaled_and_moved(&base_scene, &base_view, 10.0, t);
            let mut stored = far_scene.clone();
            stored.translate(-t);
            let at_origin = visibility_image(&stored, &far_view.translated(-t), tracer, None);
            let far = visibility_image(&far_scene, &far_view, tracer, Some(Vec3::ZERO));
            let (off, darkened) = differences(&at_origin, &far);
            eprintln!(
                "{tracer} at {offset:e}: {off} of {} pixels differ by more than 1/16, {darkened} lit pixels darkened",
                far.len()
            );
            if darkened * 1000 > far.len() {
                failures.push(format!("{tracer} at {offset:e}: {darkened} lit pixels darkened"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "self-shadowing far from the origin: {failures:?}"
    );
}

/// Far scenes keep their shadows as at the origin, whether the renderer moves them there
/// itself (`GpuScene::new` works relative to a far scene's centre) or the caller did
/// before building the BVH (`Scene::recentre`, as the CLI does): the playground made 30
/// times larger (360 m, so that f32 stores it at 1e6 to 1/10,000 of its size) and moved
/// by 1e5 and 1e6 renders for every tracer a visibility where at most 0.1 % of the
/// pixels differ by more than 1/16 from the scene built at the origin.
#[test]
fn re_centred_far_scenes_keep_their_shadows() {
    let (base_scene, base_view) = embedded("playground");
    let mut failures = Vec::new();
    for tracer in [Tracer::Mft, Tracer::Packet, Tracer::PerRay] {
        let (scene, view) = scaled_and_moved(&base_scene, &base_view, 30.0, Vec3::ZERO);
        let near = visibility_image(&scene, &view, tracer, None);
        for offset in [1e5f32, 1e6] {
            let t = Vec3::new(offset, 0.0, offset);
            let (far_scene, far_view) = scaled_and_moved(&base_scene, &base_view, 30.0, t);
            let mut moved = far_scene.clone();
            let shift = moved.recentre();
            assert_ne!(shift, Vec3::ZERO, "a scene at {offset:e} is re-centred");
            for (how, far) in [
                (
                    "by the renderer",
                    visibility_image(&far_scene, &far_view, tracer, None),
                ),
                (
                    "by the caller",
                    visibility_image(&moved, &far_view.translated(-shift), tracer, None),
                ),
            ] {
                let (off, _) = differences(&near, &far);
                eprintln!(
                    "{tracer} at {offset:e}, re-centred {how}: {off} of {} pixels differ by more than 1/16",
                    far.len()
                );
                if off * 1000 > far.len() {
                    failures.push(format!(
                        "{tracer} at {offset:e}, re-centred {how}: {off} pixels off"
                    ));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "shadows change far from the origin: {failures:?}"
    );
    // A scene near the origin is left as it is, bit for bit.
    let mut near = base_scene.clone();
    assert_eq!(near.recentre(), Vec3::ZERO);
    assert_eq!(near.triangles, base_scene.triangles);
}
