//! Image error metrics against values worked out by hand.

use penumbra::quality::metrics::{Channel, ImageMetrics, difference_image, false_colour, pixel_differences};

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * b.abs().max(1.0)
}

#[test]
fn one_channel_metrics_by_hand() {
    // Errors 0, 0.25, 0.5, 0: MAE 0.75/4, MSE (0.0625 + 0.25)/4 = 0.078125.
    let test = [0.0, 0.5, 1.0, 0.25];
    let reference = [0.0, 0.25, 0.5, 0.25];
    let m = ImageMetrics::of_values(&test, &reference);
    assert_eq!(m.values, 4);
    assert!(close(m.mean_abs, 0.1875), "{m:?}");
    assert!(close(m.rmse, 0.078125f64.sqrt()), "{m:?}");
    assert!(close(m.max_abs, 0.5), "{m:?}");
    assert_eq!(m.max_pixel, 2);
    // −10·log10(0.078125) = 11.0721 dB.
    assert!((m.psnr - 11.072_099_696_478_683).abs() < 1e-9, "{m:?}");
}

#[test]
fn identical_images_have_infinite_psnr() {
    let a = [0.3f32, 0.7, 1.5];
    let m = ImageMetrics::of_values(&a, &a);
    assert_eq!((m.rmse, m.mean_abs, m.max_abs), (0.0, 0.0, 0.0));
    assert_eq!(m.psnr, f64::INFINITY);
}

#[test]
fn channel_choice_picks_the_values() {
    let test = [[1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.5]];
    let reference = [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 1.0]];
    let r = ImageMetrics::of_pixels(&test, &reference, Channel::R);
    assert_eq!((r.values, r.mean_abs, r.max_pixel), (2, 0.5, 0));
    assert!(close(r.rmse, 0.5f64.sqrt()));
    assert!(close(r.psnr, 10.0 * 2f64.log10()), "{r:?}");
    let g = ImageMetrics::of_pixels(&test, &reference, Channel::G);
    assert_eq!(g.psnr, f64::INFINITY);
    let a = ImageMetrics::of_pixels(&test, &reference, Channel::A);
    assert_eq!((a.mean_abs, a.max_abs, a.max_pixel), (0.25, 0.5, 1));
    let l = ImageMetrics::of_pixels(&test, &reference, Channel::Luminance);
    assert!(close(l.mean_abs, 0.2126f32 as f64 / 2.0), "{l:?}");
    // All: six values, one of them off by 1.
    let all = ImageMetrics::of_pixels(&test, &reference, Channel::All);
    assert_eq!(all.values, 6);
    assert!(close(all.mean_abs, 1.0 / 6.0));
    assert!(close(all.rmse, (1.0f64 / 6.0).sqrt()));
    assert_eq!(pixel_differences(&test, &reference, Channel::All), vec![1.0, 0.0]);
    assert_eq!(pixel_differences(&test, &reference, Channel::A), vec![0.0, 0.5]);
}

#[test]
fn nan_is_not_hidden() {
    let m = ImageMetrics::of_values(&[0.0, f32::NAN, 0.5], &[0.0, 0.0, 0.0]);
    assert!(m.rmse.is_nan() && m.mean_abs.is_nan() && m.max_abs.is_nan() && m.psnr.is_nan());
    assert_eq!(m.max_pixel, 1);
}

#[test]
fn false_colour_ramp_and_difference_image() {
    assert_eq!(false_colour(0.0), [0.0, 0.0, 1.0]);
    assert_eq!(false_colour(0.125), [0.0, 0.5, 1.0]);
    assert_eq!(false_colour(0.25), [0.0, 1.0, 1.0]);
    assert_eq!(false_colour(0.5), [0.0, 1.0, 0.0]);
    assert_eq!(false_colour(0.75), [1.0, 1.0, 0.0]);
    assert_eq!(false_colour(1.0), [1.0, 0.0, 0.0]);
    assert_eq!(false_colour(7.0), [1.0, 0.0, 0.0]);
    assert_eq!(false_colour(-1.0), [0.0, 0.0, 1.0]);
    assert_eq!(false_colour(f32::NAN), [1.0, 0.0, 1.0]);
    let d = [0.0, 0.5, 1.0];
    // Scaled to the largest difference: blue, green, red.
    assert_eq!(
        difference_image(&d, None),
        vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]
    );
    // A given scale: 1.0 is half way (green), 0.5 a quarter (cyan).
    assert_eq!(
        difference_image(&d, Some(2.0)),
        vec![[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [0.0, 1.0, 0.0]]
    );
    assert_eq!(difference_image(&[0.0, 0.0], None), vec![[0.0, 0.0, 1.0]; 2]);
}
