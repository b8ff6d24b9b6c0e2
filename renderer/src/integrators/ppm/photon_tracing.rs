//! Tracing one photon (Hachisuka et al. 2008, section 4.2; pbrt-v4 section 13.8.3): emitted by
//! a light chosen by power, scattered by the BSDFs with Russian roulette on the change of its
//! power, and deposited at every hit point whose disc holds it from its second hit on (direct
//! light is next-event estimation's). What it deposits goes to a callback, so that uniform
//! photons add to a pass's sums at once and Metropolis photons (`metropolis.rs`) can be kept
//! as their chain's state.

use super::PhotonMapper;
use super::hash_grid::HashGrid;
use crate::geometry::luminance;
use crate::integrators::kernel_bias::INNER_RADIUS_RATIO;
use crate::integrators::{PassStats, scatter};
use crate::light::emission::emit_photon;
use crate::material::TransportMode;
use crate::sampling::sampler::SampleSource;
use glam::{DVec3, Vec3};

/// A photon's contribution to one hit point: `contribution` is beta f flux (before any
/// normalisation), `inner` whether it lies within the inner disc of the bias estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Deposit {
    pub pixel: u32,
    pub contribution: DVec3,
    pub inner: bool,
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
        let Some((_, mut ray, mut flux)) = emit_photon(scene, sampler) else {
            return;
        };
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
