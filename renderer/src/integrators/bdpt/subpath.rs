//! Generating camera and light subpaths by random walks (pbrt-v3 section 16.3.2), recording
//! at every vertex the forward density and, once the next direction is sampled, the reverse
//! density of the vertex before it.

use crate::camera::Camera;
use crate::integrators::bdpt::vertex::{Vertex, infinite_light_density};
use crate::integrators::scatter;
use crate::light::emission::sample_le;
use crate::material::TransportMode;
use crate::sampling::sampler::SampleSource;
use crate::scene::Scene;
use glam::{Vec2, Vec3};

/// How a walk ends besides its vertex budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Termination {
    /// Russian roulette on the subpath's throughput relative to its start, from the third
    /// vertex on (BDPT), as the path tracer's.
    Roulette,
    /// Exactly the budget or nothing (MMLT's chains have a fixed path length).
    Fixed,
}

/// What the walks of one path sample share: the scene, the sample source, how walks end and
/// the count of rays they trace.
pub struct Walker<'a, S> {
    pub scene: &'a Scene,
    pub sampler: &'a mut S,
    pub termination: Termination,
    pub rays: &'a mut u64,
}

impl<S: SampleSource> Walker<'_, S> {
    /// A camera subpath of at most `max_vertices` (at least 1) vertices through film
    /// position `film`.
    pub fn camera_subpath(
        &mut self,
        camera: &Camera,
        film: Vec2,
        max_vertices: usize,
        path: &mut Vec<Vertex>,
    ) {
        debug_assert!(
            max_vertices > 0,
            "a camera subpath holds at least the camera"
        );
        path.clear();
        let ray = camera.generate_ray(film);
        // W_e cos / (pdf_pos pdf_dir) = 1 for either camera with a uniform film sample.
        path.push(Vertex::camera(ray.o, Vec3::ONE));
        let pdf_dir = camera.pdf_we_dir(ray.d);
        let start = (Vec3::ONE, pdf_dir);
        self.random_walk(ray, start, max_vertices, TransportMode::Radiance, path);
        // The orthographic camera's first hit has an area density without distance falloff,
        // which the walk's solid-angle conversion cannot express.
        if camera.is_orthographic() && path.len() > 1 {
            path[1].pdf_fwd = path[0].pdf(self.scene, camera, None, &path[1]);
        }
    }

    /// A light subpath of at most `max_vertices` vertices from a light chosen by power.
    pub fn light_subpath(&mut self, max_vertices: usize, path: &mut Vec<Vertex>) {
        path.clear();
        if max_vertices == 0 {
            return;
        }
        let (scene, sampler) = (self.scene, &mut *self.sampler);
        let ul = sampler.get_1d();
        let (u_pos, u_dir, u_side) = (sampler.get_2d(), sampler.get_2d(), sampler.get_1d());
        let Some((index, pmf)) = scene.light_sampler.sample(ul) else {
            return;
        };
        let Some(e) = sample_le(scene, &scene.lights[index], u_pos, u_dir, u_side) else {
            return;
        };
        if !(e.pdf_pos > 0.0 && e.pdf_dir > 0.0 && pmf > 0.0) {
            return;
        }
        path.push(Vertex::light(
            Some(index),
            e.ray.o,
            e.n,
            e.le,
            e.pdf_pos * pmf,
        ));
        let start = (e.flux() / pmf, e.pdf_dir);
        self.random_walk(e.ray, start, max_vertices, TransportMode::Importance, path);
        if scene.lights[index].is_infinite() {
            // The first surface's density is the disc's area density projected onto it, and the
            // light's own is directional (pbrt-v3 section 16.3.2).
            if path.len() > 1 {
                let cos = if path[1].is_on_surface() {
                    path[1].ng.dot(e.ray.d).abs()
                } else {
                    1.0
                };
                path[1].pdf_fwd = e.pdf_pos * cos;
            }
            path[0].pdf_fwd = infinite_light_density(scene, e.ray.d);
        }
    }

    /// Extends `path` (which holds the subpath's first vertex) until it has `max_vertices`,
    /// starting with throughput and direction density `(beta, pdf_dir)` along `ray`.
    fn random_walk(
        &mut self,
        mut ray: crate::geometry::Ray,
        (mut beta, pdf_dir): (Vec3, f32),
        max_vertices: usize,
        mode: TransportMode,
        path: &mut Vec<Vertex>,
    ) {
        let (scene, sampler) = (self.scene, &mut *self.sampler);
        let mut pdf_fwd = pdf_dir;
        // Roulette compares the throughput with where it started (a light subpath starts at
        // the light's power), with the 1/eta^2 of radiance through refractions factored out
        // (pbrt-v4 section 13.4.4), so that it ends paths whose contribution has become
        // small, not those that merely passed a surface that compresses radiance.
        let start = beta.max_element();
        let mut eta_scale = 1.0f32;
        while path.len() < max_vertices {
            *self.rays += 1;
            let Some(si) = scene.intersect(&ray) else {
                // A camera ray that escapes reaches the environment: a light vertex at infinity.
                if mode == TransportMode::Radiance && scene.environment.is_some() {
                    path.push(Vertex::light(None, ray.o + ray.d, -ray.d, beta, pdf_fwd));
                }
                return;
            };
            beta *= si.transmittance;
            let bsdf = scene.bsdf(&si);
            let mut vertex = Vertex::surface(si, bsdf, beta);
            let prev = path.last().expect("a subpath starts with its endpoint");
            vertex.pdf_fwd = prev.convert_density(pdf_fwd, &vertex, scene);
            path.push(vertex);
            if path.len() >= max_vertices {
                return;
            }
            let wo = si.shading.to_local(si.wo);
            let Some(next) = scatter(&si, &bsdf, wo, sampler, mode) else {
                return;
            };
            pdf_fwd = next.sample.pdf;
            let mut pdf_rev = bsdf.pdf(next.sample.wi, wo);
            let n = path.len();
            if next.sample.is_delta {
                path[n - 1].delta = true;
                pdf_fwd = 0.0;
                pdf_rev = 0.0;
            }
            beta *= next.weight;
            if mode == TransportMode::Radiance && next.sample.eta != 1.0 {
                eta_scale *= next.sample.eta * next.sample.eta;
            }
            if !beta.is_finite() || beta == Vec3::ZERO {
                return;
            }
            if self.termination == Termination::Roulette && n >= 3 {
                let survive = (beta.max_element() * eta_scale / start).min(1.0);
                if !(sampler.get_1d() < survive) {
                    return;
                }
                beta /= survive;
            }
            let (head, tail) = path.split_at_mut(n - 1);
            head[n - 2].pdf_rev = tail[0].convert_density(pdf_rev, &head[n - 2], scene);
            ray = next.ray;
        }
    }
}
