//! Automatic exposure: the exposure (in stops) that suits an image, from a robust statistic
//! of its luminance, so that a scene lit by a 6830-lux sun and one lit by a dim lamp both
//! show. Photometric numbers are rendered as they stand; only the display adapts.
//!
//! The rule: the `AUTO_EXPOSURE_PERCENTILE` of the luminance of the pixels that are not black
//! is shown at `AUTO_EXPOSURE_WHITE` of white. With the linear curve, only the brightest few
//! percent (highlights, lamps seen directly) clip; the median of a scene of mixed surfaces
//! lands in the middle tones. A percentile, unlike the mean or the maximum, ignores the few
//! fireflies an early frame has. Black pixels (an unlit background) are left out so that a
//! small object in an empty view is exposed for itself.

use crate::geometry::luminance;
use crate::image::Image;

/// Which percentile of the lit pixels' luminance is placed near white.
pub const AUTO_EXPOSURE_PERCENTILE: f64 = 0.97;
/// Where that percentile is shown, as a fraction of white.
pub const AUTO_EXPOSURE_WHITE: f32 = 0.9;
/// The range of exposures the rule may choose, in stops.
pub const EXPOSURE_RANGE: f32 = 20.0;

/// The exposure in stops for `image`; 0 for an image with no lit pixel.
pub fn auto_exposure(image: &Image) -> f32 {
    let mut lit: Vec<f32> = image
        .pixels
        .iter()
        .map(|&p| luminance(p))
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lit.is_empty() {
        return 0.0;
    }
    let k = ((lit.len() - 1) as f64 * AUTO_EXPOSURE_PERCENTILE).round() as usize;
    let (_, &mut level, _) = lit.select_nth_unstable_by(k, f32::total_cmp);
    (AUTO_EXPOSURE_WHITE / level)
        .log2()
        .clamp(-EXPOSURE_RANGE, EXPOSURE_RANGE)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn image_of(values: &[f32]) -> Image {
        let mut image = Image::new(values.len(), 1);
        for (p, &v) in image.pixels.iter_mut().zip(values) {
            *p = Vec3::splat(v);
        }
        image
    }

    #[test]
    fn the_percentile_lands_near_white_whatever_the_scale() {
        // 100 lit pixels from 1 to 100 (the 97th percentile is 97) and black background: the
        // exposure brings 97 to 0.9, for a dim scene and a sunlit one alike.
        let mut values: Vec<f32> = (1..=100).map(|v| v as f32).collect();
        values.extend([0.0; 300]);
        for scale in [1e-3f32, 1.0, 6830.0] {
            let scaled: Vec<f32> = values.iter().map(|v| v * scale).collect();
            let ev = auto_exposure(&image_of(&scaled));
            let shown = 97.0 * scale * ev.exp2();
            assert!(
                (shown - AUTO_EXPOSURE_WHITE).abs() < 1e-3,
                "scale {scale}: {shown}"
            );
        }
        // A few fireflies do not move it.
        values.extend([1e6; 2]);
        let ev = auto_exposure(&image_of(&values));
        assert!(
            (97.0 * ev.exp2() - AUTO_EXPOSURE_WHITE).abs() < 0.02,
            "{ev}"
        );
    }

    #[test]
    fn a_black_or_absurd_image_gets_a_bounded_exposure() {
        assert_eq!(auto_exposure(&image_of(&[0.0; 10])), 0.0);
        assert_eq!(auto_exposure(&image_of(&[1e-30; 10])), EXPOSURE_RANGE);
        assert_eq!(auto_exposure(&image_of(&[f32::NAN, 1e30])), -EXPOSURE_RANGE);
    }
}
