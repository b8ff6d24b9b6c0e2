//! KHR_materials_volume: the medium inside a closed mesh, as the absorption coefficient of
//! Beer-Lambert's law. The thickness texture is not read: a path tracer follows the real
//! distance through the mesh, and the factor only says whether there is a volume.

use super::LayerReader;
use crate::material::Material;
use crate::scene::SceneError;
use glam::Vec3;

pub(super) fn read(r: &mut LayerReader, m: &mut Material) -> Result<(), SceneError> {
    let thickness = r.factor("thicknessFactor", 0.0)?;
    let distance = r.factor("attenuationDistance", f32::INFINITY)?;
    let color = r.color("attenuationColor", Vec3::ONE)?;
    m.absorption = absorption(thickness, color, distance);
    Ok(())
}

/// Light that travels `distance` inside keeps `color` of itself, so sigma_a = -ln(color) /
/// distance per channel (the extension's Beer-Lambert law). A thickness of zero means
/// thin-walled (no volume), and an infinite distance (the default) no absorption.
fn absorption(thickness: f32, color: Vec3, distance: f32) -> Vec3 {
    if thickness <= 0.0 || !(distance > 0.0) || distance == f32::INFINITY {
        return Vec3::ZERO;
    }
    -color.clamp(Vec3::splat(1e-30), Vec3::ONE).ln() / distance
}
