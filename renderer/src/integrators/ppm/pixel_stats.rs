//! What photon mapping keeps per pixel: the progressive statistics of its hit point
//! (Hachisuka et al. 2008, eqs. 5-7 and 10) with the sums the error estimate needs, and what
//! one photon pass gathered there.

use super::photon_tracing::Deposit;
use crate::integrators::kernel_bias::PassSums;
use glam::DVec3;

#[derive(Clone, Copy, Debug, Default)]
pub(super) struct PixelStats {
    /// Accumulated photon count N (fractional after the alpha reduction).
    pub(super) n: f64,
    pub(super) radius_sq: f64,
    pub(super) tau: DVec3,
    pub(super) direct_sum: DVec3,
    /// Sum over passes of the merges at the first specular vertex (`trapped_light.rs`), a
    /// photon pass's counted for the passes it stands for.
    pub(super) trapped_sum: DVec3,
    pub(super) photons_counted: u64,
    /// Sums over passes of the one-pass estimates L_k (PPPM's image is their mean; for all
    /// variants their spread is the noise) and of their kernel-bias estimates.
    pub(super) passes: PassSums,
}

impl PixelStats {
    /// A pass's photons at this pixel (`m` of them carrying flux `tau_m`) added to its
    /// statistics with the progressive radius reduction, Hachisuka et al. 2008, eqs. 5-7:
    /// N' = N + alpha M, R'^2 = R^2 (N + alpha M) / (N + M), tau' = (tau + tau_M) times the
    /// same ratio. The radius never falls below `floor_sq`.
    pub(super) fn add_photons(&mut self, m: u32, tau_m: DVec3, alpha: f64, floor_sq: f64) {
        self.photons_counted += u64::from(m);
        if m == 0 {
            return;
        }
        let (n, mf) = (self.n, f64::from(m));
        let ratio = (n + alpha * mf) / (n + mf);
        self.n = n + alpha * mf;
        self.radius_sq = (self.radius_sq * ratio).max(floor_sq);
        self.tau = (self.tau + tau_m) * ratio;
    }

    /// Adds pass `pass`'s one-pass estimate (`error.rs`), after `n` passes: the eye pass's
    /// `direct` light plus, from a photon pass, its photon part L_M and their bias estimate
    /// b, standing for k passes (`photons` = (L_M, b, k): itself and the k - 1 before it
    /// that traced none, `photon_budget`). A pass without photons (`None`) counts the
    /// photons' running mean m and their bias's, and the photon pass after it
    /// k L_M - (k - 1) m: the k passes sum to the k L_M the image holds of them, and their
    /// spread carries the photons' variance as the image does (error.rs).
    pub(super) fn add_pass(
        &mut self,
        pass: u64,
        n: u64,
        direct: DVec3,
        photons: Option<(DVec3, DVec3, u64)>,
    ) {
        let (estimate, bias) = match photons {
            Some((photons, bias, 1)) => (direct + photons, bias),
            Some((photons, bias, k)) => {
                let (photon_mean, bias_mean) = self.photon_means(n);
                let k = k as f64;
                (
                    direct + k * photons - (k - 1.0) * photon_mean,
                    k * bias - (k - 1.0) * bias_mean,
                )
            }
            None => {
                let (photon_mean, bias_mean) = self.photon_means(n);
                (direct + photon_mean, bias_mean)
            }
        };
        self.passes.add(pass, estimate, bias);
        self.direct_sum += direct;
    }

    /// The means over the `n` passes so far of the photon part of the one-pass estimates and
    /// of their bias estimates.
    fn photon_means(&self, n: u64) -> (DVec3, DVec3) {
        if n == 0 {
            return (DVec3::ZERO, DVec3::ZERO);
        }
        let n = n as f64;
        (
            (self.passes.estimate_sum - self.direct_sum) / n,
            self.passes.bias_sum / n,
        )
    }

    /// The radiance the photons gathered so far estimate: tau / (pi R^2 N_emitted)
    /// (Hachisuka et al. 2008, eq. 10).
    pub(super) fn indirect(&self, photons_emitted: u64) -> DVec3 {
        if photons_emitted > 0 && self.radius_sq > 0.0 {
            self.tau / (std::f64::consts::PI * self.radius_sq * photons_emitted as f64)
        } else {
            DVec3::ZERO
        }
    }
}

/// What a photon pass gathered at each pixel's hit point.
pub(super) struct Gathered {
    /// New photon count M.
    pub(super) m: Vec<u32>,
    /// Flux sum tau_M (beta f flux, not yet divided by anything).
    pub(super) tau: Vec<DVec3>,
    /// The part of tau_M from photons within R / 2 (`INNER_RADIUS_RATIO`).
    pub(super) tau_inner: Vec<DVec3>,
    /// The variance of tau_M's luminance (`photon_budget`): in a worker's part, the sum of its
    /// photons' squared contributions (the variance of a sum of independent photons); merged
    /// from several workers, the spread of their parts, which also holds the correlation of a
    /// Markov chain's photons (each worker's chain is independent of the others'). Empty
    /// unless the photon count is automatic: nothing else reads it.
    pub(super) tau_sq: Vec<f64>,
    /// What the merges at the pixels' first specular vertices summed (`trapped_light.rs`);
    /// empty until a photon merges there.
    pub(super) trapped: Vec<DVec3>,
}

/// The luminance of a photon mapper's double-precision sums.
pub(super) fn luminance(v: DVec3) -> f64 {
    f64::from(crate::geometry::luminance(v.as_vec3()))
}

impl Gathered {
    /// An empty gather of `n` pixels, with `tau_sq` kept only when `variance` is asked for.
    pub(super) fn new(n: usize, variance: bool) -> Self {
        Gathered {
            m: vec![0; n],
            tau: vec![DVec3::ZERO; n],
            tau_inner: vec![DVec3::ZERO; n],
            tau_sq: if variance { vec![0.0; n] } else { Vec::new() },
            trapped: Vec::new(),
        }
    }

    /// The sum of `parts` (the workers' gathers), in their order, in parallel over pixels: the
    /// sums do not depend on scheduling.
    pub(super) fn merge<'a>(
        n: usize,
        parts: impl Iterator<Item = &'a Gathered> + Clone + Sync,
    ) -> Gathered {
        use rayon::prelude::*;
        let parts: Vec<&Gathered> = parts.collect();
        let variance = parts.iter().any(|g| !g.tau_sq.is_empty());
        let mut merged = Gathered::new(n, variance);
        merged
            .m
            .par_iter_mut()
            .zip(merged.tau.par_iter_mut())
            .zip(merged.tau_inner.par_iter_mut())
            .enumerate()
            .for_each(|(i, ((mi, ti), ii))| {
                for g in &parts {
                    *mi += g.m[i];
                    *ti += g.tau[i];
                    *ii += g.tau_inner[i];
                }
            });
        if parts.iter().any(|g| !g.trapped.is_empty()) {
            merged.trapped = vec![DVec3::ZERO; n];
            for g in parts.iter().filter(|g| !g.trapped.is_empty()) {
                for (t, s) in merged.trapped.iter_mut().zip(&g.trapped) {
                    *t += *s;
                }
            }
        }
        if variance {
            let tau = &merged.tau;
            merged
                .tau_sq
                .par_iter_mut()
                .enumerate()
                .for_each(|(i, si)| {
                    // W parts of equal photon counts: Var(sum) = W s^2 with s^2 their sample
                    // variance; one part keeps its photons' own sum of squares.
                    let w = parts.len() as f64;
                    if w >= 2.0 {
                        let mean = luminance(tau[i]) / w;
                        let spread: f64 = parts
                            .iter()
                            .map(|g| (luminance(g.tau[i]) - mean).powi(2))
                            .sum();
                        *si = w / (w - 1.0) * spread;
                    } else {
                        *si = parts.iter().map(|g| g.tau_sq[i]).sum();
                    }
                });
        }
        merged
    }

    /// One photon's deposit at its hit point.
    pub(super) fn add(&mut self, d: &Deposit) {
        self.add_scaled(d, 1.0);
    }

    /// A deposit counted once, its flux weighted by `scale` (Metropolis photons carry their
    /// chain's normalisation).
    pub(super) fn add_scaled(&mut self, d: &Deposit, scale: f64) {
        let c = d.pixel as usize;
        if d.trapped {
            if self.trapped.is_empty() {
                self.trapped = vec![DVec3::ZERO; self.m.len()];
            }
            self.trapped[c] += d.contribution * scale;
            return;
        }
        self.m[c] += 1;
        self.tau[c] += d.contribution * scale;
        if !self.tau_sq.is_empty() {
            let l = luminance(d.contribution) * scale;
            self.tau_sq[c] += l * l;
        }
        if d.inner {
            self.tau_inner[c] += d.contribution * scale;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error_estimate::variance_of_mean;

    /// A run of `blocks` blocks of `k` passes (the first pass a photon pass of its own), each
    /// block's photons in its last pass: the eye pass's light 1 + e every pass, the photons'
    /// 2 + p (their bias estimate the same) in the photon passes, e and p uniform with
    /// standard deviations 0.3 and 1. Returns the image (the mean of the eye passes' light
    /// plus the photon passes' weighted by the passes they stand for, as SPPM's image
    /// weighs them by their photons, k times the average), the mean of the one-pass
    /// estimates and the variance of it their spread gives. `running_mean`: a pass without
    /// photons adds their running mean (as shipped), else nothing, with k L_M in the photon
    /// pass.
    fn run(rng: &mut u64, blocks: u64, k: u64, running_mean: bool) -> (f64, f64, f64) {
        let mut uniform = |sd: f64| {
            // xorshift64*, uniform on [-sqrt(3) sd, sqrt(3) sd): variance sd^2.
            *rng ^= *rng >> 12;
            *rng ^= *rng << 25;
            *rng ^= *rng >> 27;
            let u = (rng.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64;
            (2.0 * u - 1.0) * 3f64.sqrt() * sd
        };
        let mut px = PixelStats::default();
        let (mut direct, mut photons) = (0.0, 0.0);
        let mut pass = 0;
        for block in 0..=blocks {
            let k = if block == 0 { 1 } else { k };
            for i in 0..k {
                let d = 1.0 + uniform(0.3);
                direct += d;
                let d = DVec3::splat(d);
                if i + 1 < k {
                    if running_mean {
                        px.add_pass(pass, pass, d, None);
                    } else {
                        px.passes.add(pass, d, DVec3::ZERO);
                        px.direct_sum += d;
                    }
                } else {
                    let p = 2.0 + uniform(1.0);
                    photons += k as f64 * p;
                    let l = DVec3::splat(p);
                    let stands_for = if running_mean { k } else { 1 };
                    let weight = if running_mean { 1.0 } else { k as f64 };
                    px.add_pass(pass, pass, d, Some((weight * l, weight * l, stands_for)));
                }
                pass += 1;
            }
        }
        let n = pass;
        let image = (direct + photons) / n as f64;
        let mean = px.passes.estimate_sum.x / n as f64;
        let variance = variance_of_mean(px.passes.estimate_sum, px.passes.estimate_sum_sq, n);
        (image, mean, variance.x)
    }

    /// Passes without photons (`photon_budget`) keep the one-pass estimates' mean at the
    /// image and their spread at its variance: over 8,000 runs of 1,025 passes whose photons
    /// come every fourth, the variance of the mean the sums give is within 7 % of the runs'
    /// own spread (V_e / n + V_p sum k^2 / n^2). The running mean's own noise adds about
    /// (k - 1) / k ln(B) / B for B blocks (error.rs), 2 % here (19 % at 16 blocks), and the
    /// spread's standard error over 8,000 runs is 1.6 %. Counting nothing between photon
    /// passes and k L_M in them would add the on-and-off of the photons' whole value: about
    /// four times.
    #[test]
    fn passes_without_photons_keep_the_image_and_its_variance() {
        for running_mean in [true, false] {
            let mut rng = 0x9e37_79b9_7f4a_7c15u64;
            let runs: Vec<(f64, f64, f64)> = (0..8_000)
                .map(|_| run(&mut rng, 256, 4, running_mean))
                .collect();
            for &(image, mean, _) in &runs {
                assert!((image - mean).abs() < 1e-11, "{image} against {mean}");
            }
            let m = runs.iter().map(|r| r.0).sum::<f64>() / runs.len() as f64;
            let spread =
                runs.iter().map(|r| (r.0 - m).powi(2)).sum::<f64>() / (runs.len() - 1) as f64;
            let estimated = runs.iter().map(|r| r.2).sum::<f64>() / runs.len() as f64;
            let ratio = estimated / spread;
            eprintln!(
                "running mean {running_mean}: estimated {estimated:.4e}, spread {spread:.4e}"
            );
            if running_mean {
                assert!((ratio - 1.0).abs() < 0.07, "ratio {ratio}");
            } else {
                assert!(ratio > 3.0, "ratio {ratio}: the alternative is told apart");
            }
        }
    }

    /// Ten million passes of one pixel under a uniform photon density: each pass finds the
    /// photons its shrinking disc holds (1000 at first, about 5 at the end, whole numbers with
    /// the fraction carried to the next pass), 10^5 photons emitted a pass (10^12 in all). The
    /// estimate tau / (pi R^2 N_emitted) stays at density x flux / photons per pass within
    /// 1e-6: the sums' rounding over 10^7 updates does not drift and no counter overflows
    /// (tau and R^2 kept in f32 drift by over 1e-3 here).
    #[test]
    fn ten_million_photon_passes_keep_the_estimate() {
        let (alpha, photons_per_pass, passes) = (2.0 / 3.0, 100_000u64, 10_000_000u64);
        let density = 1000.0 / std::f64::consts::PI; // photons per unit area per pass
        let flux = 0.37; // per photon
        let mut px = PixelStats {
            radius_sq: 1.0,
            ..Default::default()
        };
        let (mut carried, mut counted) = (0.0f64, 0u64);
        for _ in 0..passes {
            let expected = density * std::f64::consts::PI * px.radius_sq + carried;
            let m = expected.floor();
            carried = expected - m;
            counted += m as u64;
            px.add_photons(m as u32, DVec3::splat(m * flux), alpha, 0.0);
        }
        let emitted = photons_per_pass * passes;
        let exact = density * flux / photons_per_pass as f64;
        let estimate = px.indirect(emitted).x;
        assert!(
            ((estimate - exact) / exact).abs() < 1e-6,
            "{estimate} against {exact}"
        );
        assert_eq!(px.photons_counted, counted);
        // The radius shrank as the analysis says, R^2 ~ passes^-(1 - alpha) (within a factor 2).
        let predicted = (passes as f64).powf(-(1.0 - alpha));
        assert!(
            px.radius_sq > 0.5 * predicted && px.radius_sq < 2.0 * predicted,
            "{}",
            px.radius_sq
        );
    }
}
