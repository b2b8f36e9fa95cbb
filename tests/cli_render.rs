//! `penumbra render` end to end: with no arguments, and on each generated
//! scene at 128×128 to PNG and EXR; the visibility AOV's mean agrees with the
//! CPU oracle's within 1 %.

use std::path::{Path, PathBuf};
use std::process::Command;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::frame::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::output::{read_float_image, read_hdr_image};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow::{MASK_SKY, per_ray_masks, shadow_params, visibility};
use penumbra::{assets, sampling, scene::Scene};

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli_render")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn penumbra(dir: &Path, args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "penumbra {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

#[test]
fn render_without_arguments_writes_penumbra_png() {
    let dir = out_dir("default");
    let stdout = penumbra(&dir, &["render"]);
    eprintln!("{stdout}");
    for line in [
        "adapter", "vector", "primary", "shadow", "shade", "filter", "Mrays/s",
    ] {
        assert!(stdout.contains(line), "no '{line}' in the output:\n{stdout}");
    }
    let image = read_hdr_image(&dir.join("penumbra.png")).unwrap();
    assert_eq!((image.width, image.height), (512, 512));
}

#[test]
fn generated_scenes_to_png_and_exr_with_visibility_close_to_the_oracle() {
    for s in assets::EMBEDDED_SCENES {
        let dir = out_dir(s.name);
        for file in ["out.png", "out.exr"] {
            penumbra(
                &dir,
                &[
                    "render",
                    s.name,
                    "--size",
                    "128x128",
                    "-o",
                    file,
                    "--aov",
                    "visibility",
                ],
            );
            let image = read_hdr_image(&dir.join(file)).unwrap();
            assert_eq!((image.width, image.height), (128, 128), "{} {file}", s.name);
        }
        let vis = read_float_image(&dir.join("out.visibility.exr")).unwrap();
        let filtered = read_float_image(&dir.join("out.visibility-filtered.exr")).unwrap();
        assert_eq!((vis.width, vis.height, filtered.width), (128, 128, 128));

        // The CPU oracle's mean visibility over the pixels that see geometry.
        let scene = Scene::from_bytes(s.glb, Path::new(s.file_name)).unwrap();
        let view = s.view();
        let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
        let cam = camera_params(
            &view.camera,
            128,
            128,
            scene.bounds().diagonal() * RAY_OFFSET_FRACTION,
        );
        let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
        let params = shadow_params(&view.light, 128, 128);
        let masks = per_ray_masks(&bvh, &gbuffer, &sampling::light_points(&view.light), &params);
        let hit: Vec<usize> = (0..masks.len()).filter(|&p| masks[p] & MASK_SKY == 0).collect();
        let oracle = hit.iter().map(|&p| visibility(masks[p]) as f64).sum::<f64>() / hit.len() as f64;
        let gpu = hit.iter().map(|&p| vis.pixels[p] as f64).sum::<f64>() / hit.len() as f64;
        let gpu_filtered = hit.iter().map(|&p| filtered.pixels[p] as f64).sum::<f64>() / hit.len() as f64;
        eprintln!(
            "{}: mean visibility oracle {oracle:.4}, EXR {gpu:.4}, filtered {gpu_filtered:.4}",
            s.name
        );
        assert!(
            (gpu - oracle).abs() <= 0.01 * oracle,
            "{}: {gpu} vs {oracle}",
            s.name
        );
        assert!(
            (gpu_filtered - oracle).abs() <= 0.01 * oracle,
            "{}: filtered {gpu_filtered} vs {oracle}",
            s.name
        );
    }
}

#[test]
fn bad_render_arguments_fail_with_one_line() {
    let dir = out_dir("bad");
    for (args, needle) in [
        (
            vec!["render", "--output", "x.jpg"],
            "x.jpg: unsupported output format",
        ),
        (vec!["render", "--spp", "64"], "exactly 16 rays"),
        (vec!["render", "--view", "nope.json"], "nope.json"),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args(&args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert!(
            stderr
                .lines()
                .any(|l| l.starts_with("error: ") && l.contains(needle)),
            "{args:?}: {stderr}"
        );
    }
    assert!(!dir.join("x.jpg").exists());
}

#[test]
fn leaf_mode_is_selectable_and_reported() {
    let dir = out_dir("leaf_mode");
    for (mode, reported) in [
        ("per-lane", "(per-lane leaves)"),
        ("transposed", "(transposed leaves)"),
    ] {
        let stdout = penumbra(
            &dir,
            &["render", "lattice", "--size", "32x32", "--leaf-mode", mode],
        );
        let vector = stdout
            .lines()
            .find(|l| l.starts_with("tracer"))
            .unwrap_or_default();
        assert!(vector.contains(reported), "--leaf-mode {mode}:\n{stdout}");
    }
}
