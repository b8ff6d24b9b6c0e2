//! MMLT's remaining error without a reference (the framework: `error_estimate.rs`).
//!
//! The passes of a chain are correlated (a chain lingers), so their spread says nothing of the
//! error. The chains are dealt into `CHAIN_GROUPS` groups, each seeded from its own share of
//! the bootstrap samples with the same mix of path lengths (`bootstrap::Seeding`), so the
//! groups' estimates are independent and identically distributed, and their sample variance
//! over G is the variance of their mean, the image, whatever the correlation along each chain
//! (batch means over independent chains rather than over time, which would need batches
//! longer than the chains' memory; DESIGN.md section 5 says what else was tried). What the
//! groups share, the normalisation b, adds its own relative variance times x^2: the
//! bootstrap's and large steps' spread of target values per length over their count. The
//! direct part adds its own variance (its passes are independent). The denominator r^2 comes
//! from the groups' estimates and, for pixels only one group has found, from the image of the
//! large-step proposals alone (`error_estimate::robust_reference_sq`): a large step ignores
//! the chain's state, so those proposals are independent uniform samples of each length, as
//! the bootstrap's, and each pass's, weighted by pixels over the expected number of large
//! steps of its length, is an unbiased image.

use super::{Mmlt, Phase};
use crate::error_estimate::{self, ErrorEstimate, PixelError};
use glam::DVec3;
use rayon::prelude::*;

impl Mmlt {
    pub(super) fn estimate_error(&self) -> Option<ErrorEstimate> {
        if matches!(self.phase, Phase::Black) {
            return self.direct.error_estimate();
        }
        let scale = self.group_scale()?;
        let Phase::Running {
            groups,
            b_sum,
            b_sum_sq,
            b_count,
            ..
        } = &self.phase
        else {
            return None;
        };
        let groups = *groups;
        if groups < 2 {
            return None;
        }
        // Relative variance of b = sum of b_k: each b_k's sample variance over its count.
        let (mut b, mut b_variance) = (0.0, 0.0);
        for k in 0..b_sum.len() {
            let n = b_count[k].max(1) as f64;
            let mean = b_sum[k] / n;
            b += mean;
            b_variance += (b_sum_sq[k] / n - mean * mean).max(0.0) / (n - 1.0).max(1.0);
        }
        let b_relative_variance = if b > 0.0 { b_variance / (b * b) } else { 0.0 };
        let g = groups as f64;
        let (w, h) = (
            self.ctx.camera.width as usize,
            self.ctx.camera.height as usize,
        );
        // Each group's estimate of the whole image: its chains' part plus the direct part,
        // which all groups share (it adds its own variance below, not to the spread).
        let direct: Vec<DVec3> = (0..w * h).map(|i| self.direct.mean(i)).collect();
        let plus_direct = |part: &[DVec3], scale: f64| -> Vec<DVec3> {
            part.par_iter()
                .zip(&direct)
                .map(|(v, d)| *v * scale + *d)
                .collect()
        };
        let estimates: Vec<Vec<DVec3>> = self.group_splats[..groups]
            .iter()
            .map(|splats| plus_direct(splats, scale))
            .collect();
        let large_steps = (self.large_step_passes > 0)
            .then(|| plus_direct(&self.large_step_image, 1.0 / self.large_step_passes as f64));
        let reference_sq =
            error_estimate::robust_reference_sq(&estimates, large_steps.as_deref(), w, h);
        let pixels: Vec<PixelError> = (0..w * h)
            .into_par_iter()
            .map(|i| {
                let mean = estimates.iter().map(|e| e[i]).sum::<DVec3>() / g;
                let spread: DVec3 = estimates
                    .iter()
                    .map(|e| (e[i] - mean) * (e[i] - mean))
                    .sum();
                let chains = mean - direct[i];
                PixelError {
                    variance: spread / (g * (g - 1.0))
                        + chains * chains * b_relative_variance
                        + self.direct.variance_of_mean(i),
                    bias_sq: DVec3::ZERO,
                    reference_sq: reference_sq[i],
                }
            })
            .collect();
        ErrorEstimate::from_pixels(
            self.ctx.camera.width as usize,
            self.ctx.camera.height as usize,
            &pixels,
        )
    }
}
