//! The light half of a VCM pass (Georgiev et al. 2012, section 5; the report's algorithm 1):
//! one light subpath per pixel, each non-specular vertex stored for connections and merges
//! with its MIS quantities, and joined to the camera (t = 1) as it is found.

use super::mis::{SubpathMis, weight_light_trace};
use super::techniques::TechniqueShares;
use super::{Pass, light_densities, scatter_with_mis};
use crate::film::sanitize;
use crate::integrators::bdpt::connect::visible;
use crate::integrators::bdpt::vertex::Vertex;
use crate::integrators::{Cancelled, PassStats};
use crate::light::emission::sample_le;
use crate::material::TransportMode;
use crate::sampling::sampler::{SampleSource, Sampler};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Light subpaths draw from their own stream, camera subpaths from the pixel's.
const LIGHT_STREAM: u64 = 0x11c4_7a7b_5eed_0002;

/// A stored vertex of a light subpath: where it is with its BSDF and arrival direction
/// (`Vertex`), the number of edges from the light, and its MIS quantities.
#[derive(Clone, Copy, Debug)]
pub struct LightVertex {
    pub vertex: Vertex,
    pub path_length: u32,
    pub mis: SubpathMis,
}

/// A pass's light subpaths, one per pixel in pixel order.
pub(super) struct LightPaths {
    /// Their non-specular vertices, subpath after subpath.
    pub vertices: Vec<LightVertex>,
    /// Where each subpath's vertices end in `vertices`.
    pub ends: Vec<u32>,
    /// What light tracing brought to the film: (pixel, value), in row order.
    pub splats: Vec<(usize, Vec3)>,
    /// What light tracing brought, by path length (`techniques`).
    pub shares: TechniqueShares,
}

/// The light half of pass `pass`: image rows in parallel, each with its sampler keyed by
/// (seed, pixel, pass) as the camera's, so the result does not depend on the scheduling.
pub(super) fn light_pass(
    setup: &Pass,
    seed: u64,
    pass: u64,
    cancel: &AtomicBool,
    stats: &mut PassStats,
) -> Result<LightPaths, Cancelled> {
    let width = setup.camera.width as usize;
    let height = setup.camera.height as usize;
    let rows: Vec<(LightPaths, PassStats)> = (0..height)
        .into_par_iter()
        .map(|y| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let mut sampler = Sampler::new(seed ^ LIGHT_STREAM);
            let mut row = LightPaths {
                vertices: Vec::new(),
                ends: Vec::with_capacity(width),
                splats: Vec::new(),
                shares: TechniqueShares::default(),
            };
            let mut st = PassStats::default();
            for x in 0..width {
                sampler.start_pixel_sample((y * width + x) as u64, pass);
                let (splats, shares) = (&mut row.splats, &mut row.shares);
                trace_light_subpath(
                    setup,
                    &mut sampler,
                    &mut row.vertices,
                    &mut |edges, pixel, value| {
                        shares.connection(edges, edges, value);
                        splats.push((pixel, value));
                    },
                    &mut st,
                );
                row.ends.push(row.vertices.len() as u32);
            }
            Ok((row, st))
        })
        .collect::<Result<_, _>>()?;
    let mut all = LightPaths {
        vertices: Vec::with_capacity(rows.iter().map(|r| r.0.vertices.len()).sum()),
        ends: Vec::with_capacity(width * height),
        splats: Vec::new(),
        shares: TechniqueShares::default(),
    };
    for (row, st) in rows {
        let offset = all.vertices.len() as u32;
        all.ends.extend(row.ends.iter().map(|e| e + offset));
        all.vertices.extend(row.vertices);
        all.splats.extend(row.splats);
        all.shares.add(&row.shares);
        *stats = *stats + st;
    }
    Ok(all)
}

/// Traces one light subpath: pushes its non-specular vertices to `vertices` (in order of
/// their path length) and hands what each brings to the camera (t = 1) to `to_camera` as
/// (edges, pixel, value).
pub(super) fn trace_light_subpath(
    pass: &Pass,
    sampler: &mut impl SampleSource,
    vertices: &mut Vec<LightVertex>,
    to_camera: &mut impl FnMut(u32, usize, Vec3),
    stats: &mut PassStats,
) {
    let scene = pass.scene;
    let w = &pass.weights;
    let ul = sampler.get_1d();
    let (u_pos, u_dir, u_side) = (sampler.get_2d(), sampler.get_2d(), sampler.get_1d());
    let Some((index, pmf)) = scene.light_sampler.sample(ul) else {
        return;
    };
    let light = &scene.lights[index];
    let Some(e) = sample_le(scene, light, u_pos, u_dir, u_side) else {
        return;
    };
    if !(e.pdf_pos > 0.0 && e.pdf_dir > 0.0 && pmf > 0.0) {
        return;
    }
    let start = light_densities::emission_start(light, pmf, &e);
    let mut mis = SubpathMis::light_start(
        w,
        start.direct_pdf_a,
        start.emission_pdf_w,
        start.cos_light,
        light.is_delta(),
    );
    let mut beta = e.flux() / pmf;
    // Roulette on the throughput relative to the light's power, as bdpt's light subpaths.
    let power = beta.max_element();
    let finite = !light.is_infinite();
    let mut ray = e.ray;
    let mut prev = e.ray.o;
    let mut path_length = 1u32;
    loop {
        stats.rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            return;
        };
        beta *= si.transmittance;
        let dist_sq = (path_length > 1 || finite).then(|| (si.p - prev).length_squared());
        mis.arrive(w, dist_sq, si.n.dot(ray.d));
        let bsdf = scene.bsdf(&si);
        if !bsdf.is_delta() {
            let vertex = LightVertex {
                vertex: Vertex::surface(si, bsdf, beta),
                path_length,
                mis,
            };
            if pass.connections
                && path_length < pass.max_path_length
                && let Some((pixel, value)) = connect_to_camera(pass, &vertex, stats)
            {
                to_camera(vertex.path_length + 1, pixel, value);
            }
            vertices.push(vertex);
        }
        // A vertex further on could still be connected or merged only within the budget.
        if path_length + 2 > pass.max_path_length {
            return;
        }
        let Some(next) =
            scatter_with_mis(w, &mut mis, &si, &bsdf, sampler, TransportMode::Importance)
        else {
            return;
        };
        beta *= next.weight;
        if !beta.is_finite() || beta == Vec3::ZERO {
            return;
        }
        if path_length >= 2 {
            let survive = (beta.max_element() / power).min(1.0);
            if !(sampler.get_1d() < survive) {
                return;
            }
            beta /= survive;
        }
        prev = si.p;
        ray = next.ray;
        path_length += 1;
    }
}

/// Light tracing: the light vertex joined to the camera, (the pixel it lands on, its value).
fn connect_to_camera(pass: &Pass, y: &LightVertex, stats: &mut PassStats) -> Option<(usize, Vec3)> {
    let (scene, camera) = (pass.scene, pass.camera);
    let v = &y.vertex;
    let (Some(si), Some(bsdf)) = (&v.si, &v.bsdf) else {
        return None;
    };
    let cs = camera.sample_wi(v.p)?;
    let pinhole = Vertex::camera(cs.p_camera, Vec3::splat(cs.importance / cs.pdf));
    let l =
        v.beta * v.f(&pinhole, TransportMode::Importance) * pinhole.beta * cs.wi.dot(v.ns).abs();
    if l == Vec3::ZERO {
        return None;
    }
    let camera_pdf_a = camera.pdf_first_hit(cs.p_camera, v.p, Some(v.ng));
    let rev_pdf = bsdf.pdf(si.shading.to_local(cs.wi), si.shading.to_local(si.wo));
    let weight = weight_light_trace(&pass.weights, &y.mis, camera_pdf_a, rev_pdf);
    if !visible(scene, v, &pinhole, &mut stats.rays) {
        return None;
    }
    let Some(value) = sanitize(l * weight) else {
        stats.dropped += 1;
        return None;
    };
    let (x, yy) = (cs.raster.x as usize, cs.raster.y as usize);
    Some((yy * camera.width as usize + x, value))
}
