//! A survey of a scene's light transport: a few thousand camera paths and light paths, which
//! take milliseconds, measure what decides between the estimators (the advisor, `advisor.rs`,
//! draws the conclusions; the photon mappers take their automatic radius from the view):
//!
//! - how much of the view is seen through specular surfaces (paths E S+ D: glass, mirrors),
//! - how much of the light reaching diffuse or glossy surfaces has passed specular ones first
//!   (L S+ D: caustics), and how much of that comes from delta lights (point, spot,
//!   directional); and the same share of the light reaching the surfaces the camera sees
//!   (directly or through specular chains), which is what decides: a caustic in a closed
//!   closet matters as little as any light there, a caustic under the glass the camera looks
//!   through is the image,
//! - how much of what the camera sees has a light in direct view (the rest is lit through
//!   openings or by interreflection only), and how much of it is glossy,
//! - how far away the camera sees surfaces, through specular chains.

use crate::camera::Camera;
use crate::integrators::path_tracer::sample_direct;
use crate::integrators::scatter;
use crate::light::emission::emit_photon;
use crate::material::{Bsdf, TransportMode};
use crate::sampling::sampler::Sampler;
use crate::scene::Scene;
use glam::{IVec3, Vec2, Vec3};
use std::collections::HashSet;

/// Bounces followed through specular surfaces before a path is given up.
const MAX_SPECULAR_DEPTH: u32 = 16;
/// Microfacet roughness (alpha) below which a surface counts as glossy.
const GLOSSY_ALPHA: f32 = 0.2;

/// What a survey of camera and light paths found.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TransportSurvey {
    pub camera_paths: usize,
    pub light_paths: usize,
    /// Of the camera paths that reach a non-specular surface, the share that got there
    /// through at least one specular bounce (E S+ D).
    pub seen_through_specular: f64,
    /// Of the same, the share whose surface is glossy (a microfacet lobe with alpha < 0.2).
    pub glossy: f64,
    /// Of the same, the share with a light in direct view (a next-event sample unoccluded).
    pub directly_lit: f64,
    /// The share of the camera paths that reach no surface (background, escaped).
    pub background: f64,
    /// Of the lights' power, the share in delta lights (point, spot, directional).
    pub delta_light_power: f64,
    /// Of the flux photons bring to their first non-specular surface, the share that passed
    /// at least one specular surface first (L S+ D).
    pub caustic_flux: f64,
    /// The part of `caustic_flux` that comes from delta lights.
    pub delta_caustic_flux: f64,
    /// `caustic_flux` of the light that lands where the camera sees (within about two spacings
    /// of the camera paths' first non-specular vertices): the share of the seen surfaces'
    /// first-bounce light that is caustic.
    pub seen_caustic_flux: f64,
    /// Of the flux photons bring to their first non-specular surface, the share that lands
    /// where the camera sees.
    pub seen_flux: f64,
    /// Median length of the camera paths to their first non-specular vertex (scene units).
    pub median_hit_distance: f64,
}

fn is_glossy(bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::MetallicRoughness(m) => m.distrib.alpha < GLOSSY_ALPHA,
        _ => false,
    }
}

/// Traces `camera_paths` camera paths (stratified over the image) and `light_paths` light
/// paths; deterministic for a given seed.
pub fn survey(
    scene: &Scene,
    camera: &Camera,
    camera_paths: usize,
    light_paths: usize,
    seed: u64,
) -> TransportSurvey {
    let mut s = TransportSurvey {
        camera_paths,
        light_paths,
        ..Default::default()
    };
    let (view, seen) = view_and_seen_cells(scene, camera, camera_paths, seed);
    s.seen_through_specular = view.seen_through_specular;
    s.glossy = view.glossy;
    s.directly_lit = view.directly_lit;
    s.background = view.background;
    s.median_hit_distance = view.median_hit_distance;
    let mut sampler = Sampler::new(seed ^ 0x5a7e_e7a1_0000_0002);

    // Light paths, lights chosen by power as the photon mappers choose them.
    let total_power: f64 = (0..scene.lights.len())
        .map(|i| scene.light_sampler.pmf(i) as f64)
        .sum();
    s.delta_light_power = if total_power > 0.0 {
        (0..scene.lights.len())
            .filter(|&i| scene.lights[i].is_delta())
            .map(|i| scene.light_sampler.pmf(i) as f64)
            .sum::<f64>()
            / total_power
    } else {
        0.0
    };
    let (mut flux_all, mut flux_caustic, mut flux_delta_caustic) = (0.0f64, 0.0f64, 0.0f64);
    let (mut flux_seen, mut flux_seen_caustic) = (0.0f64, 0.0f64);
    for i in 0..light_paths {
        sampler.start_pixel_sample(i as u64, 1);
        let Some((light, mut ray, mut flux)) = emit_photon(scene, &mut sampler) else {
            continue;
        };
        for depth in 0..=MAX_SPECULAR_DEPTH {
            let Some(si) = scene.intersect(&ray) else {
                break;
            };
            let bsdf = scene.bsdf(&si);
            if !bsdf.is_delta() {
                let power = crate::geometry::luminance(flux) as f64;
                if power.is_finite() {
                    flux_all += power;
                    let is_seen = seen.contains(si.p, facing(si.n, -ray.d));
                    if is_seen {
                        flux_seen += power;
                    }
                    if depth > 0 {
                        flux_caustic += power;
                        if is_seen {
                            flux_seen_caustic += power;
                        }
                        if scene.lights[light].is_delta() {
                            flux_delta_caustic += power;
                        }
                    }
                }
                break;
            }
            let wo = si.shading.to_local(si.wo);
            let Some(next) = scatter(&si, &bsdf, wo, &mut sampler, TransportMode::Importance)
            else {
                break;
            };
            flux *= next.weight;
            ray = next.ray;
        }
    }
    if flux_all > 0.0 {
        s.caustic_flux = flux_caustic / flux_all;
        s.delta_caustic_flux = flux_delta_caustic / flux_all;
        s.seen_flux = flux_seen / flux_all;
    }
    if flux_seen > 0.0 {
        s.seen_caustic_flux = flux_seen_caustic / flux_seen;
    }
    s
}

/// Cells of a grid around the camera paths' first non-specular vertices: a point is seen if
/// its cell is one of them on the same side of the surface. The cell is twice the vertices'
/// spacing on a surface facing the camera at their median distance (the paths are fewer than
/// the pixels), and each vertex marks its cell and the 26 around it, so a point within about
/// two spacings of one counts. The side (the axis and sign nearest the normal facing where
/// the path came from) keeps the far face of a thin wall apart: without it the closet behind
/// the gap-and-glass scene's partition counted as seen, and with it half the light.
struct SeenCells {
    cell: f32,
    cells: HashSet<(IVec3, u8)>,
}

/// The axis and sign nearest `n` (0..6).
fn side(n: Vec3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    2 * axis + u8::from(n[axis as usize] < 0.0)
}

/// The geometric normal on the side `towards` points to.
fn facing(n: Vec3, towards: Vec3) -> Vec3 {
    if n.dot(towards) < 0.0 { -n } else { n }
}

impl SeenCells {
    fn new(points: &[(Vec3, Vec3)], spacing: f64) -> Self {
        let cell = (2.0 * spacing) as f32;
        let mut cells = HashSet::new();
        if cell > 0.0 && cell.is_finite() {
            for (p, n) in points {
                let c = (*p / cell).floor().as_ivec3();
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            cells.insert((c + IVec3::new(dx, dy, dz), side(*n)));
                        }
                    }
                }
            }
        }
        Self { cell, cells }
    }

    /// Whether the point `p` on a surface whose normal on the side it is seen or lit from is
    /// `n` is near a camera path's vertex on the same side.
    fn contains(&self, p: Vec3, n: Vec3) -> bool {
        !self.cells.is_empty()
            && self
                .cells
                .contains(&((p / self.cell).floor().as_ivec3(), side(n)))
    }
}

/// The camera half of the survey and the cells it sees.
fn view_and_seen_cells(
    scene: &Scene,
    camera: &Camera,
    paths: usize,
    seed: u64,
) -> (TransportSurvey, SeenCells) {
    let mut points = Vec::new();
    let view = camera_half(scene, camera, paths, seed, Some(&mut points));
    let pixels = camera.width as f64 * camera.height as f64;
    let spacing = camera
        .desc()
        .pixel_size(view.median_hit_distance, camera.height)
        * (pixels / paths.max(1) as f64).sqrt();
    (view, SeenCells::new(&points, spacing))
}

/// The camera half of the survey: `paths` camera paths on a jittered grid over the image,
/// followed through specular bounces to their first non-specular vertex (or given up after
/// `MAX_SPECULAR_DEPTH`); fills the view's shares and the median hit distance.
pub fn survey_view(scene: &Scene, camera: &Camera, paths: usize, seed: u64) -> TransportSurvey {
    camera_half(scene, camera, paths, seed, None)
}

/// `survey_view`, which also collects the first non-specular vertices in `points`.
fn camera_half(
    scene: &Scene,
    camera: &Camera,
    paths: usize,
    seed: u64,
    mut points: Option<&mut Vec<(Vec3, Vec3)>>,
) -> TransportSurvey {
    let mut s = TransportSurvey {
        camera_paths: paths,
        ..Default::default()
    };
    let camera_paths = paths;
    let mut sampler = Sampler::new(seed ^ 0x5a7e_e7a1_0000_0001);
    let mut rays = 0u64;
    // Camera paths on a jittered grid over the image.
    let side = (camera_paths as f64).sqrt().ceil().max(1.0) as usize;
    let (mut surfaces, mut through, mut glossy, mut lit) = (0usize, 0usize, 0usize, 0usize);
    let mut distances = Vec::new();
    for i in 0..camera_paths {
        sampler.start_pixel_sample(i as u64, 0);
        let cell = Vec2::new((i % side) as f32, (i / side % side) as f32);
        let film = (cell + sampler.get_2d()) / side as f32
            * Vec2::new(camera.width as f32, camera.height as f32);
        let mut ray = camera.generate_ray(film);
        let mut length = 0.0f32;
        for depth in 0..=MAX_SPECULAR_DEPTH {
            let Some(si) = scene.intersect(&ray) else {
                break;
            };
            length += si.t * ray.d.length();
            let bsdf = scene.bsdf(&si);
            let wo = si.shading.to_local(si.wo);
            if !bsdf.is_delta() {
                surfaces += 1;
                through += usize::from(depth > 0);
                glossy += usize::from(is_glossy(&bsdf));
                distances.push(length as f64);
                if let Some(points) = points.as_deref_mut() {
                    points.push((si.p, facing(si.n, -ray.d)));
                }
                let seen = (0..4).any(|_| {
                    sample_direct(scene, &si, &bsdf, wo, &mut sampler, &mut rays, false)
                        .max_element()
                        > 0.0
                });
                lit += usize::from(seen);
                break;
            }
            let Some(next) = scatter(&si, &bsdf, wo, &mut sampler, TransportMode::Radiance) else {
                break;
            };
            ray = next.ray;
        }
    }
    let share = |n: usize, of: usize| if of > 0 { n as f64 / of as f64 } else { 0.0 };
    s.seen_through_specular = share(through, surfaces);
    s.glossy = share(glossy, surfaces);
    s.directly_lit = share(lit, surfaces);
    s.background = share(camera_paths - surfaces, camera_paths);
    distances.sort_by(f64::total_cmp);
    s.median_hit_distance = distances.get(distances.len() / 2).copied().unwrap_or(0.0);

    s
}

/// The standard survey (4096 camera paths, 8192 light paths) for a `width` x `height` image.
pub fn survey_at(scene: &Scene, width: u32, height: u32) -> TransportSurvey {
    let camera = Camera::new(&scene.camera, width, height);
    survey(scene, &camera, 4096, 8192, 1)
}
