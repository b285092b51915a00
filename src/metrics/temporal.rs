//! Temporal stability over a sequence of frames (linear HDR, all the same size).
//!
//! Every measure works on per-pixel linear luminance `Y = 0.2126 R + 0.7152 G + 0.0722 B`
//! ([`super::luminance`]), so its absolute values are in the renderer's radiance units.

use super::{Mask, MetricError, Result, luminance_plane};
use crate::image_io::CpuImage;

/// Result of [`flicker`].
#[derive(Clone, Debug, PartialEq)]
pub struct FlickerReport {
    /// `d_i = mean_{p ∈ M} |Y_{s+i+1}(p) − Y_{s+i}(p)|` for each consecutive pair after the
    /// convergence index `s` (luminance units).
    pub per_step: Vec<f64>,
    /// Mean of `per_step`: the flicker, in luminance units.
    pub mean_abs_change: f64,
    /// Mean luminance over the masked pixels of frames `s..` (luminance units).
    pub mean_luminance: f64,
    /// `mean_abs_change / mean_luminance` (dimensionless); `None` when the mean luminance is not
    /// positive, where a relative change means nothing.
    pub relative: Option<f64>,
}

/// Flicker of a static view after convergence: the mean absolute frame-to-frame change of
/// luminance over the frames `frames[converged_at..]`, restricted to `mask` if given.
///
/// `flicker = (1/(K−1)) Σ_{k=s+1}^{s+K−1} (1/|M|) Σ_{p ∈ M} |Y_k(p) − Y_{k−1}(p)|`, with
/// `s = converged_at` and `K = frames.len() − s` (at least 2). A pixel toggling between `v` and
/// `v + d` every frame contributes `d`. Errors if fewer than two frames follow `converged_at`,
/// sizes differ, or the mask selects no pixel.
pub fn flicker(frames: &[CpuImage], converged_at: usize, mask: Option<&Mask>) -> Result<FlickerReport> {
    let frames = frames.get(converged_at..).unwrap_or_default();
    if frames.len() < 2 {
        return Err(MetricError::InvalidParameter(format!(
            "flicker: needs at least 2 frames from index {converged_at} on, has {}",
            frames.len()
        )));
    }
    let lum = luminance_sequence(frames, converged_at)?;
    let selected = selection(mask, &frames[0], "flicker")?;
    let n = selected.len() as f64;
    let per_step: Vec<f64> = lum
        .windows(2)
        .map(|pair| selected.iter().map(|&i| (pair[1][i] as f64 - pair[0][i] as f64).abs()).sum::<f64>() / n)
        .collect();
    let mean_abs_change = per_step.iter().sum::<f64>() / per_step.len() as f64;
    let mean_luminance =
        lum.iter().map(|l| selected.iter().map(|&i| l[i] as f64).sum::<f64>()).sum::<f64>() / (n * lum.len() as f64);
    let relative = (mean_luminance > 0.0).then(|| mean_abs_change / mean_luminance);
    Ok(FlickerReport { per_step, mean_abs_change, mean_luminance, relative })
}

/// Result of [`ghosting`].
#[derive(Clone, Debug, PartialEq)]
pub struct GhostingReport {
    /// `E_t = Σ_{p ∈ T_t} |Y_t(p) − Y_bg(p)|` per frame: the luminance left over (or missing)
    /// in the trail, in luminance units × pixels.
    pub energy: Vec<f64>,
    /// `E_t / |T_t|`: the mean absolute luminance error per trail pixel (0 for an empty trail).
    pub mean_error: Vec<f64>,
    /// The first frame index `t` from which `E_s ≤ clear_fraction · max(E)` for every `s ≥ t`:
    /// frames until the ghost has faded. `None` if the last frame is still above.
    pub frames_to_clear: Option<usize>,
}

/// Ghosting behind a moving object: per frame, the energy left inside the trail mask (the pixels
/// where the object was but no longer is) compared with the expected `background` there.
///
/// `trail_masks` holds one mask per frame, or a single mask used for every frame. `frames[0]`
/// should be the first frame after the object left (the ghost's peak); see
/// [`GhostingReport`] for the formulas. `clear_fraction` in [0, 1]: e.g. 0.1 asks for the frame
/// where the ghost has fallen to a tenth of its peak.
pub fn ghosting(
    frames: &[CpuImage],
    background: &CpuImage,
    trail_masks: &[Mask],
    clear_fraction: f64,
) -> Result<GhostingReport> {
    if frames.is_empty() {
        return Err(MetricError::InvalidParameter("ghosting: no frames".into()));
    }
    if trail_masks.len() != 1 && trail_masks.len() != frames.len() {
        return Err(MetricError::InvalidParameter(format!(
            "ghosting: {} trail masks for {} frames (give one, or one per frame)",
            trail_masks.len(),
            frames.len()
        )));
    }
    if !(0.0..=1.0).contains(&clear_fraction) {
        return Err(MetricError::InvalidParameter(format!(
            "ghosting: clear_fraction must be in [0, 1], not {clear_fraction}"
        )));
    }
    let bg = luminance_plane(background, "background")?;
    let lum = luminance_sequence(frames, 0)?;
    let (w, h) = (background.width, background.height);
    super::check_dims("frame 0", (w, h), (frames[0].width, frames[0].height))?;
    let mut energy = Vec::with_capacity(frames.len());
    let mut mean_error = Vec::with_capacity(frames.len());
    for (t, l) in lum.iter().enumerate() {
        let mask = &trail_masks[t.min(trail_masks.len() - 1)];
        mask.check_size(&format!("trail mask {t}"), w, h)?;
        let (mut e, mut n) = (0.0f64, 0usize);
        for (i, _) in mask.bits().iter().enumerate().filter(|(_, b)| **b) {
            e += (l[i] as f64 - bg[i] as f64).abs();
            n += 1;
        }
        energy.push(e);
        mean_error.push(if n == 0 { 0.0 } else { e / n as f64 });
    }
    let peak = energy.iter().cloned().fold(0.0, f64::max);
    let frames_to_clear = settle_index(&energy, clear_fraction * peak);
    Ok(GhostingReport { energy, mean_error, frames_to_clear })
}

/// Result of [`lag`].
#[derive(Clone, Debug, PartialEq)]
pub struct LagReport {
    /// `e_t = Σ_p |Y_t(p) − Y_s(p)| / Σ_p Y_s(p)` per frame: the relative mean absolute
    /// luminance error against the settled image (dimensionless; 0.05 = 5 %).
    pub errors: Vec<f64>,
    /// The lag: the first frame index `t` from which `e_s ≤ threshold` for every `s ≥ t`, i.e.
    /// the number of frames rendered after the change before the image stays settled (0 if the
    /// first frame after the change already is). `None` if the last frame is still above.
    pub frames: Option<usize>,
}

/// Lag after a change (a light switched or moved): `frames[0]` is the first frame rendered after
/// the change, `settled` the image the renderer converges to afterwards (e.g. a converged
/// reference render of the new state), and `threshold` the relative error (see
/// [`LagReport::errors`]) under which a frame counts as settled. Errors if the settled image's
/// total luminance is not positive (a relative error would be undefined).
pub fn lag(frames: &[CpuImage], settled: &CpuImage, threshold: f64) -> Result<LagReport> {
    if frames.is_empty() {
        return Err(MetricError::InvalidParameter("lag: no frames".into()));
    }
    if !(threshold >= 0.0 && threshold.is_finite()) {
        return Err(MetricError::InvalidParameter(format!("lag: threshold must be finite and >= 0, not {threshold}")));
    }
    let target = luminance_plane(settled, "settled")?;
    super::check_dims("frame 0", (settled.width, settled.height), (frames[0].width, frames[0].height))?;
    let total: f64 = target.iter().map(|&v| v as f64).sum();
    if total <= 0.0 {
        return Err(MetricError::InvalidParameter(format!(
            "lag: the settled image's total luminance is {total}; a relative error needs it positive"
        )));
    }
    let errors: Vec<f64> = luminance_sequence(frames, 0)?
        .iter()
        .map(|l| l.iter().zip(&target).map(|(&a, &b)| (a as f64 - b as f64).abs()).sum::<f64>() / total)
        .collect();
    let frames = settle_index(&errors, threshold);
    Ok(LagReport { errors, frames })
}

/// The first index from which every value is at most `limit`; `None` if the last one exceeds it.
fn settle_index(series: &[f64], limit: f64) -> Option<usize> {
    match series.iter().rposition(|&v| v > limit) {
        None => Some(0),
        Some(i) if i + 1 < series.len() => Some(i + 1),
        Some(_) => None,
    }
}

/// Luminance planes of frames that all have the first frame's size; `first_index` numbers them
/// in error messages.
fn luminance_sequence(frames: &[CpuImage], first_index: usize) -> Result<Vec<Vec<f32>>> {
    let (w, h) = (frames[0].width, frames[0].height);
    frames
        .iter()
        .enumerate()
        .map(|(k, f)| {
            let what = format!("frame {}", first_index + k);
            super::check_dims(&what, (w, h), (f.width, f.height))?;
            luminance_plane(f, &what)
        })
        .collect()
}

/// Indices of the selected pixels (all if no mask); errors on a size mismatch or an empty selection.
fn selection(mask: Option<&Mask>, frame: &CpuImage, what: &str) -> Result<Vec<usize>> {
    let selected: Vec<usize> = match mask {
        None => (0..frame.pixel_count()).collect(),
        Some(m) => {
            m.check_size(&format!("{what} mask"), frame.width, frame.height)?;
            m.bits().iter().enumerate().filter(|(_, b)| **b).map(|(i, _)| i).collect()
        }
    };
    if selected.is_empty() {
        return Err(MetricError::InvalidParameter(format!("{what}: the mask selects no pixel")));
    }
    Ok(selected)
}

#[cfg(test)]
mod tests {
    use super::super::test_util::*;
    use super::*;

    #[test]
    fn flicker_of_a_toggle_is_its_amplitude() {
        // Frames 0..3 converge (big changes), then the pixels toggle between v and v + d.
        let d = 0.05f32;
        let frames: Vec<CpuImage> = (0..12)
            .map(|k| {
                grey_image(6, 4, move |x, y| {
                    let v = 0.3 + 0.1 * unit(x + 6 * y);
                    if k < 3 { 5.0 * k as f32 } else { v + if k % 2 == 0 { d } else { 0.0 } }
                })
            })
            .collect();
        let r = flicker(&frames, 3, None).unwrap();
        assert_eq!(r.per_step.len(), 8);
        assert!((r.mean_abs_change - d as f64).abs() < 1e-6, "{}", r.mean_abs_change);
        let rel = r.relative.unwrap();
        assert!((rel - r.mean_abs_change / r.mean_luminance).abs() < 1e-12);
        // A static sequence does not flicker.
        assert_eq!(flicker(&vec![frames[5].clone(); 3], 0, None).unwrap().mean_abs_change, 0.0);
    }

    #[test]
    fn flicker_respects_the_mask() {
        // Only the left half flickers; masking the right half gives 0, the left half gives d.
        let frames: Vec<CpuImage> =
            (0..6).map(|k| grey_image(8, 2, move |x, _| if x < 4 && k % 2 == 1 { 1.2 } else { 1.0 })).collect();
        let left = Mask::from_fn(8, 2, |x, _| x < 4);
        let right = Mask::from_fn(8, 2, |x, _| x >= 4);
        assert!((flicker(&frames, 0, Some(&left)).unwrap().mean_abs_change - 0.2).abs() < 1e-6);
        assert_eq!(flicker(&frames, 0, Some(&right)).unwrap().mean_abs_change, 0.0);
        let none = Mask::from_fn(8, 2, |_, _| false);
        assert!(flicker(&frames, 0, Some(&none)).is_err());
        assert!(flicker(&frames, 5, None).is_err());
        assert!(flicker(&frames, 99, None).is_err());
    }

    #[test]
    fn ghost_halving_each_frame() {
        // A trail of 6 pixels starts 0.8 above the background and halves every frame.
        let bg = grey_image(10, 6, |x, y| 0.1 + 0.05 * unit(x + 10 * y));
        let trail = Mask::from_fn(10, 6, |x, y| (2..5).contains(&x) && (1..3).contains(&y));
        let frames: Vec<CpuImage> = (0..8)
            .map(|t| {
                let extra = 0.8 * 0.5f32.powi(t);
                grey_image(10, 6, |x, y| {
                    bg.get(x, y, 0) + if trail.bits()[(10 * y + x) as usize] { extra } else { 0.0 }
                })
            })
            .collect();
        let r = ghosting(&frames, &bg, std::slice::from_ref(&trail), 0.1).unwrap();
        for (t, e) in r.energy.iter().enumerate() {
            let want = 6.0 * 0.8 * 0.5f64.powi(t as i32);
            assert!((e - want).abs() < 1e-5, "frame {t}: {e} vs {want}");
            assert!((r.mean_error[t] - want / 6.0).abs() < 1e-6);
        }
        // 0.5^t <= 0.1 first at t = 4 (0.0625); 0.5^3 = 0.125 is still above.
        assert_eq!(r.frames_to_clear, Some(4));
        // A ghost that never fades below a hundredth within 5 frames.
        assert_eq!(ghosting(&frames[..5], &bg, std::slice::from_ref(&trail), 0.01).unwrap().frames_to_clear, None);
        assert!(ghosting(&frames, &bg, &[trail.clone(), trail], 0.1).is_err());
    }

    #[test]
    fn lag_of_an_exponential_settle() {
        // A light change from luminance 1 to 2, approached by an exponential moving average with
        // weight 0.2: Y_t = 2 − 0.8^t, e_t = 0.8^t / 2. e_t <= 0.05 first at t = ceil(ln 0.1 / ln 0.8) = 11.
        let frames: Vec<CpuImage> = (0..20).map(|t| grey_image(5, 5, move |_, _| 2.0 - 0.8f32.powi(t))).collect();
        let settled = grey_image(5, 5, |_, _| 2.0);
        let r = lag(&frames, &settled, 0.05).unwrap();
        let want = (0.1f64.ln() / 0.8f64.ln()).ceil() as usize;
        assert_eq!(want, 11);
        assert_eq!(r.frames, Some(want));
        assert!((r.errors[0] - 0.5).abs() < 1e-6);
        assert_eq!(lag(&frames[..8], &settled, 0.05).unwrap().frames, None);
        assert_eq!(lag(&frames, &settled, 1.0).unwrap().frames, Some(0));
        let black = grey_image(5, 5, |_, _| 0.0);
        assert!(lag(&frames, &black, 0.05).is_err());
    }

    #[test]
    fn settle_index_needs_to_stay_below() {
        // Dipping below and rising again does not count as settled.
        assert_eq!(settle_index(&[5.0, 0.5, 3.0, 0.5, 0.4], 1.0), Some(3));
        assert_eq!(settle_index(&[0.5, 0.4], 1.0), Some(0));
        assert_eq!(settle_index(&[0.5, 2.0], 1.0), None);
    }
}
