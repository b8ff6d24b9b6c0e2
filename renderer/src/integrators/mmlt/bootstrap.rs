//! Bootstrap (Hachisuka et al. 2014, section 4.3; pbrt-v3 section 16.4.4): independent
//! samples of every path length estimate the normalisation b = sum over k of b_k, the mean
//! target value, and chains start from bootstrap samples drawn in proportion to their
//! luminance, so they spread over path lengths as the image's energy does.

use crate::camera::PerspectiveCamera;
use crate::integrators::Cancelled;
use crate::integrators::mmlt::path_sample::{Subpaths, evaluate};
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
    /// Standard error of b from the samples' spread.
    pub standard_error: f64,
    /// Chooses a bootstrap sample (index i (max_depth + 1) + k) by luminance; None if every
    /// sample was black.
    pub seeds: Option<Distribution1D>,
    pub rays: u64,
    pub dropped: u64,
}

/// Key of bootstrap sample `i` of path length `k`: the PSS state it was drawn from.
pub fn bootstrap_key(i: usize, k: usize, max_depth: usize) -> u64 {
    (i * (max_depth + 1) + k) as u64
}

pub fn run(
    scene: &Scene,
    camera: &PerspectiveCamera,
    seed: u64,
    samples: usize,
    max_depth: usize,
    cancel: &AtomicBool,
) -> Result<Bootstrap, Cancelled> {
    let lengths = max_depth + 1;
    let results: Vec<(f64, u64, bool)> = (0..samples * lengths)
        .into_par_iter()
        .map_init(Subpaths::default, |scratch, key| {
            if key % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let (i, k) = (key / lengths, key % lengths);
            let mut sampler = PssSampler::new(seed, bootstrap_key(i, k, max_depth), 0.0, 1.0);
            let mut rays = 0;
            let sample = evaluate(scene, camera, &mut sampler, k, scratch, &mut rays);
            Ok((sample.luminance() as f64, rays, !sample.is_valid()))
        })
        .collect::<Result<_, _>>()?;
    let mut per_length = vec![0.0; lengths];
    // Sample i of every length together is one sample of the sum over lengths.
    let mut sum_sq = 0.0;
    for (key, (y, _, _)) in results.iter().enumerate() {
        per_length[key % lengths] += y / samples as f64;
    }
    for i in 0..samples {
        let y: f64 = results[i * lengths..(i + 1) * lengths]
            .iter()
            .map(|r| r.0)
            .sum();
        sum_sq += y * y;
    }
    let weights: Vec<f64> = results.iter().map(|r| r.0).collect();
    let b = per_length.iter().sum::<f64>();
    let n = samples as f64;
    let variance = (sum_sq / n - b * b).max(0.0) * n / (n - 1.0).max(1.0);
    Ok(Bootstrap {
        b,
        per_length,
        standard_error: (variance / n).sqrt(),
        seeds: (b > 0.0).then(|| Distribution1D::new(&weights)),
        rays: results.iter().map(|r| r.1).sum(),
        dropped: results.iter().filter(|r| r.2).count() as u64,
    })
}
