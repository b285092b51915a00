//! Pixel-wise errors: MSE, RMSE, relative MSE and PSNR.
//!
//! All are means over every pixel and each of the three RGB channels (N = 3 · width · height),
//! accumulated in f64.

use super::{DisplayTransform, MetricError, Result, rgb_pair};
use crate::image_io::CpuImage;

/// The ε of [`rel_mse`] that renderers commonly use (e.g. Rousselle et al. 2011): it keeps
/// near-black reference pixels from dominating the mean.
pub const REL_MSE_EPSILON: f64 = 1e-2;

/// Mean of `f(r, t)` over all pixels and RGB channels.
fn mean_over(reference: &CpuImage, test: &CpuImage, f: impl Fn(f64, f64) -> f64) -> Result<f64> {
    let (r, t) = rgb_pair(reference, test)?;
    let sum: f64 = r.iter().zip(&t).flat_map(|(rc, tc)| rc.iter().zip(tc)).map(|(&a, &b)| f(a as f64, b as f64)).sum();
    Ok(sum / (3 * reference.pixel_count()) as f64)
}

/// Mean squared error of the linear RGB values: `MSE = (1/N) Σ (t − r)²`, in squared input units.
pub fn mse(reference: &CpuImage, test: &CpuImage) -> Result<f64> {
    mean_over(reference, test, |r, t| (t - r) * (t - r))
}

/// Root mean squared error of the linear RGB values, `√MSE`, in input units.
pub fn rmse(reference: &CpuImage, test: &CpuImage) -> Result<f64> {
    mse(reference, test).map(f64::sqrt)
}

/// Relative MSE of the linear RGB values: `relMSE = (1/N) Σ (t − r)² / (r² + ε)`, dimensionless.
/// Use [`REL_MSE_EPSILON`] unless there is a reason not to; `eps` must be positive and finite.
pub fn rel_mse(reference: &CpuImage, test: &CpuImage, eps: f64) -> Result<f64> {
    if !(eps > 0.0 && eps.is_finite()) {
        return Err(MetricError::InvalidParameter(format!("rel_mse: epsilon must be positive and finite, not {eps}")));
    }
    mean_over(reference, test, |r, t| (t - r) * (t - r) / (r * r + eps))
}

/// PSNR of the **linear** RGB values in dB: `10 · log10(peak² / MSE)`; `f64::INFINITY` when the
/// images are equal. `peak` is the largest meaningful value (1 for LDR data; for HDR pick the
/// reference's white, e.g. its maximum). It must be positive and finite.
pub fn psnr(reference: &CpuImage, test: &CpuImage, peak: f64) -> Result<f64> {
    if !(peak > 0.0 && peak.is_finite()) {
        return Err(MetricError::InvalidParameter(format!("psnr: peak must be positive and finite, not {peak}")));
    }
    Ok(psnr_from_mse(mse(reference, test)?, peak))
}

/// PSNR in dB of the display-encoded values (each channel through `transform`, so in [0, 1]),
/// with peak 1: what a viewer of the tonemapped images would compare.
pub fn psnr_display(reference: &CpuImage, test: &CpuImage, transform: DisplayTransform) -> Result<f64> {
    let e = mean_over(reference, test, |r, t| {
        let d = transform.apply(t as f32) as f64 - transform.apply(r as f32) as f64;
        d * d
    })?;
    Ok(psnr_from_mse(e, 1.0))
}

fn psnr_from_mse(mse: f64, peak: f64) -> f64 {
    if mse == 0.0 { f64::INFINITY } else { 10.0 * (peak * peak / mse).log10() }
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn identical_images() {
        let a = rgb_image(8, 5, |x, y, c| unit(x + 8 * y + 40 * c as u32) * 4.0);
        assert_eq!(mse(&a, &a).unwrap(), 0.0);
        assert_eq!(psnr(&a, &a, 1.0).unwrap(), f64::INFINITY);
        assert_eq!(psnr_display(&a, &a, DisplayTransform::Srgb).unwrap(), f64::INFINITY);
        assert_eq!(rel_mse(&a, &a, REL_MSE_EPSILON).unwrap(), 0.0);
    }

    #[test]
    fn constant_offset() {
        // An offset d everywhere: MSE = d², PSNR = 10 log10(peak² / d²) = 20 log10(peak / d).
        let a = rgb_image(9, 7, |x, y, c| unit(x + 9 * y + 63 * c as u32));
        let b = rgb_image(9, 7, |x, y, c| unit(x + 9 * y + 63 * c as u32) + 0.125);
        assert!((mse(&a, &b).unwrap() - 0.015_625).abs() < 1e-9);
        assert!((rmse(&a, &b).unwrap() - 0.125).abs() < 1e-8);
        let want = 20.0 * (2.0f64 / 0.125).log10();
        assert!((psnr(&a, &b, 2.0).unwrap() - want).abs() < 1e-6);
    }

    #[test]
    fn relative_mse_formula() {
        // r = 1 everywhere, t = 1.5: relMSE = 0.25 / (1 + ε).
        let a = grey_image(4, 4, |_, _| 1.0);
        let b = grey_image(4, 4, |_, _| 1.5);
        assert!((rel_mse(&a, &b, 0.01).unwrap() - 0.25 / 1.01).abs() < 1e-12);
        assert!(rel_mse(&a, &b, 0.0).is_err());
        assert!(psnr(&a, &b, f64::NAN).is_err());
    }

    #[test]
    fn display_psnr_clamps_hdr() {
        // Both above 1 in linear: Srgb clamps them to the same white, so no visible error.
        let a = grey_image(4, 4, |_, _| 2.0);
        let b = grey_image(4, 4, |_, _| 3.0);
        assert_eq!(psnr_display(&a, &b, DisplayTransform::Srgb).unwrap(), f64::INFINITY);
        assert!(psnr_display(&a, &b, DisplayTransform::AcesSrgb { exposure: 0.0 }).unwrap().is_finite());
    }
}
