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
