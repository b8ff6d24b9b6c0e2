//! Connection strategies and their MIS weights (Veach 1997, chapter 10; pbrt-v3 section
//! 16.3.3-16.3.4). Strategy (s, t) joins the first s vertices of the light subpath to the
//! first t of the camera subpath: s = 0 takes the camera path's emission, s = 1 samples a
//! fresh point on a light (next-event estimation), t = 1 connects a light vertex to the
//! pinhole and splats to the pixel it lands in.

use crate::camera::Camera;
use crate::geometry::Ray;
use crate::integrators::bdpt::vertex::{Vertex, VertexKind};
use crate::material::TransportMode;
use crate::sampling::sampler::SampleSource;
use crate::scene::Scene;
use glam::{Vec2, Vec3};

/// The unweighted contribution of one strategy, its MIS weight, and for t = 1 the film
/// position to splat to.
#[derive(Clone, Copy, Debug)]
pub struct Connection {
    pub l: Vec3,
    pub mis: f32,
    pub raster: Option<Vec2>,
}

/// Evaluates strategy (s, t). `mis` false gives weight 1 (one strategy on its own).
#[allow(clippy::too_many_arguments)]
pub fn connect(
    scene: &Scene,
    camera: &Camera,
    light_path: &[Vertex],
    camera_path: &[Vertex],
    s: usize,
    t: usize,
    sampler: &mut impl SampleSource,
    rays: &mut u64,
    mis: bool,
) -> Option<Connection> {
    // An escaped camera vertex can only be used by s = 0.
    if t > 1 && s != 0 && camera_path[t - 1].kind == VertexKind::Light {
        return None;
    }
    let mut sampled = None;
    let mut raster = None;
    let l = if s == 0 {
        let pt = &camera_path[t - 1];
        if !pt.is_light(scene) {
            return None;
        }
        pt.le(scene, &camera_path[t - 2]) * pt.beta
    } else if t == 1 {
        let qs = &light_path[s - 1];
        if !qs.is_connectible(scene) {
            return None;
        }
        let cs = camera.sample_wi(qs.p)?;
        let pinhole = Vertex::camera(cs.p_camera, Vec3::splat(cs.importance / cs.pdf));
        let mut l = qs.beta * qs.f(&pinhole, TransportMode::Importance) * pinhole.beta;
        if qs.is_on_surface() {
            l *= cs.wi.dot(qs.ns).abs();
        }
        if l == Vec3::ZERO || !visible(scene, qs, &pinhole, rays) {
            return None;
        }
        raster = Some(cs.raster);
        sampled = Some(pinhole);
        l
    } else if s == 1 {
        let pt = &camera_path[t - 1];
        if !pt.is_connectible(scene) {
            return None;
        }
        let si = pt.si.as_ref()?;
        let (ul, u) = (sampler.get_1d(), sampler.get_2d());
        let (index, pmf, ls) = scene.sample_light(si, ul, u)?;
        let mut light = Vertex::light(
            Some(index),
            ls.p_light,
            ls.n_light,
            ls.l / (ls.pdf * pmf),
            0.0,
        );
        light.pdf_fwd = light.pdf_light_origin(scene, pt);
        let mut l = pt.beta * pt.f(&light, TransportMode::Radiance) * light.beta;
        if pt.is_on_surface() {
            l *= ls.wi.dot(pt.ns).abs();
        }
        if l == Vec3::ZERO {
            return None;
        }
        *rays += 1;
        let shadow = si.shadow_ray(&ls);
        if scene.occluded(&shadow) {
            return None;
        }
        sampled = Some(light);
        l
    } else {
        let (qs, pt) = (&light_path[s - 1], &camera_path[t - 1]);
        if !qs.is_connectible(scene) || !pt.is_connectible(scene) {
            return None;
        }
        let l = qs.beta
            * qs.f(pt, TransportMode::Importance)
            * pt.f(qs, TransportMode::Radiance)
            * pt.beta;
        if l == Vec3::ZERO {
            return None;
        }
        let g = geometry_term(qs, pt);
        if g == 0.0 || !visible(scene, qs, pt, rays) {
            return None;
        }
        l * g
    };
    if l == Vec3::ZERO {
        return None;
    }
    let mis = if mis {
        mis_weight(
            scene,
            camera,
            light_path,
            camera_path,
            sampled.as_ref(),
            s,
            t,
        )
    } else {
        1.0
    };
    Some(Connection { l, mis, raster })
}

/// G without visibility: |cos| |cos| / distance^2 (shading normals, as the BSDFs use them).
pub(crate) fn geometry_term(a: &Vertex, b: &Vertex) -> f32 {
    let d = a.p - b.p;
    let dist_sq = d.length_squared();
    if !(dist_sq > 0.0) {
        return 0.0;
    }
    let d = d / dist_sq.sqrt();
    let mut g = 1.0 / dist_sq;
    if a.is_on_surface() {
        g *= a.ns.dot(d).abs();
    }
    if b.is_on_surface() {
        g *= b.ns.dot(d).abs();
    }
    g
}

/// Nothing between two vertices (each ray end kept off its own surface).
pub(crate) fn visible(scene: &Scene, a: &Vertex, b: &Vertex, rays: &mut u64) -> bool {
    let o = a.ray_origin_towards(b.p);
    let target = b.ray_origin_towards(a.p);
    let d = target - o;
    let dist = d.length();
    if !(dist > 0.0 && dist.is_finite()) {
        return true;
    }
    *rays += 1;
    let ray = Ray {
        o,
        d: d / dist,
        t_max: dist * (1.0 - 1e-4),
    };
    !scene.occluded(&ray)
}

/// Balance-heuristic weight of strategy (s, t) among all strategies that could have produced
/// the same path (Veach 1997, eq. 10.9, computed as pbrt-v3's ratios of reverse to forward
/// densities). The connection changes four reverse densities and makes the connected
/// vertices non-degenerate; those are computed here and read in place of the stored ones.
/// Delta densities are stored as 0 and count as 1 in the ratios (`remap0`), and strategies
/// that would need to hit a delta vertex are skipped.
fn mis_weight(
    scene: &Scene,
    camera: &Camera,
    light_path: &[Vertex],
    camera_path: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let remap0 = |f: f32| if f != 0.0 { f } else { 1.0 };
    let qs = match s {
        0 => None,
        1 => sampled.or(light_path.first()),
        _ => Some(&light_path[s - 1]),
    };
    let pt = if t == 1 {
        sampled.unwrap_or(&camera_path[0])
    } else {
        &camera_path[t - 1]
    };
    let qs_minus = (s > 1).then(|| &light_path[s - 2]);
    let pt_minus = (t > 1).then(|| &camera_path[t - 2]);

    let pt_rev = match qs {
        Some(qs) => qs.pdf(scene, camera, qs_minus, pt),
        None => pt_minus.map_or(0.0, |m| pt.pdf_light_origin(scene, m)),
    };
    let pt_minus_rev = pt_minus.map(|m| match qs {
        Some(qs) => pt.pdf(scene, camera, Some(qs), m),
        None => pt.pdf_light(scene, m),
    });
    let qs_rev = qs.map(|qs| pt.pdf(scene, camera, pt_minus, qs));
    let qs_minus_rev = qs_minus.map(|m| qs.unwrap().pdf(scene, camera, Some(pt), m));

    let mut sum_ri = 0.0f32;
    // Strategies with fewer camera vertices.
    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        let v = if i == t - 1 { pt } else { &camera_path[i] };
        let pdf_rev = if i == t - 1 {
            pt_rev
        } else if i == t - 2 {
            pt_minus_rev.unwrap_or(v.pdf_rev)
        } else {
            v.pdf_rev
        };
        let delta = i != t - 1 && v.delta;
        let prev_delta = i - 1 != t - 1 && camera_path[i - 1].delta;
        ri *= remap0(pdf_rev) / remap0(v.pdf_fwd);
        if !delta && !prev_delta {
            sum_ri += ri;
        }
    }
    // Strategies with fewer light vertices.
    ri = 1.0;
    for i in (0..s).rev() {
        let v = if i == s - 1 {
            qs.unwrap()
        } else {
            &light_path[i]
        };
        let pdf_rev = if i == s - 1 {
            qs_rev.unwrap_or(0.0)
        } else if i + 2 == s {
            qs_minus_rev.unwrap_or(v.pdf_rev)
        } else {
            v.pdf_rev
        };
        let delta = i != s - 1 && v.delta;
        let delta_light_vertex = if i > 0 {
            i - 1 != s - 1 && light_path[i - 1].delta
        } else if s == 1 {
            v.is_delta_light(scene)
        } else {
            light_path[0].is_delta_light(scene)
        };
        ri *= remap0(pdf_rev) / remap0(v.pdf_fwd);
        if !delta && !delta_light_vertex {
            sum_ri += ri;
        }
    }
    1.0 / (1.0 + sum_ri)
}
