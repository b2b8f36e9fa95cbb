//! Error metrics between two equally sized float images (a test image against
//! a reference): RMSE, mean absolute error, max error and PSNR, plus a
//! false-colour picture of where they differ.
//!
//! Values are compared as given (linear for EXR, stored values for PNG). The
//! sums run in `f64`. A NaN in either image makes every metric NaN rather
//! than being skipped: a NaN in a render is a bug worth seeing.

/// Which values of an RGBA pixel are compared.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Channel {
    /// Red only (the value of a one-channel image).
    R,
    /// Green only.
    G,
    /// Blue only.
    B,
    /// Alpha only.
    A,
    /// Rec. 709 luminance `0.2126 r + 0.7152 g + 0.0722 b`, one value per pixel.
    Luminance,
    /// Red, green and blue, three values per pixel (alpha is left out).
    #[default]
    All,
}

impl Channel {
    /// The values this choice takes from `p`, written to `out`; returns how many (1 or 3).
    fn values(self, p: [f32; 4], out: &mut [f32; 3]) -> usize {
        let one = |out: &mut [f32; 3], v: f32| {
            out[0] = v;
            1
        };
        match self {
            Channel::R => one(out, p[0]),
            Channel::G => one(out, p[1]),
            Channel::B => one(out, p[2]),
            Channel::A => one(out, p[3]),
            Channel::Luminance => one(out, 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]),
            Channel::All => {
                *out = [p[0], p[1], p[2]];
                3
            }
        }
    }
}

/// How far a test image is from a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImageMetrics {
    /// Number of values compared (pixels × values per pixel).
    pub values: usize,
    /// Root mean square error.
    pub rmse: f64,
    /// Mean absolute error.
    pub mean_abs: f64,
    /// Largest absolute error.
    pub max_abs: f64,
    /// Index of the (first) pixel with the largest error.
    pub max_pixel: usize,
    /// Peak signal-to-noise ratio in dB for a peak of 1: `10·log10(1 / MSE)`;
    /// `+∞` for identical images.
    pub psnr: f64,
}

impl ImageMetrics {
    /// Metrics of one-channel images (for example visibility).
    ///
    /// # Panics
    ///
    /// When the two slices differ in length (the caller checks image sizes).
    pub fn of_values(test: &[f32], reference: &[f32]) -> ImageMetrics {
        assert_eq!(test.len(), reference.len(), "images of different sizes");
        Self::accumulate(
            test.iter()
                .zip(reference)
                .enumerate()
                .map(|(i, (&a, &b))| (i, (f64::from(a) - f64::from(b)).abs())),
        )
    }

    /// Metrics of RGBA images over the values `channel` picks.
    ///
    /// # Panics
    ///
    /// When the two slices differ in length (the caller checks image sizes).
    pub fn of_pixels(test: &[[f32; 4]], reference: &[[f32; 4]], channel: Channel) -> ImageMetrics {
        assert_eq!(test.len(), reference.len(), "images of different sizes");
        Self::accumulate(test.iter().zip(reference).enumerate().flat_map(|(i, (&a, &b))| {
            let (mut va, mut vb) = ([0.0; 3], [0.0; 3]);
            let n = channel.values(a, &mut va);
            channel.values(b, &mut vb);
            (0..n).map(move |k| (i, (f64::from(va[k]) - f64::from(vb[k])).abs()))
        }))
    }

    /// Metrics from `(pixel index, absolute error)` pairs.
    fn accumulate(errors: impl Iterator<Item = (usize, f64)>) -> ImageMetrics {
        let (mut values, mut sum, mut sum_sq) = (0usize, 0.0f64, 0.0f64);
        let (mut max_abs, mut max_pixel) = (0.0f64, 0usize);
        for (pixel, e) in errors {
            values += 1;
            sum += e;
            sum_sq += e * e;
            // NaN sticks: once the max is NaN no comparison replaces it.
            if e > max_abs || (e.is_nan() && !max_abs.is_nan()) {
                max_abs = e;
                max_pixel = pixel;
            }
        }
        let n = values.max(1) as f64;
        let mse = sum_sq / n;
        ImageMetrics {
            values,
            rmse: mse.sqrt(),
            mean_abs: sum / n,
            max_abs,
            max_pixel,
            psnr: if mse == 0.0 {
                f64::INFINITY
            } else {
                -10.0 * mse.log10()
            },
        }
    }
}

/// Per-pixel absolute difference for a channel choice: the largest over the
/// values it picks (so a pixel is as bad as its worst channel).
///
/// # Panics
///
/// When the two slices differ in length.
pub fn pixel_differences(test: &[[f32; 4]], reference: &[[f32; 4]], channel: Channel) -> Vec<f32> {
    assert_eq!(test.len(), reference.len(), "images of different sizes");
    test.iter()
        .zip(reference)
        .map(|(&a, &b)| {
            let (mut va, mut vb) = ([0.0; 3], [0.0; 3]);
            let n = channel.values(a, &mut va);
            channel.values(b, &mut vb);
            (0..n).map(|k| (va[k] - vb[k]).abs()).fold(0.0, f32::max)
        })
        .collect()
}

/// The false colour of `t` in `[0, 1]` (clamped; NaN is magenta): blue at 0,
/// through cyan, green and yellow, to red at 1. RGB in `[0, 1]`.
pub fn false_colour(t: f32) -> [f32; 3] {
    if t.is_nan() {
        return [1.0, 0.0, 1.0];
    }
    const STOPS: [[f32; 3]; 5] = [
        [0.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 0.0, 0.0],
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x as usize).min(3);
    let f = x - i as f32;
    std::array::from_fn(|c| STOPS[i][c] + (STOPS[i + 1][c] - STOPS[i][c]) * f)
}

/// A false-colour picture of absolute differences: `|d| / scale` through
/// [`false_colour`], so `scale` and above are red. `scale: None` uses the
/// largest difference (all blue when there is none).
pub fn difference_image(differences: &[f32], scale: Option<f32>) -> Vec<[f32; 3]> {
    let scale = scale.unwrap_or_else(|| {
        differences
            .iter()
            .copied()
            .filter(|d| !d.is_nan())
            .fold(0.0, f32::max)
    });
    differences
        .iter()
        .map(|&d| {
            let t = if scale > 0.0 || d.is_nan() { d / scale } else { 0.0 };
            false_colour(t)
        })
        .collect()
}
