//! `penumbra compare`: how far one image is from another (RMSE, mean and max
//! absolute error, PSNR), and a false-colour picture of where.

use std::path::PathBuf;

use penumbra::output::{HdrImage, read_rgba_image, write_display_image};
use penumbra::quality::metrics::{Channel, ImageMetrics, difference_image, pixel_differences};
use penumbra::{Error, Result};

/// `--channel` values.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum ChannelArg {
    /// Red (the value of a one-channel image such as a visibility AOV).
    R,
    /// Green.
    G,
    /// Blue.
    B,
    /// Alpha (1 where a file has none).
    A,
    /// Rec. 709 luminance of r, g, b.
    Luminance,
    /// Red, green and blue together (three values per pixel).
    All,
}

impl From<ChannelArg> for Channel {
    fn from(arg: ChannelArg) -> Channel {
        match arg {
            ChannelArg::R => Channel::R,
            ChannelArg::G => Channel::G,
            ChannelArg::B => Channel::B,
            ChannelArg::A => Channel::A,
            ChannelArg::Luminance => Channel::Luminance,
            ChannelArg::All => Channel::All,
        }
    }
}

/// Arguments of `penumbra compare`.
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// The image to measure (.png or .exr).
    #[arg(value_name = "A")]
    test: PathBuf,
    /// The reference it is measured against (.png or .exr), the same size.
    #[arg(value_name = "B")]
    reference: PathBuf,
    /// Also write a false-colour picture of |A − B| (blue 0, cyan, green, yellow, red at
    /// the scale) as .png or .exr.
    #[arg(long, value_name = "OUT")]
    diff: Option<PathBuf>,
    /// The difference shown red in the --diff picture; default: the largest difference.
    #[arg(long, requires = "diff", value_parser = parse_scale)]
    diff_scale: Option<f32>,
    /// Which values are compared. EXR values are compared as stored (linear);
    /// PNG samples as stored over their maximum (no sRGB decoding).
    #[arg(long, value_enum, default_value_t = ChannelArg::All)]
    channel: ChannelArg,
}

fn parse_scale(s: &str) -> std::result::Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(_) => Err("must be a positive number".into()),
        Err(e) => Err(format!("'{s}': {e}")),
    }
}

/// Reads both images, prints the metrics, writes the difference picture if asked.
pub fn run(args: &CompareArgs) -> Result<()> {
    if let Some(path) = &args.diff {
        super::check_output_folder(path)?;
    }
    let a = read_rgba_image(&args.test)?;
    let b = read_rgba_image(&args.reference)?;
    if (a.width, a.height) != (b.width, b.height) {
        return Err(Error::ImageSizeMismatch {
            a: args.test.clone(),
            a_size: (a.width, a.height),
            b: args.reference.clone(),
            b_size: (b.width, b.height),
        });
    }
    let channel = Channel::from(args.channel);
    let m = ImageMetrics::of_pixels(&a.pixels, &b.pixels, channel);
    let (x, y) = (m.max_pixel as u32 % a.width, m.max_pixel as u32 / a.width);
    outln!("A         {}", args.test.display());
    outln!(
        "B         {} ({}×{})",
        args.reference.display(),
        a.width,
        a.height
    );
    outln!(
        "channel   {} ({} values)",
        format!("{:?}", args.channel).to_lowercase(),
        m.values
    );
    outln!("RMSE      {:.6}", m.rmse);
    outln!("MAE       {:.6}", m.mean_abs);
    outln!("max       {:.6} at ({x}, {y})", m.max_abs);
    if m.psnr.is_infinite() {
        outln!("PSNR      inf (identical)");
    } else {
        outln!("PSNR      {:.2} dB (peak 1)", m.psnr);
    }
    if let Some(path) = &args.diff {
        let differences = pixel_differences(&a.pixels, &b.pixels, channel);
        let image = HdrImage {
            width: a.width,
            height: a.height,
            pixels: difference_image(&differences, args.diff_scale),
        };
        write_display_image(path, &image)?;
        let scale = args.diff_scale.map_or(m.max_abs, f64::from);
        outln!("wrote     {} (red = {scale:.6})", path.display());
    }
    Ok(())
}
