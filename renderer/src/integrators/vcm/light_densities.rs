//! The densities vertex connection and merging weighs its light techniques with, for every
//! kind of light (Georgiev 2012, "Implementing vertex connection and merging", section 5.1
//! and eqs. 48-50 for delta lights): how likely next-event estimation is to pick a point or
//! direction of a light (`direct`), and how likely a light subpath is to leave it along a
//! given direction (`emission`, origin and direction together). Each carries the light's
//! selection probability, which next-event estimation and emission share
//! (`Scene::light_sampler`).
//!
//! A delta component (a point light's position, a directional light's direction) is 1 in
//! both, so it cancels; `sample_le` already gives 1 there, `pdf_le` gives 0, which is mapped
//! to 1 here.

use crate::light::emission::{EmittedRay, pdf_le};
use crate::light::{Light, LightLiSample};
use crate::scene::Scene;
use glam::Vec3;

/// What a light subpath's first vertex needs for its MIS quantities.
#[derive(Clone, Copy, Debug)]
pub struct EmissionStart {
    /// Next-event estimation's density of the origin: per area for area lights, per solid
    /// angle for the environment, 1 for delta positions and directional lights.
    pub direct_pdf_a: f32,
    /// The density of the emitted ray, origin and direction.
    pub emission_pdf_w: f32,
    /// The cosine at an area light's surface, 1 for every other light.
    pub cos_light: f32,
}

/// The densities of a ray `e` just emitted by `light`, chosen with probability `pmf`.
pub fn emission_start(light: &Light, pmf: f32, e: &EmittedRay) -> EmissionStart {
    let direct = match light {
        Light::Area(_) => e.pdf_pos,
        Light::Environment(_) => e.pdf_dir,
        Light::Point(_) | Light::Spot(_) | Light::Directional(_) => 1.0,
    };
    let cos_light = match light {
        Light::Area(_) => e.n.dot(e.ray.d).abs(),
        _ => 1.0,
    };
    EmissionStart {
        direct_pdf_a: pmf * direct,
        emission_pdf_w: pmf * e.pdf_pos * e.pdf_dir,
        cos_light,
    }
}

/// For a camera subpath that finds light `index` (an area light it hit, or the environment
/// it escaped to) and would receive it along `w`, the direction of travel of the light:
/// (next-event estimation's density of that point or direction, the density of a light
/// subpath leaving along `w`).
pub fn emitter_hit(scene: &Scene, index: usize, w: Vec3) -> (f32, f32) {
    let light = &scene.lights[index];
    let pmf = scene.light_sampler.pmf(index);
    let (pos, dir) = pdf_le(scene, light, w);
    let direct = match light {
        Light::Environment(_) => dir,
        _ => pos,
    };
    (pmf * direct, pmf * pos * dir)
}

/// Next-event estimation's sample `ls` of light `index` (chosen with probability `pmf`)
/// seen from a point `dist` away: (its solid-angle density at the point, as SmallVCM's
/// `directPdfW`; the density of the light emitting towards the point; the cosine at the
/// light). For point and spot lights the solid-angle density is taken as d^2 (their position
/// is a delta, and `ls.l` already holds I / d^2), so that the ratio of emission to direct
/// density is the emitted ray's area density at the point.
pub fn next_event(scene: &Scene, index: usize, pmf: f32, ls: &LightLiSample) -> (f32, f32, f32) {
    let light = &scene.lights[index];
    let (pos, dir) = pdf_le(scene, light, -ls.wi);
    let (pos, dir) = (
        if pos == 0.0 { 1.0 } else { pos },
        if dir == 0.0 && matches!(light, Light::Directional(_)) {
            1.0
        } else {
            dir
        },
    );
    let direct = match light {
        Light::Point(_) | Light::Spot(_) => ls.dist * ls.dist,
        Light::Directional(_) => 1.0,
        Light::Area(_) | Light::Environment(_) => ls.pdf,
    };
    let cos_at_light = match light {
        Light::Area(_) => ls.n_light.dot(ls.wi).abs(),
        _ => 1.0,
    };
    (pmf * direct, pmf * pos * dir, cos_at_light)
}
