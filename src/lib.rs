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
//! and `examples/embed/`), and moves objects with [`gpu::GpuScene::set_transforms`].
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
