//! How the connection stream's first number picks the path length k and the technique (s, t)
//! among those of a slot (Hachisuka et al. 2014, section 4: a discrete dimension of primary
//! sample space). The contribution is divided by the probability of the pick, so the
//! expectation over the first number is the sum over techniques of the MIS-weighted
//! contributions, the full contribution of every length in the slot (their eq. 7), whatever
//! the probabilities, as long as none that carries light is zero.
//!
//! Within a length, techniques are equally likely (n = k + 2 of them, as in the paper).
//! Across the lengths of the shared slot (`path_sample::slot_lengths`), a length is a factor
//! `LENGTH_DECAY` less likely than the one before it, mixed with the choice that makes every
//! technique equally likely (`DEFENSIVE_SHARE`), so that no length is left unsampled. The
//! bootstrap and the chains pick alike, so a bootstrap sample is a valid chain state as it is.
//!
//! Why not every technique equally likely: at a maximum depth of 64 that gives the lengths from
//! 40 on most of the large steps and the bootstrap's samples, though they carry next to
//! nothing, and weighs the rare bright long paths by the technique count, about 2000:
//! fireflies, and chains seeded from the two or three bright samples the bootstrap found
//! (measured: relMSE 1.1 on the caustic pool at 20 s against 0.11 at depth 10). Why not in
//! proportion to the light the bootstrap found per length: with 10^5 samples over 2000
//! techniques it found light at two long lengths of the pool and none at the others, and the
//! proportional choice was no better (0.42). Light falls off with path length about
//! geometrically (each bounce keeps a surface's albedo at most); 0.6 and 0.8 measured alike.
//!
//! The choice does not change where a chain spends its steps: its target is the pick's
//! contribution over the pick's probability, and the pick's share of primary sample space is
//! that probability, so the stationary share of technique (k, s) is its share of the light
//! under any choice. It changes the large steps' proposals, and so how often a chain finds
//! each length.

use crate::sampling::distribution::Distribution1D;
use std::ops::RangeInclusive;

/// The share of the length choice that makes every technique equally likely, so that no
/// length's weight exceeds five times what it would be under that choice (a defensive
/// mixture; Hesterberg 1995).
pub const DEFENSIVE_SHARE: f64 = 0.2;

/// How much less likely each length of the shared slot is than the one before it.
pub const LENGTH_DECAY: f64 = 0.75;

/// Number of techniques for path length `k`.
pub fn technique_count(k: usize) -> usize {
    if k == 0 { 1 } else { k + 2 }
}

/// A probability for each length of a slot; techniques within a length equally likely.
#[derive(Clone, Debug)]
pub struct TechniqueChoice {
    first: usize,
    lengths: Distribution1D,
    techniques: usize,
}

/// One pick: the technique and the factor that divides out its probability.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pick {
    pub k: usize,
    pub s: usize,
    pub weight: f32,
}

impl TechniqueChoice {
    /// Bytes of the path-length distribution (the struct itself apart).
    pub fn heap_bytes(&self) -> usize {
        self.lengths.memory_bytes()
    }

    /// Every technique of every length in `lengths` equally likely.
    pub fn uniform(lengths: RangeInclusive<usize>) -> Self {
        let counts: Vec<f64> = lengths.clone().map(|k| technique_count(k) as f64).collect();
        TechniqueChoice {
            first: *lengths.start(),
            techniques: counts.iter().sum::<f64>() as usize,
            lengths: Distribution1D::new(&counts),
        }
    }

    /// Lengths in proportion to `light` (one weight per length of `lengths`, in order), mixed
    /// with the uniform choice by `DEFENSIVE_SHARE`.
    pub fn in_proportion(lengths: RangeInclusive<usize>, light: &[f64]) -> Self {
        let uniform = Self::uniform(lengths);
        let total: f64 = light.iter().filter(|l| l.is_finite() && **l > 0.0).sum();
        if !(total > 0.0) || light.len() != uniform.lengths.len() {
            return uniform;
        }
        let weights: Vec<f64> = light
            .iter()
            .enumerate()
            .map(|(j, l)| {
                let l = if l.is_finite() { l.max(0.0) } else { 0.0 };
                (1.0 - DEFENSIVE_SHARE) * l / total
                    + DEFENSIVE_SHARE * uniform.lengths.pmf(j) as f64
            })
            .collect();
        TechniqueChoice {
            lengths: Distribution1D::new(&weights),
            ..uniform
        }
    }

    /// The choice of the slot over `lengths` (module docs): each length `LENGTH_DECAY` times
    /// as likely as the one before, mixed with the uniform choice.
    pub fn for_slot(lengths: RangeInclusive<usize>) -> Self {
        let light: Vec<f64> = (0..lengths.clone().count())
            .map(|j| LENGTH_DECAY.powi(j as i32))
            .collect();
        Self::in_proportion(lengths, &light)
    }

    /// Whether there is anything to choose (else the first number is not read).
    pub fn is_choice(&self) -> bool {
        self.techniques > 1
    }

    /// The technique for a uniform number `u`.
    pub fn pick(&self, u: f32) -> Pick {
        let Some((j, p, within)) = self.lengths.sample_remapped(u) else {
            return Pick {
                k: self.first,
                s: 0,
                weight: 1.0,
            };
        };
        let k = self.first + j;
        let n = technique_count(k);
        Pick {
            k,
            s: ((within * n as f32) as usize).min(n - 1),
            weight: n as f32 / p,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_choice_weighs_every_technique_by_their_number() {
        let c = TechniqueChoice::uniform(10..=12);
        let n = (12 + 13 + 14) as f32;
        let mut seen = vec![0usize; 3 * 14];
        let m = 39 * 100;
        for i in 0..m {
            let p = c.pick((i as f32 + 0.5) / m as f32);
            assert!((p.weight - n).abs() < 1e-3 * n, "{p:?}");
            seen[(p.k - 10) * 14 + p.s] += 1;
        }
        // 100 numbers land in each of the 39 techniques.
        assert!(
            seen.iter().all(|&c| c == 0 || c.abs_diff(100) <= 1),
            "{seen:?}"
        );
        assert_eq!(seen.iter().filter(|&&c| c > 0).count(), 39);
    }

    /// The estimator's expectation does not depend on the choice: the mean of weight times a
    /// per-technique value over uniform numbers is the sum of the values.
    #[test]
    fn proportional_choice_keeps_the_sum_and_favours_bright_lengths() {
        let c = TechniqueChoice::in_proportion(10..=13, &[1.0, 0.0, 3.0, 0.0]);
        let value = |k: usize, s: usize| (k * 7 + s) as f64;
        let exact: f64 = (10..=13)
            .flat_map(|k| (0..technique_count(k)).map(move |s| value(k, s)))
            .sum();
        let m = 200_000;
        let mut mean = 0.0;
        let mut bright = 0;
        for i in 0..m {
            let p = c.pick((i as f32 + 0.5) / m as f32);
            mean += p.weight as f64 * value(p.k, p.s) / m as f64;
            bright += usize::from(p.k == 12);
        }
        assert!((mean / exact - 1.0).abs() < 1e-3, "{mean} against {exact}");
        // 0.8 x 3/4 + 0.2 x 14/54
        let expected = 0.8 * 0.75 + 0.2 * 14.0 / 54.0;
        assert!((bright as f64 / m as f64 - expected).abs() < 1e-3);
    }

    #[test]
    fn the_shared_slot_favours_short_lengths_and_bounds_every_weight() {
        let c = TechniqueChoice::for_slot(10..=64);
        let uniform = TechniqueChoice::uniform(10..=64);
        let m = 100_000;
        let picks: Vec<Pick> = (0..m)
            .map(|i| c.pick((i as f32 + 0.5) / m as f32))
            .collect();
        let short = picks.iter().filter(|p| p.k <= 13).count() as f64 / m as f64;
        // 0.8 (1 - 0.75^4) of the geometric part, and a little of the uniform one.
        assert!(short > 0.8 * (1.0 - 0.75f64.powi(4)), "{short}");
        let bound = uniform.pick(0.5).weight / DEFENSIVE_SHARE as f32;
        assert!(picks.iter().all(|p| p.weight <= bound * 1.0001), "{bound}");
    }
}
