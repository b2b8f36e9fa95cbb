//! Writing (and reading back) the renderer's images: linear HDR as EXR,
//! tone-mapped sRGB as PNG.
//!
//! The format follows the file's extension, case-insensitive: `.png` or `.exr`
//! ([`SUPPORTED_EXTENSIONS`]); anything else is an [`Error::Output`].
//!
//! # PNG tone map
//!
//! A PNG holds 8-bit sRGB, so linear radiance goes through [`ToneMap`] per
//! channel:
//!
//! ```text
//! t = 1 − exp(−exposure · c)          exponential map: 0 stays 0, ∞ → 1, no hard clip
//! s = 12.92 · t                        if t ≤ 0.0031308   (sRGB transfer function)
//!   = 1.055 · t^(1/2.4) − 0.055        otherwise
//! byte = round(255 · clamp(s, 0, 1))   NaN → 0
//! ```
//!
//! EXR files hold the linear values as 32-bit floats, untouched.
//!
//! # Whole or not at all
//!
//! Every writer encodes the image into memory first, writes it to a temporary
//! file beside the target (`.NAME.tmp-PID-N`), syncs it, and renames it onto
//! the target. A reader of the target sees the old file or the new one, never
//! half of one; on failure the temporary file is removed and an existing
//! target is left as it was.

use std::ffi::OsString;
use std::fs::{self, File, OpenOptions};
use std::io::{self, Cursor, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use image::codecs::openexr::OpenExrEncoder;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder, ImageFormat};

use crate::{Error, Result};

/// The file extensions the writers and readers understand (lower case, without the dot).
pub const SUPPORTED_EXTENSIONS: [&str; 2] = ["png", "exr"];

/// A linear RGB image (radiance or irradiance), row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` linear RGB triples; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<[f32; 3]>,
}

/// A one-channel float image (for example the visibility AOV), row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct FloatImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` values; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<f32>,
}

/// A four-channel float image as read from a file, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbaImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width · height` RGBA values; pixel `(x, y)` is `pixels[y · width + x]`.
    pub pixels: Vec<[f32; 4]>,
}

/// How linear radiance becomes 8-bit sRGB for PNG output.
///
/// Per channel: `t = 1 − exp(−exposure · c)`, then the sRGB transfer function,
/// then rounding to 8 bits (see the [module docs](self) for the exact
/// formulas). The exponential map keeps 0 at 0, is close to linear
/// (`≈ exposure · c`) in the shadows, and approaches white smoothly instead of
/// clipping, so bright lit areas keep their gradients. It works per channel, so
/// very bright saturated colours drift toward white.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToneMap {
    /// Scale applied to linear values before the map. Larger brightens; 1.0
    /// maps radiance 1 to `1 − e⁻¹ ≈ 0.63` (sRGB byte 208). 0 gives black.
    pub exposure: f32,
}

impl Default for ToneMap {
    /// Exposure 1.0.
    fn default() -> Self {
        ToneMap { exposure: 1.0 }
    }
}

impl ToneMap {
    /// The 8-bit sRGB value of the linear channel value `c`.
    ///
    /// Negative values and NaN map to 0, +∞ to 255.
    pub fn apply(&self, c: f32) -> u8 {
        let t = 1.0 - (-self.exposure * c).exp();
        let s = srgb_encode(t.clamp(0.0, 1.0));
        // `as u8` saturates and maps NaN to 0, which is the documented result for NaN.
        (s * 255.0).round() as u8
    }

    /// The 8-bit sRGB pixel of a linear RGB pixel ([`ToneMap::apply`] per channel).
    pub fn apply_rgb(&self, rgb: [f32; 3]) -> [u8; 3] {
        rgb.map(|c| self.apply(c))
    }
}

/// The sRGB transfer function (linear → encoded), for `t` in 0..=1.
fn srgb_encode(t: f32) -> f32 {
    if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    }
}

/// Writes `image` to `path`: `.png` as 8-bit sRGB RGB through `tone`, `.exr` as
/// 32-bit float linear RGB (no tone map). The extension is matched
/// case-insensitively.
///
/// The file is replaced whole or not at all (see the [module docs](self)).
///
/// # Errors
///
/// [`Error::Output`] for an unsupported extension, an empty image, or a pixel
/// count that is not `width · height`; [`Error::Io`] when the file cannot be
/// written. Both name `path`.
pub fn write_image(path: &Path, image: &HdrImage, tone: &ToneMap) -> Result<()> {
    encode_to_file(
        path,
        image.width,
        image.height,
        image.pixels.len(),
        |format, bytes| match format {
            ImageFormat::Png => {
                let srgb: Vec<u8> = image.pixels.iter().flat_map(|&p| tone.apply_rgb(p)).collect();
                PngEncoder::new(bytes).write_image(&srgb, image.width, image.height, ExtendedColorType::Rgb8)
            }
            _ => encode_exr(bytes, &image.pixels, image.width, image.height),
        },
    )
}

/// Writes the one-channel `image` to `path`: `.exr` as a 32-bit float RGB
/// image with R = G = B = the value (the `image` crate writes no one-channel
/// EXR), `.png` as 16-bit grayscale holding `round(65535 · clamp(v, 0, 1))`,
/// linear (no transfer function; NaN → 0). The extension is matched
/// case-insensitively.
///
/// The file is replaced whole or not at all (see the [module docs](self)).
///
/// # Errors
///
/// As for [`write_image`].
pub fn write_float_image(path: &Path, image: &FloatImage) -> Result<()> {
    encode_to_file(
        path,
        image.width,
        image.height,
        image.pixels.len(),
        |format, bytes| match format {
            ImageFormat::Png => {
                // Native-endian u16 samples: the PNG encoder swaps them to big endian itself.
                let samples: Vec<u16> = image
                    .pixels
                    .iter()
                    .map(|&v| (v.clamp(0.0, 1.0) * 65535.0).round() as u16)
                    .collect();
                PngEncoder::new(bytes).write_image(
                    bytemuck::cast_slice(&samples),
                    image.width,
                    image.height,
                    ExtendedColorType::L16,
                )
            }
            _ => {
                let rgb: Vec<[f32; 3]> = image.pixels.iter().map(|&v| [v; 3]).collect();
                encode_exr(bytes, &rgb, image.width, image.height)
            }
        },
    )
}

/// Writes display values (already mapped to `[0, 1]`, for example a false-colour
/// picture) to `path`: `.png` as 8-bit RGB holding `round(255 · clamp(v, 0, 1))`
/// with no tone map or transfer function (NaN → 0), `.exr` as 32-bit floats
/// as given.
///
/// The file is replaced whole or not at all (see the [module docs](self)).
///
/// # Errors
///
/// As for [`write_image`].
pub fn write_display_image(path: &Path, image: &HdrImage) -> Result<()> {
    encode_to_file(
        path,
        image.width,
        image.height,
        image.pixels.len(),
        |format, bytes| match format {
            ImageFormat::Png => {
                // `as u8` saturates and maps NaN to 0.
                let rgb: Vec<u8> = image
                    .pixels
                    .iter()
                    .flat_map(|p| p.map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8))
                    .collect();
                PngEncoder::new(bytes).write_image(&rgb, image.width, image.height, ExtendedColorType::Rgb8)
            }
            _ => encode_exr(bytes, &image.pixels, image.width, image.height),
        },
    )
}

/// The writers' common part: checks the extension and the pixel count, lets
/// `encode` fill a buffer for the file's format, and replaces `path` with it whole.
fn encode_to_file(
    path: &Path,
    width: u32,
    height: u32,
    len: usize,
    encode: impl FnOnce(ImageFormat, &mut Vec<u8>) -> image::ImageResult<()>,
) -> Result<()> {
    let format = format_of(path)?;
    check_size(path, width, height, len)?;
    let mut bytes = Vec::new();
    encode(format, &mut bytes).map_err(|e| output_error(path, format!("cannot encode the image: {e}")))?;
    replace_file(path, |file| file.write_all(&bytes))
}

/// 32-bit float linear RGB EXR of `pixels`.
fn encode_exr(bytes: &mut Vec<u8>, pixels: &[[f32; 3]], width: u32, height: u32) -> image::ImageResult<()> {
    OpenExrEncoder::new(Cursor::new(bytes)).write_image(
        bytemuck::cast_slice(pixels),
        width,
        height,
        ExtendedColorType::Rgb32F,
    )
}

/// Reads an RGBA image from `path` (`.exr` or `.png`, by extension): alpha
/// is 1 where the file has none, and a gray image gives R = G = B.
///
/// Values come back as for [`read_hdr_image`] (EXR as stored, PNG samples
/// divided by the format's maximum, no sRGB decoding).
///
/// # Errors
///
/// As for [`read_hdr_image`].
pub fn read_rgba_image(path: &Path) -> Result<RgbaImage> {
    let image = read_dynamic(path)?.into_rgba32f();
    let (width, height) = image.dimensions();
    let pixels = image.pixels().map(|p| p.0).collect();
    Ok(RgbaImage {
        width,
        height,
        pixels,
    })
}

/// Reads an RGB image from `path` (`.exr` or `.png`, by extension).
///
/// EXR values come back as stored (alpha, if any, dropped); PNG samples come
/// back as stored divided by the format's maximum (255 for 8 bits), with no
/// sRGB decoding — enough to check what [`write_image`] wrote.
///
/// # Errors
///
/// [`Error::Io`] when the file cannot be read, [`Error::Output`] for an
/// unsupported extension or undecodable contents.
pub fn read_hdr_image(path: &Path) -> Result<HdrImage> {
    let image = read_dynamic(path)?.into_rgb32f();
    let (width, height) = image.dimensions();
    let pixels = image.pixels().map(|p| p.0).collect();
    Ok(HdrImage {
        width,
        height,
        pixels,
    })
}

/// Reads a one-channel image from `path` (`.exr` or `.png`, by extension): the
/// first (red or gray) channel.
///
/// EXR values come back as stored; PNG samples as stored divided by the
/// format's maximum (65535 for the 16-bit files [`write_float_image`] writes).
///
/// # Errors
///
/// As for [`read_hdr_image`].
pub fn read_float_image(path: &Path) -> Result<FloatImage> {
    let image = read_dynamic(path)?.into_rgb32f();
    let (width, height) = image.dimensions();
    let pixels = image.pixels().map(|p| p.0[0]).collect();
    Ok(FloatImage {
        width,
        height,
        pixels,
    })
}

fn read_dynamic(path: &Path) -> Result<image::DynamicImage> {
    let format = format_of(path)?;
    let bytes = fs::read(path).map_err(|source| Error::Io {
        path: path.to_owned(),
        source,
    })?;
    image::load_from_memory_with_format(&bytes, format)
        .map_err(|e| output_error(path, format!("cannot decode the image: {e}")))
}

fn output_error(path: &Path, message: impl Into<String>) -> Error {
    Error::Output {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// The image format for `path`'s extension.
fn format_of(path: &Path) -> Result<ImageFormat> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("png") => Ok(ImageFormat::Png),
        Some("exr") => Ok(ImageFormat::OpenExr),
        other => {
            let found = match other {
                Some(e) => format!("extension `.{e}`"),
                None => "no usable extension".to_owned(),
            };
            let supported: Vec<String> = SUPPORTED_EXTENSIONS.iter().map(|e| format!(".{e}")).collect();
            Err(output_error(
                path,
                format!(
                    "unsupported image format ({found}); supported: {}",
                    supported.join(", ")
                ),
            ))
        }
    }
}

/// Checks that a `width × height` image holds `len` pixels and is not empty.
fn check_size(path: &Path, width: u32, height: u32, len: usize) -> Result<()> {
    // u64: `width · height` can overflow a 32-bit usize.
    let expected = u64::from(width) * u64::from(height);
    if expected == 0 {
        return Err(output_error(
            path,
            format!("the image is empty ({width}×{height})"),
        ));
    }
    if expected != len as u64 {
        return Err(output_error(
            path,
            format!("the image is {width}×{height} = {expected} pixels but holds {len}"),
        ));
    }
    Ok(())
}

/// Writes `bytes` to `path` whole or not at all (a temporary file beside it, renamed into place; see the [module docs](self)): for reports
/// and other small files.
pub fn write_bytes_atomically(path: &Path, bytes: &[u8]) -> Result<()> {
    replace_file(path, |f| f.write_all(bytes))
}

/// Replaces `path` with what `write` puts into a fresh file: written to a
/// temporary file in the same directory (so the rename stays on one file
/// system and is atomic), synced, then renamed onto `path`.
///
/// On any failure the temporary file is removed and `path` is untouched.
fn replace_file(path: &Path, write: impl FnOnce(&mut File) -> io::Result<()>) -> Result<()> {
    let io_error = |source| Error::Io {
        path: path.to_owned(),
        source,
    };
    let (tmp_path, mut file) = create_temp_beside(path)?;
    let written = write(&mut file).and_then(|()| file.sync_all()).and_then(|()| {
        // Closed before the rename: Windows cannot rename an open file.
        drop(file);
        fs::rename(&tmp_path, path)
    });
    if let Err(source) = written {
        // Best effort: the write error is the one worth reporting.
        let _ = fs::remove_file(&tmp_path);
        return Err(io_error(source));
    }
    sync_directory(&tmp_path);
    Ok(())
}

/// Creates `.NAME.tmp-PID-N` beside `path`, a name no other writer (thread or process) uses.
fn create_temp_beside(path: &Path) -> Result<(PathBuf, File)> {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    // A temporary file left by a crashed process with the same id may exist: take the next number.
    let mut attempts = 0;
    loop {
        let tmp_path = temp_path(path, NEXT.fetch_add(1, Ordering::Relaxed))
            .ok_or_else(|| output_error(path, "the path does not name a file"))?;
        match OpenOptions::new().write(true).create_new(true).open(&tmp_path) {
            Ok(file) => return Ok((tmp_path, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists && attempts < 100 => attempts += 1,
            Err(source) => {
                return Err(Error::Io {
                    path: path.to_owned(),
                    source,
                });
            }
        }
    }
}

/// `.NAME.tmp-PID-N` in `path`'s folder (`.` for a bare file name); `None`
/// when `path` names no file (`/`, `..`).
fn temp_path(path: &Path, n: u64) -> Option<PathBuf> {
    let name = path.file_name()?;
    let dir = match path.parent() {
        Some(parent) if !parent.as_os_str().is_empty() => parent,
        _ => Path::new("."),
    };
    let mut tmp_name = OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".tmp-{}-{n}", std::process::id()));
    Some(dir.join(tmp_name))
}

/// Makes the rename itself durable by syncing the directory that holds `file`
/// (Unix only; best effort, since the file is already complete either way).
fn sync_directory(file: &Path) {
    #[cfg(unix)]
    if let Some(dir) = file.parent().filter(|d| !d.as_os_str().is_empty()) {
        if let Ok(dir) = File::open(dir) {
            let _ = dir.sync_all();
        }
    }
    #[cfg(not(unix))]
    let _ = file;
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
