//! PNG and EXR encoding and decoding of the image types, format by extension; files are
//! replaced whole ([`super::atomic_file`]).

use std::fs;
use std::io::{Cursor, Write};
use std::path::Path;

use image::codecs::openexr::OpenExrEncoder;
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder, ImageFormat};

use super::atomic_file::replace_file;
use super::{FloatImage, HdrImage, RgbaImage, SUPPORTED_EXTENSIONS, ToneMap};
use crate::{Error, Result};

/// Writes `image` to `path`: `.png` as 8-bit sRGB RGB through `tone`, `.exr` as
/// 32-bit float linear RGB (no tone map). The extension is matched
/// case-insensitively.
///
/// The file is replaced whole or not at all (see the [module docs](super)).
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
                let srgb = tone.apply_pixels(&image.pixels);
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
/// The file is replaced whole or not at all (see the [module docs](super)).
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
/// The file is replaced whole or not at all (see the [module docs](super)).
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

pub(super) fn output_error(path: &Path, message: impl Into<String>) -> Error {
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
