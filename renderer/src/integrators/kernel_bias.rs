//! The kernel bias of density estimation and the remaining error it leaves, shared by the
//! photon mappers (their gathers) and vcm (its merges), after Hachisuka, Jarosz & Jensen 2010
//! ("A progressive error estimation framework for photon density estimation"). The image is
//! the mean over passes of one-pass estimates L_k, each with its pass's radius R_k; the noise
//! is the sample variance of the L_k over n (independent given the radii, HJJ 2010 section
//! 4.1).
//!
//! The kernel bias is estimated by Richardson extrapolation on the same photons (or light vertices): each pass
//! also sums the photons within R_k / 2 (a quarter of the disc's area), and
//! b_k = c (L_R - L_{R/2}) estimates the pass's bias, their mean the image's. Where radiance
//! is smooth, E[L_R] - L = a R^2 + O(R^4) (HJJ 2010 eq. 9, the Laplacian term), and
//! c = 1 / (1 - 1/4) = 4/3; at a step in radiance (a shadow's or a caustic's edge, a wall's
//! corner) the bias is first order in R, and over the pixels within R of a straight edge
//! the sum of squared biases equals that of c (L_R - L_{R/2}) for c = 2.08 (quadrature of
//! the disc's segment areas). The measured bias of a Cornell box with a glass sphere is
//! dominated by such edges (with the smooth case's factor it was 3.6 times too small), so
//! `BIAS_FACTOR` is the geometric mean of the two, 1.665: the squared bias is then within a
//! factor 1.56 of the truth in both regimes. The inner radius R / 2 rather than R / sqrt(2)
//! keeps the two regimes' factors 1.5 apart rather than 1.8, at the same noise. This replaces
//! HJJ 2010's Laplacian estimated with a smooth kernel's second derivative, which assumes the
//! smooth regime everywhere: the same leading term where radiance is smooth, measured with
//! the kernel the image actually uses, at the cost of one comparison per photon already found.
//! b's mean is noisy (about three times the image's standard deviation), so its square is
//! corrected by its own variance of the mean, b^2 = mean(b)^2 - Var(mean(b)), or noise would
//! pass for bias; only the sum over the image is clamped at zero (a clamp per pixel would
//! keep the noise's positive half: measured, it doubled the estimate on a scene without any
//! bias). Where b stands out of its noise it is clamped at x: radiance is not negative, so
//! E[x] = r + bias bounds it, while Richardson's estimate reaches 1.665 L_R where only the
//! outer disc reaches a bright region.

use crate::error_estimate::{self, PixelError};
use crate::image::Image;
use glam::{BVec3, DVec3};
use rayon::prelude::*;

/// The inner disc of the bias estimate, as a fraction of the radius (module docs).
pub const INNER_RADIUS_RATIO: f64 = 0.5;
/// c in b = c (L_R - L_{R/2}): the geometric mean of 4/3 (smooth radiance) and 2.08 (a step).
pub const BIAS_FACTOR: f64 = 1.665;

/// A pixel's kernel-bias estimate counts as its own, rather than noise, when its square
/// exceeds this many times its variance of the mean (three standard deviations), and the
/// variance comes from at least `SIGNIFICANT_PASSES` passes: from fewer, it is itself too
/// noisy (with two passes a third of pure noise stands two of its standard deviations out).
const SIGNIFICANT_BIAS: f64 = 9.0;
const SIGNIFICANT_PASSES: u64 = 8;

/// Per pixel, sums over passes of the one-pass estimates L_k and their bias estimates b_k.
#[derive(Clone, Copy, Debug, Default)]
pub struct PassSums {
    pub estimate_sum: DVec3,
    pub estimate_sum_sq: DVec3,
    /// The sum over odd passes: two independent halves for a robust r^2 (`error_estimate`).
    pub odd_estimate_sum: DVec3,
    pub bias_sum: DVec3,
    pub bias_sum_sq: DVec3,
}

impl PassSums {
    /// Pass `pass`'s estimate and its bias estimate.
    pub fn add(&mut self, pass: u64, estimate: DVec3, bias: DVec3) {
        self.estimate_sum += estimate;
        self.estimate_sum_sq += estimate * estimate;
        if pass % 2 == 1 {
            self.odd_estimate_sum += estimate;
        }
        self.bias_sum += bias;
        self.bias_sum_sq += bias * bias;
    }
}

/// The bias estimate of one pass: `c (L_R - L_{R/2})` from the sums over the disc of radius
/// R (`outer`) and over its inner disc (`inner`), each not yet divided by its area
/// (`outer_area` is the outer disc's, with whatever else normalises the estimate).
pub fn pass_bias(outer: DVec3, inner: DVec3, outer_area: f64) -> DVec3 {
    let inner_area = INNER_RADIUS_RATIO * INNER_RADIUS_RATIO * outer_area;
    BIAS_FACTOR * (outer / outer_area - inner / inner_area)
}

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

/// Each pixel's variance, squared bias and robust r^2 for `image`, the mean of `passes`
/// passes whose sums `sums(i)` gives for pixel i (at least two passes). `independent`, where
/// the integrator has one, is an unbiased image whose noise does not follow the passes'
/// (`error_estimate::robust_reference_sq`).
pub fn pixel_errors<'a>(
    image: &Image,
    passes: u64,
    sums: impl Fn(usize) -> &'a PassSums + Sync,
    independent: Option<&[DVec3]>,
) -> Vec<PixelError> {
    let n = passes;
    let (w, h) = (image.width, image.height);
    let count = w * h;
    let (n_odd, n_even) = ((n / 2) as f64, n.div_ceil(2) as f64);
    let odd: Vec<DVec3> = (0..count)
        .into_par_iter()
        .map(|i| sums(i).odd_estimate_sum / n_odd)
        .collect();
    let even: Vec<DVec3> = (0..count)
        .into_par_iter()
        .map(|i| (sums(i).estimate_sum - sums(i).odd_estimate_sum) / n_even)
        .collect();
    let robust = error_estimate::robust_reference_sq(&[odd, even], independent, w, h);
    // The kernel bias lifts x on the dark side of every edge, just where the squared bias
    // is largest relative to r^2: r is taken below x by the bias estimate there, the
    // pixel's own where it stands out of its noise, else the neighbourhood's mean (the
    // estimate is three times noisier than x). The own one matters where a bias is the
    // pixel's alone: a fixed PPM hit point beside the door's lit gap reads several times
    // its converged value for the whole run, and the neighbourhood's mean, a ninth of
    // it, left the estimate at a sixth of the true relMSE.
    let own_bias: Vec<(DVec3, DVec3, BVec3)> = (0..count)
        .into_par_iter()
        .map(|i| {
            let p = sums(i);
            let variance = error_estimate::variance_of_mean(p.bias_sum, p.bias_sum_sq, n);
            let x = image.pixels[i].as_dvec3();
            let (bias, significant) = significant_bias(p.bias_sum / n as f64, variance, x, n);
            (bias, variance, significant)
        })
        .collect();
    let smoothed_bias: Vec<DVec3> = own_bias.iter().map(|b| b.0).collect();
    let smoothed_bias = error_estimate::box_filter_3x3(&smoothed_bias, w, h);
    (0..count)
        .into_par_iter()
        .map(|i| {
            // A bias well above its noise is the pixel's own (PPM's fixed hit point beside
            // a bright region); below it, the neighbourhood's is less noisy.
            let (own, bias_variance, significant) = own_bias[i];
            let bias = DVec3::select(significant, own, smoothed_bias[i]);
            let corrected = (image.pixels[i].as_dvec3() - bias).max(DVec3::ZERO);
            // E[x] = r + bias: where the bias is negative (the bright side of an edge, a peak
            // the kernel flattens) r lies above the robust estimate of E[x], not at it. Taking
            // r at E[x] there, as first built, counted vcm's merges of a point light's peak
            // (the mirrored light with a large radius) 4.7 times too high.
            let expected = robust[i].map(f64::sqrt);
            let r = DVec3::select(
                bias.cmplt(DVec3::ZERO),
                expected - bias,
                expected.min(corrected),
            );
            let p = sums(i);
            PixelError {
                variance: error_estimate::variance_of_mean(p.estimate_sum, p.estimate_sum_sq, n),
                bias_sq: own * own - bias_variance,
                reference_sq: r * r,
            }
        })
        .collect()
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
