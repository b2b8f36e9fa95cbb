//! The embedded shadow pass on a host's rasterized G-buffer (the example's rasterizer):
//! against the standalone renderer for the same view and samples, against the CPU oracles
//! on its own G-buffer, on devices that lack what it needs, and with bad inputs.
//!
//! Run with `--nocapture` to see the figures measured.

use crate::support;

// The example application's G-buffer pass: the test rasterizes exactly as the example does.
#[allow(dead_code)]
#[path = "../../examples/embed/raster.rs"]
mod raster;

use penumbra::Error;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::GBufferTexel;
use penumbra::gpu::{
    FrameSettings, GpuContext, GpuScene, NormalEncoding, Renderer, ShadowInputs, ShadowPass, ShadowSettings,
    ShadowTargets, SurfaceInput, VectorVariant, read_buffer, read_texture,
};
use penumbra::reference::filter::discontinuity_filter;
use penumbra::reference::visibility::visibility;
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use raster::{HostGBuffer, Rasterizer, camera_matrices};
use support::assert_masks_match_oracle;
use support::gpu::{ctx, embedded, variants};

/// What the embedded pass produced, read back.
struct Embedded {
    gbuffer: Vec<GBufferTexel>,
    masks: Vec<u32>,
    unfiltered: Vec<f32>,
    filtered: Vec<f32>,
    unfinished: u64,
}

/// Rasterizes `scene` seen through `view` and records the embedded pass on it, in one
/// encoder as a host would; `positions` picks the world-position input over the depth one.
fn embedded_frame(
    pass: &ShadowPass,
    scene: &Scene,
    gpu_scene: &GpuScene,
    view: &View,
    (w, h): (u32, u32),
    positions: bool,
) -> Embedded {
    let targets = ShadowTargets::new(ctx(), w, h).unwrap();
    embedded_frame_into(pass, scene, gpu_scene, view, &targets, positions)
}

/// [`embedded_frame`] into targets the caller keeps (and may have used for other frames).
fn embedded_frame_into(
    pass: &ShadowPass,
    scene: &Scene,
    gpu_scene: &GpuScene,
    view: &View,
    targets: &ShadowTargets,
    positions: bool,
) -> Embedded {
    embedded_frame_with_normals(pass, scene, gpu_scene, view, targets, positions, None)
}

/// Normal textures handed to the pass instead of the host's: shading, geometric, and how
/// both store normals.
type GivenNormals<'a> = (&'a wgpu::Texture, &'a wgpu::Texture, NormalEncoding);

/// [`embedded_frame_into`] with `normals` in place of the rasterizer's (signed) ones.
fn embedded_frame_with_normals(
    pass: &ShadowPass,
    scene: &Scene,
    gpu_scene: &GpuScene,
    view: &View,
    targets: &ShadowTargets,
    positions: bool,
    normals: Option<GivenNormals<'_>>,
) -> Embedded {
    let ctx = ctx();
    let (w, h) = (targets.width(), targets.height());
    let rasterizer = Rasterizer::new(&ctx.device, scene);
    let host = HostGBuffer::new(&ctx.device, w, h);
    let (view_matrix, projection) = camera_matrices(&view.camera, scene.bounds().diagonal(), w, h);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    rasterizer.record(
        &ctx.device,
        &mut encoder,
        projection * view_matrix,
        &host,
        positions,
    );
    let surface = if positions {
        SurfaceInput::Position {
            texture: &host.position,
            eye: view.camera.eye,
        }
    } else {
        SurfaceInput::Depth {
            texture: &host.depth,
            view: view_matrix,
            projection,
            background_depth: 1.0,
        }
    };
    let (normal, geometric, normal_encoding) =
        normals.unwrap_or((&host.normal, &host.face_normal, NormalEncoding::Signed));
    let inputs = ShadowInputs {
        surface,
        normal,
        geometric_normal: Some(geometric),
        normal_encoding,
        light: &view.light,
    };
    pass.record(&mut encoder, gpu_scene, &inputs, targets).unwrap();
    ctx.queue.submit([encoder.finish()]);
    let pixels = u64::from(w * h);
    Embedded {
        gbuffer: read_buffer(ctx, &targets.pixels.gbuffer, 0..pixels * 64).unwrap(),
        masks: read_buffer(ctx, &targets.pixels.masks, 0..pixels * 4).unwrap(),
        unfiltered: read_texture(ctx, &targets.unfiltered).unwrap(),
        filtered: read_texture(ctx, &targets.filtered).unwrap(),
        unfinished: targets.unfinished_tiles(ctx).unwrap(),
    }
}

/// Whether the rasterized and the ray-traced primary hits of a pixel differ: one sees
/// geometry and the other not, or the surface points lie more than `tol` apart, or the
/// geometric normals differ by more than ~2.5°.
fn primary_differs(a: &GBufferTexel, b: &GBufferTexel, tol: f32) -> bool {
    a.is_hit() != b.is_hit()
        || (a.is_hit() && ((a.origin - b.origin).length() > tol || a.geo_normal.dot(b.geo_normal) < 0.999))
}

/// The embedded pass's own outputs are consistent: masks match the per-ray oracle on its
/// G-buffer, the unfiltered texture is the masks' visibility, the filtered one the CPU
/// filter of it.
fn check_against_oracles(
    label: &str,
    scene: &Scene,
    bvh: &Bvh,
    view: &View,
    e: &Embedded,
    (w, h): (u32, u32),
) {
    let (differing, total, _) =
        assert_masks_match_oracle(label, scene, bvh, view, &e.gbuffer, &e.masks, w, h);
    eprintln!("{label}: {differing} of {total} rays differ from the per-ray oracle");
    let vis: Vec<f32> = e.masks.iter().map(|&m| visibility(m)).collect();
    assert_eq!(
        e.unfiltered, vis,
        "{label}: unfiltered texture is not the masks' visibility"
    );
    let values: Vec<[f32; 4]> = vis.iter().map(|&v| [0.0, 0.0, 0.0, v]).collect();
    let depth: Vec<f32> = e.gbuffer.iter().map(|t| t.depth).collect();
    let normal: Vec<[f32; 3]> = e.gbuffer.iter().map(|t| t.normal.to_array()).collect();
    let cpu = discontinuity_filter(&FilterParams::new(w, h), &values, &depth, &normal);
    let worst = cpu
        .iter()
        .zip(&e.filtered)
        .map(|(c, g)| (c[3] - g).abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst <= 1e-6,
        "{label}: filtered texture differs from the CPU filter by {worst}"
    );
}

#[test]
fn embedded_pass_matches_the_standalone_renderer_except_where_primary_hits_differ() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let size @ (w, h) = (128, 96);
    let diagonal = scene.bounds().diagonal();
    for variant in variants() {
        let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let frame = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
        let traced = frame.gbuffer.as_ref().unwrap();
        let pass = ShadowPass::new(
            ctx(),
            ShadowSettings {
                variant: Some(variant),
                ..Default::default()
            },
        )
        .unwrap();
        for positions in [false, true] {
            let label = format!(
                "{variant}, {} input",
                if positions { "position" } else { "depth" }
            );
            let e = embedded_frame(&pass, &scene, &gpu_scene, &view, size, positions);
            assert_eq!(e.unfinished, 0, "{label}: tiles left unfinished");
            check_against_oracles(&label, &scene, &bvh, &view, &e, size);

            let differs: Vec<bool> = (0..traced.len())
                .map(|p| primary_differs(&e.gbuffer[p], &traced[p], 1e-4 * diagonal))
                .collect();
            let n_differs = differs.iter().filter(|&&d| d).count();
            let (mut mask_pixels, mut mask_rays, mut vis_pixels) = (0, 0, 0);
            let mut max_offset = 0.0f32;
            for p in 0..traced.len() {
                if differs[p] {
                    continue;
                }
                if traced[p].is_hit() {
                    max_offset = max_offset.max((e.gbuffer[p].origin - traced[p].origin).length());
                }
                let diff = (e.masks[p] ^ frame.masks[p]).count_ones();
                mask_pixels += usize::from(diff > 0);
                mask_rays += diff as usize;
                // The filter mixes a 5×5 window: compare where the whole window agrees in
                // primary hit and mask, so that the only difference left is rounding.
                let (x, y) = (p as i64 % i64::from(w), p as i64 / i64::from(w));
                let window_agrees = (-2..=2).all(|dy| {
                    (-2..=2).all(|dx| {
                        let (nx, ny) = (x + dx, y + dy);
                        let q = (ny * i64::from(w) + nx) as usize;
                        nx < 0
                            || ny < 0
                            || nx >= i64::from(w)
                            || ny >= i64::from(h)
                            || (!differs[q] && e.masks[q] == frame.masks[q])
                    })
                });
                if window_agrees && (e.filtered[p] - frame.filtered[p][3]).abs() > 1e-5 {
                    vis_pixels += 1;
                }
            }
            let pixels = (w * h) as usize;
            eprintln!(
                "{label}: primary hits differ at {n_differs} of {pixels} pixels; elsewhere \
                 (origins within {max_offset:.2e} of the traced ones) {mask_pixels} pixels / \
                 {mask_rays} rays have other masks, {vis_pixels} pixels other filtered visibility"
            );
            assert!(
                n_differs * 100 < pixels,
                "{label}: {n_differs} pixels differ in primary hit"
            );
            assert!(
                mask_rays * 1000 <= pixels * 16,
                "{label}: {mask_rays} rays differ where the primary hits agree"
            );
            assert!(
                vis_pixels * 1000 <= pixels,
                "{label}: {vis_pixels} pixels differ in filtered visibility where the primary hits agree"
            );
        }
    }
}

/// A device created without what the pass needs (WebGPU's downlevel limits: 4 storage
/// buffers per stage; no SUBGROUP feature) gets `Error::DeviceUnsupported` naming each
/// missing thing, not a panic.
#[test]
fn a_device_without_the_required_limits_or_features_gets_the_documented_error() {
    let adapter = ctx().adapter.as_ref().expect("the test context owns its adapter");
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("too small"),
        required_features: wgpu::Features::empty(),
        required_limits: wgpu::Limits::downlevel_defaults(),
        ..Default::default()
    }))
    .unwrap();
    let small = GpuContext::from_device(&device, &queue);
    match ShadowPass::new(&small, ShadowSettings::default()) {
        Err(Error::DeviceUnsupported { missing, .. }) => {
            eprintln!(
                "downlevel device: {}",
                Error::DeviceUnsupported {
                    what: "the embedded shadow pass".into(),
                    missing: missing.clone()
                }
            );
            assert!(
                missing
                    .iter()
                    .any(|m| m.starts_with("max_storage_buffers_per_shader_stage 4 (needs 8)")),
                "{missing:?}"
            );
        }
        other => panic!("expected DeviceUnsupported, got {other:?}"),
    }

    // Enough limits but no subgroups, with the subgroup vector forced.
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("no subgroups"),
        required_features: ShadowPass::required_features(),
        required_limits: ShadowPass::required_limits(),
        ..Default::default()
    }))
    .unwrap();
    let plain = GpuContext::from_device(&device, &queue);
    for variant in [VectorVariant::Subgroup, VectorVariant::SubgroupReduce] {
        let forced = ShadowSettings {
            variant: Some(variant),
            ..Default::default()
        };
        match ShadowPass::new(&plain, forced) {
            Err(Error::DeviceUnsupported { missing, .. }) => {
                assert_eq!(missing, ["feature SUBGROUP"], "{variant}");
            }
            other => panic!("{variant}: expected DeviceUnsupported, got {other:?}"),
        }
    }
    // The same device runs the pass with the default settings: the requirements are enough.
    let pass = ShadowPass::new(&plain, ShadowSettings::default()).unwrap();
    assert_eq!(pass.variant(), VectorVariant::Workgroup);
}

/// Textures that do not fit are refused with `Error::InvalidInput` before anything is recorded.
#[test]
fn bad_input_textures_are_refused_with_a_clear_error() {
    let ctx = ctx();
    let (scene, view) = embedded("playground");
    let gpu_scene =
        GpuScene::new(ctx, &scene, &Bvh::build(&scene, &BvhSettings::default()).unwrap()).unwrap();
    let pass = ShadowPass::new(ctx, ShadowSettings::default()).unwrap();
    let targets = ShadowTargets::new(ctx, 32, 24).unwrap();
    let host = HostGBuffer::new(&ctx.device, 32, 24);
    let texture = |w, format, usage| {
        ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: None,
            size: wgpu::Extent3d {
                width: w,
                height: 24,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let bind = wgpu::TextureUsages::TEXTURE_BINDING;
    let cases = [
        (
            texture(16, wgpu::TextureFormat::Rgba16Float, bind),
            "is 16x24, the targets are 32x24",
        ),
        (
            texture(32, wgpu::TextureFormat::Rgba8Uint, bind),
            "cannot be read as floats",
        ),
        (
            texture(
                32,
                wgpu::TextureFormat::Rgba16Float,
                wgpu::TextureUsages::COPY_DST,
            ),
            "needs TextureUsages::TEXTURE_BINDING",
        ),
    ];
    for (normal, expected) in &cases {
        let inputs = ShadowInputs {
            surface: SurfaceInput::Position {
                texture: &host.position,
                eye: view.camera.eye,
            },
            normal,
            geometric_normal: None,
            normal_encoding: NormalEncoding::Signed,
            light: &view.light,
        };
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        match pass.record(&mut encoder, &gpu_scene, &inputs, &targets) {
            Err(e @ Error::InvalidInput { .. }) => {
                let text = e.to_string();
                assert!(
                    text.starts_with("ShadowInputs::normal: ") && text.contains(expected),
                    "{text}"
                );
            }
            other => panic!("expected InvalidInput containing '{expected}', got {other:?}"),
        }
    }
    assert!(matches!(
        ShadowTargets::new(ctx, 0, 24),
        Err(Error::InvalidInput { .. })
    ));
}

/// An `Rgb10a2Unorm` texture (Bevy's normal-prepass format) holding `normals` as
/// `n · ½ + ½`, rounded to the nearest of its 1023 steps.
fn biased_normal_texture(normals: &[glam::Vec3], (w, h): (u32, u32)) -> wgpu::Texture {
    let ctx = ctx();
    let texture = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("biased normals"),
        size: wgpu::Extent3d {
            width: w,
            height: h,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgb10a2Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let unorm10 = |c: f32| ((c * 0.5 + 0.5).clamp(0.0, 1.0) * 1023.0).round() as u32;
    let texels: Vec<u32> = normals
        .iter()
        .map(|n| unorm10(n.x) | unorm10(n.y) << 10 | unorm10(n.z) << 20 | 3 << 30)
        .collect();
    ctx.queue.write_texture(
        texture.as_image_copy(),
        bytemuck::cast_slice(&texels),
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(w * 4),
            rows_per_image: None,
        },
        texture.size(),
    );
    texture
}

/// Normals stored biased in a unorm texture (`NormalEncoding::Biased`, as Bevy's prepass
/// writes them) give the G-buffer the signed input gives, up to the texture's rounding,
/// and masks that match the oracle. The biased textures hold the signed run's own unit
/// normals: 10-bit steps of 1/1023 on `n · ½ + ½` move each decoded component by at most
/// 1/1023, a unit vector by at most √3/1023 < 1.7e-3, and normalizing keeps that bound.
#[test]
fn biased_normals_in_a_unorm_texture_decode_to_the_signed_ones() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let size = (64, 48);
    let pass = ShadowPass::new(ctx(), ShadowSettings::default()).unwrap();
    let targets = ShadowTargets::new(ctx(), size.0, size.1).unwrap();
    let signed = embedded_frame_into(&pass, &scene, &gpu_scene, &view, &targets, false);
    let shading: Vec<glam::Vec3> = signed.gbuffer.iter().map(|t| t.normal).collect();
    let geometric: Vec<glam::Vec3> = signed.gbuffer.iter().map(|t| t.geo_normal).collect();
    let (shading, geometric) = (
        biased_normal_texture(&shading, size),
        biased_normal_texture(&geometric, size),
    );
    let given = (&shading, &geometric, NormalEncoding::Biased);
    let biased = embedded_frame_with_normals(&pass, &scene, &gpu_scene, &view, &targets, false, Some(given));
    let mut worst = 0.0f32;
    let mut hits = 0;
    for (s, b) in signed.gbuffer.iter().zip(&biased.gbuffer) {
        assert_eq!(
            s.is_hit(),
            b.is_hit(),
            "the normals changed which pixels see geometry"
        );
        if s.is_hit() {
            hits += 1;
            worst = worst
                .max((s.normal - b.normal).length())
                .max((s.geo_normal - b.geo_normal).length());
        }
    }
    eprintln!("biased normals: {hits} pixels with geometry, normals within {worst:.2e} of the signed ones");
    assert!(hits > 0, "the view sees no geometry");
    assert!(
        worst < 1.7e-3,
        "decoded normals differ from the signed ones by {worst} (rounding allows 1.7e-3)"
    );
    check_against_oracles("biased normals", &scene, &bvh, &view, &biased, size);
}

/// Two passes, two scenes and two sets of targets recorded into one encoder: each frame
/// matches the oracle for its own scene (no shared state between them).
#[test]
fn several_passes_and_scenes_live_side_by_side() {
    let size @ (w, h) = (64, 48);
    let scenes: Vec<_> = ["playground", "lattice"]
        .iter()
        .map(|name| {
            let (scene, view) = embedded(name);
            let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
            let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
            (scene, view, bvh, gpu_scene)
        })
        .collect();
    let unfiltered = ShadowSettings {
        filter: None,
        ..Default::default()
    };
    let passes = [
        ShadowPass::new(ctx(), ShadowSettings::default()).unwrap(),
        ShadowPass::new(ctx(), unfiltered).unwrap(),
    ];
    for (i, (scene, view, bvh, gpu_scene)) in scenes.iter().enumerate() {
        for (j, pass) in passes.iter().enumerate() {
            let e = embedded_frame(pass, scene, gpu_scene, view, size, true);
            let label = format!("scene {i}, pass {j}");
            assert_masks_match_oracle(&label, scene, bvh, view, &e.gbuffer, &e.masks, w, h);
            if pass.settings().filter.is_none() {
                assert_eq!(
                    e.filtered, e.unfiltered,
                    "{label}: no filter, yet the textures differ"
                );
            }
        }
    }
}

/// With a small iteration budget, tiles suspend: no resume rounds leave them unfinished
/// (and `unfinished_tiles` says so), enough rounds give the masks of an uninterrupted run.
#[test]
fn unfinished_tiles_are_reported_and_resume_rounds_finish_them() {
    let (scene, view) = embedded("lattice");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let size = (46, 38);
    let run = |iteration_budget, resume_rounds| {
        let settings = ShadowSettings {
            iteration_budget,
            resume_rounds,
            ..Default::default()
        };
        let pass = ShadowPass::new(ctx(), settings).unwrap();
        embedded_frame(&pass, &scene, &gpu_scene, &view, size, true)
    };
    let full = run(ShadowSettings::default().iteration_budget, 0);
    assert_eq!(
        full.unfinished, 0,
        "the default budget finishes this frame in one round"
    );
    let cut = run(100, 0);
    eprintln!(
        "budget 100, no resume rounds: {} tiles unfinished",
        cut.unfinished
    );
    assert!(cut.unfinished > 0, "a budget of 100 steps suspends some tile");
    assert_ne!(cut.masks, full.masks, "unfinished tiles have incomplete masks");
    let resumed = run(100, 1000);
    assert_eq!(resumed.unfinished, 0);
    assert_eq!(
        resumed.masks, full.masks,
        "resumed tiles give the uninterrupted masks"
    );
}

/// A frame that leaves tiles unfinished leaves their suspended state in the targets'
/// scratch buffers. The next frame recorded into the same targets must start every tile
/// afresh: with resume rounds of its own, it must not resume the old frame's tiles (which
/// would overwrite its finished masks with the old light's partial ones).
#[test]
fn a_frame_after_an_unfinished_one_starts_every_tile_afresh() {
    let (scene, view) = embedded("lattice");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (46, 38);
    let targets = ShadowTargets::new(ctx(), w, h).unwrap();
    let unfinishing = ShadowPass::new(
        ctx(),
        ShadowSettings {
            iteration_budget: 100,
            resume_rounds: 0,
            ..Default::default()
        },
    )
    .unwrap();
    let first = embedded_frame_into(&unfinishing, &scene, &gpu_scene, &view, &targets, true);
    assert!(
        first.unfinished > 0,
        "a budget of 100 steps leaves tiles unfinished"
    );
    // The next frame's light is elsewhere: a tile resumed from the first frame's state
    // would carry that frame's blocked rays into this one.
    let mut moved = view;
    moved.light.corner += view.light.edge_u * 1.5;
    let second = embedded_frame_into(
        &ShadowPass::new(ctx(), ShadowSettings::default()).unwrap(),
        &scene,
        &gpu_scene,
        &moved,
        &targets,
        true,
    );
    eprintln!(
        "first frame: {} tiles unfinished; second frame: {} unfinished",
        first.unfinished, second.unfinished
    );
    assert_eq!(second.unfinished, 0);
    assert_masks_match_oracle(
        "the frame after an unfinished one",
        &scene,
        &bvh,
        &moved,
        &second.gbuffer,
        &second.masks,
        w,
        h,
    );
}

/// The embedded pass on a scene far from the origin: the host's surface points (world
/// coordinates) are moved into the scene's frame (`GpuScene::origin`), the light too, and
/// the ray origins clear the surface by 4 f32 steps of the world point, as the host
/// rounds it: the playground made ten times larger and moved by 1e5 along x and z, given
/// as world positions, darkens at most 0.1 % of the pixels that are lit in the same pass
/// over the same (rounded) geometry at the origin (rays that start behind their surface would darken many; a pass that
/// mixed world and scene coordinates would be wrong everywhere). Given as a depth buffer,
/// the host's own rasterization at 1e5 (its f32 view matrix) is rounded more coarsely; that
/// figure is printed: hosts with far scenes should pass positions, or render relative to
/// the eye.
#[test]
fn the_embedded_pass_on_a_far_scene_sees_the_shadows_it_sees_at_the_origin() {
    let (base, base_view) = embedded("playground");
    let size = (96, 64);
    let pass = ShadowPass::new(ctx(), ShadowSettings::default()).unwrap();
    let t = glam::Vec3::new(1e5, 0.0, 1e5);
    let (far_scene, far_view) = support::scaled_and_moved(&base, &base_view, 10.0, t);
    // The far scene's own (rounded) geometry moved back: what f32 stores out there, at the origin.
    let mut stored = far_scene.clone();
    stored.translate(-t);
    let stored_view = far_view.translated(-t);
    let diagonal = stored.bounds().diagonal();
    let mut frames = Vec::new();
    for (offset, scene, view) in [(glam::Vec3::ZERO, stored, stored_view), (t, far_scene, far_view)] {
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        assert_eq!(gpu_scene.origin == glam::Vec3::ZERO, offset == glam::Vec3::ZERO);
        for positions in [true, false] {
            let e = embedded_frame(&pass, &scene, &gpu_scene, &view, size, positions);
            assert_eq!(e.unfinished, 0);
            // Texels in the near frame: the far pass's are relative to its scene's origin.
            let shift = gpu_scene.origin - offset;
            let points: Vec<GBufferTexel> = e
                .gbuffer
                .iter()
                .map(|g| GBufferTexel {
                    origin: g.origin + shift,
                    ..*g
                })
                .collect();
            frames.push((points, e.unfiltered));
        }
    }
    for (input, near, far) in [("position", 0, 2), ("depth", 1, 3)] {
        let ((ga, a), (gb, b)) = (&frames[near], &frames[far]);
        // Where the host saw the same surface in both (its raster at 1e5 is rounded too).
        let same: Vec<usize> = (0..a.len())
            .filter(|&p| !primary_differs(&ga[p], &gb[p], 5e-4 * diagonal))
            .collect();
        let off = same.iter().filter(|&&p| (a[p] - b[p]).abs() > 1.0 / 16.0).count();
        let darkened = same.iter().filter(|&&p| a[p] == 1.0 && b[p] < 0.5).count();
        eprintln!(
            "{input} input at 1e5: the host saw the same surface at {} of {} pixels; there {off} \
             differ by more than 1/16, {darkened} lit pixels darkened",
            same.len(),
            a.len()
        );
        if input == "position" {
            assert!(
                same.len() * 100 >= a.len() * 95,
                "{input} input: the host's raster moved"
            );
            assert!(
                darkened * 1000 <= a.len(),
                "{input} input: {darkened} lit pixels darkened"
            );
        }
    }
}
