//! The remaining error of a progressive estimate, without a reference.
//!
//! The error a user cares about is relMSE against the converged image r (DESIGN.md section 3):
//! the mean over pixels and channels of (x - r)^2 / (r^2 + 0.01). Without r, each integrator
//! estimates every pixel's expected squared error from its own samples,
//!
//! ```text
//! E[(x - r)^2] = Var(x) + bias(x)^2,
//! ```
//!
//! (the variance from independent estimates it keeps for that purpose, the bias where its
//! estimator has one), and r^2 in the denominator is replaced by an estimate that a single
//! outlier cannot inflate: a firefly makes x^2 as large as the squared error it causes, which
//! would hide exactly the error it is. How each integrator does it is documented beside its
//! `Integrator::error_estimate`; this module holds what they share.

use glam::DVec3;
use rayon::prelude::*;

/// Estimated remaining error of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorEstimate {
    /// Estimated relMSE of the whole image.
    pub rel_mse: f64,
    /// Each pixel's estimated relMSE term, the mean over its channels (row-major), with its
    /// squared-bias part clamped at zero (so their mean can exceed `rel_mse` a little).
    pub per_pixel: Vec<f32>,
    pub width: usize,
    pub height: usize,
    /// The part of `rel_mse` that is squared bias (kernel bias of the photon mappers).
    pub bias_rel_mse: f64,
}

/// One pixel's estimated squared error and the squared radiance to divide it by.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelError {
    /// Var(x) per channel.
    pub variance: DVec3,
    /// Squared bias per channel. It may be negative: an unbiased estimate of a square,
    /// corrected for its own noise, is negative where the noise exceeds it; only the sum over
    /// the image is clamped at zero (clamping each pixel would turn noise into bias).
    pub bias_sq: DVec3,
    /// The estimate of r^2 per channel used in relMSE's denominator.
    pub reference_sq: DVec3,
}

/// The most partial estimates `robust_reference_sq` takes (more are ignored).
pub const MAX_PARTS: usize = 8;

/// The relMSE denominator's stabiliser (DESIGN.md section 3).
pub const REL_MSE_EPSILON: f64 = 0.01;

impl ErrorEstimate {
    /// Sums per-pixel errors into the relMSE estimate; None for an empty image or any
    /// non-finite term (an estimate that cannot be trusted is not shown).
    pub fn from_pixels(width: usize, height: usize, pixels: &[PixelError]) -> Option<Self> {
        debug_assert_eq!(pixels.len(), width * height);
        if pixels.is_empty() {
            return None;
        }
        let mut per_pixel = Vec::with_capacity(pixels.len());
        let (mut variance_total, mut bias_total) = (0.0f64, 0.0f64);
        for p in pixels {
            if !(p.variance.is_finite() && p.bias_sq.is_finite() && p.reference_sq.is_finite()) {
                return None;
            }
            let denominator = p.reference_sq.max(DVec3::ZERO) + DVec3::splat(REL_MSE_EPSILON);
            let variance = (p.variance.max(DVec3::ZERO) / denominator).element_sum() / 3.0;
            let bias = (p.bias_sq / denominator).element_sum() / 3.0;
            variance_total += variance;
            bias_total += bias;
            // Shown per pixel, where a negative estimate of a square means "none seen".
            per_pixel.push((variance + bias.max(0.0)) as f32);
        }
        let n = pixels.len() as f64;
        let bias_rel_mse = bias_total.max(0.0) / n;
        let rel_mse = variance_total / n + bias_rel_mse;
        rel_mse.is_finite().then_some(ErrorEstimate {
            rel_mse,
            per_pixel,
            width,
            height,
            bias_rel_mse,
        })
    }

    /// The estimate for independent runs averaged with weights `weights` (summing to any
    /// positive total): their errors are independent, so variances combine with the squared
    /// weights. Used by `merge` on the whole-image figure; exact for unbiased estimates, and
    /// for biased ones the bias part, common to all runs, is kept as it is.
    pub fn merged_rel_mse(parts: &[(f64, f64, f64)]) -> Option<f64> {
        let total: f64 = parts.iter().map(|p| p.0).sum();
        if !(total > 0.0) {
            return None;
        }
        let mut variance = 0.0;
        let mut bias = 0.0;
        for &(weight, rel_mse, bias_rel_mse) in parts {
            let w = weight / total;
            variance += w * w * (rel_mse - bias_rel_mse).max(0.0);
            bias += w * bias_rel_mse;
        }
        Some(variance + bias)
    }
}

/// Per channel, the variance of the mean of `n` independent estimates whose sum is `sum` and
/// sum of squares `sum_sq` (the sample variance over n, with Bessel's correction).
pub fn variance_of_mean(sum: DVec3, sum_sq: DVec3, n: u64) -> DVec3 {
    if n < 2 {
        return DVec3::ZERO;
    }
    let nf = n as f64;
    let mean = sum / nf;
    ((sum_sq / nf - mean * mean) * (nf / (nf - 1.0)) / nf).max(DVec3::ZERO)
}

/// Estimates of r^2 for every pixel from independent partial estimates of the whole image
/// (halves of the passes, groups of chains), each scaled to estimate the full image.
///
/// Per channel, r = min(x, max(m, m3, x3, i3)): x the mean of the parts (the image), m their
/// lower median (the minimum of two), m3 the lower median of the parts averaged over the
/// pixel's 3 x 3 neighbourhood, x3 the lower median of the parts' medians over that
/// neighbourhood. Each term answers one way a plug-in r fails:
/// - a firefly or a lingering Markov chain lands in one part, so m, m3 and x3 all stay near
///   r where x is far above it (x^2 would hide the very error the outlier causes). A chain
///   lingers over a patch wider than the neighbourhood, so the median over the neighbourhood
///   is taken within each part, not of x: the median of x took such a patch for the signal,
///   and the estimate on the caustic pool for a third of MMLT's true error;
/// - early on every part is noisy, and the minimum of noisy parts falls below r (with two
///   passes, far below): the neighbourhood's median in each part is three times less noisy
///   and unbiased where the image is locally flat;
/// - where the signal itself is rare (a pixel that sees a light through glass in a few passes
///   only; Metropolis chains, early, with no sample yet at most pixels of a part) m and x3 are
///   near zero and would make the error look a hundred times larger than it is; the
///   neighbourhood's mean in each part holds enough samples for m3 to stand for the pixel;
/// - across an edge the neighbourhood mixes both sides and m3 lends a dark pixel its bright
///   neighbours' radiance, which the minimum with x (the pixel's own mean) takes back;
/// - where only a few parts see a pixel's light at all and see it brightly (a caustic that
///   one group of Metropolis chains lingers on while the others have not found it), every
///   median is near zero. `independent`, where the integrator has it, is an unbiased image
///   whose noise does not follow the parts' (MMLT's large-step proposals): its 3 x 3 mean,
///   a fifth candidate in the maximum, stands for such pixels. Without it, MMLT's estimate
///   on the Cornell box with glass was 2 to 8 times its true error once its chains no longer
///   rendered the direct light (which had hidden the caustic's share); with it, 1.3 to 1.8.
pub fn robust_reference_sq(
    parts: &[Vec<DVec3>],
    independent: Option<&[DVec3]>,
    width: usize,
    height: usize,
) -> Vec<DVec3> {
    let count = width * height;
    if parts.is_empty() {
        return vec![DVec3::ZERO; count];
    }
    let parts = &parts[..parts.len().min(MAX_PARTS)];
    let smoothed: Vec<Vec<DVec3>> = parts
        .iter()
        .map(|part| box_filter_3x3(part, width, height))
        .collect();
    let mean: Vec<DVec3> = (0..count)
        .into_par_iter()
        .map(|i| parts.iter().map(|p| p[i].max(DVec3::ZERO)).sum::<DVec3>() / parts.len() as f64)
        .collect();
    let medians: Vec<Vec<DVec3>> = parts
        .iter()
        .map(|part| median_filter_3x3(part, width, height))
        .collect();
    let independent = independent.map(|image| box_filter_3x3(image, width, height));
    let rank = (parts.len() - 1) / 2;
    let lower_median = |parts: &[Vec<DVec3>], i: usize, c: usize| {
        // Few parts (two halves, four groups): on the stack, sorted by insertion.
        let mut v = [0.0f64; MAX_PARTS];
        for (j, p) in parts.iter().enumerate() {
            let x = p[i][c].max(0.0);
            let mut k = j;
            while k > 0 && v[k - 1] > x {
                v[k] = v[k - 1];
                k -= 1;
            }
            v[k] = x;
        }
        v[rank]
    };
    (0..count)
        .into_par_iter()
        .map(|i| {
            let channel = |c: usize| {
                let robust = lower_median(parts, i, c)
                    .max(lower_median(&smoothed, i, c))
                    .max(lower_median(&medians, i, c))
                    .max(independent.as_ref().map_or(0.0, |s| s[i][c]));
                mean[i][c].min(robust)
            };
            let r = DVec3::new(channel(0), channel(1), channel(2));
            r * r
        })
        .collect()
}

/// Per channel, the median over each pixel's 3 x 3 neighbourhood (clipped at the borders;
/// the lower median of an even count).
fn median_filter_3x3(image: &[DVec3], width: usize, height: usize) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; image.len()];
    out.par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            let mut values: Vec<f64> = Vec::with_capacity(9);
            for (x, m) in row.iter_mut().enumerate() {
                if x > 0 && y > 0 && x + 1 < width && y + 1 < height {
                    let mut p = [DVec3::ZERO; 9];
                    for (k, v) in p.iter_mut().enumerate() {
                        *v = image[(y + k / 3 - 1) * width + x + k % 3 - 1];
                    }
                    *m = median_of_9(p);
                    continue;
                }
                for c in 0..3 {
                    values.clear();
                    for yy in y.saturating_sub(1)..(y + 2).min(height) {
                        for xx in x.saturating_sub(1)..(x + 2).min(width) {
                            values.push(image[yy * width + xx][c]);
                        }
                    }
                    let rank = (values.len() - 1) / 2;
                    m[c] = *values.select_nth_unstable_by(rank, f64::total_cmp).1;
                }
            }
        });
    out
}

/// Per channel, the median of nine values: the 19 compare-exchanges of Paeth's network
/// (Devillard 1998, "Fast median search", `opt_med9`), on all three channels at once.
fn median_of_9(mut p: [DVec3; 9]) -> DVec3 {
    let mut sort = |a: usize, b: usize| {
        let (lo, hi) = (p[a].min(p[b]), p[a].max(p[b]));
        p[a] = lo;
        p[b] = hi;
    };
    for (a, b) in [
        (1, 2),
        (4, 5),
        (7, 8),
        (0, 1),
        (3, 4),
        (6, 7),
        (1, 2),
        (4, 5),
        (7, 8),
        (0, 3),
        (5, 8),
        (4, 7),
        (3, 6),
        (1, 4),
        (2, 5),
        (4, 7),
        (4, 2),
        (6, 4),
        (4, 2),
    ] {
        sort(a, b);
    }
    p[4]
}

/// The mean over each pixel's 3 x 3 neighbourhood (clipped at the borders).
pub fn box_filter_3x3(image: &[DVec3], width: usize, height: usize) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; image.len()];
    out.par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, o) in row.iter_mut().enumerate() {
                let (mut sum, mut n) = (DVec3::ZERO, 0.0);
                for yy in y.saturating_sub(1)..(y + 2).min(height) {
                    for xx in x.saturating_sub(1)..(x + 2).min(width) {
                        sum += image[yy * width + xx];
                        n += 1.0;
                    }
                }
                *o = sum / n;
            }
        });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sum_follows_the_definition() {
        let pixels = [
            PixelError {
                variance: DVec3::splat(0.02),
                bias_sq: DVec3::ZERO,
                reference_sq: DVec3::splat(0.99),
            },
            PixelError {
                variance: DVec3::ZERO,
                bias_sq: DVec3::new(0.03, 0.0, 0.0),
                reference_sq: DVec3::ZERO,
            },
        ];
        let e = ErrorEstimate::from_pixels(2, 1, &pixels).unwrap();
        let expected = (0.02 / 1.0 + 0.03 / 0.01 / 3.0) / 2.0;
        assert!((e.rel_mse - expected).abs() < 1e-12, "{}", e.rel_mse);
        assert!((e.bias_rel_mse - 0.5).abs() < 1e-12);
        assert!((e.per_pixel[1] - 1.0).abs() < 1e-6);
        assert_eq!(ErrorEstimate::from_pixels(0, 0, &[]), None);
        let nan = [PixelError {
            variance: DVec3::splat(f64::NAN),
            ..Default::default()
        }];
        assert_eq!(ErrorEstimate::from_pixels(1, 1, &nan), None);
    }

    #[test]
    fn the_variance_of_the_mean_is_unbiased() {
        // Values 1, 2, 3, 4: sample variance 5/3, of the mean 5/12.
        let (sum, sum_sq) = (DVec3::splat(10.0), DVec3::splat(30.0));
        let v = variance_of_mean(sum, sum_sq, 4);
        assert!((v.x - 5.0 / 12.0).abs() < 1e-12);
        assert_eq!(variance_of_mean(sum, sum_sq, 1), DVec3::ZERO);
    }

    #[test]
    fn merging_divides_the_variance_and_keeps_the_bias() {
        let e = ErrorEstimate::merged_rel_mse(&[(1.0, 0.4, 0.1), (1.0, 0.4, 0.1)]).unwrap();
        assert!((e - (0.15 + 0.1)).abs() < 1e-12);
        assert_eq!(ErrorEstimate::merged_rel_mse(&[]), None);
    }

    #[test]
    fn the_median_network_agrees_with_sorting() {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as f64 / (1u64 << 31) as f64
        };
        for _ in 0..2000 {
            let p: [DVec3; 9] =
                std::array::from_fn(|_| DVec3::new(next(), next(), (next() * 4.0).floor()));
            let m = median_of_9(p);
            for c in 0..3 {
                let mut v: Vec<f64> = p.iter().map(|x| x[c]).collect();
                v.sort_by(f64::total_cmp);
                assert_eq!(m[c], v[4]);
            }
        }
    }

    #[test]
    fn the_robust_reference_resists_outliers_sparse_parts_and_edges() {
        let flat = |v: f64| vec![DVec3::splat(v); 9];
        // A 3 x 3 image of 0.5 with a firefly in the middle of one half.
        let mut a = flat(0.5);
        a[4] = DVec3::splat(90.0);
        let r = robust_reference_sq(&[a, flat(0.5)], None, 3, 3);
        assert!((r[4].x - 0.25).abs() < 1e-9, "{}", r[4]);
        // Four groups, one far off at the centre of a flat neighbourhood of 2: the lower median.
        let parts: Vec<Vec<DVec3>> = [1.0, 40.0, 2.0, 3.0]
            .iter()
            .map(|v| {
                let mut part = flat(2.0);
                part[4] = DVec3::splat(*v);
                part
            })
            .collect();
        assert!((robust_reference_sq(&parts, None, 3, 3)[4].x - 4.0).abs() < 1e-9);
        // A chain lingering over a whole 3 x 3 patch of one group of four: its neighbourhood
        // median is the patch, the other groups' are not.
        let parts: Vec<Vec<DVec3>> = [50.0, 1.0, 1.0, 1.0].iter().map(|v| flat(*v)).collect();
        assert!((robust_reference_sq(&parts, None, 3, 3)[4].x - 1.0).abs() < 1e-9);
        // Sparse parts with samples at alternate pixels: each part's own value is 0 at half the
        // pixels, but the neighbourhoods stand in (about the centre, one part holds five
        // samples of 1.8, mean 1, the other four, mean 0.8; the parts' medians are 1.8 and 0,
        // so r is the lower mean, 0.8, where every x is 0.9).
        let sparse = |offset: usize| -> Vec<DVec3> {
            (0..9)
                .map(|i| {
                    DVec3::splat(if (i + offset).is_multiple_of(2) {
                        1.8
                    } else {
                        0.0
                    })
                })
                .collect()
        };
        let r = robust_reference_sq(&[sparse(0), sparse(1)], None, 3, 3);
        assert!((r[4].x - 0.64).abs() < 1e-9, "{}", r[4]);
        // A dark column beside a bright one: the dark pixels keep their own value.
        let edge: Vec<DVec3> = (0..9)
            .map(|i| DVec3::splat(if i % 3 == 2 { 100.0 } else { 0.1 }))
            .collect();
        let r = robust_reference_sq(&[edge.clone(), edge], None, 3, 3);
        assert!((r[4].x - 0.01).abs() < 1e-9, "{}", r[4]);
    }
}
