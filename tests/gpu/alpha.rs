//! Alpha-masked shadows: the built-in `screen` (one quad over the ground whose holes are
//! an alpha-masked texture, `alphaMode: MASK`) lets light through its holes and nowhere
//! else, for every tracer (the driver's ray queries too, where the adapter has them), and
//! not at all when its mask is ignored. (Its masks over a
//! whole view against the per-ray oracle and Embree are checked with the other built-in
//! scenes: shadow_mft, shadow_tracers, peers.)

use crate::support;

use glam::{Vec2, Vec3};
use penumbra::assets::generate::{SCREEN_HEIGHT, SCREEN_SIZE, SCREEN_TEXELS, screen_texel_is_hole};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::{GBufferTexel, MASK_FULL};
use penumbra::gpu::{GpuContext, GpuScene, ShadowTracer, Tracer, TracerOptions};
use penumbra::reference::shadow_per_ray::{per_ray_masks, shadow_params};
use penumbra::sampling;
use penumbra::scene::view::View;
use support::gpu::{ctx, embedded, every_tracer, ray_query_ctx, shadow_tracer, try_trace_masks_on};

/// The world point of the screen at texture coordinate `uv` (u along +x, v along +z).
fn screen_point(uv: Vec2) -> Vec3 {
    let h = 0.5 * SCREEN_SIZE;
    Vec3::new(-h + uv.x * SCREEN_SIZE, SCREEN_HEIGHT, -h + uv.y * SCREEN_SIZE)
}

/// A ground texel (y = 0, facing up) on the line from the light's centre through `p`.
fn ground_texel_behind(view: &View, p: Vec3) -> GBufferTexel {
    let c = view.light.center();
    let ground = c + (p - c) * (c.y / (c.y - p.y));
    GBufferTexel {
        origin: Vec3::new(ground.x, 1e-3, ground.z),
        depth: 1.0,
        normal: Vec3::Y,
        geo_normal: Vec3::Y,
        triangle: GBufferTexel::UNKNOWN_TRIANGLE,
        ..GBufferTexel::default()
    }
}

/// Sixteen ground points, one behind the centre of each of the screen's 4 × 4 holes seen
/// from the light's centre; and sixteen behind the nine inner corners where four holes meet
/// (repeated to fill a 4 × 4 tile). The light is 0.6 m wide 3 m over the screen, the ground
/// 1 m under it: the rays of a point cross the screen within 0.6/2 · 1/4 · √2 = 0.106 m of
/// the line through the light's centre. A hole holds every point within 2.6 − √2/2 texels
/// (0.177 m) of its centre, so every ray of the first tile passes; an inner corner is 4√2
/// texels (0.53 m) from the nearest hole centre, farther than 2.6 + √2/2 texels (0.31 m)
/// plus 0.106 m, so every ray of the second is blocked.
fn hole_and_corner_tiles(view: &View) -> (Vec<GBufferTexel>, Vec<GBufferTexel>) {
    let texel = 1.0 / SCREEN_TEXELS as f32;
    let holes: Vec<GBufferTexel> = (0..16)
        .map(|k| {
            let (i, j) = (k % 4, k / 4);
            let uv = Vec2::new((4 + 8 * i) as f32, (4 + 8 * j) as f32) * texel;
            assert!(screen_texel_is_hole(4 + 8 * i, 4 + 8 * j));
            ground_texel_behind(view, screen_point(uv))
        })
        .collect();
    let corners = (0..16)
        .map(|k| {
            let (i, j) = (1 + k % 3, 1 + (k / 3) % 3);
            let uv = Vec2::new((8 * i) as f32, (8 * j) as f32) * texel;
            ground_texel_behind(view, screen_point(uv))
        })
        .collect();
    (holes, corners)
}

#[test]
fn light_passes_the_screens_holes_and_only_them_for_every_tracer() {
    let (scene, view) = embedded("screen");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    assert_eq!(
        bvh.alpha.triangles, 2,
        "the screen's two triangles are alpha-tested"
    );
    let opaque = bvh.without_alpha();
    let masked_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let opaque_scene = GpuScene::new(ctx(), &scene, &opaque).unwrap();
    let (holes, corners) = hole_and_corner_tiles(&view);
    let params = shadow_params(&view.light, 4, 4);
    let points = sampling::light_points(&view.light);
    // The CPU oracle first: the tiles say what the comment above says.
    assert_eq!(per_ray_masks(&bvh, &holes, &points, &params), vec![0; 16]);
    assert_eq!(
        per_ray_masks(&bvh, &corners, &points, &params),
        vec![MASK_FULL; 16]
    );
    assert_eq!(
        per_ray_masks(&opaque, &holes, &points, &params),
        vec![MASK_FULL; 16]
    );
    let check = |label: &str, ctx: &GpuContext, pass: &ShadowTracer, masked: &GpuScene, opaque: &GpuScene| {
        let trace = |scene: &GpuScene, texels: &[GBufferTexel]| {
            try_trace_masks_on(ctx, pass, scene, texels, &view, &params)
                .unwrap_or_else(|e| panic!("{label}: {e}"))
                .0
        };
        assert_eq!(
            trace(masked, &holes),
            vec![0; 16],
            "{label}: under the holes, every ray passes"
        );
        assert_eq!(
            trace(masked, &corners),
            vec![MASK_FULL; 16],
            "{label}: under the screen, every ray is blocked"
        );
        assert_eq!(
            trace(opaque, &holes),
            vec![MASK_FULL; 16],
            "{label}: with the mask ignored, the holes block"
        );
    };
    for (tracer, leaf_mode, variant) in every_tracer() {
        let pass = shadow_tracer(tracer, leaf_mode, variant);
        check(
            &format!("{tracer} {leaf_mode} {variant}"),
            ctx(),
            &pass,
            &masked_scene,
            &opaque_scene,
        );
    }
    // The driver's ray queries, where the adapter has them (Mesa 25 lavapipe).
    match ray_query_ctx() {
        Ok(rq) => {
            let options = TracerOptions {
                tracer: Tracer::RayQuery,
                ..TracerOptions::default()
            };
            let pass = ShadowTracer::new(rq, &options).unwrap();
            let masked = GpuScene::new(rq, &scene, &bvh).unwrap();
            let opaque = GpuScene::new(rq, &scene, &opaque).unwrap();
            check("ray-query", rq, &pass, &masked, &opaque);
        }
        Err(e) => eprintln!("ray-query not checked: {e}"),
    }
}
