//! Where the discontinuity filter's error comes from, by what happened to each pixel's
//! window, for `penumbra quality`. A pixel's window is *full* when the filter averages
//! every tap; *cut by visibility* when the geometry test keeps every tap but the
//! visibility test drops some (a sharp shadow transition); *cut by geometry* when depth,
//! normal or the image border drops some (silhouettes, creases). Per class,
//! [`filter_window_errors`] splits the filtered error of each pixel into the window's
//! **bias** (the exact visibility averaged over the same taps, against the exact value:
//! what a noiseless image would still lose in that window) and **sampling** (the rest:
//! the rays' own error that the window did not average away). The two add up to the
//! filtered error pixel by pixel.

use crate::contract::filter::{FULL_WINDOW, FilterParams};
use crate::reference::filter::{paired_taps, tap_weight};

/// What the filter's tests did to a pixel's window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WindowClass {
    /// Every tap and its mirror image averaged: the 16 sample sets at weight 1 each.
    Full,
    /// The geometry test keeps every tap; the visibility test drops some.
    CutByVisibility,
    /// Depth, normal or the image border drops taps.
    CutByGeometry,
}

impl WindowClass {
    /// Every class, in the order of the enum.
    pub const ALL: [WindowClass; 3] = [
        WindowClass::Full,
        WindowClass::CutByVisibility,
        WindowClass::CutByGeometry,
    ];

    /// Short name for tables and JSON.
    pub fn name(self) -> &'static str {
        match self {
            WindowClass::Full => "full",
            WindowClass::CutByVisibility => "cut by visibility",
            WindowClass::CutByGeometry => "cut by geometry",
        }
    }
}

/// One class's part of the filtered image's error.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct WindowClassError {
    /// The class's name ([`WindowClass::name`]).
    pub class: &'static str,
    /// Fraction of the compared pixels in this class.
    pub pixel_share: f64,
    /// The class's share of the filtered image's summed squared error.
    pub error_share: f64,
    /// RMSE of the filtered values over the class's pixels.
    pub rmse: f64,
    /// RMSE of the window's bias: the exact visibility averaged over the same taps,
    /// against the exact value.
    pub bias_rmse: f64,
    /// RMSE of the rest (filtered − exact averaged over the same taps).
    pub sampling_rmse: f64,
    /// Rays the window averages, on average over the class: 16 × the taps' weight sum.
    pub mean_rays: f64,
    /// RMSE of the `reference` values over the same pixels.
    pub reference_rmse: f64,
}

/// The weighted mean of `values` over the taps `bits` of `(x, y)`'s window.
fn mean_over_taps(values: &[f32], width: usize, x: usize, y: usize, bits: u32) -> (f64, f64) {
    let (mut sum, mut weight) = (0.0f64, 0.0f64);
    for k in 0..25u32 {
        if bits & (1 << k) != 0 {
            let nx = (x as i32 + k as i32 % 5 - 2) as usize;
            let ny = (y as i32 + k as i32 / 5 - 2) as usize;
            let w = f64::from(tap_weight(k));
            sum += w * f64::from(values[ny * width + nx]);
            weight += w;
        }
    }
    (sum / weight, weight)
}

/// Each [`WindowClass`]'s part of the error of the filter applied to `unfiltered`
/// visibility, against `exact`, over the pixels where `compared` is true; and
/// `reference`'s RMSE over the same pixels. The window is the filter's CPU twin
/// ([`paired_taps`] with `params`); its mean is taken in `f64`, so the filtered values
/// here match the kernel's to rounding. `depth` and `normal` are the G-buffer's, row-major.
///
/// # Panics
///
/// If a slice does not hold `params.width · params.height` values (a caller bug).
pub fn filter_window_errors(
    params: &FilterParams,
    unfiltered: &[f32],
    depth: &[f32],
    normal: &[[f32; 3]],
    exact: &[f32],
    reference: &[f32],
    compared: &[bool],
) -> Vec<WindowClassError> {
    let n = params.pixel_count();
    assert!(
        [
            unfiltered.len(),
            depth.len(),
            normal.len(),
            exact.len(),
            reference.len(),
            compared.len()
        ]
        .iter()
        .all(|&l| l == n),
        "filter_window_errors: a {}×{} image needs {n} values in every slice",
        params.width,
        params.height
    );
    let values: Vec<[f32; 4]> = unfiltered.iter().map(|&v| [0.0, 0.0, 0.0, v]).collect();
    // The geometry test alone: a visibility tolerance no difference of visibilities exceeds.
    let geometry_only = FilterParams {
        visibility_tolerance: f32::MAX,
        ..*params
    };
    let width = params.width as usize;
    #[derive(Default, Clone, Copy)]
    struct Sums {
        pixels: usize,
        filtered: f64,
        bias: f64,
        sampling: f64,
        weight: f64,
        reference: f64,
    }
    let mut sums = [Sums::default(); WindowClass::ALL.len()];
    for y in 0..params.height {
        for x in 0..params.width {
            let ix = y as usize * width + x as usize;
            if !compared[ix] || depth[ix] <= 0.0 {
                continue;
            }
            let taps = paired_taps(params, &values, depth, normal, x, y);
            let class = if paired_taps(&geometry_only, &values, depth, normal, x, y) != FULL_WINDOW {
                WindowClass::CutByGeometry
            } else if taps != FULL_WINDOW {
                WindowClass::CutByVisibility
            } else {
                WindowClass::Full
            };
            let (filtered, weight) = mean_over_taps(unfiltered, width, x as usize, y as usize, taps);
            let (exact_mean, _) = mean_over_taps(exact, width, x as usize, y as usize, taps);
            let e = f64::from(exact[ix]);
            let s = &mut sums[class as usize];
            s.pixels += 1;
            s.filtered += (filtered - e).powi(2);
            s.bias += (exact_mean - e).powi(2);
            s.sampling += (filtered - exact_mean).powi(2);
            s.weight += weight;
            s.reference += (f64::from(reference[ix]) - e).powi(2);
        }
    }
    let pixels: usize = sums.iter().map(|s| s.pixels).sum();
    let squared: f64 = sums.iter().map(|s| s.filtered).sum();
    let share = |part: f64, whole: f64| if whole > 0.0 { part / whole } else { 0.0 };
    WindowClass::ALL
        .iter()
        .map(|&c| {
            let s = sums[c as usize];
            let rms = |sum: f64| share(sum, s.pixels as f64).sqrt();
            WindowClassError {
                class: c.name(),
                pixel_share: share(s.pixels as f64, pixels as f64),
                error_share: share(s.filtered, squared),
                rmse: rms(s.filtered),
                bias_rmse: rms(s.bias),
                sampling_rmse: rms(s.sampling),
                mean_rays: 16.0 * share(s.weight, s.pixels as f64),
                reference_rmse: rms(s.reference),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::reference::filter::filter_pixel;

    const W: u32 = 12;
    const UP: [f32; 3] = [0.0, 0.0, 1.0];

    fn class(errors: &[WindowClassError], c: WindowClass) -> WindowClassError {
        errors[c as usize]
    }

    /// A 12×12 plane at depth 2 facing the camera; every pixel compared.
    fn plane() -> (FilterParams, Vec<f32>, Vec<[f32; 3]>, Vec<bool>) {
        let n = (W * W) as usize;
        (FilterParams::new(W, W), vec![2.0; n], vec![UP; n], vec![true; n])
    }

    #[test]
    fn an_even_image_has_full_windows_inside_and_cut_ones_at_the_border() {
        let (params, depth, normal, compared) = plane();
        let v = vec![0.5; depth.len()];
        let e = filter_window_errors(&params, &v, &depth, &normal, &v, &v, &compared);
        // The windows of the inner 8×8 pixels lie inside the image; the border's do not.
        assert_eq!(class(&e, WindowClass::Full).pixel_share, 64.0 / 144.0);
        assert_eq!(class(&e, WindowClass::CutByGeometry).pixel_share, 80.0 / 144.0);
        assert_eq!(class(&e, WindowClass::CutByVisibility).pixel_share, 0.0);
        // A full window averages the 16 sets: 256 rays.
        assert_eq!(class(&e, WindowClass::Full).mean_rays, 256.0);
        for c in &e {
            assert_eq!(
                (c.rmse, c.bias_rmse, c.sampling_rmse, c.reference_rmse),
                (0.0, 0.0, 0.0, 0.0)
            );
        }
    }

    #[test]
    fn a_depth_step_cuts_by_geometry_and_a_visibility_step_by_visibility() {
        let (params, mut depth, normal, compared) = plane();
        // A wall in front of columns 0..6 (its depth 1, half the plane's).
        for y in 0..W as usize {
            for x in 0..6 {
                depth[y * W as usize + x] = 1.0;
            }
        }
        let v = vec![0.5; depth.len()];
        let e = filter_window_errors(&params, &v, &depth, &normal, &v, &v, &compared);
        // Inner rows 2..10: columns 2, 3 (wall) and 8, 9 (plane) keep full windows; columns
        // 4..=7 reach across the step, the rest across the border.
        assert_eq!(class(&e, WindowClass::Full).pixel_share, 32.0 / 144.0);
        assert_eq!(class(&e, WindowClass::CutByGeometry).pixel_share, 112.0 / 144.0);
        assert_eq!(class(&e, WindowClass::CutByVisibility).pixel_share, 0.0);
        // Visibility steps from 0 to 1 between columns 5 and 6 of the plane.
        let (_, depth, _, _) = plane();
        let v: Vec<f32> = (0..depth.len())
            .map(|i| if i % W as usize >= 6 { 1.0 } else { 0.0 })
            .collect();
        let e = filter_window_errors(&params, &v, &depth, &normal, &v, &v, &compared);
        // Inner rows 2..10: columns 2, 3, 8 and 9 keep full windows (theirs end before the
        // step), columns 4..=7 lose the taps across it.
        assert_eq!(class(&e, WindowClass::CutByVisibility).pixel_share, 32.0 / 144.0);
        assert_eq!(class(&e, WindowClass::Full).pixel_share, 32.0 / 144.0);
        // Noiseless values equal to the exact ones: the kept taps agree, so nothing is lost.
        assert_eq!(class(&e, WindowClass::CutByVisibility).rmse, 0.0);
    }

    #[test]
    fn bias_and_sampling_split_the_filtered_error_of_the_filter_itself() {
        let (params, depth, normal, compared) = plane();
        let n = depth.len();
        // Exact values on a curved ramp (so the window has a bias), noisy values around it
        // (noise within ±0.03 and a slope below 0.03 a pixel, so that most taps pass the
        // visibility test and the weights matter).
        let (x_of, y_of) = (|i: usize| i % W as usize, |i: usize| i / W as usize);
        let exact: Vec<f32> = (0..n)
            .map(|i| 0.2 + 0.3 * (x_of(i) as f32 / 11.0).powi(2) + y_of(i) as f32 / 88.0)
            .collect();
        let noisy: Vec<f32> = (0..n)
            .map(|i| exact[i] + 0.015 * ((x_of(i) * 7 + y_of(i) * 13) % 5) as f32 - 0.03)
            .collect();
        let e = filter_window_errors(&params, &noisy, &depth, &normal, &exact, &noisy, &compared);
        let values: Vec<[f32; 4]> = noisy.iter().map(|&v| [0.0, 0.0, 0.0, v]).collect();
        let (mut squared, mut count) = (0.0f64, 0usize);
        for y in 0..W {
            for x in 0..W {
                let f = filter_pixel(&params, &values, &depth, &normal, x, y)[3];
                let ix = (y * W + x) as usize;
                squared += (f64::from(f) - f64::from(exact[ix])).powi(2);
                count += 1;
            }
        }
        let total: f64 = e.iter().map(|c| c.rmse.powi(2) * c.pixel_share).sum();
        // The filter sums in f32; these means are f64: equal to f32 rounding of values ≤ 1.
        assert!(
            (total.sqrt() - (squared / count as f64).sqrt()).abs() < 1e-6,
            "the classes' RMSE {} is not the filter's {}",
            total.sqrt(),
            (squared / count as f64).sqrt()
        );
        for c in &e {
            // bias + sampling = filtered, pixel by pixel, so the RMSEs obey the triangle rule.
            assert!(c.rmse <= c.bias_rmse + c.sampling_rmse + 1e-12, "{c:?}");
        }
        // The inner windows are full, and both parts are there, far above rounding (1e-7).
        let full = class(&e, WindowClass::Full);
        assert!(
            full.pixel_share > 0.3 && full.bias_rmse > 1e-4 && full.sampling_rmse > 1e-4,
            "{e:?}"
        );
    }
}
