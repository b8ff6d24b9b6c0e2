//! The immutable scene: world-space triangles with their attributes, materials, textures,
//! lights and camera, plus the BVH. Built once from a `SceneDescription` (which the glTF loader
//! or a test produces), then shared by every worker thread through an `Arc`.

pub mod accel;
mod build;
pub mod gltf;
mod lighting;
pub mod limits;
mod traversal;
pub mod triangle;

use crate::camera::CameraDesc;
use crate::geometry::{Bounds3, Frame, Ray, interpolate2, interpolate3, offset_ray_origin};
use crate::light::area::AreaLight;
use crate::light::sampler::PowerLightSampler;
use crate::light::{Light, LightLiSample, LightSampleContext};
use crate::material::{AlphaMode, Bsdf, Material};
use crate::texture::{TexCoords, Texture};
use accel::Accel;
use glam::{Vec2, Vec3, Vec4};
use std::path::PathBuf;
use std::time::Duration;

/// A scene that could not be loaded or built: which file, and what is wrong with it.
#[derive(Debug, Clone, thiserror::Error)]
#[error("{}{problem}", file.as_ref().map(|f| format!("{}: ", f.display())).unwrap_or_default())]
pub struct SceneError {
    pub file: Option<PathBuf>,
    pub problem: String,
}

impl SceneError {
    pub fn new(problem: impl Into<String>) -> Self {
        SceneError {
            file: None,
            problem: problem.into(),
        }
    }

    pub fn in_file(mut self, file: impl Into<PathBuf>) -> Self {
        self.file = Some(file.into());
        self
    }
}

/// One triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct MeshDesc {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub uvs: Option<Vec<Vec2>>,
    /// The second set of texture coordinates (TEXCOORD_1), for textures that ask for it.
    pub uvs1: Option<Vec<Vec2>>,
    /// Linear RGBA vertex colours (COLOR_0), which multiply the base colour and its alpha.
    pub colors: Option<Vec<Vec4>>,
    /// Three indices per triangle, counter-clockwise seen from the front.
    pub indices: Vec<u32>,
    pub material: u32,
}

/// KHR_lights_punctual lights in world space; directions are where the light travels.
#[derive(Clone, Debug)]
pub enum PunctualLightDesc {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_cone: f32,
        outer_cone: f32,
    },
    Directional {
        direction: Vec3,
        irradiance: Vec3,
    },
}

/// Everything a scene is made of, before validation and the BVH build.
#[derive(Clone, Debug, Default)]
pub struct SceneDescription {
    pub name: String,
    pub meshes: Vec<MeshDesc>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<PunctualLightDesc>,
    pub camera: Option<CameraDesc>,
    /// Every camera of the file, named, in the order met (the first is `camera`).
    pub cameras: Vec<(String, CameraDesc)>,
    /// What lights the scene from outside (not part of glTF: the user's choice).
    pub environment: crate::light::environment::EnvironmentSettings,
    pub warnings: Vec<String>,
}

#[derive(Clone, Copy, Debug)]
pub struct TriangleAttributes {
    pub normals: Option<[Vec3; 3]>,
    pub uvs: [Vec2; 3],
    pub material: u32,
}

/// What loading and building measured and decided, for the log and the viewer.
#[derive(Clone, Debug, Default)]
pub struct SceneInfo {
    pub name: String,
    pub triangles: usize,
    pub lights: usize,
    pub degenerate_triangles_dropped: usize,
    pub default_camera: bool,
    pub default_environment: bool,
    /// What lights the scene from outside and, when the default rule chose it, why.
    pub lighting: String,
    /// Where the environment's warnings start in `warnings` (they come last, and are
    /// replaced with the environment).
    pub environment_warnings_from: usize,
    pub warnings: Vec<String>,
    pub load_time: Duration,
    pub bvh_build_time: Duration,
}

/// A ray's hit on a surface. `n` is the geometric normal of the front face (counter-clockwise
/// winding); the shading frame's normal lies on the same side as `n`.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub p: Vec3,
    pub p_error: Vec3,
    pub t: f32,
    pub n: Vec3,
    pub shading: Frame,
    pub uv: TexCoords,
    /// The interpolated vertex colour (COLOR_0), white where the mesh has none.
    pub vertex_color: Vec4,
    /// Beer-Lambert transmittance of the segment that led here, when it ran inside an
    /// absorbing medium (it met this surface from the back); one otherwise. Every estimator
    /// multiplies its throughput by it.
    pub transmittance: Vec3,
    pub wo: Vec3,
    pub triangle: u32,
}

impl SurfaceInteraction {
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        Ray::new(offset_ray_origin(self.p, self.p_error, self.n, d), d)
    }

    /// A shadow ray to `target` that stops just short of it (empty if the target is here).
    pub fn spawn_ray_to(&self, target: Vec3) -> Ray {
        let o = offset_ray_origin(self.p, self.p_error, self.n, target - self.p);
        let d = target - o;
        let dist = d.length();
        if !(dist > 0.0 && dist.is_finite()) {
            return Ray {
                o,
                d: self.n,
                t_max: 0.0,
            };
        }
        Ray {
            o,
            d: d / dist,
            t_max: dist * (1.0 - SHADOW_EPSILON),
        }
    }

    /// True when the geometric surface agrees with the shading frame on whether the local pair
    /// (wo, wi) is a reflection or a transmission. Interpolated or mapped normals can claim a
    /// reflection for a direction that crosses the real surface, which lets light leak through
    /// closed objects; such pairs are discarded (Veach's thesis, section 5.3).
    pub fn consistent(&self, wo_local: Vec3, wi_local: Vec3, wi: Vec3) -> bool {
        let geometric_reflection = (wi.dot(self.n) > 0.0) == (self.wo.dot(self.n) > 0.0);
        let shading_reflection = wo_local.z * wi_local.z > 0.0;
        geometric_reflection == shading_reflection
    }

    /// The shadow ray of next-event estimation's sample `ls`: to its point, or along its
    /// direction for a light at infinity.
    pub fn shadow_ray(&self, ls: &LightLiSample) -> Ray {
        if ls.dist.is_finite() {
            self.spawn_ray_to(ls.p_light)
        } else {
            self.spawn_ray(ls.wi)
        }
    }

    pub fn light_context(&self) -> LightSampleContext {
        LightSampleContext {
            p: self.p,
            p_error: self.p_error,
            n: self.n,
        }
    }
}

/// Relative shortening of shadow rays so they never reach the surface they aim at (pbrt-v4).
pub const SHADOW_EPSILON: f32 = 1e-4;

#[derive(Clone)]
pub struct Scene {
    pub positions: Vec<[Vec3; 3]>,
    pub attributes: Vec<TriangleAttributes>,
    /// Each triangle's TEXCOORD_1 at its corners; empty when no mesh has a second set.
    pub uvs1: Vec<[Vec2; 3]>,
    /// Each triangle's vertex colours; empty when no mesh has COLOR_0.
    pub colors: Vec<[Vec4; 3]>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub light_sampler: PowerLightSampler,
    /// Light index of each triangle, or `NO_LIGHT`.
    pub triangle_light: Vec<u32>,
    /// Index of the environment light, if any.
    pub environment: Option<usize>,
    pub camera: CameraDesc,
    /// The file's cameras, named (empty when it has none and `camera` is the default view).
    pub cameras: Vec<(String, CameraDesc)>,
    pub bounds: Bounds3,
    pub info: SceneInfo,
    accel: Accel,
}

pub const NO_LIGHT: u32 = u32::MAX;

/// Bytes a scene holds in memory, by part (the vectors' contents; their few headers and
/// the materials' names are left out).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SceneMemory {
    /// Triangle positions, normals, texture coordinates and materials.
    pub geometry: usize,
    /// The BVH with its reordered copy of the triangles.
    pub bvh: usize,
    pub textures: usize,
    /// Lights, the light sampler's table and the triangle-to-light map.
    pub lights: usize,
}

impl Scene {
    /// What the scene's parts take in memory.
    pub fn memory(&self) -> SceneMemory {
        use std::mem::size_of_val;
        SceneMemory {
            geometry: size_of_val(self.positions.as_slice())
                + size_of_val(self.attributes.as_slice())
                + size_of_val(self.uvs1.as_slice())
                + size_of_val(self.colors.as_slice())
                + size_of_val(self.materials.as_slice()),
            bvh: self.accel.memory_bytes(),
            textures: self.textures.iter().map(Texture::texel_bytes).sum(),
            lights: size_of_val(self.lights.as_slice())
                + self.light_sampler.memory_bytes()
                + size_of_val(self.triangle_light.as_slice()),
        }
    }

    pub fn triangle_material(&self, triangle: u32) -> &Material {
        &self.materials[self.attributes[triangle as usize].material as usize]
    }

    /// The vertex colour at barycentrics `b` of triangle `t`.
    fn vertex_color(&self, t: usize, b: Vec3) -> Vec4 {
        self.colors
            .get(t)
            .map_or(Vec4::ONE, |c| c[0] * b.x + c[1] * b.y + c[2] * b.z)
    }

    /// Both sets of texture coordinates at barycentrics `b` of triangle `t`.
    fn tex_coords(&self, t: usize, b: Vec3) -> TexCoords {
        let uv0 = interpolate2(&self.attributes[t].uvs, b);
        [
            uv0,
            self.uvs1.get(t).map_or(uv0, |uvs| interpolate2(uvs, b)),
        ]
    }

    /// Closest surface hit along the ray.
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self
            .accel
            .intersect_accepted(ray, |t, b| self.surface_is_there(t, b, ray))?;
        let t = hit.triangle as usize;
        let p = &self.positions[t];
        let attr = &self.attributes[t];
        let (point, p_error) = triangle::hit_point_and_error(p, hit.b);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let uv = self.tex_coords(t, hit.b);
        let mut ns = attr
            .normals
            .map_or(n, |ns| interpolate3(&ns, hit.b).normalize_or(n));
        if ns.dot(n) < 0.0 {
            ns = -ns;
        }
        let material = &self.materials[attr.material as usize];
        let shading = match material
            .normal_texture
            .and_then(|(r, s)| self.textures.get(r.texture as usize).map(|tex| (r, tex, s)))
        {
            Some((r, tex, scale)) => {
                // The tangent follows the coordinates the normal map is read at.
                let corners = match (r.tex_coord, self.uvs1.get(t)) {
                    (1, Some(uvs1)) => uvs1,
                    _ => &attr.uvs,
                };
                let corners = corners.map(|c| r.transform.transform_point2(c));
                let frame = Frame::from_normal_tangent(ns, dpdu(p, &corners).unwrap_or(Vec3::ZERO));
                let c = tex.lookup(r.uv(&uv));
                let local = Vec3::new(
                    (2.0 * c.x - 1.0) * scale,
                    (2.0 * c.y - 1.0) * scale,
                    2.0 * c.z - 1.0,
                );
                let mapped = frame.from_local(local).normalize_or(ns);
                Frame::from_z(if mapped.dot(n) < 0.0 { ns } else { mapped })
            }
            None => Frame::from_z(ns),
        };
        Some(SurfaceInteraction {
            p: point,
            p_error,
            t: hit.t,
            n,
            shading,
            uv,
            vertex_color: self.vertex_color(t, hit.b),
            transmittance: transmittance(material.absorption, ray, hit.t, n),
            wo: -ray.d,
            triangle: hit.triangle,
        })
    }

    /// True if something blocks the ray before `ray.t_max`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel
            .occluded_accepted(ray, |t, b| self.surface_is_there(t, b, ray))
    }

    /// Whether a ray that meets triangle `t` (a cut-out) at barycentrics `b` finds it there:
    /// where alpha reaches the cutoff (MASK), or with probability alpha (BLEND), decided by
    /// a hash of the ray and the triangle so that the answer is the same every time the same
    /// ray asks, on any thread.
    fn surface_is_there(&self, t: u32, b: Vec3, ray: &Ray) -> bool {
        let material = self.triangle_material(t);
        let alpha = || {
            let uv = self.tex_coords(t as usize, b);
            material.alpha_at(&self.textures, &uv) * self.vertex_color(t as usize, b).w
        };
        match material.alpha_mode {
            AlphaMode::Opaque => true,
            AlphaMode::Mask(cutoff) => alpha() >= cutoff,
            AlphaMode::Blend => alpha() > coverage_hash(ray, t),
        }
    }

    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        self.triangle_material(si.triangle)
            .bsdf(&self.textures, &si.uv, si.vertex_color.truncate())
    }

    /// Light index of the hit triangle, if it emits.
    pub fn area_light(&self, si: &SurfaceInteraction) -> Option<(usize, &AreaLight)> {
        let l = self.triangle_light[si.triangle as usize];
        match self.lights.get(l as usize) {
            Some(Light::Area(a)) => Some((l as usize, a)),
            _ => None,
        }
    }

    /// Next-event estimation's light sample for the point `si` (pbrt-v4 section 13.4.3): a
    /// light chosen by power with `ul`, a point on it drawn with `u` (delta lights ignore
    /// it). Gives the light's index, the probability it was chosen and the sample, when the
    /// sample carries radiance with a positive density.
    pub fn sample_light(
        &self,
        si: &SurfaceInteraction,
        ul: f32,
        u: Vec2,
    ) -> Option<(usize, f32, LightLiSample)> {
        let (index, pmf) = self.light_sampler.sample(ul)?;
        let ctx = si.light_context();
        let ls = match &self.lights[index] {
            Light::Area(a) => a.sample_li(&self.textures, &ctx, u),
            Light::Point(p) => p.sample_li(&ctx),
            Light::Spot(s) => s.sample_li(&ctx),
            Light::Directional(d) => d.sample_li(&ctx),
            Light::Environment(e) => e.sample_li(&ctx, u),
        }?;
        (ls.pdf > 0.0 && ls.l != Vec3::ZERO).then_some((index, pmf, ls))
    }

    /// Radiance emitted by the surface at `si` towards `w`.
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3) -> Vec3 {
        self.area_light(si)
            .map_or(Vec3::ZERO, |(_, a)| a.l(&self.textures, &si.uv, w))
    }

    /// Radiance arriving along a ray that left the scene in direction `w`.
    #[inline]
    pub fn environment_radiance(&self, w: Vec3) -> Vec3 {
        match self.environment.and_then(|i| self.lights.get(i)) {
            Some(Light::Environment(e)) => e.le(w),
            _ => Vec3::ZERO,
        }
    }
}

/// Partial derivative of position with respect to u, for tangent frames (pbrt-v4 eq. 6.23).
fn dpdu(p: &[Vec3; 3], uv: &[Vec2; 3]) -> Option<Vec3> {
    let (duv02, duv12) = (uv[0] - uv[2], uv[1] - uv[2]);
    let (dp02, dp12) = (p[0] - p[2], p[1] - p[2]);
    let det = duv02.x * duv12.y - duv02.y * duv12.x;
    if det.abs() < 1e-12 {
        return None;
    }
    Some((duv12.y * dp02 - duv02.y * dp12) / det)
}

/// A number in [0, 1) fixed by the ray and the triangle (stochastic transparency's draw).
fn coverage_hash(ray: &Ray, triangle: u32) -> f32 {
    let words = [ray.o.to_array(), ray.d.to_array()].concat();
    let mut h = 0x9e37_79b9_7f4a_7c15u64 ^ triangle as u64;
    for w in words {
        // SplitMix64's finaliser after each word.
        h = (h ^ w.to_bits() as u64).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h ^= h >> 31;
    }
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    ((h ^ (h >> 31)) >> 40) as f32 / (1u64 << 24) as f32
}

/// exp(-sigma_a d) over the segment of length `t |d|` that met a surface of normal `n` from
/// its back, i.e. from inside a closed mesh with outward normals (KHR_materials_volume).
fn transmittance(absorption: Vec3, ray: &Ray, t: f32, n: Vec3) -> Vec3 {
    if absorption == Vec3::ZERO || ray.d.dot(n) <= 0.0 {
        return Vec3::ONE;
    }
    (-absorption * (t * ray.d.length())).exp()
}
