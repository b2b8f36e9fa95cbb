//! penumbra: ray-traced soft shadows from area lights with multi-frusta tracing
//! (Benthin & Wald, HPG 2009) on wgpu.
//!
//! The pipeline: [`scene::Scene::load`] reads a glTF file into world-space
//! triangles, [`bvh::Bvh::build`] builds a BVH of 32-byte nodes with triangles
//! in leaf order, the GPU kernels trace it, and [`reference`](mod@reference) traces rays
//! over exactly the data the GPU reads (it is the oracle for every GPU kernel). What both
//! sides share — layouts, uniforms, constants — is [`contract`]; the README's
//! "Architecture" section maps the folders to the pipeline's stages.
//!
//! On the GPU, [`gpu::Renderer`] renders whole frames; an application with its own wgpu
//! device adds the soft shadows to its frame with [`gpu::ShadowPass`] (see [`gpu::embed`]
//! and `examples/embed/`), and moves objects with [`gpu::GpuScene::set_transforms`].
//!
//! Rendering the built-in scene's soft shadows on the GPU and writing the image (what
//! `penumbra render` does; on a machine without a GPU, lavapipe runs it):
//!
//! ```
//! use penumbra::gpu::{FrameSettings, GpuContext, GpuOptions, GpuScene, Renderer, RendererOptions};
//! use penumbra::output::{HdrImage, ToneMap, write_image};
//! use penumbra::{assets, bvh::{Bvh, BvhSettings}, scene::Scene};
//!
//! let default = assets::default_scene();
//! let scene = Scene::from_bytes(default.glb, std::path::Path::new(default.file_name))?;
//! let bvh = Bvh::build(&scene, &BvhSettings::default())?;
//! let ctx = GpuContext::new(&GpuOptions::default())?; // an error naming the cause without an adapter
//! let gpu_scene = GpuScene::new(&ctx, &scene, &bvh)?;
//! let renderer = Renderer::new(&ctx, RendererOptions::default())?;
//! let frame = renderer.render(&ctx, &gpu_scene, &default.view(), &FrameSettings::new(128, 96))?;
//! let image = HdrImage { width: frame.width, height: frame.height, pixels: frame.radiance() };
//! let path = std::env::temp_dir().join(format!("penumbra-doc-{}.png", std::process::id()));
//! write_image(&path, &image, &ToneMap::default())?; // whole or not at all
//! # std::fs::remove_file(&path).ok();
//! # Ok::<(), penumbra::Error>(())
//! ```
//!
//! The CPU side is public too: the oracles trace the same data, ray by ray.
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
pub mod contract;
#[cfg(feature = "embree")]
pub mod embree;
mod error;
pub mod gpu;
pub mod output;
pub mod pass_inputs;
pub mod quality;
pub mod reference;
pub mod sampling;
pub mod scene;
pub mod shaders;

pub use error::{Error, Result};

#[cfg(test)]
mod tests {
    /// Every `src/…`, `shaders/…`, `tests/…` and `examples/…` path named in a comment of
    /// a Rust or WGSL file, or in the README, exists (a file, or a folder when it ends in
    /// `/`): comments that point newcomers to files must not point at removed ones.
    #[test]
    fn paths_named_in_comments_exist() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut files = vec![root.join("README.md")];
        let mut dirs: Vec<_> = ["src", "shaders", "tests", "examples"]
            .iter()
            .map(|d| root.join(d))
            .collect();
        while let Some(dir) = dirs.pop() {
            for entry in std::fs::read_dir(&dir).unwrap() {
                let path = entry.unwrap().path();
                if path.is_dir() {
                    dirs.push(path);
                } else if path.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
                    files.push(path);
                }
            }
        }
        let mut missing = Vec::new();
        for file in &files {
            let text = std::fs::read_to_string(file).unwrap();
            let readme = file.extension().is_some_and(|e| e == "md");
            for (n, line) in text.lines().enumerate() {
                if !readme && !line.trim_start().starts_with("//") {
                    continue;
                }
                for start in ["src/", "shaders/", "tests/", "examples/"] {
                    for (i, _) in line.match_indices(start) {
                        // A path starts the word: not `../shared/scenes/…` nor `foo_tests/`.
                        let before = line[..i].chars().next_back();
                        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '.' || c == '/') {
                            continue;
                        }
                        let path: String = line[i..]
                            .chars()
                            .take_while(|c| c.is_alphanumeric() || "_-./".contains(*c))
                            .collect();
                        let path = path.trim_end_matches('.');
                        let is_file = [".rs", ".wgsl", ".md", ".png", ".json", ".glb"]
                            .iter()
                            .any(|e| path.ends_with(e));
                        if (is_file || path.ends_with('/')) && !root.join(path).exists() {
                            missing.push(format!(
                                "{}:{}: {path}",
                                file.strip_prefix(root).unwrap().display(),
                                n + 1
                            ));
                        }
                    }
                }
            }
        }
        assert!(
            missing.is_empty(),
            "paths named in comments that do not exist:\n{}",
            missing.join("\n")
        );
    }
}
