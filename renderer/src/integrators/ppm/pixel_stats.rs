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
