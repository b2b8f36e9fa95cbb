//! Where the multi-frusta kernel's loop passes go, tile by tile. The CPU twin
//! (`reference::shadow_mft`, whose node and triangle counters equal the kernel's:
//! `tests/gpu` `shadow_tracers::counters_equal_the_cpu_twins`; its loop runs as the
//! kernel's, two traversal steps and up to two leaf triangles a pass, but the kernel does
//! not count its passes) traces every 4×4 tile of a view as
//! the shadow pass runs it by default (frustum shrinking, per-lane leaves), and the
//! tiles are sorted by what their rays found (all lit, all blocked, some of each) and by
//! what they lie on (the view's ground plane, or the scene). For each class it prints
//! the tiles, their share of all loop passes, and per tile the passes, the inner nodes
//! visited and the leaf triangles read. On lavapipe a pass costs about the same
//! whatever it does (README "Where the MFT kernel's time goes"), so the passes are
//! what a class costs.
//!
//! `cargo run --release --example mft_tile_work -- SCENE VIEW [SIZE]`, SCENE a glTF
//! file or a built-in scene's name, SIZE the image's side (256), e.g.
//! `cargo run --release --example mft_tile_work --
//! ../shared/scenes/stanford_bunny/stanford-bunny.gltf assets/views/bunny.json`

use std::path::Path;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::{GBufferTexel, MASK_FULL};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_mft::{Counters, Frustum, TileOptions, trace_tile};
use penumbra::reference::shadow_per_ray::{ITERATION_BUDGET, shadow_params};
use penumbra::scene::{Scene, view::View};
use penumbra::{assets, sampling};

/// What a tile's rays found.
const OUTCOMES: [&str; 3] = ["all lit", "all blocked", "lit and blocked"];
/// What a tile lies on.
const SURFACES: [&str; 2] = ["the scene", "the ground plane"];

/// One class's sums.
#[derive(Clone, Copy, Default)]
struct Sums {
    tiles: u64,
    passes: u64,
    nodes: u64,
    triangles: u64,
}

fn main() -> penumbra::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene_arg, view_arg, rest @ ..] = args.as_slice() else {
        eprintln!("usage: mft_tile_work SCENE VIEW [SIZE]");
        std::process::exit(2);
    };
    let size: u32 = match rest.first().map(|s| s.parse()) {
        None => 256,
        Some(Ok(n)) if n >= 4 => n,
        Some(_) => {
            eprintln!("mft_tile_work: SIZE must be a whole number of pixels, at least 4");
            std::process::exit(2);
        }
    };
    let view = View::load(Path::new(view_arg))?;
    let mut scene = match assets::embedded_scene(scene_arg) {
        Some(s) if !Path::new(scene_arg).exists() => Scene::from_bytes(s.glb, Path::new(s.file_name))?,
        _ => Scene::load(Path::new(scene_arg))?,
    };
    if let Some(y) = view.ground_y {
        scene.add_ground_plane(y);
    }
    let bvh = Bvh::build(&scene, &BvhSettings::default())?;
    // Scene::bounds walks every triangle: once, not per pixel.
    let diagonal = scene.bounds().diagonal();
    let cam = camera_params(&view.camera, size, size, diagonal * RAY_OFFSET_FRACTION);
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh)?, &cam);
    let params = shadow_params(&view.light, size, size);
    let points = sampling::light_points(&view.light);
    // The shadow pass's defaults: shrinking on, per-lane leaves.
    let options = TileOptions {
        budget: ITERATION_BUDGET,
        shrink: true,
        transposed: false,
    };
    let on_ground = |t: &GBufferTexel| {
        view.ground_y
            .is_some_and(|y| t.geo_normal.y > 0.99 && (t.origin.y - y).abs() <= 1e-3 * diagonal)
    };

    let mut sums = [[Sums::default(); 2]; 3];
    let side = size.div_ceil(4) as usize;
    let w = size as usize;
    for ty in 0..side {
        for tx in 0..side {
            let pixel = |i: usize| {
                let (x, y) = (tx * 4 + i % 4, ty * 4 + i / 4);
                (x < w && y < w).then(|| &gbuffer[y * w + x])
            };
            let frusta = std::array::from_fn(|i| match pixel(i) {
                Some(t) => Frustum::new(t, i, &points, &params),
                None => Frustum::outside(),
            });
            let mut counters = Counters::default();
            let masks = trace_tile(&bvh, frusta, &params, &options, &mut counters);
            let (mut hits, mut ground, mut blocked) = (0, 0, 0);
            for (i, m) in masks.iter().enumerate() {
                if let Some(t) = pixel(i).filter(|t| t.depth > 0.0) {
                    hits += 1;
                    ground += u32::from(on_ground(t));
                    blocked += (m & MASK_FULL).count_ones();
                }
            }
            if hits == 0 {
                continue; // sky only: no rays
            }
            let outcome = match blocked {
                0 => 0,
                b if b == 16 * hits => 1,
                _ => 2,
            };
            let s = &mut sums[outcome][usize::from(2 * ground > hits)];
            s.tiles += 1;
            s.passes += counters.traversal_steps;
            s.nodes += counters.nodes_visited;
            s.triangles += counters.triangles_accessed;
        }
    }

    let total: u64 = sums.iter().flatten().map(|s| s.passes).sum();
    println!(
        "{view_arg} at {size}x{size}: {total} loop passes over {} tiles with geometry",
        sums.iter().flatten().map(|s| s.tiles).sum::<u64>()
    );
    println!(
        "| tile's rays | tile lies on | tiles | share of passes | passes / tile | nodes / tile | triangles / tile |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for (outcome, row) in OUTCOMES.iter().zip(&sums) {
        for (surface, s) in SURFACES.iter().zip(row) {
            if s.tiles == 0 {
                continue;
            }
            let per_tile = |v: u64| v as f64 / s.tiles as f64;
            println!(
                "| {outcome} | {surface} | {} | {:.1} % | {:.1} | {:.1} | {:.1} |",
                s.tiles,
                100.0 * s.passes as f64 / total.max(1) as f64,
                per_tile(s.passes),
                per_tile(s.nodes),
                per_tile(s.triangles)
            );
        }
    }
    Ok(())
}
