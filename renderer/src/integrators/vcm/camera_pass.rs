//! The camera half of a VCM pass (Georgiev et al. 2012, section 5): one camera subpath per
//! pixel; at each vertex emission found (s = 0), next-event estimation (s = 1), connections
//! to every vertex of the pixel's own light subpath, and merges with the light vertices of
//! every subpath within the pass's radius, each weighted by `mis`.

use super::light_pass::LightVertex;
use super::mis::{
    SubpathMis, weight_connection, weight_emission_hit, weight_merge, weight_next_event,
};
use super::techniques::TechniqueShares;
use super::{Pass, light_densities, scatter_with_mis};
use crate::film::sanitize;
use crate::integrators::bdpt::connect::{geometry_term, visible};
use crate::integrators::bdpt::vertex::Vertex;
use crate::integrators::{Cancelled, PassStats};
use crate::material::TransportMode;
use crate::sampling::sampler::{SampleSource, Sampler};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// What one camera subpath brings its pixel.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CameraSample {
    /// Every technique's weighted contribution.
    pub value: Vec3,
    /// The merges' part of it before their normalisation 1 / (pi r^2 N_L), and the part of
    /// that from light vertices within the inner radius (`kernel_bias`).
    pub merged: Vec3,
    pub merged_inner: Vec3,
}

/// The camera half's skeleton: image rows of `buffer` in parallel, each pixel's sampler keyed
/// by (seed, pixel, pass) as `pixel_pass`'s and its film position jittered, cancellation
/// checked per row. `per_pixel` traces a pixel's subpath with its row's own state (from
/// `new_row`); each row's state, counters and technique shares come back in row order.
#[allow(clippy::type_complexity)]
pub(super) fn camera_rows<R: Send>(
    buffer: &mut [CameraSample],
    setup: &Pass,
    (seed, pass): (u64, u64),
    cancel: &AtomicBool,
    new_row: impl Fn() -> R + Sync,
    per_pixel: impl Fn(
        &mut R,
        usize,
        Vec2,
        &mut Sampler,
        &mut PassStats,
        &mut TechniqueShares,
    ) -> CameraSample
    + Sync,
) -> Result<Vec<(R, PassStats, TechniqueShares)>, Cancelled> {
    let width = setup.camera.width as usize;
    buffer
        .par_chunks_mut(width.max(1))
        .enumerate()
        .map(|(y, row)| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let mut sampler = Sampler::new(seed);
            let mut state = new_row();
            let mut stats = PassStats::default();
            let mut shares = TechniqueShares::default();
            for (x, out) in row.iter_mut().enumerate() {
                let pixel = y * width + x;
                sampler.start_pixel_sample(pixel as u64, pass);
                let film = Vec2::new(x as f32, y as f32) + sampler.get_2d();
                *out = per_pixel(
                    &mut state,
                    pixel,
                    film,
                    &mut sampler,
                    &mut stats,
                    &mut shares,
                );
                stats.samples += 1;
            }
            Ok((state, stats, shares))
        })
        .collect()
}

/// One camera subpath through film position `film`, whose pixel's light subpath is
/// `own_light_path`: every technique of vcm.
pub(super) fn trace_camera_subpath(
    pass: &Pass,
    film: Vec2,
    own_light_path: &[LightVertex],
    sampler: &mut impl SampleSource,
    stats: &mut PassStats,
    shares: &mut TechniqueShares,
) -> CameraSample {
    trace_camera_techniques(
        pass,
        film,
        sampler,
        stats,
        shares,
        |x, out, stats, shares| {
            if pass.connections {
                for y in own_light_path {
                    if y.path_length + 1 + x.path_length > pass.max_path_length {
                        break;
                    }
                    let v = connect(pass, x, y, stats);
                    if let Some(v) = add(&mut out.value, v, stats) {
                        shares.connection(y.path_length + 1 + x.path_length, y.path_length + 1, v);
                    }
                }
            }
            if pass.merges {
                let (outer, inner) = merge(pass, x, shares);
                match (sanitize(outer), sanitize(inner)) {
                    (Some(outer), Some(inner)) => {
                        out.value += outer * pass.merge_normalization;
                        out.merged += outer;
                        out.merged_inner += inner;
                    }
                    _ => stats.dropped += 1,
                }
            }
        },
    )
}

/// One camera subpath through film position `film` with the techniques of its own vertices:
/// emission it finds (s = 0) and next-event estimation (s = 1); at each non-specular vertex
/// `with_light_subpaths` adds the techniques that need light subpaths (connections, merges).
pub(super) fn trace_camera_techniques(
    pass: &Pass,
    film: Vec2,
    sampler: &mut impl SampleSource,
    stats: &mut PassStats,
    shares: &mut TechniqueShares,
    mut with_light_subpaths: impl FnMut(
        &CameraVertex,
        &mut CameraSample,
        &mut PassStats,
        &mut TechniqueShares,
    ),
) -> CameraSample {
    let (scene, camera, w) = (pass.scene, pass.camera, &pass.weights);
    let mut ray = camera.generate_ray(film);
    let mut beta = Vec3::ONE;
    let mut mis = SubpathMis::default();
    let mut path_length = 1u32;
    // Every scattering so far was specular: what merging alone cannot see.
    let mut specular_path = true;
    let mut eta_scale = 1.0f32;
    let mut out = CameraSample::default();
    loop {
        stats.rays += 1;
        let Some(si) = scene.intersect(&ray) else {
            if let Some(env) = scene.environment {
                let le = scene.environment_radiance(ray.d);
                if le != Vec3::ZERO {
                    let weight = emission_weight(pass, &mis, path_length, specular_path, || {
                        light_densities::emitter_hit(scene, env, -ray.d)
                    });
                    if let Some(v) = add(&mut out.value, beta * le * weight, stats) {
                        shares.connection(path_length, 0, v);
                    }
                }
            }
            break;
        };
        beta *= si.transmittance;
        if path_length == 1 {
            let pdf = camera.pdf_first_hit(ray.o, si.p, Some(si.n));
            if !(pdf > 0.0) {
                break;
            }
            mis = SubpathMis::camera_first_hit(w, pdf);
        } else {
            mis.arrive(w, Some((si.p - ray.o).length_squared()), si.n.dot(ray.d));
        }
        if let Some((index, area)) = scene.area_light(&si) {
            let le = area.l(&scene.textures, &si.uv, si.wo);
            if le != Vec3::ZERO {
                let weight = emission_weight(pass, &mis, path_length, specular_path, || {
                    light_densities::emitter_hit(scene, index, si.wo)
                });
                if let Some(v) = add(&mut out.value, beta * le * weight, stats) {
                    shares.connection(path_length, 0, v);
                }
            }
        }
        if path_length >= pass.max_path_length {
            break;
        }
        let bsdf = scene.bsdf(&si);
        if !bsdf.is_delta() {
            let x = Vertex::surface(si, bsdf, beta);
            let camera_vertex = CameraVertex {
                vertex: &x,
                mis: &mis,
                path_length,
            };
            if pass.connections && path_length < pass.max_path_length {
                let v = next_event(pass, &camera_vertex, sampler, stats);
                if let Some(v) = add(&mut out.value, v, stats) {
                    shares.connection(path_length + 1, 1, v);
                }
            }
            with_light_subpaths(&camera_vertex, &mut out, stats, shares);
        }
        let Some(next) =
            scatter_with_mis(w, &mut mis, &si, &bsdf, sampler, TransportMode::Radiance)
        else {
            break;
        };
        specular_path &= next.sample.is_delta;
        beta *= next.weight;
        if next.sample.eta != 1.0 {
            eta_scale *= next.sample.eta * next.sample.eta;
        }
        if !beta.is_finite() || beta == Vec3::ZERO {
            break;
        }
        // Roulette as bdpt's camera subpaths: from the third vertex, on the throughput with
        // refraction's 1/eta^2 factored out.
        if path_length >= 2 {
            let survive = (beta.max_element() * eta_scale).min(1.0);
            if !(sampler.get_1d() < survive) {
                break;
            }
            beta /= survive;
        }
        ray = next.ray;
        path_length += 1;
    }
    out
}

/// Adds a technique's weighted value to the pixel's and gives it back, or counts it dropped.
pub(super) fn add(l: &mut Vec3, v: Vec3, stats: &mut PassStats) -> Option<Vec3> {
    let v = sanitize(v);
    match v {
        Some(v) => *l += v,
        None => stats.dropped += 1,
    }
    v.filter(|v| *v != Vec3::ZERO)
}

/// A non-specular vertex of a camera subpath, with what its techniques need.
pub(super) struct CameraVertex<'a> {
    pub vertex: &'a Vertex,
    pub mis: &'a SubpathMis,
    pub path_length: u32,
}

/// Weight of emission a camera subpath found: alone on the first edge; with merges only, all
/// or nothing (what a specular chain sees of a light no merge can reach, and nothing else);
/// otherwise MIS against every other technique (`densities` gives next-event estimation's
/// and emission's densities of the light point).
fn emission_weight(
    pass: &Pass,
    mis: &SubpathMis,
    path_length: u32,
    specular_path: bool,
    densities: impl FnOnce() -> (f32, f32),
) -> f32 {
    if path_length == 1 {
        return 1.0;
    }
    if !pass.connections {
        return if specular_path { 1.0 } else { 0.0 };
    }
    let (direct_pdf_a, emission_pdf_w) = densities();
    weight_emission_hit(&pass.weights, mis, direct_pdf_a, emission_pdf_w)
}

/// Next-event estimation (s = 1) from a camera vertex.
fn next_event(
    pass: &Pass,
    x: &CameraVertex,
    sampler: &mut impl SampleSource,
    stats: &mut PassStats,
) -> Vec3 {
    let scene = pass.scene;
    let v = x.vertex;
    let (Some(si), Some(bsdf)) = (&v.si, &v.bsdf) else {
        return Vec3::ZERO;
    };
    let (ul, u) = (sampler.get_1d(), sampler.get_2d());
    let Some((index, pmf, ls)) = scene.sample_light(si, ul, u) else {
        return Vec3::ZERO;
    };
    let wo = si.shading.to_local(si.wo);
    let wi = si.shading.to_local(ls.wi);
    let f = bsdf.f(wo, wi, TransportMode::Radiance) * wi.z.abs();
    if f == Vec3::ZERO || !si.consistent(wo, wi, ls.wi) {
        return Vec3::ZERO;
    }
    let (direct_pdf_w, emission_pdf_w, cos_at_light) =
        light_densities::next_event(scene, index, pmf, &ls);
    let bsdf_pdf = if ls.is_delta { 0.0 } else { bsdf.pdf(wo, wi) };
    let weight = weight_next_event(
        &pass.weights,
        x.mis,
        bsdf_pdf,
        bsdf.pdf(wi, wo),
        direct_pdf_w,
        emission_pdf_w,
        si.n.dot(ls.wi).abs(),
        cos_at_light,
    );
    stats.rays += 1;
    let shadow = si.shadow_ray(&ls);
    if scene.occluded(&shadow) {
        return Vec3::ZERO;
    }
    v.beta * f * ls.l * (weight / (pmf * ls.pdf))
}

/// A connection of camera vertex `x` with light vertex `y` of the pixel's own light subpath.
pub(super) fn connect(
    pass: &Pass,
    x: &CameraVertex,
    y: &LightVertex,
    stats: &mut PassStats,
) -> Vec3 {
    let (xv, yv) = (x.vertex, &y.vertex);
    let (Some(xs), Some(xb), Some(ys), Some(yb)) = (&xv.si, &xv.bsdf, &yv.si, &yv.bsdf) else {
        return Vec3::ZERO;
    };
    let l =
        xv.beta * xv.f(yv, TransportMode::Radiance) * yv.f(xv, TransportMode::Importance) * yv.beta;
    if l == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let g = geometry_term(xv, yv);
    let d = yv.p - xv.p;
    let dist_sq = d.length_squared();
    if g == 0.0 || !(dist_sq > 0.0) {
        return Vec3::ZERO;
    }
    let dir = d / dist_sq.sqrt();
    let (x_wo, x_wi) = (xs.shading.to_local(xs.wo), xs.shading.to_local(dir));
    let (y_wo, y_wi) = (ys.shading.to_local(ys.wo), ys.shading.to_local(-dir));
    let camera_pdf_a = xb.pdf(x_wo, x_wi) * yv.ng.dot(dir).abs() / dist_sq;
    let light_pdf_a = yb.pdf(y_wo, y_wi) * xv.ng.dot(dir).abs() / dist_sq;
    let weight = weight_connection(
        &pass.weights,
        &y.mis,
        x.mis,
        (camera_pdf_a, xb.pdf(x_wi, x_wo)),
        (light_pdf_a, yb.pdf(y_wi, y_wo)),
    );
    if !visible(pass.scene, xv, yv, &mut stats.rays) {
        return Vec3::ZERO;
    }
    l * (g * weight)
}

/// Merges camera vertex `x` with every light vertex within the pass's radius (a photon
/// density estimate over the disc, weighted per light vertex): the sum before its
/// normalisation, and the part of it from within the inner radius.
fn merge(pass: &Pass, x: &CameraVertex, shares: &mut TechniqueShares) -> (Vec3, Vec3) {
    let Some(grid) = pass.grid else {
        return (Vec3::ZERO, Vec3::ZERO);
    };
    let (mut sum, mut inner) = (Vec3::ZERO, Vec3::ZERO);
    for &c in grid.candidates(x.vertex.p) {
        let y = &pass.light_vertices[c as usize];
        let Some((value, within_inner)) = merge_pair(pass, x, y) else {
            continue;
        };
        shares.merge(
            y.path_length + x.path_length,
            y.path_length,
            value * pass.merge_normalization,
        );
        sum += value;
        if within_inner {
            inner += value;
        }
    }
    (sum, inner)
}

/// One merge of camera vertex `x` with light vertex `y`: its value before the normalisation
/// 1 / (pi r^2 N_L) (the camera subpath's throughput included) and whether `y` lies within
/// the inner radius; None where they do not merge.
pub(super) fn merge_pair(pass: &Pass, x: &CameraVertex, y: &LightVertex) -> Option<(Vec3, bool)> {
    let v = x.vertex;
    let (si, bsdf) = (v.si.as_ref()?, v.bsdf.as_ref()?);
    let dist_sq = (y.vertex.p - si.p).length_squared();
    if y.path_length + x.path_length > pass.max_path_length || dist_sq > pass.radius_sq {
        return None;
    }
    let ys = y.vertex.si.as_ref()?;
    // The light arrived along ys.wo; from behind this surface it cannot be reflected here.
    let wi = ys.wo;
    let facing = if si.n.dot(si.wo) >= 0.0 { si.n } else { -si.n };
    if wi.dot(facing) <= 0.0 {
        return None;
    }
    let wo = si.shading.to_local(si.wo);
    let wi_local = si.shading.to_local(wi);
    let f = bsdf.f(wo, wi_local, TransportMode::Radiance);
    if f == Vec3::ZERO {
        return None;
    }
    // Photon density is flux per area of the surface it landed on; the ratio of cosines is
    // as the photon mappers' (`HitPoint::response`).
    let cos_ratio = wi_local.z.abs() / wi.dot(ys.n).abs();
    let weight = weight_merge(
        &pass.weights,
        &y.mis,
        x.mis,
        bsdf.pdf(wo, wi_local),
        bsdf.pdf(wi_local, wo),
    );
    let value = v.beta * f * y.vertex.beta * (cos_ratio * weight);
    Some((value, dist_sq <= pass.inner_radius_sq))
}
