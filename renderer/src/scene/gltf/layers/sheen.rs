//! KHR_materials_sheen: a fibre-like sheen lobe over the base (`material/sheen.rs`).

use super::LayerReader;
use crate::material::Material;
use crate::scene::SceneError;
use glam::Vec3;

pub(super) fn read(r: &mut LayerReader, m: &mut Material) -> Result<(), SceneError> {
    m.sheen_color = r.color("sheenColorFactor", Vec3::ZERO)?;
    m.sheen_roughness = r.factor("sheenRoughnessFactor", 0.0)?;
    // The colour in the texture's RGB (sRGB), the roughness in its alpha channel.
    m.sheen_color_texture = r.texture("sheenColorTexture", true)?;
    m.sheen_roughness_texture = r.texture("sheenRoughnessTexture", false)?;
    Ok(())
}
