//! The multi-frusta primary kernel against the per-ray kernel and both CPU
//! twins: G-buffers on the built-in scenes and a random soup at odd and
//! block-aligned sizes, the Table 1 counters (GPU against CPU twin, and
//! against values counted by hand on scenes built to be counted), and the
//! report of a vector that runs out of loop iterations.
//!
//! Run with `--nocapture` to see the figures; on lavapipe set
//! `LP_NATIVE_VECTOR_WIDTH=512` to test the subgroup vector too.

use crate::support;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::counters::Counters;
use penumbra::contract::layout::{CameraParams, GBufferTexel};
use penumbra::gpu::{
    FrameSettings, GpuScene, PrimaryOptions, PrimaryPass, PrimaryTracer, Renderer, RendererOptions,
    VectorVariant, empty_storage_buffer, read_buffer,
};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer_counted;
use penumbra::reference::primary_mft::{ITERATION_BUDGET, primary_mft_gbuffer, trace_block};
use penumbra::scene::Scene;
use penumbra::scene::view::Camera;
use support::gpu::{ctx, embedded, variants};
use support::{Rng, near_miss_column, random_soup, scene_from_triangles};

/// A scene, its BVH and a camera for one image size.
struct Case {
    name: String,
    scene: Scene,
    bvh: Bvh,
    cam: CameraParams,
}

impl Case {
    fn new(name: &str, scene: Scene, camera: &Camera, settings: &BvhSettings, (w, h): (u32, u32)) -> Case {
        let bvh = Bvh::build(&scene, settings).unwrap();
        let cam = camera_params(camera, w, h, scene.bounds().diagonal() * RAY_OFFSET_FRACTION);
        Case {
            name: format!("{name} {w}x{h}"),
            scene,
            bvh,
            cam,
        }
    }

    fn shading(&self) -> ShadingData {
        ShadingData::new(&self.scene, &self.bvh).unwrap()
    }
}

/// The built-in scenes and a random soup, at an odd size and a block-aligned one.
fn cases() -> Vec<Case> {
    let mut out = Vec::new();
    for size in [(37, 23), (64, 64)] {
        for name in ["playground", "lattice", "screen"] {
            let (scene, view) = embedded(name);
            out.push(Case::new(
                name,
                scene,
                &view.camera,
                &BvhSettings::default(),
                size,
            ));
        }
        let soup: Vec<([Vec3; 3], u32)> = random_soup(&mut Rng::new(7), 3000, 0.15)
            .into_iter()
            .map(|t| (t, 0))
            .collect();
        let camera = Camera {
            eye: Vec3::new(0.4, 0.7, 2.4),
            target: Vec3::splat(0.5),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        };
        let scene = scene_from_triangles(&soup, &[[0.7, 0.6, 0.5]]);
        out.push(Case::new(
            "random soup",
            scene,
            &camera,
            &BvhSettings::default(),
            size,
        ));
    }
    out
}

/// Runs `pass` on the GPU; returns the G-buffer and the status it reported.
fn gpu_gbuffer(pass: &PrimaryPass, case: &Case) -> (Vec<GBufferTexel>, penumbra::Result<Option<Counters>>) {
    let gpu_scene = GpuScene::new(ctx(), &case.scene, &case.bvh).unwrap();
    let bytes = u64::from(case.cam.width * case.cam.height) * size_of::<GBufferTexel>() as u64;
    let gbuffer = empty_storage_buffer(ctx(), "G-buffer", bytes, wgpu::BufferUsages::COPY_SRC).unwrap();
    let result = pass
        .run(ctx(), &gpu_scene, &case.cam, &gbuffer, None)
        .and_then(|s| s.check());
    (read_buffer(ctx(), &gbuffer, 0..bytes).unwrap(), result)
}

/// Asserts that two G-buffers are equal texel for texel, except where the two
/// traversal orders kept different triangles hit at exactly the same distance
/// (the only difference the kernels allow); returns how many such ties.
fn assert_equal_but_ties(label: &str, a: &[GBufferTexel], b: &[GBufferTexel], width: u32) -> usize {
    assert_eq!(a.len(), b.len(), "{label}: sizes");
    let mut ties = 0;
    for (p, (x, y)) in a.iter().zip(b).enumerate() {
        if x == y {
            continue;
        }
        let at = (p as u32 % width, p as u32 / width);
        assert!(
            x.triangle != y.triangle && x.is_hit() && y.is_hit() && x.depth == y.depth,
            "{label}: pixel {at:?} differs beyond an equal-depth tie:\n  {x:?}\n  {y:?}"
        );
        ties += 1;
    }
    assert!(ties * 100 <= a.len(), "{label}: {ties} ties");
    ties
}

/// Asserts that a GPU G-buffer matches its CPU twin within the primary pass's
/// tolerance (tests/gpu/frame.rs): hits on the same triangle but for 0.1 % of pixels,
/// and positions, depths and normals within 1e-4; returns the pixels that
/// differ at all.
fn assert_close(label: &str, gpu: &[GBufferTexel], cpu: &[GBufferTexel], diagonal: f32) -> usize {
    let mut other_triangle = 0;
    let mut differ = 0;
    for (p, (g, c)) in gpu.iter().zip(cpu).enumerate() {
        differ += usize::from(g != c);
        if g.triangle != c.triangle {
            other_triangle += 1;
            continue;
        }
        if !c.is_hit() {
            assert_eq!(g, c, "{label}: pixel {p}: both miss");
            continue;
        }
        assert!(
            g.origin.distance(c.origin) <= 1e-4 * diagonal,
            "{label}: pixel {p} origin"
        );
        assert!(
            (g.depth - c.depth).abs() <= 1e-4 * c.depth,
            "{label}: pixel {p} depth"
        );
        assert!(g.normal.distance(c.normal) <= 1e-4, "{label}: pixel {p} normal");
        assert!(
            g.geo_normal.distance(c.geo_normal) <= 1e-4,
            "{label}: pixel {p} geo normal"
        );
        assert_eq!(g.albedo, c.albedo, "{label}: pixel {p} albedo");
    }
    assert!(
        other_triangle * 1000 <= gpu.len(),
        "{label}: {other_triangle} of {} pixels hit other triangles",
        gpu.len()
    );
    differ
}

/// The pass of `tracer` (vector `variant`) with its work counters compiled in.
fn counting_pass(tracer: PrimaryTracer, variant: Option<VectorVariant>) -> PrimaryPass {
    let options = PrimaryOptions {
        tracer,
        variant,
        counters: true,
        ..PrimaryOptions::default()
    };
    PrimaryPass::new(ctx(), &options).unwrap()
}

#[test]
fn mft_equals_per_ray_and_cpu_twins() {
    let start = std::time::Instant::now();
    let per_ray = counting_pass(PrimaryTracer::PerRay, None);
    let mft: Vec<(VectorVariant, PrimaryPass)> = variants()
        .into_iter()
        .map(|v| (v, counting_pass(PrimaryTracer::Mft, Some(v))))
        .collect();
    for case in cases() {
        let label = &case.name;
        let shading = case.shading();
        let w = case.cam.width;
        let (cpu_per_ray, cpu_per_ray_counters) = primary_gbuffer_counted(&case.bvh, &shading, &case.cam);
        let twin = primary_mft_gbuffer(&case.bvh, &shading, &case.cam, ITERATION_BUDGET);
        assert_eq!(twin.overflow_pixels, 0, "{label}");
        let hits = twin.gbuffer.iter().filter(|t| t.is_hit()).count();
        assert!(
            hits * 4 > twin.gbuffer.len(),
            "{label}: the view must see geometry"
        );
        let cpu_ties = assert_equal_but_ties(
            &format!("{label}: CPU twins, frusta vs per-ray"),
            &twin.gbuffer,
            &cpu_per_ray,
            w,
        );

        let (gpu_per_ray, status) = gpu_gbuffer(&per_ray, &case);
        let gpu_per_ray_counters = status.unwrap().unwrap();
        assert_eq!(
            gpu_per_ray_counters, cpu_per_ray_counters,
            "{label}: per-ray counters, GPU (left) vs CPU twin (right)"
        );
        let per_ray_differ = assert_close(
            &format!("{label}: per-ray GPU vs CPU"),
            &gpu_per_ray,
            &cpu_per_ray,
            case.scene.bounds().diagonal(),
        );
        for (variant, pass) in &mft {
            let label = format!("{label} ({variant})");
            let (gpu, status) = gpu_gbuffer(pass, &case);
            let counters = status.unwrap().unwrap();
            let gpu_ties =
                assert_equal_but_ties(&format!("{label}: GPU, frusta vs per-ray"), &gpu, &gpu_per_ray, w);
            let twin_differ = assert_close(
                &format!("{label}: frusta GPU vs CPU twin"),
                &gpu,
                &twin.gbuffer,
                case.scene.bounds().diagonal(),
            );
            assert_eq!(
                counters, twin.counters,
                "{label}: frusta counters, GPU (left) vs CPU twin (right)"
            );
            eprintln!(
                "{label}: {hits} hits; ties frusta/per-ray: GPU {gpu_ties}, CPU {cpu_ties}; \
                 texels differing GPU/CPU: frusta {twin_differ}, per-ray {per_ray_differ}\n  \
                 frusta  {counters:?}\n  per-ray {gpu_per_ray_counters:?}"
            );
        }
    }
    eprintln!(
        "mft_equals_per_ray_and_cpu_twins: {:.1} s",
        start.elapsed().as_secs_f64()
    );
}

/// A camera 10 above the origin looking straight down with a 90° field of
/// view: at depth D, pixel x of a 16-pixel row is centred on X = D·(2(x+½)/16 − 1),
/// and pixel row y on Z = −D·(1 − 2(y+½)/16).
fn counting_camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 10.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        fov_y_degrees: 90.0,
    }
}

/// A horizontal triangle at height `y` that covers the whole view at any depth up to 11.
fn covering_triangle(y: f32) -> [Vec3; 3] {
    [
        Vec3::new(-12.0, y, -12.0),
        Vec3::new(40.0, y, -12.0),
        Vec3::new(-12.0, y, 40.0),
    ]
}

/// Counters of the CPU twins and of every GPU kernel on a 16×16 image of a
/// two-triangle scene whose BVH is a root and two one-triangle leaves.
fn counted(triangles: &[[Vec3; 3]; 2]) -> Vec<(String, Counters)> {
    let tris: Vec<([Vec3; 3], u32)> = triangles.iter().map(|&t| (t, 0)).collect();
    let settings = BvhSettings {
        max_leaf_size: 1,
        ..BvhSettings::default()
    };
    let case = Case::new(
        "counted",
        scene_from_triangles(&tris, &[[0.5; 3]]),
        &counting_camera(),
        &settings,
        (16, 16),
    );
    let nodes = &case.bvh.nodes;
    assert!(
        nodes.len() == 3 && !nodes[0].is_leaf() && nodes[1].count == 1 && nodes[2].count == 1,
        "the BVH must be a root over two one-triangle leaves: {nodes:?}"
    );
    let shading = case.shading();
    let mut out = vec![
        (
            "per-ray CPU".to_owned(),
            primary_gbuffer_counted(&case.bvh, &shading, &case.cam).1,
        ),
        (
            "frusta CPU".to_owned(),
            primary_mft_gbuffer(&case.bvh, &shading, &case.cam, ITERATION_BUDGET).counters,
        ),
    ];
    let pass = counting_pass(PrimaryTracer::PerRay, None);
    out.push((
        "per-ray GPU".to_owned(),
        gpu_gbuffer(&pass, &case).1.unwrap().unwrap(),
    ));
    for v in variants() {
        let pass = counting_pass(PrimaryTracer::Mft, Some(v));
        out.push((
            format!("frusta GPU {v}"),
            gpu_gbuffer(&pass, &case).1.unwrap().unwrap(),
        ));
    }
    out
}

fn counters(steps: u64, boxes: u64, accessed: u64, after_culling: u64, tests: u64) -> Counters {
    Counters {
        nodes_visited: steps,
        box_tests: boxes,
        triangles_accessed: accessed,
        triangles_after_culling: after_culling,
        triangle_tests: tests,
        ..Counters::default()
    }
}

/// Two planes covering the view, at depths 5 and 10.
///
/// Per ray (256): the root's box test; the root (1 step) tests both leaves'
/// boxes (2), both are hit, and the ray tests both triangles: it does not
/// test the far leaf's box again after its hit. So 256 steps, 768 box tests,
/// 512 triangles. Frusta: the root's box test; the root (1 step, 2 box
/// tests) sends all 16 frusta into the near leaf first (its centre is nearer
/// along the block's central ray): 1 triangle, no frustum culls it, 16
/// 16-ray tests; every ray then hits at depth 5, so when the far leaf comes
/// off the stack its depth 10 exceeds every frustum's farthest hit and no
/// frustum enters it.
#[test]
fn counters_by_hand_near_plane_hides_far_plane() {
    let expected = [
        ("per-ray", counters(256, 768, 512, 512, 512)),
        ("frusta", counters(1, 3, 1, 1, 16)),
    ];
    for (who, got) in counted(&[covering_triangle(5.0), covering_triangle(0.0)]) {
        let want = expected.iter().find(|(k, _)| who.starts_with(k)).unwrap().1;
        eprintln!("{who}: {got:?}");
        assert_eq!(got, want, "{who}");
    }
}

/// A ground plane covering the view at depth 10 and a small triangle at depth
/// 5 whose box spans pixel centres 5 and 6 in both x and y (X and Z from −1.75
/// to −0.6875, i.e. pixel coordinates 5.2 to 6.9): inside frustum 5 (pixels
/// 4..8 × 4..8) and outside the side planes of every other frustum.
///
/// Per ray: 256 root tests + 2 × 256 child tests, 256 steps; every ray tests
/// the ground triangle and the 4 rays through the small box also the small
/// triangle: 260. Frusta: root test, 1 step with 2 box tests; frustum 5 alone
/// enters the small leaf (1 triangle, 1 16-ray test), then all 16 frusta the
/// ground's (some of frustum 5's rays still have no hit): 1 triangle, 16 tests.
#[test]
fn counters_by_hand_small_triangle_in_one_frustum() {
    let small = [
        Vec3::new(-1.75, 5.0, -1.75),
        Vec3::new(-0.6875, 5.0, -1.75),
        Vec3::new(-1.75, 5.0, -0.6875),
    ];
    let expected = [
        ("per-ray", counters(256, 768, 260, 260, 260)),
        ("frusta", counters(1, 3, 2, 2, 17)),
    ];
    for (who, got) in counted(&[covering_triangle(0.0), small]) {
        let want = expected.iter().find(|(k, _)| who.starts_with(k)).unwrap().1;
        eprintln!("{who}: {got:?}");
        assert_eq!(got, want, "{who}");
    }
}

/// The built-in playground from its view's camera at `size`, default BVH.
fn playground(size: (u32, u32)) -> Case {
    let (scene, view) = embedded("playground");
    Case::new("playground", scene, &view.camera, &BvhSettings::default(), size)
}

/// The multi-frusta pass with vector `v` and `budget` iterations on `case`, recorded once:
/// the pixels it reports out of iterations (with the pass, scene and G-buffer, to run again).
fn overflow_pixels(case: &Case, v: VectorVariant, budget: u32) -> (PrimaryPass, GpuScene, wgpu::Buffer, u64) {
    let pass = PrimaryPass::new(
        ctx(),
        &PrimaryOptions {
            tracer: PrimaryTracer::Mft,
            variant: Some(v),
            iteration_budget: budget,
            ..PrimaryOptions::default()
        },
    )
    .unwrap();
    let (w, h) = (case.cam.width, case.cam.height);
    let gpu_scene = GpuScene::new(ctx(), &case.scene, &case.bvh).unwrap();
    let bytes = u64::from(w * h) * size_of::<GBufferTexel>() as u64;
    let gbuffer = empty_storage_buffer(ctx(), "G-buffer", bytes, wgpu::BufferUsages::empty()).unwrap();
    let status = PrimaryPass::status_buffer(&ctx().device);
    let camera = penumbra::gpu::kernel::uniform_buffer(ctx(), "camera", &case.cam);
    let mut encoder = ctx().device.create_command_encoder(&Default::default());
    let groups = pass.workgroups(ctx(), w, h).unwrap();
    pass.record(
        &ctx().device,
        &mut encoder,
        &gpu_scene,
        &camera,
        &gbuffer,
        &status,
        groups,
        None,
    )
    .unwrap();
    ctx().queue.submit([encoder.finish()]);
    let reported = pass.read_status(ctx(), &status).unwrap().overflow_pixels;
    (pass, gpu_scene, gbuffer, u64::from(reported))
}

/// Every vector runs as many loop passes as its CPU twin: for each pass count `p` a
/// block of the image needs, the kernel with a budget of `p - 1` reports the pixels of
/// exactly the blocks the twin says need more than `p - 1`, and with `p` those needing
/// more than `p`. So a kernel that does more (or less) in one pass than the twin fails.
#[test]
fn every_vector_runs_its_twins_passes() {
    let case = playground((69, 41));
    let (bw, bh) = (case.cam.width.div_ceil(16), case.cam.height.div_ceil(16));
    let mut passes: Vec<u32> = (0..bh)
        .flat_map(|by| (0..bw).map(move |bx| (bx, by)))
        .map(|(bx, by)| {
            let mut counters = Counters::default();
            trace_block(&case.bvh, &case.cam, bx, by, ITERATION_BUDGET, &mut counters).passes
        })
        .collect();
    passes.sort_unstable();
    passes.dedup();
    assert!(
        passes.len() > 3,
        "blocks with few distinct pass counts: {passes:?}"
    );
    // Four of them, lowest to highest (each budget is a pipeline to compile).
    let n = passes.len() - 1;
    let passes: Vec<u32> = [0, n / 3, 2 * n / 3, n].map(|i| passes[i]).to_vec();
    let shading = case.shading();
    for v in variants() {
        for &p in &passes {
            // A budget of 0 is refused (running_out_of_iterations_is_an_error).
            for budget in [p.saturating_sub(1), p].into_iter().filter(|&b| b > 0) {
                let twin = primary_mft_gbuffer(&case.bvh, &shading, &case.cam, budget).overflow_pixels;
                let (.., reported) = overflow_pixels(&case, v, budget);
                assert_eq!(
                    reported, twin,
                    "{v}, budget {budget}: pixels out of iterations, GPU vs CPU twin"
                );
            }
        }
        eprintln!("{v}: pass counts {passes:?} as the twin's");
    }
}

/// With a budget of a few loop iterations, some vectors stop early: the kernel
/// reports exactly the pixels of those vectors (as the CPU twin counts them)
/// and the pass turns that into an error, never a silently incomplete G-buffer.
#[test]
fn running_out_of_iterations_is_an_error() {
    let case = playground((37, 23));
    // The smallest budget that stops some vectors but not all, so that the count is a real check.
    let shading = case.shading();
    let (budget, twin) = [5, 10, 20, 40, 80, 160, 320]
        .into_iter()
        .map(|b| (b, primary_mft_gbuffer(&case.bvh, &shading, &case.cam, b)))
        .find(|(_, t)| t.overflow_pixels > 0 && t.overflow_pixels < 37 * 23)
        .expect("a budget that stops some vectors but not all");
    for v in variants() {
        let (pass, gpu_scene, gbuffer, reported) = overflow_pixels(&case, v, budget);
        assert_eq!(
            reported, twin.overflow_pixels,
            "{v}: pixels reported out of iterations, GPU vs CPU twin"
        );
        let err = pass
            .run(ctx(), &gpu_scene, &case.cam, &gbuffer, None)
            .and_then(|s| s.check())
            .unwrap_err();
        assert!(
            err.to_string().contains("ran out of their loop iterations"),
            "{err}"
        );
        eprintln!(
            "{v}: {} of {} pixels out of {budget} iterations: {err}",
            reported,
            37 * 23
        );
    }
    let pass = PrimaryPass::new(
        ctx(),
        &PrimaryOptions {
            tracer: PrimaryTracer::PerRay,
            iteration_budget: 1,
            ..PrimaryOptions::default()
        },
    )
    .unwrap();
    let err = gpu_gbuffer(&pass, &case).1.unwrap_err();
    assert!(
        err.to_string().contains("ran out of their loop iterations"),
        "per-ray: {err}"
    );
    // A budget past lavapipe's loop limit is allowed (a loop the driver ends is then an
    // error: a_loop_the_driver_ends_is_an_error_never_a_wrong_gbuffer); none at all is not.
    let err = PrimaryPass::new(
        ctx(),
        &PrimaryOptions {
            tracer: PrimaryTracer::Mft,
            iteration_budget: 0,
            ..PrimaryOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, penumbra::Error::InvalidValue { .. }), "{err:?}");
}

/// A renderer whose multi-frusta primary vectors run out of loop iterations does not
/// fail: the per-ray kernel traces the frame's camera rays again, so the frame is the
/// per-ray renderer's, bit for bit, and says how many pixels ran out (as the CPU twin
/// counts them). Small images of big scenes do this with the full budget (an 8×8
/// image of Sponza: each lane's frustum spans a quarter of the view).
#[test]
fn a_renderer_falls_back_to_per_ray_when_a_vector_runs_out() {
    let (scene, view) = embedded("playground");
    let (w, h) = (37, 23);
    let case = Case::new("playground", scene, &view.camera, &BvhSettings::default(), (w, h));
    let shading = case.shading();
    let (budget, twin) = [5, 10, 20, 40, 80, 160, 320]
        .into_iter()
        .map(|b| (b, primary_mft_gbuffer(&case.bvh, &shading, &case.cam, b)))
        .find(|(_, t)| t.overflow_pixels > 0 && t.overflow_pixels < u64::from(w * h))
        .expect("a budget that stops some vectors but not all");
    let gpu_scene = GpuScene::new(ctx(), &case.scene, &case.bvh).unwrap();
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    for v in variants() {
        let render = |primary, primary_iteration_budget| {
            let options = RendererOptions {
                variant: Some(v),
                primary,
                primary_iteration_budget,
                ..RendererOptions::default()
            };
            Renderer::new(ctx(), options)
                .unwrap()
                .render(ctx(), &gpu_scene, &view, &settings)
                .unwrap()
        };
        let per_ray = render(PrimaryTracer::PerRay, ITERATION_BUDGET);
        let fallback = render(PrimaryTracer::Mft, budget);
        let mft = render(PrimaryTracer::Mft, ITERATION_BUDGET);
        assert_eq!(
            u64::from(fallback.primary_fallback_pixels),
            twin.overflow_pixels,
            "{v}: pixels that ran out, GPU vs CPU twin"
        );
        assert_eq!(per_ray.primary_fallback_pixels, 0, "{v}");
        assert_eq!(mft.primary_fallback_pixels, 0, "{v}");
        assert_eq!(
            fallback.gbuffer, per_ray.gbuffer,
            "{v}: fallback G-buffer vs per-ray"
        );
        assert_eq!(fallback.masks, per_ray.masks, "{v}: fallback masks vs per-ray");
        let primary_dispatches =
            |f: &penumbra::gpu::Frame| f.timings.iter().filter(|(n, _)| n == "primary").count();
        if !per_ray.timings.is_empty() {
            assert_eq!(primary_dispatches(&per_ray), 1, "{v}");
            assert_eq!(
                primary_dispatches(&fallback),
                2,
                "{v}: both primary dispatches are timed"
            );
        }
        eprintln!(
            "{v}: budget {budget}: {} of {} pixels ran out; per-ray fallback = per-ray frame",
            fallback.primary_fallback_pixels,
            w * h
        );
    }
}

/// A budget far above lavapipe's loop limit on camera rays that need more passes than the
/// limit (200,000 near misses before the blocker, [`near_miss_column`], seen from above):
/// where the driver ends the loop, the pass reports an error naming the pass; where it
/// does not, every pixel sees the blocker, as in the CPU twin. Never a silent miss.
#[test]
fn a_loop_the_driver_ends_is_an_error_never_a_wrong_gbuffer() {
    let scene = scene_from_triangles(&near_miss_column(200_000, 0.5), &[[0.8; 3], [0.3; 3]]);
    let camera = Camera {
        eye: Vec3::new(0.0, 12.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        fov_y_degrees: 0.2,
    };
    let case = Case::new(
        "near-miss column",
        scene,
        &camera,
        &BvhSettings::default(),
        (16, 16),
    );
    let twin = penumbra::reference::primary::primary_gbuffer(&case.bvh, &case.shading(), &case.cam);
    let blocker: Vec<u32> = (0..case.bvh.triangles.len() as u32)
        .filter(|&i| (2..4).contains(&case.bvh.triangles[i as usize].scene_index))
        .collect();
    assert!(
        twin.iter().all(|t| blocker.contains(&t.triangle)),
        "every CPU camera ray hits the blocker"
    );
    let mut runs = vec![(PrimaryTracer::PerRay, None)];
    runs.extend(variants().into_iter().map(|v| (PrimaryTracer::Mft, Some(v))));
    for (tracer, variant) in runs {
        let pass = PrimaryPass::new(
            ctx(),
            &PrimaryOptions {
                tracer,
                variant,
                iteration_budget: 1 << 30,
                ..PrimaryOptions::default()
            },
        )
        .unwrap();
        let label = format!("{tracer:?} {variant:?}");
        let (gbuffer, result) = gpu_gbuffer(&pass, &case);
        match result {
            Err(e) => {
                let message = e.to_string();
                eprintln!("{label}: {message}");
                assert!(
                    message.contains("primary pass") && message.contains("ended"),
                    "{label}: the error must name the pass and say its loop was ended: {message}"
                );
            }
            Ok(_) => {
                eprintln!("{label}: the driver did not end the loop");
                let wrong = gbuffer
                    .iter()
                    .zip(&twin)
                    .filter(|(g, t)| g.triangle != t.triangle)
                    .count();
                assert_eq!(wrong, 0, "{label}: {wrong} texels from a traversal cut short");
            }
        }
    }
}
