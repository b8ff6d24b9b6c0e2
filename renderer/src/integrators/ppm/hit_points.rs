//! The eye pass of photon mapping (Hachisuka et al. 2008, section 4.1): a camera ray follows
//! specular and glossy bounces to the first surface with a diffuse lobe and no polished
//! specular layer (`POLISHED_ALPHA`), and leaves a hit point there (pbrt-v4's SPPM stops at
//! any diffuse lobe). A glossy-only surface (metal, rough glass) gets no hit point: its BSDF's
//! peak times the rare photon in it made the brightest fireflies of every photon mapper
//! (DESIGN.md 4), and the path goes on by sampling the BSDF instead. So does a polished
//! plastic, whose diffuse base lies under a mirror-like specular layer: on the material
//! spheres its fireflies were most of the photon mappers' error (DESIGN.md 4). Emission met on
//! the way and direct light at each glossy surface passed (next-event estimation, the two
//! weighted by MIS as in the path tracer) and direct light at the hit point (`HitPoint::direct`:
//! photons never carry direct light) form the pixel's direct estimate.

use super::trapped_light::{SpecularPoint, TRAPPED_REFLECTIONS};
use crate::geometry::Ray;
use crate::integrators::path_tracer::{found_emission, sample_direct};
use crate::integrators::scatter;
use crate::material::{Bsdf, TransportMode};
use crate::sampling::sampler::Sampler;
use crate::scene::{Scene, SurfaceInteraction};
use glam::Vec3;

/// Microfacet alpha below which a plastic's specular layer is polished enough that photons
/// gathered through it make fireflies, and the eye path goes on instead of leaving a hit point.
/// Measured (`caustica converge ... --integrator amcppm --time 30`, 128 wide, one seed): the
/// material spheres 1.1e-2 with hit points on every plastic, 1.5e-3 below 0.01 (the polished
/// sphere passed, the 0.25-roughness one, alpha 0.0625, still firing), 1.9e-4 below 0.07,
/// 2.2e-4 below 0.2; the door, whose floor is a plastic of alpha 0.09 where the light through
/// the gap lands, 1.0e-2 below 0.07 and 5.9e-2 below 0.2 (its eye paths leave the lit floor
/// for the walls).
const POLISHED_ALPHA: f32 = 0.08;

#[derive(Clone, Copy, Debug)]
pub struct HitPoint {
    pub si: SurfaceInteraction,
    /// Geometric normal turned towards the viewer: photons count only on this side.
    pub facing: Vec3,
    pub bsdf: Bsdf,
    /// Outgoing direction (towards the camera) in the shading frame.
    pub wo: Vec3,
    /// Throughput of the eye path up to here.
    pub beta: Vec3,
}

impl HitPoint {
    /// The hit point's contribution factor for a photon arriving from direction `wi` (world,
    /// pointing away from the surface) at a surface of geometric normal `photon_normal`:
    /// beta f(wo, wi) |wi.ns| / |wi.ng_photon|, or zero from behind. Photon density measures
    /// flux per unit area of the surface the photons land on, the integral of L |wi.ng_photon|,
    /// while the reflected radiance integrates f L |wi.ns| with the hit point's shading normal
    /// (Veach 1997, section 5.3); the ratio of cosines makes the estimate the one the path
    /// tracer computes, and is exactly 1 where shading and geometric normals agree.
    pub fn response(&self, wi: Vec3, photon_normal: Vec3) -> Vec3 {
        if wi.dot(self.facing) <= 0.0 {
            return Vec3::ZERO;
        }
        let cos_geometric = wi.dot(photon_normal).abs();
        let wi_local = self.si.shading.to_local(wi);
        self.beta
            * self.bsdf.f(self.wo, wi_local, TransportMode::Radiance)
            * (wi_local.z.abs() / cos_geometric)
    }

    /// Direct light at the hit point. On a BSDF with a glossy lobe, next-event estimation and
    /// a BSDF-sampled ray that finds an emitter, weighted by MIS as in the path tracer
    /// (pbrt-v3's SPPM does the same through `EstimateDirect`): light sampling alone misses the
    /// highlights of a broad light (the studio's sky) in a rough plastic's specular lobe, and
    /// on the material spheres gave photon mapping's direct estimate twice the path tracer's
    /// error per pass (DESIGN.md 4). A purely diffuse BSDF keeps light sampling alone, which
    /// does as well there for one ray less.
    pub fn direct(&self, scene: &Scene, sampler: &mut Sampler, rays: &mut u64) -> Vec3 {
        if self.bsdf.microfacet_alpha().is_none() {
            return self.beta
                * sample_direct(scene, &self.si, &self.bsdf, self.wo, sampler, rays, false);
        }
        let light = sample_direct(scene, &self.si, &self.bsdf, self.wo, sampler, rays, true);
        let Some(next) = scatter(
            &self.si,
            &self.bsdf,
            self.wo,
            sampler,
            TransportMode::Radiance,
        ) else {
            return self.beta * light;
        };
        // Only emission is counted here: what the sampled ray finds on a surface that does not
        // emit is indirect light, which the photons carry.
        let bsdf_pdf = (!next.sample.is_delta).then_some(next.sample.pdf);
        *rays += 1;
        let emitted = match scene.intersect(&next.ray) {
            None => found_emission(scene, self.si.p, next.ray.d, None, bsdf_pdf),
            Some(hit) => {
                hit.transmittance
                    * found_emission(scene, self.si.p, next.ray.d, Some(&hit), bsdf_pdf)
            }
        };
        self.beta * (light + next.weight * emitted)
    }
}

/// Result of one eye path: the light it found on the way (module docs), the hit point, and
/// its first vertex if that is specular (`trapped_light.rs`, when asked for).
pub struct EyePath {
    pub emitted: Vec3,
    pub hit_point: Option<HitPoint>,
    pub specular: Option<SpecularPoint>,
}

/// Traces the eye path of one camera ray: `eye` draws its bounces, `nee` the direct light at
/// the glossy surfaces it passes (module docs). With `trapped_light` the first vertex, if
/// specular, is returned (`trapped_light.rs`), and the emitter found through specular
/// vertices only, two or more of which totally reflected, is left to the merges there.
pub fn trace_eye_path(
    scene: &Scene,
    mut ray: Ray,
    eye: &mut Sampler,
    nee: &mut Sampler,
    max_depth: u32,
    trapped_light: bool,
    rays: &mut u64,
) -> EyePath {
    let mut beta = Vec3::ONE;
    let mut emitted = Vec3::ZERO;
    let mut specular = None;
    // Every vertex so far specular, and how many of them totally reflected.
    let (mut all_specular, mut trapped) = (true, 0u32);
    // The density of the last glossy bounce (None from the camera or a specular one), whose
    // emission is weighted against next-event estimation at the glossy surface.
    let mut bsdf_pdf = None;
    let mut prev_p = ray.o;
    for depth in 0..=max_depth {
        *rays += 1;
        // Emission found along here is trapped light, the merges' (`trapped_light.rs`).
        let merged = all_specular && trapped >= TRAPPED_REFLECTIONS && specular.is_some();
        let Some(si) = scene.intersect(&ray) else {
            if !merged {
                emitted += beta * found_emission(scene, prev_p, ray.d, None, bsdf_pdf);
            }
            break;
        };
        beta *= si.transmittance;
        if !merged {
            emitted += beta * found_emission(scene, prev_p, ray.d, Some(&si), bsdf_pdf);
        }
        let bsdf = scene.bsdf(&si);
        let wo = si.shading.to_local(si.wo);
        if bsdf.is_delta() {
            if trapped_light && depth == 0 {
                specular = SpecularPoint::new(si.p, si.n, si.wo, beta);
            }
            trapped += u32::from(bsdf.totally_reflects(wo));
        } else {
            all_specular = false;
        }
        if !bsdf.is_delta() {
            let polished = bsdf.microfacet_alpha().is_some_and(|a| a < POLISHED_ALPHA);
            if (bsdf.has_diffuse_lobe() && !polished) || depth == max_depth {
                let facing = if si.n.dot(si.wo) >= 0.0 { si.n } else { -si.n };
                return EyePath {
                    emitted,
                    hit_point: Some(HitPoint {
                        si,
                        facing,
                        bsdf,
                        wo,
                        beta,
                    }),
                    specular,
                };
            }
            emitted += beta * sample_direct(scene, &si, &bsdf, wo, nee, rays, true);
        }
        if depth == max_depth {
            break;
        }
        let Some(next) = scatter(&si, &bsdf, wo, eye, TransportMode::Radiance) else {
            break;
        };
        bsdf_pdf = (!next.sample.is_delta).then_some(next.sample.pdf);
        prev_p = si.p;
        beta *= next.weight;
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        ray = next.ray;
    }
    EyePath {
        emitted,
        hit_point: None,
        specular,
    }
}
