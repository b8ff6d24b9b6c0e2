//! Reference path tracer (pbrt-v4 section 13.4, `PathIntegrator`): BSDF sampling plus
//! next-event estimation, combined by multiple importance sampling with the power heuristic
//! (Veach's thesis, section 9.2) for area and environment lights; delta lights by next-event
//! estimation alone. Russian roulette from bounce `rr_depth` on (Mitsuba's parameter of that
//! name; by default the second bounce), on the throughput with the refraction eta^2 factored
//! out (pbrt-v4 section 13.4.4).

use crate::film::sanitize;
use crate::geometry::Ray;
use crate::integrators::pixel_pass::{PixelEstimator, PixelIntegrator, Row};
use crate::integrators::{Integrator, ParamSpec, ParamValues, RenderContext, params, scatter};
use crate::light::Light;
use crate::material::{Bsdf, TransportMode};
use crate::sampling::sampler::Sampler;
use crate::sampling::warp::power_heuristic;
use crate::scene::{Scene, SurfaceInteraction};
use glam::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize)]
pub struct PathSettings {
    /// Maximum number of scattering events along a path.
    pub max_depth: u32,
    /// The first bounce at which Russian roulette may end a path.
    pub rr_depth: u32,
}

impl PathSettings {
    pub const PARAMS: &'static [ParamSpec] = &[
        params::MAX_DEPTH,
        ParamSpec::new(
            "rr_depth",
            "Bounces before Russian roulette may end a path: more spends time on long paths to spare the first bounces roulette's extra noise.",
            1.0,
            (0.0, 1024.0),
        )
        .integer(),
    ];

    pub fn from_params(p: &ParamValues) -> Self {
        params::read_settings(Self::PARAMS, p)
    }
}

impl Default for PathSettings {
    fn default() -> Self {
        Self::from_params(&ParamValues::new())
    }
}

/// The path tracer: one path per pixel sample.
pub type PathTracer = PixelIntegrator<PathSettings>;

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(PathTracer::new(ctx, PathSettings::from_params(params)))
}

impl PixelEstimator for PathSettings {
    type Scratch = ();

    fn sample_pixel(&self, ctx: &RenderContext, film: Vec2, row: &mut Row<()>) -> Vec3 {
        let ray = ctx.camera.generate_ray(film);
        let l = li(&ctx.scene, ray, &mut row.sampler, self, &mut row.stats.rays);
        row.stats.samples += 1;
        sanitize(l).unwrap_or_else(|| {
            row.stats.dropped += 1;
            Vec3::ZERO
        })
    }
}

/// Radiance arriving along `ray`.
pub fn li(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    settings: &PathSettings,
    rays: &mut u64,
) -> Vec3 {
    let max_depth = settings.max_depth;
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut specular_bounce = false;
    let mut eta_scale = 1.0f32;
    let mut prev_bsdf_pdf = 0.0f32;
    let mut prev_p = ray.o;
    let mut depth = 0u32;
    loop {
        *rays += 1;
        // Emission found by BSDF sampling is weighted against next-event estimation, except
        // from the camera or a specular bounce, which next-event estimation cannot sample.
        let bsdf_pdf = (depth > 0 && !specular_bounce).then_some(prev_bsdf_pdf);
        let Some(si) = scene.intersect(&ray) else {
            l += beta * found_emission(scene, prev_p, ray.d, None, bsdf_pdf);
            break;
        };
        beta *= si.transmittance;
        l += beta * found_emission(scene, prev_p, ray.d, Some(&si), bsdf_pdf);
        if depth == max_depth {
            break;
        }
        let bsdf = scene.bsdf(&si);
        let wo = si.shading.to_local(si.wo);
        if !bsdf.is_delta() {
            l += beta * sample_direct(scene, &si, &bsdf, wo, sampler, rays, true);
        }
        let Some(next) = scatter(&si, &bsdf, wo, sampler, TransportMode::Radiance) else {
            break;
        };
        beta *= next.weight;
        prev_bsdf_pdf = next.sample.pdf;
        specular_bounce = next.sample.is_delta;
        if next.sample.eta != 1.0 {
            eta_scale *= next.sample.eta * next.sample.eta;
        }
        prev_p = si.p;
        ray = next.ray;
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        let rr_beta = beta * eta_scale;
        if rr_beta.max_element() < 1.0 && depth >= settings.rr_depth {
            let q = (1.0 - rr_beta.max_element()).max(0.0);
            if sampler.get_1d() < q {
                break;
            }
            beta /= 1.0 - q;
        }
        depth += 1;
    }
    l
}

/// The radiance a ray leaving `prev_p` in direction `d` finds: the emission at `si`, or the
/// environment's when it left the scene. `bsdf_pdf` is the solid-angle density the ray was
/// sampled with at a non-specular surface, whose emission next-event estimation also samples:
/// then it is weighted by the power heuristic against that (Veach 1997, section 9.2); None
/// counts it whole (a camera ray, a specular bounce).
#[inline]
pub(crate) fn found_emission(
    scene: &Scene,
    prev_p: Vec3,
    d: Vec3,
    si: Option<&SurfaceInteraction>,
    bsdf_pdf: Option<f32>,
) -> Vec3 {
    let (le, light_pdf) = match si {
        None => {
            let Some(env) = scene.environment else {
                return Vec3::ZERO;
            };
            let light_pdf = || match &scene.lights[env] {
                Light::Environment(e) => scene.light_sampler.pmf(env) * e.pdf_li(d),
                _ => 0.0,
            };
            (scene.environment_radiance(d), bsdf_pdf.map(|_| light_pdf()))
        }
        Some(si) => {
            let Some((light, area)) = scene.area_light(si) else {
                return Vec3::ZERO;
            };
            let light_pdf = || scene.light_sampler.pmf(light) * area.pdf_li(prev_p, si.p);
            (
                area.l(&scene.textures, &si.uv, si.wo),
                bsdf_pdf.map(|_| light_pdf()),
            )
        }
    };
    match (bsdf_pdf, light_pdf) {
        (Some(bsdf_pdf), Some(light_pdf)) if le != Vec3::ZERO => {
            le * power_heuristic(1.0, bsdf_pdf, 1.0, light_pdf)
        }
        _ => le,
    }
}

/// Next-event estimation: one light chosen by power, one point on it, weighted by MIS against
/// BSDF sampling unless the light is a delta light.
///
/// Without `mis` the estimate stands alone (for integrators that never find emitters by BSDF
/// sampling, such as the photon mappers' eye pass).
pub(crate) fn sample_direct(
    scene: &Scene,
    si: &SurfaceInteraction,
    bsdf: &Bsdf,
    wo: Vec3,
    sampler: &mut Sampler,
    rays: &mut u64,
    mis: bool,
) -> Vec3 {
    let (ul, u) = (sampler.get_1d(), sampler.get_2d());
    let Some((_, pmf, ls)) = scene.sample_light(si, ul, u) else {
        return Vec3::ZERO;
    };
    let wi = si.shading.to_local(ls.wi);
    let f = bsdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs();
    if f == Vec3::ZERO || !si.consistent(wo, wi, ls.wi) {
        return Vec3::ZERO;
    }
    let shadow = si.shadow_ray(&ls);
    *rays += 1;
    if scene.occluded(&shadow) {
        return Vec3::ZERO;
    }
    let light_pdf = pmf * ls.pdf;
    if ls.is_delta || !mis {
        return f * ls.l / light_pdf;
    }
    let w = power_heuristic(1.0, light_pdf, 1.0, bsdf.pdf(wo, wi));
    f * ls.l * w / light_pdf
}
