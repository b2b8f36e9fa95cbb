//! Compares the obvhs build presets and leaf sizes on the scenes in
//! `../shared/scenes` (and the built-in ones): build time (min of 3) against
//! SAH cost and measured CPU traversal speed of the reference tracer.
//!
//! `cargo run --release --example bvh_builders [SCENE...]`

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use penumbra::bvh::{BuildQuality, Bvh, BvhSettings};
use penumbra::{assets, reference, scene::Scene};

/// Rays from points spread over the scene bounds toward points on random
/// triangles (a mix of hits and occluded segments, like shadow rays).
fn rays(scene: &Scene, n: usize) -> Vec<(Vec3, Vec3)> {
    let b = scene.bounds();
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .map(|_| {
            let o = b.min + (b.max - b.min) * Vec3::new(next(), next(), next());
            let t =
                &scene.triangles[(next() * scene.triangles.len() as f32) as usize % scene.triangles.len()];
            let (u, v) = (next() * 0.5, next() * 0.5);
            let target = t.positions[0]
                + u * (t.positions[1] - t.positions[0])
                + v * (t.positions[2] - t.positions[0]);
            (o, target - o)
        })
        .collect()
}

fn main() -> penumbra::Result<()> {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    let mut scenes: Vec<Scene> = Vec::new();
    if args.is_empty() {
        for s in assets::EMBEDDED_SCENES {
            scenes.push(Scene::from_bytes(s.glb, Path::new(s.file_name))?);
        }
        let shared = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes");
        let mut files: Vec<PathBuf> = std::fs::read_dir(&shared)
            .into_iter()
            .flatten()
            .flatten()
            .flat_map(|d| std::fs::read_dir(d.path()).into_iter().flatten().flatten())
            .map(|e| e.path())
            .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("gltf" | "glb")))
            .collect();
        files.sort();
        for f in files {
            scenes.push(Scene::load(&f)?);
        }
    } else {
        for f in &args {
            scenes.push(Scene::load(f)?);
        }
    }
    println!(
        "{:<28} {:>7} {:>5} {:>9} {:>8} {:>8} {:>10}",
        "scene", "quality", "leaf", "build ms", "nodes", "SAH", "Mrays/s"
    );
    for scene in &scenes {
        let name = scene
            .source
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let rays = rays(scene, 100_000);
        for quality in [BuildQuality::Fast, BuildQuality::Medium, BuildQuality::High] {
            for leaf in [1, 4, 8] {
                let settings = BvhSettings {
                    max_leaf_size: leaf,
                    quality,
                };
                let mut best_ms = f64::INFINITY;
                let mut bvh = None;
                for _ in 0..3 {
                    let b = Bvh::build(scene, &settings)?;
                    best_ms = best_ms.min(b.build_time.as_secs_f64() * 1e3);
                    bvh = Some(b);
                }
                let bvh = bvh.expect("built three times");
                let start = Instant::now();
                let hits = rays
                    .iter()
                    .filter(|(o, d)| reference::any_hit(&bvh, *o, *d, 0.999))
                    .count();
                let secs = start.elapsed().as_secs_f64();
                std::hint::black_box(hits);
                let stats = bvh.stats();
                println!(
                    "{:<28} {:>7} {:>5} {:>9.2} {:>8} {:>8.2} {:>10.2}",
                    name,
                    format!("{quality:?}"),
                    leaf,
                    best_ms,
                    stats.nodes,
                    stats.sah_cost,
                    rays.len() as f64 / secs / 1e6
                );
            }
        }
    }
    Ok(())
}
