//! The photon mappers' remaining error, after Hachisuka, Jarosz & Jensen 2010 ("A progressive
//! error estimation framework for photon density estimation").
//!
//! Every variant's image is the
//! mean over passes of one-pass estimates L_k = direct_k + tau_M,k / (pi R_k^2 P) (for PPM and
//! SPPM because eq. 7's rescaling telescopes: tau_n / R_n^2 = sum of tau_M,k / R_k^2), so
//!
//! - the noise is the sample variance of the L_k over n, as in HJJ 2010 section 4.1. The L_k
//!   are independent given the radii, with variances that grow as R_k shrinks; the sample
//!   variance estimates their mean, which is what the variance of the mean needs.
//! - the kernel bias is estimated by Richardson extrapolation on the same photons, as
//!   `kernel_bias` describes (shared with vcm's merges).
//! - where amcppm's passes trace photons only every k-th pass (`photon_budget`), a pass
//!   without photons counts the photons' running mean m (and their bias's), and the photon
//!   pass that follows k L_M - (k - 1) m for its photon part L_M: the k passes then sum to
//!   k L_M, the photons' share of the image, and the spread of the L_k is V_e + k V_M, so the
//!   variance of their mean is V_e / n + V_M / (n / k), which is the image's (its photon part
//!   is the mean of n / k photon passes). Counting 0 in the passes between, with k L_M in
//!   the photon pass, would add the on-and-off of the photons' whole value to the spread.
//!   The running mean's own noise adds to the spread too (it cancels in the sum, not in
//!   the squares): about (k - 1) / k ln(B) / B of the photons' variance after B photon
//!   passes, an overestimate that fades (`pixel_stats`'s test: 19 % after 16, 2 % after 256).
//! - PPM gathers at one hit point per pixel for the whole run, so its photon part converges to
//!   the radiance at that point, not to the pixel's mean: an error whose expected square is the
//!   variance of the indirect radiance over the pixel's footprint. It is estimated from the
//!   image's second differences (the nugget of a variogram): for a pixel whose neighbours' hit
//!   points are independent draws, E[(I_p - (I_l + I_r) / 2)^2] = 1.5 V + their noise +
//!   curvature^2, so V is 2/3 of the mean of the horizontal and vertical squared second
//!   differences less the noise variances. The pixel's converged value is the mean over its
//!   footprint, so this variance is divided by the square of that mean, estimated by the 3x3
//!   mean of the image, not by the pixel's own value: a feature thinner than a pixel (the lit
//!   gap of the door) is missed by most pixels' hit points, whose own values are then far
//!   below the truth. (Dividing by the pixel's own value overestimated the door's relMSE 49
//!   times; an earlier correction for edge pixels counted twice, calibrated with that
//!   denominator, proved to be compensating it, and is gone.) Across a sharp edge a pixel's
//!   neighbours see its variance too, which counts it up to 1.5 times over; detail finer than
//!   a pixel with no edge is counted once.
//!

use super::PhotonMapper;
use crate::error_estimate::{self, ErrorEstimate, PixelError};
use crate::integrators::{Integrator, kernel_bias};
use glam::DVec3;
use rayon::prelude::*;

impl PhotonMapper {
    /// The remaining error of `image()` (module docs).
    pub(super) fn estimate_error(&self) -> Option<ErrorEstimate> {
        if self.passes < 2 {
            return None;
        }
        let image = self.image();
        let mut pixels =
            kernel_bias::pixel_errors(&image, self.passes, |i| &self.pixels[i].passes, None);
        if self.variant.fixed_hit_points() {
            self.add_footprint_variance(&mut pixels);
        }
        ErrorEstimate::from_pixels(image.width, image.height, &pixels)
    }

    /// PPM's error from gathering at one fixed point per pixel (module docs): the variance of
    /// the indirect radiance over each pixel's footprint, from the squared second differences
    /// of the indirect image less the noise in them. Added to the pixels' variance, as the
    /// hit point's position is random like the noise. A pixel whose eye path found no hit
    /// point counts with an indirect radiance of zero: that is what its footprint gave there
    /// (through glass, where the one specular choice PPM keeps per pixel decides it, this
    /// took the estimate on the caustic pool from a third of the truth to within 10 %).
    fn add_footprint_variance(&self, pixels: &mut [PixelError]) {
        let (w, h) = (
            self.ctx.camera.width as usize,
            self.ctx.camera.height as usize,
        );
        let indirect: Vec<DVec3> = (0..self.pixels.len())
            .into_par_iter()
            .map(|i| self.indirect(i))
            .collect();
        let noise: Vec<DVec3> = pixels.iter().map(|p| p.variance).collect();
        // The pixel's converged value is the mean over its footprint, which its neighbours
        // sample too: the footprint error is relative to the neighbourhood's mean, not to the
        // pixel's own value, which misses a bright feature thinner than a pixel whenever its
        // hit point does (measured on the door, whose lit gap is a pixel wide: dividing by the
        // pixel's own r^2 overestimated the relMSE 49 times).
        let n = self.passes.max(1) as f64;
        let values: Vec<DVec3> = (0..self.pixels.len())
            .map(|i| self.pixels[i].direct_sum / n + indirect[i])
            .collect();
        let footprint_mean = error_estimate::box_filter_3x3(&values, w, h);
        pixels
            .par_chunks_mut(w.max(1))
            .enumerate()
            .for_each(|(y, row)| {
                for (x, pixel) in row.iter_mut().enumerate() {
                    let i = y * w + x;
                    let mut sum = DVec3::ZERO;
                    let mut count = 0.0;
                    let horizontal = (x > 0 && x + 1 < w).then(|| (i - 1, i + 1));
                    let vertical = (y > 0 && y + 1 < h).then(|| (i - w, i + w));
                    for b in [horizontal, vertical].into_iter().flatten() {
                        let d = indirect[i] - 0.5 * (indirect[b.0] + indirect[b.1]);
                        sum += d * d - noise[i] - 0.25 * (noise[b.0] + noise[b.1]);
                        count += 1.0;
                    }
                    if count > 0.0 {
                        let variance = (sum / (1.5 * count)).max(DVec3::ZERO);
                        // Expressed over the pixel's own denominator, as the film's variance is.
                        let own = pixel.reference_sq + error_estimate::REL_MSE_EPSILON;
                        let mean_sq = footprint_mean[i] * footprint_mean[i];
                        let footprint = mean_sq + error_estimate::REL_MSE_EPSILON;
                        pixel.variance += variance * own / footprint;
                    }
                }
            });
    }
}
