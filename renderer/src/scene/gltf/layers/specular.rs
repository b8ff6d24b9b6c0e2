//! KHR_materials_specular: the strength and colour of the base's dielectric specular
//! reflection (`material/metallic_roughness.rs` says how they enter the BSDF).

use super::LayerReader;
use crate::material::Material;
use crate::scene::SceneError;
use glam::Vec3;

pub(super) fn read(r: &mut LayerReader, m: &mut Material) -> Result<(), SceneError> {
    m.specular = r.factor("specularFactor", 1.0)?;
    m.specular_color = r.color("specularColorFactor", Vec3::ONE)?;
    // The factor is read from the texture's alpha channel, the colour from its RGB (sRGB).
    m.specular_texture = r.texture("specularTexture", false)?;
    m.specular_color_texture = r.texture("specularColorTexture", true)?;
    Ok(())
}
