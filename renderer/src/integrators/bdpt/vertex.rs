//! A vertex of a camera or light subpath (pbrt-v3 section 16.3.1, `Vertex`): where it is, the
//! throughput `beta` of the subpath up to it, and the area densities of reaching it forwards
//! (`pdf_fwd`, along the subpath's own direction) and backwards (`pdf_rev`, as the other
//! subpath would), which is all Veach's MIS weights need (Veach 1997, section 10.2).

use crate::camera::Camera;
use crate::geometry::offset_ray_origin;
use crate::light::Light;
use crate::light::emission::pdf_le;
use crate::material::{Bsdf, TransportMode};
use crate::scene::{Scene, SurfaceInteraction};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// The pinhole.
    Camera,
    /// A point on a light: a light subpath's first vertex, next-event estimation's sampled
    /// point, or where a camera ray escaped to the environment (`light` None).
    Light,
    /// A scattering surface (possibly emissive).
    Surface,
}

#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    pub kind: VertexKind,
    pub p: Vec3,
    /// Geometric normal; zero for points not on a surface (pinhole, point lights).
    pub ng: Vec3,
    /// Shading normal (the geometric one off surfaces).
    pub ns: Vec3,
    pub si: Option<SurfaceInteraction>,
    pub bsdf: Option<Bsdf>,
    /// Index of the light in `Scene::lights` for light vertices.
    pub light: Option<usize>,
    pub beta: Vec3,
    /// Sampled from a delta BSDF: no other technique can produce the same direction.
    pub delta: bool,
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
}

impl Vertex {
    pub fn camera(p: Vec3, beta: Vec3) -> Vertex {
        Vertex {
            kind: VertexKind::Camera,
            p,
            ng: Vec3::ZERO,
            ns: Vec3::ZERO,
            si: None,
            bsdf: None,
            light: None,
            beta,
            delta: false,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        }
    }

    pub fn light(light: Option<usize>, p: Vec3, n: Vec3, beta: Vec3, pdf_fwd: f32) -> Vertex {
        Vertex {
            kind: VertexKind::Light,
            p,
            ng: n,
            ns: n,
            si: None,
            bsdf: None,
            light,
            beta,
            delta: false,
            pdf_fwd,
            pdf_rev: 0.0,
        }
    }

    pub fn surface(si: SurfaceInteraction, bsdf: Bsdf, beta: Vec3) -> Vertex {
        Vertex {
            kind: VertexKind::Surface,
            p: si.p,
            ng: si.n,
            ns: si.shading.n,
            si: Some(si),
            bsdf: Some(bsdf),
            light: None,
            beta,
            delta: false,
            pdf_fwd: 0.0,
            pdf_rev: 0.0,
        }
    }

    pub fn is_on_surface(&self) -> bool {
        self.ng != Vec3::ZERO
    }

    /// The light this vertex emits as: its own, or the area light of an emissive surface.
    fn emitter<'a>(&self, scene: &'a Scene) -> Option<(usize, &'a Light)> {
        match self.kind {
            VertexKind::Light => self.light.map(|i| (i, &scene.lights[i])),
            VertexKind::Surface => {
                let (i, _) = scene.area_light(self.si.as_ref()?)?;
                Some((i, &scene.lights[i]))
            }
            VertexKind::Camera => None,
        }
    }

    pub fn is_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light || self.emitter(scene).is_some()
    }

    pub fn is_infinite_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light && self.light.is_none_or(|i| scene.lights[i].is_infinite())
    }

    pub fn is_delta_light(&self, scene: &Scene) -> bool {
        self.kind == VertexKind::Light && self.light.is_some_and(|i| scene.lights[i].is_delta())
    }

    /// Whether a deterministic connection can end here (pbrt-v3 `IsConnectible`): not at a
    /// purely specular surface, nor at a light that emits in a single direction.
    pub fn is_connectible(&self, scene: &Scene) -> bool {
        match self.kind {
            VertexKind::Camera => true,
            VertexKind::Light => self
                .light
                .is_some_and(|i| !matches!(scene.lights[i], Light::Directional(_))),
            VertexKind::Surface => self.bsdf.is_some_and(|b| !b.is_delta()),
        }
    }

    /// Where a ray towards `target` leaves this vertex without hitting its own surface.
    pub fn ray_origin_towards(&self, target: Vec3) -> Vec3 {
        match &self.si {
            Some(si) => offset_ray_origin(si.p, si.p_error, si.n, target - si.p),
            None => self.p,
        }
    }

    /// BSDF value for light arriving from `next` and leaving towards the subpath's previous
    /// vertex, with the adjoint's shading-normal correction in importance mode (Veach 1997,
    /// section 5.3). Zero where shading and geometric normals disagree about the side of
    /// `next` (light leaks, as in the path tracer).
    pub fn f(&self, next: &Vertex, mode: TransportMode) -> Vec3 {
        let (Some(si), Some(bsdf)) = (&self.si, &self.bsdf) else {
            return Vec3::ZERO;
        };
        let wi = (next.p - self.p).normalize_or_zero();
        if wi == Vec3::ZERO {
            return Vec3::ZERO;
        }
        // A connection along the surface itself (two points of one facet) would pass the side
        // tests by rounding and carry light through closed shells; its true weight is nil.
        if wi.dot(si.n).abs() < 1e-5 {
            return Vec3::ZERO;
        }
        let wo_local = si.shading.to_local(si.wo);
        let wi_local = si.shading.to_local(wi);
        if !si.consistent(wo_local, wi_local, wi) {
            return Vec3::ZERO;
        }
        let f = bsdf.f(wo_local, wi_local, mode);
        match mode {
            TransportMode::Radiance => f,
            TransportMode::Importance => {
                let (wo_ng, wi_ns) = (si.wo.dot(si.n).abs(), wi_local.z.abs());
                if wo_ng == 0.0 || wi_ns == 0.0 {
                    return Vec3::ZERO;
                }
                f * (wo_local.z.abs() * wi.dot(si.n).abs() / (wo_ng * wi_ns))
            }
        }
    }

    /// Converts a solid-angle density at this vertex into an area density at `next`.
    pub fn convert_density(&self, pdf: f32, next: &Vertex, scene: &Scene) -> f32 {
        if next.is_infinite_light(scene) {
            return pdf;
        }
        let w = next.p - self.p;
        let dist_sq = w.length_squared();
        if !(dist_sq > 0.0) {
            return 0.0;
        }
        let mut pdf = pdf / dist_sq;
        if next.is_on_surface() {
            pdf *= next.ng.dot(w / dist_sq.sqrt()).abs();
        }
        pdf
    }

    /// Area density at `next` of continuing a subpath from this vertex, having arrived from
    /// `prev` (pbrt-v3 `Vertex::Pdf`).
    pub fn pdf(&self, scene: &Scene, camera: &Camera, prev: Option<&Vertex>, next: &Vertex) -> f32 {
        if self.kind == VertexKind::Light {
            return self.pdf_light(scene, next);
        }
        let wn = (next.p - self.p).normalize_or_zero();
        if wn == Vec3::ZERO {
            return 0.0;
        }
        let pdf = match self.kind {
            VertexKind::Camera if next.is_infinite_light(scene) => return camera.pdf_we_dir(wn),
            VertexKind::Camera => {
                let n = next.is_on_surface().then_some(next.ng);
                return camera.pdf_first_hit(self.p, next.p, n);
            }
            _ => {
                let (Some(si), Some(bsdf), Some(prev)) = (&self.si, &self.bsdf, prev) else {
                    return 0.0;
                };
                let wp = (prev.p - self.p).normalize_or_zero();
                bsdf.pdf(si.shading.to_local(wp), si.shading.to_local(wn))
            }
        };
        self.convert_density(pdf, next, scene)
    }

    /// Area density at `next` of a light subpath starting here with a direction towards it.
    pub fn pdf_light(&self, scene: &Scene, next: &Vertex) -> f32 {
        let w = next.p - self.p;
        let dist_sq = w.length_squared();
        if !(dist_sq > 0.0) {
            return 0.0;
        }
        let w = w / dist_sq.sqrt();
        let mut pdf = if self.is_infinite_light(scene) {
            let radius = scene.bounds.bounding_sphere().1.max(1e-6);
            1.0 / (std::f32::consts::PI * radius * radius)
        } else {
            let Some((_, light)) = self.emitter(scene) else {
                return 0.0;
            };
            pdf_le(scene, light, w).1 / dist_sq
        };
        if next.is_on_surface() {
            pdf *= next.ng.dot(w).abs();
        }
        pdf
    }

    /// Density of choosing this point as a light subpath's origin (light pmf times area
    /// density; for infinite lights the directional density towards `next`).
    pub fn pdf_light_origin(&self, scene: &Scene, next: &Vertex) -> f32 {
        let w = (next.p - self.p).normalize_or_zero();
        if w == Vec3::ZERO {
            return 0.0;
        }
        if self.is_infinite_light(scene) {
            return infinite_light_density(scene, w);
        }
        let Some((i, light)) = self.emitter(scene) else {
            return 0.0;
        };
        scene.light_sampler.pmf(i) * pdf_le(scene, light, w).0
    }

    /// Radiance this vertex emits towards `towards` (zero unless it is a light).
    pub fn le(&self, scene: &Scene, towards: &Vertex) -> Vec3 {
        if !self.is_light(scene) {
            return Vec3::ZERO;
        }
        let w = (towards.p - self.p).normalize_or_zero();
        if self.is_infinite_light(scene) {
            return scene.environment_radiance(-w);
        }
        match (self.emitter(scene), &self.si) {
            (Some((_, Light::Area(a))), Some(si)) => a.l(&scene.textures, &si.uv, w),
            _ => Vec3::ZERO,
        }
    }
}

/// Directional density of a light subpath leaving the infinite lights in direction `w` (of
/// travel): pmf times the environment's density for the direction it came from, -w (pbrt-v3's
/// `InfiniteLightDensity`; a directional light's is a delta, zero here).
pub fn infinite_light_density(scene: &Scene, w: Vec3) -> f32 {
    scene
        .lights
        .iter()
        .enumerate()
        .map(|(i, l)| match l {
            Light::Environment(e) => scene.light_sampler.pmf(i) * e.pdf_li(-w),
            _ => 0.0,
        })
        .sum()
}
