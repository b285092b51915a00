//! SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment: from error visibility
//! to structural similarity").
//!
//! Computed on one channel, the luma of the display-encoded image:
//! `Y' = 0.2126 R' + 0.7152 G' + 0.0722 B'`, where `R' = transform(R)` etc. are in [0, 1]
//! (dynamic range L = 1). Local statistics use the paper's 11x11 Gaussian window with σ = 1.5
//! (normalised to sum 1), with `C1 = (0.01 L)²` and `C2 = (0.03 L)²`:
//!
//! `SSIM(x, y) = (2 μx μy + C1)(2 σxy + C2) / ((μx² + μy² + C1)(σx² + σy² + C2))`
//!
//! with population (not sample) variances. The result is the mean over the window positions
//! that lie fully inside the image (the reference implementation's "valid" region), so images
//! must be at least 11x11. There is no down-sampling step.

use super::{DisplayTransform, MetricError, Planes, Result, convolve_columns, convolve_rows, rgb_pair};
use crate::image_io::CpuImage;

const WINDOW_RADIUS: usize = 5;
const SIGMA: f64 = 1.5;
const C1: f64 = 0.01 * 0.01;
const C2: f64 = 0.03 * 0.03;

/// SSIM of HDR linear images as a viewer would see them: [`ssim_with`] with
/// `DisplayTransform::AcesSrgb { exposure: 0.0 }` (ACES filmic, then sRGB encoding). In [-1, 1];
/// 1 for identical images.
pub fn ssim(reference: &CpuImage, test: &CpuImage) -> Result<f64> {
    ssim_with(reference, test, DisplayTransform::AcesSrgb { exposure: 0.0 })
}

/// Mean SSIM after mapping both images to display-encoded values with `transform`.
pub fn ssim_with(reference: &CpuImage, test: &CpuImage, transform: DisplayTransform) -> Result<f64> {
    let (r, t) = rgb_pair(reference, test)?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let n = 2 * WINDOW_RADIUS + 1;
    if w < n || h < n {
        return Err(MetricError::InvalidParameter(format!("ssim: images must be at least {n}x{n}, not {w}x{h}")));
    }
    // f64 from here on: the variances are differences of nearly equal moments, and f32 would
    // leave errors of ~1e-7 in them, comparable to C2 in flat regions.
    let luma = |p: &Planes| -> Vec<f64> {
        (0..w * h)
            .map(|i| {
                super::luminance(transform.apply(p[0][i]), transform.apply(p[1][i]), transform.apply(p[2][i])) as f64
            })
            .collect()
    };
    let (x, y) = (luma(&r), luma(&t));
    let kernel = gaussian_window();
    let blur = |plane: Vec<f64>| valid_blur(&plane, w, h, &kernel);
    let mu_x = blur(x.clone());
    let mu_y = blur(y.clone());
    let xx = blur(x.iter().map(|v| v * v).collect());
    let yy = blur(y.iter().map(|v| v * v).collect());
    let xy = blur(x.iter().zip(&y).map(|(a, b)| a * b).collect());
    let sum: f64 = (0..mu_x.len())
        .map(|i| {
            let (mx, my) = (mu_x[i], mu_y[i]);
            let vx = xx[i] - mx * mx;
            let vy = yy[i] - my * my;
            let cov = xy[i] - mx * my;
            ((2.0 * mx * my + C1) * (2.0 * cov + C2)) / ((mx * mx + my * my + C1) * (vx + vy + C2))
        })
        .sum();
    Ok(sum / mu_x.len() as f64)
}

fn gaussian_window() -> Vec<f64> {
    let g: Vec<f64> = (0..=2 * WINDOW_RADIUS)
        .map(|i| (-((i as f64 - WINDOW_RADIUS as f64).powi(2)) / (2.0 * SIGMA * SIGMA)).exp())
        .collect();
    let sum: f64 = g.iter().sum();
    g.iter().map(|v| v / sum).collect()
}

/// Gaussian-weighted means over every window that lies inside the image: the full (edge-clamped)
/// filter restricted to the pixels at least the window radius away from each border, where no
/// clamped pixel is read.
fn valid_blur(plane: &[f64], w: usize, h: usize, k: &[f64]) -> Vec<f64> {
    let (mut tmp, mut full) = (Vec::new(), Vec::new());
    convolve_rows(plane, w, k, &mut tmp);
    convolve_columns(&tmp, w, h, k, &mut full);
    let r = WINDOW_RADIUS;
    (r..h - r).flat_map(|y| full[y * w + r..y * w + w - r].to_vec()).collect()
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    fn textured(w: u32, h: u32, seed: u32) -> CpuImage {
        grey_image(w, h, |x, y| 0.2 + 0.6 * unit(seed + x + 1000 * y))
    }

    #[test]
    fn identical_is_one() {
        let a = textured(24, 17, 0);
        assert!((ssim(&a, &a).unwrap() - 1.0).abs() < 1e-6);
        assert!((ssim_with(&a, &a, DisplayTransform::Encoded).unwrap() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn constant_images_follow_the_luminance_term() {
        // No variance anywhere: SSIM = (2ab + C1) / (a² + b² + C1).
        let (a, b) = (0.4f64, 0.55f64);
        let x = grey_image(16, 12, |_, _| a as f32);
        let y = grey_image(16, 12, |_, _| b as f32);
        let want = (2.0 * a * b + C1) / (a * a + b * b + C1);
        let got = ssim_with(&x, &y, DisplayTransform::Encoded).unwrap();
        assert!((got - want).abs() < 1e-5, "{got} vs {want}");
    }

    #[test]
    fn brightness_shift_keeps_structure_term() {
        // y = x + c: every window has the same variances and covariance = variance, so the
        // contrast-structure term is 1 and SSIM = mean of (2 μx (μx + c) + C1) / (μx² + (μx + c)² + C1).
        let x = textured(20, 20, 7);
        let c = 0.1f32;
        let y = grey_image(20, 20, |px, py| x.get(px, py, 0) + c);
        let mu = valid_blur(
            &(0..400).map(|i| x.get(i % 20, i / 20, 0) as f64).collect::<Vec<_>>(),
            20,
            20,
            &gaussian_window(),
        );
        let c = c as f64;
        let want = mu.iter().map(|&m| (2.0 * m * (m + c) + C1) / (m * m + (m + c).powi(2) + C1)).sum::<f64>()
            / mu.len() as f64;
        let got = ssim_with(&x, &y, DisplayTransform::Encoded).unwrap();
        assert!((got - want).abs() < 1e-4, "{got} vs {want}");
    }

    #[test]
    fn matches_scikit_image() {
        // skimage.metrics.structural_similarity(a, b, gaussian_weights=True, sigma=1.5,
        // use_sample_covariance=False, data_range=1.0) of the same images (scikit-image 0.26),
        // generated in NumPy with the same hash and float32 operations.
        let a = grey_image(40, 31, |x, y| {
            0.5 * (0.2 + 0.6 * unit(1 + x + 1000 * y)) + 0.5 * unit(77 + (y / 4) * 100 + x / 4)
        });
        let b = grey_image(40, 31, |x, y| a.get(x, y, 0) + 0.2 * (unit(99 + x + 50 * y) - 0.5));
        let got = ssim_with(&a, &b, DisplayTransform::Encoded).unwrap();
        assert!((got - 0.920_764_084_521_419).abs() < 1e-6, "{got}");
    }

    #[test]
    fn noise_lowers_ssim_and_small_images_fail() {
        let a = textured(32, 32, 1);
        let b = grey_image(32, 32, |x, y| a.get(x, y, 0) + 0.2 * (unit(99 + x + 50 * y) - 0.5));
        let s = ssim_with(&a, &b, DisplayTransform::Encoded).unwrap();
        assert!(s < 0.95 && s > 0.0, "{s}");
        let tiny = textured(10, 40, 0);
        assert!(matches!(ssim(&tiny, &tiny), Err(MetricError::InvalidParameter(_))));
    }
}
