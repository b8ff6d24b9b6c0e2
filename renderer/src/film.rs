//! The film: per-pixel sums of radiance estimates in f64 (DESIGN.md section 1: accumulators
//! that grow without bound are f64/u64), one sample per pixel per pass, box filter.
//! A pass is computed into its own buffer and merged only when complete, so a cancelled pass
//! leaves the film as it was and the image stays a normalised estimate.
//!
//! Passes are independent estimates of every pixel, so the film also keeps what the
//! remaining error is estimated from (`error_estimate`): each pixel's sum of squared pass
//! values, whose spread gives the variance of the mean, and the sum over odd passes, which
//! splits the passes into two independent halves for a robust estimate of the pixel's value.

use crate::error_estimate::{self, ErrorEstimate, PixelError};
use crate::image::Image;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    sum: Vec<DVec3>,
    sum_sq: Vec<DVec3>,
    odd_sum: Vec<DVec3>,
    passes: u64,
}

impl Film {
    /// Bytes of the accumulators.
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.sum.as_slice())
            + size_of_val(self.sum_sq.as_slice())
            + size_of_val(self.odd_sum.as_slice())
    }

    pub fn new(width: usize, height: usize) -> Film {
        Film {
            width,
            height,
            sum: vec![DVec3::ZERO; width * height],
            sum_sq: vec![DVec3::ZERO; width * height],
            odd_sum: vec![DVec3::ZERO; width * height],
            passes: 0,
        }
    }

    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// Adds one complete pass (one estimate per pixel, row-major).
    pub fn add_pass(&mut self, pass: &[Vec3]) {
        debug_assert_eq!(pass.len(), self.sum.len());
        let odd = self.passes % 2 == 1;
        for (i, v) in pass.iter().enumerate() {
            debug_assert!(
                v.is_finite() && v.min_element() >= 0.0,
                "invalid sample {v} reached the film"
            );
            let v = v.as_dvec3();
            self.sum[i] += v;
            self.sum_sq[i] += v * v;
            if odd {
                self.odd_sum[i] += v;
            }
        }
        self.passes += 1;
    }

    /// The remaining error of `image()`: per pixel, the sample variance of the passes over
    /// their number (the passes are independent and identically distributed), divided by a
    /// robust r^2 from the even and odd passes' means (`robust_reference_sq`). None before two
    /// passes.
    pub fn error_estimate(&self) -> Option<ErrorEstimate> {
        if self.passes < 2 {
            return None;
        }
        let n = self.passes;
        let (n_odd, n_even) = ((n / 2) as f64, n.div_ceil(2) as f64);
        let odd: Vec<DVec3> = self.odd_sum.par_iter().map(|s| *s / n_odd).collect();
        let even: Vec<DVec3> = (self.sum.par_iter().zip(&self.odd_sum))
            .map(|(s, o)| (*s - *o) / n_even)
            .collect();
        let reference_sq =
            error_estimate::robust_reference_sq(&[odd, even], None, self.width, self.height);
        let pixels: Vec<PixelError> = (0..self.sum.len())
            .into_par_iter()
            .map(|i| PixelError {
                variance: error_estimate::variance_of_mean(self.sum[i], self.sum_sq[i], n),
                bias_sq: DVec3::ZERO,
                reference_sq: reference_sq[i],
            })
            .collect();
        ErrorEstimate::from_pixels(self.width, self.height, &pixels)
    }

    /// Pixel `i`'s estimate (the mean of its passes; zero before the first).
    pub fn mean(&self, i: usize) -> DVec3 {
        self.sum[i] / self.passes.max(1) as f64
    }

    /// The variance of pixel `i`'s estimate, from the spread of its passes (zero before two).
    pub fn variance_of_mean(&self, i: usize) -> DVec3 {
        error_estimate::variance_of_mean(self.sum[i], self.sum_sq[i], self.passes)
    }

    /// The mean of all passes so far (black before the first).
    pub fn image(&self) -> Image {
        let inv = if self.passes > 0 {
            1.0 / self.passes as f64
        } else {
            0.0
        };
        Image {
            width: self.width,
            height: self.height,
            pixels: self.sum.iter().map(|s| (*s * inv).as_vec3()).collect(),
        }
    }
}

/// Guards a radiance estimate at its source: NaN, infinite or negative values are replaced
/// by zero and reported, so they never reach the film.
pub fn sanitize(l: Vec3) -> Option<Vec3> {
    (l.is_finite() && l.min_element() >= 0.0).then_some(l)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn invalid_estimates_are_refused_and_valid_ones_averaged() {
        assert_eq!(sanitize(Vec3::new(f32::NAN, 0.0, 0.0)), None);
        assert_eq!(sanitize(Vec3::new(0.0, f32::INFINITY, 0.0)), None);
        assert_eq!(sanitize(Vec3::new(0.0, 0.0, -1e-3)), None);
        assert_eq!(sanitize(Vec3::ONE), Some(Vec3::ONE));
        let mut film = Film::new(1, 1);
        film.add_pass(&[Vec3::splat(1.0)]);
        film.add_pass(&[Vec3::splat(3.0)]);
        assert_eq!(film.image().pixels[0], Vec3::splat(2.0));
        assert_eq!(film.passes(), 2);
    }

    /// Ten million passes cycling through 0.0, 0.1, ..., 0.9 (as f32, none but 0 exact in
    /// binary): the image is their mean and the variance of the mean its exact value, both
    /// within 1e-6 relative (summed in f32 the mean would be off by over 1e-2, and the
    /// variance from sums of squares lost entirely).
    #[test]
    fn ten_million_passes_keep_mean_and_variance() {
        let values: Vec<f32> = (0..10).map(|k| k as f32 / 10.0).collect();
        let passes = 10_000_000u64;
        let mut film = Film::new(1, 1);
        for p in 0..passes {
            film.add_pass(&[Vec3::splat(values[(p % 10) as usize])]);
        }
        let exact: Vec<f64> = values.iter().map(|&v| f64::from(v)).collect();
        let mean = exact.iter().sum::<f64>() / 10.0;
        let spread = exact.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 10.0;
        // The sample variance over n - 1, over n for the variance of the mean.
        let n = passes as f64;
        let variance = spread * n / (n - 1.0) / n;
        let relative = |a: f64, b: f64| ((a - b) / b).abs();
        assert_eq!(film.passes(), passes);
        assert!(relative(film.mean(0).x, mean) < 1e-6, "{}", film.mean(0).x);
        assert!(
            relative(f64::from(film.image().pixels[0].x), mean) < 1e-6,
            "{}",
            film.image().pixels[0].x
        );
        let v = film.variance_of_mean(0).x;
        assert!(relative(v, variance) < 1e-6, "{v} against {variance}");
    }
}
