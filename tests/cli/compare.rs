//! `penumbra compare` on small images written with the library: the printed
//! metrics, the difference picture, and clear errors.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use penumbra::output::{FloatImage, HdrImage, read_rgba_image, write_float_image, write_image};

fn penumbra(args: &[&Path]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .output()
        .expect("the penumbra binary runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// A fresh folder for one test.
fn folder(test: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("cli_compare_{test}"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn float(width: u32, height: u32, pixels: Vec<f32>) -> FloatImage {
    FloatImage {
        width,
        height,
        pixels,
    }
}

#[test]
fn prints_metrics_and_writes_the_difference_picture() {
    let dir = folder("metrics");
    let (a, b, diff) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("diff.png"));
    // Errors 0, 0.25, 0.5, 0: MAE 0.1875, RMSE sqrt(0.078125) = 0.279508, PSNR 11.07 dB.
    write_float_image(&a, &float(2, 2, vec![0.0, 0.5, 1.0, 0.25])).unwrap();
    write_float_image(&b, &float(2, 2, vec![0.0, 0.25, 0.5, 0.25])).unwrap();
    let out = penumbra(&[Path::new("compare"), &a, &b, Path::new("--diff"), &diff]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    for line in [
        "RMSE      0.279508",
        "MAE       0.187500",
        "max       0.500000 at (0, 1)",
        "PSNR      11.07 dB",
        "channel   all (12 values)",
    ] {
        assert!(stdout.contains(line), "no '{line}' in:\n{stdout}");
    }
    // Scaled to the largest error: red there, green at half of it, blue where equal.
    let picture = read_rgba_image(&diff).unwrap();
    assert_eq!(
        picture.pixels,
        vec![
            [0.0, 0.0, 1.0, 1.0],
            [0.0, 1.0, 0.0, 1.0],
            [1.0, 0.0, 0.0, 1.0],
            [0.0, 0.0, 1.0, 1.0]
        ]
    );
}

#[test]
fn identical_pngs_and_one_channel() {
    let dir = folder("identical");
    let a = dir.join("a.png");
    let image = HdrImage {
        width: 3,
        height: 1,
        pixels: vec![[0.0, 0.1, 0.2], [0.3, 0.4, 0.5], [0.6, 0.7, 0.8]],
    };
    write_image(&a, &image, &Default::default()).unwrap();
    let out = penumbra(&[Path::new("compare"), &a, &a]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("PSNR      inf (identical)"),
        "{}",
        text(&out.stdout)
    );
    // Only green differs, by 0.1 in every pixel.
    let mut other = image.clone();
    other.pixels.iter_mut().for_each(|p| p[1] += 0.1);
    let (b, c) = (dir.join("b.exr"), dir.join("c.exr"));
    write_image(&b, &image, &Default::default()).unwrap();
    write_image(&c, &other, &Default::default()).unwrap();
    let red = penumbra(&[
        Path::new("compare"),
        &b,
        &c,
        Path::new("--channel"),
        Path::new("r"),
    ]);
    assert!(
        text(&red.stdout).contains("PSNR      inf"),
        "{}",
        text(&red.stdout)
    );
    let green = penumbra(&[
        Path::new("compare"),
        &b,
        &c,
        Path::new("--channel"),
        Path::new("g"),
    ]);
    let stdout = text(&green.stdout);
    assert!(stdout.contains("MAE       0.100000"), "{stdout}");
    assert!(stdout.contains("channel   g (3 values)"), "{stdout}");
}

#[test]
fn size_mismatch_names_both_files_and_sizes() {
    let dir = folder("mismatch");
    let (a, b) = (dir.join("a.exr"), dir.join("b.png"));
    write_float_image(&a, &float(4, 2, vec![0.5; 8])).unwrap();
    write_float_image(&b, &float(2, 4, vec![0.5; 8])).unwrap();
    let out = penumbra(&[Path::new("compare"), &a, &b]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    let expected = format!(
        "error: {} is 4×2 but {} is 2×4: images must be the same size to compare",
        a.display(),
        b.display()
    );
    assert_eq!(stderr.trim_end(), expected);
}

#[test]
fn unreadable_input_names_the_file() {
    let dir = folder("unreadable");
    let missing = dir.join("missing.exr");
    let bad = dir.join("image.bmp");
    std::fs::write(&bad, b"not an image").unwrap();
    // The operating system words a missing file its own way: only the name is checked.
    for (path, what) in [(&missing, ""), (&bad, "unsupported image format")] {
        let out = penumbra(&[Path::new("compare"), path, path]);
        assert_eq!(out.status.code(), Some(1));
        let stderr = text(&out.stderr);
        assert!(
            stderr.starts_with(&format!("error: {}", path.display())) && stderr.contains(what),
            "{stderr}"
        );
    }
}
