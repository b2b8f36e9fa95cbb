//! `penumbra render`: a soft-shadowed image of a scene, PNG or EXR.

use std::path::{Path, PathBuf};
use std::time::Instant;

use penumbra::bvh::Bvh;
use penumbra::contract::filter::FilterParams;
use penumbra::contract::layout::MASK_SKY;
use penumbra::contract::refine::REFINE_SET_COUNTS;
use penumbra::gpu::{
    Ambient, FrameSettings, GpuContext, GpuOptions, GpuScene, LeafMode, Phase, PrimaryTracer, Renderer,
    RendererOptions, Tracer, VectorVariant, image_of_lights,
};
use penumbra::output::{FloatImage, HdrImage, ToneMap, write_float_image, write_image};
use penumbra::scene::view_checks::view_warnings;
use penumbra::{Error, Result};

use super::BvhArgs;
use super::scene_arg::{builtin_names, load_scene_and_views};

/// `--vector` values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum VectorArg {
    /// Subgroups when the adapter has fixed 16k-wide ones, else workgroups.
    Auto,
    /// 16 lanes of a subgroup (needs fixed subgroups of 16, 32 or 64), sharing BVH words by
    /// broadcasts.
    Subgroup,
    /// As subgroup, sharing BVH words by reductions (faster on lavapipe from Mesa 24.3 on;
    /// the automatic choice there).
    SubgroupReduce,
    /// A 16-invocation workgroup exchanging through workgroup memory (works everywhere).
    Workgroup,
    /// Four such vectors in a 64-invocation workgroup (fills a GPU's warps).
    Workgroup4,
}

impl VectorArg {
    /// The variant this value forces, `None` for automatic.
    pub fn forced(self) -> Option<VectorVariant> {
        match self {
            VectorArg::Auto => None,
            VectorArg::Subgroup => Some(VectorVariant::Subgroup),
            VectorArg::SubgroupReduce => Some(VectorVariant::SubgroupReduce),
            VectorArg::Workgroup => Some(VectorVariant::Workgroup),
            VectorArg::Workgroup4 => Some(VectorVariant::Workgroup4),
        }
    }
}

/// `--leaf-mode` values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum LeafModeArg {
    /// Each lane tests its own frustum's 16 rays against a leaf triangle.
    PerLane,
    /// The paper's form: per surviving frustum, the 16 lanes test its 16 rays.
    Transposed,
}

impl From<LeafMode> for LeafModeArg {
    fn from(mode: LeafMode) -> LeafModeArg {
        match mode {
            LeafMode::PerLane => LeafModeArg::PerLane,
            LeafMode::Transposed => LeafModeArg::Transposed,
        }
    }
}

impl From<LeafModeArg> for LeafMode {
    fn from(arg: LeafModeArg) -> LeafMode {
        match arg {
            LeafModeArg::PerLane => LeafMode::PerLane,
            LeafModeArg::Transposed => LeafMode::Transposed,
        }
    }
}

/// `--primary` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum PrimaryArg {
    /// One invocation per pixel with its own stack.
    PerRay,
    /// Multi-frusta: one 16-wide vector per 16x16 pixels.
    Mft,
}

impl From<PrimaryArg> for PrimaryTracer {
    fn from(arg: PrimaryArg) -> PrimaryTracer {
        match arg {
            PrimaryArg::PerRay => PrimaryTracer::PerRay,
            PrimaryArg::Mft => PrimaryTracer::Mft,
        }
    }
}

/// `--aov` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum AovArg {
    /// Also write the unfiltered and the filtered visibility as float images.
    Visibility,
}

/// Arguments of `penumbra render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// glTF (.gltf/.glb) file, or a built-in scene name; default: the built-in default scene.
    #[arg(value_name = "SCENE", long_help = format!(
        "glTF 2.0 file (.gltf or .glb), or the name of a built-in scene ({}). \
         Without it, the built-in default scene.", builtin_names()))]
    pub scene: Option<PathBuf>,
    /// View file (camera + quad light, JSON; see README). Default: the built-in scene's
    /// view, else the file's camera and a light above the scene.
    #[arg(long)]
    pub view: Option<PathBuf>,
    /// Image size WIDTHxHEIGHT in pixels (any size; edge tiles are partial).
    #[arg(long, default_value = "512x512", value_parser = super::parse_size)]
    pub size: (u32, u32),
    /// Shadow tracer: mft (multi-frusta), packet (16-ray packets), per-ray, ray-query (the
    /// driver's ray tracing, where the adapter has ray queries), reference
    /// (--spp rays per pixel to the same stratified points, unfiltered), or exact (CPU
    /// beam splitting: the exactly visible fraction of the light; writes the visibility
    /// image as the output).
    #[arg(long, default_value = "mft", value_parser = parse_tracer)]
    tracer: TracerArg,
    /// Exact tracer: give up (with an error, writing nothing) after this many seconds.
    #[arg(long, default_value_t = 600.0)]
    pub time_budget: f64,
    /// Shadow rays per pixel: 16 for mft, packet, per-ray and ray-query (one interleaved set per
    /// pixel); any number up to 65535 for reference (default 256).
    #[arg(long)]
    pub spp: Option<u32>,
    /// Skip the 4x4 discontinuity filter.
    #[arg(long)]
    no_filter: bool,
    /// After the filter, trace all 256 light samples at the pixels where visibility changes
    /// around them and the filter's window is cut (silhouettes, creases, neighbours more
    /// than one ray apart) or their own 16 rays agree (the edge of a penumbra): closer to
    /// exact visibility, for more rays (mft, packet and per-ray; needs the filter).
    #[arg(long, conflicts_with = "no_filter")]
    refine: bool,
    /// With --refine: trace at most RAYS shadow rays per pixel with geometry on average (the
    /// frame's 16 included; a refined pixel costs 256), refining first the pixels whose
    /// filtered visibility is furthest from the mean of the unfiltered ones around them.
    #[arg(long, value_name = "RAYS", requires = "refine")]
    ray_budget: Option<f32>,
    /// With --refine: how many of the 16 sample sets (16 rays each) a refined pixel traces:
    /// 1, 2, 4, 8 or 16 (all 256 light samples). Fewer refine more pixels within a
    /// --ray-budget, each less exactly.
    #[arg(long, value_name = "N", default_value_t = 16, requires = "refine")]
    refine_sets: u32,
    /// Filter: neighbours whose depth differs by more than this fraction of the pixel's are ignored.
    #[arg(long, default_value_t = FilterParams::DEFAULT_DEPTH_TOLERANCE)]
    depth_tolerance: f32,
    /// Filter: neighbours whose normal has a smaller dot product with the pixel's are ignored.
    #[arg(long, default_value_t = FilterParams::DEFAULT_NORMAL_TOLERANCE)]
    normal_tolerance: f32,
    /// Output image; .png (8-bit sRGB, tone-mapped) or .exr (32-bit float linear RGB).
    #[arg(long, short, default_value = "penumbra.png")]
    pub output: PathBuf,
    /// Extra images: `visibility` writes NAME.visibility.exr and NAME.visibility-filtered.exr.
    #[arg(long, value_enum)]
    aov: Option<AovArg>,
    /// Exposure of the PNG tone map `1 - exp(-exposure * radiance)`.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// Unshadowed ambient light for the image: the radiance of a uniform sky every surface
    /// sees (a surface reflects albedo × it), so what the light does not reach is dark, not
    /// black; 0 turns it off. Not in the visibility AOVs.
    #[arg(long, default_value_t = Ambient::DEFAULT_RADIANCE, value_parser = parse_radiance)]
    ambient: f32,
    /// Linear RGB radiance of the pixels that see no geometry, as R,G,B.
    #[arg(long, default_value = "0.03,0.03,0.04", value_parser = parse_rgb)]
    background: Rgb,
    /// How the shadow kernel's 16-wide vector is built.
    #[arg(long, value_enum, default_value_t = VectorArg::Auto)]
    vector: VectorArg,
    /// How the shadow kernel spends its 16 lanes on a leaf triangle (same image either way).
    #[arg(long, value_enum, default_value_t = LeafMode::default().into())]
    leaf_mode: LeafModeArg,
    /// Camera rays: per-ray (one invocation per pixel) or mft (16 frusta of 4x4 pixels
    /// per 16-wide vector); the same G-buffer either way.
    #[arg(long, value_enum, default_value_t = PrimaryArg::Mft)]
    primary: PrimaryArg,
    /// MFT: do not shrink frusta to their still-active rays (at the start and after a
    /// leaf that blocked some: the paper's "CR" frustum shrinking, on by default; same
    /// image either way).
    #[arg(long)]
    no_shrink: bool,
    /// GPU adapter: an index or part of its name (else PENUMBRA_ADAPTER, else automatic).
    #[arg(long)]
    adapter: Option<String>,
    #[command(flatten)]
    pub bvh: BvhArgs,
}

/// `--tracer` values: a GPU tracer, or the CPU's exact visibility.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TracerArg {
    /// A GPU shadow tracer.
    Gpu(Tracer),
    /// Exact visibility by beam splitting, on the CPU.
    Exact,
    /// Embree 3's `rtcOccluded16` on all CPU cores, the same rays and masks as `packet`
    /// (needs a penumbra built with `--features embree`).
    Embree,
}

/// A linear RGB radiance given as `R,G,B`.
#[derive(Clone, Copy, Debug)]
pub struct Rgb(pub [f32; 3]);

/// A radiance: a finite number ≥ 0.
fn parse_radiance(s: &str) -> std::result::Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a radiance (a finite number ≥ 0)")),
    }
}

/// Three radiances `R,G,B`, each a finite number ≥ 0.
fn parse_rgb(s: &str) -> std::result::Result<Rgb, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "'{s}' is not a colour R,G,B (three finite numbers ≥ 0, comma-separated)"
        ));
    }
    let mut rgb = [0.0; 3];
    for (c, p) in rgb.iter_mut().zip(parts) {
        *c = parse_radiance(p)
            .map_err(|_| format!("'{s}' is not a colour R,G,B (three finite numbers ≥ 0)"))?;
    }
    Ok(Rgb(rgb))
}

fn parse_tracer(s: &str) -> std::result::Result<TracerArg, String> {
    match s {
        "exact" => Ok(TracerArg::Exact),
        "embree" if cfg!(feature = "embree") => Ok(TracerArg::Embree),
        "embree" => {
            Err("this penumbra was built without Embree (cargo build --release --features embree)".into())
        }
        _ => s
            .parse()
            .map(TracerArg::Gpu)
            .map_err(|e| format!("{e}, exact or embree")),
    }
}

/// `out.png` + `visibility` → `out.visibility.exr`.
fn aov_path(output: &Path, name: &str) -> PathBuf {
    let stem = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    output.with_file_name(format!("{stem}.{name}.exr"))
}

/// Checks `--ray-budget` and `--refine-sets` (render's and quality's) before anything runs,
/// so that a bad value is named by its flag.
pub(super) fn check_refine_args(budget: Option<f32>, sets: u32) -> Result<()> {
    if let Some(budget) = budget.filter(|b| !(b.is_finite() && *b >= 16.0)) {
        return Err(Error::invalid(
            "--ray-budget",
            format!("{budget}: the budget is a number of rays per pixel ≥ 16 (the frame's own rays)"),
        ));
    }
    if !REFINE_SET_COUNTS.contains(&sets) {
        return Err(Error::invalid(
            "--refine-sets",
            format!("{sets}: a refined pixel traces 1, 2, 4, 8 or 16 of the 16 sample sets"),
        ));
    }
    Ok(())
}

/// The device and the renderer `args` ask for (the shadow tracer `tracer`).
fn new_renderer(args: &RenderArgs, tracer: Tracer) -> Result<(GpuContext, Renderer)> {
    let ctx = GpuContext::new(&GpuOptions {
        adapter: args.adapter.clone(),
        ray_query: tracer == Tracer::RayQuery,
    })?;
    let renderer = Renderer::new(
        &ctx,
        RendererOptions {
            variant: args.vector.forced(),
            leaf_mode: args.leaf_mode.into(),
            tracer,
            counters: false,
            shrink: !args.no_shrink,
            primary: args.primary.into(),
            ..RendererOptions::default()
        },
    )?;
    Ok((ctx, renderer))
}

/// Renders and writes the image(s), printing what ran and how long it took.
pub fn run(args: &RenderArgs) -> Result<()> {
    if args.refine
        && matches!(
            args.tracer,
            TracerArg::Exact | TracerArg::Gpu(Tracer::Reference { .. })
        )
    {
        return Err(Error::invalid(
            "--refine",
            "only the mft, packet, per-ray, ray-query and embree tracers are refined (exact and reference are not filtered)",
        ));
    }
    check_refine_args(args.ray_budget, args.refine_sets)?;
    let embree = args.tracer == TracerArg::Embree;
    let tracer = match args.tracer {
        TracerArg::Gpu(tracer) => tracer,
        TracerArg::Exact => return super::exact::run(args),
        // The frame's stages and light samples are MFT's; Embree replaces its shadow pass.
        TracerArg::Embree => Tracer::Mft,
    };
    let tracer = match (tracer, args.spp) {
        (Tracer::Reference { .. }, Some(rays)) if (1..=65_535).contains(&rays) => Tracer::Reference { rays },
        (Tracer::Reference { .. }, Some(rays)) => {
            return Err(penumbra::Error::value(
                "--spp",
                rays,
                "the reference tracer takes 1 to 65535 rays per pixel",
            ));
        }
        (tracer, None) | (tracer, Some(16)) => tracer,
        (tracer, Some(spp)) => {
            return Err(penumbra::Error::value(
                "--spp",
                spp,
                format!(
                    "the {tracer} tracer traces exactly 16 rays per pixel (use --tracer reference for other counts)"
                ),
            ));
        }
    };
    let ext = args
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("png" | "exr")) {
        return Err(Error::Output {
            path: args.output.clone(),
            message: "unsupported output format: use .png or .exr".into(),
        });
    }
    super::check_output_folder(&args.output)?;
    let (width, height) = args.size;
    // The scene loads and its BVH builds on a second thread while the device and the
    // pipelines are made (each a tenth of a second or more on lavapipe). A scene error
    // comes first, as it would alone.
    let (loaded, gpu) = std::thread::scope(|s| {
        let loading = s.spawn(|| -> Result<_> {
            let (scene, file) = load_scene_and_views(args.scene.as_deref(), args.view.as_deref())?;
            let bvh = Bvh::build(&scene, &args.bvh.settings())?;
            Ok((scene, file, bvh))
        });
        let gpu = new_renderer(args, tracer);
        let loaded = loading
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        (loaded, gpu)
    });
    let (scene, file, bvh) = loaded?;
    let (ctx, renderer) = gpu?;
    let views = file.views();
    let view_name = args
        .view
        .as_ref()
        .map_or_else(|| "view".to_owned(), |p| p.display().to_string());
    for (i, view) in views.iter().enumerate() {
        for w in view_warnings(view, &scene, &bvh) {
            match views.len() {
                1 => eprintln!("warning: {view_name}: {w}"),
                _ => eprintln!("warning: {view_name}: light {}: {w}", i + 1),
            }
        }
    }
    outln!(
        "scene     {} — {} triangles, BVH {} nodes in {:.1} ms",
        scene.source.display(),
        scene.triangles.len(),
        bvh.nodes.len(),
        bvh.build_time.as_secs_f64() * 1e3
    );

    outln!("adapter   {}", ctx.info);
    if embree {
        outln!("tracer    embree (CPU: rtcOccluded16, one 16-ray packet per pixel)");
    } else if tracer.uses_vector() {
        outln!(
            "tracer    {tracer}, vector {} ({} leaves)",
            renderer.variant(),
            renderer.leaf_mode()
        );
    } else {
        outln!("tracer    {tracer}");
    }
    let gpu_scene = GpuScene::new(&ctx, &scene, &bvh)?;
    let mut settings = FrameSettings::new(width, height);
    settings.refine = args.refine;
    settings.ray_budget = args.ray_budget;
    settings.refine_sets = args.refine_sets;
    if args.no_filter || matches!(tracer, Tracer::Reference { .. }) {
        settings.filter = None;
    } else {
        settings.filter = Some((args.depth_tolerance, args.normal_tolerance));
    }
    progress!("compiling kernels…\r");
    renderer.warm_up(&ctx, &gpu_scene, &views[0], &settings)?;
    let unit = tracer.unit();
    let rays_per_pixel = f64::from(tracer.rays_per_pixel());
    let start = Instant::now();
    let mut report = |phase, done, total| {
        let name = match phase {
            Phase::Shadow => "shadow",
            Phase::Refine => "refine",
        };
        progress!(
            "\r{name}    {done}/{total} {}   ",
            if unit == 4 { "tiles of 4x4" } else { "pixels" }
        );
    };
    let frames = if embree {
        // Embree's masks come per light; each light's frame traces its own primary pass.
        let mut frames = Vec::with_capacity(views.len());
        for view in &views {
            frames.push(embree_frame(
                &ctx,
                &renderer,
                &gpu_scene,
                &bvh,
                view,
                &settings,
                &mut report,
            )?);
        }
        frames
    } else {
        renderer.render_lights(&ctx, &gpu_scene, &views, &settings, &mut report)?
    };
    progress!("\r{:60}\r", "");
    let wall = start.elapsed().as_secs_f64();

    let first = &frames[0];
    let hits = first.masks.iter().filter(|&&m| m & MASK_SKY == 0).count() as f64;
    let several = frames.len() > 1;
    let sum_ms = |name: &str| -> Option<f64> {
        let times: Vec<f64> = frames.iter().filter_map(|f| f.timed_ms(name)).collect();
        (!times.is_empty()).then(|| times.iter().sum())
    };
    outln!("{:<9} {}", "primary", gpu_ms(sum_ms("primary")));
    for (i, frame) in frames.iter().enumerate() {
        let light = if several {
            format!(" (light {})", i + 1)
        } else {
            String::new()
        };
        for pass in ["shadow", "shade", "filter"] {
            match frame.timed_ms("shadow-cpu").filter(|_| pass == "shadow") {
                Some(ms) => outln!("{pass:<9} {ms:>9.2} ms CPU (Embree){light}"),
                None => outln!("{pass:<9} {}{light}", gpu_ms(frame.timed_ms(pass))),
            }
        }
        if args.refine {
            let refined = frame.refined.iter().filter(|&&r| r).count();
            let share = refined as f64 / hits.max(1.0);
            let rays = 16 * args.refine_sets;
            outln!(
                "refine    {}: {refined} px ({:.1} % of those with geometry) traced {rays} rays each, \
                 {:.1} rays per pixel with geometry in all{light}",
                gpu_ms(frame.timed_ms("refine")),
                100.0 * share,
                16.0 + f64::from(rays) * share
            );
        }
    }
    let shadow_ms = sum_ms("shadow-cpu").or(sum_ms("shadow"));
    let rays = hits * rays_per_pixel * frames.len() as f64;
    let rate = match shadow_ms {
        Some(ms) if ms > 0.0 => format!("{:.2}", rays / (ms * 1e3)),
        _ => "n/a".to_owned(),
    };
    outln!(
        "rays      {:.2} M shadow rays ({} px with geometry x {rays_per_pixel}{}), {rate} Mrays/s in the shadow pass{}",
        rays / 1e6,
        hits,
        if several {
            format!(" x {} lights", frames.len())
        } else {
            String::new()
        },
        if several { "es" } else { "" }
    );
    let dispatches: u32 = frames.iter().map(|f| f.shadow_stats.dispatches).sum();
    let suspensions: u64 = frames.iter().map(|f| f.shadow_stats.suspensions).sum();
    outln!(
        "frame     {wall:.2} s wall (with readback); {dispatches} shadow dispatches, {suspensions} tile suspensions"
    );
    let fallback: u32 = frames.iter().map(|f| f.primary_fallback_pixels).sum();
    if fallback > 0 {
        outln!(
            "note      the primary frusta of {fallback} pixels ran out of loop iterations; the per-ray \
             kernel traced the camera rays instead (its time is in the primary line)"
        );
    }

    let image = HdrImage {
        width,
        height,
        pixels: image_of_lights(
            &frames,
            &Ambient {
                radiance: args.ambient,
                background: args.background.0,
            },
        ),
    };
    write_image(
        &args.output,
        &image,
        &ToneMap {
            exposure: args.exposure,
        },
    )?;
    outln!("wrote     {}", args.output.display());
    if args.aov == Some(AovArg::Visibility) {
        let aovs = frames.iter().enumerate().flat_map(|(i, frame)| {
            let light = if several {
                format!("light{}.", i + 1)
            } else {
                String::new()
            };
            [
                (format!("{light}visibility"), &frame.unfiltered),
                (format!("{light}visibility-filtered"), &frame.filtered),
            ]
        });
        for (name, values) in aovs {
            let path = aov_path(&args.output, &name);
            let image = FloatImage {
                width,
                height,
                pixels: values.iter().map(|v| v[3]).collect(),
            };
            write_float_image(&path, &image)?;
            outln!("wrote     {}", path.display());
        }
    }
    Ok(())
}

/// The frame with Embree's masks (`--tracer embree`): Embree's BVH is built from the same
/// triangles; the G-buffer the renderer hands over is relative to the GPU scene's origin.
#[cfg(feature = "embree")]
fn embree_frame(
    ctx: &GpuContext,
    renderer: &Renderer,
    gpu_scene: &GpuScene,
    bvh: &Bvh,
    view: &penumbra::scene::view::View,
    settings: &FrameSettings,
    report: &mut dyn FnMut(Phase, u64, u64),
) -> Result<penumbra::gpu::Frame> {
    let scene = penumbra::embree::EmbreeScene::new(bvh)?;
    outln!("embree    BVH built in {:.1} ms", scene.build_ms);
    if let Ok(config) = std::env::var(penumbra::embree::EMBREE_CONFIG_VAR) {
        outln!(
            "embree    device config {config:?} ({})",
            penumbra::embree::EMBREE_CONFIG_VAR
        );
    }
    let shadows = |texels: &[_], w, h| scene.frame_masks(&view.light, gpu_scene.origin, texels, w, h);
    renderer.render_with_cpu_shadows(ctx, gpu_scene, view, settings, &shadows, report)
}

/// Without the `embree` feature `--tracer embree` is refused when parsed.
#[cfg(not(feature = "embree"))]
fn embree_frame(
    _: &GpuContext,
    _: &Renderer,
    _: &GpuScene,
    _: &Bvh,
    _: &penumbra::scene::view::View,
    _: &FrameSettings,
    _: &mut dyn FnMut(Phase, u64, u64),
) -> Result<penumbra::gpu::Frame> {
    unreachable!("parse_tracer refuses embree without the feature")
}

/// A pass's GPU time for the report: milliseconds, or `n/a` where the adapter has no
/// timestamp queries (a 0 would read as a measurement).
fn gpu_ms(ms: Option<f64>) -> String {
    match ms {
        Some(ms) => format!("{ms:>9.2} ms GPU"),
        None => format!("{:>9} (no GPU timestamps on this adapter)", "n/a"),
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn untimed_passes_print_as_not_available() {
        assert_eq!(super::gpu_ms(Some(1.5)), "     1.50 ms GPU");
        assert!(super::gpu_ms(None).trim_start().starts_with("n/a"));
    }
}
