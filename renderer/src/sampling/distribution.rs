//! Piecewise-constant distributions: discrete (lights chosen in proportion to power) and over
//! the unit square (an environment map's texels in proportion to their radiance).

use crate::sampling::sampler::ONE_MINUS_EPSILON;

/// Discrete distribution over `weights.len()` items. Negative or non-finite weights count as
/// zero; if every weight is zero, the distribution is uniform so that sampling stays defined.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f64>,
    pmf: Vec<f32>,
    /// A guide table (Chen and Asau's, in Devroye 1986, section III.2.4): `guide[j]` is the
    /// item whose interval of the CDF holds j / n, so inversion starts there and scans on,
    /// one or two steps on average (at most one item starts in each of n equal slices of
    /// [0, 1) on average), where a binary search over a large table misses the cache at
    /// every step. The result is the binary search's.
    guide: Vec<u32>,
}

impl Distribution1D {
    /// Bytes of its tables.
    pub fn memory_bytes(&self) -> usize {
        std::mem::size_of_val(self.cdf.as_slice())
            + std::mem::size_of_val(self.pmf.as_slice())
            + std::mem::size_of_val(self.guide.as_slice())
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
        let mut guide = Vec::with_capacity(n);
        let mut i = 0;
        for j in 0..n {
            let start = j as f64 / n as f64;
            while i + 1 < n && cdf[i + 1] <= start {
                i += 1;
            }
            guide.push(i as u32);
        }
        Distribution1D {
            cdf,
            pmf: probs.iter().map(|&p| p as f32).collect(),
            guide,
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
        let n = self.pmf.len();
        // The index i with cdf[i] <= u < cdf[i+1], from the guide on, skipping
        // zero-probability items.
        let slice = ((u * n as f64) as usize).min(n - 1);
        let mut i = self.guide[slice] as usize;
        while i + 1 < n && self.cdf[i + 1] <= u {
            i += 1;
        }
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

/// Piecewise-constant density over [0,1)^2 on an `nu` x `nv` grid of cells, sampled by
/// inversion: a row from the marginal, then a column from that row's conditional
/// distribution (pbrt-v4's `PiecewiseConstant2D`, section A.5.3).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    nu: usize,
    nv: usize,
    /// One distribution per row, over its `nu` cells.
    conditional: Vec<Distribution1D>,
    /// Over the rows, in proportion to their sums.
    marginal: Distribution1D,
}

impl Distribution2D {
    /// `weights` holds `nv` rows of `nu` cells each, row after row; negative or non-finite
    /// weights count as zero. All zero gives the uniform density.
    pub fn new(weights: &[f64], nu: usize, nv: usize) -> Self {
        assert!(nu > 0 && nv > 0 && weights.len() == nu * nv);
        let conditional: Vec<Distribution1D> =
            weights.chunks(nu).map(Distribution1D::new).collect();
        let row_sums: Vec<f64> = weights
            .chunks(nu)
            .map(|row| row.iter().filter(|w| w.is_finite() && **w > 0.0).sum())
            .collect();
        Distribution2D {
            nu,
            nv,
            conditional,
            marginal: Distribution1D::new(&row_sums),
        }
    }

    pub fn memory_bytes(&self) -> usize {
        self.marginal.memory_bytes()
            + self
                .conditional
                .iter()
                .map(Distribution1D::memory_bytes)
                .sum::<usize>()
    }

    /// A point of [0,1)^2 for `u`, with its density (with respect to area on the square).
    pub fn sample(&self, u: glam::Vec2) -> (glam::Vec2, f32) {
        let Some((row, p_row, v_in)) = self.marginal.sample_remapped(u.y) else {
            return (glam::Vec2::ZERO, 0.0);
        };
        let Some((col, p_col, u_in)) = self.conditional[row].sample_remapped(u.x) else {
            return (glam::Vec2::ZERO, 0.0);
        };
        let point = glam::Vec2::new(
            ((col as f32 + u_in) / self.nu as f32).min(ONE_MINUS_EPSILON),
            ((row as f32 + v_in) / self.nv as f32).min(ONE_MINUS_EPSILON),
        );
        (point, p_row * p_col * (self.nu * self.nv) as f32)
    }

    /// The density of `sample` at `p` in [0,1]^2.
    pub fn pdf(&self, p: glam::Vec2) -> f32 {
        let col = ((p.x * self.nu as f32) as usize).min(self.nu - 1);
        let row = ((p.y * self.nv as f32) as usize).min(self.nv - 1);
        self.marginal.pmf(row) * self.conditional[row].pmf(col) * (self.nu * self.nv) as f32
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

    #[test]
    fn two_dimensional_density_matches_its_samples() {
        // Cells weighted 1..=6 on a 3 x 2 grid: the fraction of samples in each cell is its
        // weight over 21, and the density is constant within a cell.
        let weights: Vec<f64> = (1..=6).map(f64::from).collect();
        let d = Distribution2D::new(&weights, 3, 2);
        let n = 300;
        let mut counts = [0usize; 6];
        for i in 0..n {
            for j in 0..n {
                let u = glam::Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let (p, pdf) = d.sample(u);
                let cell = (p.y * 2.0) as usize * 3 + (p.x * 3.0) as usize;
                counts[cell] += 1;
                assert!((pdf - d.pdf(p)).abs() < 1e-4 * pdf, "{pdf} at {p}");
                assert!((pdf - weights[cell] as f32 / 21.0 * 6.0).abs() < 1e-4);
            }
        }
        for (c, w) in counts.iter().zip(&weights) {
            let expected = w / 21.0;
            assert!(
                (*c as f64 / (n * n) as f64 - expected).abs() < 1e-3,
                "{counts:?}"
            );
        }
    }

    #[test]
    fn the_guide_table_gives_the_binary_searchs_item() {
        // Weights from tiny to huge, zeros included: every u's item is the first whose CDF
        // interval ends above u, as a plain binary search finds it.
        let weights: Vec<f64> = (0..300)
            .map(|i| match i % 7 {
                0 => 0.0,
                1 => 1e6,
                _ => (i as f64 * 0.37).sin().abs() * 1e-3,
            })
            .collect();
        let d = Distribution1D::new(&weights);
        for k in 0..100_000 {
            let u = (k as f32 + 0.5) / 100_000.0;
            let (i, _) = d.sample(u).unwrap();
            let mut j = d.cdf.partition_point(|&c| c <= u as f64).saturating_sub(1);
            while d.pmf[j] == 0.0 && j + 1 < d.pmf.len() {
                j += 1;
            }
            assert_eq!(i, j, "u = {u}");
        }
    }
}
