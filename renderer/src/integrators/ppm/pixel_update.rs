//! What a pass leaves in each pixel's statistics (`pixel_stats`): its one-pass estimate and
//! bias estimate (`error.rs`), the progressive radius reduction (module docs), and, where
//! the count is chosen here, what the photon budget observes and the next average count
//! (`photon_budget`); and what a pass without photons leaves.

use super::photon_budget::{PixelPass, photon_range};
use super::pixel_stats::{Gathered, luminance};
use super::{PhotonMapper, Radii, photons_per_pass};
use crate::integrators::kernel_bias;
use glam::{DVec3, Vec3};

impl PhotonMapper {
    /// After a photon pass that stands for `stands_for` passes (`photon_budget`), with the
    /// eye pass's light `direct`, what the photons `gathered`, and the rays (eye, photon) the
    /// two parts traced.
    pub(super) fn update_pixels(
        &mut self,
        pass: u64,
        direct: &[Vec3],
        gathered: &Gathered,
        stands_for: u64,
        rays: (u64, u64),
    ) {
        let alpha = self.settings.alpha;
        let photons = self.settings.photons;
        let mut budget_pixels = Vec::new();
        let global_radius_sq = match self.radii {
            Radii::Global { radius_sq } => Some(radius_sq),
            Radii::PerPixel => None,
        };
        for (i, px) in self.pixels.iter_mut().enumerate() {
            // This pass's estimate with the radius it gathered with, and its bias estimate
            // (module docs): both before the radius shrinks.
            let radius_sq = global_radius_sq.unwrap_or(px.radius_sq);
            let area = std::f64::consts::PI * radius_sq * photons as f64;
            let trapped = match (&self.trapped, gathered.trapped.get(i)) {
                (Some(t), Some(&sum)) => t.radiance(sum, photons),
                _ => DVec3::ZERO,
            };
            px.trapped_sum += trapped * stands_for as f64;
            let indirect = gathered.tau[i] / area + trapped;
            let estimate = direct[i].as_dvec3() + indirect;
            let bias = kernel_bias::pass_bias(gathered.tau[i], gathered.tau_inner[i], area);
            if self.photons_automatic && self.passes > 0 {
                budget_pixels.push(PixelPass {
                    estimate: luminance(estimate),
                    mean: luminance(px.passes.estimate_sum) / self.passes as f64,
                    photon_variance: gathered.tau_sq[i] / (area * area),
                });
            }
            let photons = Some((indirect, bias, stands_for));
            px.add_pass(pass, self.passes, direct[i].as_dvec3(), photons);
            if global_radius_sq.is_some() {
                px.photons_counted += u64::from(gathered.m[i]);
            } else {
                px.add_photons(gathered.m[i], gathered.tau[i], alpha, self.radius_floor_sq);
            }
        }
        if let Radii::Global { radius_sq } = &mut self.radii {
            // Knaus & Zwicker 2011: the next pass's global radius, eq. 20.
            let k = (pass + 1) as f64;
            *radius_sq = (*radius_sq * (k + alpha) / (k + 1.0)).max(self.radius_floor_sq);
        }
        self.photons_emitted += photons;
        self.passes += 1;
        self.photon_passes += 1;
        if self.photons_automatic {
            if !budget_pixels.is_empty() {
                self.budget.observe(budget_pixels.into_iter());
            }
            let (w, h) = (self.ctx.camera.width, self.ctx.camera.height);
            let range = photon_range(photons_per_pass(w, h));
            self.photon_average = self.budget.next(
                self.photon_average,
                photons,
                rays.0,
                rays.1,
                self.passes,
                range,
            );
            self.settings.photons = self.photon_average;
        }
        self.record_radius();
    }

    /// A pass that traced no photons (`photon_budget`): its estimate is its eye pass's light
    /// plus the photons' running mean, and its bias estimate their bias's, which the next
    /// photon pass takes back (error.rs); the radii and the photon statistics stay.
    pub(super) fn pass_without_photons(&mut self, pass: u64, direct: &[Vec3]) {
        let n = self.passes;
        for (px, d) in self.pixels.iter_mut().zip(direct) {
            px.add_pass(pass, n, d.as_dvec3(), None);
        }
        self.passes += 1;
        self.record_radius();
    }
}
