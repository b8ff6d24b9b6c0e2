//! The eye pass of photon mapping (Hachisuka et al. 2008, section 4.1): a camera ray follows
//! specular bounces to the first surface with a non-delta BSDF and leaves a hit point there.
//! Emission met on the way and direct light at the hit point (next-event estimation without
//! MIS: photons never carry direct light) form the pixel's direct estimate (DESIGN.md 4).

use crate::geometry::Ray;
use crate::integrators::path_tracer::sample_direct;
use crate::integrators::scatter;
use crate::material::{Bsdf, TransportMode};
use crate::sampling::sampler::Sampler;
use crate::scene::{Scene, SurfaceInteraction};
use glam::Vec3;

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

    /// Direct light at the hit point by next-event estimation.
    pub fn direct(&self, scene: &Scene, sampler: &mut Sampler, rays: &mut u64) -> Vec3 {
        self.beta * sample_direct(scene, &self.si, &self.bsdf, self.wo, sampler, rays, false)
    }
}

/// Result of one eye path: emission seen through specular chains, and the hit point.
pub struct EyePath {
    pub emitted: Vec3,
    pub hit_point: Option<HitPoint>,
}

pub fn trace_eye_path(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    max_depth: u32,
    rays: &mut u64,
) -> EyePath {
    let mut beta = Vec3::ONE;
    let mut emitted = Vec3::ZERO;
    for depth in 0..=max_depth {
        *rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            emitted += beta * scene.environment_radiance(ray.d);
            break;
        };
        beta *= si.transmittance;
        emitted += beta * scene.emitted(&si, si.wo);
        let bsdf = scene.bsdf(&si);
        let wo = si.shading.to_local(si.wo);
        if !bsdf.is_delta() {
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
            };
        }
        if depth == max_depth {
            break;
        }
        let Some(next) = scatter(&si, &bsdf, wo, sampler, TransportMode::Radiance) else {
            break;
        };
        beta *= next.weight;
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        ray = next.ray;
    }
    EyePath {
        emitted,
        hit_point: None,
    }
}
