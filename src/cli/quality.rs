//! `penumbra quality`: how close each way of computing visibility gets to the
//! exact answer (beam splitting) on the same G-buffer: MFT 16 spp with and
//! without the filter, filtered and refined (fully, and within a ray budget with all 16 and
//! with fewer sample sets per refined pixel), and the reference tracer at 64 and 256 rays
//! per pixel;
//! then where each one's error lies ([`penumbra::quality::error_regions`]).

use std::path::PathBuf;
use std::time::{Duration, Instant};

use penumbra::bvh::Bvh;
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::MASK_SKY;
use penumbra::gpu::{FrameSettings, GpuContext, GpuOptions, GpuScene, Renderer, RendererOptions, Tracer};
use penumbra::output::{FloatImage, write_float_image};
use penumbra::quality::error_regions::{Region, RegionError, classify_pixels, error_by_region};
use penumbra::quality::filter_windows::{WindowClassError, filter_window_errors};
use penumbra::quality::metrics::ImageMetrics;
use penumbra::reference::exact::{ExactImageOptions, exact_visibility_image_with};
use penumbra::reference::filter::depths_and_normals;
use penumbra::{Error, Result};
use serde::Serialize;

use super::BvhArgs;
use super::parse_size;
use super::render::VectorArg;
use super::scene_arg::{builtin_names, load_scene_and_view};

/// Arguments of `penumbra quality`.
#[derive(Debug, clap::Args)]
pub struct QualityArgs {
    /// glTF (.gltf/.glb) file, or a built-in scene name; default: the built-in default scene.
    #[arg(value_name = "SCENE", long_help = format!(
        "glTF 2.0 file (.gltf or .glb), or the name of a built-in scene ({}). \
         Without it, the built-in default scene.", builtin_names()))]
    scene: Option<PathBuf>,
    /// View file (default: the built-in scene's view, else one made from the scene's bounds).
    #[arg(long)]
    view: Option<PathBuf>,
    /// Image size WIDTHxHEIGHT.
    #[arg(long, default_value = "256x256", value_parser = parse_size)]
    size: (u32, u32),
    /// Filter: neighbours whose depth differs by more than this fraction of the pixel's are ignored.
    #[arg(long, default_value_t = penumbra::contract::filter::FilterParams::DEFAULT_DEPTH_TOLERANCE)]
    depth_tolerance: f32,
    /// Filter: neighbours whose normal has a smaller dot product with the pixel's are ignored.
    #[arg(long, default_value_t = penumbra::contract::filter::FilterParams::DEFAULT_NORMAL_TOLERANCE)]
    normal_tolerance: f32,
    /// Ray budget of the budgeted refinement (`mft-16-refined-RAYS`): average rays per pixel
    /// with geometry, the frame's 16 included.
    #[arg(long, value_name = "RAYS", default_value_t = 24.0)]
    ray_budget: f32,
    /// The budgeted refinement also runs with refined pixels tracing N of the 16 sample sets
    /// (`mft-16-refined-RAYS-sN`; 1, 2, 4 or 8; 16: only the all-sets run).
    #[arg(long, value_name = "N", default_value_t = 8)]
    refine_sets: u32,
    /// Give up on the exact visibility (an error) after this many seconds.
    #[arg(long, default_value_t = 1800.0)]
    time_budget: f64,
    /// Write each method's visibility image, and the exact one, as DIR/METHOD.exr (32-bit
    /// float) and DIR/METHOD.png (16-bit grey, linear: to look at side by side).
    #[arg(long, value_name = "DIR")]
    images: Option<PathBuf>,
    /// Write every figure as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// How the 16-wide vector is built.
    #[arg(long, value_enum, default_value_t = VectorArg::Auto)]
    vector: VectorArg,
    /// GPU adapter: an index or part of its name.
    #[arg(long)]
    adapter: Option<String>,
    #[command(flatten)]
    bvh: BvhArgs,
}

/// One method's error against exact visibility, over the pixels with geometry.
#[derive(Debug, Serialize)]
struct MethodResult {
    method: String,
    /// GPU milliseconds of its shadow pass plus its filter and refinement.
    gpu_ms: f64,
    /// Shadow rays per pixel with geometry, on average (refinement: 16 + 256 × the
    /// share of those pixels it refined, which trace their own 16 again).
    rays_per_pixel: f64,
    rmse: f64,
    mean_abs: f64,
    max_abs: f64,
    psnr: f64,
    /// Its error by region of the image (geometric edges, sharp transitions, …).
    regions: Vec<RegionError>,
}

#[derive(Debug, Serialize)]
struct QualityReport {
    scene: String,
    width: u32,
    height: u32,
    adapter: String,
    /// Pixels with geometry (the only ones compared).
    pixels: usize,
    exact_cpu_seconds: f64,
    methods: Vec<MethodResult>,
    /// The filtered 16-ray image's error by what the filter did to each pixel's window.
    filter_windows: Vec<WindowClassError>,
}

/// Prints, per region, its share of the pixels, then per method the region's
/// share of the squared error and its RMSE.
fn print_regions(results: &[MethodResult]) {
    outln!("error by region: share of the squared error (RMSE in the region)");
    out!("  {:<18} {:>7}", "region", "pixels");
    for r in results {
        out!(" {:>18}", r.method);
    }
    outln!();
    for (i, region) in Region::ALL.iter().enumerate() {
        let share = results.first().map_or(0.0, |r| r.regions[i].pixel_share);
        out!("  {:<18} {:>6.1}%", region.name(), 100.0 * share);
        for r in results {
            let e = &r.regions[i];
            out!(" {:>9.1}% ({:.4})", 100.0 * e.error_share, e.rmse);
        }
        outln!();
    }
}

/// Prints the filtered 16-ray image's error by window class (see
/// [`penumbra::quality::filter_windows`]), beside reference-64's over the same pixels.
fn print_filter_windows(windows: &[WindowClassError]) {
    outln!(
        "filter windows (mft-16-filtered; RMSE = window bias + sampling, the window's rays on average; reference-64 on the same pixels)"
    );
    outln!(
        "  {:<18} {:>7} {:>7} {:>9} {:>9} {:>9} {:>6} {:>9}",
        "window",
        "pixels",
        "error",
        "RMSE",
        "bias",
        "sampling",
        "rays",
        "ref. 64"
    );
    for c in windows {
        outln!(
            "  {:<18} {:>6.1}% {:>6.1}% {:>9.4} {:>9.4} {:>9.4} {:>6.0} {:>9.4}",
            c.class,
            100.0 * c.pixel_share,
            100.0 * c.error_share,
            c.rmse,
            c.bias_rmse,
            c.sampling_rmse,
            c.mean_rays,
            c.reference_rmse
        );
    }
}

/// Renders every method, prints its errors against exact visibility.
pub fn run(args: &QualityArgs) -> Result<()> {
    super::render::check_refine_args(Some(args.ray_budget), args.refine_sets)?;
    // Output paths first: the exact visibility can take many minutes.
    if let Some(path) = &args.json {
        super::check_output_folder(path)?;
    }
    if let Some(dir) = &args.images {
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.clone(),
            source,
        })?;
    }
    let (w, h) = args.size;
    let (scene, view) = load_scene_and_view(args.scene.as_deref(), args.view.as_deref())?;
    let bvh = Bvh::build(&scene, &args.bvh.settings())?;
    let ctx = GpuContext::new(&GpuOptions {
        adapter: args.adapter.clone(),
        ..GpuOptions::default()
    })?;
    outln!("adapter   {}", ctx.info);
    outln!(
        "scene     {} — {} triangles, {w}x{h}",
        scene.source.display(),
        scene.triangles.len()
    );
    let gpu_scene = GpuScene::new(&ctx, &scene, &bvh)?;
    let renderer = |tracer| {
        Renderer::new(
            &ctx,
            RendererOptions {
                variant: args.vector.forced(),
                tracer,
                ..RendererOptions::default()
            },
        )
    };
    let mut settings = FrameSettings::new(w, h);
    settings.keep_gbuffer = true;
    settings.filter = Some((args.depth_tolerance, args.normal_tolerance));
    // (method, visibility per pixel, GPU ms, rays per pixel with geometry)
    let mut methods: Vec<(String, Vec<f32>, f64, f64)> = Vec::new();
    progress!("rendering MFT 16 spp…\r");
    let mft = renderer(Tracer::Mft)?;
    // Compile before timing (the refinement's kernels too, where the small frame lists a pixel).
    mft.warm_up(
        &ctx,
        &gpu_scene,
        &view,
        &FrameSettings {
            refine: true,
            ..settings
        },
    )?;
    let frame = mft.render(&ctx, &gpu_scene, &view, &settings)?;
    let shadow_ms = frame.pass_ms("shadow");
    methods.push((
        "mft-16-filtered".into(),
        frame.filtered.iter().map(|v| v[3]).collect(),
        shadow_ms + frame.pass_ms("filter"),
        16.0,
    ));
    methods.push((
        "mft-16".into(),
        frame.unfiltered.iter().map(|v| v[3]).collect(),
        shadow_ms,
        16.0,
    ));
    let gbuffer = frame.gbuffer.expect("asked for the G-buffer");
    let hit: Vec<bool> = frame.masks.iter().map(|m| m & MASK_SKY == 0).collect();
    let hits = hit.iter().filter(|&&h| h).count().max(1);
    progress!("rendering MFT 16 spp + refinement…\r");
    settings.refine = true;
    let refined = mft.render(&ctx, &gpu_scene, &view, &settings)?;
    let refined_share = refined.refined.iter().filter(|&&r| r).count() as f64 / hits as f64;
    methods.push((
        "mft-16-refined".into(),
        refined.filtered.iter().map(|v| v[3]).collect(),
        refined.pass_ms("shadow") + refined.pass_ms("filter") + refined.pass_ms("refine"),
        16.0 + 256.0 * refined_share,
    ));
    // Within the ray budget: all 16 sets per refined pixel, and `--refine-sets` of them.
    let budget = args.ray_budget;
    settings.ray_budget = Some(budget);
    let mut set_counts = vec![16];
    if args.refine_sets != 16 {
        set_counts.push(args.refine_sets);
    }
    for sets in set_counts {
        progress!("rendering MFT 16 spp + refinement ({sets} sets) within {budget} rays per pixel…\r");
        settings.refine_sets = sets;
        let budgeted = mft.render(&ctx, &gpu_scene, &view, &settings)?;
        let share = budgeted.refined.iter().filter(|&&r| r).count() as f64 / hits as f64;
        methods.push((
            match sets {
                16 => format!("mft-16-refined-{budget}"),
                _ => format!("mft-16-refined-{budget}-s{sets}"),
            },
            budgeted.filtered.iter().map(|v| v[3]).collect(),
            budgeted.pass_ms("shadow") + budgeted.pass_ms("filter") + budgeted.pass_ms("refine"),
            16.0 + f64::from(16 * sets) * share,
        ));
    }
    settings.ray_budget = None;
    settings.refine_sets = 16;
    settings.refine = false;
    settings.filter = None;
    settings.keep_gbuffer = false;
    for rays in [64, 256] {
        progress!("rendering reference {rays} spp…   \r");
        let r = renderer(Tracer::Reference { rays })?;
        r.warm_up(&ctx, &gpu_scene, &view, &settings)?;
        let f = r.render(&ctx, &gpu_scene, &view, &settings)?;
        methods.push((
            format!("reference-{rays}"),
            f.unfiltered.iter().map(|v| v[3]).collect(),
            f.pass_ms("shadow"),
            f64::from(rays),
        ));
    }
    let start = Instant::now();
    let progress = |rows: usize| progress!("\rexact     {rows}/{h} rows   ");
    let options = ExactImageOptions {
        budget: Some(Duration::from_secs_f64(args.time_budget.max(0.0))),
        on_row: Some(&progress),
    };
    let exact = exact_visibility_image_with(&bvh, &gbuffer, w, h, &view.light, &options);
    progress!("\r{:40}\r", "");
    let exact = exact?;
    let exact_seconds = start.elapsed().as_secs_f64();

    let pick = |v: &[f32]| -> Vec<f32> { v.iter().zip(&hit).filter(|(_, h)| **h).map(|(x, _)| *x).collect() };
    let exact_hit = pick(&exact);
    outln!(
        "exact     {exact_seconds:.2} s on the CPU; {} pixels with geometry compared",
        exact_hit.len()
    );
    outln!(
        "  {:<18} {:>10} {:>8} {:>9} {:>9} {:>9} {:>8}",
        "method",
        "GPU ms",
        "rays/px",
        "RMSE",
        "mean |e|",
        "max |e|",
        "PSNR dB"
    );
    // The filter's tolerances, for the regions and the window classes.
    let filter_params = FilterParams::with_tolerances(w, h, args.depth_tolerance, args.normal_tolerance);
    let mut regions = classify_pixels(&gbuffer, &exact, w, h, &filter_params);
    // The same pixels as the metrics above.
    for (region, hit) in regions.iter_mut().zip(&hit) {
        if !hit {
            *region = None;
        }
    }
    let mut results = Vec::new();
    for (name, values, ms, rays) in &methods {
        let m = ImageMetrics::of_values(&pick(values), &exact_hit);
        outln!(
            "  {name:<18} {ms:>10.1} {rays:>8.1} {:>9.5} {:>9.5} {:>9.4} {:>8.2}",
            m.rmse,
            m.mean_abs,
            m.max_abs,
            m.psnr
        );
        results.push(MethodResult {
            method: name.clone(),
            gpu_ms: *ms,
            rays_per_pixel: *rays,
            rmse: m.rmse,
            mean_abs: m.mean_abs,
            max_abs: m.max_abs,
            psnr: m.psnr,
            regions: error_by_region(values, &exact, &regions),
        });
    }
    print_regions(&results);
    let values_of = |name: &str| {
        &methods
            .iter()
            .find(|(n, ..)| n == name)
            .expect("every method above is rendered")
            .1
    };
    let (depth, normal) = depths_and_normals(&gbuffer);
    let windows = filter_window_errors(
        &filter_params,
        values_of("mft-16"),
        &depth,
        &normal,
        &exact,
        values_of("reference-64"),
        &hit,
    );
    print_filter_windows(&windows);
    if let Some(dir) = &args.images {
        let images = methods
            .iter()
            .map(|(n, v, _, _)| (n.as_str(), v))
            .chain([("exact", &exact)]);
        for (name, values) in images {
            let image = FloatImage {
                width: w,
                height: h,
                pixels: values.clone(),
            };
            for extension in ["exr", "png"] {
                write_float_image(&dir.join(format!("{name}.{extension}")), &image)?;
            }
        }
        outln!("wrote     {}/{{method}}.exr and .png", dir.display());
    }
    if let Some(path) = &args.json {
        let report = QualityReport {
            scene: scene.source.display().to_string(),
            width: w,
            height: h,
            adapter: ctx.info.name.clone(),
            pixels: exact_hit.len(),
            exact_cpu_seconds: exact_seconds,
            methods: results,
            filter_windows: windows,
        };
        super::write_json(path, &report)?;
        outln!("wrote     {}", path.display());
    }
    Ok(())
}
