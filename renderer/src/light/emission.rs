//! Emission sampling for light tracing (pbrt-v4's `Light::SampleLe` and `PDF_Le`, section
//! 12.1): a light subpath's first ray with its emitted radiance and the densities of its
//! origin (area measure) and direction (solid angle), for every kind of light. A photon's
//! power weight is Le cos / (pmf pdf_pos pdf_dir). Infinite lights start their rays on a disc
//! as wide as the scene's bounding sphere (pdf_pos = 1 / (pi r^2)). Delta densities (a point
//! light's position, a directional light's direction) are 1 here and 0 from `pdf_le`, as in
//! pbrt, so that BDPT's MIS treats them as unsampleable.

use crate::geometry::{Frame, Ray, offset_ray_origin};
use crate::light::Light;
use crate::sampling::warp::{
    sample_cosine_hemisphere, sample_uniform_cone, sample_uniform_disk_concentric,
    sample_uniform_sphere, sample_uniform_triangle, uniform_cone_pdf, uniform_sphere_pdf,
};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A ray leaving a light.
#[derive(Clone, Copy, Debug)]
pub struct EmittedRay {
    pub ray: Ray,
    /// Emitted radiance (area and environment lights), intensity (point, spot) or irradiance
    /// (directional) along the ray.
    pub le: Vec3,
    /// The emitting surface's normal (the disc's for infinite lights), zero for points.
    pub n: Vec3,
    /// Density of the origin, area measure (1 for a delta position).
    pub pdf_pos: f32,
    /// Density of the direction, solid angle (1 for a delta direction).
    pub pdf_dir: f32,
}

impl EmittedRay {
    /// The ray's power weight Le |cos| / (pdf_pos pdf_dir), before the light's selection pmf.
    pub fn flux(&self) -> Vec3 {
        let cos = if self.n == Vec3::ZERO {
            1.0
        } else {
            self.n.dot(self.ray.d).abs()
        };
        self.le * (cos / (self.pdf_pos * self.pdf_dir))
    }
}

/// A photon: a light chosen in proportion to power, a ray leaving it, and the photon's flux
/// (the ray's power weight over the light's selection probability). Draws five uniform
/// numbers from `sampler`, in the order the photon mappers have always drawn them.
pub fn emit_photon(
    scene: &Scene,
    sampler: &mut impl crate::sampling::sampler::SampleSource,
) -> Option<(usize, Ray, Vec3)> {
    let (light, pmf) = scene.light_sampler.sample(sampler.get_1d())?;
    let (u_pos, u_dir, u_side) = (sampler.get_2d(), sampler.get_2d(), sampler.get_1d());
    let emitted = sample_le(scene, &scene.lights[light], u_pos, u_dir, u_side)?;
    Some((light, emitted.ray, emitted.flux() / pmf))
}

/// Samples a ray leaving `light` with uniform numbers `u_pos`, `u_dir` and `u_side`.
pub fn sample_le(
    scene: &Scene,
    light: &Light,
    u_pos: Vec2,
    u_dir: Vec2,
    u_side: f32,
) -> Option<EmittedRay> {
    let (center, radius) = scene.bounds.bounding_sphere();
    let radius = radius.max(1e-6);
    match light {
        Light::Area(a) => {
            let b = sample_uniform_triangle(u_pos);
            let (p, uv) = a.point(b);
            // A two-sided emitter picks its side with probability 1/2.
            let (n, side_pdf) = if a.two_sided {
                (if u_side < 0.5 { a.normal } else { -a.normal }, 0.5)
            } else {
                (a.normal, 1.0)
            };
            let local = sample_cosine_hemisphere(u_dir);
            let d = Frame::from_z(n).from_local(local);
            let le = a.l_sampled(&scene.textures, &uv, d);
            let p_error = crate::scene::triangle::hit_point_and_error(&a.positions, b).1;
            (le.max_element() > 0.0 && local.z > 0.0).then(|| EmittedRay {
                ray: Ray::new(offset_ray_origin(p, p_error, n, d), d),
                le,
                n,
                pdf_pos: 1.0 / a.area,
                pdf_dir: local.z / PI * side_pdf,
            })
        }
        Light::Point(l) => {
            let d = sample_uniform_sphere(u_dir);
            Some(EmittedRay {
                ray: Ray::new(l.position, d),
                le: l.intensity,
                n: Vec3::ZERO,
                pdf_pos: 1.0,
                pdf_dir: uniform_sphere_pdf(),
            })
        }
        Light::Spot(s) => {
            let local = sample_uniform_cone(u_dir, s.cos_outer);
            let d = s.frame.from_local(local);
            let le = s.intensity * s.falloff(local.z);
            (le.max_element() > 0.0).then(|| EmittedRay {
                ray: Ray::new(s.position, d),
                le,
                n: Vec3::ZERO,
                pdf_pos: 1.0,
                pdf_dir: uniform_cone_pdf(s.cos_outer),
            })
        }
        Light::Directional(l) => {
            // A disc as wide as the scene, upstream of it, facing the light's direction.
            let frame = Frame::from_z(l.direction);
            let disk = sample_uniform_disk_concentric(u_pos) * radius;
            let o = center - l.direction * radius + frame.s * disk.x + frame.t * disk.y;
            Some(EmittedRay {
                ray: Ray::new(o, l.direction),
                le: l.irradiance,
                n: l.direction,
                pdf_pos: 1.0 / (PI * radius * radius),
                pdf_dir: 1.0,
            })
        }
        Light::Environment(e) => {
            // Direction towards the environment, then a disc across the scene (pbrt-v4 12.5).
            let (to_env, pdf_dir) = e.sample_direction(u_dir)?;
            let frame = Frame::from_z(-to_env);
            let disk = sample_uniform_disk_concentric(u_pos) * radius;
            let o = center + to_env * radius + frame.s * disk.x + frame.t * disk.y;
            let le = e.le(to_env);
            (le.max_element() > 0.0).then(|| EmittedRay {
                ray: Ray::new(o, -to_env),
                le,
                n: -to_env,
                pdf_pos: 1.0 / (PI * radius * radius),
                pdf_dir,
            })
        }
    }
}

/// Densities with which `sample_le` would emit along direction `w` (unit) from a point of
/// `light`: (pdf_pos, pdf_dir). Delta components are 0. For infinite lights `w` is the
/// direction of travel.
pub fn pdf_le(scene: &Scene, light: &Light, w: Vec3) -> (f32, f32) {
    let radius = scene.bounds.bounding_sphere().1.max(1e-6);
    match light {
        Light::Area(a) => {
            let cos = a.normal.dot(w);
            let pdf_dir = if a.two_sided {
                0.5 * cos.abs() / PI
            } else if cos > 0.0 {
                cos / PI
            } else {
                0.0
            };
            (1.0 / a.area, pdf_dir)
        }
        Light::Point(_) => (0.0, uniform_sphere_pdf()),
        Light::Spot(s) => {
            let inside = w.dot(s.frame.n) > s.cos_outer;
            (
                0.0,
                if inside {
                    uniform_cone_pdf(s.cos_outer)
                } else {
                    0.0
                },
            )
        }
        Light::Directional(_) => (1.0 / (PI * radius * radius), 0.0),
        Light::Environment(e) => (1.0 / (PI * radius * radius), e.pdf_li(-w)),
    }
}
