//! GPU test helpers: one context per test binary, the variants it can run,
//! and the built-in scenes.

use std::path::Path;
use std::sync::OnceLock;

use penumbra::gpu::{GpuContext, GpuOptions, LeafMode, ShadowTracer, Tracer, TracerOptions, VectorVariant};
use penumbra::{assets, scene::Scene, scene::view::View};

/// One context per test binary; a missing adapter fails every test with the reason.
pub fn ctx() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| {
        let ctx = GpuContext::new(&GpuOptions::default())
            .unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
        eprintln!("adapter: {}", ctx.info);
        refuse_a_shared_lavapipe_cache(&ctx);
        ctx
    })
}

/// Fails the tests where lavapipe runs at a vector width set in the environment with Mesa's
/// default shader cache: processes at other widths share that cache, and Mesa 25.0 then hands
/// this one texel-fetch functions compiled for another width (wrong texels or SIGSEGV; see
/// `lavapipe_shader_cache_dir`). The binaries do not set the variable themselves, because
/// other test threads run by then.
fn refuse_a_shared_lavapipe_cache(ctx: &GpuContext) {
    if ctx.info.driver != "llvmpipe" {
        return;
    }
    if let Some(dir) = penumbra::gpu::lavapipe_shader_cache_dir() {
        panic!(
            "{} is set but {} is not: run the GPU tests at this lavapipe width with a shader \
             cache of their own, e.g. {}={} (Mesa 25.0 shares cached texel fetches between \
             widths and then reads wrong texels)",
            penumbra::gpu::LAVAPIPE_VECTOR_WIDTH_ENV,
            penumbra::gpu::SHADER_CACHE_DIR_ENV,
            penumbra::gpu::SHADER_CACHE_DIR_ENV,
            dir.display()
        );
    }
}

/// Set (to anything) where the adapter must have ray queries (`.ci/run` on Mesa 25
/// lavapipe): then [`ray_query_ctx`] fails instead of answering `None`.
pub const REQUIRE_RAY_QUERY_ENV: &str = "PENUMBRA_REQUIRE_RAY_QUERY";

/// A second context on the same adapter, made with ray queries; `Err` with the error's
/// one-line message (which tests check) when the adapter has none, unless
/// [`REQUIRE_RAY_QUERY_ENV`] is set; any other error fails the test.
#[allow(dead_code)]
pub fn ray_query_ctx() -> Result<&'static GpuContext, &'static str> {
    static CTX: OnceLock<Result<GpuContext, String>> = OnceLock::new();
    let made = CTX.get_or_init(|| {
        match GpuContext::new(&GpuOptions {
            ray_query: true,
            ..GpuOptions::default()
        }) {
            Ok(ctx) => Ok(ctx),
            Err(e @ penumbra::Error::RayQueryUnsupported { .. }) => Err(e.to_string()),
            Err(e) => panic!("a context with ray queries: {e}"),
        }
    });
    match made {
        Ok(ctx) => Ok(ctx),
        Err(e) => {
            assert!(
                std::env::var_os(REQUIRE_RAY_QUERY_ENV).is_none(),
                "{REQUIRE_RAY_QUERY_ENV} is set, but: {e}"
            );
            Err(e)
        }
    }
}

/// Set to a comma-separated list of variant names (`workgroup`, `workgroup4`, `subgroup`,
/// `subgroup-reduce`) to test only those of [`variants`]. `.ci/run` tests every variant at
/// 8 lanes on both drivers and at 16 lanes on Mesa 22.3, and only the variant each remaining
/// run is for elsewhere (`subgroup-reduce` at 16 lanes on Mesa 25.0, whose cold compiles were
/// most of the CI's time; `subgroup` at 32 lanes).
pub const TEST_VARIANTS_ENV: &str = "PENUMBRA_TEST_VARIANTS";

/// The variants this adapter can run: always workgroup (one vector and four per workgroup),
/// subgroup with broadcasts and with reductions when it has fixed 16k-wide subgroups; only
/// those named in [`TEST_VARIANTS_ENV`] where it is set (a name the adapter cannot run, or
/// none left, fails the test).
pub fn variants() -> Vec<VectorVariant> {
    let mut v = vec![VectorVariant::Workgroup, VectorVariant::Workgroup4];
    if VectorVariant::choose(&ctx().info, Some(VectorVariant::Subgroup)).is_ok() {
        v.push(VectorVariant::Subgroup);
        v.push(VectorVariant::SubgroupReduce);
    }
    let Some(wanted) = std::env::var_os(TEST_VARIANTS_ENV) else {
        return v;
    };
    let wanted = wanted.to_string_lossy().into_owned();
    let names: Vec<&str> = wanted
        .split(',')
        .map(str::trim)
        .filter(|n| !n.is_empty())
        .collect();
    for name in &names {
        assert!(
            v.iter().any(|x| x.to_string() == *name),
            "{TEST_VARIANTS_ENV} names {name:?}, which is not one of the variants {} can run: {v:?}",
            ctx().info.name
        );
    }
    v.retain(|x| names.contains(&x.to_string().as_str()));
    assert!(
        !v.is_empty(),
        "{TEST_VARIANTS_ENV}={wanted:?} leaves no variant to test"
    );
    v
}

/// A built-in scene and its view.
pub fn embedded(name: &str) -> (Scene, View) {
    let s = assets::embedded_scene(name).expect("a built-in scene");
    (
        Scene::from_bytes(s.glb, Path::new(s.file_name)).expect("built-in scenes load"),
        s.view(),
    )
}

/// Runs `pass` alone over a G-buffer the test already has: uploads `texels` and the
/// view's 256 light points, traces with `params`, and returns the masks and statistics.
#[allow(dead_code)] // not every test binary that includes support/ traces directly
pub fn trace_masks(
    pass: &penumbra::gpu::ShadowTracer,
    gpu_scene: &penumbra::gpu::GpuScene,
    texels: &[penumbra::contract::layout::GBufferTexel],
    view: &View,
    params: &penumbra::contract::layout::ShadowParams,
) -> (Vec<u32>, penumbra::gpu::ShadowStats) {
    try_trace_masks(pass, gpu_scene, texels, view, params).unwrap()
}

/// [`trace_masks`], with the pass's error returned instead of a panic.
#[allow(dead_code)]
pub fn try_trace_masks(
    pass: &penumbra::gpu::ShadowTracer,
    gpu_scene: &penumbra::gpu::GpuScene,
    texels: &[penumbra::contract::layout::GBufferTexel],
    view: &View,
    params: &penumbra::contract::layout::ShadowParams,
) -> penumbra::Result<(Vec<u32>, penumbra::gpu::ShadowStats)> {
    try_trace_masks_on(ctx(), pass, gpu_scene, texels, view, params)
}

/// [`try_trace_masks`] on the device `ctx` (which made `pass` and `gpu_scene`).
#[allow(dead_code)]
pub fn try_trace_masks_on(
    ctx: &GpuContext,
    pass: &penumbra::gpu::ShadowTracer,
    gpu_scene: &penumbra::gpu::GpuScene,
    texels: &[penumbra::contract::layout::GBufferTexel],
    view: &View,
    params: &penumbra::contract::layout::ShadowParams,
) -> penumbra::Result<(Vec<u32>, penumbra::gpu::ShadowStats)> {
    use penumbra::gpu::{empty_storage_buffer, read_buffer, storage_buffer};
    let gbuffer = storage_buffer(ctx, "G-buffer", texels, wgpu::BufferUsages::empty())?;
    let light_points = pass.light_points_buffer(&ctx.device, &view.light);
    let bytes = u64::from(params.width * params.height) * 4;
    let masks = empty_storage_buffer(
        ctx,
        "masks",
        bytes,
        wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
    )?;
    let image = penumbra::gpu::ShadowImage {
        gbuffer: &gbuffer,
        light_points: &light_points,
        masks: &masks,
    };
    let stats = pass.run(ctx, gpu_scene, &image, params, None, "shadow", &mut |_, _| {})?;
    Ok((read_buffer(ctx, &masks, 0..bytes)?, stats))
}

/// Whether this adapter's f32 arithmetic is compared exactly: on lavapipe (llvmpipe) two
/// pipelines that compute the same expressions (the two vector variants, the two leaf
/// modes) and the CPU twins give the same bits — the exact comparisons below hold there,
/// on 8- and 16-wide builds, Mesa 22.3 and 25.0. Another driver may contract `a * b + c`
/// into a fused multiply-add in one pipeline and not in the other (Rust never does),
/// which moves a result by an ulp and can flip a ray that grazes an edge or a box; there
/// the tests compare within the oracle comparison's tolerance instead
/// ([`super::compare_masks`] at [`super::edge_tolerance`], ≤ 0.1 % of the rays). One
/// pipeline run twice, or over tiles, computes the same bits on any adapter and stays
/// exact everywhere.
#[allow(dead_code)]
pub fn exact_arithmetic() -> bool {
    ctx().info.name.contains("llvmpipe")
}

/// Asserts that two tracings of the same rays agree: bit for bit where
/// [`exact_arithmetic`], else ray for ray within the oracle comparison's tolerance.
#[allow(dead_code, clippy::too_many_arguments)]
pub fn assert_same_rays(
    label: &str,
    a: &[u32],
    b: &[u32],
    scene: &Scene,
    bvh: &penumbra::bvh::Bvh,
    view: &View,
    gbuffer: &[penumbra::contract::layout::GBufferTexel],
    width: u32,
) {
    if exact_arithmetic() {
        assert_eq!(a, b, "{label}: masks differ");
        return;
    }
    let c = super::compare_view_masks(a, b, scene, bvh, view, gbuffer, width);
    eprintln!("{label}: not compared bit for bit on {}: {c}", ctx().info.name);
    assert!(
        c.unexplained.is_empty() && c.differing * 1000 <= c.total,
        "{label}: {c}"
    );
}

/// Every shadow tracer configuration a test runs: MFT with both leaf modes, packet and
/// per-ray, each vector tracer in every variant this adapter has.
#[allow(dead_code)]
pub fn every_tracer() -> Vec<(Tracer, LeafMode, VectorVariant)> {
    let mut out = vec![(Tracer::PerRay, LeafMode::PerLane, VectorVariant::Workgroup)];
    for variant in variants() {
        out.push((Tracer::Mft, LeafMode::PerLane, variant));
        out.push((Tracer::Mft, LeafMode::Transposed, variant));
        out.push((Tracer::Packet, LeafMode::PerLane, variant));
    }
    out
}

/// The shadow pass of one tracer, leaf mode and vector variant, otherwise by default.
#[allow(dead_code)]
pub fn shadow_tracer(tracer: Tracer, leaf_mode: LeafMode, variant: VectorVariant) -> ShadowTracer {
    let options = TracerOptions {
        tracer,
        variant: Some(variant),
        leaf_mode,
        ..TracerOptions::default()
    };
    ShadowTracer::new(ctx(), &options).unwrap()
}
