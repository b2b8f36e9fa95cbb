//! `penumbra bench`: shadow-pass GPU times of every tracer on a set of scenes,
//! the speedup of multi-frusta tracing over each baseline taken in the same run,
//! and the paper's Table-1 counters with their reductions.
//!
//! `cases.rs` is the scene catalogue, `report.rs` the figures and how they print.

mod cases;
mod report;

use std::path::PathBuf;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::GBufferTexel;
use penumbra::contract::layout::MASK_SKY;
use penumbra::gpu::MotionSettings;
use penumbra::gpu::animate::{animate_instance, default_moving_instance};
use penumbra::gpu::{
    FrameSettings, GpuContext, GpuOptions, GpuScene, GpuTimer, PrimaryOptions, PrimaryPass, PrimaryTracer,
    Renderer, RendererOptions, Tracer, empty_storage_buffer,
};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, camera_params};
use penumbra::scene::Scene;
use penumbra::scene::view::View;
use penumbra::{Error, Result};

use super::BvhArgs;
use super::parse_size;
use super::render::VectorArg;
use cases::cases;
use report::*;

/// Arguments of `penumbra bench`.
#[derive(Debug, clap::Args)]
pub struct BenchArgs {
    /// Scenes: glTF files or built-in names. Default: the built-in scenes plus every
    /// .gltf/.glb under --shared-scenes.
    #[arg(value_name = "SCENE")]
    scenes: Vec<PathBuf>,
    /// Where to look for the shared scenes when no SCENE is given.
    #[arg(long, default_value = "../shared/scenes")]
    shared_scenes: PathBuf,
    /// A view file to use for every scene (default: each scene's known views, else one
    /// made from its bounds).
    #[arg(long)]
    view: Option<PathBuf>,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "1024x1024", value_parser = parse_size)]
    size: (u32, u32),
    /// Shadow rays per pixel (the tracers compared here trace 16).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(16..=16))]
    spp: u32,
    /// Tracers to time, comma-separated: mft, packet, per-ray, ray-query (the driver's ray
    /// tracing, where the adapter has ray queries; its BLAS/TLAS build is reported
    /// apart), and embree (Embree 3's
    /// `rtcOccluded16` on all CPU cores, the same rays and masks; needs a penumbra built with
    /// `--features embree`). MFT is always included (speedups are over it).
    #[arg(long, value_delimiter = ',', default_value = "mft,packet,per-ray", value_parser = parse_tracer)]
    tracers: Vec<BenchTracer>,
    /// Timed runs per tracer (after one warm-up run).
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    runs: u32,
    /// BVH leaf sizes to bench, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "8")]
    leaf_sizes: Vec<u32>,
    /// Also time MFT without frustum shrinking (the paper's "CR", on by default), as the
    /// row `mft-no-cr`.
    #[arg(long)]
    without_cr: bool,
    /// Skip the extra counting run per tracer (counters are gathered in a separate
    /// run with the counting kernels, so they never slow the timed runs).
    #[arg(long)]
    no_counters: bool,
    /// Skip each case's refined frame (the MFT frame again with `render --refine`, timed
    /// after the plain frames; on the lattice it takes longer than every other run of the
    /// case together); its figures are then left out (null in --json).
    #[arg(long)]
    no_refine: bool,
    /// Frames of the moving-object case per scene (the largest object that is not the
    /// whole scene circles and spins; refit/rebuild and upload ms per frame); 0: skip it.
    #[arg(long, default_value_t = 30)]
    animate_frames: u32,
    /// How the 16-wide vector is built.
    #[arg(long, value_enum, default_value_t = VectorArg::Auto)]
    vector: VectorArg,
    /// GPU adapter: an index or part of its name.
    #[arg(long)]
    adapter: Option<String>,
    /// Also write every figure of the table as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    #[command(flatten)]
    bvh: BvhArgs,
}

/// A tracer `bench` times: one of the GPU shadow tracers, or the Embree peer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchTracer {
    /// A GPU shadow tracer.
    Gpu(Tracer),
    /// Embree 3 on the CPU ([`penumbra::embree`]).
    Embree,
}

fn parse_tracer(s: &str) -> std::result::Result<BenchTracer, String> {
    if s == "embree" {
        return if cfg!(feature = "embree") {
            Ok(BenchTracer::Embree)
        } else {
            Err("this penumbra was built without Embree (cargo build --release --features embree)".into())
        };
    }
    match s.parse()? {
        Tracer::Reference { .. } => {
            Err("bench compares 16-ray tracers: mft, packet, per-ray, ray-query, embree".into())
        }
        t => Ok(BenchTracer::Gpu(t)),
    }
}

/// Runs the benchmark and prints its table.
pub fn run(args: &BenchArgs) -> Result<()> {
    if let Some(path) = &args.json {
        crate::cli::check_output_folder(path)?;
    }
    // (tracer, shrink): MFT first, the speedups are over it.
    let mut tracers = vec![(Tracer::Mft, true)];
    if args.without_cr {
        tracers.push((Tracer::Mft, false));
    }
    tracers.extend(args.tracers.iter().filter_map(|&t| match t {
        BenchTracer::Gpu(t) if t != Tracer::Mft => Some((t, false)),
        _ => None,
    }));
    let embree = args.tracers.contains(&BenchTracer::Embree);
    for &leaf in &args.leaf_sizes {
        if !(1..=255).contains(&leaf) {
            return Err(Error::value(
                "--leaf-sizes",
                leaf,
                "each leaf size must be in 1..=255",
            ));
        }
    }
    let cases = cases(args)?;
    let options = |ray_query| GpuOptions {
        adapter: args.adapter.clone(),
        ray_query,
    };
    // One command for every driver: where ray queries are missing, the others are still
    // benched and the table says why ray-query is not among them.
    let ctx = match GpuContext::new(&options(tracers.iter().any(|t| t.0 == Tracer::RayQuery))) {
        Err(e @ Error::RayQueryUnsupported { .. }) => {
            outln!("  ray-query: not benched: {e}");
            tracers.retain(|t| t.0 != Tracer::RayQuery);
            GpuContext::new(&options(false))?
        }
        made => made?,
    };
    let variant = args.vector.forced();
    let mut renderers = Vec::new();
    for &(tracer, shrink) in &tracers {
        let options = |counters| RendererOptions {
            variant,
            tracer,
            counters,
            shrink,
            ..RendererOptions::default()
        };
        let counting = (!args.no_counters && tracer.uses_vector())
            .then(|| Renderer::new(&ctx, options(true)))
            .transpose()?;
        let name = if tracer == Tracer::Mft && !shrink {
            "mft-no-cr".to_owned()
        } else {
            tracer.to_string()
        };
        renderers.push((name, Renderer::new(&ctx, options(false))?, counting));
    }
    let vector = renderers[0].1.variant().to_string();
    outln!("adapter   {}", ctx.info);
    outln!(
        "bench     {} case(s) x leaf sizes {:?}, {}x{}, 16 rays/pixel, {} runs after a warm-up, vector {vector}",
        cases.len(),
        args.leaf_sizes,
        args.size.0,
        args.size.1,
        args.runs
    );
    let (w, h) = args.size;
    let mut results = Vec::new();
    let total_steps = cases.len() * args.leaf_sizes.len() * tracers.len();
    let mut step = 0;
    for case in &cases {
        for &leaf_size in &args.leaf_sizes {
            let settings = BvhSettings {
                max_leaf_size: leaf_size,
                ..args.bvh.settings()
            };
            let bvh = Bvh::build(&case.scene, &settings)?;
            let bvh = if case.opaque_masks {
                bvh.without_alpha()
            } else {
                bvh
            };
            let gpu_scene = GpuScene::new(&ctx, &case.scene, &bvh)?;
            // Made only on a device with ray queries (asked for when ray-query is benched).
            let ray_query_build_ms = gpu_scene.ray_query.as_ref().map(|rq| rq.build_ms);
            if let Some(ms) = ray_query_build_ms {
                progress!("\r{:100}\r", "");
                outln!("  ray-query: BLAS + TLAS built by the driver in {ms:.1} ms wall (not in its times)");
            }
            let frame_settings = FrameSettings::new(w, h);
            let mut tracer_results = Vec::new();
            let mut primary = Vec::new();
            // The MFT renderer's frames (the first renderer): every pass, and the wall time.
            let (mut shade, mut filter, mut wall) = (Vec::new(), Vec::new(), Vec::new());
            let (mut refine, mut refined_wall, mut refined_pixels) = (Vec::new(), Vec::new(), None);
            let mut rays = 0;
            for (tracer, renderer, counting) in &renderers {
                step += 1;
                let label = format!(
                    "[{step}/{total_steps}] {} ({}) leaf {leaf_size} {tracer}",
                    case.name, case.view_name
                );
                let mut times = Vec::new();
                for run in 0..=args.runs {
                    progress!(
                        "\r{label}: {} {:30}",
                        if run == 0 {
                            "warm-up".to_owned()
                        } else {
                            format!("run {run}/{}", args.runs)
                        },
                        ""
                    );
                    let start = std::time::Instant::now();
                    let frame = renderer.render(&ctx, &gpu_scene, &case.view, &frame_settings)?;
                    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                    if run > 0 {
                        times.push(frame.pass_ms("shadow"));
                        if tracer_results.is_empty() {
                            primary.push(frame.pass_ms("primary"));
                            shade.push(frame.pass_ms("shade"));
                            filter.push(frame.pass_ms("filter"));
                            wall.push(wall_ms);
                        }
                    }
                    rays = frame.masks.iter().filter(|&&m| m & MASK_SKY == 0).count() as u64 * 16;
                }
                if tracer_results.is_empty() && !args.no_refine {
                    let refined_settings = FrameSettings {
                        refine: true,
                        ..frame_settings
                    };
                    for run in 0..=args.runs {
                        progress!("\r{label}: refined frame, run {run}/{} {:30}", args.runs, "");
                        let start = std::time::Instant::now();
                        let frame = renderer.render(&ctx, &gpu_scene, &case.view, &refined_settings)?;
                        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                        if run > 0 {
                            refine.push(frame.pass_ms("refine"));
                            refined_wall.push(wall_ms);
                        }
                        refined_pixels = Some(frame.refined.iter().filter(|&&r| r).count());
                    }
                }
                let counters = match counting {
                    Some(r) => {
                        progress!("\r{label}: counting {:30}", "");
                        Some(
                            r.render(&ctx, &gpu_scene, &case.view, &frame_settings)?
                                .shadow_stats
                                .counters,
                        )
                    }
                    None => None,
                };
                let med = median(&times);
                tracer_results.push(TracerResult {
                    tracer: tracer.clone(),
                    shadow_ms_min: times.iter().copied().fold(f64::INFINITY, f64::min),
                    shadow_ms_median: med,
                    mrays_per_s: rays as f64 / (med * 1e3),
                    shadow_ms: times,
                    mft_speedup: f64::NAN,
                    counters,
                });
            }
            let embree_build_ms = if embree {
                let (result, build_ms) =
                    bench_embree(&ctx, args, &renderers[0].1, &gpu_scene, &bvh, case, rays)?;
                tracer_results.push(result);
                Some(build_ms)
            } else {
                None
            };
            progress!("\r{:100}\r", "");
            let mft_median = tracer_results[0].shadow_ms_median;
            for t in &mut tracer_results {
                t.mft_speedup = t.shadow_ms_median / mft_median;
            }
            let find = |name: &str| {
                tracer_results
                    .iter()
                    .find(|t| t.tracer == name)
                    .and_then(|t| t.counters)
            };
            let reductions_vs_packet = match (find("mft"), find("packet")) {
                (Some(m), Some(p)) => Some(Reductions {
                    triangles_accessed: ratio(p.triangles_accessed, m.triangles_accessed),
                    triangles_after_culling: ratio(p.triangles_after_culling, m.triangles_after_culling),
                    box_tests: ratio(p.box_tests, m.box_tests),
                    triangle_tests: ratio(p.triangle_tests, m.triangle_tests),
                }),
                _ => None,
            };
            let primary_results = bench_primary(&ctx, args, &gpu_scene, &case.view, &case.scene)?;
            let moving = default_moving_instance(&case.scene).filter(|_| args.animate_frames > 0);
            let animation = match moving {
                Some(instance) => {
                    progress!(
                        "\ranimating instance {instance} for {} frames…   ",
                        args.animate_frames
                    );
                    let report = animate_instance(
                        &ctx,
                        &case.scene,
                        &bvh,
                        instance,
                        args.animate_frames,
                        MotionSettings::default(),
                    )?;
                    progress!("\r{:60}\r", "");
                    Some(AnimationResult::of(&report))
                }
                None => None,
            };
            let primary_ms = median(&primary);
            let result = CaseResult {
                scene: case.name.clone(),
                view: case.view_name.clone(),
                triangles: case.scene.triangles.len(),
                leaf_size,
                bvh_nodes: bvh.nodes.len(),
                width: w,
                height: h,
                shadow_rays: rays,
                primary_ms_median: primary_ms,
                frame: FrameResult {
                    primary_ms_median: primary_ms,
                    shadow_ms_median: tracer_results[0].shadow_ms_median,
                    shade_ms_median: median(&shade),
                    filter_ms_median: median(&filter),
                    wall_ms_min: wall.iter().copied().fold(f64::INFINITY, f64::min),
                    wall_ms_median: median(&wall),
                    wall_ms: wall,
                    refine_ms_median: (!refine.is_empty()).then(|| median(&refine)),
                    refined_wall_ms_median: (!refined_wall.is_empty()).then(|| median(&refined_wall)),
                    refined_pixels,
                },
                primary: primary_results,
                tracers: tracer_results,
                embree_build_ms,
                ray_query_build_ms,
                animation,
                reductions_vs_packet,
            };
            print_case(&result);
            results.push(result);
        }
    }
    let light_totals = light_totals(&results);
    for t in &light_totals {
        print_light_total(t);
    }
    let report = BenchReport {
        adapter: ctx.info.name.clone(),
        driver: format!("{} {}", ctx.info.driver, ctx.info.driver_info),
        vector,
        runs: args.runs,
        cases: results,
        light_totals,
    };
    if let Some(path) = &args.json {
        super::write_json(path, &report)?;
        outln!("wrote     {}", path.display());
    }
    Ok(())
}

/// Times Embree's occlusion queries for the frame's own G-buffer (from one MFT frame) and
/// light samples: wall ms per run of [`penumbra::embree::EmbreeScene::masks`], after a
/// warm-up; returns its row and Embree's BVH build ms (reported apart). The masks must be
/// the MFT frame's up to the rays the oracle comparison excuses; a count is printed.
#[cfg(feature = "embree")]
fn bench_embree(
    ctx: &GpuContext,
    args: &BenchArgs,
    mft: &Renderer,
    gpu_scene: &GpuScene,
    bvh: &Bvh,
    case: &cases::Case,
    rays: u64,
) -> Result<(TracerResult, f64)> {
    let (w, h) = args.size;
    let settings = FrameSettings {
        keep_gbuffer: true,
        ..FrameSettings::new(w, h)
    };
    let frame = mft.render(ctx, gpu_scene, &case.view, &settings)?;
    let gbuffer = frame.gbuffer.clone().unwrap_or_default();
    let embree = penumbra::embree::EmbreeScene::new(bvh)?;
    let mut times = Vec::new();
    let mut masks = Vec::new();
    for run in 0..=args.runs {
        progress!("\r{} embree: run {run}/{} {:30}", case.name, args.runs, "");
        let start = std::time::Instant::now();
        masks = embree.frame_masks(&case.view.light, gpu_scene.origin, &gbuffer, w, h);
        if run > 0 {
            times.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    let differing: u32 = masks
        .iter()
        .zip(&frame.masks)
        .map(|(a, b)| ((a ^ b) & 0xffff).count_ones())
        .sum();
    progress!("\r{:100}\r", "");
    outln!(
        "  embree: BVH build {:.1} ms (not in its times); its masks differ from MFT's in {differing} of {rays} rays",
        embree.build_ms
    );
    let med = median(&times);
    Ok((
        TracerResult {
            tracer: "embree".to_owned(),
            shadow_ms_min: times.iter().copied().fold(f64::INFINITY, f64::min),
            shadow_ms_median: med,
            mrays_per_s: rays as f64 / (med * 1e3),
            shadow_ms: times,
            mft_speedup: f64::NAN,
            counters: None,
        },
        embree.build_ms,
    ))
}

/// Without the `embree` feature `--tracers embree` is refused when parsed.
#[cfg(not(feature = "embree"))]
fn bench_embree(
    _: &GpuContext,
    _: &BenchArgs,
    _: &Renderer,
    _: &GpuScene,
    _: &Bvh,
    _: &cases::Case,
    _: u64,
) -> Result<(TracerResult, f64)> {
    unreachable!("parse_tracer refuses embree without the feature")
}

/// Times the camera-ray pass alone with each primary tracer, then counts its work.
fn bench_primary(
    ctx: &GpuContext,
    args: &BenchArgs,
    scene: &GpuScene,
    view: &View,
    cpu_scene: &Scene,
) -> Result<Vec<PrimaryResult>> {
    let (w, h) = args.size;
    let camera = camera_params(
        &view.camera,
        w,
        h,
        cpu_scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = empty_storage_buffer(
        ctx,
        "bench G-buffer",
        u64::from(w) * u64::from(h) * size_of::<GBufferTexel>() as u64,
        wgpu::BufferUsages::empty(),
    )?;
    let mut out = Vec::new();
    for tracer in [PrimaryTracer::Mft, PrimaryTracer::PerRay] {
        let pass = PrimaryPass::new(
            ctx,
            &PrimaryOptions {
                tracer,
                variant: args.vector.forced(),
                ..PrimaryOptions::default()
            },
        )?;
        let mut times = Vec::new();
        let mut ran_out_pixels = 0;
        for run in 0..=args.runs {
            progress!("\rprimary {tracer:?}: run {run}/{}   ", args.runs);
            let mut timer = GpuTimer::new(ctx, 4);
            let status = pass.run(ctx, scene, &camera, &gbuffer, Some(&mut timer))?;
            if tracer == PrimaryTracer::Mft && status.overflow_pixels > 0 {
                // Frusta of a small image's blocks can meet more of the scene than a
                // vector's loop may visit; the renderer falls back to per-ray there.
                ran_out_pixels = status.overflow_pixels;
                break;
            }
            status.check()?;
            if run > 0 {
                times.push(timer.read(ctx)?.iter().map(|(_, ms)| ms).sum());
            }
        }
        let counters = if args.no_counters || ran_out_pixels > 0 {
            None
        } else {
            PrimaryPass::new(
                ctx,
                &PrimaryOptions {
                    tracer,
                    variant: args.vector.forced(),
                    counters: true,
                    ..PrimaryOptions::default()
                },
            )?
            .run(ctx, scene, &camera, &gbuffer, None)?
            .check()?
        };
        out.push(PrimaryResult {
            tracer: match tracer {
                PrimaryTracer::Mft => "mft",
                PrimaryTracer::PerRay => "per-ray",
            }
            .to_owned(),
            primary_ms_min: times.iter().copied().reduce(f64::min).unwrap_or(f64::NAN),
            primary_ms_median: median(&times),
            primary_ms: times,
            mft_speedup: f64::NAN,
            counters,
            ran_out_pixels,
        });
    }
    progress!("\r{:60}\r", "");
    let mft = out[0].primary_ms_median;
    for p in &mut out {
        p.mft_speedup = p.primary_ms_median / mft;
    }
    Ok(out)
}
