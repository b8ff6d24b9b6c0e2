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
//! - the kernel bias is estimated by Richardson extrapolation on the same photons: each pass
//!   also sums the photons within R_k / 2 (a quarter of the disc's area), and
//!   b_k = c (L_R - L_{R/2}) estimates the pass's bias, their mean the image's. Where radiance
//!   is smooth, E[L_R] - L = a R^2 + O(R^4) (HJJ 2010 eq. 9, the Laplacian term), and
//!   c = 1 / (1 - 1/4) = 4/3; at a step in radiance (a shadow's or a caustic's edge, a wall's
//!   corner) the bias is first order in R, and over the pixels within R of a straight edge
//!   the sum of squared biases equals that of c (L_R - L_{R/2}) for c = 2.08 (quadrature of
//!   the disc's segment areas). The measured bias of a Cornell box with a glass sphere is
//!   dominated by such edges (with the smooth case's factor it was 3.6 times too small), so
//!   `BIAS_FACTOR` is the geometric mean of the two, 1.665: the squared bias is then within a
//!   factor 1.56 of the truth in both regimes. The inner radius R / 2 rather than R / sqrt(2)
//!   keeps the two regimes' factors 1.5 apart rather than 1.8, at the same noise. This replaces
//!   HJJ 2010's Laplacian estimated with a smooth kernel's second derivative, which assumes the
//!   smooth regime everywhere: the same leading term where radiance is smooth, measured with
//!   the kernel the image actually uses, at the cost of one comparison per photon already found.
//!   b's mean is noisy (about three times the image's standard deviation), so its square is
//!   corrected by its own variance of the mean, b^2 = mean(b)^2 - Var(mean(b)), or noise would
//!   pass for bias; only the sum over the image is clamped at zero (a clamp per pixel would
//!   keep the noise's positive half: measured, it doubled the estimate on a scene without any
//!   bias). Where b stands out of its noise it is clamped at x: radiance is not negative, so
//!   E[x] = r + bias bounds it, while Richardson's estimate reaches 1.665 L_R where only the
//!   outer disc reaches a bright region.
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
use crate::integrators::Integrator;
use glam::{BVec3, DVec3};
use rayon::prelude::*;

/// A pixel's kernel-bias estimate counts as its own, rather than noise, when its square
/// exceeds this many times its variance of the mean (three standard deviations), and the
/// variance comes from at least `SIGNIFICANT_PASSES` passes: from fewer, it is itself too
/// noisy (with two passes a third of pure noise stands two of its standard deviations out).
const SIGNIFICANT_BIAS: f64 = 9.0;
const SIGNIFICANT_PASSES: u64 = 8;

/// The pixel's kernel-bias estimate, per channel at most its value x where it stands above
/// its noise (and which channels do): the radiance is not negative, so E[x] = r + bias
/// bounds the bias. Richardson's estimate exceeds it where the inner disc misses a bright
/// region the outer one reaches (a hit point beside a lit gap: 1.665 L_R for a bias of at
/// most L_R). Where the estimate is noise, clamping it would keep only its negative half, and
/// it is left as it is.
fn significant_bias(bias: DVec3, variance: DVec3, x: DVec3, passes: u64) -> (DVec3, BVec3) {
    let significant = BVec3::from_array(std::array::from_fn(|c| {
        passes >= SIGNIFICANT_PASSES && bias[c] * bias[c] > SIGNIFICANT_BIAS * variance[c]
    }));
    let clamped = DVec3::select(significant, bias.min(x.max(DVec3::ZERO)), bias);
    (clamped, significant)
}

impl PhotonMapper {
    /// The remaining error of `image()` (module docs).
    pub(super) fn estimate_error(&self) -> Option<ErrorEstimate> {
        if self.passes < 2 {
            return None;
        }
        let n = self.passes;
        let image = self.image();
        let (n_odd, n_even) = ((n / 2) as f64, n.div_ceil(2) as f64);
        let odd: Vec<DVec3> = self
            .pixels
            .par_iter()
            .map(|p| p.odd_estimate_sum / n_odd)
            .collect();
        let even: Vec<DVec3> = self
            .pixels
            .par_iter()
            .map(|p| (p.estimate_sum - p.odd_estimate_sum) / n_even)
            .collect();
        let (w, h) = (image.width, image.height);
        let robust = error_estimate::robust_reference_sq(&[odd, even], None, w, h);
        // The kernel bias lifts x on the dark side of every edge, just where the squared bias
        // is largest relative to r^2: r is taken below x by the bias estimate there, the
        // pixel's own where it stands out of its noise, else the neighbourhood's mean (the
        // estimate is three times noisier than x). The own one matters where a bias is the
        // pixel's alone: a fixed PPM hit point beside the door's lit gap reads several times
        // its converged value for the whole run, and the neighbourhood's mean, a ninth of
        // it, left the estimate at a sixth of the true relMSE.
        let own_bias: Vec<(DVec3, DVec3, BVec3)> = self
            .pixels
            .par_iter()
            .zip(&image.pixels)
            .map(|(p, x)| {
                let variance = error_estimate::variance_of_mean(p.bias_sum, p.bias_sum_sq, n);
                let (bias, significant) =
                    significant_bias(p.bias_sum / n as f64, variance, x.as_dvec3(), n);
                (bias, variance, significant)
            })
            .collect();
        let smoothed_bias: Vec<DVec3> = own_bias.iter().map(|b| b.0).collect();
        let smoothed_bias = error_estimate::box_filter_3x3(&smoothed_bias, w, h);
        let reference_sq: Vec<DVec3> = (0..self.pixels.len())
            .into_par_iter()
            .map(|i| {
                // A bias well above its noise is the pixel's own (PPM's fixed hit point beside
                // a bright region); below it, the neighbourhood's is less noisy.
                let (own, _, significant) = own_bias[i];
                let bias = DVec3::select(significant, own, smoothed_bias[i]);
                let corrected = (image.pixels[i].as_dvec3() - bias).max(DVec3::ZERO);
                let r = robust[i].map(f64::sqrt).min(corrected);
                r * r
            })
            .collect();
        let mut pixels: Vec<PixelError> = self
            .pixels
            .par_iter()
            .zip(reference_sq.into_par_iter())
            .zip(&own_bias)
            .map(
                |((px, reference_sq), &(bias, bias_variance, _))| PixelError {
                    variance: error_estimate::variance_of_mean(
                        px.estimate_sum,
                        px.estimate_sum_sq,
                        n,
                    ),
                    bias_sq: bias * bias - bias_variance,
                    reference_sq,
                },
            )
            .collect();
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_significant_bias_is_bounded_by_the_value_and_noise_is_left_alone() {
        let x = DVec3::new(4.0, 4.0, 0.1);
        // Red: 7 +- 0.3, clamped at x; green: 7 +- 10, noise, kept; blue: -2 +- 0.1, a
        // negative bias (the bright side of an edge), which the value does not bound.
        let bias = DVec3::new(7.0, 7.0, -2.0);
        let variance = DVec3::new(0.09, 100.0, 0.01);
        assert_eq!(
            significant_bias(bias, variance, x, 8),
            (DVec3::new(4.0, 7.0, -2.0), BVec3::new(true, false, true))
        );
        // From too few passes nothing is significant.
        assert_eq!(significant_bias(bias, variance, x, 4), (bias, BVec3::FALSE));
    }
}
