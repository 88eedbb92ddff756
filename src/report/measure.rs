//! Error measures of an image against a reference, over the three channel planes.
//!
//! Errors are relative L2 (`‖a − r‖ / ‖r‖`, dimensionless) pooled over R, G and B: each plane's
//! squared error is weighted by its reference's squared norm, so the result equals the relative L2 of
//! the three planes taken together.

use crate::compare::{box_blur, relative_l2};
use crate::film::Image;

/// Radius of the box blur of [`blurred_error`]: a 5×5 window.
pub const BLUR_RADIUS: usize = 2;

/// One channel plane of an interleaved RGB image, optionally box-blurred with `radius`.
fn plane(image: &Image, c: usize, radius: Option<usize>) -> Vec<f32> {
    let values: Vec<f32> = image.rgb.iter().skip(c).step_by(3).copied().collect();
    match radius {
        Some(r) => box_blur(&values, image.width as usize, image.height as usize, r),
        None => values,
    }
}

/// Relative L2 of `a` against `reference` over R, G, B, after a box blur of `radius` if any.
fn pooled(a: &Image, reference: &Image, radius: Option<usize>) -> f64 {
    assert_eq!(
        (a.width, a.height),
        (reference.width, reference.height),
        "error of images of different sizes"
    );
    let (mut num, mut den) = (0.0, 0.0);
    for c in 0..3 {
        let (x, y) = (plane(a, c, radius), plane(reference, c, radius));
        let e = relative_l2(&x, &y);
        let n: f64 = y.iter().map(|v| (*v as f64).powi(2)).sum();
        if n == 0.0 {
            // A zero reference plane: the error is 0 or infinite, as `relative_l2` says.
            if e > 0.0 {
                return f64::INFINITY;
            }
            continue;
        }
        num += e * e * n;
        den += n;
    }
    if den > 0.0 { (num / den).sqrt() } else { 0.0 }
}

/// Relative L2 error of `a` against `reference`, per pixel (no blur), over R, G, B.
pub fn raw_error(a: &Image, reference: &Image) -> f64 {
    pooled(a, reference, None)
}

/// Relative L2 error of `a` against `reference` after a 5×5 box blur of both, over R, G, B: the blur
/// averages pixel noise away while keeping the bias of an estimator (a missing boundary term is a
/// band several pixels wide), so it is the figure "time to X%" is measured with.
pub fn blurred_error(a: &Image, reference: &Image) -> f64 {
    pooled(a, reference, Some(BLUR_RADIUS))
}

/// One run's own noise, relative to `reference`, from two runs with different seeds: their difference
/// has twice one run's variance, hence the division by √2. Blurred like [`blurred_error`].
pub fn seed_noise(a: &Image, b: &Image, reference: &Image) -> f64 {
    let mut diff = a.clone();
    for (d, x) in diff.rgb.iter_mut().zip(&b.rgb) {
        *d -= x;
    }
    let mut total = 0.0;
    let mut norm = 0.0;
    for c in 0..3 {
        let d = plane(&diff, c, Some(BLUR_RADIUS));
        let r = plane(reference, c, Some(BLUR_RADIUS));
        total += d.iter().map(|v| (*v as f64).powi(2)).sum::<f64>();
        norm += r.iter().map(|v| (*v as f64).powi(2)).sum::<f64>();
    }
    if norm > 0.0 {
        (total / norm).sqrt() / std::f64::consts::SQRT_2
    } else {
        f64::INFINITY
    }
}

/// The blurred error that remains when the estimator's own noise is subtracted in quadrature:
/// `√max(error² − noise², 0)`. What stays is bias (or the reference's own error).
pub fn bias_floor(blurred: f64, noise: f64) -> f64 {
    (blurred * blurred - noise * noise).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: impl Fn(usize) -> f32) -> Image {
        let (width, height) = (8, 8);
        Image {
            width,
            height,
            rgb: (0..(width * height * 3) as usize).map(values).collect(),
        }
    }

    #[test]
    fn a_uniform_scale_is_its_relative_error_raw_and_blurred() {
        let r = image(|i| 1.0 + (i % 7) as f32);
        let a = image(|i| 1.1 * (1.0 + (i % 7) as f32));
        assert!((raw_error(&a, &r) - 0.1).abs() < 1e-6);
        assert!((blurred_error(&a, &r) - 0.1).abs() < 1e-6);
    }

    #[test]
    fn the_blur_removes_alternating_noise_but_not_an_offset() {
        let r = image(|_| 1.0);
        let noisy = image(|i| if (i / 3) % 2 == 0 { 1.5 } else { 0.5 });
        assert!(raw_error(&noisy, &r) > 0.4);
        assert!(blurred_error(&noisy, &r) < 0.15);
        let offset = image(|_| 1.2);
        assert!((blurred_error(&offset, &r) - 0.2).abs() < 1e-6);
    }

    #[test]
    fn seed_noise_and_bias_floor() {
        let r = image(|_| 1.0);
        let (a, b) = (image(|_| 1.1), image(|_| 0.9));
        // ‖a − b‖ = 0.2 ‖r‖, one run's share 0.2 / √2.
        assert!((seed_noise(&a, &b, &r) - 0.2 / std::f64::consts::SQRT_2).abs() < 1e-6);
        assert_eq!(bias_floor(0.3, 0.4), 0.0);
        assert!((bias_floor(0.5, 0.3) - 0.4).abs() < 1e-12);
    }
}
