//! Times the primary pass with the per-ray and the multi-frusta kernel on one
//! scene and view (GPU timestamps, min / median of RUNS after a warm-up), then
//! runs each once more with its counters compiled in and prints them.
//!
//! `cargo run --release --example primary_tracers -- SCENE VIEW [SIZE] [RUNS] [LEAF]`
//! e.g. `LP_NATIVE_VECTOR_WIDTH=512 cargo run --release --example primary_tracers --
//! ../shared/scenes/dabrovic_sponza/sponza.gltf assets/views/sponza-atrium.json 512 3`

use std::path::PathBuf;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::gpu::{
    GpuContext, GpuOptions, GpuScene, GpuTimer, PrimaryOptions, PrimaryPass, PrimaryTracer,
    empty_storage_buffer,
};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, camera_params};
use penumbra::scene::Scene;
use penumbra::scene::view::View;

fn main() -> penumbra::Result<()> {
    // SAFETY: first thing in main, before any thread or Vulkan instance exists.
    unsafe { penumbra::gpu::set_driver_defaults() };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene_path, view_path, rest @ ..] = args.as_slice() else {
        eprintln!("usage: primary_tracers SCENE VIEW [SIZE] [RUNS] [LEAF]");
        std::process::exit(2);
    };
    let number = |i: usize, default: u32| rest.get(i).map_or(default, |s| s.parse().expect("a number"));
    let (size, runs, leaf) = (number(0, 512), number(1, 3).max(1), number(2, 4));
    let scene = Scene::load(&PathBuf::from(scene_path))?;
    let view = View::load(&PathBuf::from(view_path))?;
    let bvh = Bvh::build(
        &scene,
        &BvhSettings {
            max_leaf_size: leaf,
            ..BvhSettings::default()
        },
    )?;
    let ctx = GpuContext::new(&GpuOptions::default())?;
    println!("adapter: {}", ctx.info);
    println!(
        "{}: {} triangles, {} nodes, leaf size {leaf}; {size}x{size}, {runs} runs",
        scene_path,
        bvh.triangles.len(),
        bvh.nodes.len()
    );
    let gpu_scene = GpuScene::new(&ctx, &scene, &bvh)?;
    let cam = camera_params(
        &view.camera,
        size,
        size,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let bytes = u64::from(size * size) * size_of::<GBufferTexel>() as u64;
    let gbuffer = empty_storage_buffer(&ctx, "G-buffer", bytes, wgpu::BufferUsages::empty())?;
    let rays = f64::from(size * size);
    let tracers = [PrimaryTracer::PerRay, PrimaryTracer::Mft];
    let passes = tracers
        .iter()
        .map(|&t| {
            PrimaryPass::new(
                &ctx,
                &PrimaryOptions {
                    tracer: t,
                    ..PrimaryOptions::default()
                },
            )
        })
        .collect::<penumbra::Result<Vec<_>>>()?;
    for pass in &passes {
        pass.run(&ctx, &gpu_scene, &cam, &gbuffer, None)?.check()?; // warm-up: lavapipe compiles here
    }
    // Interleaved, so that both tracers see the same load on a shared machine.
    let mut ms = vec![Vec::new(); passes.len()];
    for _ in 0..runs {
        for (pass, ms) in passes.iter().zip(&mut ms) {
            let mut timer = GpuTimer::new(&ctx, 1);
            pass.run(&ctx, &gpu_scene, &cam, &gbuffer, Some(&mut timer))?
                .check()?;
            ms.extend(timer.read(&ctx)?.into_iter().map(|(_, t)| t));
        }
    }
    let ratios: Vec<f64> = ms[0].iter().zip(&ms[1]).map(|(p, m)| p / m).collect();
    for (pass, ms) in passes.iter().zip(&mut ms) {
        let tracer = pass.tracer();
        let all = ms.clone();
        ms.sort_by(f64::total_cmp);
        let (min, median) = (ms[0], ms[ms.len() / 2]);
        let counted = PrimaryPass::new(
            &ctx,
            &PrimaryOptions {
                tracer,
                variant: pass.variant(),
                counters: true,
                ..PrimaryOptions::default()
            },
        )?;
        let c = counted
            .run(&ctx, &gpu_scene, &cam, &gbuffer, None)?
            .check()?
            .expect("counters compiled in");
        let variant = pass.variant().map_or("-".to_owned(), |v| v.to_string());
        println!(
            "{tracer:<8} ({variant}): GPU ms min {min:.1} median {median:.1} ({:.2} Mrays/s at the median); \
             runs {all:.1?}",
            rays / median / 1e3
        );
        // Per-ray counts are single rays: /16 gives the paper's 16-wide figures.
        let per16 = if tracer == PrimaryTracer::PerRay {
            16.0
        } else {
            1.0
        };
        println!(
            "  steps {}  box tests {} ({:.0} 16-wide)  triangles accessed {}  after culling {}  \
             triangle tests {} ({:.0} 16-wide)",
            c.traversal_steps,
            c.box_tests,
            c.box_tests as f64 / per16,
            c.triangles_accessed,
            c.triangles_after_culling,
            c.triangle_tests,
            c.triangle_tests as f64 / per16,
        );
    }
    println!("per-ray / mft time, run by run: {ratios:.2?}");
    Ok(())
}
