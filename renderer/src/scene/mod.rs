//! The immutable scene: world-space triangles with their attributes, materials, textures,
//! lights and camera, plus the BVH. Built once from a `SceneDescription` (which the glTF loader
//! or a test produces), then shared by every worker thread through an `Arc`.

pub mod accel;
pub mod gltf;
pub mod gltf_export;
pub mod texture;
pub mod triangle;

use crate::camera::CameraDesc;
use crate::geometry::{Bounds3, Frame, Ray, interpolate2, interpolate3, offset_ray_origin};
use crate::light::area::AreaLight;
use crate::light::environment::UniformEnvironment;
use crate::light::punctual::{DirectionalLight, PointLight, SpotLight};
use crate::light::sampler::PowerLightSampler;
use crate::light::{Light, LightSampleContext};
use crate::material::{Bsdf, Material};
use accel::Accel;
use glam::{Vec2, Vec3};
use std::path::PathBuf;
use std::time::{Duration, Instant};
use texture::Texture;

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
    pub uv: Vec2,
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

pub struct Scene {
    pub positions: Vec<[Vec3; 3]>,
    pub attributes: Vec<TriangleAttributes>,
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub light_sampler: PowerLightSampler,
    /// Light index of each triangle, or `NO_LIGHT`.
    pub triangle_light: Vec<u32>,
    /// Index of the environment light, if any.
    pub environment: Option<usize>,
    pub camera: CameraDesc,
    pub bounds: Bounds3,
    pub info: SceneInfo,
    accel: Accel,
}

pub const NO_LIGHT: u32 = u32::MAX;

fn is_degenerate(p: &[Vec3; 3]) -> bool {
    let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length();
    !(area2 > 0.0) || !area2.is_finite()
}

impl Scene {
    /// Validates a description and builds the scene. Degenerate triangles are dropped and
    /// counted; indices out of range or non-finite data are errors.
    pub fn build(desc: SceneDescription) -> Result<Scene, SceneError> {
        let SceneDescription {
            name,
            meshes,
            mut materials,
            textures,
            lights: punctual,
            camera,
            mut warnings,
        } = desc;
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let default_material = materials.len() as u32 - 1;
        let mut positions = Vec::new();
        let mut attributes = Vec::new();
        let mut dropped = 0usize;
        let mut bounds = Bounds3::EMPTY;
        for mesh in &meshes {
            if mesh.indices.len() % 3 != 0 {
                return Err(SceneError::new(format!(
                    "mesh '{}': index count {} is not a multiple of 3",
                    mesh.name,
                    mesh.indices.len()
                )));
            }
            if let Some(bad) = mesh.positions.iter().position(|p| !p.is_finite()) {
                return Err(SceneError::new(format!(
                    "mesh '{}': position {bad} is NaN or infinite",
                    mesh.name
                )));
            }
            let n = mesh.positions.len();
            let check_len = |len: usize, what: &str| {
                if len != n {
                    return Err(SceneError::new(format!(
                        "mesh '{}': {len} {what} for {n} positions",
                        mesh.name
                    )));
                }
                Ok(())
            };
            if let Some(normals) = &mesh.normals {
                check_len(normals.len(), "normals")?;
            }
            if let Some(uvs) = &mesh.uvs {
                check_len(uvs.len(), "texture coordinates")?;
            }
            let material = if (mesh.material as usize) < materials.len() {
                mesh.material
            } else {
                default_material
            };
            for tri in mesh.indices.chunks_exact(3) {
                let idx = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
                if let Some(&bad) = idx.iter().find(|&&i| i >= n) {
                    return Err(SceneError::new(format!(
                        "mesh '{}': vertex index {bad} out of range ({n} vertices)",
                        mesh.name
                    )));
                }
                let p = idx.map(|i| mesh.positions[i]);
                if is_degenerate(&p) {
                    dropped += 1;
                    continue;
                }
                let normals = mesh
                    .normals
                    .as_ref()
                    .map(|ns| idx.map(|i| ns[i].normalize_or_zero()))
                    .filter(|ns| ns.iter().all(|n| n.is_finite() && *n != Vec3::ZERO));
                let uvs = mesh
                    .uvs
                    .as_ref()
                    .map_or([Vec2::ZERO; 3], |uv| idx.map(|i| uv[i]));
                let uvs = if uvs.iter().all(|u| u.is_finite()) {
                    uvs
                } else {
                    [Vec2::ZERO; 3]
                };
                for q in p {
                    bounds = bounds.union_point(q);
                }
                positions.push(p);
                attributes.push(TriangleAttributes {
                    normals,
                    uvs,
                    material,
                });
            }
        }
        if positions.is_empty() {
            return Err(SceneError::new(if dropped > 0 {
                format!("all {dropped} triangles are degenerate")
            } else {
                "the scene has no triangle meshes".to_string()
            }));
        }
        if dropped > 0 {
            warnings.push(format!(
                "dropped {dropped} degenerate (zero-area) triangles"
            ));
        }
        let (_, scene_radius) = bounds.bounding_sphere();

        // Lights: every triangle with an emissive material, then the punctual lights.
        let mut lights = Vec::new();
        let mut triangle_light = vec![NO_LIGHT; positions.len()];
        for (i, (p, attr)) in positions.iter().zip(&attributes).enumerate() {
            let m = &materials[attr.material as usize];
            if !m.is_emissive() {
                continue;
            }
            let cross = (p[1] - p[0]).cross(p[2] - p[0]);
            let mean = m.emission
                * m.emissive_texture
                    .and_then(|t| textures.get(t.texture as usize))
                    .map_or(Vec3::ONE, |t| t.mean_rgb());
            triangle_light[i] = lights.len() as u32;
            lights.push(Light::Area(AreaLight {
                triangle: i as u32,
                area: 0.5 * cross.length(),
                normal: cross.normalize(),
                two_sided: m.double_sided,
                mean_radiance: mean,
            }));
        }
        for l in punctual {
            lights.push(match l {
                PunctualLightDesc::Point {
                    position,
                    intensity,
                } => Light::Point(PointLight {
                    position,
                    intensity,
                }),
                PunctualLightDesc::Spot {
                    position,
                    direction,
                    intensity,
                    inner_cone,
                    outer_cone,
                } => Light::Spot(SpotLight {
                    position,
                    frame: Frame::from_z(direction.normalize_or(Vec3::NEG_Z)),
                    intensity,
                    cos_inner: inner_cone.cos(),
                    cos_outer: outer_cone.cos(),
                }),
                PunctualLightDesc::Directional {
                    direction,
                    irradiance,
                } => Light::Directional(DirectionalLight {
                    direction: direction.normalize_or(Vec3::NEG_Z),
                    irradiance,
                    scene_radius,
                }),
            });
        }
        let default_environment = lights.is_empty();
        let mut environment = None;
        if default_environment {
            warnings.push(
                "the scene has no emitter: lit by a uniform environment of radiance 1".to_string(),
            );
            environment = Some(lights.len());
            lights.push(Light::Environment(UniformEnvironment {
                radiance: Vec3::ONE,
                scene_radius,
            }));
        }
        let light_sampler = PowerLightSampler::new(&lights);

        let default_camera = camera.is_none();
        if default_camera {
            warnings.push(
                "the scene has no camera: using a default one that frames its bounds".to_string(),
            );
        }
        let camera = camera.unwrap_or_else(|| CameraDesc::framing(&bounds));

        let start = Instant::now();
        let extent = bounds.min.abs().max(bounds.max.abs()).max_element();
        let accel = Accel::build(&positions, extent);
        let info = SceneInfo {
            name,
            triangles: positions.len(),
            lights: lights.len(),
            degenerate_triangles_dropped: dropped,
            default_camera,
            default_environment,
            warnings,
            load_time: Duration::ZERO,
            bvh_build_time: start.elapsed(),
        };
        Ok(Scene {
            positions,
            attributes,
            materials,
            textures,
            lights,
            light_sampler,
            triangle_light,
            environment,
            camera,
            bounds,
            info,
            accel,
        })
    }

    pub fn triangle_material(&self, triangle: u32) -> &Material {
        &self.materials[self.attributes[triangle as usize].material as usize]
    }

    /// Point and texture coordinate at barycentrics `b` of a triangle.
    pub fn triangle_point(&self, triangle: u32, b: Vec3) -> (Vec3, Vec2) {
        let t = triangle as usize;
        (
            interpolate3(&self.positions[t], b),
            interpolate2(&self.attributes[t].uvs, b),
        )
    }

    /// Closest surface hit along the ray.
    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceInteraction> {
        let hit = self.accel.intersect(ray)?;
        let t = hit.triangle as usize;
        let p = &self.positions[t];
        let attr = &self.attributes[t];
        let (point, p_error) = triangle::hit_point_and_error(p, hit.b);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let uv = interpolate2(&attr.uvs, hit.b);
        let mut ns = attr
            .normals
            .map_or(n, |ns| interpolate3(&ns, hit.b).normalize_or(n));
        if ns.dot(n) < 0.0 {
            ns = -ns;
        }
        let material = &self.materials[attr.material as usize];
        let shading = match material
            .normal_texture
            .and_then(|(t, s)| self.textures.get(t.texture as usize).map(|tex| (tex, s)))
        {
            Some((tex, scale)) => {
                let frame =
                    Frame::from_normal_tangent(ns, dpdu(p, &attr.uvs).unwrap_or(Vec3::ZERO));
                let c = tex.lookup(uv);
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
            wo: -ray.d,
            triangle: hit.triangle,
        })
    }

    /// True if something blocks the ray before `ray.t_max`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.accel.occluded(ray)
    }

    pub fn bsdf(&self, si: &SurfaceInteraction) -> Bsdf {
        self.triangle_material(si.triangle)
            .bsdf(&self.textures, si.uv)
    }

    /// Light index of the hit triangle, if it emits.
    pub fn area_light(&self, si: &SurfaceInteraction) -> Option<(usize, &AreaLight)> {
        let l = self.triangle_light[si.triangle as usize];
        match self.lights.get(l as usize) {
            Some(Light::Area(a)) => Some((l as usize, a)),
            _ => None,
        }
    }

    /// Radiance emitted by the surface at `si` towards `w`.
    pub fn emitted(&self, si: &SurfaceInteraction, w: Vec3) -> Vec3 {
        self.area_light(si)
            .map_or(Vec3::ZERO, |(_, a)| a.l(self, si.uv, w))
    }

    /// Radiance arriving along a ray that left the scene.
    pub fn environment_radiance(&self) -> Vec3 {
        match self.environment.and_then(|i| self.lights.get(i)) {
            Some(Light::Environment(e)) => e.radiance,
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
