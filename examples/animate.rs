//! Moving objects, measured: one instance circles and spins through a scene; per frame
//! the GPU scene is refitted (or rebuilt when the tree degrades) and the changed ranges
//! uploaded. Prints refit/rebuild, upload and flush milliseconds.
//!
//! ```text
//! cargo run --release --example animate -- [SCENE] [FRAMES] [REBUILD_RATIO]
//! ```
//!
//! SCENE: a built-in scene name or a glTF file (default: the default scene); FRAMES:
//! default 120; REBUILD_RATIO: [`MotionSettings::rebuild_ratio`] (default 1.3; 0 rebuilds
//! every frame).

use std::path::Path;

use penumbra::assets;
use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::animate::{animate_instance, default_moving_instance};
use penumbra::gpu::{GpuContext, GpuOptions, MotionSettings};
use penumbra::scene::Scene;

fn main() {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists.
    unsafe { penumbra::gpu::set_driver_defaults() };
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or(assets::default_scene().name, String::as_str);
    let frames: u32 = args.get(1).map_or(Ok(120), |s| s.parse())?;
    let mut settings = MotionSettings::default();
    if let Some(r) = args.get(2) {
        settings.rebuild_ratio = r.parse()?;
    }
    let scene = match assets::embedded_scene(name) {
        Some(s) => Scene::from_bytes(s.glb, Path::new(s.file_name))?,
        None => Scene::load(Path::new(name))?,
    };
    let instance =
        default_moving_instance(&scene).ok_or("the scene has no instance smaller than itself to move")?;
    let ctx = GpuContext::new(&GpuOptions::default())?;
    let bvh = Bvh::build(&scene, &BvhSettings::default())?;
    let report = animate_instance(&ctx, &scene, &bvh, instance, frames, settings)?;
    let who = scene.instances[instance as usize]
        .name
        .as_deref()
        .unwrap_or("unnamed");
    println!("{name}: moving '{who}' on {}", ctx.info.name);
    println!("{}", report.summary());
    Ok(())
}
