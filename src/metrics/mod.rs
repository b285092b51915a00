//! Image-quality metrics for comparing renders: per-image errors (MSE, PSNR, relMSE, SSIM,
//! LDR-/HDR-FLIP), energy (mean luminance against the reference's) and temporal measures over
//! frame sequences (flicker, ghosting, lag).
//!
//! # Data model
//! Every metric takes [`CpuImage`]s with `Texels::F32` values, rows top to bottom, and reads the
//! first three channels as **linear RGB** (Rec. 709 / sRGB primaries) unless a function says
//! otherwise; extra channels (alpha) are ignored. Luminance, where used, is
//! `Y = 0.2126 R + 0.7152 G + 0.0722 B` of the linear values ([`luminance`]).
//!
//! # Errors, NaN and infinity
//! No function panics on bad input: sizes that differ, fewer than three channels, integer
//! texels, empty images, a texel buffer shorter than `width * height * channels` and invalid
//! parameters all return a [`MetricError`]. **Any NaN or ±infinity in the channels a metric
//! reads is an error** ([`MetricError::NonFinite`], with the count and the first location):
//! a renderer that produced one has a bug that an averaged number would hide. Negative finite
//! values are accepted: MSE/PSNR/relMSE and the temporal measures use them as they are, the
//! display transforms and FLIP clamp them to 0 (as NVIDIA's FLIP does).
//!
//! # Which metric on which values
//! | metric | values it compares |
//! | --- | --- |
//! | [`mse`], [`rmse`], [`rel_mse`], [`psnr()`] | linear HDR values as given |
//! | [`psnr_display`], [`ssim()`], [`ssim_with`] | display-encoded values in [0, 1] after a [`DisplayTransform`] |
//! | [`ldr_flip`] | LDR values in [0, 1], sRGB-encoded or linear ([`LdrInput`]) |
//! | [`hdr_flip`] | linear HDR values, tonemapped by HDR-FLIP itself at several exposures |
//! | [`luminance_ratio`] | linear luminance, lights seen directly left out |
//! | [`flicker`], [`ghosting`], [`lag`] | linear luminance per pixel |
//!
//! FLIP is implemented here from the papers (Andersson et al., HPG 2020 and EGSR/CGF 2021); see
//! [`flip`] for what it was checked against.

pub mod energy;
pub mod flip;
pub mod psnr;
pub mod ssim;
pub mod temporal;

pub use energy::luminance_ratio;
pub use flip::{DEFAULT_PPD, Exposures, FlipResult, HdrFlipOptions, LdrInput, hdr_flip, ldr_flip, pixels_per_degree};
pub use psnr::{REL_MSE_EPSILON, mse, psnr, psnr_display, rel_mse, rmse};
pub use ssim::{ssim, ssim_with};
pub use temporal::{FlickerReport, GhostingReport, LagReport, flicker, ghosting, lag};

use crate::image_io::{CpuImage, Texels};

/// Why a metric could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricError {
    #[error("{what}: size {found_w}x{found_h} differs from the reference's {expected_w}x{expected_h}")]
    SizeMismatch { what: String, expected_w: u32, expected_h: u32, found_w: u32, found_h: u32 },
    #[error("{what}: metrics need at least 3 float channels (RGB); it has {channels} {kind} channels")]
    NotRgb { what: String, channels: usize, kind: &'static str },
    #[error("{what}: the image is empty ({width}x{height})")]
    Empty { what: String, width: u32, height: u32 },
    #[error("{what}: {len} texel values, but {width}x{height} pixels of {channels} channels need {needed}")]
    ShortBuffer { what: String, len: usize, width: u32, height: u32, channels: usize, needed: usize },
    #[error("{what}: {count} NaN or infinite values, the first at pixel ({x}, {y}) channel {channel}")]
    NonFinite { what: String, count: usize, x: u32, y: u32, channel: usize },
    #[error("{0}")]
    InvalidParameter(String),
}

pub type Result<T> = std::result::Result<T, MetricError>;

/// Rec. 709 luminance of linear RGB.
pub fn luminance(r: f32, g: f32, b: f32) -> f32 {
    0.2126 * r + 0.7152 * g + 0.0722 * b
}

/// How linear values are turned into display-encoded values in [0, 1] for the metrics that
/// compare what a viewer sees ([`ssim()`], [`psnr_display`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DisplayTransform {
    /// The values already are display-encoded (e.g. a tonemapped 8-bit read-back): only clamped to [0, 1].
    Encoded,
    /// Linear values clamped to [0, 1], then sRGB-encoded (the sRGB OETF).
    Srgb,
    /// Linear values scaled by `2^exposure`, tonemapped per channel with the ACES filmic fit of
    /// Narkowicz (2016) including its 0.6 pre-exposure (the same curve HDR-FLIP uses), clamped to
    /// [0, 1], then sRGB-encoded.
    AcesSrgb { exposure: f32 },
}

impl DisplayTransform {
    /// The display-encoded value in [0, 1] of one linear channel value.
    pub fn apply(self, v: f32) -> f32 {
        match self {
            Self::Encoded => v.clamp(0.0, 1.0),
            Self::Srgb => srgb_encode(v.clamp(0.0, 1.0)),
            Self::AcesSrgb { exposure } => srgb_encode(aces(v.max(0.0) * exposure.exp2())),
        }
    }
}

/// The ACES fit with the 0.6 pre-exposure folded into its coefficients, as HDR-FLIP defines it:
/// `(k0 x² + k1 x) / (k3 x² + k4 x + k5)`.
pub(crate) const ACES: [f32; 5] = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14];

/// ACES-tonemapped `x >= 0`, clamped to [0, 1].
pub(crate) fn aces(x: f32) -> f32 {
    // Beyond 1e15 x² overflows f32 to infinity and the ratio turns NaN; the curve saturates long
    // before (it passes 1 near x = 1e2), so such values map to white.
    if x > 1e15 {
        return 1.0;
    }
    let [k0, k1, k3, k4, k5] = ACES;
    ((k0 * x * x + k1 * x) / (k3 * x * x + k4 * x + k5)).clamp(0.0, 1.0)
}

pub(crate) fn srgb_encode(v: f32) -> f32 {
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

pub(crate) fn srgb_decode(v: f32) -> f32 {
    if v <= 0.040_45 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// A per-pixel selection (rows top to bottom), e.g. the pixels a moving object left behind.
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    width: u32,
    height: u32,
    bits: Vec<bool>,
}

impl Mask {
    /// A mask from `width * height` values in row order.
    pub fn new(width: u32, height: u32, bits: Vec<bool>) -> Result<Self> {
        if bits.len() != width as usize * height as usize {
            return Err(MetricError::InvalidParameter(format!(
                "mask: {} values for {width}x{height} pixels",
                bits.len()
            )));
        }
        Ok(Self { width, height, bits })
    }

    /// A mask with `f(x, y)` at each pixel.
    pub fn from_fn(width: u32, height: u32, f: impl Fn(u32, u32) -> bool) -> Self {
        let bits = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).map(|(x, y)| f(x, y)).collect();
        Self { width, height, bits }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Number of selected pixels.
    pub fn count(&self) -> usize {
        self.bits.iter().filter(|&&b| b).count()
    }

    pub(crate) fn bits(&self) -> &[bool] {
        &self.bits
    }

    pub(crate) fn check_size(&self, what: &str, width: u32, height: u32) -> Result<()> {
        check_dims(what, (width, height), (self.width, self.height))
    }
}

pub(crate) fn check_dims(what: &str, expected: (u32, u32), found: (u32, u32)) -> Result<()> {
    if expected != found {
        return Err(MetricError::SizeMismatch {
            what: what.to_string(),
            expected_w: expected.0,
            expected_h: expected.1,
            found_w: found.0,
            found_h: found.1,
        });
    }
    Ok(())
}

/// The float texels of a non-empty image with at least 3 channels whose first three channels
/// are all finite.
fn checked_texels<'a>(img: &'a CpuImage, what: &str) -> Result<&'a [f32]> {
    let values = match &img.texels {
        Texels::F32(v) if img.channels >= 3 => v,
        Texels::F32(_) => return Err(MetricError::NotRgb { what: what.into(), channels: img.channels, kind: "float" }),
        Texels::U32(_) => {
            return Err(MetricError::NotRgb { what: what.into(), channels: img.channels, kind: "integer" });
        }
    };
    if img.width == 0 || img.height == 0 {
        return Err(MetricError::Empty { what: what.into(), width: img.width, height: img.height });
    }
    let needed = img.pixel_count() * img.channels;
    if values.len() < needed {
        return Err(MetricError::ShortBuffer {
            what: what.into(),
            len: values.len(),
            width: img.width,
            height: img.height,
            channels: img.channels,
            needed,
        });
    }
    let values = &values[..needed];
    let mut bad = values
        .chunks_exact(img.channels)
        .enumerate()
        .flat_map(|(i, px)| px[..3].iter().enumerate().filter(|(_, v)| !v.is_finite()).map(move |(c, _)| (i, c)));
    if let Some((i, channel)) = bad.next() {
        let count = 1 + bad.count();
        let (x, y) = ((i % img.width as usize) as u32, (i / img.width as usize) as u32);
        return Err(MetricError::NonFinite { what: what.into(), count, x, y, channel });
    }
    Ok(values)
}

/// An image as three planes (R, G, B or another three-channel space), each `width * height` long.
pub(crate) type Planes = [Vec<f32>; 3];

/// Linear RGB of a checked image as planes.
pub(crate) fn rgb_planes(img: &CpuImage, what: &str) -> Result<Planes> {
    let values = checked_texels(img, what)?;
    let plane = |c: usize| values.chunks_exact(img.channels).map(|px| px[c]).collect();
    Ok([plane(0), plane(1), plane(2)])
}

/// Linear luminance of a checked image, one value per pixel.
pub(crate) fn luminance_plane(img: &CpuImage, what: &str) -> Result<Vec<f32>> {
    let values = checked_texels(img, what)?;
    Ok(values.chunks_exact(img.channels).map(|px| luminance(px[0], px[1], px[2])).collect())
}

/// Checks a reference/test pair and returns both as RGB planes.
pub(crate) fn rgb_pair(reference: &CpuImage, test: &CpuImage) -> Result<(Planes, Planes)> {
    let r = rgb_planes(reference, "reference")?;
    check_dims("test", (reference.width, reference.height), (test.width, test.height))?;
    Ok((r, rgb_planes(test, "test")?))
}

/// Convolves the `width x height` plane `src` with `kx` along rows and then `ky` along columns
/// (both odd-length and centred), reading pixels outside the image from the nearest edge pixel.
/// `tmp` and `dst` are resized as needed.
pub(crate) fn convolve_separable(
    src: &[f32],
    width: usize,
    height: usize,
    kx: &[f32],
    ky: &[f32],
    tmp: &mut Vec<f32>,
    dst: &mut Vec<f32>,
) {
    convolve_rows(src, width, kx, tmp);
    convolve_columns(tmp, width, height, ky, dst);
}

/// The sample types the filters run on: f32 for FLIP (as NVIDIA's), f64 where SSIM subtracts
/// nearly equal moments.
pub(crate) trait Sample:
    Copy + Default + std::ops::Mul<Output = Self> + std::ops::AddAssign + std::iter::Sum
{
}
impl Sample for f32 {}
impl Sample for f64 {}

/// Horizontal pass of [`convolve_separable`]. Each row is first copied with its edge pixels
/// repeated `r` times on both sides, so the taps need no clamping; outputs are then produced 8
/// at a time with independent accumulators, which the compiler keeps in (vector) registers.
pub(crate) fn convolve_rows<T: Sample>(src: &[T], width: usize, k: &[T], dst: &mut Vec<T>) {
    const BLOCK: usize = 8;
    let r = k.len() / 2;
    dst.resize(src.len(), T::default());
    let mut padded = vec![T::default(); width + 2 * r];
    for (row, out) in src.chunks_exact(width).zip(dst.chunks_exact_mut(width)) {
        for (i, p) in padded.iter_mut().enumerate() {
            *p = row[i.saturating_sub(r).min(width - 1)];
        }
        let mut blocks = out.chunks_exact_mut(BLOCK);
        for (b, out) in (&mut blocks).enumerate() {
            let window = &padded[b * BLOCK..b * BLOCK + BLOCK + k.len() - 1];
            let mut acc = [T::default(); BLOCK];
            for (i, &w) in k.iter().enumerate() {
                for (a, &v) in acc.iter_mut().zip(&window[i..i + BLOCK]) {
                    *a += w * v;
                }
            }
            out.copy_from_slice(&acc);
        }
        let done = width - width % BLOCK;
        for (x, o) in blocks.into_remainder().iter_mut().enumerate() {
            *o = padded[done + x..].iter().zip(k).map(|(&v, &w)| v * w).sum();
        }
    }
}

/// Vertical pass of [`convolve_separable`]: whole rows are accumulated at a time so the inner
/// loop runs over contiguous memory.
pub(crate) fn convolve_columns<T: Sample>(src: &[T], width: usize, height: usize, k: &[T], dst: &mut Vec<T>) {
    let r = k.len() / 2;
    dst.resize(src.len(), T::default());
    for (y, out) in dst.chunks_exact_mut(width).enumerate() {
        out.fill(T::default());
        for (i, &w) in k.iter().enumerate() {
            let sy = (y + i).saturating_sub(r).min(height - 1);
            for (o, v) in out.iter_mut().zip(&src[sy * width..(sy + 1) * width]) {
                *o += w * *v;
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod test_util {
    use crate::image_io::{CpuImage, Texels};
    use ash::vk;

    /// An RGB image with `f(x, y, c)` per channel.
    pub fn rgb_image(width: u32, height: u32, f: impl Fn(u32, u32, usize) -> f32) -> CpuImage {
        let texels = (0..height)
            .flat_map(|y| (0..width).flat_map(move |x| (0..3).map(move |c| (x, y, c))))
            .map(|(x, y, c)| f(x, y, c))
            .collect();
        CpuImage { width, height, channels: 3, texels: Texels::F32(texels), format: vk::Format::UNDEFINED }
    }

    /// A grey image of luminance `f(x, y)` (R = G = B, so luminance equals the value).
    pub fn grey_image(width: u32, height: u32, f: impl Fn(u32, u32) -> f32) -> CpuImage {
        rgb_image(width, height, |x, y, _| f(x, y))
    }

    /// A well-mixed 32-bit integer hash, so test images are reproducible in any language.
    pub fn hash(mut v: u32) -> u32 {
        v ^= v >> 16;
        v = v.wrapping_mul(0x7feb_352d);
        v ^= v >> 15;
        v = v.wrapping_mul(0x846c_a68b);
        v ^ (v >> 16)
    }

    /// A uniform value in [0, 1) from `hash(seed)`, exact in f32.
    pub fn unit(seed: u32) -> f32 {
        (hash(seed) >> 8) as f32 / 16_777_216.0
    }
}

#[cfg(test)]
mod tests {
    use super::test_util::*;
    use super::*;

    #[test]
    fn rejects_bad_images() {
        let good = grey_image(4, 4, |_, _| 0.5);
        let small = grey_image(3, 4, |_, _| 0.5);
        assert!(matches!(rgb_pair(&good, &small), Err(MetricError::SizeMismatch { .. })));

        let mut nan = good.clone();
        if let Texels::F32(v) = &mut nan.texels {
            v[3 * 5 + 1] = f32::NAN;
            v[3 * 7] = f32::INFINITY;
        }
        let err = rgb_planes(&nan, "test").unwrap_err();
        assert_eq!(err, MetricError::NonFinite { what: "test".into(), count: 2, x: 1, y: 1, channel: 1 });

        let mut grey1 = good.clone();
        grey1.channels = 1;
        assert!(matches!(rgb_planes(&grey1, "x"), Err(MetricError::NotRgb { .. })));
        let mut ids = good.clone();
        ids.texels = Texels::U32(vec![0; 48]);
        assert!(matches!(rgb_planes(&ids, "x"), Err(MetricError::NotRgb { kind: "integer", .. })));
        let mut short = good.clone();
        short.texels = Texels::F32(vec![0.0; 47]);
        assert!(matches!(rgb_planes(&short, "x"), Err(MetricError::ShortBuffer { .. })));
        let empty = grey_image(0, 4, |_, _| 0.0);
        assert!(matches!(rgb_planes(&empty, "x"), Err(MetricError::Empty { .. })));
        assert!(Mask::new(2, 2, vec![true; 3]).is_err());
    }

    #[test]
    fn alpha_nan_is_ignored() {
        // Only the RGB channels are read, so a NaN in alpha is no error.
        let mut img = grey_image(2, 2, |_, _| 0.25);
        img.channels = 4;
        img.texels = Texels::F32([0.25, 0.25, 0.25, f32::NAN].repeat(4));
        assert_eq!(luminance_plane(&img, "x").unwrap(), vec![0.25; 4]);
    }

    #[test]
    fn separable_convolution_matches_direct_sum() {
        // Widths below, at and beyond the 8-pixel blocks of the row pass, and kernels wider
        // than the image (all taps clamp).
        let kx = [0.05, 0.15, 0.25, 0.3, 0.25];
        let ky = [0.1, 0.2, 0.4, 0.2, 0.1];
        for (w, h) in [(7usize, 5usize), (8, 3), (19, 6), (2, 1)] {
            let src: Vec<f32> = (0..w * h).map(|i| unit(i as u32)).collect();
            let (mut tmp, mut dst) = (Vec::new(), Vec::new());
            convolve_separable(&src, w, h, &kx, &ky, &mut tmp, &mut dst);
            for y in 0..h {
                for x in 0..w {
                    let mut want = 0.0;
                    for (j, wy) in ky.iter().enumerate() {
                        for (i, wx) in kx.iter().enumerate() {
                            let sx = (x as i64 + i as i64 - 2).clamp(0, w as i64 - 1) as usize;
                            let sy = (y as i64 + j as i64 - 2).clamp(0, h as i64 - 1) as usize;
                            want += wx * wy * src[sy * w + sx];
                        }
                    }
                    let got = dst[y * w + x];
                    assert!((got - want).abs() < 1e-6, "{w}x{h} at ({x}, {y}): {got} vs {want}");
                }
            }
        }
    }

    #[test]
    fn display_transforms() {
        assert_eq!(DisplayTransform::Encoded.apply(1.5), 1.0);
        assert!((DisplayTransform::Srgb.apply(0.5) - 0.735_357).abs() < 1e-5);
        assert!((srgb_decode(srgb_encode(0.2)) - 0.2).abs() < 1e-6);
        // ACES of 1.0 with the 0.6 pre-exposure: 0.6 (2.51 0.6 + 0.03) / (0.6 (2.43 0.6 + 0.59) + 0.14).
        let want = 0.6 * (2.51 * 0.6 + 0.03) / (0.6 * (2.43 * 0.6 + 0.59) + 0.14);
        assert!((aces(1.0) - want).abs() < 1e-6);
        assert_eq!(aces(1e30), 1.0);
        assert_eq!(DisplayTransform::AcesSrgb { exposure: 0.0 }.apply(-3.0), 0.0);
    }
}
