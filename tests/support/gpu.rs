//! GPU test helpers: one context per test binary, the variants it can run,
//! and the built-in scenes.

use std::path::Path;
use std::sync::OnceLock;

use penumbra::gpu::{GpuContext, GpuOptions, VectorVariant};
use penumbra::{assets, scene::Scene, view::View};

/// One context per test binary; a missing adapter fails every test with the reason.
pub fn ctx() -> &'static GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| {
        let ctx = GpuContext::new(&GpuOptions::default())
            .unwrap_or_else(|e| panic!("GPU tests need an adapter: {e}"));
        eprintln!("adapter: {}", ctx.info);
        ctx
    })
}

/// The variants this adapter can run: always workgroup, subgroup when it has fixed 16k-wide subgroups.
pub fn variants() -> Vec<VectorVariant> {
    let mut v = vec![VectorVariant::Workgroup];
    if VectorVariant::choose(&ctx().info, Some(VectorVariant::Subgroup)).is_ok() {
        v.push(VectorVariant::Subgroup);
    }
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
    texels: &[penumbra::layout::GBufferTexel],
    view: &View,
    params: &penumbra::layout::ShadowParams,
) -> (Vec<u32>, penumbra::gpu::ShadowStats) {
    use penumbra::gpu::{empty_storage_buffer, read_buffer, storage_buffer};
    let points: Vec<[f32; 4]> = penumbra::sampling::light_points(&view.light)
        .iter()
        .map(|p| p.extend(0.0).to_array())
        .collect();
    let usage = wgpu::BufferUsages::empty();
    let gbuffer = storage_buffer(ctx(), "G-buffer", texels, usage).unwrap();
    let light_points = storage_buffer(ctx(), "light points", &points, usage).unwrap();
    let bytes = u64::from(params.width * params.height) * 4;
    let masks = empty_storage_buffer(ctx(), "masks", bytes, wgpu::BufferUsages::COPY_SRC).unwrap();
    let stats = pass
        .run(
            ctx(),
            gpu_scene,
            &gbuffer,
            &light_points,
            &masks,
            params,
            None,
            &mut |_, _| {},
        )
        .unwrap();
    (read_buffer(ctx(), &masks, 0..bytes).unwrap(), stats)
}
