//! `penumbra render` end to end: with no arguments, and on each generated
//! scene at 128×128 to PNG and EXR; the visibility AOV's mean agrees with the
//! CPU oracle's within 1 %.

use std::path::{Path, PathBuf};
use std::process::Command;

use penumbra::bvh::{Bvh, BvhSettings};
use penumbra::contract::layout::MASK_SKY;
use penumbra::output::{read_float_image, read_hdr_image};
use penumbra::pass_inputs::{RAY_OFFSET_FRACTION, ShadingData, camera_params};
use penumbra::reference::primary::primary_gbuffer;
use penumbra::reference::shadow_per_ray::{per_ray_masks, shadow_params};
use penumbra::reference::visibility::visibility;
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

/// With nothing set in the environment, `render` on lavapipe gets 16-wide subgroups (the
/// binary sets `LP_NATIVE_VECTOR_WIDTH=512` itself), so it runs the subgroup vector and
/// says so; and on a headless machine the Vulkan stack prints nothing to stderr.
#[test]
fn render_on_lavapipe_runs_the_subgroup_vector_without_any_setting() {
    let dir = out_dir("default-vector");
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--size", "64x64"])
        .env_remove(penumbra::gpu::LAVAPIPE_VECTOR_WIDTH_ENV)
        .env_remove(penumbra::gpu::NO_DEVICE_SELECT_ENV)
        .env_remove("XDG_RUNTIME_DIR")
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let adapter = stdout.lines().find(|l| l.starts_with("adapter")).unwrap();
    if adapter.contains("llvmpipe") {
        assert!(
            stdout.contains("vector subgroup") && adapter.contains("subgroups 16..16"),
            "lavapipe without LP_NATIVE_VECTOR_WIDTH should run 16-wide:\n{stdout}"
        );
        assert!(stderr.trim().is_empty(), "stderr of a headless render:\n{stderr}");
    } else {
        eprintln!("not lavapipe ({adapter}): the 16-wide default does not apply");
    }
}

/// The binary gives lavapipe a shader cache of its own for the vector width it runs at
/// (`penumbra-lavapipe-512` in the user's cache folder), so that processes at other widths do
/// not share Mesa 25.0's cached texel fetches (gpu::lavapipe_shader_cache_dir); a cache folder
/// the user named is kept.
#[test]
fn render_keeps_a_shader_cache_per_lavapipe_width() {
    let dir = out_dir("shader-cache");
    let cache_home = dir.join("cache-home");
    let _ = std::fs::remove_dir_all(&cache_home);
    let render = |user_cache: Option<&std::path::Path>| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_penumbra"));
        cmd.args(["render", "--size", "16x16"])
            .env_remove(penumbra::gpu::LAVAPIPE_VECTOR_WIDTH_ENV)
            .env_remove(penumbra::gpu::SHADER_CACHE_DIR_ENV)
            .env("XDG_CACHE_HOME", &cache_home)
            .current_dir(&dir);
        if let Some(user_cache) = user_cache {
            cmd.env(penumbra::gpu::SHADER_CACHE_DIR_ENV, user_cache);
        }
        let out = cmd.output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(
            out.status.success(),
            "{stdout}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        stdout
    };
    let stdout = render(None);
    let adapter = stdout.lines().find(|l| l.starts_with("adapter")).unwrap();
    if !adapter.contains("llvmpipe") {
        eprintln!("not lavapipe ({adapter}): the lavapipe cache folder does not apply");
        return;
    }
    let own = cache_home.join("penumbra-lavapipe-512");
    let entries = std::fs::read_dir(&own).map(|d| d.count()).unwrap_or(0);
    assert!(
        entries > 0,
        "{} should hold Mesa's cache after a render",
        own.display()
    );

    let user_cache = dir.join("user-cache");
    let _ = std::fs::remove_dir_all(&user_cache);
    std::fs::remove_dir_all(&own).unwrap();
    render(Some(&user_cache));
    assert!(!own.exists(), "a cache folder the user named must be kept");
    assert!(
        user_cache.exists(),
        "{} should hold Mesa's cache",
        user_cache.display()
    );
}

/// A width the user set is kept: at `LP_NATIVE_VECTOR_WIDTH=256` lavapipe has 8-wide
/// subgroups and `render` runs the workgroup vector.
#[test]
fn render_keeps_the_users_lavapipe_vector_width() {
    let dir = out_dir("user-vector");
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--size", "32x32"])
        .env(penumbra::gpu::LAVAPIPE_VECTOR_WIDTH_ENV, "256")
        .current_dir(&dir)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let adapter = stdout.lines().find(|l| l.starts_with("adapter")).unwrap();
    if adapter.contains("llvmpipe") {
        assert!(
            stdout.contains("vector workgroup") && adapter.contains("subgroups 8..8"),
            "LP_NATIVE_VECTOR_WIDTH=256 should give 8-wide subgroups:\n{stdout}"
        );
    } else {
        eprintln!("not lavapipe ({adapter}): the variable does not apply");
    }
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
        (
            vec!["render", "--output", "missing/x.png"],
            "missing/x.png: cannot write there: the folder missing does not exist",
        ),
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
        // Refused before any rendering: nothing on standard output.
        assert!(
            out.stdout.is_empty(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stdout)
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

/// Runs the binary in `dir` without asserting success. `XDG_RUNTIME_DIR` is
/// set because without it the Vulkan loader prints lines of its own on
/// stderr, and these tests check that stderr holds exactly penumbra's lines.
fn run(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(dir)
        .env("XDG_RUNTIME_DIR", dir)
        .output()
        .unwrap()
}

/// Every entry of `dir`, sorted.
fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn an_image_too_large_for_the_device_names_the_limit() {
    let dir = out_dir("too_large");
    let out = run(&dir, &["render", "--size", "100000x100000", "-o", "big.png"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    let line = stderr.lines().next().unwrap();
    let prefix = "error: GPU error: image size 100000x100000: this adapter's largest image side \
                  (max_texture_dimension_2d) is ";
    let rest = line.strip_prefix(prefix).unwrap_or_else(|| panic!("{line}"));
    let limit: u32 = rest.strip_suffix(" pixels").unwrap().parse().unwrap();
    assert!(limit >= 2048, "{line}");
    assert!(!dir.join("big.png").exists());
}

#[test]
fn legal_but_suspicious_views_render_with_a_warning() {
    let dir = out_dir("view_warnings");
    let view = r#"{"camera": {"eye": [-13.5, 1.8, 0], "target": [0, 4, 0], "fov_y_degrees": 60},
                   "light": {"corner": [1.5, 40, -7.5], "edge_u": [0, 0, 5], "edge_v": [5, 0, 0]}}"#;
    std::fs::write(dir.join("up.json"), view).unwrap();
    let out = run(
        &dir,
        &["render", "--view", "up.json", "--size", "8x8", "-o", "up.png"],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert_eq!(
        stderr,
        "warning: up.json: the light faces away from the whole scene (every vertex is behind its \
         plane; it emits toward [0, 1, 0]): every surface is unlit\n"
    );
    // Without ambient light and background the unlit image is black; with the defaults
    // its surfaces (albedo × ambient) and background are dark but visible.
    let dark = run(
        &dir,
        &[
            "render",
            "--view",
            "up.json",
            "--size",
            "8x8",
            "--ambient",
            "0",
            "--background",
            "0,0,0",
            "-o",
            "black.png",
        ],
    );
    assert!(dark.status.success(), "{}", String::from_utf8_lossy(&dark.stderr));
    let black = read_hdr_image(&dir.join("black.png")).unwrap();
    assert!(
        black.pixels.iter().all(|p| *p == [0.0; 3]),
        "an unlit image without ambient light is black"
    );
    assert_no_black_pixel(&dir.join("up.png"));
}

/// Fails if a pixel of the image at `path` is black (every channel 0).
fn assert_no_black_pixel(path: &Path) {
    let image = read_hdr_image(path).unwrap();
    let black = image
        .pixels
        .iter()
        .filter(|p| p.iter().all(|&c| c <= 0.0))
        .count();
    assert_eq!(black, 0, "{}: black pixels", path.display());
}

#[test]
fn ambient_and_background_must_be_finite_and_not_negative() {
    let dir = out_dir("ambient_args");
    for args in [
        ["--ambient", "-0.5"],
        ["--ambient", "inf"],
        ["--ambient", "NaN"],
        ["--background", "1,2"],
        ["--background", "1,2,x"],
        ["--background", "0,-1,0"],
    ] {
        let arg = format!("{}={}", args[0], args[1]);
        let out = run(&dir, &["render", "--size", "8x8", &arg, "-o", "out.png"]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains(args[0]) && stderr.contains("finite"),
            "{args:?}: {stderr}"
        );
        assert!(!dir.join("out.png").exists(), "{args:?}");
    }
}

#[test]
fn a_failed_render_leaves_the_previous_image_intact() {
    let dir = out_dir("intact");
    let good = run(&dir, &["render", "lattice", "--size", "16x16", "-o", "out.png"]);
    assert!(good.status.success(), "{}", String::from_utf8_lossy(&good.stderr));
    let before = std::fs::read(dir.join("out.png")).unwrap();
    std::fs::write(dir.join("bad.json"), "{\"camera\": 1}").unwrap();
    for args in [
        // Fails reading the view, before any GPU work.
        vec!["render", "--view", "bad.json", "-o", "out.png"],
        // Fails at the device limit, after the scene and the GPU are set up.
        vec!["render", "--size", "100000x100000", "-o", "out.png"],
        // Fails at an unsupported option value.
        vec!["render", "--spp", "4", "-o", "out.png"],
    ] {
        let out = run(&dir, &args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{args:?}: {stderr}");
        assert!(stderr.starts_with("error: "), "{args:?}: {stderr}");
        assert_eq!(std::fs::read(dir.join("out.png")).unwrap(), before, "{args:?}");
        assert_eq!(
            entries(&dir),
            ["bad.json", "out.png"],
            "{args:?}: no temporary file"
        );
    }
}

#[test]
fn an_interrupted_render_leaves_the_old_image_or_the_whole_new_one() {
    let dir = out_dir("interrupted");
    let good = run(&dir, &["render", "lattice", "--size", "8x8", "-o", "out.png"]);
    assert!(good.status.success(), "{}", String::from_utf8_lossy(&good.stderr));
    let before = std::fs::read(dir.join("out.png")).unwrap();
    let mut outcomes = Vec::new();
    for delay_ms in [50, 1000, 2500] {
        // The workgroup vector is the slow one: the kill lands mid-render.
        let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .args([
                "render",
                "lattice",
                "--size",
                "160x160",
                "--vector",
                "workgroup",
                "-o",
                "out.png",
            ])
            .current_dir(&dir)
            .env("XDG_RUNTIME_DIR", &dir)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let finished = child.try_wait().unwrap().is_some();
        child.kill().unwrap();
        child.wait().unwrap();
        let now = std::fs::read(dir.join("out.png")).unwrap();
        let outcome = if now == before {
            "old image intact"
        } else {
            let image = read_hdr_image(&dir.join("out.png")).expect("a whole new image");
            assert_eq!((image.width, image.height), (160, 160));
            "whole new image"
        };
        outcomes.push(format!(
            "killed after {delay_ms} ms (finished: {finished}): {outcome}"
        ));
        assert_eq!(
            entries(&dir),
            ["out.png"],
            "no temporary file after a kill at {delay_ms} ms"
        );
    }
    eprintln!("{}", outcomes.join("\n"));
    assert!(
        outcomes.iter().any(|o| o.contains("finished: false")),
        "no kill landed before the end of the render: {outcomes:?}"
    );
}

/// `render --tracer embree` (built with the `embree` feature): Embree's masks go through the
/// same shade and filter, so the unfiltered visibility matches MFT's wherever their rays
/// agree — all but 0.1 % of the pixels with geometry on the generated scenes (the oracle
/// comparison's bound; both match the per-ray oracle there).
#[cfg(feature = "embree")]
#[test]
fn render_with_embree_matches_mft() {
    for s in assets::EMBEDDED_SCENES {
        let dir = out_dir(&format!("embree-{}", s.name));
        let stdout = penumbra(&dir, &visibility_args(s.name, "embree", "e.exr"));
        assert!(stdout.contains("ms CPU (Embree)"), "{stdout}");
        penumbra(&dir, &visibility_args(s.name, "mft", "m.exr"));
        assert_same_visibility(&dir, "e", "m", s.name);
    }
}

/// `render SCENE --size 96x96 --tracer TRACER -o FILE --aov visibility`.
fn visibility_args<'a>(scene: &'a str, tracer: &'a str, file: &'a str) -> [&'a str; 10] {
    [
        "render",
        scene,
        "--size",
        "96x96",
        "--tracer",
        tracer,
        "-o",
        file,
        "--aov",
        "visibility",
    ]
}

/// Asserts that `dir/A.visibility.exr` and `dir/B.visibility.exr` differ in at most 0.1 % of
/// their pixels and show a shadow.
fn assert_same_visibility(dir: &Path, a: &str, b: &str, label: &str) {
    let a = read_float_image(&dir.join(format!("{a}.visibility.exr"))).unwrap();
    let b = read_float_image(&dir.join(format!("{b}.visibility.exr"))).unwrap();
    let differing = a.pixels.iter().zip(&b.pixels).filter(|(p, q)| p != q).count();
    eprintln!("{label}: {differing} pixels differ");
    assert!(
        differing * 1000 <= a.pixels.len(),
        "{label}: {differing} pixels differ"
    );
    let shadowed = a.pixels.iter().filter(|&&v| v < 1.0).count();
    assert!(shadowed > 0, "{label}: no shadow at all");
}

/// `render --tracer ray-query`: where the adapter has ray queries (Mesa 25 lavapipe), the
/// same unfiltered visibility as MFT on every generated scene (all but 0.1 % of the pixels
/// with geometry, as for Embree above; both match the per-ray oracle, `tests/gpu/peers.rs`);
/// elsewhere a failing exit status, one line on stderr that names the missing feature, and
/// no output file. `PENUMBRA_REQUIRE_RAY_QUERY` (set by `.ci/run` on Mesa 25) makes the
/// second case a failure.
#[test]
fn render_with_ray_query_matches_mft_or_names_the_missing_feature() {
    for s in assets::EMBEDDED_SCENES {
        let dir = out_dir(&format!("ray-query-{}", s.name));
        let out = run(&dir, &visibility_args(s.name, "ray-query", "r.exr"));
        let stderr = String::from_utf8_lossy(&out.stderr);
        if !out.status.success() {
            assert!(
                std::env::var_os("PENUMBRA_REQUIRE_RAY_QUERY").is_none(),
                "ray queries were required: {stderr}"
            );
            let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
            assert!(
                lines.len() == 1
                    && lines[0].starts_with("error: ray queries are missing")
                    && lines[0].contains("EXPERIMENTAL_RAY_QUERY"),
                "{stderr}"
            );
            assert!(!dir.join("r.exr").exists() && !dir.join("r.visibility.exr").exists());
            eprintln!("{}: no ray queries here; checked the error: {}", s.name, lines[0]);
            continue;
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(stdout.contains("tracer    ray-query"), "{stdout}");
        penumbra(&dir, &visibility_args(s.name, "mft", "m.exr"));
        assert_same_visibility(&dir, "r", "m", s.name);
    }
}

/// A glTF file without a view file gets a light above its bounds, and `render` says where;
/// with the default ambient light no surface of the image is black.
#[test]
fn a_file_without_a_view_says_where_its_light_is_and_shows_every_surface() {
    let dir = out_dir("no_view");
    std::fs::write(dir.join("scene.glb"), assets::default_scene().glb).unwrap();
    let out = run(&dir, &["render", "scene.glb", "--size", "32x32", "-o", "out.png"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.starts_with("note: scene.glb: no view file, so a ")
            && stderr.contains("quad light facing down is placed at ["),
        "{stderr}"
    );
    assert_no_black_pixel(&dir.join("out.png"));
}

/// The Cornell box of `../shared/scenes` without a view file is lit by its luminaire (an
/// emissive quad under the ceiling): `render` says so, the light faces down, and the mean
/// visibility of the floor agrees with the CPU oracle's for that light within 1 % — and is
/// well above 0; and the luminaire's own triangles block none of its rays.
#[test]
fn the_cornell_box_without_a_view_is_lit_by_its_luminaire() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes/cornell_box/cornell_box.gltf");
    if !file.exists() {
        eprintln!("{} is missing: not tested", file.display());
        return;
    }
    let dir = out_dir("cornell");
    let file_arg = file.to_str().unwrap();
    let out = run(
        &dir,
        &[
            "render",
            file_arg,
            "--size",
            "64x64",
            "--aov",
            "visibility",
            "-o",
            "out.exr",
        ],
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("lit by the file's emissive quad"), "{stderr}");

    let scene = Scene::load(&file).unwrap();
    let offset = scene.bounds().diagonal() * RAY_OFFSET_FRACTION;
    let found = penumbra::scene::emitters::find(&scene, offset);
    assert_eq!((found.lights.len(), found.unusable.len()), (1, 0), "{found:?}");
    let light = found.lights[0];
    let normal = light.edge_u.cross(light.edge_v);
    assert!(
        normal.normalize().y < -0.999,
        "the luminaire faces down: {normal}"
    );
    assert!(
        (normal.length() - 130.0 * 105.0).abs() < 1.0,
        "area {}",
        normal.length()
    );

    let vis = read_float_image(&dir.join("out.visibility.exr")).unwrap();
    let bvh = Bvh::build(&scene, &BvhSettings::default()).unwrap();
    let camera = scene.camera.expect("the Cornell box has a camera");
    let cam = camera_params(&camera, 64, 64, offset);
    let gbuffer = primary_gbuffer(&bvh, &ShadingData::new(&scene, &bvh).unwrap(), &cam);
    let masks = per_ray_masks(
        &bvh,
        &gbuffer,
        &sampling::light_points(&light),
        &shadow_params(&light, 64, 64),
    );
    let floor: Vec<usize> = (0..masks.len())
        .filter(|&p| masks[p] & MASK_SKY == 0 && gbuffer[p].normal.y > 0.99 && gbuffer[p].origin.y < 1.0)
        .collect();
    assert!(floor.len() > 200, "{} floor pixels", floor.len());
    let mean = |f: &dyn Fn(usize) -> f64| floor.iter().map(|&p| f(p)).sum::<f64>() / floor.len() as f64;
    let oracle = mean(&|p| f64::from(visibility(masks[p])));
    let gpu = mean(&|p| f64::from(vis.pixels[p]));
    eprintln!("Cornell floor: mean visibility {gpu:.4}, oracle {oracle:.4}");
    assert!(oracle > 0.5, "the floor is lit: {oracle}");
    assert!((gpu - oracle).abs() <= 0.01 * oracle, "{gpu} vs {oracle}");

    // The luminaire's own triangles block none of its rays: the oracle's masks are the same
    // with them taken out of the shadow rays' scene (the G-buffer stays that of the whole box).
    let mut without = scene.clone();
    without
        .triangles
        .retain(|t| scene.materials[t.material as usize].emissive == [0.0; 3]);
    assert_eq!(without.triangles.len(), scene.triangles.len() - 2);
    let bvh_without = Bvh::build(&without, &BvhSettings::default()).unwrap();
    let shadow_gbuffer = primary_gbuffer(
        &bvh_without,
        &ShadingData::new(&without, &bvh_without).unwrap(),
        &cam,
    );
    let masks_without = per_ray_masks(
        &bvh_without,
        &shadow_gbuffer,
        &sampling::light_points(&light),
        &shadow_params(&light, 64, 64),
    );
    let same_surface: Vec<usize> = (0..masks.len())
        .filter(|&p| gbuffer[p].origin == shadow_gbuffer[p].origin)
        .collect();
    assert!(same_surface.len() > 3000, "{} pixels", same_surface.len());
    let differing = same_surface
        .iter()
        .filter(|&&p| masks[p] != masks_without[p])
        .count();
    assert_eq!(differing, 0, "pixels whose rays the luminaire blocks");
}

/// A view file with two lights: `render` traces both (its report names each), writes one
/// pair of visibility AOVs per light, and its image is the sum of the two one-light images
/// (no ambient, black background), within the rounding bound of
/// `support::assert_image_is_sum` (the EXR holds the f32 values).
#[test]
fn a_view_with_two_lights_renders_the_sum_of_its_lights() {
    use penumbra::scene::view::{QuadLight, View};
    let dir = out_dir("two-lights");
    let view = assets::default_scene().view();
    let second = QuadLight {
        corner: glam::Vec3::new(2.0, 5.0, -3.0),
        edge_u: glam::Vec3::new(1.0, 0.0, 0.0),
        edge_v: glam::Vec3::new(0.0, 0.0, 1.5),
        color: glam::Vec3::new(1.0, 0.6, 0.3),
        intensity: 20.0,
    };
    let both = serde_json::json!({ "camera": view.camera, "lights": [view.light, second] });
    std::fs::write(dir.join("both.json"), both.to_string()).unwrap();
    std::fs::write(dir.join("one.json"), view.to_json()).unwrap();
    std::fs::write(
        dir.join("two.json"),
        View {
            light: second,
            ..view
        }
        .to_json(),
    )
    .unwrap();
    let render = |name: &str| {
        let (json, exr) = (format!("{name}.json"), format!("{name}.exr"));
        let args = ["render", "--view", &json, "--size", "48x32", "--ambient", "0"];
        penumbra(
            &dir,
            &[
                &args[..],
                &["--background", "0,0,0", "--aov", "visibility", "-o", &exr],
            ]
            .concat(),
        )
    };
    let stdout = render("both");
    for line in ["shadow", "(light 1)", "(light 2)", "x 2 lights"] {
        assert!(stdout.contains(line), "no '{line}' in:\n{stdout}");
    }
    for aov in ["light1.visibility", "light2.visibility-filtered"] {
        assert!(dir.join(format!("both.{aov}.exr")).exists(), "no both.{aov}.exr");
    }
    render("one");
    render("two");
    let [s, a, b] = ["both", "one", "two"].map(|n| read_hdr_image(&dir.join(format!("{n}.exr"))).unwrap());
    let lit_by_second = crate::support::assert_image_is_sum(&s.pixels, &a.pixels, &b.pixels, "two lights");
    assert!(
        lit_by_second * 10 > s.pixels.len(),
        "the second light lights {lit_by_second} pixels"
    );
}

/// A reader that stops reading (`penumbra render | head -3`) is no error: the render still
/// writes its image, exits 0 and prints nothing about it. Here the pipe is closed before the
/// first line, so every line meets it.
#[test]
fn render_into_a_closed_pipe_still_writes_the_image() {
    let dir = out_dir("closed-pipe");
    let mut child = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(["render", "--size", "32x32", "-o", "shadows.png"])
        .current_dir(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "render into a closed pipe failed ({}):\n{stderr}",
        out.status
    );
    assert!(
        !stderr.contains("error"),
        "render into a closed pipe reported:\n{stderr}"
    );
    let image = read_hdr_image(&dir.join("shadows.png")).unwrap();
    assert_eq!((image.width, image.height), (32, 32));
}
