//! `penumbra render --tracer exact`: the exactly visible fraction of the light per
//! pixel, by beam splitting on the CPU, written as the output image.

use std::time::{Duration, Instant};

use penumbra::Result;
use penumbra::bvh::Bvh;
use penumbra::output::{FloatImage, write_float_image};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::exact::{ExactImageOptions, exact_visibility_image_with};
use penumbra::reference::primary::primary_gbuffer;

use super::render::RenderArgs;
use super::scene_arg::load_scene_and_view;

/// Renders the exact visibility image (primary hits traced on the CPU too).
pub fn run(args: &RenderArgs) -> Result<()> {
    if args.spp.is_some() {
        return Err(penumbra::Error::Gpu(
            "--spp: the exact tracer integrates the whole light, it takes no rays per pixel".into(),
        ));
    }
    let (width, height) = args.size;
    let (scene, view) = load_scene_and_view(args.scene.as_deref(), args.view.as_deref())?;
    let bvh = Bvh::build(&scene, &args.bvh.settings())?;
    outln!(
        "scene     {} — {} triangles, BVH {} nodes",
        scene.source.display(),
        scene.triangles.len(),
        bvh.nodes.len()
    );
    outln!(
        "tracer    exact (CPU beam splitting), time budget {:.0} s",
        args.time_budget
    );
    let start = Instant::now();
    let camera = camera_params(
        &view.camera,
        width,
        height,
        scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
    );
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh)?, &camera);
    let progress = |rows: usize| progress!("\rexact     {rows}/{height} rows   ");
    let options = ExactImageOptions {
        budget: Some(Duration::from_secs_f64(args.time_budget.max(0.0))),
        on_row: Some(&progress),
    };
    let visibility = exact_visibility_image_with(&bvh, &gbuffer, width, height, &view.light, &options);
    progress!("\r{:40}\r", "");
    let visibility = visibility?;
    let seconds = start.elapsed().as_secs_f64();
    outln!(
        "exact     {seconds:.2} s CPU wall, {:.3} ms per pixel",
        seconds * 1e3 / f64::from(width * height)
    );
    let image = FloatImage {
        width,
        height,
        pixels: visibility,
    };
    write_float_image(&args.output, &image)?;
    outln!("wrote     {} (visibility)", args.output.display());
    Ok(())
}
