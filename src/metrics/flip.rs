//! FLIP, the perceptual difference evaluator of Andersson, Nilsson, Akenine-Möller, Oskarsson,
//! Åström and Fairchild, "FLIP: A Difference Evaluator for Alternating Images" (HPG 2020), and
//! its HDR extension by Andersson, Nilsson, Shirley and Akenine-Möller, "Visualizing Errors in
//! Rendered High Dynamic Range Images" (Eurographics 2021). Implemented here from the papers'
//! description, with separable filters.
//!
//! # LDR-FLIP
//! Per pixel error in [0, 1] between two images in [0, 1] seen at `ppd` pixels per degree:
//! 1. **Colour pipeline.** Linear RGB → CIE XYZ (D65) → YCxCz (the linearised CIELAB opponent
//!    space). Each channel is convolved with its contrast sensitivity filter: achromatic and
//!    red-green one Gaussian each, blue-yellow a sum of two, all given in the frequency domain by
//!    `a · √(π/b) · exp(−π² x² / b)` (x in degrees) with (a, b) = (1, 0.0047), (1, 0.0053) and
//!    (34.1, 0.04) + (13.5, 0.025); every 2D filter is normalised to sum 1 and has radius
//!    `⌈3 √(0.04 / (2π²)) · ppd⌉` pixels. The result goes back to linear RGB, is clamped to
//!    [0, 1], converted to CIELAB and Hunt-adjusted (`a, b ← 0.01 L · a, b`). The colour
//!    difference is HyAB (`|ΔL| + √(Δa² + Δb²)`) raised to `q_c = 0.7` and remapped so that
//!    `p_c · c_max` (`p_c = 0.4`, `c_max` the distance between Hunt-adjusted green and blue) maps
//!    to `p_t = 0.95` and `c_max` to 1, linearly on each side.
//! 2. **Feature pipeline.** On the normalised luminance `(Y_ycxcz + 16) / 116`, edges (first
//!    derivative of a Gaussian) and points (second derivative) are detected in x and y with
//!    σ = `0.5 · 0.082 · ppd` pixels and radius `⌈3σ⌉`; each derivative filter's positive weights
//!    sum to 1 and negative ones to −1. The feature difference is
//!    `(max(|‖edge_r‖ − ‖edge_t‖|, |‖point_r‖ − ‖point_t‖|) / √2)^0.5`.
//! 3. **Error** `= colour_difference ^ (1 − feature_difference)`; the image's FLIP is the mean.
//!
//! Pixels outside the image are read from the nearest edge pixel.
//!
//! # HDR-FLIP
//! The exposure range is taken from the reference's luminance: `c_start = log2(x_max / Y_max)`
//! and `c_stop = log2(x_max / Y_median)`, where `x_max` is the input the tonemapper maps to
//! 0.85, `Y_max` the largest luminance and `Y_median` the element at index `n/2` of the sorted
//! luminances. `n = max(2, ⌈c_stop − c_start⌉)` exposures evenly spaced in
//! `[c_start, c_stop]` each scale both images by `2^c`, tonemap them with the ACES fit (with its
//! 0.6 pre-exposure), clamp to [0, 1] and run LDR-FLIP; the HDR-FLIP error of a pixel is its
//! maximum over the exposures.
//!
//! Deviations from NVIDIA's tool, all in cases it does not handle: negative input values are
//! clamped to 0 (as NVIDIA's PyTorch version does); if more than half of the reference is
//! black, `Y_median` is taken over its non-black pixels (NVIDIA's would be 0 and the stop
//! exposure infinite); an all-black reference uses the single exposure 0 (twice).
//!
//! # Checked against
//! The unit tests compare this implementation with NVIDIA's own (their C++ FLIP, as shipped in
//! the `flip-evaluator` 1.7 Python package) on generated 97x64 images: three LDR cases (noise,
//! a blue-only change, a one-pixel shift at 30 ppd with linear input) and two HDR cases
//! (automatic exposures, and given ones). The means agree to within 5e-7, single pixels (corners
//! included) to within 4e-6, and the automatic exposure range to within 1e-6. NVIDIA's
//! published reference pair (images/reference.{png,exr} and test.{png,exr} in their repository,
//! expected LDR mean 0.159691 and HDR mean 0.283478 with exposures −12.5423 … 0.9427 in 14
//! steps) was not available offline; `tests/metrics.rs` has an ignored test that checks those
//! numbers when the images are supplied.

use super::{ACES, MetricError, Planes, Result, aces, convolve_columns, convolve_rows, rgb_pair, srgb_decode};
use crate::image_io::CpuImage;
use std::f32::consts::PI;

/// Pixels per degree of the FLIP papers' default viewer: 0.7 m from a 0.7 m wide 3840-pixel
/// monitor (= [`pixels_per_degree`]`(0.7, 3840.0, 0.7)`).
pub const DEFAULT_PPD: f32 = 67.020_645;

/// Pixels per degree of visual angle for a viewer `distance_m` from a monitor `width_m` wide
/// showing `width_px` pixels across (small-angle approximation, as FLIP defines it).
pub fn pixels_per_degree(distance_m: f32, width_px: f32, width_m: f32) -> f32 {
    distance_m * (width_px / width_m) * (PI / 180.0)
}

/// How the values of an LDR image encode colour.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LdrInput {
    /// sRGB-encoded values in [0, 1] (a PNG, or an 8-bit UNORM read-back of a tonemapped frame):
    /// decoded with the sRGB EOTF, as NVIDIA's tool does for PNG files.
    Srgb,
    /// Linear values in [0, 1].
    Linear,
}

/// The exposures HDR-FLIP evaluated: `count` evenly spaced values from `start` to `stop`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposures {
    pub start: f32,
    pub stop: f32,
    pub count: usize,
}

/// A FLIP evaluation.
#[derive(Clone, Debug, PartialEq)]
pub struct FlipResult {
    /// Mean FLIP error over all pixels, in [0, 1] (0 for identical images).
    pub mean: f64,
    /// Per-pixel FLIP error in [0, 1], rows top to bottom, if asked for.
    pub map: Option<Vec<f32>>,
    /// HDR-FLIP only: the exposures used.
    pub exposures: Option<Exposures>,
}

/// Settings of [`hdr_flip`]; `None` exposures are computed from the reference as in the paper.
#[derive(Clone, Debug, PartialEq)]
pub struct HdrFlipOptions {
    pub ppd: f32,
    pub start_exposure: Option<f32>,
    pub stop_exposure: Option<f32>,
    pub num_exposures: Option<usize>,
    pub keep_map: bool,
}

impl Default for HdrFlipOptions {
    fn default() -> Self {
        Self { ppd: DEFAULT_PPD, start_exposure: None, stop_exposure: None, num_exposures: None, keep_map: false }
    }
}

/// LDR-FLIP of two images whose RGB values are in [0, 1] (clamped to it first, as NVIDIA does).
pub fn ldr_flip(
    reference: &CpuImage,
    test: &CpuImage,
    input: LdrInput,
    ppd: f32,
    keep_map: bool,
) -> Result<FlipResult> {
    let (r, t) = rgb_pair(reference, test)?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let filters = Filters::new(ppd)?;
    let to_linear = |planes: Planes| {
        planes.map(|p| {
            p.into_iter()
                .map(|v| match input {
                    LdrInput::Srgb => srgb_decode(v.clamp(0.0, 1.0)),
                    LdrInput::Linear => v.clamp(0.0, 1.0),
                })
                .collect::<Vec<f32>>()
        })
    };
    let map = ldr_map(&to_linear(r), &to_linear(t), w, h, &filters);
    Ok(FlipResult { mean: mean(&map), map: keep_map.then_some(map), exposures: None })
}

/// HDR-FLIP of two linear HDR images.
pub fn hdr_flip(reference: &CpuImage, test: &CpuImage, options: &HdrFlipOptions) -> Result<FlipResult> {
    let (r, t) = rgb_pair(reference, test)?;
    let (w, h) = (reference.width as usize, reference.height as usize);
    let filters = Filters::new(options.ppd)?;
    let clamp = |planes: Planes| planes.map(|p| p.into_iter().map(|v| v.max(0.0)).collect::<Vec<f32>>());
    let (r, t) = (clamp(r), clamp(t));
    let exposures = exposure_range(&r, options)?;
    let step =
        if exposures.count > 1 { (exposures.stop - exposures.start) / (exposures.count - 1) as f32 } else { 0.0 };
    let mut map = vec![0.0f32; w * h];
    for i in 0..exposures.count {
        let scale = (exposures.start + i as f32 * step).exp2();
        let expose =
            |planes: &Planes| [0, 1, 2].map(|c| planes[c].iter().map(|&v| aces(v * scale)).collect::<Vec<f32>>());
        let ldr = ldr_map(&expose(&r), &expose(&t), w, h, &filters);
        for (m, v) in map.iter_mut().zip(ldr) {
            *m = m.max(v);
        }
    }
    Ok(FlipResult { mean: mean(&map), map: options.keep_map.then_some(map), exposures: Some(exposures) })
}

fn mean(map: &[f32]) -> f64 {
    map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64
}

/// The exposures to evaluate: the options' where given, else from the reference's luminance.
fn exposure_range(reference: &Planes, options: &HdrFlipOptions) -> Result<Exposures> {
    let auto = || {
        let mut lum: Vec<f32> = (0..reference[0].len())
            .map(|i| super::luminance(reference[0][i], reference[1][i], reference[2][i]))
            .collect();
        let y_max = lum.iter().cloned().fold(0.0f32, f32::max);
        if y_max <= 0.0 {
            return (0.0, 0.0);
        }
        let mid = lum.len() / 2;
        let mut y_median = *lum.select_nth_unstable_by(mid, f32::total_cmp).1;
        if y_median <= 0.0 {
            lum.retain(|&v| v > 0.0);
            let mid = lum.len() / 2;
            y_median = *lum.select_nth_unstable_by(mid, f32::total_cmp).1;
        }
        let x_max = aces_input_for(0.85);
        ((x_max / y_max).log2(), (x_max / y_median).log2())
    };
    let (auto_start, auto_stop) =
        if options.start_exposure.is_none() || options.stop_exposure.is_none() { auto() } else { (0.0, 0.0) };
    let start = options.start_exposure.unwrap_or(auto_start);
    let stop = options.stop_exposure.unwrap_or(auto_stop);
    if !(start.is_finite() && stop.is_finite() && start <= stop) {
        return Err(MetricError::InvalidParameter(format!(
            "hdr_flip: exposures must be finite with start <= stop, not {start} .. {stop}"
        )));
    }
    let count = match options.num_exposures {
        Some(0) => return Err(MetricError::InvalidParameter("hdr_flip: num_exposures must be at least 1".into())),
        Some(n) => n,
        None => (stop - start).ceil().max(2.0) as usize,
    };
    Ok(Exposures { start, stop, count })
}

/// The input `x > 0` that the ACES fit maps to `t`: the positive root of
/// `(k0 − t k3) x² + (k1 − t k4) x − t k5 = 0`.
fn aces_input_for(t: f32) -> f32 {
    let [k0, k1, k3, k4, k5] = ACES;
    let (a, b, c) = (k0 - t * k3, k1 - t * k4, -t * k5);
    (-b + (b * b - 4.0 * a * c).sqrt()) / (2.0 * a)
}

/// The separable 1D filters of one pixels-per-degree setting.
struct Filters {
    /// Contrast sensitivity of the achromatic (Y) and red-green (Cx) channels.
    csf_y: Vec<f32>,
    csf_cx: Vec<f32>,
    /// The blue-yellow (Cz) filter is a sum of two 2D Gaussians: each is the outer product of one
    /// of these with itself, scaled so that the 2D sum of both terms is 1.
    csf_cz: [Vec<f32>; 2],
    /// Gaussian, its first derivative and its second derivative for the feature detectors.
    gauss: Vec<f32>,
    edge: Vec<f32>,
    point: Vec<f32>,
}

impl Filters {
    fn new(ppd: f32) -> Result<Self> {
        // Beyond ~1000 ppd (a 4K monitor 10 m away) the filters grow to thousands of taps.
        if !(ppd > 0.0 && ppd <= 1000.0) {
            return Err(MetricError::InvalidParameter(format!("FLIP: ppd must be in (0, 1000], not {ppd}")));
        }
        // Frequency-domain CSF (a, b) pairs of the papers, turned into spatial Gaussians.
        let radius = (3.0 * (0.04 / (2.0 * PI * PI)).sqrt() * ppd).ceil() as i32;
        let spatial = |a: f32, b: f32, sqrt: bool| -> Vec<f32> {
            let scale = a * (PI / b).sqrt();
            // A 2D term a·√(π/b)·exp(−π²(x²+y²)/b) is the outer product of two 1D factors
            // √(a·√(π/b))·exp(−π²x²/b); for a single Gaussian the scale cancels in normalisation.
            let scale = if sqrt { scale.sqrt() } else { scale };
            (-radius..=radius)
                .map(|i| {
                    let x = i as f32 / ppd;
                    scale * (-PI * PI * x * x / b).exp()
                })
                .collect()
        };
        let normalise = |k: Vec<f32>, sum: f32| k.into_iter().map(|v| v / sum).collect::<Vec<f32>>();
        let (y, cx) = (spatial(1.0, 0.0047, false), spatial(1.0, 0.0053, false));
        let (cz1, cz2) = (spatial(34.1, 0.04, true), spatial(13.5, 0.025, true));
        let (s1, s2) = (cz1.iter().sum::<f32>(), cz2.iter().sum::<f32>());
        // The 2D sum of both terms is s1² + s2²; dividing each 1D factor by its root makes it 1.
        let cz_norm = (s1 * s1 + s2 * s2).sqrt();
        let (sy, scx) = (y.iter().sum(), cx.iter().sum());

        let sigma = 0.5 * 0.082 * ppd;
        let r = (3.0 * sigma).ceil() as i32;
        let xs: Vec<f32> = (-r..=r).map(|i| i as f32).collect();
        let gauss: Vec<f32> = xs.iter().map(|x| (-x * x / (2.0 * sigma * sigma)).exp()).collect();
        let edge: Vec<f32> = xs.iter().zip(&gauss).map(|(x, g)| -x * g).collect();
        let point: Vec<f32> = xs.iter().zip(&gauss).map(|(x, g)| (x * x / (sigma * sigma) - 1.0) * g).collect();
        let g_sum: f32 = gauss.iter().sum();
        Ok(Self {
            csf_y: normalise(y, sy),
            csf_cx: normalise(cx, scx),
            csf_cz: [normalise(cz1, cz_norm), normalise(cz2, cz_norm)],
            gauss: normalise(gauss, g_sum),
            edge: balance(edge),
            point: balance(point),
        })
    }
}

/// Scales a derivative filter's positive weights to sum 1 and its negative weights to sum −1.
fn balance(k: Vec<f32>) -> Vec<f32> {
    let pos: f32 = k.iter().filter(|v| **v > 0.0).sum();
    let neg: f32 = -k.iter().filter(|v| **v < 0.0).sum::<f32>();
    k.into_iter().map(|v| if v > 0.0 { v / pos } else { v / neg }).collect()
}

/// What FLIP compares of one image: Hunt-adjusted CIELAB after the CSF filters, and the edge and
/// point feature magnitudes.
struct Perceived {
    lab: Planes,
    edge: Vec<f32>,
    point: Vec<f32>,
}

/// The LDR-FLIP error map of two linear RGB images in [0, 1]. The two images are prepared on
/// two threads: they are independent until the final per-pixel comparison.
fn ldr_map(reference: &Planes, test: &Planes, w: usize, h: usize, f: &Filters) -> Vec<f32> {
    let (r, t) = std::thread::scope(|s| {
        let r = s.spawn(|| perceive(reference, w, h, f));
        let t = perceive(test, w, h, f);
        (r.join().unwrap_or_else(|e| std::panic::resume_unwind(e)), t)
    });
    let c_max = hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(Q_C);
    let pc_max = P_C * c_max;
    (0..w * h)
        .map(|i| {
            let lab = |p: &Perceived| [p.lab[0][i], p.lab[1][i], p.lab[2][i]];
            let d = hyab(lab(&r), lab(&t)).powf(Q_C);
            let colour =
                if d < pc_max { d * (P_T / pc_max) } else { P_T + (d - pc_max) / (c_max - pc_max) * (1.0 - P_T) };
            let feature_diff = (r.edge[i] - t.edge[i]).abs().max((r.point[i] - t.point[i]).abs());
            let feature = (feature_diff * std::f32::consts::FRAC_1_SQRT_2).powf(Q_F);
            colour.powf(1.0 - feature)
        })
        .collect()
}

const Q_C: f32 = 0.7;
const P_C: f32 = 0.4;
const P_T: f32 = 0.95;
const Q_F: f32 = 0.5;

fn perceive(rgb: &Planes, w: usize, h: usize, f: &Filters) -> Perceived {
    let n = w * h;
    let mut ycxcz = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
    for i in 0..n {
        let v = xyz_to_ycxcz(rgb_to_xyz([rgb[0][i], rgb[1][i], rgb[2][i]]));
        for c in 0..3 {
            ycxcz[c][i] = v[c];
        }
    }
    let (mut tmp, mut a, mut b) = (Vec::new(), Vec::new(), Vec::new());

    // Feature pipeline on the normalised luminance.
    let gray: Vec<f32> = ycxcz[0].iter().map(|y| (y + 16.0) / 116.0).collect();
    let (mut rows_g, mut rows_d, mut rows_p) = (Vec::new(), Vec::new(), Vec::new());
    convolve_rows(&gray, w, &f.gauss, &mut rows_g);
    convolve_rows(&gray, w, &f.edge, &mut rows_d);
    convolve_rows(&gray, w, &f.point, &mut rows_p);
    // d/dx is the x-derivative filtered by a Gaussian in y; d/dy the other way round.
    let magnitude = |along_x: &[f32], along_y: &[f32], k: &[f32], a: &mut Vec<f32>, b: &mut Vec<f32>| {
        convolve_columns(along_x, w, h, &f.gauss, a);
        convolve_columns(along_y, w, h, k, b);
        a.iter().zip(b.iter()).map(|(x, y)| (x * x + y * y).sqrt()).collect::<Vec<f32>>()
    };
    let edge = magnitude(&rows_d, &rows_g, &f.edge, &mut a, &mut b);
    let point = magnitude(&rows_p, &rows_g, &f.point, &mut a, &mut b);
    // Free three planes before the colour pipeline allocates its own (8 MB each at 1080p).
    drop((rows_g, rows_d, rows_p));

    // Colour pipeline: CSF filtering in YCxCz, back to clamped linear RGB, then Hunt-adjusted Lab.
    let [y, cx, cz] = &ycxcz;
    let (mut yf, mut cxf, mut czf) = (Vec::new(), Vec::new(), Vec::new());
    super::convolve_separable(y, w, h, &f.csf_y, &f.csf_y, &mut tmp, &mut yf);
    super::convolve_separable(cx, w, h, &f.csf_cx, &f.csf_cx, &mut tmp, &mut cxf);
    super::convolve_separable(cz, w, h, &f.csf_cz[0], &f.csf_cz[0], &mut tmp, &mut czf);
    super::convolve_separable(cz, w, h, &f.csf_cz[1], &f.csf_cz[1], &mut tmp, &mut a);
    for (v, extra) in czf.iter_mut().zip(&a) {
        *v += extra;
    }
    for i in 0..n {
        let rgb = xyz_to_rgb(ycxcz_to_xyz([yf[i], cxf[i], czf[i]])).map(|v| v.clamp(0.0, 1.0));
        let lab = hunt_lab(rgb);
        (yf[i], cxf[i], czf[i]) = (lab[0], lab[1], lab[2]);
    }
    Perceived { lab: [yf, cxf, czf], edge, point }
}

/// The D65 white of XYZ, which YCxCz and CIELAB are relative to.
const WHITE: [f32; 3] = [0.950_428_5, 1.0, 1.088_900_4];

/// Linear sRGB to CIE XYZ (D65), with the rational matrix of the sRGB primaries that FLIP uses.
fn rgb_to_xyz([r, g, b]: [f32; 3]) -> [f32; 3] {
    [
        (10_135_552.0 * r + 8_788_810.0 * g + 4_435_075.0 * b) / 24_577_794.0,
        (2_613_072.0 * r + 8_788_810.0 * g + 887_015.0 * b) / 12_288_897.0,
        (1_425_312.0 * r + 8_788_810.0 * g + 70_074_185.0 * b) / 73_733_382.0,
    ]
}

/// The inverse of [`rgb_to_xyz`].
fn xyz_to_rgb([x, y, z]: [f32; 3]) -> [f32; 3] {
    [
        3.241_003_3 * x - 1.537_398_9 * y - 0.498_615_87 * z,
        -0.969_224_3 * x + 1.875_930_1 * y + 0.041_554_224 * z,
        0.055_639_423 * x - 0.204_011_2 * y + 1.057_148_9 * z,
    ]
}

fn xyz_to_ycxcz(xyz: [f32; 3]) -> [f32; 3] {
    let [x, y, z] = [xyz[0] / WHITE[0], xyz[1], xyz[2] / WHITE[2]];
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_xyz([yy, cx, cz]: [f32; 3]) -> [f32; 3] {
    let y = (yy + 16.0) / 116.0;
    [(y + cx / 500.0) * WHITE[0], y, (y - cz / 200.0) * WHITE[2]]
}

/// CIELAB of linear RGB with the Hunt adjustment (chroma scaled by 0.01 L: colours look less
/// saturated when dark).
fn hunt_lab(rgb: [f32; 3]) -> [f32; 3] {
    let xyz = rgb_to_xyz(rgb);
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| if t > DELTA * DELTA * DELTA { t.cbrt() } else { t / (3.0 * DELTA * DELTA) + 4.0 / 29.0 };
    let [fx, fy, fz] = [f(xyz[0] / WHITE[0]), f(xyz[1]), f(xyz[2] / WHITE[2])];
    let l = 116.0 * fy - 16.0;
    [l, 0.01 * l * 500.0 * (fx - fy), 0.01 * l * 200.0 * (fy - fz)]
}

/// HyAB colour distance: city-block in lightness, Euclidean in chroma.
fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    (p[0] - q[0]).abs() + ((p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    // The generated test images. The same images in NumPy, to reproduce the NVIDIA values below
    // with `pip install flip-evaluator==1.7` (NVIDIA's C++ FLIP):
    //
    //   y, x, c = np.meshgrid(np.arange(64), np.arange(97), np.arange(3), indexing='ij')  # as uint64
    //   unit(s) = (hash(s & 0xffffffff) >> 8) / 2**24 in float32, hash as test_util::hash
    //   block(s) = unit(s * 1000003 + ((y // 8) * 64 + x // 8) * 3 + c)
    //   noise(s) = unit(s * 7919 + (y * 97 + x) * 3 + c + 0x9e3779b9)
    //   pattern(s) = 0.5 * block(s) + 0.3 * (x / 97) + 0.2 * noise(s)             # float32 throughout
    //   flip_evaluator.evaluate(ref, test, "LDR" | "HDR", inputsRGB=..., parameters=...)[1]
    const W: u32 = 97;
    const H: u32 = 64;

    fn block(seed: u32, x: u32, y: u32, c: usize) -> f32 {
        unit(seed.wrapping_mul(1_000_003).wrapping_add(((y / 8) * 64 + x / 8) * 3 + c as u32))
    }

    fn noise(seed: u32, x: u32, y: u32, c: usize) -> f32 {
        unit(seed.wrapping_mul(7919).wrapping_add((y * W + x) * 3 + c as u32).wrapping_add(0x9e37_79b9))
    }

    fn pattern(seed: u32, x: u32, y: u32, c: usize) -> f32 {
        0.5 * block(seed, x, y, c) + 0.3 * (x as f32 / W as f32) + 0.2 * noise(seed, x, y, c)
    }

    fn ldr_reference() -> CpuImage {
        rgb_image(W, H, |x, y, c| pattern(1, x, y, c))
    }

    fn ldr_noisy(amount: f32) -> CpuImage {
        rgb_image(W, H, |x, y, c| (pattern(1, x, y, c) + amount * (noise(2, x, y, c) - 0.5)).clamp(0.0, 1.0))
    }

    fn hdr_reference() -> CpuImage {
        rgb_image(W, H, |x, y, c| (12.0 * block(3, x, y, c) - 6.0).exp2() * (0.5 + 0.5 * noise(3, x, y, c)))
    }

    fn ldr(reference: &CpuImage, test: &CpuImage, input: LdrInput, ppd: f32) -> f64 {
        ldr_flip(reference, test, input, ppd, false).unwrap().mean
    }

    fn close(got: f64, want: f64, tol: f64, what: &str) {
        assert!((got - want).abs() <= tol, "{what}: {got} vs NVIDIA's {want}");
    }

    #[test]
    fn matches_nvidia_ldr() {
        let r = ldr_reference();
        let noisy = ldr_flip(&r, &ldr_noisy(0.2), LdrInput::Srgb, DEFAULT_PPD, true).unwrap();
        close(noisy.mean, 0.119_361_020_624_637_6, 2e-6, "noise");
        // Pixels at the corners (edge clamping) and inside.
        let map = noisy.map.unwrap();
        for ((x, y), want) in [
            ((0, 0), 0.198_089_167_475_700_38),
            ((96, 0), 0.186_172_485_351_562_5),
            ((0, 63), 0.290_621_817_111_969),
            ((96, 63), 0.162_752_181_291_580_2),
            ((48, 32), 0.107_330_210_506_916_05),
            ((5, 40), 0.101_677_864_789_962_77),
        ] {
            close(map[(y * W + x) as usize] as f64, want, 2e-5, &format!("pixel ({x}, {y})"));
        }
        // A chroma-only change (blue scaled): the blue-yellow channel's two-Gaussian filter.
        let blue = rgb_image(W, H, |x, y, c| pattern(1, x, y, c) * if c == 2 { 0.6 } else { 1.0 });
        close(ldr(&r, &blue, LdrInput::Srgb, DEFAULT_PPD), 0.447_773_575_782_775_9, 2e-6, "blue");
        // A one-pixel shift (features), linear input, another viewing distance.
        let shifted = rgb_image(W, H, |x, y, c| pattern(1, (x + 1).min(W - 1), y, c));
        close(ldr(&r, &shifted, LdrInput::Linear, 30.0), 0.276_627_808_809_280_4, 2e-6, "shift");
    }

    #[test]
    fn matches_nvidia_hdr() {
        let r = hdr_reference();
        let t = rgb_image(W, H, |x, y, c| r.get(x, y, c) * (1.0 + 0.5 * (noise(4, x, y, c) - 0.5)));
        let result = hdr_flip(&r, &t, &HdrFlipOptions { keep_map: true, ..Default::default() }).unwrap();
        close(result.mean, 0.081_590_786_576_271_06, 2e-6, "noise");
        let e = result.exposures.unwrap();
        close(e.start as f64, -4.579_623_222_351_074, 1e-5, "start exposure");
        close(e.stop as f64, -0.555_947_363_376_617_4, 1e-5, "stop exposure");
        assert_eq!(e.count, 5);
        let map = result.map.unwrap();
        for ((x, y), want) in [
            ((0, 0), 0.104_686_833_918_094_64),
            ((96, 0), 0.214_212_223_887_443_54),
            ((0, 63), 0.118_794_322_013_854_98),
            ((96, 63), 0.068_937_718_868_255_62),
            ((48, 32), 0.066_686_898_469_924_93),
            ((5, 40), 0.027_088_794_857_263_565),
        ] {
            close(map[(y * W + x) as usize] as f64, want, 2e-5, &format!("pixel ({x}, {y})"));
        }
        // Given exposures, and a global brightness error.
        let brighter = rgb_image(W, H, |x, y, c| r.get(x, y, c) * 1.25);
        let opts = HdrFlipOptions {
            start_exposure: Some(-3.0),
            stop_exposure: Some(2.0),
            num_exposures: Some(4),
            ..Default::default()
        };
        close(hdr_flip(&r, &brighter, &opts).unwrap().mean, 0.247_752_338_647_842_4, 2e-6, "brighter");
    }

    #[test]
    fn identical_images_have_zero_error() {
        let r = ldr_reference();
        let result = ldr_flip(&r, &r, LdrInput::Srgb, DEFAULT_PPD, true).unwrap();
        assert_eq!(result.mean, 0.0);
        assert!(result.map.unwrap().iter().all(|&v| v == 0.0));
        let h = hdr_reference();
        assert_eq!(hdr_flip(&h, &h, &HdrFlipOptions::default()).unwrap().mean, 0.0);
    }

    #[test]
    fn error_grows_with_the_perturbation() {
        // NVIDIA's values: 0.0426417, 0.0711177, 0.1193610, 0.2044059.
        let r = ldr_reference();
        let means: Vec<f64> = [0.05, 0.1, 0.2, 0.4].map(|k| ldr(&r, &ldr_noisy(k), LdrInput::Srgb, DEFAULT_PPD)).into();
        assert!(means.windows(2).all(|m| m[0] < m[1]), "{means:?}");
        for (got, want) in means.iter().zip([0.042_641_744, 0.071_117_721, 0.119_361_021, 0.204_405_874]) {
            close(*got, want, 2e-6, "noise series");
        }
    }

    #[test]
    fn green_against_blue_is_the_maximum_colour_error() {
        // Uniform images have no features, and the CSF filters keep them uniform, so the error is
        // the colour term alone; green vs blue is c_max, which the remapping sends to 1.
        let green = rgb_image(16, 16, |_, _, c| if c == 1 { 1.0 } else { 0.0 });
        let blue = rgb_image(16, 16, |_, _, c| if c == 2 { 1.0 } else { 0.0 });
        close(ldr(&green, &blue, LdrInput::Linear, DEFAULT_PPD), 1.0, 1e-5, "green/blue");
        // And p_c · c_max maps to p_t: a grey pair whose HyAB^q_c is 0.4 c_max scores 0.95.
        let c_max = hyab(hunt_lab([0.0, 1.0, 0.0]), hunt_lab([0.0, 0.0, 1.0])).powf(Q_C);
        let d = (P_C * c_max).powf(1.0 / Q_C); // the lightness step that gives it
        let l0 = 30.0f32;
        let lin = |l: f32| ((l + 16.0) / 116.0).powi(3); // CIELAB L to luminance (above the linear toe)
        let a = rgb_image(8, 8, |_, _, _| lin(l0));
        let b = rgb_image(8, 8, |_, _, _| lin(l0 + d));
        close(ldr(&a, &b, LdrInput::Linear, DEFAULT_PPD), 0.95, 1e-3, "p_t");
    }

    #[test]
    fn viewing_conditions_and_bad_parameters() {
        assert!((pixels_per_degree(0.7, 3840.0, 0.7) - DEFAULT_PPD).abs() < 1e-4);
        let r = ldr_reference();
        assert!(ldr_flip(&r, &r, LdrInput::Srgb, 0.0, false).is_err());
        assert!(ldr_flip(&r, &r, LdrInput::Srgb, f32::NAN, false).is_err());
        let bad = |start, stop, n| HdrFlipOptions {
            start_exposure: Some(start),
            stop_exposure: Some(stop),
            num_exposures: n,
            ..Default::default()
        };
        assert!(hdr_flip(&r, &r, &bad(1.0, -1.0, None)).is_err());
        assert!(hdr_flip(&r, &r, &bad(-1.0, 1.0, Some(0))).is_err());
        assert!(hdr_flip(&r, &r, &bad(f32::NEG_INFINITY, 1.0, None)).is_err());
        assert_eq!(hdr_flip(&r, &r, &bad(-1.0, 1.0, Some(1))).unwrap().exposures.unwrap().count, 1);
    }

    #[test]
    fn dark_references_get_finite_exposures() {
        // All black: one exposure range [0, 0]; mostly black: the median of the lit pixels.
        let black = rgb_image(20, 20, |_, _, _| 0.0);
        let lit = rgb_image(20, 20, |x, _, _| if x < 5 { 2.0 } else { 0.0 });
        let e = hdr_flip(&black, &lit, &HdrFlipOptions::default()).unwrap();
        assert_eq!(e.exposures, Some(Exposures { start: 0.0, stop: 0.0, count: 2 }));
        assert!(e.mean > 0.0 && e.mean <= 1.0);
        let e = hdr_flip(&lit, &black, &HdrFlipOptions::default()).unwrap();
        let x = e.exposures.unwrap();
        // Max and median luminance are both 2: log2(x_max / 2).
        let want = aces_input_for(0.85).log2() - 1.0;
        assert!((x.start - want).abs() < 1e-5 && (x.stop - want).abs() < 1e-5, "{x:?}");
        // Negative test values are clamped to 0, i.e. equal to a black reference.
        let negative = rgb_image(20, 20, |_, _, _| -1.0);
        assert_eq!(hdr_flip(&black, &negative, &HdrFlipOptions::default()).unwrap().mean, 0.0);
    }
}
