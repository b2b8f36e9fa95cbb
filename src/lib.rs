//! penumbra: ray-traced soft shadows from area lights with multi-frusta tracing
//! (Benthin & Wald, HPG 2009) on wgpu.
//!
//! The pipeline: [`scene::Scene::load`] reads a glTF file into world-space
//! triangles, [`bvh::Bvh::build`] builds a BVH of 32-byte nodes with triangles
//! in leaf order, and [`reference`](mod@reference) traces rays over exactly the data the GPU
//! reads (it is the oracle for every GPU kernel).
//!
//! On the GPU, [`gpu::Renderer`] renders whole frames; an application with its own wgpu
//! device adds the soft shadows to its frame with [`gpu::ShadowPass`] (see [`gpu::embed`]
//! and `examples/embed.rs`), and moves objects with [`gpu::GpuScene::set_transforms`].
//!
//! ```
//! use penumbra::{assets, bvh::{Bvh, BvhSettings}, reference, scene::Scene};
//! use glam::Vec3;
//!
//! let default = assets::default_scene();
//! let scene = Scene::from_bytes(default.glb, std::path::Path::new(default.file_name))?;
//! let bvh = Bvh::build(&scene, &BvhSettings::default())?;
//! let hit = reference::closest_hit(&bvh, Vec3::new(0.0, 5.0, 0.0), Vec3::NEG_Y, f32::INFINITY);
//! assert!(hit.is_some(), "looking down from above hits the ground");
//! # Ok::<(), penumbra::Error>(())
//! ```

pub mod assets;
pub mod bvh;
pub mod counters;
mod error;
pub mod error_regions;
pub mod filter;
pub mod frame;
pub mod gpu;
pub mod layout;
pub mod metrics;
pub mod output;
pub mod reference;
pub mod sampling;
pub mod scene;
pub mod shaders;
pub mod view;
pub mod view_checks;

pub use error::{Error, Result};
