//! Emission sampling for light tracing (pbrt-v4's `Light::SampleLe`, section 12.1): a photon's
//! first ray and its power weight Le cos / (pmf pdf_pos pdf_dir), for every kind of light.

use crate::geometry::{Frame, Ray, offset_ray_origin};
use crate::light::Light;
use crate::sampling::warp::{
    sample_cosine_hemisphere, sample_uniform_cone, sample_uniform_disk_concentric,
    sample_uniform_sphere, sample_uniform_triangle, uniform_cone_pdf, uniform_sphere_pdf,
};
use crate::scene::Scene;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// A photon leaving a light: its ray and flux (already divided by every pdf but the light's
/// selection probability, which the caller divides by).
#[derive(Clone, Copy, Debug)]
pub struct EmittedPhoton {
    pub ray: Ray,
    pub flux: Vec3,
}

/// Samples an emitted photon from `light` with uniform numbers `u_pos`, `u_dir` and `u_side`.
pub fn sample_le(
    scene: &Scene,
    light: &Light,
    u_pos: Vec2,
    u_dir: Vec2,
    u_side: f32,
) -> Option<EmittedPhoton> {
    let (center, radius) = scene.bounds.bounding_sphere();
    let radius = radius.max(1e-6);
    match light {
        Light::Area(a) => {
            let b = sample_uniform_triangle(u_pos);
            let (p, uv) = scene.triangle_point(a.triangle, b);
            // A two-sided emitter picks its side with probability 1/2.
            let (n, side_pdf) = if a.two_sided {
                (if u_side < 0.5 { a.normal } else { -a.normal }, 0.5)
            } else {
                (a.normal, 1.0)
            };
            let local = sample_cosine_hemisphere(u_dir);
            let d = Frame::from_z(n).from_local(local);
            let le = a.l(scene, uv, d);
            // Le cos / (pdf_pos pdf_dir) = Le cos / ((1 / area) (cos / pi) side_pdf).
            let flux = le * (PI * a.area / side_pdf);
            let p_error = crate::scene::triangle::hit_point_and_error(
                &scene.positions[a.triangle as usize],
                b,
            )
            .1;
            (flux.max_element() > 0.0).then(|| EmittedPhoton {
                ray: Ray::new(offset_ray_origin(p, p_error, n, d), d),
                flux,
            })
        }
        Light::Point(l) => {
            let d = sample_uniform_sphere(u_dir);
            Some(EmittedPhoton {
                ray: Ray::new(l.position, d),
                flux: l.intensity / uniform_sphere_pdf(),
            })
        }
        Light::Spot(s) => {
            let local = sample_uniform_cone(u_dir, s.cos_outer);
            let d = s.frame.from_local(local);
            let flux = s.intensity * s.falloff(local.z) / uniform_cone_pdf(s.cos_outer);
            (flux.max_element() > 0.0).then(|| EmittedPhoton {
                ray: Ray::new(s.position, d),
                flux,
            })
        }
        Light::Directional(l) => {
            // A disc as wide as the scene, upstream of it, facing the light's direction.
            let frame = Frame::from_z(l.direction);
            let disk = sample_uniform_disk_concentric(u_pos) * radius;
            let o = center - l.direction * radius + frame.s * disk.x + frame.t * disk.y;
            Some(EmittedPhoton {
                ray: Ray::new(o, l.direction),
                flux: l.irradiance * (PI * radius * radius),
            })
        }
        Light::Environment(e) => {
            // Direction towards the environment, then a disc across the scene (pbrt-v4 12.5).
            let to_env = sample_uniform_sphere(u_dir);
            let frame = Frame::from_z(-to_env);
            let disk = sample_uniform_disk_concentric(u_pos) * radius;
            let o = center + to_env * radius + frame.s * disk.x + frame.t * disk.y;
            let flux = e.radiance * (PI * radius * radius) / uniform_sphere_pdf();
            Some(EmittedPhoton {
                ray: Ray::new(o, -to_env),
                flux,
            })
        }
    }
}
