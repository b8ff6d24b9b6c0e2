//! A glTF material (section 3.9): the metallic-roughness base with its textures,
//! transmission, ior, emissive strength, alpha mode, the normal texture and the unlit look,
//! each factor checked; the layers that extensions add over the base are read by `layers/`.

use super::{Loader, err, layers};
use crate::material::{AlphaMode, Material};
use crate::scene::SceneError;
use glam::Vec3;

impl Loader<'_> {
    /// The index of `m` in the scene's materials, read on its first use.
    pub(super) fn material(&mut self, m: gltf::Material) -> Result<u32, SceneError> {
        if let Some(&i) = self.material_index.get(&m.index()) {
            return Ok(i);
        }
        let pbr = m.pbr_metallic_roughness();
        let base = pbr.base_color_factor();
        let strength = m.emissive_strength().unwrap_or(1.0);
        let mut material = Material {
            name: m.name().unwrap_or("").to_string(),
            base_color: Vec3::new(base[0], base[1], base[2]),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            transmission: m.transmission().map_or(0.0, |t| t.transmission_factor()),
            ior: m.ior().unwrap_or(1.5),
            emission: Vec3::from(m.emissive_factor()) * strength,
            double_sided: m.double_sided(),
            alpha: base[3].clamp(0.0, 1.0),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            ..Default::default()
        };
        let label = material.name.clone();
        let checks = [
            ("baseColorFactor", material.base_color.is_finite()),
            ("metallicFactor", material.metallic.is_finite()),
            ("roughnessFactor", material.roughness.is_finite()),
            (
                "emission",
                material.emission.is_finite() && material.emission.min_element() >= 0.0,
            ),
            ("ior", material.ior.is_finite() && material.ior > 0.0),
            ("baseColorFactor alpha", material.alpha.is_finite()),
            (
                "alphaCutoff",
                !matches!(material.alpha_mode, AlphaMode::Mask(c) if !c.is_finite()),
            ),
        ];
        for (what, ok) in checks {
            if !ok {
                return Err(err(format!("material '{label}': invalid {what}")));
            }
        }
        material.base_color_texture = pbr
            .base_color_texture()
            .and_then(|t| self.texture_info(&t, true));
        material.metallic_roughness_texture = pbr
            .metallic_roughness_texture()
            .and_then(|t| self.texture_info(&t, false));
        material.emissive_texture = m
            .emissive_texture()
            .and_then(|t| self.texture_info(&t, true));
        layers::read(self, &m, &mut material)?;
        if let Some(t) = m.normal_texture() {
            // The gltf crate reads no transform on a normal texture: take the JSON's.
            let transform = t
                .extension_value("KHR_texture_transform")
                .and_then(|v| {
                    serde_json::from_value::<gltf::json::extensions::texture::TextureTransform>(
                        v.clone(),
                    )
                    .ok()
                })
                .map(|t| (t.offset.0, t.rotation.0, t.scale.0, t.tex_coord));
            let (transform, tex_coord) =
                self.transform(t.texture().index(), transform, t.tex_coord());
            material.normal_texture = self
                .texture(&t.texture(), tex_coord, transform, false)
                .map(|r| (r, t.scale()));
        }
        if m.unlit() {
            // KHR_materials_unlit asks for the base colour as it stands, whatever the light: a
            // path tracer shows that as a black surface emitting its base colour (which then
            // also lights what is near it).
            self.desc.warnings.push(format!(
                "material '{label}' asks for an unlit look (KHR_materials_unlit): shown as an \
                 emitter of its base colour"
            ));
            material.emission = material.base_color;
            material.emissive_texture = material.base_color_texture;
            material.base_color = Vec3::ZERO;
            material.base_color_texture = None;
            // Black diffuse: it reflects nothing (a glossy lobe would still mirror 4 %).
            material.metallic = 0.0;
            material.roughness = 1.0;
            material.metallic_roughness_texture = None;
            material.normal_texture = None;
            material.transmission = 0.0;
        }
        let i = self.desc.materials.len() as u32;
        self.desc.materials.push(material);
        self.material_index.insert(m.index(), i);
        Ok(i)
    }
}
