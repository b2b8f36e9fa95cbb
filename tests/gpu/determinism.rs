//! The same scene, view and settings give bit-identical frames: run to run (one
//! pipeline on the same input, so on any adapter), and across the two leaf modes
//! and the two vector variants where the adapter runs both (on lavapipe:
//! `LP_NATIVE_VECTOR_WIDTH=512`, as CI's second run of the GPU tests sets) — bit for
//! bit where the arithmetic is exact (`support::gpu::exact_arithmetic`: lavapipe),
//! ray for ray within the oracle's tolerance elsewhere, where a compiler may fuse
//! multiply-adds differently in different pipelines. Where the subgroup variant is
//! missing, the test says so and compares the workgroup runs only.

use crate::support;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::gpu::{Frame, FrameSettings, GpuScene, LeafMode, Renderer, RendererOptions, VectorVariant};
use penumbra::output::{HdrImage, ToneMap, write_image};
use support::gpu::{assert_same_rays, ctx, embedded, exact_arithmetic, variants};

/// Every buffer of a frame, as raw bytes, by name.
fn frame_bytes(frame: &Frame) -> Vec<(&'static str, Vec<u8>)> {
    let floats = |v: &[[f32; 4]]| bytemuck::cast_slice::<[f32; 4], u8>(v).to_vec();
    vec![
        ("masks", bytemuck::cast_slice(&frame.masks).to_vec()),
        ("unfiltered", floats(&frame.unfiltered)),
        ("filtered", floats(&frame.filtered)),
        ("brdf", floats(&frame.brdf)),
        (
            "G-buffer",
            bytemuck::cast_slice(frame.gbuffer.as_deref().expect("kept")).to_vec(),
        ),
        ("radiance", bytemuck::cast_slice(&frame.radiance()).to_vec()),
    ]
}

/// Panics naming the first buffer and byte where `b` differs from `a`.
fn assert_identical(a: &Frame, b: &Frame, what: &str) {
    for ((name, x), (_, y)) in frame_bytes(a).iter().zip(frame_bytes(b)) {
        assert_eq!(x.len(), y.len(), "{what}: {name} sizes");
        if let Some(i) = x.iter().zip(&y).position(|(p, q)| p != q) {
            panic!(
                "{what}: {name} differs first at byte {i} of {} ({} of {} bytes differ)",
                x.len(),
                x.iter().zip(&y).filter(|(p, q)| p != q).count(),
                x.len()
            );
        }
    }
}

/// The PNG the CLI would write for `frame`, as bytes.
fn png_bytes(frame: &Frame, name: &str) -> Vec<u8> {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("gpu_determinism");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.png"));
    let image = HdrImage {
        width: frame.width,
        height: frame.height,
        pixels: frame.radiance(),
    };
    write_image(&path, &image, &ToneMap::default()).unwrap();
    std::fs::read(&path).unwrap()
}

#[test]
fn same_input_gives_bit_identical_frames() {
    // The dense lattice: many frusta, partial tiles at the right and bottom edges.
    let (scene, view) = embedded("lattice");
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let gpu_scene = GpuScene::new(ctx(), &scene, &bvh).unwrap();
    let mut settings = FrameSettings::new(45, 37);
    settings.keep_gbuffer = true;

    let available = variants();
    if !available.contains(&VectorVariant::Subgroup) {
        eprintln!(
            "gpu_determinism: the subgroup vector is unavailable on {} (subgroups {}..{}); \
             comparing workgroup runs only (on lavapipe, LP_NATIVE_VECTOR_WIDTH=512 enables it)",
            ctx().info.name,
            ctx().info.subgroup_min_size,
            ctx().info.subgroup_max_size
        );
    }
    let mut reference: Option<(String, Frame)> = None;
    let mut compared = Vec::new();
    for &variant in &available {
        for leaf_mode in [LeafMode::PerLane, LeafMode::Transposed] {
            let renderer = Renderer::new(
                ctx(),
                RendererOptions {
                    variant: Some(variant),
                    leaf_mode,
                    ..RendererOptions::default()
                },
            )
            .unwrap();
            let name = format!("{variant}, {leaf_mode} leaves");
            let first = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
            let second = renderer.render(ctx(), &gpu_scene, &view, &settings).unwrap();
            assert_identical(&first, &second, &format!("{name}: run 1 vs run 2"));
            let file_name = format!("{variant}-{leaf_mode}");
            assert_eq!(
                png_bytes(&first, &format!("{file_name}-1")),
                png_bytes(&second, &format!("{file_name}-2")),
                "{name}: PNG files"
            );
            let shadowed = first.masks.iter().filter(|&&m| m != 0 && m != 1 << 16).count();
            assert!(
                shadowed > 100,
                "{name}: only {shadowed} shadowed pixels; a weak test"
            );
            match &reference {
                None => reference = Some((name.clone(), first)),
                Some((ref_name, ref_frame)) => {
                    let what = format!("{ref_name} vs {name}");
                    if exact_arithmetic() {
                        assert_identical(ref_frame, &first, &what);
                    } else {
                        assert_same_rays(
                            &what,
                            &ref_frame.masks,
                            &first.masks,
                            &scene,
                            &bvh,
                            &view,
                            first.gbuffer.as_deref().expect("kept"),
                            settings.width,
                        );
                    }
                }
            }
            compared.push(name);
        }
    }
    eprintln!(
        "gpu_determinism: bit-identical frames (2 runs each) across: {}",
        compared.join("; ")
    );
}
