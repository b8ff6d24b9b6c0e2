//! KHR_materials_clearcoat: a clear dielectric coat over the base (`material/clearcoat.rs`).
//! The coat's own normal texture is not read: it takes the base's normals.

use super::LayerReader;
use crate::material::Material;
use crate::scene::SceneError;

pub(super) fn read(r: &mut LayerReader, m: &mut Material) -> Result<(), SceneError> {
    m.clearcoat = r.factor("clearcoatFactor", 0.0)?;
    m.clearcoat_roughness = r.factor("clearcoatRoughnessFactor", 0.0)?;
    // The factor in the texture's R channel, the roughness in G; both linear.
    m.clearcoat_texture = r.texture("clearcoatTexture", false)?;
    m.clearcoat_roughness_texture = r.texture("clearcoatRoughnessTexture", false)?;
    if r.has("clearcoatNormalTexture") {
        r.ignore(
            "clearcoatNormalTexture",
            "the coat takes the base's normals",
        );
    }
    Ok(())
}
