//! The plugin on the fence example's scene, headless on lavapipe (or any adapter): the
//! visibility it traces is penumbra's (masks against the per-ray oracle on the plugin's
//! own G-buffer), a moved caster moves its shadow, and a `NotShadowCaster` casts none.

#[allow(dead_code)]
#[path = "../examples/fence.rs"]
mod fence;

use bevy::prelude::*;
use bevy::render::RenderApp;
use penumbra::contract::layout::GBufferTexel;
use penumbra::gpu::{read_buffer, read_texture};
use penumbra::reference::shadow_per_ray::{per_ray_masks, shadow_params};
use penumbra_bevy::render::{ExtractedShadowWorld, PenumbraGpu, ViewShadowTargets};

/// One view's first light, read back after a frame.
struct Traced {
    width: u32,
    gbuffer: Vec<GBufferTexel>,
    masks: Vec<u32>,
    filtered: Vec<f32>,
    /// World position of each pixel's shadow-ray origin.
    points: Vec<Vec3>,
}

/// Runs `frames` frames and reads the camera's first light back.
fn traced(app: &mut App, frames: u32) -> Traced {
    for _ in 0..frames {
        app.update();
    }
    let world = app.sub_app_mut(RenderApp).world_mut();
    let mut views = world.query::<&ViewShadowTargets>();
    let targets = &views.single(world).expect("one view with shadow targets").0[0];
    let gpu = world.resource::<PenumbraGpu>();
    let (_, scene) = gpu.scene.as_ref().expect("the casters are on the GPU");
    let pixels = u64::from(targets.width() * targets.height());
    let gbuffer: Vec<GBufferTexel> = read_buffer(&gpu.ctx, &targets.pixels.gbuffer, 0..pixels * 64).unwrap();
    let origin = Vec3::from_array(scene.origin.to_array());
    Traced {
        width: targets.width(),
        masks: read_buffer(&gpu.ctx, &targets.pixels.masks, 0..pixels * 4).unwrap(),
        filtered: read_texture(&gpu.ctx, &targets.filtered).unwrap(),
        points: gbuffer
            .iter()
            .map(|t| Vec3::from_array(t.origin.to_array()) + origin)
            .collect(),
        gbuffer,
    }
}

/// The plugin's masks against penumbra's per-ray oracle on the plugin's own G-buffer (made
/// from Bevy's depth and normal prepass): at most 0.1 % of the rays may differ, the
/// acceptance rule of penumbra's own embedded-pass tests (rays that graze a triangle edge
/// within float rounding).
#[test]
fn the_plugin_traces_what_the_per_ray_oracle_sees_from_bevys_prepass() {
    let mut app = fence::app(false);
    let t = traced(&mut app, 3);
    // The rect light is penumbra's alone: Bevy's own (unshadowed) shading of it is off.
    let render_world = app.sub_app_mut(RenderApp).world_mut();
    let bevy_lit = render_world
        .query::<&bevy::pbr::ExtractedRectLight>()
        .iter(render_world)
        .count();
    assert_eq!(bevy_lit, 0, "Bevy still shades {bevy_lit} rect lights itself");
    let world = app.sub_app(RenderApp).world();
    let gpu = world.resource::<PenumbraGpu>();
    let light = world.resource::<ExtractedShadowWorld>().lights[0];
    let (_, scene) = gpu.scene.as_ref().unwrap();
    let bvh = scene
        .cpu_bvh()
        .expect("the plugin's scene keeps its BVH (with_motion)");
    let height = t.gbuffer.len() as u32 / t.width;
    let points = penumbra::sampling::light_points(&light);
    let mut gbuffer = t.gbuffer.clone();
    for (g, p) in gbuffer.iter_mut().zip(&t.points) {
        g.origin = glam::Vec3::from_array(p.to_array());
    }
    let oracle = per_ray_masks(bvh, &gbuffer, &points, &shadow_params(&light, t.width, height));
    let hits = t.gbuffer.iter().filter(|g| g.is_hit()).count();
    let rays = hits * 16;
    let differing: u32 = oracle
        .iter()
        .zip(&t.masks)
        .map(|(a, b)| ((a ^ b) & 0xffff).count_ones())
        .sum();
    let shadowed = t.masks.iter().filter(|&&m| m & 0xffff != 0).count();
    eprintln!(
        "{hits} pixels see geometry, {shadowed} have a blocked ray; {differing} of {rays} rays differ from the oracle"
    );
    assert!(
        hits * 2 > t.gbuffer.len(),
        "the camera sees little geometry: {hits} pixels"
    );
    assert!(
        shadowed * 20 > hits,
        "hardly any shadow: {shadowed} of {hits} pixels"
    );
    assert!(
        differing as usize * 1000 <= rays,
        "{differing} of {rays} rays differ from the per-ray oracle"
    );

    // penumbra's own renderer, same scene, camera (Bevy's default 45° vertical field of
    // view), light and rays: where both see the same surface point with the same normal,
    // the masks are the same (the embedded pass's rule: 0.1 % of the rays).
    let mut camera = app.world_mut().query_filtered::<&Transform, With<Camera3d>>();
    let eye_transform = *camera.single(app.world()).unwrap();
    let v = |p: Vec3| glam::Vec3::from_array(p.to_array());
    let view = penumbra::scene::view::View {
        camera: penumbra::scene::view::Camera {
            eye: v(eye_transform.translation),
            target: v(eye_transform.translation + eye_transform.forward().as_vec3()),
            up: glam::Vec3::Y,
            fov_y_degrees: 45.0,
        },
        light,
        ground_y: None,
    };
    let world = app.sub_app(RenderApp).world();
    let gpu = world.resource::<PenumbraGpu>();
    let (_, gpu_scene) = gpu.scene.as_ref().unwrap();
    let renderer = penumbra::gpu::Renderer::new(&gpu.ctx, None).unwrap();
    let mut settings = penumbra::gpu::FrameSettings::new(t.width, height);
    settings.keep_gbuffer = true;
    let frame = renderer.render(&gpu.ctx, gpu_scene, &view, &settings).unwrap();
    let standalone = frame.gbuffer.as_ref().unwrap();
    let (mut same, mut hit_differs, mut rays_differ) = (0usize, 0usize, 0u32);
    let mut ground_normal = 1.0f32;
    for (p, (b, s)) in t.gbuffer.iter().zip(standalone).enumerate() {
        if b.is_hit() != s.is_hit() {
            hit_differs += 1;
        } else if b.is_hit() && (b.origin - s.origin).length() < 1e-3 && b.normal.dot(s.normal) > 0.999 {
            same += 1;
            rays_differ += ((t.masks[p] ^ frame.masks[p]) & 0xffff).count_ones();
        }
        if b.is_hit() && s.is_hit() && (b.origin - s.origin).length() < 1e-3 && s.normal.y > 0.999 {
            ground_normal = ground_normal.min(b.normal.dot(s.normal));
        }
    }
    eprintln!(
        "against penumbra's renderer: {hit_differs} pixels differ in seeing geometry; {same} see the same \
         point and normal, where {rays_differ} of {} rays differ; on the ground the decoded normals are within \
         {:.2e} of +y (cos)",
        same * 16,
        1.0 - ground_normal
    );
    assert!(
        hit_differs * 100 < t.gbuffer.len(),
        "{hit_differs} pixels differ in seeing geometry"
    );
    assert!(
        same * 2 > hits,
        "only {same} of {hits} pixels see the same point and normal"
    );
    assert!(
        rays_differ as usize * 1000 <= same * 16,
        "{rays_differ} rays differ from penumbra's renderer"
    );
    // Bevy's 10-bit normals: +y's zero components are stored as 511 or 512 of 1023, so
    // each decodes up to e = 1/1023 off; two such give 1 − cos ≈ e² = 9.6e-7.
    assert!(
        1.0 - ground_normal < 1.2e-6,
        "ground normals decode {ground_normal} off +y"
    );
}

/// Pixels that see the same ground point in both frames, within `radius` of `centre`
/// (x, z), whose filtered visibility rose, and those whose visibility fell, by more than a
/// half from `before` to `after`; and the largest change of any such pixel farther than
/// `radius` from every centre in `all`.
fn changes(before: &Traced, after: &Traced, centre: Vec2, radius: f32, all: &[Vec2]) -> (usize, usize, f32) {
    let (mut rose, mut fell, mut elsewhere) = (0, 0, 0.0f32);
    for (i, p) in after.points.iter().enumerate() {
        let same_ground = p.y.abs() < 0.01 && p.distance(before.points[i]) < 1e-3;
        if !same_ground {
            continue;
        }
        let (a, b) = (after.filtered[i], before.filtered[i]);
        let ground = Vec2::new(p.x, p.z);
        if ground.distance(centre) < radius {
            rose += usize::from(a - b > 0.5);
            fell += usize::from(b - a > 0.5);
        } else if all.iter().all(|c| ground.distance(*c) >= radius) {
            elsewhere = elsewhere.max((a - b).abs());
        }
    }
    (rose, fell, elsewhere)
}

/// Moving the box (a refit of the plugin's BVH) moves its shadow and changes nothing else;
/// the sphere marked `NotShadowCaster` casts a shadow once the marker is removed (a
/// rebuild), none before.
#[test]
fn a_moved_caster_moves_its_shadow_and_a_not_shadow_caster_casts_none() {
    let mut app = fence::app(false);
    let before = traced(&mut app, 3);
    let world = app.world_mut();
    let mut mover = world.query_filtered::<&mut Transform, With<fence::Mover>>();
    mover.single_mut(world).unwrap().translation.x = 1.9;
    let moved = traced(&mut app, 2);
    let (old, new) = (Vec2::new(1.0, -0.7), Vec2::new(1.9, -0.7));
    let (rose_old, fell_old, far) = changes(&before, &moved, old, 1.5, &[old, new]);
    let (rose_new, fell_new, _) = changes(&before, &moved, new, 1.5, &[old, new]);
    eprintln!(
        "box moved: near its old place {rose_old} ground pixels lit up ({fell_old} darkened), near the \
         new {fell_new} darkened ({rose_new} lit up); elsewhere visibility changed by at most {far}"
    );
    // Counts, not fractions: from this camera the box hides most of its old shadow (34
    // pixels of it are seen at 480×320). The scene is traced with the same rays in both
    // frames, so nothing but the move flips a pixel (`far` checks that); 10 pixels are
    // more than a stray one.
    assert!(rose_old >= 10, "the old shadow stayed: {rose_old} pixels lit up");
    assert!(
        fell_new >= 10,
        "no shadow at the new place: {fell_new} pixels darkened"
    );
    assert!(far < 1e-6, "ground far from the box changed visibility by {far}");

    // The NotShadowCaster sphere (x 0.1, z −1.6) and where its shadow falls, z −2.1.
    let sphere = Vec2::new(0.1, -1.9);
    let world = app.world_mut();
    let mut ignored = world.query_filtered::<Entity, With<bevy::light::NotShadowCaster>>();
    let entity = ignored.single(world).unwrap();
    world.entity_mut(entity).remove::<bevy::light::NotShadowCaster>();
    let casting = traced(&mut app, 2);
    let (rose, fell, _) = changes(&moved, &casting, sphere, 0.6, &[sphere]);
    eprintln!("the sphere made a caster: {fell} ground pixels darkened, {rose} lit up");
    assert!(
        fell >= 10,
        "the sphere casts no shadow once it is a caster: {fell} pixels darkened"
    );
}
