//! The film: per-pixel sums of radiance estimates in f64 (design.md section 1: accumulators
//! that grow without bound are f64/u64), one sample per pixel per pass, box filter.
//! A pass is computed into its own buffer and merged only when complete, so a cancelled pass
//! leaves the film as it was and the image stays a normalised estimate.

use crate::image::Image;
use glam::{DVec3, Vec3};

#[derive(Clone, Debug)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    sum: Vec<DVec3>,
    passes: u64,
}

impl Film {
    pub fn new(width: usize, height: usize) -> Film {
        Film {
            width,
            height,
            sum: vec![DVec3::ZERO; width * height],
            passes: 0,
        }
    }

    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// Adds one complete pass (one estimate per pixel, row-major).
    pub fn add_pass(&mut self, pass: &[Vec3]) {
        debug_assert_eq!(pass.len(), self.sum.len());
        for (s, v) in self.sum.iter_mut().zip(pass) {
            debug_assert!(
                v.is_finite() && v.min_element() >= 0.0,
                "invalid sample {v} reached the film"
            );
            *s += v.as_dvec3();
        }
        self.passes += 1;
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
}
