//! Reference path tracer (pbrt-v4 section 13.4, `PathIntegrator`): BSDF sampling plus
//! next-event estimation, combined by multiple importance sampling with the power heuristic
//! (Veach's thesis, section 9.2) for area and environment lights; delta lights by next-event
//! estimation alone. Russian roulette from the second bounce on, on the throughput with the
//! refraction eta^2 factored out (pbrt-v4 section 13.4.4).

use crate::error_estimate::ErrorEstimate;
use crate::film::{Film, sanitize};
use crate::geometry::Ray;
use crate::image::Image;
use crate::integrators::{
    Cancelled, Integrator, ParamSpec, ParamValues, PassStats, RenderContext, scatter,
};
use crate::light::Light;
use crate::material::{Bsdf, TransportMode};
use crate::sampling::sampler::Sampler;
use crate::sampling::warp::power_heuristic;
use crate::scene::{Scene, SurfaceInteraction};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSettings {
    /// Maximum number of scattering events along a path.
    pub max_depth: u32,
}

impl PathSettings {
    pub const PARAMS: &'static [ParamSpec] = &[ParamSpec {
        name: "max_depth",
        doc: "Maximum number of bounces of a path; Russian roulette ends most paths earlier.",
        default: 64.0,
        min: 0.0,
        max: 1024.0,
        integer: true,
        live: false,
    }];

    pub fn from_params(p: &ParamValues) -> Self {
        PathSettings {
            max_depth: p
                .get("max_depth")
                .copied()
                .unwrap_or(Self::PARAMS[0].default) as u32,
        }
    }
}

impl Default for PathSettings {
    fn default() -> Self {
        Self::from_params(&ParamValues::new())
    }
}

pub struct PathIntegrator {
    ctx: RenderContext,
    settings: PathSettings,
    film: Film,
    pass_buffer: Vec<Vec3>,
}

pub fn create(ctx: RenderContext, params: &ParamValues) -> Box<dyn Integrator> {
    Box::new(PathIntegrator::new(ctx, PathSettings::from_params(params)))
}

impl PathIntegrator {
    pub fn new(ctx: RenderContext, settings: PathSettings) -> Self {
        let (w, h) = (ctx.camera.width as usize, ctx.camera.height as usize);
        PathIntegrator {
            ctx,
            settings,
            film: Film::new(w, h),
            pass_buffer: vec![Vec3::ZERO; w * h],
        }
    }
}

impl Integrator for PathIntegrator {
    fn render_pass(&mut self, pass: u64, cancel: &AtomicBool) -> Result<PassStats, Cancelled> {
        let width = self.film.width;
        let (scene, camera, seed, settings) = (
            &*self.ctx.scene,
            &self.ctx.camera,
            self.ctx.seed,
            self.settings,
        );
        let stats = self
            .pass_buffer
            .par_chunks_mut(width)
            .enumerate()
            .map(|(y, row)| {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                let mut sampler = Sampler::new(seed);
                let mut stats = PassStats::default();
                for (x, out) in row.iter_mut().enumerate() {
                    sampler.start_pixel_sample((y * width + x) as u64, pass);
                    let film = Vec2::new(x as f32, y as f32) + sampler.get_2d();
                    let ray = camera.generate_ray(film);
                    let l = li(
                        scene,
                        ray,
                        &mut sampler,
                        settings.max_depth,
                        &mut stats.rays,
                    );
                    stats.samples += 1;
                    *out = sanitize(l).unwrap_or_else(|| {
                        stats.dropped += 1;
                        Vec3::ZERO
                    });
                }
                Ok(stats)
            })
            .try_reduce(PassStats::default, |a, b| Ok(a + b))?;
        self.film.add_pass(&self.pass_buffer);
        Ok(stats)
    }

    fn image(&self) -> Image {
        self.film.image()
    }

    fn set_live_param(&mut self, _name: &str, _value: f64) -> bool {
        false
    }

    fn error_estimate(&self) -> Option<ErrorEstimate> {
        self.film.error_estimate()
    }
}

/// Radiance arriving along `ray`.
pub fn li(
    scene: &Scene,
    mut ray: Ray,
    sampler: &mut Sampler,
    max_depth: u32,
    rays: &mut u64,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut beta = Vec3::ONE;
    let mut specular_bounce = false;
    let mut eta_scale = 1.0f32;
    let mut prev_bsdf_pdf = 0.0f32;
    let mut prev_p = ray.o;
    let mut depth = 0u32;
    loop {
        *rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            if let Some(env) = scene.environment {
                let le = scene.environment_radiance();
                let w = if depth == 0 || specular_bounce {
                    1.0
                } else {
                    let light_pdf = match &scene.lights[env] {
                        Light::Environment(e) => scene.light_sampler.pmf(env) * e.pdf_li(),
                        _ => 0.0,
                    };
                    power_heuristic(1.0, prev_bsdf_pdf, 1.0, light_pdf)
                };
                l += beta * le * w;
            }
            break;
        };
        if let Some((light, area)) = scene.area_light(&si) {
            let le = area.l(scene, si.uv, si.wo);
            if le != Vec3::ZERO {
                let w = if depth == 0 || specular_bounce {
                    1.0
                } else {
                    let light_pdf = scene.light_sampler.pmf(light) * area.pdf_li(prev_p, si.p);
                    power_heuristic(1.0, prev_bsdf_pdf, 1.0, light_pdf)
                };
                l += beta * le * w;
            }
        }
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
        if rr_beta.max_element() < 1.0 && depth >= 1 {
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
    let ul = sampler.get_1d();
    let u = sampler.get_2d();
    let Some((index, pmf)) = scene.light_sampler.sample(ul) else {
        return Vec3::ZERO;
    };
    let ctx = si.light_context();
    let sample = match &scene.lights[index] {
        Light::Area(a) => a.sample_li(scene, &ctx, u),
        Light::Point(p) => p.sample_li(&ctx),
        Light::Spot(s) => s.sample_li(&ctx),
        Light::Directional(d) => d.sample_li(&ctx),
        Light::Environment(e) => e.sample_li(&ctx, u),
    };
    let Some(ls) = sample else {
        return Vec3::ZERO;
    };
    if !(ls.pdf > 0.0) || ls.l == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let wi = si.shading.to_local(ls.wi);
    let f = bsdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs();
    if f == Vec3::ZERO || !si.consistent(wo, wi, ls.wi) {
        return Vec3::ZERO;
    }
    let shadow = if ls.dist.is_finite() {
        si.spawn_ray_to(ls.p_light)
    } else {
        si.spawn_ray(ls.wi)
    };
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
