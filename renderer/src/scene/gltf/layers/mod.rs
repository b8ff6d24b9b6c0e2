//! The material extensions that add a layer over the metallic-roughness base, or change one
//! of its parts: KHR_materials_specular, _clearcoat, _sheen and _volume. Each is one entry of
//! [`LAYERS`], its extension's name and a function of its own file that reads the extension's
//! JSON object through a [`LayerReader`], which does what every layer needs: factors and
//! colours read with their defaults and checked (finite, not negative), textureInfo objects
//! read with their transforms, and anything wrong named by its JSON path. A new layer is one
//! file and one entry here (and its fields in `Material`, its lobe in `material/`).
//!
//! The gltf crate's own parsers for these extensions are turned off (the workspace's gltf
//! features), so all of them arrive the same way: as the material's raw extension JSON.

mod clearcoat;
mod sheen;
mod specular;
mod volume;

use super::{Loader, err};
use crate::material::{Material, TextureRef};
use crate::scene::SceneError;
use glam::Vec3;
use serde_json::Value;

/// A material extension read into the material's layers.
struct Layer {
    extension: &'static str,
    read: fn(&mut LayerReader, &mut Material) -> Result<(), SceneError>,
}

/// Every layer we read, in the order they are read (none depends on another).
const LAYERS: &[Layer] = &[
    Layer {
        extension: "KHR_materials_specular",
        read: specular::read,
    },
    Layer {
        extension: "KHR_materials_clearcoat",
        read: clearcoat::read,
    },
    Layer {
        extension: "KHR_materials_sheen",
        read: sheen::read,
    },
    Layer {
        extension: "KHR_materials_volume",
        read: volume::read,
    },
];

/// Reads every layer `m`'s extensions carry into `material`.
pub(super) fn read(
    loader: &mut Loader,
    m: &gltf::Material,
    material: &mut Material,
) -> Result<(), SceneError> {
    for layer in LAYERS {
        let Some(json) = m.extensions().and_then(|e| e.get(layer.extension)) else {
            continue;
        };
        let mut reader = LayerReader {
            loader: &mut *loader,
            json,
            at: format!(
                "materials[{}].extensions.{}",
                m.index().unwrap_or(0),
                layer.extension
            ),
        };
        (layer.read)(&mut reader, material)?;
    }
    Ok(())
}

/// One extension's JSON object, at JSON path `at`, and the loader its textures go to.
pub(super) struct LayerReader<'l, 'a> {
    loader: &'l mut Loader<'a>,
    json: &'l Value,
    at: String,
}

impl LayerReader<'_, '_> {
    /// The number `name`, `default` when absent; an error unless finite and not negative
    /// (every factor of these extensions is, and a colour may exceed 1: KHR_materials_specular
    /// allows it).
    pub fn factor(&self, name: &str, default: f32) -> Result<f32, SceneError> {
        let Some(value) = self.json.get(name) else {
            return Ok(default);
        };
        let v = value
            .as_f64()
            .ok_or_else(|| err(format!("{}.{name}: not a number", self.at)))?
            as f32;
        if !(v.is_finite() && v >= 0.0) {
            return Err(err(format!(
                "{}.{name}: {v} is not a finite number of at least 0",
                self.at
            )));
        }
        Ok(v)
    }

    /// The RGB colour `name`, `default` when absent; each channel checked as a factor.
    pub fn color(&self, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        let Some(value) = self.json.get(name) else {
            return Ok(default);
        };
        let c = serde_json::from_value::<[f32; 3]>(value.clone())
            .map(Vec3::from)
            .map_err(|_| err(format!("{}.{name}: not three numbers", self.at)))?;
        if !(c.is_finite() && c.min_element() >= 0.0) {
            return Err(err(format!(
                "{}.{name}: {c} is not three finite numbers of at least 0",
                self.at
            )));
        }
        Ok(c)
    }

    /// The textureInfo `name` (spec 5.29), read in sRGB or linearly; None when absent.
    pub fn texture(&mut self, name: &str, srgb: bool) -> Result<Option<TextureRef>, SceneError> {
        match self.json.get(name) {
            None => Ok(None),
            Some(info) => self.loader.json_texture_info(info, &self.at, name, srgb),
        }
    }

    /// Whether the object has `name`, for the parts a layer does not read.
    pub fn has(&self, name: &str) -> bool {
        self.json.get(name).is_some()
    }

    /// Warns that `name` is read no further, and why.
    pub fn ignore(&mut self, name: &str, why: &str) {
        let warning = format!("{}.{name} ignored: {why}", self.at);
        self.loader.desc.warnings.push(warning);
    }
}
