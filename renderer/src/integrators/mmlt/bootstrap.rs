//! Bootstrap (Hachisuka et al. 2014, section 4.3; pbrt-v3 section 16.4.4): independent
//! samples of every path length estimate the normalisation b = sum over k of b_k, the mean
//! target value, and chains start from bootstrap samples drawn in proportion to their
//! luminance, so they spread over path lengths as the image's energy does (`seeding`).

use crate::camera::Camera;
use crate::integrators::Cancelled;
use crate::integrators::mmlt::FIRST_CHAIN_LENGTH;
use crate::integrators::mmlt::path_sample::{Subpaths, evaluate, slot_count, slot_lengths};
use crate::integrators::mmlt::technique_choice::TechniqueChoice;
use crate::sampling::distribution::Distribution1D;
use crate::sampling::pss::PssSampler;
use crate::scene::Scene;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

pub struct Bootstrap {
    /// b: the mean over primary sample space of the target summed over path lengths.
    pub b: f64,
    /// b_k per path length.
    pub per_length: Vec<f64>,
    /// The mean of the squared target values per path length (for b_k's standard error).
    pub per_length_mean_sq: Vec<f64>,
    /// Standard error of b from the samples' spread.
    pub standard_error: f64,
    /// The samples of each path length with light.
    pub lit_per_length: Vec<u64>,
    /// The target value (luminance) of every sample, at index i (max_depth + 1) + k.
    pub luminance: Vec<f64>,
    pub rays: u64,
    pub dropped: u64,
}

/// Key of bootstrap sample `i` of path length `k`: the PSS state it was drawn from.
pub fn bootstrap_key(i: usize, k: usize, max_depth: usize) -> u64 {
    (i * (max_depth + 1) + k) as u64
}

/// One bootstrap evaluation: its path length and target value, the rays it traced, whether
/// its contribution was invalid (dropped), and its contribution and film position, which the
/// image shown while the bootstrap runs sums (`Mmlt::image`).
pub struct Evaluation {
    pub k: usize,
    pub luminance: f64,
    pub rays: u64,
    pub invalid: bool,
    pub l: glam::Vec3,
    pub raster: glam::Vec2,
}

/// Evaluates bootstrap samples `samples` (every path length of each), in key order.
pub fn evaluate_samples(
    scene: &Scene,
    camera: &Camera,
    seed: u64,
    samples: std::ops::Range<usize>,
    max_depth: usize,
    cancel: &AtomicBool,
) -> Result<Vec<Evaluation>, Cancelled> {
    let slots = slot_count(max_depth);
    let choices: Vec<TechniqueChoice> = (0..slots)
        .map(|slot| TechniqueChoice::for_slot(slot_lengths(slot, max_depth)))
        .collect();
    (samples.start * slots..samples.end * slots)
        .into_par_iter()
        .map_init(Subpaths::default, |scratch, key| {
            if key % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let (i, slot) = (key / slots, key % slots);
            if slot < FIRST_CHAIN_LENGTH {
                // Path traced apart (module `mmlt`): no chain samples these lengths.
                return Ok(Evaluation {
                    k: slot,
                    luminance: 0.0,
                    rays: 0,
                    invalid: false,
                    l: glam::Vec3::ZERO,
                    raster: glam::Vec2::ZERO,
                });
            }
            let mut sampler = PssSampler::new(seed, bootstrap_key(i, slot, max_depth), 0.0, 1.0);
            let mut rays = 0;
            let sample = evaluate(
                scene,
                camera,
                &mut sampler,
                &choices[slot],
                scratch,
                &mut rays,
            );
            Ok(Evaluation {
                k: sample.k,
                luminance: sample.luminance() as f64,
                rays,
                invalid: !sample.is_valid(),
                l: if sample.is_valid() {
                    sample.l
                } else {
                    glam::Vec3::ZERO
                },
                raster: sample.raster,
            })
        })
        .collect()
}

impl Bootstrap {
    /// The bootstrap's statistics from the target value of every sample of every length (at
    /// index i (max_depth + 1) + k), with the rays traced and the samples dropped.
    pub fn from_luminance(luminance: Vec<f64>, lengths: usize, rays: u64, dropped: u64) -> Self {
        let samples = luminance.len() / lengths.max(1);
        let mut per_length = vec![0.0; lengths];
        let mut per_length_mean_sq = vec![0.0; lengths];
        let mut lit_per_length = vec![0; lengths];
        for (key, y) in luminance.iter().enumerate() {
            per_length[key % lengths] += y / samples as f64;
            per_length_mean_sq[key % lengths] += y * y / samples as f64;
            lit_per_length[key % lengths] += u64::from(*y > 0.0);
        }
        // Sample i of every length together is one sample of the sum over lengths.
        let sum_sq: f64 = luminance
            .chunks(lengths.max(1))
            .map(|ys| ys.iter().sum::<f64>().powi(2))
            .sum();
        let b = per_length.iter().sum::<f64>();
        let n = samples as f64;
        let variance = (sum_sq / n - b * b).max(0.0) * n / (n - 1.0).max(1.0);
        Bootstrap {
            b,
            per_length,
            per_length_mean_sq,
            standard_error: (variance / n).sqrt(),
            lit_per_length,
            luminance,
            rays,
            dropped,
        }
    }

    /// Per path length, the effective number of distinct paths chains start from (Kish's
    /// effective sample size of the luminance weights, (sum y)^2 / sum y^2): chains start in
    /// proportion to luminance, so where a few bright samples carry the light most chains
    /// start on the same few paths and, accepting few large steps, stay near them (on the
    /// caustic pool: 87 lit samples of 10^5 at 5 bounces, 10 of them 97 % of the light).
    pub fn effective_samples(&self) -> Vec<f64> {
        let n = (self.luminance.len() / self.per_length.len().max(1)) as f64;
        self.per_length
            .iter()
            .zip(&self.per_length_mean_sq)
            .map(|(m, sq)| if *sq > 0.0 { n * m * m / sq } else { 0.0 })
            .collect()
    }
}

/// Bootstrap samples evaluated in the preparation step after `done` of them: few at first,
/// so the first image comes at once, then twice as many each step, up to 8192.
pub fn next_chunk(done: usize, total: usize) -> std::ops::Range<usize> {
    let size = done.clamp(256, 8192);
    done..(done + size).min(total)
}

/// Where chains start: first a path length for each chain, drawn in proportion to luminance
/// over all bootstrap samples (so chains spread over lengths as the image's energy does; the
/// caller first gives every group one chain of each lit length, `Mmlt::start`);
/// then, per group of chains (module `mmlt`), a bootstrap sample of that length from the
/// group's own disjoint share of the samples (i = g, g + G, g + 2G, ...), again in proportion
/// to luminance. The first step is shared, so every group gets the same number of chains of
/// each length (to one); the second is not, so groups start independently, which the error
/// estimate needs: chains of different groups seeded from the same few bright paths (a hard
/// scene, a small bootstrap) would agree with each other more than with the truth.
pub struct Seeding {
    lengths: usize,
    groups: usize,
    all: Distribution1D,
    /// Per group g and length k (index g lengths + k): over the group's samples of length k,
    /// None if they are all black.
    shares: Vec<Option<Distribution1D>>,
    /// Per length: over all samples of that length.
    per_length: Vec<Distribution1D>,
}

impl Seeding {
    pub fn new(luminance: &[f64], lengths: usize, groups: usize) -> Self {
        let groups = groups.max(1);
        let samples = luminance.len() / lengths.max(1);
        let lit = |w: &[f64]| w.iter().any(|&y| y.is_finite() && y > 0.0);
        let shares = (0..groups * lengths)
            .map(|index| {
                let (g, k) = (index / lengths, index % lengths);
                let weights: Vec<f64> = (g..samples)
                    .step_by(groups)
                    .map(|i| luminance[i * lengths + k])
                    .collect();
                lit(&weights).then(|| Distribution1D::new(&weights))
            })
            .collect();
        let per_length = (0..lengths)
            .map(|k| {
                let weights: Vec<f64> = (0..samples).map(|i| luminance[i * lengths + k]).collect();
                Distribution1D::new(&weights)
            })
            .collect();
        Seeding {
            lengths,
            groups,
            all: Distribution1D::new(luminance),
            shares,
            per_length,
        }
    }

    /// A path length for a uniform number `u`.
    pub fn length(&self, u: f32) -> usize {
        self.all.sample(u).map_or(0, |(key, _)| key % self.lengths)
    }

    /// The bootstrap sample i of length k that a chain of group g starts from, for a uniform
    /// number `u`. A share with no light at that length (rare lengths, small bootstraps)
    /// falls back to a draw over all samples of the length, shared with the other groups.
    pub fn start(&self, group: usize, k: usize, u: f32) -> usize {
        match &self.shares[group * self.lengths + k] {
            Some(share) => share
                .sample(u)
                .map_or(group, |(j, _)| j * self.groups + group),
            None => self.per_length[k].sample(u).map_or(group, |(i, _)| i),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Equal lit values are as many distinct starts as there are; one value carrying all but
    /// a little of the light is about one, whatever the count of dim ones; a black length none.
    #[test]
    fn effective_starts_count_distinct_light_not_lit_samples() {
        let samples = 100;
        // Length 0: 40 lit samples of equal value; length 1: one of 1000 and 99 of 0.01;
        // length 2: black. Index i lengths + k.
        let luminance: Vec<f64> = (0..samples)
            .flat_map(|i| {
                let even = if i < 40 { 2.0 } else { 0.0 };
                let skewed = if i == 7 { 1000.0 } else { 0.01 };
                [even, skewed, 0.0]
            })
            .collect();
        let boot = Bootstrap::from_luminance(luminance, 3, 0, 0);
        assert_eq!(boot.lit_per_length, vec![40, 100, 0]);
        let ess = boot.effective_samples();
        assert!((ess[0] - 40.0).abs() < 1e-9, "{ess:?}");
        // (1000 + 0.99)^2 / (1000^2 + 99 x 10^-4) = 1.00198...
        assert!((ess[1] - 1.00198).abs() < 1e-4, "{ess:?}");
        assert_eq!(ess[2], 0.0);
    }
}
