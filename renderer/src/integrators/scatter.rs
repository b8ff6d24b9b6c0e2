//! The step every path shares: sampling the BSDF for the next direction, for camera paths
//! (radiance) and photons and light subpaths (importance) alike.

use crate::geometry::Ray;
use crate::material::{Bsdf, BsdfSample, TransportMode};
use crate::sampling::sampler::SampleSource;
use crate::scene::SurfaceInteraction;
use glam::Vec3;

/// The next segment of a path leaving `si`: the BSDF sample, its throughput factor
/// f |cos| / pdf, and the spawned ray.
pub(crate) struct Scatter {
    pub sample: BsdfSample,
    pub weight: Vec3,
    pub ray: Ray,
}

/// Samples the BSDF for the next direction of a path (camera paths in radiance mode, photons
/// in importance mode). None ends the path: no sample, or a direction the geometric surface
/// contradicts (`SurfaceInteraction::consistent`), which would leak light.
pub(crate) fn scatter(
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    wo: Vec3,
    sampler: &mut impl SampleSource,
    mode: TransportMode,
) -> Option<Scatter> {
    let uc = sampler.get_1d();
    let u = sampler.get_2d();
    let sample = bsdf.sample_f(wo, uc, u, mode)?;
    let wi = si.shading.from_local(sample.wi).normalize();
    if !si.consistent(wo, sample.wi, wi) {
        return None;
    }
    let weight = match mode {
        TransportMode::Radiance => sample.f * sample.wi.z.abs() / sample.pdf,
        // Importance flows the other way, and with shading normals the adjoint BSDF is not f:
        // f*(wo, wi) |wi.ns| = f(wo, wi) |wo.ns| |wi.ng| / |wo.ng| (Veach 1997, eq. 5.19),
        // without which photons and light subpaths gain or lose energy wherever interpolated
        // normals depart from the faces.
        TransportMode::Importance => {
            let wo_ng = si.wo.dot(si.n).abs();
            if wo_ng == 0.0 {
                return None;
            }
            sample.f * (wo.z.abs() * wi.dot(si.n).abs() / wo_ng) / sample.pdf
        }
    };
    Some(Scatter {
        weight,
        ray: si.spawn_ray(wi),
        sample,
    })
}
