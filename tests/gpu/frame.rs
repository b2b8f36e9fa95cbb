//! The whole GPU frame against its CPU twins: the primary pass, the discontinuity
//! filter, the shade pass, exact lit and umbra values on a scene whose shadow is known
//! geometrically, and images of odd sizes (loop limits: `loop_limit.rs`; far scenes:
//! `far_from_origin.rs`).
//!
//! Run with `--nocapture` to see the figures measured; on lavapipe set
//! `LP_NATIVE_VECTOR_WIDTH=512` to test the subgroup vector too.

use crate::support;

use std::time::Instant;

use glam::{Vec2, Vec3};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::GBufferTexel;
use penumbra::contract::layout::{MASK_FULL, MASK_SKY};
use penumbra::gpu::{Frame, FrameSettings, GpuScene, Renderer};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::filter::discontinuity_filter;
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_per_ray::{per_ray_masks, shadow_params};
use penumbra::scene::Scene;
use penumbra::scene::view::{Camera, QuadLight, View};
use penumbra::{assets, sampling};
use support::gpu::{assert_same_rays, ctx, embedded, variants};
use support::{compare_masks, edge_tolerance, own_triangle, scene_from_triangles};

/// The horizontal square `[-half, half]²` at height `y`, facing +y, as two triangles.
pub(super) fn horizontal_square(y: f32, half: f32, material: u32) -> [([Vec3; 3], u32); 2] {
    let p = |x: f32, z: f32| Vec3::new(x, y, z);
    let (a, b, c, d) = (p(-half, -half), p(-half, half), p(half, half), p(half, -half));
    [([a, b, c], material), ([a, c, d], material)]
}

/// A camera straight above `target`, looking down (image up = −z).
pub(super) fn top_down_camera(eye_height: f32, target: Vec3, fov_y_degrees: f32) -> Camera {
    Camera {
        eye: target + Vec3::Y * eye_height,
        target,
        up: Vec3::NEG_Z,
        fov_y_degrees,
    }
}

/// Renders one frame; returns it with the wall time in milliseconds.
pub(super) fn render(
    renderer: &Renderer,
    scene: &GpuScene,
    view: &View,
    settings: &FrameSettings,
) -> (Frame, f64) {
    let start = Instant::now();
    let frame = renderer
        .render(ctx(), scene, view, settings)
        .unwrap_or_else(|e| panic!("{} frame failed: {e}", renderer.variant()));
    (frame, start.elapsed().as_secs_f64() * 1e3)
}

/// The CPU twin of the primary pass for `scene` seen through `view`.
pub(super) fn cpu_gbuffer(scene: &Scene, bvh: &Bvh, view: &View, w: u32, h: u32) -> Vec<GBufferTexel> {
    let cam = camera_params(
        &view.camera,
        w,
        h,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    primary_gbuffer(bvh, &ShadingData::new(scene, bvh).unwrap(), &cam)
}

/// The CPU filter over a frame's unfiltered values, with the G-buffer's depths and normals.
fn cpu_filter(frame: &Frame, gbuffer: &[GBufferTexel], params: &FilterParams) -> Vec<[f32; 4]> {
    let depth: Vec<f32> = gbuffer.iter().map(|t| t.depth).collect();
    let normal: Vec<[f32; 3]> = gbuffer.iter().map(|t| t.normal.to_array()).collect();
    discontinuity_filter(params, &frame.unfiltered, &depth, &normal)
}

/// Largest `|a − b| / max(1, |b|)` over every channel, and the pixel where it occurs.
fn max_channel_error(a: &[[f32; 4]], b: &[[f32; 4]]) -> (f32, usize) {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .enumerate()
        .flat_map(|(p, (x, y))| (0..4).map(move |k| ((x[k] - y[k]).abs() / y[k].abs().max(1.0), p)))
        .fold((0.0, 0), |best, e| if e.0 > best.0 { e } else { best })
}

#[test]
fn primary_pass_matches_cpu_twin() {
    let start = Instant::now();
    let (w, h) = (64, 48);
    let renderer = Renderer::new(ctx(), None).unwrap();
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
        let gpu = frame.gbuffer.as_ref().unwrap();
        let cpu = cpu_gbuffer(&scene, &bvh, &view, w, h);
        assert_eq!(gpu.len(), cpu.len());
        let diag = scene.bounds().diagonal();

        let mut different_triangle = Vec::new();
        let (mut hits, mut misses) = (0usize, 0usize);
        let (mut origin_err, mut depth_err, mut normal_err, mut geo_err) = (0f32, 0f32, 0f32, 0f32);
        for (p, (g, c)) in gpu.iter().zip(&cpu).enumerate() {
            let (x, y) = (p as u32 % w, p as u32 / w);
            if g.triangle != c.triangle {
                different_triangle.push(format!("({x},{y}): GPU {} CPU {}", g.triangle, c.triangle));
                continue;
            }
            if c.triangle == u32::MAX {
                misses += 1;
                assert_eq!(g, c, "{} ({x},{y}): both miss, texels differ", s.name);
                assert!(!g.is_hit());
                continue;
            }
            hits += 1;
            let oe = g.origin.distance(c.origin) / diag;
            let de = (g.depth - c.depth).abs() / c.depth;
            let ne = g.normal.distance(c.normal);
            let ge = g.geo_normal.distance(c.geo_normal);
            origin_err = origin_err.max(oe);
            depth_err = depth_err.max(de);
            normal_err = normal_err.max(ne);
            geo_err = geo_err.max(ge);
            assert!(
                oe <= 1e-4,
                "{} ({x},{y}): origin {} vs {}",
                s.name,
                g.origin,
                c.origin
            );
            assert!(
                de <= 1e-4,
                "{} ({x},{y}): depth {} vs {}",
                s.name,
                g.depth,
                c.depth
            );
            assert!(
                ne <= 1e-4,
                "{} ({x},{y}): normal {} vs {}",
                s.name,
                g.normal,
                c.normal
            );
            assert!(
                ge <= 1e-4,
                "{} ({x},{y}): geo normal {} vs {}",
                s.name,
                g.geo_normal,
                c.geo_normal
            );
            assert_eq!(g.albedo, c.albedo, "{} ({x},{y}): albedo", s.name);
        }
        let total = (w * h) as usize;
        eprintln!(
            "{}: {hits} hits + {misses} misses agree, {} of {total} pixels hit another triangle {:?}; \
             max errors: origin {origin_err:.2e}·diag, depth {depth_err:.2e} rel, normal {normal_err:.2e}, \
             geo normal {geo_err:.2e}; frame {ms:.0} ms, GPU primary {:.2} ms",
            s.name,
            different_triangle.len(),
            &different_triangle[..different_triangle.len().min(5)],
            frame.pass_ms("primary"),
        );
        assert!(
            hits > total / 2 && misses < total,
            "{}: the view must mostly see geometry",
            s.name
        );
        assert!(
            different_triangle.len() * 1000 <= total,
            "{}: {} of {total} pixels hit different triangles: {:?}",
            s.name,
            different_triangle.len(),
            &different_triangle[..different_triangle.len().min(10)]
        );
    }
    eprintln!(
        "primary_pass_matches_cpu_twin: {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

#[test]
fn filter_matches_cpu_twin() {
    let start = Instant::now();
    let renderer = Renderer::new(ctx(), None).unwrap();
    // 64 pixels wide: the filter's input textures are filled by one copy each; 61: one copy
    // per row (a row of 61 × 16 bytes is not a multiple of wgpu's 256-byte row alignment).
    for ((w, h), s) in [(64, 48), (61, 37)]
        .into_iter()
        .flat_map(|size| assets::EMBEDDED_SCENES.iter().map(move |s| (size, s)))
    {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
        let gbuffer = frame.gbuffer.as_ref().unwrap();
        let params = FilterParams::new(w, h);
        assert_eq!(
            settings.filter,
            Some((params.depth_tolerance, params.normal_tolerance)),
            "the renderer's default tolerances are the filter's"
        );
        let cpu = cpu_filter(&frame, gbuffer, &params);
        let (err, at) = max_channel_error(&frame.filtered, &cpu);
        let largest = frame
            .unfiltered
            .iter()
            .flat_map(|v| v.iter().copied())
            .fold(0f32, |m, x| m.max(x.abs()));
        let changed = frame
            .filtered
            .iter()
            .zip(&frame.unfiltered)
            .filter(|(a, b)| a != b)
            .count();
        let exact = frame.filtered.iter().zip(&cpu).filter(|(a, b)| a == b).count();
        eprintln!(
            "{} {w}x{h}: filter GPU vs CPU max error {err:.2e} (pixel {at}), {exact} of {} pixels \
             bit-equal; largest value {largest:.3}; the filter changed {changed} pixels; frame \
             {ms:.0} ms, GPU filter {:.2} ms",
            s.name,
            cpu.len(),
            frame.pass_ms("filter"),
        );
        // Values are O(1) (largest printed above): 1e-6 is absolute up to 1, relative beyond.
        assert!(
            err <= 1e-6,
            "{}: pixel {at}: GPU {:?} vs CPU {:?}",
            s.name,
            frame.filtered[at],
            cpu[at]
        );
        assert!(changed > 0, "{}: the filter must change the noisy image", s.name);

        // Filter off: the filtered image is the unfiltered one, and that is the same as with the filter on.
        let off = FrameSettings {
            filter: None,
            ..settings
        };
        let (plain, _) = render(&renderer, &gpu_scene, &view, &off);
        assert_eq!(plain.filtered, plain.unfiltered, "{}: filter off", s.name);
        assert_eq!(plain.unfiltered, frame.unfiltered, "{}: shading differs", s.name);
        // One pipeline on the same input: the same bits on any adapter.
        assert_eq!(plain.masks, frame.masks, "{}: masks differ", s.name);
        assert_eq!(plain.pass_ms("filter"), 0.0, "{}: no filter pass ran", s.name);
    }
    eprintln!("filter_matches_cpu_twin: {:.1} s", start.elapsed().as_secs_f64());
}

/// Where a plate of half-size `half` at height `plate_y` sends the shadow of
/// the light (corners `corners`) seen from ground point `p`: the rectangle,
/// in (x, z), of the points where the segments from `p` to the light cross
/// the plate's plane (the light's image under an affine map, so its corners'
/// bounding box is exact for an axis-aligned light).
fn crossing_rect(p: Vec3, corners: &[Vec3; 4], plate_y: f32) -> (Vec2, Vec2) {
    let mut lo = Vec2::INFINITY;
    let mut hi = Vec2::NEG_INFINITY;
    for &l in corners {
        let t = (plate_y - p.y) / (l.y - p.y);
        let x = p + (l - p) * t;
        lo = lo.min(Vec2::new(x.x, x.z));
        hi = hi.max(Vec2::new(x.x, x.z));
    }
    (lo, hi)
}

#[test]
fn lit_and_umbra_are_exact() {
    let start = Instant::now();
    // Ground [-10, 10]² at y = 0, a plate [-2, 2]² at y = 1, a 0.5 × 0.5 light at y = 3 facing down.
    let (plate_y, plate_half) = (1.0f32, 2.0f32);
    let mut tris = Vec::new();
    tris.extend(horizontal_square(0.0, 10.0, 0));
    tris.extend(horizontal_square(plate_y, plate_half, 1));
    let scene = scene_from_triangles(&tris, &[[0.8, 0.8, 0.8], [0.5, 0.6, 0.7]]);
    let light = QuadLight::from_center(
        Vec3::new(0.0, 3.0, 0.0),
        Vec3::new(0.5, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 0.5),
    );
    assert!(light.area_normal().y < 0.0, "the light faces down");
    let view = View {
        camera: top_down_camera(10.0, Vec3::ZERO, 60.0),
        light,
        ground_y: None,
    };
    view.validate().unwrap();
    let corners = [
        light.corner,
        light.corner + light.edge_u,
        light.corner + light.edge_u + light.edge_v,
        light.corner + light.edge_v,
    ];
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (96, 96);
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    // Margin (world units) that keeps the classified points clear of the penumbra's
    // boundaries: far above the ray offset (1e-4 of a ~28 diagonal) and rounding.
    let margin = 0.05;
    let mut first: Option<Vec<u32>> = None;
    for variant in variants() {
        let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
        let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
        let gbuffer = frame.gbuffer.as_ref().unwrap();
        let (mut lit, mut umbra, mut plate, mut penumbra_px) = (0, 0, 0, 0);
        let mut penumbra_vis = (f32::INFINITY, f32::NEG_INFINITY);
        for (p, t) in gbuffer.iter().enumerate() {
            let (x, y) = (p as u32 % w, p as u32 / w);
            let (mask, value) = (frame.masks[p], frame.unfiltered[p]);
            assert!(t.is_hit(), "{variant} ({x},{y}): the ground fills the view");
            assert_eq!(mask & MASK_SKY, 0, "{variant} ({x},{y}): not sky");
            if t.origin.y > 0.5 * plate_y {
                // The plate's top: nothing lies between it and the light.
                plate += 1;
                assert_eq!(mask, 0, "{variant} ({x},{y}) plate top: mask {mask:#x}");
                assert_eq!(value[3], 1.0, "{variant} ({x},{y}) plate top: {value:?}");
                continue;
            }
            let (lo, hi) = crossing_rect(t.origin, &corners, plate_y);
            let inside = |m: f32| {
                lo.cmpge(Vec2::splat(-plate_half + m)).all() && hi.cmple(Vec2::splat(plate_half - m)).all()
            };
            let outside = |m: f32| {
                lo.cmpgt(Vec2::splat(plate_half + m)).any() || hi.cmplt(Vec2::splat(-plate_half - m)).any()
            };
            if inside(margin) {
                umbra += 1;
                assert_eq!(
                    mask & MASK_FULL,
                    MASK_FULL,
                    "{variant} ({x},{y}) umbra at {}: mask {mask:#x}",
                    t.origin
                );
                assert_eq!(value, [0.0; 4], "{variant} ({x},{y}) umbra at {}", t.origin);
            } else if outside(margin) {
                lit += 1;
                assert_eq!(mask, 0, "{variant} ({x},{y}) lit at {}: mask {mask:#x}", t.origin);
                assert_eq!(value[3], 1.0, "{variant} ({x},{y}) lit at {}", t.origin);
                assert!(value[0] > 0.0, "{variant} ({x},{y}) lit: {value:?}");
            } else {
                penumbra_px += 1;
                penumbra_vis = (penumbra_vis.0.min(value[3]), penumbra_vis.1.max(value[3]));
            }
            // Whatever the class, the geometry bounds the visibility: no light
            // through the plate's umbra margin, none blocked outside it.
            if inside(-margin) {
                assert!(value[3] < 1.0, "{variant} ({x},{y}) near umbra: {value:?}");
            }
            if outside(-margin) {
                assert!(value[3] > 0.0, "{variant} ({x},{y}) near lit: {value:?}");
            }
        }
        eprintln!(
            "{variant}: {lit} lit ground pixels (visibility 1), {umbra} umbra (0), {plate} plate top (1), \
             {penumbra_px} in the penumbra band with visibility {:.4}..{:.4}; frame {ms:.0} ms, shadow {:.2} ms, \
             {:?}",
            penumbra_vis.0,
            penumbra_vis.1,
            frame.pass_ms("shadow"),
            frame.shadow_stats
        );
        assert!(lit >= 500, "{variant}: only {lit} lit pixels");
        assert!(umbra >= 200, "{variant}: only {umbra} umbra pixels");
        assert!(plate >= 500, "{variant}: only {plate} plate pixels");
        assert!(penumbra_px > 0 && penumbra_vis.0 < penumbra_vis.1);
        match &first {
            None => first = Some(frame.masks.clone()),
            Some(m) => assert_same_rays(
                "subgroup vs workgroup",
                m,
                &frame.masks,
                &scene,
                &bvh,
                &view,
                gbuffer,
                w,
            ),
        }
    }
    eprintln!("lit_and_umbra_are_exact: {:.1} s", start.elapsed().as_secs_f64());
}

#[test]
fn cli_free_sizes() {
    let start = Instant::now();
    let (scene, view) = embedded(assets::default_scene().name);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();
    let points = sampling::light_points(&view.light);
    for variant in variants() {
        let renderer = Renderer::new(ctx(), Some(variant)).unwrap();
        for (w, h) in [(1u32, 1u32), (1, 7), (7, 1), (5, 3), (17, 33)] {
            let n = (w * h) as usize;
            let mut settings = FrameSettings::new(w, h);
            settings.keep_gbuffer = true;
            let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
            let gbuffer = frame.gbuffer.as_ref().unwrap();
            assert_eq!((frame.width, frame.height), (w, h));
            assert_eq!(frame.masks.len(), n, "{variant} {w}x{h}: masks");
            assert_eq!(frame.unfiltered.len(), n, "{variant} {w}x{h}: unfiltered");
            assert_eq!(frame.filtered.len(), n, "{variant} {w}x{h}: filtered");
            assert_eq!(gbuffer.len(), n, "{variant} {w}x{h}: G-buffer");

            // Every pixel, the last column and row of partial tiles included, is
            // where the CPU twins put it.
            let cpu = cpu_gbuffer(&scene, &bvh, &view, w, h);
            let other_triangle = gbuffer
                .iter()
                .zip(&cpu)
                .filter(|(g, c)| g.triangle != c.triangle)
                .count();
            let params = shadow_params(&view.light, w, h);
            let oracle = per_ray_masks(&bvh, gbuffer, &points, &params);
            let c = compare_masks(
                &oracle,
                &frame.masks,
                gbuffer,
                w,
                &points,
                &params,
                &corners,
                &own_triangle(&bvh),
                edge_tolerance(&scene),
            );
            eprintln!("{variant} {w}x{h}: against the per-ray oracle: {c}");
            let (differing, total, unexplained) = (c.differing, c.total, c.unexplained);
            let (filter_err, _) = max_channel_error(
                &frame.filtered,
                &cpu_filter(&frame, gbuffer, &FilterParams::new(w, h)),
            );
            eprintln!(
                "{variant} {w}x{h}: {other_triangle} pixels hit another triangle than the CPU's, \
                 {differing} of {total} rays differ from the oracle, filter error {filter_err:.1e}; \
                 {ms:.0} ms, {:?}",
                frame.shadow_stats
            );
            assert!(other_triangle * 100 <= n, "{variant} {w}x{h}: primary pass");
            assert!(unexplained.is_empty(), "{variant} {w}x{h}: {unexplained:?}");
            assert!(
                differing * 100 <= total,
                "{variant} {w}x{h}: {differing} of {total}"
            );
            assert!(filter_err <= 1e-6, "{variant} {w}x{h}: filter error {filter_err}");
        }
    }
    // Size 0 is refused, not rendered.
    let renderer = Renderer::new(ctx(), None).unwrap();
    for (w, h) in [(0, 5), (5, 0)] {
        let err = renderer
            .render(ctx(), &gpu_scene, &view, &FrameSettings::new(w, h))
            .expect_err("an empty image must be refused");
        eprintln!("{w}x{h}: {err}");
        assert!(
            !matches!(err, penumbra::Error::Gpu(_)) && err.to_string().contains(&format!("{w}x{h}")),
            "a bad size is an input error naming it, not a GPU failure: {err:?}"
        );
    }
    // A forced tile too large for one storage buffer: refused before anything is
    // allocated, naming the limit and the largest image that fits. (Unforced, the
    // renderer picks tiles that fit: tests/gpu/tiles.rs.)
    let limit = penumbra::gpu::memory::storage_limit(ctx());
    let side = ((limit / 64) as f64).sqrt() as u32 + 64; // a G-buffer over the limit
    let mut settings = FrameSettings::new(side, side);
    settings.max_tile = Some(side);
    let err = renderer
        .render(ctx(), &gpu_scene, &view, &settings)
        .expect_err("a tile beyond the device's buffer limit must be refused");
    eprintln!("{side}x{side} in one tile: {err}");
    match err {
        penumbra::Error::ImageTooLarge {
            limit: l,
            largest_width,
            largest_height,
            ..
        } => {
            assert_eq!(l, limit);
            let fits = FrameSettings::new(largest_width, largest_height);
            assert!(penumbra::gpu::memory::check_frame_fits(limit, fits.width, fits.height).is_ok());
        }
        other => panic!("expected ImageTooLarge, got {other:?}"),
    }
    eprintln!("cli_free_sizes: {:.1} s", start.elapsed().as_secs_f64());
}

#[test]
fn shade_matches_cpu_twin() {
    use penumbra::reference::shade::{shade_params, shade_pixel};
    let (w, h) = (64, 48);
    let renderer = Renderer::new(ctx(), None).unwrap();
    for s in assets::EMBEDDED_SCENES {
        let (scene, view) = embedded(s.name);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let (frame, _) = render(&renderer, &gpu_scene, &view, &settings);
        let gbuffer = frame.gbuffer.as_ref().unwrap();
        let params = shade_params(&view.light, w, h);
        let mut worst = 0f32;
        for (p, texel) in gbuffer.iter().enumerate() {
            let cpu = shade_pixel(&params, texel, frame.masks[p]).to_array();
            for (c, gpu) in cpu.iter().zip(&frame.unfiltered[p]) {
                // sqrt and division may round differently on the GPU: a relative tolerance of 1e-5.
                worst = worst.max((c - gpu).abs() / c.abs().max(1.0));
            }
            let brdf = texel.albedo / std::f32::consts::PI;
            assert!((Vec3::from_slice(&frame.brdf[p][..3]) - brdf).abs().max_element() <= 1e-6);
        }
        eprintln!("{}: shade GPU vs CPU worst relative error {worst:.2e}", s.name);
        assert!(worst <= 1e-5, "{}: {worst}", s.name);
        let radiance = frame.radiance();
        assert_eq!(radiance.len(), (w * h) as usize);
        assert!(
            radiance.iter().any(|r| r[0] > 0.0),
            "{}: the image is not black",
            s.name
        );
    }
}

/// `Renderer::render` checks the view itself, as the CLI does: a degenerate camera or
/// light is an error naming the field, not an image of NaN rays.
#[test]
fn render_refuses_a_degenerate_view() {
    let (scene, view) = embedded("playground");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let renderer = Renderer::new(ctx(), None).unwrap();
    let settings = FrameSettings::new(8, 8);
    let mut same_point = view;
    same_point.camera.target = same_point.camera.eye;
    let mut flat_light = view;
    flat_light.light.edge_v = flat_light.light.edge_u;
    for (bad, field) in [(same_point, "camera.target"), (flat_light, "light")] {
        let Err(err) = renderer.render(ctx(), &gpu_scene, &bad, &settings) else {
            panic!("a degenerate view ({field}) must be refused");
        };
        let message = err.to_string();
        assert!(
            matches!(err, penumbra::Error::InvalidInput { .. }) && message.contains(field),
            "{message}"
        );
    }
}
