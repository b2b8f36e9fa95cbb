//! Tests of the writers and readers: round trips, the tone map's values, errors naming
//! the file, and files replaced whole.

use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use super::atomic_file::{replace_file, temp_path};
use super::tone_map::srgb_encode;
use super::*;
use crate::Error;

/// A fresh, empty folder for one test, removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new(test: &str) -> TempDir {
        let dir = std::env::temp_dir().join(format!("penumbra-output-{}-{test}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).expect("create the test folder");
        TempDir(dir)
    }

    fn join(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Names of every entry in the folder, sorted.
    fn entries(&self) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(&self.0)
            .expect("list the test folder")
            .map(|e| {
                e.expect("folder entry")
                    .file_name()
                    .to_string_lossy()
                    .into_owned()
            })
            .collect();
        names.sort();
        names
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = fs::remove_dir_all(&self.0);
    }
}

/// A small image with values from 0 up past 1 (and one negative), so the tone map's range shows.
fn sample_hdr() -> HdrImage {
    let (width, height) = (5, 3);
    let pixels = (0..width * height)
        .map(|i| {
            let v = i as f32 * 0.37;
            [v, 0.5 * v + 0.01, if i == 4 { -1.0 } else { 2.0 - 0.1 * v }]
        })
        .collect();
    HdrImage {
        width,
        height,
        pixels,
    }
}

fn sample_float() -> FloatImage {
    let (width, height) = (4, 3);
    let pixels = (0..width * height).map(|i| i as f32 / 9.0 - 0.2).collect();
    FloatImage {
        width,
        height,
        pixels,
    }
}

#[test]
fn tone_map_reference_values() {
    let tone = ToneMap::default();
    assert_eq!(tone.exposure, 1.0);
    assert_eq!(tone.apply(0.0), 0);
    assert_eq!(tone.apply(-3.0), 0);
    assert_eq!(tone.apply(f32::NAN), 0);
    assert_eq!(tone.apply(f32::INFINITY), 255);
    assert_eq!(tone.apply(1000.0), 255);
    // 1 − e⁻¹ = 0.632…, sRGB-encoded 0.8165…, × 255 = 208.2 → 208.
    let expected = (srgb_encode(1.0 - (-1.0f32).exp()) * 255.0).round() as u8;
    assert_eq!(tone.apply(1.0), expected);
    assert_eq!(expected, 208);
    // Monotonic: brighter never maps darker.
    let bytes: Vec<u8> = (0..1000).map(|i| tone.apply(i as f32 * 0.01)).collect();
    assert!(bytes.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(ToneMap { exposure: 0.0 }.apply(5.0), 0);
}

#[test]
fn srgb_encode_is_continuous_at_the_knee() {
    let knee = 0.003_130_8f32;
    let below = 12.92 * knee;
    let above = 1.055 * knee.powf(1.0 / 2.4) - 0.055;
    assert!((below - above).abs() < 1e-6, "{below} vs {above}");
    assert_eq!(srgb_encode(0.0), 0.0);
    assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
}

#[test]
fn exr_round_trip_is_exact() {
    let dir = TempDir::new("exr_round_trip");
    let image = sample_hdr();
    let path = dir.join("out.exr");
    write_image(&path, &image, &ToneMap::default()).expect("write EXR");
    let back = read_hdr_image(&path).expect("read EXR");
    assert_eq!(back, image);
    assert_eq!(dir.entries(), ["out.exr"]);
}

#[test]
fn png_round_trip_holds_the_tone_mapped_bytes() {
    let dir = TempDir::new("png_round_trip");
    let image = sample_hdr();
    let tone = ToneMap { exposure: 0.7 };
    let path = dir.join("out.png");
    write_image(&path, &image, &tone).expect("write PNG");
    let back = read_hdr_image(&path).expect("read PNG");
    assert_eq!((back.width, back.height), (image.width, image.height));
    for (stored, linear) in back.pixels.iter().zip(&image.pixels) {
        let bytes = stored.map(|s| (s * 255.0).round() as u8);
        assert_eq!(bytes, tone.apply_rgb(*linear), "pixel {linear:?}");
    }
    assert_eq!(dir.entries(), ["out.png"]);
}

/// The threaded tone map gives every pixel's bytes in order, across chunk boundaries
/// (more pixels than two chunks of 65536, and a partial last one).
#[test]
fn tone_mapping_all_pixels_equals_each_pixel_in_order() {
    let tone = ToneMap { exposure: 1.3 };
    let pixels: Vec<[f32; 3]> = (0..3 * 65_536 + 7)
        .map(|i| {
            let x = i as f32;
            [
                x * 1e-5,
                (x * 0.37).sin().abs() * 4.0,
                if i % 5 == 0 {
                    f32::NAN
                } else {
                    1e-3 * (i % 1000) as f32
                },
            ]
        })
        .collect();
    let bytes = tone.apply_pixels(&pixels);
    assert_eq!(bytes.len(), 3 * pixels.len());
    for (i, (b, &p)) in bytes.chunks_exact(3).zip(&pixels).enumerate() {
        assert_eq!(b, tone.apply_rgb(p), "pixel {i}");
    }
}

#[test]
fn extension_is_case_insensitive() {
    let dir = TempDir::new("extension_case");
    let image = sample_hdr();
    write_image(&dir.join("a.PNG"), &image, &ToneMap::default()).expect("write .PNG");
    write_image(&dir.join("b.Exr"), &image, &ToneMap::default()).expect("write .Exr");
    assert_eq!(read_hdr_image(&dir.join("b.Exr")).expect("read .Exr"), image);
    assert_eq!(dir.entries(), ["a.PNG", "b.Exr"]);
}

#[test]
fn float_exr_round_trip_is_exact() {
    let dir = TempDir::new("float_exr");
    let image = sample_float();
    let path = dir.join("vis.exr");
    write_float_image(&path, &image).expect("write EXR");
    assert_eq!(read_float_image(&path).expect("read EXR"), image);
    // Stored as gray RGB.
    let rgb = read_hdr_image(&path).expect("read EXR as RGB");
    assert!(rgb.pixels.iter().zip(&image.pixels).all(|(p, &v)| *p == [v; 3]));
}

#[test]
fn float_png_round_trip_is_16_bit_linear() {
    let dir = TempDir::new("float_png");
    let image = sample_float();
    let path = dir.join("vis.png");
    write_float_image(&path, &image).expect("write PNG");
    let back = read_float_image(&path).expect("read PNG");
    assert_eq!((back.width, back.height), (image.width, image.height));
    for (&stored, &v) in back.pixels.iter().zip(&image.pixels) {
        let expected = (v.clamp(0.0, 1.0) * 65535.0).round() / 65535.0;
        assert!(
            (stored - expected).abs() <= 1e-7,
            "{v}: stored {stored}, expected {expected}"
        );
    }
    let decoded = image::open(&path).expect("decode with the image crate");
    assert_eq!(decoded.color(), image::ColorType::L16);
}

#[test]
fn display_png_holds_the_values_and_reads_back_as_rgba() {
    let dir = TempDir::new("display_png");
    let image = HdrImage {
        width: 2,
        height: 1,
        pixels: vec![[0.0, 0.5, 1.0], [2.0, -1.0, f32::NAN]],
    };
    let path = dir.join("diff.png");
    write_display_image(&path, &image).unwrap();
    let back = read_rgba_image(&path).unwrap();
    assert_eq!((back.width, back.height), (2, 1));
    assert_eq!(
        back.pixels,
        vec![[0.0, 128.0 / 255.0, 1.0, 1.0], [1.0, 0.0, 0.0, 1.0]]
    );
    // A one-channel 16-bit PNG reads back as gray with alpha 1.
    let gray = dir.join("gray.png");
    write_float_image(&gray, &sample_float()).unwrap();
    let back = read_rgba_image(&gray).unwrap();
    let expected = read_float_image(&gray).unwrap().pixels;
    for (p, v) in back.pixels.iter().zip(expected) {
        assert_eq!(*p, [v, v, v, 1.0]);
    }
}

#[test]
fn unsupported_extension_is_an_error_naming_the_file() {
    let dir = TempDir::new("bad_extension");
    for name in ["out.bmp", "out", "out.png.txt"] {
        let path = dir.join(name);
        let err = write_image(&path, &sample_hdr(), &ToneMap::default()).expect_err(name);
        let text = err.to_string();
        assert!(matches!(err, Error::Output { .. }), "{text}");
        assert!(
            text.contains(name) && text.contains(".png") && text.contains(".exr"),
            "{text}"
        );
        assert!(write_float_image(&path, &sample_float()).is_err());
    }
    assert!(dir.entries().is_empty());
}

#[test]
fn pixel_count_must_match_the_size() {
    let dir = TempDir::new("size_mismatch");
    let path = dir.join("out.exr");
    let mut image = sample_hdr();
    image.width += 1;
    let err = write_image(&path, &image, &ToneMap::default()).expect_err("too few pixels");
    assert!(err.to_string().contains("out.exr"), "{err}");
    let empty = HdrImage {
        width: 0,
        height: 0,
        pixels: Vec::new(),
    };
    assert!(write_image(&dir.join("empty.png"), &empty, &ToneMap::default()).is_err());
    let float = FloatImage {
        width: 2,
        height: 2,
        pixels: vec![0.0; 5],
    };
    assert!(write_float_image(&dir.join("f.png"), &float).is_err());
    // Big dimensions whose product overflows u32 must not wrap around to a match.
    let huge = FloatImage {
        width: 65536,
        height: 65536,
        pixels: Vec::new(),
    };
    assert!(write_float_image(&dir.join("huge.exr"), &huge).is_err());
    assert!(dir.entries().is_empty());
}

#[test]
fn writing_into_a_missing_folder_fails() {
    let dir = TempDir::new("missing_folder");
    let path = dir.join("no-such-folder").join("out.png");
    let err = write_image(&path, &sample_hdr(), &ToneMap::default()).expect_err("no folder");
    assert!(matches!(err, Error::Io { .. }));
    assert!(err.to_string().contains("out.png"), "{err}");
    assert!(dir.entries().is_empty());
}

#[test]
fn a_directory_in_the_way_is_an_error_and_stays() {
    let dir = TempDir::new("directory_target");
    let target = dir.join("out.exr");
    fs::create_dir(&target).expect("create a folder named like the target");
    fs::write(target.join("keep"), b"x").expect("fill it");
    let err = write_image(&target, &sample_hdr(), &ToneMap::default()).expect_err("folder target");
    assert!(err.to_string().contains("out.exr"), "{err}");
    assert_eq!(dir.entries(), ["out.exr"], "no temporary file left behind");
    assert_eq!(fs::read(target.join("keep")).expect("still there"), b"x");
}

#[test]
fn a_failed_write_leaves_the_old_file_and_no_temporary() {
    let dir = TempDir::new("failed_write");
    let path = dir.join("out.png");
    fs::write(&path, b"old contents").expect("pre-existing target");

    // Fails half-way through writing the temporary file.
    let err = replace_file(&path, |file| {
        file.write_all(b"half")?;
        Err(io::Error::other("disk full"))
    })
    .expect_err("injected failure");
    assert!(
        err.to_string().contains("out.png") && err.to_string().contains("disk full"),
        "{err}"
    );
    assert_eq!(fs::read(&path).expect("target"), b"old contents");
    assert_eq!(dir.entries(), ["out.png"]);

    // Fails before any file is touched.
    let mut bad = sample_hdr();
    bad.pixels.pop();
    assert!(write_image(&path, &bad, &ToneMap::default()).is_err());
    assert_eq!(fs::read(&path).expect("target"), b"old contents");
    assert_eq!(dir.entries(), ["out.png"]);

    // And a successful write replaces it.
    write_image(&path, &sample_hdr(), &ToneMap::default()).expect("write PNG");
    assert_eq!(read_hdr_image(&path).expect("read").width, 5);
    assert_eq!(dir.entries(), ["out.png"]);
}

#[test]
fn temporary_files_sit_beside_the_target() {
    let pid = std::process::id();
    let tmp = temp_path(Path::new("renders/out.png"), 7).expect("a file name");
    assert_eq!(tmp, Path::new("renders").join(format!(".out.png.tmp-{pid}-7")));
    // `parent()` of a bare name is "", which must mean "." rather than an error.
    let tmp = temp_path(Path::new("out.png"), 0).expect("a file name");
    assert_eq!(tmp, Path::new(".").join(format!(".out.png.tmp-{pid}-0")));
    assert_eq!(temp_path(Path::new("/"), 0), None);
}

#[test]
fn reading_a_missing_file_names_it() {
    let dir = TempDir::new("missing_file");
    let err = read_hdr_image(&dir.join("nothing.exr")).expect_err("missing");
    assert!(
        matches!(err, Error::Io { .. }) && err.to_string().contains("nothing.exr"),
        "{err}"
    );
    fs::write(dir.join("junk.png"), b"not a png").expect("write junk");
    let err = read_float_image(&dir.join("junk.png")).expect_err("junk");
    assert!(matches!(err, Error::Output { .. }), "{err}");
}
