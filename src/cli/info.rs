//! `penumbra info`: what a scene holds and what its BVH looks like.

use std::path::PathBuf;
use std::time::Instant;

use penumbra::bvh::Bvh;
use penumbra::gpu::memory;
use penumbra::pass_inputs::texture_dimensions;
use penumbra::scene::Scene;

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
    /// Image size WIDTHxHEIGHT for the per-frame GPU memory estimate.
    #[arg(long, default_value = "1024x1024", value_parser = super::parse_size)]
    size: (u32, u32),
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

    outln!("scene        {}", scene.source.display());
    outln!("load         {load_ms:.1} ms");
    outln!("triangles    {}", scene.triangles.len());
    for w in scene.warnings.messages() {
        outln!("warning      {w}");
    }
    outln!("materials    {}", scene.materials.len());
    outln!("images       {}", scene.images.len());
    outln!("instances    {}", scene.instances.len());
    let emitters = super::scene_arg::file_lights(&scene);
    outln!(
        "lights       {} emissive quad(s) in the file (used when no view file is given)",
        emitters.lights.len()
    );
    for l in &emitters.lights {
        outln!(
            "  quad       centre {:?} size {:.3} × {:.3} radiance {:?}",
            (l.corner + 0.5 * (l.edge_u + l.edge_v)).to_array(),
            l.edge_u.length(),
            l.edge_v.length(),
            (l.color * l.intensity).to_array()
        );
    }
    for why in &emitters.unusable {
        outln!("  unusable   emissive geometry of {why}");
    }
    match &scene.camera {
        Some(c) => outln!(
            "camera       eye {:?} target {:?} fov {:.2}°",
            c.eye.to_array(),
            c.target.to_array(),
            c.fov_y_degrees
        ),
        None => outln!("camera       none"),
    }
    outln!(
        "bounds       min {:?} max {:?}",
        bounds.min.to_array(),
        bounds.max.to_array()
    );
    outln!(
        "BVH          quality {:?}, max leaf size {}",
        settings.quality,
        settings.max_leaf_size
    );
    outln!("  build      {:.2} ms", bvh.build_time.as_secs_f64() * 1e3);
    outln!("  nodes      {}", stats.nodes);
    outln!("  leaves     {}", stats.leaves);
    let hist: Vec<String> = stats
        .leaf_size_histogram
        .iter()
        .map(|(k, v)| format!("{k}:{v}"))
        .collect();
    outln!("  leaf sizes {}", hist.join(" "));
    outln!("  max depth  {}", stats.max_depth);
    outln!("  SAH cost   {:.2}", stats.sah_cost);
    outln!("  GPU bytes  {} (nodes + triangles)", stats.gpu_bytes);
    outln!(
        "  alpha      {} alpha-tested triangle(s) (MASK, or BLEND at cutoff {}), {} word(s) of masks",
        bvh.alpha.triangles,
        penumbra::contract::alpha::BLEND_ALPHA_CUTOFF,
        bvh.alpha.words.len()
    );
    print_memory(&scene, &bvh, args.size);
    Ok(())
}

/// The GPU memory of the scene's buffers and of one frame of `size`.
fn print_memory(scene: &Scene, bvh: &Bvh, (width, height): (u32, u32)) {
    let mut texels = 0u64;
    for i in 0..scene.images.len() {
        // Only the headers are read; a texture that cannot be read is reported
        // here and fails a render, which decodes every texture.
        match texture_dimensions(scene, i) {
            Ok((w, h)) => texels += u64::from(w) * u64::from(h),
            Err(e) => outln!("warning      {e}; not counted below"),
        }
    }
    let list = |buffers: &[memory::BufferSize]| {
        buffers
            .iter()
            .map(|b| format!("{} {}", b.label, memory::format_bytes(b.bytes)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let scene_buffers = memory::scene_buffers(&memory::SceneCounts::new(scene, bvh, texels));
    let frame_buffers = memory::frame_buffers(width, height);
    outln!("GPU memory");
    outln!(
        "  scene      {} ({})",
        memory::format_bytes(memory::total_bytes(&scene_buffers)),
        list(&scene_buffers)
    );
    outln!(
        "  frame      {} for {width}x{height} ({})",
        memory::format_bytes(memory::total_bytes(&frame_buffers)),
        list(&frame_buffers)
    );
    if let Some(big) = memory::largest(
        &scene_buffers
            .iter()
            .chain(&frame_buffers)
            .copied()
            .collect::<Vec<_>>(),
    ) {
        outln!(
            "  largest    {} {} (must fit the adapter's storage-buffer binding limit)",
            big.label,
            memory::format_bytes(big.bytes)
        );
    }
}
