//! `penumbra quality`, `penumbra render --tracer exact|packet|per-ray|reference` and
//! `penumbra bench` end to end on the generated scenes at small sizes (CI runs these).

use std::path::{Path, PathBuf};
use std::process::Command;

use penumbra::output::read_float_image;

fn out_dir(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("cli_quality")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn penumbra(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn quality_reports_every_method_on_the_generated_scenes() {
    for scene in ["playground", "lattice"] {
        let dir = out_dir(scene);
        let args = [
            "quality", scene, "--size", "48x40", "--json", "q.json", "--images", "images",
        ];
        let (ok, stdout, stderr) = penumbra(&dir, &args);
        assert!(ok, "quality {scene} failed:\n{stdout}\n{stderr}");
        let report: serde_json::Value =
            serde_json::from_slice(&std::fs::read(dir.join("q.json")).unwrap()).unwrap();
        let methods = report["methods"].as_array().unwrap();
        let names: Vec<&str> = methods.iter().map(|m| m["method"].as_str().unwrap()).collect();
        assert_eq!(
            names,
            [
                "mft-16-filtered",
                "mft-16",
                "mft-16-refined",
                "mft-16-refined-24",
                "mft-16-refined-24-s8",
                "reference-64",
                "reference-256"
            ]
        );
        let rmse = |i: usize| methods[i]["rmse"].as_f64().unwrap();
        let rays = |i: usize| methods[i]["rays_per_pixel"].as_f64().unwrap();
        assert_eq!([rays(0), rays(1), rays(5), rays(6)], [16.0, 16.0, 64.0, 256.0]);
        // The refinement adds 256 rays at some, not all, pixels; and lowers the error.
        assert!(rays(2) > 16.0 && rays(2) < 256.0, "{scene}: {}", rays(2));
        assert!(rmse(2) < rmse(0), "{scene}: {stdout}");
        // Within the default budget of 24 rays per pixel: fewer rays than the whole
        // refinement, some refined all the same, and less error than the filter alone.
        for i in [3, 4] {
            assert!(
                rays(i) > 16.0 && rays(i) <= 24.0 && rays(i) < rays(2),
                "{scene} {}: {}",
                names[i],
                rays(i)
            );
            assert!(rmse(i) < rmse(0), "{scene} {}: {stdout}", names[i]);
        }
        for (i, name) in names.iter().enumerate() {
            assert!(
                rmse(i).is_finite() && rmse(i) > 0.0 && rmse(i) < 0.5,
                "{scene} {name}: RMSE {}",
                rmse(i)
            );
        }
        // More rays, less error: a sanity check on the yardstick itself.
        assert!(rmse(6) < rmse(5) && rmse(5) < rmse(1), "{scene}: {stdout}");
        assert!(report["pixels"].as_u64().unwrap() > 48 * 40 / 2);
        // Each method's error split by region: four regions, pixel and error shares
        // summing to 1, and the regions' RMSEs recombining to the method's.
        for (i, m) in methods.iter().enumerate() {
            let regions = m["regions"].as_array().unwrap();
            assert_eq!(regions.len(), 4, "{scene}: {m}");
            let sum = |key: &str| regions.iter().map(|r| r[key].as_f64().unwrap()).sum::<f64>();
            assert!((sum("pixel_share") - 1.0).abs() < 1e-9, "{scene}: {m}");
            assert!((sum("error_share") - 1.0).abs() < 1e-9, "{scene}: {m}");
            let mse: f64 = regions
                .iter()
                .map(|r| r["pixel_share"].as_f64().unwrap() * r["rmse"].as_f64().unwrap().powi(2))
                .sum();
            assert!(
                (mse.sqrt() - rmse(i)).abs() < 1e-6 * rmse(i).max(1e-3),
                "{scene}: regions recombine to RMSE {} not {}",
                mse.sqrt(),
                rmse(i)
            );
        }
        assert!(stdout.contains("error by region"), "{stdout}");
        // The filtered image's error by window class: three classes whose pixel and error
        // shares sum to 1, recombining to the filtered method's RMSE (the classes take the
        // filter twin's mean in f64, the kernel sums in f32: equal to 1e-6 relative) and to
        // reference-64's over the same pixels.
        let windows = report["filter_windows"].as_array().unwrap();
        assert_eq!(windows.len(), 3, "{scene}: {windows:?}");
        let share = |key: &str| windows.iter().map(|c| c[key].as_f64().unwrap()).sum::<f64>();
        assert!((share("pixel_share") - 1.0).abs() < 1e-9, "{scene}: {windows:?}");
        assert!((share("error_share") - 1.0).abs() < 1e-9, "{scene}: {windows:?}");
        let recombined = |key: &str| {
            windows
                .iter()
                .map(|c| c["pixel_share"].as_f64().unwrap() * c[key].as_f64().unwrap().powi(2))
                .sum::<f64>()
                .sqrt()
        };
        for (key, i) in [("rmse", 0), ("reference_rmse", 5)] {
            assert!(
                (recombined(key) - rmse(i)).abs() < 1e-6 * rmse(i).max(1e-3),
                "{scene}: window classes recombine to {key} {} not {}",
                recombined(key),
                rmse(i)
            );
        }
        assert!(stdout.contains("filter windows"), "{stdout}");
        // Every method's image and the exact one, as EXR and as a 16-bit PNG holding the
        // same values to the PNG's step (rounded: at most half of 1/65535 away).
        for name in names.iter().copied().chain(["exact"]) {
            let exr = read_float_image(&dir.join("images").join(format!("{name}.exr"))).unwrap();
            let png = read_float_image(&dir.join("images").join(format!("{name}.png"))).unwrap();
            assert_eq!((exr.width, exr.height, png.width, png.height), (48, 40, 48, 40));
            let worst = exr
                .pixels
                .iter()
                .zip(&png.pixels)
                .map(|(e, p)| (e.clamp(0.0, 1.0) - p).abs())
                .fold(0.0f32, f32::max);
            assert!(
                worst <= 0.5 / 65535.0 + 1e-7,
                "{scene} {name}: PNG {worst} from the EXR"
            );
        }
    }
}

#[test]
fn render_writes_every_tracer() {
    let dir = out_dir("tracers");
    for tracer in ["exact", "packet", "per-ray", "reference:32"] {
        let file = format!("{}.exr", tracer.replace(':', "-"));
        let (ok, stdout, stderr) = penumbra(
            &dir,
            &["render", "--tracer", tracer, "--size", "40x30", "-o", &file],
        );
        assert!(ok, "render --tracer {tracer} failed:\n{stdout}\n{stderr}");
        assert_eq!(
            read_float_image(&dir.join(&file)).unwrap().pixels.len(),
            40 * 30,
            "{tracer}"
        );
    }
    let (ok, _, stderr) = penumbra(
        &dir,
        &["render", "--tracer", "exact", "--spp", "16", "-o", "x.exr"],
    );
    assert!(!ok && stderr.contains("--spp"), "{stderr}");
    let (ok, _, stderr) = penumbra(&dir, &["render", "--tracer", "mft", "--spp", "64", "-o", "x.exr"]);
    assert!(!ok && stderr.contains("exactly 16 rays"), "{stderr}");
    let (ok, _, stderr) = penumbra(&dir, &["render", "--tracer", "frusta"]);
    assert!(!ok && stderr.contains("unknown tracer"), "{stderr}");
    let (ok, _, stderr) = penumbra(
        &dir,
        &[
            "render",
            "lattice",
            "--tracer",
            "exact",
            "--time-budget",
            "0",
            "-o",
            "late.exr",
        ],
    );
    assert!(!ok && stderr.contains("time budget"), "{stderr}");
    assert!(
        !dir.join("late.exr").exists(),
        "a render out of time writes nothing"
    );
}

/// One MFT run of each frame, nothing else timed or counted.
const QUICK_MFT: &[&str] = &[
    "--runs",
    "1",
    "--tracers",
    "mft",
    "--no-counters",
    "--animate-frames",
    "0",
];

/// `penumbra bench playground --size 32x32 --json b.json ARGS…` in `dir`.
fn bench_playground(dir: &Path, args: &[&str]) -> (bool, String, String) {
    let mut all = vec!["bench", "playground", "--size", "32x32", "--json", "b.json"];
    all.extend_from_slice(args);
    penumbra(dir, &all)
}

#[test]
fn bench_prints_the_table_and_its_json() {
    let dir = out_dir("bench");
    let (ok, stdout, stderr) = bench_playground(&dir, &["--runs", "2", "--without-cr"]);
    assert!(ok, "bench failed:\n{stdout}\n{stderr}");
    for row in ["mft ", "mft-no-cr", "packet", "per-ray", "packet/MFT"] {
        assert!(stdout.contains(row), "no {row} in:\n{stdout}");
    }
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("b.json")).unwrap()).unwrap();
    let tracers = report["cases"][0]["tracers"].as_array().unwrap();
    assert_eq!(tracers.len(), 4);
    for t in tracers {
        assert_eq!(t["shadow_ms"].as_array().unwrap().len(), 2);
        assert!(t["shadow_ms_median"].as_f64().unwrap() > 0.0);
    }
    // The whole frame: every pass timed; each run's wall time covers that run's shadow pass
    // (the MFT tracer's runs are the frame's runs); the refined frame refined some pixels of
    // the playground's penumbrae.
    let frame = &report["cases"][0]["frame"];
    let ms = |k: &str| frame[k].as_f64().unwrap_or_else(|| panic!("no frame.{k}"));
    let passes = [
        "primary_ms_median",
        "shadow_ms_median",
        "shade_ms_median",
        "filter_ms_median",
    ];
    assert!(passes.iter().all(|&k| ms(k) > 0.0), "{frame}");
    let walls = frame["wall_ms"].as_array().unwrap();
    let shadows = tracers[0]["shadow_ms"].as_array().unwrap();
    assert_eq!(walls.len(), shadows.len());
    for (wall, shadow) in walls.iter().zip(shadows) {
        assert!(wall.as_f64().unwrap() >= shadow.as_f64().unwrap(), "{frame}");
    }
    assert!(
        ms("refine_ms_median") > 0.0 && frame["refined_pixels"].as_u64().unwrap() > 0,
        "{frame}"
    );
    assert!(stdout.contains("frame (mft, filtered)") && stdout.contains("refined frame"));
    let mft = &tracers[0]["counters"];
    assert!(mft["box_tests"].as_u64().unwrap() > 0 && mft["triangle_tests"].as_u64().unwrap() > 0);
    assert!(
        report["cases"][0]["reductions_vs_packet"]["box_tests"]
            .as_f64()
            .unwrap()
            > 1.0
    );
}

/// `--no-refine` leaves the refined frame out: no line for it, and null in the JSON, while
/// the plain frame is still timed.
#[test]
fn bench_without_the_refined_frame_reports_none() {
    let dir = out_dir("bench-no-refine");
    let (ok, stdout, stderr) = bench_playground(&dir, &[QUICK_MFT, &["--no-refine"]].concat());
    assert!(ok, "bench failed:\n{stdout}\n{stderr}");
    assert!(
        stdout.contains("frame (mft, filtered)") && !stdout.contains("refined frame"),
        "{stdout}"
    );
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("b.json")).unwrap()).unwrap();
    let frame = &report["cases"][0]["frame"];
    assert!(frame["shadow_ms_median"].as_f64().unwrap() > 0.0, "{frame}");
    for k in ["refine_ms_median", "refined_wall_ms_median", "refined_pixels"] {
        assert!(frame[k].is_null(), "frame.{k} should be null: {frame}");
    }
}

/// A view file with two lights benches each light as its own case (`FILE, light N`), each
/// with its own timings, and reports them added up.
#[test]
fn bench_with_a_two_light_view_benches_each_light() {
    let dir = out_dir("bench-lights");
    let view = penumbra::assets::default_scene().view();
    let mut second = view.light;
    second.corner += glam::Vec3::new(4.0, 0.0, -2.0);
    second.edge_u *= 0.5;
    second.edge_v *= 0.5;
    let json = serde_json::json!({ "camera": view.camera, "lights": [view.light, second] });
    std::fs::write(dir.join("two.json"), json.to_string()).unwrap();
    let (ok, stdout, stderr) = bench_playground(&dir, &[QUICK_MFT, &["--view", "two.json"]].concat());
    assert!(ok, "bench failed:\n{stdout}\n{stderr}");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("b.json")).unwrap()).unwrap();
    let cases = report["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 2, "{report}");
    for (i, case) in cases.iter().enumerate() {
        assert_eq!(case["view"], format!("two.json, light {}", i + 1));
        assert!(case["tracers"][0]["shadow_ms_median"].as_f64().unwrap() > 0.0);
    }
    // And the two added up: rays and each tracer's median shadow time.
    let totals = report["light_totals"].as_array().unwrap();
    assert_eq!(totals.len(), 1, "{report}");
    let total = &totals[0];
    assert_eq!(
        (total["view"].as_str(), total["lights"].as_u64()),
        (Some("two.json"), Some(2))
    );
    let sum = |key: &str| -> f64 { cases.iter().map(|c| c[key].as_f64().unwrap()).sum() };
    assert_eq!(total["shadow_rays"].as_f64().unwrap(), sum("shadow_rays"));
    let ms: f64 = cases
        .iter()
        .map(|c| c["tracers"][0]["shadow_ms_median"].as_f64().unwrap())
        .sum();
    assert_eq!(total["tracers"][0]["tracer"], "mft");
    // The bench adds the medians exactly as it writes them, but serde_json's default parser
    // reads a float back up to one ulp off (measured: 1 at most over 2 M bench-like values;
    // its exact `float_roundtrip` would also change how the CLI reads view files). Three
    // parsed values and one rounded addition: at most 3.5 ulps of the total.
    let total_ms = total["tracers"][0]["shadow_ms_median"].as_f64().unwrap();
    assert!(
        (total_ms - ms).abs() <= 4.0 * f64::EPSILON * total_ms,
        "total {total_ms} against the sum {ms}"
    );
    assert!(stdout.contains("two.json, all 2 lights"), "{stdout}");
}
