//! glTF 2.0 loader (`.gltf` with external or embedded buffers, and `.glb`), interpreting the
//! file exactly as DESIGN.md section 2 says. Bad input is an error naming the file and the
//! problem, never a panic: buffer views and accessors are bounds-checked before anything
//! reads them (`checks.rs`), the node graph is walked once per node with a depth limit
//! (`nodes.rs`), images, buffers and triangles are counted against [`LoadLimits`] before they
//! are allocated, and as a last line of defence a panic inside the gltf crate is caught and
//! reported as an error.
//!
//! One concept a file: `checks.rs` (parsing, validation, buffers, accessor bounds and types),
//! `nodes.rs` (the node walk, cameras, punctual lights), `mesh.rs` (primitives, morph targets,
//! strips and fans) with `draco.rs` (KHR_draco_mesh_compression), `material.rs` (the
//! metallic-roughness base) with `layers/` (one file per material extension that adds a
//! layer, read through one table), `texture.rs` (texture references, images, their limits)
//! and `export.rs` (the writer that makes the bundled scenes).

mod checks;
mod draco;
pub mod export;
mod layers;
mod material;
mod mesh;
mod nodes;
mod texture;

use crate::light::environment::EnvironmentSettings;
use crate::scene::limits::LoadLimits;
use crate::scene::{Scene, SceneDescription, SceneError};
use glam::Mat4;
use nodes::Visit;
use std::collections::HashMap;
use std::path::Path;
use std::time::Instant;

/// Extensions we implement; a file that requires any other is refused.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_emissive_strength",
    "KHR_texture_transform",
    "KHR_materials_unlit",
    "KHR_materials_volume",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_draco_mesh_compression",
];

/// Those of `SUPPORTED_EXTENSIONS` that the gltf crate does not parse (its features for the
/// material layers are off, so that every layer is read the same way): read from the JSON.
const READ_FROM_JSON: &[&str] = &[
    "KHR_materials_volume",
    "KHR_materials_specular",
    "KHR_materials_clearcoat",
    "KHR_materials_sheen",
    "KHR_draco_mesh_compression",
];

/// Loads and builds a scene from a glTF file, lit from outside as the default rule says.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, EnvironmentSettings::default(), &LoadLimits::default())
}

/// Loads and builds a scene from a glTF file with the environment `environment`, refusing
/// what exceeds `limits`.
pub fn load_with(
    path: &Path,
    environment: EnvironmentSettings,
    limits: &LoadLimits,
) -> Result<Scene, SceneError> {
    let start = Instant::now();
    let mut desc = load_description_with(path, limits)?;
    desc.environment = environment;
    let mut scene = Scene::build(desc).map_err(|e| e.in_file(path))?;
    scene.info.load_time = start.elapsed();
    Ok(scene)
}

/// Reads a glTF file into a scene description (no BVH yet).
pub fn load_description(path: &Path) -> Result<SceneDescription, SceneError> {
    load_description_with(path, &LoadLimits::default())
}

/// Reads a glTF file into a scene description, refusing what exceeds `limits`.
pub fn load_description_with(
    path: &Path,
    limits: &LoadLimits,
) -> Result<SceneDescription, SceneError> {
    let result = std::panic::catch_unwind(|| {
        let bytes = std::fs::read(path).map_err(|e| err(format!("cannot read file: {e}")))?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        description_from_bytes(
            &bytes,
            path.parent().unwrap_or(Path::new(".")),
            &name,
            limits,
        )
    });
    match result {
        Ok(r) => r.map_err(|e| e.in_file(path)),
        Err(_) => Err(SceneError::new("the glTF reader failed on malformed data").in_file(path)),
    }
}

fn err(problem: impl Into<String>) -> SceneError {
    SceneError::new(problem)
}

/// Reads the bytes of a `.gltf` or `.glb` file into a scene description named `name`, with
/// external files resolved against `base`. Unlike [`load_description`] a panic is not caught:
/// the fuzz targets call this, so that every panic is found and fixed.
pub fn description_from_bytes(
    bytes: &[u8],
    base: &Path,
    name: &str,
    limits: &LoadLimits,
) -> Result<SceneDescription, SceneError> {
    let (mut root, blob) = checks::parse(bytes)?;
    for ext in &root.extensions_required {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(err(format!(
                "requires the unsupported extension {ext}{}",
                what_to_do(ext)
            )));
        }
    }
    let ignored_extensions: Vec<String> = root
        .extensions_used
        .iter()
        .filter(|ext| !SUPPORTED_EXTENSIONS.contains(&ext.as_str()))
        .map(|ext| format!("uses the extension {ext}, which is not read (ignored)"))
        .collect();
    // The gltf crate refuses required extensions it does not parse itself; those we read
    // from the raw JSON have been checked above.
    root.extensions_required
        .retain(|ext| !READ_FROM_JSON.contains(&ext.as_str()));
    // Validate after the extension check, so an unknown required extension is named as such.
    let document = checks::validated(root)?;
    let buffers = checks::load_buffers(&document, base, blob, limits)?;
    checks::check_views_and_accessors(&document, &buffers)?;

    let mut loader = Loader {
        document: &document,
        buffers: &buffers,
        base,
        limits,
        desc: SceneDescription {
            name: name.to_string(),
            warnings: ignored_extensions,
            ..Default::default()
        },
        visited: vec![Visit::NotYet; document.nodes().len()],
        revisited: false,
        triangles: 0,
        material_index: HashMap::new(),
        texture_index: HashMap::new(),
        images: HashMap::new(),
    };
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next());
    match scene {
        Some(s) => {
            for node in s.nodes() {
                loader.visit(&node, Mat4::IDENTITY, 0)?;
            }
        }
        // The spec leaves a file without scenes to the application; like Blender's importer
        // we show every root node (one that is no node's child) rather than nothing.
        None => {
            loader
                .desc
                .warnings
                .push("the file has no scenes: showing every root node".into());
            let children: std::collections::HashSet<usize> = document
                .nodes()
                .flat_map(|n| n.children().map(|c| c.index()))
                .collect();
            for node in document.nodes().filter(|n| !children.contains(&n.index())) {
                loader.visit(&node, Mat4::IDENTITY, 0)?;
            }
        }
    }
    if loader.desc.meshes.is_empty() {
        return Err(err("the scene has no triangle meshes"));
    }
    Ok(loader.desc)
}

/// How a user gets a file that requires `ext` into a form we read, for the extensions that
/// compress what we would otherwise read.
fn what_to_do(ext: &str) -> &'static str {
    match ext {
        "EXT_meshopt_compression" => ": export the model again without mesh compression",
        "KHR_texture_basisu" | "EXT_texture_webp" | "MSFT_texture_dds" => {
            ": export the model again with PNG or JPEG textures"
        }
        _ => "",
    }
}

/// KHR_texture_transform's (offset, rotation, scale, texCoord).
type TransformParts = ([f32; 2], f32, [f32; 2], Option<u32>);

/// The walk of one file: what it has read so far, shared by every file of the folder.
struct Loader<'a> {
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    base: &'a Path,
    limits: &'a LoadLimits,
    desc: SceneDescription,
    /// Nodes reached so far: a node has at most one parent (spec 3.5.2), and a file that
    /// shares one, each level referring twice to the next, would otherwise be walked 2^depth
    /// times.
    visited: Vec<Visit>,
    revisited: bool,
    /// Triangles so far, instances counted each time.
    triangles: u64,
    material_index: HashMap<Option<usize>, u32>,
    texture_index: HashMap<(usize, bool), u32>,
    images: HashMap<usize, Option<(usize, usize, Vec<u8>)>>,
}
