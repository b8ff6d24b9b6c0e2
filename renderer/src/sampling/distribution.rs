//! Piecewise-constant discrete distribution, used to choose lights in proportion to power.

use crate::sampling::sampler::ONE_MINUS_EPSILON;

/// Discrete distribution over `weights.len()` items. Negative or non-finite weights count as
/// zero; if every weight is zero, the distribution is uniform so that sampling stays defined.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    pmf: Vec<f32>,
}

impl Distribution1D {
    /// Bytes of its tables.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.cdf.as_slice()) + std::mem::size_of_val(self.pmf.as_slice())
    }

    pub fn new(weights: &[f64]) -> Self {
        let clean: Vec<f64> = weights
            .iter()
            .map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 })
            .collect();
        let total: f64 = clean.iter().sum();
        let n = clean.len();
        let probs: Vec<f64> = if total > 0.0 {
            clean.iter().map(|w| w / total).collect()
        } else {
            vec![1.0 / n.max(1) as f64; n]
        };
        let mut cdf = Vec::with_capacity(n + 1);
        let mut acc = 0.0;
        cdf.push(0.0);
        for p in &probs {
            acc += p;
            cdf.push(acc);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Distribution1D {
            cdf,
            pmf: probs.iter().map(|&p| p as f32).collect(),
        }
    }

    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Picks an item for `u` in [0,1): its index and probability. None when empty.
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.pmf.is_empty() {
            return None;
        }
        let u = u as f64;
        // First index i with cdf[i+1] > u, skipping zero-probability items.
        let mut i = self.cdf.partition_point(|&c| c <= u).saturating_sub(1);
        i = i.min(self.pmf.len() - 1);
        while self.pmf[i] == 0.0 && i + 1 < self.pmf.len() {
            i += 1;
        }
        while self.pmf[i] == 0.0 && i > 0 {
            i -= 1;
        }
        Some((i, self.pmf[i]))
    }

    /// As `sample`, with `u`'s position within the item's interval of the CDF as a new
    /// uniform number in [0, 1) (pbrt-v4's `SampleDiscrete` and its `uRemapped`), so one
    /// number can make a second choice within the item.
    pub fn sample_remapped(&self, u: f32) -> Option<(usize, f32, f32)> {
        let (i, p) = self.sample(u)?;
        let (start, width) = (self.cdf[i], self.cdf[i + 1] - self.cdf[i]);
        let remapped = ((u as f64 - start) / width).clamp(0.0, 1.0) as f32;
        Some((i, p, remapped.min(ONE_MINUS_EPSILON)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_in_proportion_to_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        let mut counts = [0usize; 3];
        let n = 100_000;
        for k in 0..n {
            let (i, p) = d.sample((k as f32 + 0.5) / n as f32).unwrap();
            assert_eq!(p, d.pmf(i));
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        assert!((counts[0] as f64 / n as f64 - 0.25).abs() < 1e-3);
        assert!((d.pmf(2) - 0.75).abs() < 1e-6);
    }

    #[test]
    fn all_zero_weights_fall_back_to_uniform() {
        let d = Distribution1D::new(&[0.0, f64::NAN, -1.0]);
        assert!((d.pmf(1) - 1.0 / 3.0).abs() < 1e-6);
        assert!(Distribution1D::new(&[]).sample(0.3).is_none());
    }

    #[test]
    fn remapped_numbers_are_uniform_within_the_item() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        let (i, p, r) = d.sample_remapped(0.125).unwrap();
        assert_eq!((i, p), (0, 0.25));
        assert!((r - 0.5).abs() < 1e-6);
        let (i, _, r) = d.sample_remapped(0.625).unwrap();
        assert_eq!(i, 2);
        assert!((r - 0.5).abs() < 1e-6);
    }
}
