//! `penumbra info`: what a scene holds and what its BVH looks like.

use std::path::PathBuf;
use std::time::Instant;

use penumbra::bvh::Bvh;

use super::BvhArgs;
use super::scene_arg::{builtin_names, load_scene};

/// Arguments of `penumbra info`.
#[derive(Debug, clap::Args)]
pub struct InfoArgs {
    /// glTF (.gltf/.glb) file, or a built-in scene name; default: the built-in default scene.
    #[arg(value_name = "SCENE", long_help = format!(
        "glTF 2.0 file (.gltf or .glb), or the name of a built-in scene ({}). \
         Without it, the built-in default scene.", builtin_names()))]
    scene: Option<PathBuf>,
    #[command(flatten)]
    bvh: BvhArgs,
}

/// Prints scene and BVH statistics.
pub fn run(args: &InfoArgs) -> penumbra::Result<()> {
    let start = Instant::now();
    let scene = load_scene(args.scene.as_deref())?;
    let load_ms = start.elapsed().as_secs_f64() * 1e3;
    let settings = args.bvh.settings();
    let bvh = Bvh::build(&scene, &settings)?;
    let stats = bvh.stats();
    let bounds = scene.bounds();

    println!("scene        {}", scene.source.display());
    println!("load         {load_ms:.1} ms");
    println!("triangles    {}", scene.triangles.len());
    for w in scene.warnings.messages() {
        println!("warning      {w}");
    }
    println!("materials    {}", scene.materials.len());
    println!("images       {}", scene.images.len());
    println!("instances    {}", scene.instances.len());
    match &scene.camera {
        Some(c) => println!(
            "camera       eye {:?} target {:?} fov {:.2}°",
            c.eye.to_array(),
            c.target.to_array(),
            c.fov_y_degrees
        ),
        None => println!("camera       none"),
    }
    println!(
        "bounds       min {:?} max {:?}",
        bounds.min.to_array(),
        bounds.max.to_array()
    );
    println!(
        "BVH          quality {:?}, max leaf size {}",
        settings.quality, settings.max_leaf_size
    );
    println!("  build      {:.2} ms", bvh.build_time.as_secs_f64() * 1e3);
    println!("  nodes      {}", stats.nodes);
    println!("  leaves     {}", stats.leaves);
    let hist: Vec<String> = stats
        .leaf_size_histogram
        .iter()
        .map(|(k, v)| format!("{k}:{v}"))
        .collect();
    println!("  leaf sizes {}", hist.join(" "));
    println!("  max depth  {}", stats.max_depth);
    println!("  SAH cost   {:.2}", stats.sah_cost);
    println!("  GPU bytes  {} (nodes + triangles)", stats.gpu_bytes);
    Ok(())
}
