//! `Scene::build`: a `SceneDescription` validated and turned into the scene the integrators
//! trace, in three steps: the meshes flattened into world-space triangles (bad data is an
//! error naming the mesh, degenerate triangles are dropped and counted), the lights (an area
//! light per emissive triangle, the punctual lights, the environment the user chose or the
//! default-lighting rule gives), and the BVH.

use super::accel::Accel;
use super::{MeshDesc, TriangleAttributes};
use super::{NO_LIGHT, PunctualLightDesc, Scene, SceneDescription, SceneError, SceneInfo};
use crate::camera::CameraDesc;
use crate::geometry::{Bounds3, Frame};
use crate::light::Light;
use crate::light::area::{AreaLight, Cutout};
use crate::light::punctual::{DirectionalLight, PointLight, SpotLight};
use crate::light::sampler::PowerLightSampler;
use crate::material::{AlphaMode, Material};
use crate::texture::Texture;
use crate::texture_footprint::LuminancePrefix;
use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// The meshes as world-space triangles.
struct Triangles {
    positions: Vec<[Vec3; 3]>,
    attributes: Vec<TriangleAttributes>,
    /// TEXCOORD_1 of every triangle, or nothing when no mesh has it.
    uvs1: Vec<[Vec2; 3]>,
    /// COLOR_0 of every triangle, or nothing when no mesh has it.
    colors: Vec<[Vec4; 3]>,
    bounds: Bounds3,
    /// Degenerate (zero-area) triangles dropped.
    dropped: usize,
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
            cameras,
            environment: environment_settings,
            mut warnings,
        } = desc;
        if materials.is_empty() {
            materials.push(Material::default());
        }
        let triangles = flatten_meshes(&meshes, materials.len() as u32)?;
        if triangles.dropped > 0 {
            warnings.push(format!(
                "dropped {} degenerate (zero-area) triangles",
                triangles.dropped
            ));
        }
        let Triangles {
            positions,
            attributes,
            uvs1,
            colors,
            bounds,
            dropped,
        } = triangles;
        let (_, scene_radius) = bounds.bounding_sphere();

        let (mut lights, triangle_light) =
            area_lights(&positions, &attributes, &uvs1, &materials, &textures);
        lights.extend(punctual.iter().map(|l| punctual_light(l, scene_radius)));
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
        let cutout: Vec<bool> = attributes
            .iter()
            .map(|a| materials[a.material as usize].alpha_mode != AlphaMode::Opaque)
            .collect();
        let accel = Accel::build(&positions, extent, &cutout);
        let info = SceneInfo {
            name,
            triangles: positions.len(),
            lights: lights.len(),
            degenerate_triangles_dropped: dropped,
            default_camera,
            default_environment: false,
            lighting: String::new(),
            environment_warnings_from: warnings.len(),
            warnings,
            load_time: Duration::ZERO,
            bvh_build_time: start.elapsed(),
        };
        let mut scene = Scene {
            positions,
            attributes,
            uvs1,
            colors,
            materials,
            textures,
            lights,
            light_sampler,
            triangle_light,
            environment: None,
            camera,
            cameras,
            bounds,
            info,
            accel,
        };
        scene.set_environment(environment_settings);
        Ok(scene)
    }
}

fn is_degenerate(p: &[Vec3; 3]) -> bool {
    let area2 = (p[1] - p[0]).cross(p[2] - p[0]).length();
    !(area2 > 0.0) || !area2.is_finite()
}

/// Checks one mesh's arrays: whole triangles, finite positions, one normal and one texture
/// coordinate per position when present.
fn validate_mesh(mesh: &MeshDesc) -> Result<(), SceneError> {
    if !mesh.indices.len().is_multiple_of(3) {
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
    if let Some(uvs) = &mesh.uvs1 {
        check_len(uvs.len(), "second texture coordinates")?;
    }
    if let Some(colors) = &mesh.colors {
        check_len(colors.len(), "vertex colours")?;
    }
    Ok(())
}

/// The meshes' triangles in world space; a material index out of range takes the last
/// material (the default one the loader appends).
fn flatten_meshes(meshes: &[MeshDesc], material_count: u32) -> Result<Triangles, SceneError> {
    let default_material = material_count - 1;
    let mut positions = Vec::new();
    let mut attributes = Vec::new();
    let second_set = meshes.iter().any(|m| m.uvs1.is_some());
    let mut uvs1 = Vec::new();
    let vertex_colors = meshes.iter().any(|m| m.colors.is_some());
    let mut colors = Vec::new();
    let mut dropped = 0usize;
    let mut bounds = Bounds3::EMPTY;
    for mesh in meshes {
        validate_mesh(mesh)?;
        let n = mesh.positions.len();
        let material = if mesh.material < material_count {
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
            let corners = |set: Option<&Vec<Vec2>>| {
                let uvs = set.map(|uv| idx.map(|i| uv[i]));
                uvs.filter(|uvs| uvs.iter().all(|u| u.is_finite()))
            };
            let uvs = corners(mesh.uvs.as_ref()).unwrap_or([Vec2::ZERO; 3]);
            if second_set {
                uvs1.push(corners(mesh.uvs1.as_ref()).unwrap_or(uvs));
            }
            if vertex_colors {
                // Colours are factors in [0, 1]; anything else (NaN included) is white.
                let valid = |c: Vec4| c.is_finite() && c.cmpge(Vec4::ZERO).all();
                let c = mesh.colors.as_ref().map(|c| idx.map(|i| c[i]));
                colors.push(
                    c.filter(|c| c.iter().all(|&c| valid(c)))
                        .unwrap_or([Vec4::ONE; 3]),
                );
            }
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
    Ok(Triangles {
        positions,
        attributes,
        uvs1,
        colors,
        bounds,
        dropped,
    })
}

/// An area light for every triangle with an emissive material, but those whose emissive
/// texture is black wherever they can look it up (they emit nothing), each with its power
/// from its own footprint of the texture; and each triangle's light index (`NO_LIGHT` for the
/// others).
fn area_lights(
    positions: &[[Vec3; 3]],
    attributes: &[TriangleAttributes],
    uvs1: &[[Vec2; 3]],
    materials: &[Material],
    textures: &[Texture],
) -> (Vec<Light>, Vec<u32>) {
    let mut lights = Vec::new();
    let mut triangle_light = vec![NO_LIGHT; positions.len()];
    // Built on first use: only emissive textures need one.
    let mut prefixes: HashMap<u32, Option<LuminancePrefix>> = HashMap::new();
    for (i, (p, attr)) in positions.iter().zip(attributes).enumerate() {
        let m = &materials[attr.material as usize];
        if !m.is_emissive() {
            continue;
        }
        let uvs = [attr.uvs, uvs1.get(i).copied().unwrap_or(attr.uvs)];
        let texture = m
            .emissive_texture
            .and_then(|t| Some((t, textures.get(t.texture as usize)?)));
        let mean = match texture {
            None => m.emission,
            Some((reference, texture)) => {
                let index = reference.texture;
                let footprint = uvs[(reference.tex_coord as usize).min(1)]
                    .map(|uv| reference.transform.transform_point2(uv));
                let prefix = prefixes
                    .entry(index)
                    .or_insert_with(|| LuminancePrefix::new(texture));
                match prefix {
                    // The texture's colour at the footprint's strength: only the power's
                    // luminance is used, to choose lights.
                    Some(prefix) => match prefix.footprint_mean(footprint) {
                        None => continue,
                        Some(l) => m.emission * texture.mean_rgb() * (l / prefix.mean()),
                    },
                    None => m.emission * texture.mean_rgb(),
                }
            }
        };
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        triangle_light[i] = lights.len() as u32;
        lights.push(Light::Area(AreaLight {
            positions: *p,
            uvs,
            emission: m.emission,
            emissive_texture: m.emissive_texture,
            area: 0.5 * cross.length(),
            normal: cross.normalize(),
            two_sided: m.double_sided,
            mean_radiance: mean,
            cutout: (m.alpha_mode != AlphaMode::Opaque).then(|| {
                Box::new(Cutout {
                    alpha: m.alpha,
                    texture: m.base_color_texture,
                    mode: m.alpha_mode,
                })
            }),
        }));
    }
    (lights, triangle_light)
}

/// A punctual light of the description; directional lights need the scene's radius for the
/// disc their photons start from.
fn punctual_light(desc: &PunctualLightDesc, scene_radius: f32) -> Light {
    match *desc {
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
    }
}
