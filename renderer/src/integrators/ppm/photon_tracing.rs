//! Tracing one photon (Hachisuka et al. 2008, section 4.2; pbrt-v4 section 13.8.3): emitted by
//! a light chosen by power, scattered by the BSDFs with Russian roulette on the change of its
//! power, and deposited at every hit point whose disc holds it from its second hit on (direct
//! light is next-event estimation's). What it deposits goes to a callback, so that uniform
//! photons add to a pass's sums at once and Metropolis photons (`metropolis.rs`) can be kept
//! as their chain's state. A photon pass splits its photons among the workers, each gathering
//! into its own buffer, merged in the workers' order.

use super::hash_grid::HashGrid;
use super::pixel_stats::Gathered;
use super::trapped_light::TRAPPED_REFLECTIONS;
use super::{PHOTON_STREAM, PhotonMapper};
use crate::geometry::luminance;
use crate::integrators::kernel_bias::INNER_RADIUS_RATIO;
use crate::integrators::{Cancelled, PassStats, scatter};
use crate::light::emission::emit_photon;
use crate::material::TransportMode;
use crate::sampling::sampler::{SampleSource, Sampler};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// A photon's contribution to one hit point: `contribution` is beta f flux (before any
/// normalisation), `inner` whether it lies within the inner disc of the bias estimate; or,
/// `trapped`, to a pixel's first specular vertex (`trapped_light.rs`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Deposit {
    pub pixel: u32,
    pub contribution: DVec3,
    pub inner: bool,
    pub trapped: bool,
}

impl PhotonMapper {
    /// Traces one photon drawing from `sampler` and hands each of its deposits to `deposit`.
    pub(super) fn trace_photon(
        &self,
        grid: &HashGrid,
        sampler: &mut impl SampleSource,
        st: &mut PassStats,
        deposit: &mut impl FnMut(Deposit),
    ) {
        let scene = &*self.ctx.scene;
        let Some((light, mut ray, mut flux)) = emit_photon(scene, sampler) else {
            return;
        };
        // Merging at the camera's specular vertices (`trapped_light.rs`): while every vertex
        // is specular, once two totally reflected; never for a delta light's photons.
        let trapped_light = self
            .trapped
            .as_ref()
            .filter(|_| !scene.lights[light].is_delta());
        let (mut all_specular, mut trapped) = (true, 0u32);
        for depth in 0..self.settings.max_depth {
            st.rays += 1;
            let Some(si) = scene.intersect(&ray) else {
                break;
            };
            flux *= si.transmittance;
            let bsdf = scene.bsdf(&si);
            if depth > 0 && !bsdf.is_delta() {
                let wi = -ray.d;
                for &c in grid.candidates(si.p) {
                    let Some(hp) = &self.hit_points[c as usize] else {
                        continue;
                    };
                    let dist_sq = (si.p - hp.si.p).length_squared() as f64;
                    let radius_sq = self.radius_sq(c as usize);
                    if dist_sq > radius_sq {
                        continue;
                    }
                    let r = hp.response(wi, si.n);
                    if r == Vec3::ZERO {
                        continue;
                    }
                    let contribution = (r * flux).as_dvec3();
                    if contribution.is_finite() && contribution.min_element() >= 0.0 {
                        deposit(Deposit {
                            pixel: c,
                            contribution,
                            inner: dist_sq <= INNER_RADIUS_RATIO * INNER_RADIUS_RATIO * radius_sq,
                            trapped: false,
                        });
                    } else {
                        st.dropped += 1;
                    }
                }
            }
            let wo = si.shading.to_local(-ray.d);
            let Some(next) = scatter(&si, &bsdf, wo, sampler, TransportMode::Importance) else {
                break;
            };
            let new_flux = flux * next.weight;
            if let Some(t) = trapped_light.filter(|_| all_specular) {
                if bsdf.is_delta() {
                    trapped += u32::from(bsdf.totally_reflects(wo));
                    if trapped >= TRAPPED_REFLECTIONS && t.merges_leaving(si.n, next.ray.d) {
                        t.merge(
                            si.p,
                            si.n,
                            next.ray.d,
                            new_flux,
                            &mut |pixel, contribution| {
                                deposit(Deposit {
                                    pixel,
                                    contribution,
                                    inner: false,
                                    trapped: true,
                                })
                            },
                        );
                    }
                } else {
                    all_specular = false;
                }
            }
            // Russian roulette on the change of power (pbrt-v4 SPPM, section 13.8.3).
            let q = (1.0 - luminance(new_flux) / luminance(flux).max(f32::MIN_POSITIVE)).max(0.0);
            if sampler.get_1d() < q {
                break;
            }
            flux = new_flux / (1.0 - q);
            if !flux.is_finite() || flux == Vec3::ZERO {
                break;
            }
            ray = next.ray;
        }
    }
}

impl PhotonMapper {
    /// Photon pass: traces `photons` photons and returns what each pixel's hit point gathered.
    pub(super) fn photon_pass(
        &self,
        pass: u64,
        cancel: &AtomicBool,
        stats: &mut PassStats,
    ) -> Result<Gathered, Cancelled> {
        let mut workers = vec![(); self.photon_workers.max(1)];
        self.photon_pass_over(&mut workers, stats, |(), grid, photons, gathered, st| {
            let mut sampler = Sampler::new(self.ctx.seed ^ PHOTON_STREAM);
            for i in photons {
                if i % 1024 == 0 && cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                sampler.start_pixel_sample(i, pass);
                self.trace_photon(grid, &mut sampler, st, &mut |d| gathered.add(&d));
            }
            Ok(())
        })
    }

    /// What every photon pass shares: the pass's `photons` split into one range per worker,
    /// each worker's `work` on its range gathering apart, the gathers and counters summed in
    /// the workers' order (so the image does not depend on scheduling).
    pub(super) fn photon_pass_over<T: Send>(
        &self,
        workers: &mut [T],
        stats: &mut PassStats,
        work: impl Fn(
            &mut T,
            &HashGrid,
            std::ops::Range<u64>,
            &mut Gathered,
            &mut PassStats,
        ) -> Result<(), Cancelled>
        + Sync,
    ) -> Result<Gathered, Cancelled> {
        let n = self.pixels.len();
        let Some((grid, _)) = &self.grid else {
            return Ok(Gathered::new(n, self.photons_automatic));
        };
        let photons = self.settings.photons;
        let count = workers.len().max(1) as u64;
        let results: Vec<(Gathered, PassStats)> = workers
            .par_iter_mut()
            .enumerate()
            .map(|(c, worker)| {
                let c = c as u64;
                let mut gathered = Gathered::new(n, self.photons_automatic);
                let mut st = PassStats::default();
                let range = (c * photons / count)..((c + 1) * photons / count);
                work(worker, grid, range, &mut gathered, &mut st)?;
                Ok((gathered, st))
            })
            .collect::<Result<_, _>>()?;
        for (_, st) in &results {
            *stats = *stats + *st;
        }
        Ok(Gathered::merge(n, results.iter().map(|r| &r.0)))
    }
}
