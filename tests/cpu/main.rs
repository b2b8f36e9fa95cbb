//! CPU tests: the loaders, the BVH, the CPU oracles and twins against each other and closed forms; no GPU needed.

#[path = "../support/mod.rs"]
mod support;

mod assets;
mod bvh;
#[cfg(feature = "embree")]
mod embree;
mod exact_visibility;
mod metrics;
mod refit;
mod scene_loader;
mod shadow_mft;
mod views;
