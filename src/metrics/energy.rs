//! Energy: how much light an image holds against a reference, the measure of a renderer that
//! drops light (a truncated path, a clamp that cuts bright samples) however little noise it has.

use super::{Result, check_dims, luminance_plane};
use crate::image_io::CpuImage;

/// A pixel whose reference luminance exceeds this many times the reference's 90th percentile
/// is a light seen directly: both images show its emission exactly, and with it in the mean a
/// small light would outweigh everything it lights.
pub const EMITTER_FACTOR: f32 = 4.0;

/// Mean luminance of `test` over that of `reference`, both over the pixels that are not lights
/// seen directly ([`EMITTER_FACTOR`]). 1 when the test image holds the reference's light.
pub fn luminance_ratio(reference: &CpuImage, test: &CpuImage) -> Result<f64> {
    let r = luminance_plane(reference, "reference")?;
    check_dims("test", (reference.width, reference.height), (test.width, test.height))?;
    let t = luminance_plane(test, "test")?;
    let mut sorted = r.clone();
    sorted.sort_by(f32::total_cmp);
    let bound = EMITTER_FACTOR * sorted[sorted.len() * 9 / 10];
    let (mut sum_r, mut sum_t) = (0.0f64, 0.0f64);
    for (&lr, &lt) in r.iter().zip(&t) {
        if lr <= bound {
            sum_r += lr as f64;
            sum_t += lt as f64;
        }
    }
    if sum_r <= 0.0 {
        return Err(super::MetricError::InvalidParameter(
            "luminance ratio: the reference holds no light outside its emitters".into(),
        ));
    }
    Ok(sum_t / sum_r)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metrics::test_util::{grey_image, rgb_image};

    #[test]
    fn a_darker_image_reads_its_share_and_lights_seen_directly_are_left_out() {
        // A 10 x 10 wall of 0.5 with one light of 100 in its corner.
        let reference = grey_image(10, 10, |x, y| if x + y == 0 { 100.0 } else { 0.5 });
        let same = luminance_ratio(&reference, &reference).unwrap();
        assert!((same - 1.0).abs() < 1e-9, "{same}");
        // 10% darker walls; the light itself 1000x brighter: only the walls count.
        let darker = grey_image(10, 10, |x, y| if x + y == 0 { 1e5 } else { 0.45 });
        let ratio = luminance_ratio(&reference, &darker).unwrap();
        assert!((ratio - 0.9).abs() < 1e-6, "{ratio}");
    }

    #[test]
    fn luminance_weighs_the_channels() {
        let reference = grey_image(4, 4, |_, _| 1.0);
        let green = rgb_image(4, 4, |_, _, c| if c == 1 { 1.0 } else { 0.0 });
        let ratio = luminance_ratio(&reference, &green).unwrap();
        assert!((ratio - 0.7152).abs() < 1e-4, "{ratio}");
    }

    #[test]
    fn a_black_reference_is_an_error() {
        let black = grey_image(4, 4, |_, _| 0.0);
        assert!(luminance_ratio(&black, &black).is_err());
    }
}
