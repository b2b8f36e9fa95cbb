//! How far from the origin a scene can sit before its shadows change: renders a scene
//! at the origin and moved by 1e5 and 1e6 along x and z (view alike), with every shadow
//! tracer, and prints per pixel how the unfiltered visibility differs from the render at
//! the origin ("moved"). "re-centred" renders the far scene's own geometry (rounded to
//! f32 out there) moved back to the origin: what is left is that rounding, which no
//! renderer can undo (the floor for any fix); "moved vs re-centred" compares the two, so
//! it shows only what the arithmetic far from the origin adds.
//!
//! `cargo run --release --example far_from_origin -- [SCENE VIEW] [SIZE] [SCALE]`
//! (built-in playground by default; SCALE multiplies the scene's size first), e.g.
//! `LP_NATIVE_VECTOR_WIDTH=512 cargo run --release --example far_from_origin --
//! ../shared/scenes/dabrovic_sponza/sponza.gltf assets/views/sponza-atrium.json 512`

use std::path::Path;
use std::time::Instant;

use glam::Vec3;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{FrameSettings, GpuContext, GpuOptions, GpuScene, Renderer, RendererOptions, Tracer};
use penumbra::reference::visibility::visibility;
use penumbra::scene::Scene;
use penumbra::scene::view::View;

fn main() -> penumbra::Result<()> {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists.
    unsafe { penumbra::gpu::set_driver_defaults() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (mut scene, mut view, rest) = match args.as_slice() {
        [s, v, rest @ ..] if !s.chars().all(|c| c.is_ascii_digit() || c == '.') => {
            (Scene::load(Path::new(s))?, View::load(Path::new(v))?, rest)
        }
        rest => {
            let s = penumbra::assets::default_scene();
            (Scene::from_bytes(s.glb, Path::new(s.file_name))?, s.view(), rest)
        }
    };
    let size: u32 = rest
        .first()
        .map_or(Ok(256), |s| s.parse())
        .expect("SIZE is a number");
    let scale: f32 = rest
        .get(1)
        .map_or(Ok(1.0), |s| s.parse())
        .expect("SCALE is a number");
    for t in &mut scene.triangles {
        for p in &mut t.positions {
            *p *= scale;
        }
    }
    view.camera.eye *= scale;
    view.camera.target *= scale;
    view.light.corner *= scale;
    view.light.edge_u *= scale;
    view.light.edge_v *= scale;
    if let Some(y) = view.ground_y {
        scene.add_ground_plane(y * scale);
        view.ground_y = None;
    }
    let ctx = GpuContext::new(&GpuOptions::default())?;
    let b = scene.bounds();
    println!("adapter: {}", ctx.info);
    println!(
        "{}: {} triangles, bounds {:?}..{:?} (diagonal {:.1}), {size}x{size}, unfiltered visibility",
        scene.source.display(),
        scene.triangles.len(),
        b.min,
        b.max,
        b.diagonal()
    );
    let mut settings = FrameSettings::new(size, size);
    settings.filter = None;
    // `unmoved`: trace the scene where it lies (GpuScene::with_origin zero), as a host's
    // far world positions are; otherwise the renderer traces it relative to its centre.
    let render = |scene: &Scene, view: &View, tracer: Tracer, unmoved: bool| -> penumbra::Result<Vec<f32>> {
        let bvh = Bvh::build(scene, &BvhSettings::default())?;
        let gpu_scene = if unmoved {
            GpuScene::with_origin(&ctx, scene, &bvh, Vec3::ZERO)?
        } else {
            GpuScene::new(&ctx, scene, &bvh)?
        };
        let renderer = Renderer::new(
            &ctx,
            RendererOptions {
                tracer,
                ..RendererOptions::default()
            },
        )?;
        let frame = renderer.render(&ctx, &gpu_scene, view, &settings)?;
        Ok(frame.masks.iter().map(|&m| visibility(m)).collect())
    };
    println!(
        "{:<8} {:>7} {:<20} {:>13} {:>13} {:>8} {:>9}",
        "tracer", "offset", "scene", "px off >1/16", "px off >0.1", "RMSE", "speckles"
    );
    for tracer in [Tracer::Mft, Tracer::Packet, Tracer::PerRay] {
        let start = Instant::now();
        let near = render(&scene, &view, tracer, false)?;
        for offset in [1e5f32, 1e6] {
            let t = Vec3::new(offset, 0.0, offset);
            let mut moved = scene.clone();
            moved.translate(t);
            let mut recentred = moved.clone();
            recentred.translate(-t);
            let far = render(&moved, &view.translated(t), tracer, false)?;
            let unmoved = render(&moved, &view.translated(t), tracer, true)?;
            // The far scene's own (rounded) geometry and view, rendered at the origin.
            let stored = render(&recentred, &view.translated(t).translated(-t), tracer, false)?;
            for (name, a, b) in [
                ("moved", &near, &far),
                ("moved, unmoved BVH", &near, &unmoved),
                ("re-centred", &near, &stored),
                ("unmoved vs re-centred", &stored, &unmoved),
            ] {
                let n = a.len() as f64;
                let count = |tol: f32| a.iter().zip(b).filter(|(x, y)| (*x - *y).abs() > tol).count();
                let sq: f64 = a.iter().zip(b).map(|(x, y)| f64::from(x - y).powi(2)).sum();
                let (c1, c2) = (count(1.0 / 16.0), count(0.1));
                // Lit in the first, more than half dark in the second: rays that hit their own surface.
                let speckles = a.iter().zip(b).filter(|(x, y)| **x == 1.0 && **y < 0.5).count();
                println!(
                    "{:<8} {offset:>7.0e} {name:<20} {c1:>6} {:>5.2} % {c2:>6} {:>5.2} % {:>8.4} {speckles:>9}",
                    tracer.to_string(),
                    100.0 * c1 as f64 / n,
                    100.0 * c2 as f64 / n,
                    (sq / n).sqrt()
                );
            }
        }
        eprintln!("{tracer}: {:.1} s", start.elapsed().as_secs_f64());
    }
    Ok(())
}
