//! The whole GPU frame against its CPU twins: the primary pass, the
//! discontinuity filter, exact lit and umbra values on a scene whose shadow is
//! known geometrically, a tile whose traversal exceeds lavapipe's loop limit
//! (so the suspend/resume path runs), and images of odd sizes.
//!
//! Run with `--nocapture` to see the figures measured; on lavapipe set
//! `LP_NATIVE_VECTOR_WIDTH=512` to test the subgroup vector too.

use crate::support;

use std::time::Instant;

use glam::{Vec2, Vec3};
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::{GBufferTexel, ShadowParams};
use penumbra::gpu::{Frame, FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions, Tracer};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::filter::discontinuity_filter;
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_mft::{Counters, Frustum, TileOptions, mft_masks, trace_tile};
use penumbra::reference::shadow_per_ray::{
    ITERATION_BUDGET, MASK_FULL, MASK_SKY, per_ray_masks, shadow_params,
};
use penumbra::scene::Scene;
use penumbra::scene::view::{Camera, QuadLight, View};
use penumbra::{assets, sampling};
use support::gpu::{assert_same_rays, ctx, embedded, variants};
use support::{
    Rng, compare_masks, edge_tolerance, near_miss_stack, own_triangle, scaled_and_moved, scene_from_triangles,
};

/// lavapipe (Mesa 22.3) ends every loop of an invocation after this many
/// iterations, counted across all its loops. Measured here: a loop nested in
/// another costs one more iteration each time the outer body reaches it, even
/// in a branch no lane takes, so a loop with a nested loop gets only ~32,767.
const LAVAPIPE_LOOP_LIMIT: u64 = 65_535;

/// The horizontal square `[-half, half]²` at height `y`, facing +y, as two triangles.
fn horizontal_square(y: f32, half: f32, material: u32) -> [([Vec3; 3], u32); 2] {
    let p = |x: f32, z: f32| Vec3::new(x, y, z);
    let (a, b, c, d) = (p(-half, -half), p(-half, half), p(half, half), p(half, -half));
    [([a, b, c], material), ([a, c, d], material)]
}

/// A camera straight above `target`, looking down (image up = −z).
fn top_down_camera(eye_height: f32, target: Vec3, fov_y_degrees: f32) -> Camera {
    Camera {
        eye: target + Vec3::Y * eye_height,
        target,
        up: Vec3::NEG_Z,
        fov_y_degrees,
    }
}

/// Renders one frame; returns it with the wall time in milliseconds.
fn render(renderer: &Renderer, scene: &GpuScene, view: &View, settings: &FrameSettings) -> (Frame, f64) {
    let start = Instant::now();
    let frame = renderer
        .render(ctx(), scene, view, settings)
        .unwrap_or_else(|e| panic!("{} frame failed: {e}", renderer.variant()));
    (frame, start.elapsed().as_secs_f64() * 1e3)
}

/// The CPU twin of the primary pass for `scene` seen through `view`.
fn cpu_gbuffer(scene: &Scene, bvh: &Bvh, view: &View, w: u32, h: u32) -> Vec<GBufferTexel> {
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

/// The CPU twin's counters of every 4×4 tile (row-major), traced without a
/// budget as the default renderer's kernel with `leaf_mode` runs: what one
/// uninterrupted vector does.
fn tile_counters(
    bvh: &Bvh,
    gbuffer: &[GBufferTexel],
    light_points: &[Vec3],
    params: &ShadowParams,
    leaf_mode: LeafMode,
) -> Vec<Counters> {
    let (w, h) = (params.width as usize, params.height as usize);
    let mut tiles = Vec::new();
    for ty in 0..h.div_ceil(4) {
        for tx in 0..w.div_ceil(4) {
            let frusta: [Frustum; 16] = std::array::from_fn(|i| {
                let (x, y) = (tx * 4 + i % 4, ty * 4 + i / 4);
                let texel = if x < w && y < h {
                    gbuffer[y * w + x]
                } else {
                    // Outside the image: a sky lane, done from the start.
                    GBufferTexel {
                        triangle: u32::MAX,
                        ..Default::default()
                    }
                };
                Frustum::new(&texel, i, light_points, params)
            });
            let mut c = Counters::default();
            let options = TileOptions {
                budget: u32::MAX,
                shrink: RendererOptions::default().shrink,
                transposed: leaf_mode == LeafMode::Transposed,
            };
            trace_tile(bvh, frusta, params, &options, &mut c);
            tiles.push(c);
        }
    }
    tiles
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
    let (w, h) = (64, 48);
    let renderer = Renderer::new(ctx(), None).unwrap();
    for s in assets::EMBEDDED_SCENES {
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
            "{}: filter GPU vs CPU max error {err:.2e} (pixel {at}), {exact} of {} pixels bit-equal; \
             largest value {largest:.3}; the filter changed {changed} pixels; frame {ms:.0} ms, \
             GPU filter {:.2} ms",
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

/// A 2 × 2 ground, a 4 × 4 light at y = 2 and a thin layer (y 0.9..1.1) of
/// `occluders` randomly oriented triangles `size` across over [-0.6, 0.6]², all inside
/// every frustum of every pixel (the camera sees [-0.35, 0.35]² of ground
/// from below the layer), and sparse enough that no frustum is ever fully
/// blocked: every tile walks the whole tree, ~1.7 steps per triangle.
fn occluder_layer_scene(occluders: usize, size: f32) -> (Scene, View) {
    let mut rng = Rng::new(0x5eed_f00d);
    let mut tris: Vec<([Vec3; 3], u32)> = horizontal_square(0.0, 1.0, 0).to_vec();
    for _ in 0..occluders {
        let c = rng.in_box(Vec3::new(-0.6, 0.9, -0.6), Vec3::new(0.6, 1.1, 0.6));
        tris.push(([c, c + rng.direction() * size, c + rng.direction() * size], 1));
    }
    let scene = scene_from_triangles(&tris, &[[0.8, 0.8, 0.8], [0.3, 0.3, 0.3]]);
    let view = View {
        camera: top_down_camera(0.6, Vec3::ZERO, 60.0),
        light: QuadLight::from_center(
            Vec3::new(0.0, 2.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 4.0),
        ),
        ground_y: None,
    };
    view.validate().unwrap();
    (scene, view)
}

#[test]
fn loop_limit_tile_still_matches_oracle() {
    let start = Instant::now();
    let mut failures = Vec::new();
    // Transposed leaves take ~17 steps per triangle here (one per surviving
    // frustum): a sparser layer (of larger triangles, for as much shadow) exceeds
    // the limit as well and keeps lavapipe fast.
    for (leaf_mode, occluders, size) in [
        (LeafMode::PerLane, 130_000, 0.0056),
        (LeafMode::Transposed, 4_000, 0.025),
    ] {
        let (scene, view) = occluder_layer_scene(occluders, size);
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
        let (w, h) = (8, 8);
        let mut settings = FrameSettings::new(w, h);
        settings.keep_gbuffer = true;
        let params = shadow_params(&view.light, w, h);
        let points = sampling::light_points(&view.light);
        let corners: Vec<_> = scene.triangles.iter().map(|t| t.positions).collect();

        // The CPU side, on the CPU twin's G-buffer (the GPU's is checked against it below).
        let gbuffer = cpu_gbuffer(&scene, &bvh, &view, w, h);
        assert!(
            gbuffer.iter().all(|t| t.is_hit() && t.origin.y < 0.01),
            "every pixel must see the ground"
        );
        let tiles = tile_counters(&bvh, &gbuffer, &points, &params, leaf_mode);
        let steps: Vec<u64> = tiles.iter().map(|c| c.traversal_steps).collect();
        let busiest = *steps.iter().max().unwrap();
        let predicted: u64 = steps
            .iter()
            .map(|&s| s.saturating_sub(1) / u64::from(ITERATION_BUDGET))
            .sum();
        let shrink = RendererOptions::default().shrink;
        let (twin, counters) = mft_masks(
            &bvh,
            &gbuffer,
            &points,
            &params,
            &TileOptions {
                shrink,
                ..TileOptions::with_budget(ITERATION_BUDGET)
            },
        );
        if leaf_mode == LeafMode::PerLane {
            // Suspending and resuming adds no step.
            assert_eq!(
                counters.traversal_steps,
                tiles.iter().map(|c| c.traversal_steps).sum::<u64>()
            );
        }
        let oracle = per_ray_masks(&bvh, &gbuffer, &points, &params);
        let occluded: u32 = oracle.iter().map(|m| (m & MASK_FULL).count_ones()).sum();
        let rays = gbuffer.len() * 16;
        let twin_differing = compare_masks(
            &oracle,
            &twin,
            &gbuffer,
            w,
            &points,
            &params,
            &corners,
            &own_triangle(&bvh),
            0.0,
        )
        .differing;
        eprintln!(
            "{leaf_mode}: {} triangles, BVH of {} nodes (depth {}); kernel steps per tile {steps:?} \
             (lavapipe limit {LAVAPIPE_LOOP_LIMIT}, budget {ITERATION_BUDGET}) predict {predicted} \
             suspensions; twin {counters:?}; oracle: {occluded} of {rays} rays occluded, \
             {twin_differing} differ from the twin",
            scene.triangles.len(),
            bvh.nodes.len(),
            bvh.stats().max_depth,
        );
        assert!(
            busiest > LAVAPIPE_LOOP_LIMIT,
            "{leaf_mode}: the scene must give a tile more than {LAVAPIPE_LOOP_LIMIT} steps, the busiest has {busiest}"
        );
        assert!(
            occluded as usize > rays / 50 && (occluded as usize) < rays * 19 / 20,
            "{leaf_mode}: the layer must block some rays but not all ({occluded} of {rays})"
        );

        for variant in variants() {
            let options = RendererOptions {
                variant: Some(variant),
                leaf_mode,
                ..RendererOptions::default()
            };
            let renderer = Renderer::new(ctx(), options).unwrap();
            let (frame, ms) = render(&renderer, &gpu_scene, &view, &settings);
            let gpu_gbuffer = frame.gbuffer.as_ref().unwrap();
            let other_triangle = gpu_gbuffer
                .iter()
                .zip(&gbuffer)
                .filter(|(g, c)| g.triangle != c.triangle)
                .count();
            assert_eq!(
                other_triangle, 0,
                "{variant}: the G-buffer differs from the CPU twin's"
            );
            // The oracle on the GPU's own G-buffer, as in tests/gpu/shadow_mft.rs.
            let oracle = per_ray_masks(&bvh, gpu_gbuffer, &points, &params);
            let c = compare_masks(
                &oracle,
                &frame.masks,
                gpu_gbuffer,
                w,
                &points,
                &params,
                &corners,
                &own_triangle(&bvh),
                edge_tolerance(&scene),
            );
            eprintln!("{variant} {leaf_mode}: against the per-ray oracle: {c}");
            let (differing, total, unexplained) = (c.differing, c.total, c.unexplained);
            let twin_bits: u32 = twin
                .iter()
                .zip(&frame.masks)
                .map(|(a, b)| (a ^ b).count_ones())
                .sum();
            let gpu_occluded: u32 = frame.masks.iter().map(|m| (m & MASK_FULL).count_ones()).sum();
            let stats = frame.shadow_stats;
            eprintln!(
                "{variant} {leaf_mode}: GPU {stats:?}; {differing} of {total} rays differ from the \
                 oracle ({} unexplained), {twin_bits} mask bits from the twin, {gpu_occluded} rays \
                 occluded; frame {ms:.0} ms, shadow {:.1} ms",
                unexplained.len(),
                frame.pass_ms("shadow"),
            );
            let mut fail = |m: String| failures.push(format!("{variant} {leaf_mode}: {m}"));
            if stats.suspensions == 0 {
                fail(format!("no tile was suspended: {stats:?}"));
            }
            // The kernel counts its steps as the twin does: the same budget gives the same suspensions.
            if stats.suspensions != predicted {
                fail(format!(
                    "{} suspensions, the twin's step counts give {predicted}",
                    stats.suspensions
                ));
            }
            if !unexplained.is_empty() {
                fail(format!(
                    "{} rays differ from the oracle unexplained, e.g. {:?}",
                    unexplained.len(),
                    &unexplained[..unexplained.len().min(4)]
                ));
            }
            if differing * 1000 > total {
                fail(format!("{differing} of {total} rays differ from the oracle"));
            }
        }
    }
    eprintln!(
        "loop_limit_tile_still_matches_oracle: {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert!(
        failures.is_empty(),
        "tiles past lavapipe's loop limit are traced wrong:\n{}",
        failures.join("\n")
    );
}

/// A camera ray that passes through the boxes of a stack of `n` horizontal
/// triangles without touching any (each one's long edge passes 0.05 beside the
/// ray) before it hits the ground: the primary kernel visits every node.
fn near_miss_stack_scene(n: usize) -> (Scene, View) {
    let mut tris: Vec<([Vec3; 3], u32)> = horizontal_square(0.0, 2.0, 0).to_vec();
    tris.extend(near_miss_stack(n));
    let scene = scene_from_triangles(&tris, &[[0.8, 0.8, 0.8], [0.3, 0.3, 0.3]]);
    // A light low to the side, so that shadow rays pass under the stack.
    let view = View {
        camera: top_down_camera(10.0, Vec3::ZERO, 1.0),
        light: QuadLight::from_center(
            Vec3::new(5.0, 0.5, 0.0),
            Vec3::new(0.0, 0.0, 0.2),
            Vec3::new(0.0, 0.2, 0.0),
        ),
        ground_y: None,
    };
    view.validate().unwrap();
    (scene, view)
}

/// The primary kernel counts its loop steps and reports an overflow; on
/// lavapipe a ray that needs more steps than the loop limit allows must give
/// that error or, if it was not cut, the CPU twin's texel — never a silent miss.
#[test]
fn primary_pass_past_the_loop_limit_errors_or_matches_cpu() {
    let start = Instant::now();
    let (scene, view) = near_miss_stack_scene(40_000);
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let (w, h) = (1, 1);
    let cpu = cpu_gbuffer(&scene, &bvh, &view, w, h);
    let ground: Vec<u32> = (0..bvh.triangles.len() as u32)
        .filter(|&i| bvh.triangles[i as usize].scene_index < 2)
        .collect();
    assert!(ground.contains(&cpu[0].triangle), "the CPU ray hits the ground");
    // Every box holds the ray, so the kernel pops every node and tests every triangle.
    let kernel_steps = bvh.nodes.len() + bvh.triangles.len();
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    let result = Renderer::new(ctx(), None)
        .unwrap()
        .render(ctx(), &gpu_scene, &view, &settings);
    let outcome = match &result {
        Err(e) => format!("error: {e}"),
        Ok(frame) => format!("texel {:?}", frame.gbuffer.as_ref().unwrap()[0]),
    };
    eprintln!(
        "{} triangles, {} nodes: the camera ray needs {kernel_steps} kernel steps \
         (the kernel reports an error past 60000); CPU hits triangle {} at depth {}; GPU {outcome}; {:.1} s",
        bvh.triangles.len(),
        bvh.nodes.len(),
        cpu[0].triangle,
        cpu[0].depth,
        start.elapsed().as_secs_f64()
    );
    if let Ok(frame) = result {
        let g = frame.gbuffer.as_ref().unwrap()[0];
        assert_eq!(
            g.triangle, cpu[0].triangle,
            "the primary pass silently returned a wrong hit (or a miss) for a ray of \
             {kernel_steps} steps instead of the ground or an overflow error"
        );
    }
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
        .map(|&m| penumbra::reference::shadow_per_ray::visibility(m))
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
/// (frame::shadow_ray_origin), above the rounding of a hit point (at most ~2.6 steps).
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
