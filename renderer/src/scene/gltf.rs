//! glTF 2.0 loader (`.gltf` with external or embedded buffers, and `.glb`), interpreting the
//! file exactly as DESIGN.md section 2 says. Bad input is an error naming the file and the
//! problem, never a panic: buffer views and accessors are bounds-checked before anything
//! reads them, the node graph is walked once per node with a depth limit, images, buffers
//! and triangles are counted against [`LoadLimits`] before they are allocated, and as a last
//! line of defence a panic inside the gltf crate is caught and reported as an error.

use crate::camera::{CameraDesc, Projection};
use crate::light::environment::EnvironmentSettings;
use crate::material::{AlphaMode, Material, TextureRef};
use crate::scene::limits::LoadLimits;
use crate::scene::{MeshDesc, PunctualLightDesc, Scene, SceneDescription, SceneError};
use crate::texture::{Texture, Wrap};
use glam::{Affine2, Affine3A, Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
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

/// Those of `SUPPORTED_EXTENSIONS` that the gltf crate does not parse: read from the JSON.
const READ_FROM_JSON: &[&str] = &[
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
    let (mut root, blob) = parse(bytes)?;
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
    let document = validated(root)?;
    let buffers = load_buffers(&document, base, blob, limits)?;
    check_views_and_accessors(&document, &buffers)?;

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

/// The number `name` of an extension's JSON object `parent` (at JSON path `at`); 0 when
/// absent, as every factor the layered-material extensions define defaults to.
fn json_number(parent: &serde_json::Value, name: &str, at: &str) -> Result<f32, SceneError> {
    match parent.get(name) {
        None => Ok(0.0),
        Some(v) => v
            .as_f64()
            .map(|v| v as f32)
            .ok_or_else(|| err(format!("{at}.{name}: not a number"))),
    }
}

/// KHR_materials_volume's absorption coefficient: light that travels `attenuation_distance`
/// inside keeps `attenuation_color` of itself, so sigma_a = -ln(color) / distance per channel
/// (the extension's Beer-Lambert law). A thickness of zero means thin-walled: no volume.
fn absorption(thickness: f32, color: [f32; 3], distance: f32) -> Vec3 {
    if thickness <= 0.0 || !(distance > 0.0) || distance == f32::INFINITY {
        return Vec3::ZERO;
    }
    -Vec3::from(color).clamp(Vec3::splat(1e-30), Vec3::ONE).ln() / distance
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

/// The JSON document and the binary chunk of a `.gltf` or `.glb` file. A scene without a
/// `nodes` array is valid glTF (the property is optional) but the gltf crate requires it, so
/// the JSON is read as a value first and the empty array supplied.
fn parse(bytes: &[u8]) -> Result<(gltf::json::Root, Option<Vec<u8>>), SceneError> {
    let invalid = |e: &dyn std::fmt::Display| err(format!("not a valid glTF file: {e}"));
    // The JSON is read where it lies (a .gltf with embedded buffers can be tens of MB).
    let (json, blob) = if bytes.starts_with(b"glTF") {
        // The gltf crate subtracts the header's size from the length the header declares
        // before it compares (an overflow, found by fuzzing).
        let declared = bytes
            .get(8..12)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
        if declared.is_none_or(|length| length < 12) {
            return Err(invalid(&format!(
                "the GLB header declares a length of {declared:?} bytes, less than the header's 12"
            )));
        }
        let glb = gltf::Glb::from_slice(bytes).map_err(|e| invalid(&e))?;
        (glb.json, glb.bin.map(|b| b.into_owned()))
    } else {
        (std::borrow::Cow::Borrowed(bytes), None)
    };
    let mut value: serde_json::Value = serde_json::from_slice(&json).map_err(|e| invalid(&e))?;
    if let Some(scenes) = value.get_mut("scenes").and_then(|s| s.as_array_mut()) {
        for scene in scenes.iter_mut().filter_map(|s| s.as_object_mut()) {
            scene
                .entry("nodes")
                .or_insert_with(|| serde_json::json!([]));
        }
    }
    let root = serde_json::from_value(value).map_err(|e| invalid(&e))?;
    Ok((root, blob))
}

/// The document, once the gltf crate's validation finds nothing wrong with it other than
/// what KHR_draco_mesh_compression allows: the accessors of a compressed primitive keep
/// their count and type but need no buffer view (the data is in the bitstream).
fn validated(root: gltf::json::Root) -> Result<gltf::Document, SceneError> {
    use gltf::json::validation::{Error, Validate};
    let mut compressed = std::collections::HashSet::new();
    for primitive in root.meshes.iter().flat_map(|m| &m.primitives) {
        let draco = primitive
            .extensions
            .as_ref()
            .is_some_and(|e| e.others.contains_key("KHR_draco_mesh_compression"));
        if draco {
            compressed.extend(primitive.attributes.values().map(|a| a.value()));
            compressed.extend(primitive.indices.as_ref().map(|a| a.value()));
        }
    }
    // The gltf crate's validator indexes a primitive's POSITION accessor before it checks the
    // index (a panic, found by fuzzing): attribute indices are checked first.
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive
                .attributes
                .values()
                .find(|a| a.value() >= accessors)
            {
                return Err(err(format!(
                    "invalid glTF: meshes[{m}].primitives[{p}].attributes: accessor {} does not \
                     exist ({accessors} accessors)",
                    index.value()
                )));
            }
        }
    }
    let mut problems = Vec::new();
    root.validate(&root, gltf::json::Path::new, &mut |path, error| {
        let path = path();
        let allowed = matches!(error, Error::Missing)
            && compressed
                .iter()
                .any(|i| path.as_str() == format!("accessors[{i}].bufferView"));
        if !allowed {
            problems.push((path, error));
        }
    });
    if !problems.is_empty() {
        return Err(validation_error(gltf::Error::Validation(problems)));
    }
    Ok(gltf::Document::from_json_without_validation(root))
}

/// The first problem the validator found, with its JSON path, and how many more there are
/// (the gltf crate's own message lists them all on one line).
fn validation_error(e: gltf::Error) -> SceneError {
    let gltf::Error::Validation(problems) = e else {
        return err(format!("invalid glTF: {e}"));
    };
    let Some((path, problem)) = problems.first() else {
        return err("invalid glTF");
    };
    let more = match problems.len() - 1 {
        0 => String::new(),
        1 => " (and 1 more problem)".into(),
        n => format!(" (and {n} more problems)"),
    };
    err(format!("invalid glTF: {path}: {problem}{more}"))
}

/// Every buffer's bytes; a buffer that cannot be read is named by index and URI.
fn load_buffers(
    document: &gltf::Document,
    base: &Path,
    mut blob: Option<Vec<u8>>,
    limits: &LoadLimits,
) -> Result<Vec<gltf::buffer::Data>, SceneError> {
    // Declared lengths first, and an external file's size before it is read: data URIs and
    // the GLB chunk are in memory already.
    let mut total: u64 = 0;
    for buffer in document.buffers() {
        let mut size = buffer.length() as u64;
        if let gltf::buffer::Source::Uri(uri) = buffer.source()
            && !uri.starts_with("data:")
            && let Ok(meta) = std::fs::metadata(base.join(uri))
        {
            size = size.max(meta.len());
        }
        total = total.saturating_add(size);
    }
    if total > limits.max_buffer_bytes {
        return Err(err(LoadLimits::refusal(
            &format!("the buffers hold {total} bytes"),
            limits.max_buffer_bytes,
            "--max-buffer-bytes",
        )));
    }
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let name = match buffer.source() {
            gltf::buffer::Source::Uri(uri) if !uri.starts_with("data:") => format!(" ({uri})"),
            gltf::buffer::Source::Uri(_) => " (data URI)".into(),
            gltf::buffer::Source::Bin => " (the GLB binary chunk)".into(),
        };
        let index = buffer.index();
        let data = gltf::buffer::Data::from_source_and_blob(buffer.source(), Some(base), &mut blob)
            .map_err(|e| err(format!("buffers[{index}]{name}: cannot load: {e}")))?;
        if data.len() < buffer.length() {
            return Err(err(format!(
                "buffers[{index}]{name}: holds {} bytes, the file says {}",
                data.len(),
                buffer.length()
            )));
        }
        buffers.push(data);
    }
    Ok(buffers)
}

/// Bounds of every buffer view and accessor, so no read can go past its buffer.
fn check_views_and_accessors(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
) -> Result<(), SceneError> {
    for view in document.views() {
        let len = buffers.get(view.buffer().index()).map_or(0, |b| b.len());
        let end = view.offset().checked_add(view.length());
        if end.is_none_or(|e| e > len) {
            return Err(err(format!(
                "buffer view {} (offset {}, length {}) runs past its buffer of {len} bytes",
                view.index(),
                view.offset(),
                view.length()
            )));
        }
    }
    for acc in document.accessors() {
        if let Some(sparse) = acc.sparse() {
            check_sparse(&acc, &sparse, buffers)?;
        }
        // The gltf crate's reader counts from count - 1 (an overflow at 0, found by fuzzing);
        // the spec's minimum is 1.
        if acc.count() == 0 {
            return Err(err(format!(
                "accessor {}: count 0 (glTF requires at least 1)",
                acc.index()
            )));
        }
        let Some(view) = acc.view() else { continue };
        let elem = acc.size();
        let stride = view.stride().unwrap_or(elem);
        let count = acc.count();
        let needed = stride
            .checked_mul(count - 1)
            .and_then(|s| s.checked_add(elem))
            .and_then(|s| s.checked_add(acc.offset()));
        if needed.is_none_or(|n| n > view.length()) || stride < elem {
            return Err(err(format!(
                "accessor {}: {count} elements of {elem} bytes do not fit buffer view {} ({} bytes)",
                acc.index(),
                view.index(),
                view.length()
            )));
        }
    }
    Ok(())
}

/// A sparse accessor's index and value arrays fit their views, and its indices rise strictly
/// and stay below the accessor's count: the gltf crate's reader assumes both (spec 3.6.2.3)
/// and would drop values silently or panic otherwise.
fn check_sparse(
    acc: &gltf::Accessor,
    sparse: &gltf::accessor::sparse::Sparse,
    buffers: &[gltf::buffer::Data],
) -> Result<(), SceneError> {
    let at = |what: &str| format!("accessors[{}].sparse{what}", acc.index());
    let count = sparse.count();
    if count == 0 || count > acc.count() {
        return Err(err(format!(
            "{}: count {count} is not in 1..={} (the accessor's count)",
            at(""),
            acc.count()
        )));
    }
    // Bytes `offset .. offset + count * size` of a view, or None when they run past it.
    let slice = |view: gltf::buffer::View, offset: usize, size: usize| {
        let data = &buffers.get(view.buffer().index())?.0;
        let view_bytes = data.get(view.offset()..view.offset().checked_add(view.length())?)?;
        view_bytes.get(offset..offset.checked_add(count.checked_mul(size)?)?)
    };
    let values = sparse.values();
    if slice(values.view(), values.offset(), acc.size()).is_none() {
        return Err(err(format!(
            "{}: {count} values of {} bytes run past buffer view {}",
            at(".values"),
            acc.size(),
            values.view().index()
        )));
    }
    let indices = sparse.indices();
    let size = indices.index_type().size();
    let Some(bytes) = slice(indices.view(), indices.offset(), size) else {
        return Err(err(format!(
            "{}: {count} indices of {size} bytes run past buffer view {}",
            at(".indices"),
            indices.view().index()
        )));
    };
    let mut previous = None;
    for chunk in bytes.chunks_exact(size) {
        let mut le = [0u8; 4];
        le[..size].copy_from_slice(chunk);
        let index = u32::from_le_bytes(le) as usize;
        if index >= acc.count() || previous.is_some_and(|p| index <= p) {
            return Err(err(format!(
                "{}: index {index} is out of range or not above the one before it",
                at(".indices")
            )));
        }
        previous = Some(index);
    }
    Ok(())
}

/// The accessor types glTF 2.0 allows each vertex attribute, the indices and the morph
/// targets (3.7.2.1), as far as the gltf crate's readers rely on them: they read an element
/// of the type the semantic implies and panic on a component type it does not expect (found
/// by fuzzing).
fn check_accessor_types(prim: &gltf::Primitive) -> Result<(), String> {
    use gltf::Semantic;
    use gltf::accessor::{DataType, Dimensions};
    let small = |t| matches!(t, DataType::U8 | DataType::U16 | DataType::F32);
    let allowed = |semantic: &Semantic, d: Dimensions, t: DataType| match semantic {
        Semantic::Positions | Semantic::Normals => d == Dimensions::Vec3 && t == DataType::F32,
        Semantic::Tangents => d == Dimensions::Vec4 && t == DataType::F32,
        Semantic::TexCoords(_) => d == Dimensions::Vec2 && small(t),
        Semantic::Colors(_) => matches!(d, Dimensions::Vec3 | Dimensions::Vec4) && small(t),
        Semantic::Joints(_) => d == Dimensions::Vec4 && matches!(t, DataType::U8 | DataType::U16),
        Semantic::Weights(_) => d == Dimensions::Vec4 && small(t),
        // Application-specific attributes (_NAME) are not read.
        _ => true,
    };
    let refuse = |what: String, acc: &gltf::Accessor| {
        Err(format!(
            "{what}: accessor {} holds {:?} of {:?}, which glTF does not allow there",
            acc.index(),
            acc.dimensions(),
            acc.data_type()
        ))
    };
    for (semantic, acc) in prim.attributes() {
        if !allowed(&semantic, acc.dimensions(), acc.data_type()) {
            return refuse(format!("attribute {semantic:?}"), &acc);
        }
    }
    if let Some(acc) = prim.indices()
        && (acc.dimensions() != Dimensions::Scalar
            || !matches!(
                acc.data_type(),
                DataType::U8 | DataType::U16 | DataType::U32
            ))
    {
        return refuse("indices".into(), &acc);
    }
    for (t, target) in prim.morph_targets().enumerate() {
        let displacements = [target.positions(), target.normals(), target.tangents()];
        for acc in displacements.into_iter().flatten() {
            if acc.dimensions() != Dimensions::Vec3 || acc.data_type() != DataType::F32 {
                return refuse(format!("morph target {t}"), &acc);
            }
        }
    }
    Ok(())
}

/// KHR_texture_transform's (offset, rotation, scale, texCoord).
type TransformParts = ([f32; 2], f32, [f32; 2], Option<u32>);

/// A primitive's vertex attributes in the model's space, from accessors or a decoded Draco
/// bitstream; indices None means the vertices in order.
struct VertexData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    uvs: Option<Vec<Vec2>>,
    uvs1: Option<Vec<Vec2>>,
    colors: Option<Vec<Vec4>>,
    indices: Option<Vec<u32>>,
}

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

/// Where the walk of the node graph is with a node.
#[derive(Clone, Copy, PartialEq)]
enum Visit {
    NotYet,
    /// Its subtree is being walked: reaching it again is a cycle.
    Walking,
    Done,
}

fn rigid(m: Mat4) -> Affine3A {
    let (_, rotation, translation) = m.to_scale_rotation_translation();
    let rotation = if rotation.is_finite() {
        rotation.normalize()
    } else {
        Quat::IDENTITY
    };
    Affine3A::from_rotation_translation(rotation, translation)
}

impl Loader<'_> {
    fn visit(&mut self, node: &gltf::Node, parent: Mat4, depth: usize) -> Result<(), SceneError> {
        if depth as u64 > self.limits.max_node_depth {
            return Err(err(LoadLimits::refusal(
                &format!("node {}: the node hierarchy is deeper", node.index()),
                self.limits.max_node_depth,
                "--max-node-depth",
            )));
        }
        match self.visited[node.index()] {
            Visit::NotYet => {}
            Visit::Walking => {
                return Err(err(format!(
                    "node {} is its own ancestor: the node hierarchy has a cycle",
                    node.index()
                )));
            }
            Visit::Done if !self.revisited => {
                self.revisited = true;
                self.desc.warnings.push(format!(
                    "node {} is reached a second time and shown once: a node has one parent \
                     at most, and a scene's roots none (glTF 2.0, 3.5.2)",
                    node.index()
                ));
                return Ok(());
            }
            Visit::Done => return Ok(()),
        }
        self.visited[node.index()] = Visit::Walking;
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        if !world.is_finite() {
            return Err(err(format!(
                "node {}: transform is NaN or infinite",
                node.index()
            )));
        }
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                self.desc.warnings.push(format!(
                    "nodes[{}]: skin ignored, the mesh is shown in its bind pose",
                    node.index()
                ));
            }
            // The node's morph weights override the mesh's (spec 3.7.2.2).
            let weights = node.weights().or(mesh.weights()).unwrap_or(&[]);
            self.add_mesh(&mesh, world, weights)?;
        }
        if let Some(camera) = node.camera() {
            let (projection, aspect) = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    (Projection::Perspective { yfov: p.yfov() }, p.aspect_ratio())
                }
                // xmag and ymag are half the film's width and height (spec 3.10.3).
                gltf::camera::Projection::Orthographic(o) => (
                    Projection::Orthographic { ymag: o.ymag() },
                    Some(o.xmag() / o.ymag()),
                ),
            };
            let film = match projection {
                Projection::Perspective { yfov } => yfov > 0.0 && yfov < std::f32::consts::PI,
                Projection::Orthographic { ymag } => ymag > 0.0 && ymag.is_finite(),
            } && aspect.is_none_or(|a| a > 0.0 && a.is_finite());
            if film {
                let desc = CameraDesc {
                    camera_to_world: rigid(world),
                    projection,
                    aspect,
                };
                // The first is the scene's camera; all are offered to the viewer.
                self.desc.camera.get_or_insert(desc);
                let name = camera
                    .name()
                    .or(node.name())
                    .map_or_else(|| format!("camera {}", camera.index()), str::to_string);
                self.desc.cameras.push((name, desc));
            } else {
                self.desc.warnings.push(format!(
                    "cameras[{}]: a film of no size ({projection:?}, aspect {aspect:?}) is ignored",
                    camera.index()
                ));
            }
        }
        if let Some(light) = node.light() {
            self.add_light(&light, world);
        }
        for child in node.children() {
            self.visit(&child, world, depth + 1)?;
        }
        self.visited[node.index()] = Visit::Done;
        Ok(())
    }

    fn add_light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4) {
        let color = Vec3::from(light.color()) * light.intensity();
        let xf = rigid(world);
        let position = Vec3::from(xf.translation);
        let direction = xf.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
        if !color.is_finite() || color.min_element() < 0.0 {
            self.desc.warnings.push(format!(
                "light {}: negative or non-finite intensity, ignored",
                light.index()
            ));
            return;
        }
        use gltf::khr_lights_punctual::Kind;
        self.desc.lights.push(match light.kind() {
            Kind::Point => PunctualLightDesc::Point {
                position,
                intensity: color,
            },
            Kind::Directional => PunctualLightDesc::Directional {
                direction,
                irradiance: color,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => PunctualLightDesc::Spot {
                position,
                direction,
                intensity: color,
                inner_cone: inner_cone_angle.clamp(0.0, outer_cone_angle),
                outer_cone: outer_cone_angle.clamp(0.0, std::f32::consts::FRAC_PI_2),
            },
        });
    }

    /// The mesh's triangle primitives in world space, morphed by `weights` (spec 3.7.2.2:
    /// each target's displacements, times its weight, added to the base attributes).
    fn add_mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: Mat4,
        weights: &[f32],
    ) -> Result<(), SceneError> {
        let name = mesh
            .name()
            .map_or_else(|| format!("mesh {}", mesh.index()), str::to_string);
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.desc.warnings.push(format!(
                    "{name}: primitive with mode {mode:?} skipped (points and lines have no area)"
                ));
                continue;
            }
            let material = self.material(prim.material())?;
            // The second set only where a texture reads it (files often carry lightmap
            // coordinates we have no use for).
            let want_uvs1 = self.desc.materials[material as usize]
                .texture_refs()
                .any(|r| r.tex_coord == 1);
            let draco = prim.extension_value("KHR_draco_mesh_compression");
            let data = match draco {
                Some(ext) => {
                    if weights.iter().any(|&w| w != 0.0) {
                        self.desc.warnings.push(format!(
                            "{name}: morph targets of a Draco-compressed primitive ignored"
                        ));
                    }
                    let d = super::draco::decode(self.document, self.buffers, ext)
                        .map_err(|e| err(format!("{name}: KHR_draco_mesh_compression: {e}")))?;
                    let [uvs, uvs1] = d.tex_coords;
                    VertexData {
                        positions: d.positions,
                        normals: d.normals,
                        uvs,
                        uvs1: uvs1.filter(|_| want_uvs1),
                        colors: d.colors,
                        indices: Some(d.indices),
                    }
                }
                None => self.read_accessors(&prim, weights, want_uvs1, &name)?,
            };
            let VertexData {
                positions,
                normals,
                uvs,
                uvs1,
                colors,
                indices,
            } = data;
            let positions: Vec<Vec3> = positions
                .into_iter()
                .map(|p| world.transform_point3(p))
                .collect();
            if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
                return Err(err(format!("{name}: position {i} is NaN or infinite")));
            }
            let normals = normals.map(|ns| {
                ns.into_iter()
                    .map(|n| (normal_matrix * n).normalize_or_zero())
                    .collect::<Vec<_>>()
            });
            let mut indices = indices.unwrap_or_else(|| (0..positions.len() as u32).collect());
            // A Draco bitstream decodes to a triangle list whatever the mode says.
            match mode {
                _ if draco.is_some() => {}
                Mode::TriangleStrip => indices = strip_to_list(&indices),
                Mode::TriangleFan => indices = fan_to_list(&indices),
                _ => {}
            }
            if indices.len() % 3 != 0 {
                self.desc.warnings.push(format!(
                    "{name}: {} trailing indices ignored",
                    indices.len() % 3
                ));
                indices.truncate(indices.len() / 3 * 3);
            }
            self.triangles += indices.len() as u64 / 3;
            if self.triangles > self.limits.max_triangles {
                return Err(err(LoadLimits::refusal(
                    &format!(
                        "{name}: the scene holds {} triangles so far, each instance counted",
                        self.triangles
                    ),
                    self.limits.max_triangles,
                    "--max-triangles",
                )));
            }
            if flip {
                for tri in indices.chunks_exact_mut(3) {
                    tri.swap(1, 2);
                }
            }
            self.desc.meshes.push(MeshDesc {
                name: name.clone(),
                positions,
                normals,
                uvs,
                uvs1,
                colors,
                indices,
                material,
            });
        }
        Ok(())
    }

    /// A primitive's vertex attributes from its accessors, displaced by its morph targets at
    /// `weights` (spec 3.7.2.2).
    fn read_accessors(
        &self,
        prim: &gltf::Primitive,
        weights: &[f32],
        want_uvs1: bool,
        name: &str,
    ) -> Result<VertexData, SceneError> {
        check_accessor_types(prim).map_err(|e| err(format!("{name}: {e}")))?;
        let reader = prim.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
        let Some(positions) = reader.read_positions() else {
            return Err(err(format!("{name}: primitive without POSITION")));
        };
        let mut positions: Vec<Vec3> = positions.map(Vec3::from).collect();
        let mut normals: Option<Vec<Vec3>> =
            reader.read_normals().map(|ns| ns.map(Vec3::from).collect());
        for (target, &weight) in reader.read_morph_targets().zip(weights) {
            if weight == 0.0 || !weight.is_finite() {
                continue;
            }
            let (dp, dn, _) = target;
            for (p, d) in positions.iter_mut().zip(dp.into_iter().flatten()) {
                *p += weight * Vec3::from(d);
            }
            if let Some(normals) = normals.as_mut() {
                for (n, d) in normals.iter_mut().zip(dn.into_iter().flatten()) {
                    *n += weight * Vec3::from(d);
                }
            }
        }
        let tex_coords = |set| {
            reader
                .read_tex_coords(set)
                .map(|t| t.into_f32().map(Vec2::from).collect())
        };
        Ok(VertexData {
            positions,
            normals,
            uvs: tex_coords(0),
            uvs1: want_uvs1.then(|| tex_coords(1)).flatten(),
            // COLOR_0 is linear (spec 3.7.2.1); RGB colours have alpha 1.
            colors: reader
                .read_colors(0)
                .map(|c| c.into_rgba_f32().map(Vec4::from).collect()),
            indices: reader.read_indices().map(|i| i.into_u32().collect()),
        })
    }

    fn material(&mut self, m: gltf::Material) -> Result<u32, SceneError> {
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
            absorption: m.volume().map_or(Vec3::ZERO, |v| {
                absorption(
                    v.thickness_factor(),
                    v.attenuation_color(),
                    v.attenuation_distance(),
                )
            }),
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
                "KHR_materials_volume attenuation",
                material.absorption.is_finite() && material.absorption.min_element() >= 0.0,
            ),
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
        if let Some(sp) = m.specular() {
            material.specular = sp.specular_factor();
            material.specular_color = Vec3::from(sp.specular_color_factor());
            material.specular_texture = sp
                .specular_texture()
                .and_then(|t| self.texture_info(&t, false));
            material.specular_color_texture = sp
                .specular_color_texture()
                .and_then(|t| self.texture_info(&t, true));
        }
        let extension = |name: &str| m.extensions().and_then(|e| e.get(name));
        if let Some(coat) = extension("KHR_materials_clearcoat") {
            self.clearcoat(&mut material, m.index(), coat)?;
        }
        if let Some(sheen) = extension("KHR_materials_sheen") {
            self.sheen(&mut material, m.index(), sheen)?;
        }
        let layers = [
            ("KHR_materials_specular specularFactor", material.specular),
            (
                "KHR_materials_clearcoat clearcoatFactor",
                material.clearcoat,
            ),
            (
                "KHR_materials_clearcoat clearcoatRoughnessFactor",
                material.clearcoat_roughness,
            ),
            (
                "KHR_materials_sheen sheenRoughnessFactor",
                material.sheen_roughness,
            ),
            (
                "KHR_materials_sheen sheenColorFactor",
                material.sheen_color.min_element(),
            ),
        ];
        for (what, v) in layers {
            if !(v.is_finite() && v >= 0.0) {
                return Err(err(format!("material '{label}': invalid {what} {v}")));
            }
        }
        if !(material.specular_color.is_finite() && material.specular_color.min_element() >= 0.0) {
            return Err(err(format!(
                "material '{label}': invalid KHR_materials_specular specularColorFactor"
            )));
        }
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

    /// KHR_materials_clearcoat, which the gltf crate does not parse: its factors and
    /// textures from the material's JSON (`coat`). The coat's normal texture is not read.
    fn clearcoat(
        &mut self,
        material: &mut Material,
        index: Option<usize>,
        coat: &serde_json::Value,
    ) -> Result<(), SceneError> {
        let at = format!(
            "materials[{}].extensions.KHR_materials_clearcoat",
            index.unwrap_or(0)
        );
        material.clearcoat = json_number(coat, "clearcoatFactor", &at)?;
        material.clearcoat_roughness = json_number(coat, "clearcoatRoughnessFactor", &at)?;
        material.clearcoat_texture =
            self.json_texture_info(coat, "clearcoatTexture", &at, false)?;
        material.clearcoat_roughness_texture =
            self.json_texture_info(coat, "clearcoatRoughnessTexture", &at, false)?;
        if coat.get("clearcoatNormalTexture").is_some() {
            self.desc.warnings.push(format!(
                "{at}.clearcoatNormalTexture ignored: the coat takes the base's normals"
            ));
        }
        Ok(())
    }

    /// KHR_materials_sheen, which the gltf crate does not parse: its factors and textures
    /// from the material's JSON (`sheen`).
    fn sheen(
        &mut self,
        material: &mut Material,
        index: Option<usize>,
        sheen: &serde_json::Value,
    ) -> Result<(), SceneError> {
        let at = format!(
            "materials[{}].extensions.KHR_materials_sheen",
            index.unwrap_or(0)
        );
        material.sheen_color = match sheen.get("sheenColorFactor") {
            None => Vec3::ZERO,
            Some(v) => serde_json::from_value::<[f32; 3]>(v.clone())
                .map(Vec3::from)
                .map_err(|_| err(format!("{at}.sheenColorFactor: not three numbers")))?,
        };
        material.sheen_roughness = json_number(sheen, "sheenRoughnessFactor", &at)?;
        material.sheen_color_texture =
            self.json_texture_info(sheen, "sheenColorTexture", &at, true)?;
        material.sheen_roughness_texture =
            self.json_texture_info(sheen, "sheenRoughnessTexture", &at, false)?;
        Ok(())
    }

    /// A textureInfo (spec 5.29) inside an extension the gltf crate does not parse.
    fn json_texture_info(
        &mut self,
        parent: &serde_json::Value,
        name: &str,
        at: &str,
        srgb: bool,
    ) -> Result<Option<TextureRef>, SceneError> {
        let Some(value) = parent.get(name) else {
            return Ok(None);
        };
        let info: gltf::json::texture::Info =
            serde_json::from_value(value.clone()).map_err(|e| err(format!("{at}.{name}: {e}")))?;
        let Some(texture) = self.document.textures().nth(info.index.value()) else {
            return Err(err(format!(
                "{at}.{name}: texture {} does not exist",
                info.index.value()
            )));
        };
        let transform = info
            .extensions
            .as_ref()
            .and_then(|e| e.texture_transform.as_ref());
        let parts = transform.map(|t| (t.offset.0, t.rotation.0, t.scale.0, t.tex_coord));
        let (transform, tex_coord) = self.transform(texture.index(), parts, info.tex_coord);
        Ok(self.texture(&texture, tex_coord, transform, srgb))
    }

    /// The size an image's header declares, refused above the texel limit before anything is
    /// decoded: a few hundred kilobytes of PNG can declare 20000 x 20000 texels, gigabytes
    /// once decoded. Headers that cannot be read are left to the decoder to report.
    fn check_image_size(&self, image: &gltf::Image) -> Result<(), String> {
        let from_uri;
        let bytes: &[u8] = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers[view.buffer().index()];
                &buffer[view.offset()..view.offset() + view.length()]
            }
            gltf::image::Source::Uri { uri, .. } => {
                match gltf::buffer::Data::from_source_and_blob(
                    gltf::buffer::Source::Uri(uri),
                    Some(self.base),
                    &mut None,
                ) {
                    Ok(data) => {
                        from_uri = data.0;
                        &from_uri
                    }
                    Err(_) => return Ok(()),
                }
            }
        };
        let Ok(reader) = image::ImageReader::new(std::io::Cursor::new(bytes)).with_guessed_format()
        else {
            return Ok(());
        };
        let Ok((width, height)) = reader.into_dimensions() else {
            return Ok(());
        };
        let texels = u64::from(width) * u64::from(height);
        if texels > self.limits.max_texels {
            return Err(LoadLimits::refusal(
                &format!("declares {width} x {height} texels"),
                self.limits.max_texels,
                "--max-texels",
            ));
        }
        Ok(())
    }

    /// Decodes an image once, to RGBA8; None (with a warning) when it cannot be read.
    fn image_rgba8(&mut self, image: &gltf::Image) -> Option<(usize, usize, Vec<u8>)> {
        if let Some(cached) = self.images.get(&image.index()) {
            return cached.clone();
        }
        if let Err(problem) = self.check_image_size(image) {
            self.desc.warnings.push(format!(
                "image {}: {problem}; texture ignored",
                image.index()
            ));
            self.images.insert(image.index(), None);
            return None;
        }
        let decoded =
            match gltf::image::Data::from_source(image.source(), Some(self.base), self.buffers) {
                Ok(data) => to_rgba8(&data),
                Err(e) => {
                    self.desc.warnings.push(format!(
                        "image {}: cannot be read ({e}); texture ignored",
                        image.index()
                    ));
                    None
                }
            };
        self.images.insert(image.index(), decoded.clone());
        decoded
    }

    /// A texture reference with KHR_texture_transform's offset, rotation and scale, applied
    /// as the ratified extension's GLSL says: uv' = T(offset) R(rotation) S(scale) uv, where R
    /// has columns (cos, -sin) and (sin, cos): a rotation by -rotation in (u, v), which is
    /// counter-clockwise on the image since v points down (the Khronos TextureTransformTest
    /// model's markers confirm the direction). The extension's texCoord overrides the
    /// reference's.
    fn texture_info(&mut self, info: &gltf::texture::Info, srgb: bool) -> Option<TextureRef> {
        let parts = info
            .texture_transform()
            .map(|t| (t.offset(), t.rotation(), t.scale(), t.tex_coord()));
        let (transform, tex_coord) =
            self.transform(info.texture().index(), parts, info.tex_coord());
        self.texture(&info.texture(), tex_coord, transform, srgb)
    }

    /// The map and TEXCOORD set of a texture reference from KHR_texture_transform's
    /// (offset, rotation, scale, texCoord), when it has one (see `texture_info`).
    fn transform(
        &mut self,
        texture: usize,
        parts: Option<TransformParts>,
        tex_coord: u32,
    ) -> (Affine2, u32) {
        let Some((offset, rotation, scale, set)) = parts else {
            return (Affine2::IDENTITY, tex_coord);
        };
        let transform =
            Affine2::from_scale_angle_translation(Vec2::from(scale), -rotation, Vec2::from(offset));
        let tex_coord = set.unwrap_or(tex_coord);
        if transform.is_finite() {
            (transform, tex_coord)
        } else {
            self.desc.warnings.push(format!(
                "texture {texture}: KHR_texture_transform is not finite, ignored"
            ));
            (Affine2::IDENTITY, tex_coord)
        }
    }

    fn texture(
        &mut self,
        texture: &gltf::Texture,
        tex_coord: u32,
        transform: Affine2,
        srgb: bool,
    ) -> Option<TextureRef> {
        let tex_coord = if tex_coord > 1 {
            self.desc.warnings.push(format!(
                "textures[{}]: TEXCOORD_{tex_coord} is not supported (only 0 and 1), read at TEXCOORD_0",
                texture.index()
            ));
            0
        } else {
            tex_coord
        };
        let reference = |texture| TextureRef {
            texture,
            tex_coord,
            transform,
        };
        let key = (texture.index(), srgb);
        if let Some(&i) = self.texture_index.get(&key) {
            return Some(reference(i));
        }
        let (w, h, rgba) = self.image_rgba8(&texture.source())?;
        let wrap = |m: gltf::texture::WrappingMode| match m {
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
        };
        let sampler = texture.sampler();
        let mut tex = Texture::from_rgba8(
            w,
            h,
            &rgba,
            srgb,
            wrap(sampler.wrap_s()),
            wrap(sampler.wrap_t()),
        );
        tex.nearest = sampler.mag_filter() == Some(gltf::texture::MagFilter::Nearest);
        let i = self.desc.textures.len() as u32;
        self.desc.textures.push(tex);
        self.texture_index.insert(key, i);
        Some(reference(i))
    }
}

/// Triangle i of a strip is (v_i, v_{i+1+i%2}, v_{i+2-i%2}), glTF 2.0 section 3.7.2.1:
/// every other triangle swaps its last two vertices so that all keep the strip's winding.
fn strip_to_list(strip: &[u32]) -> Vec<u32> {
    (0..strip.len().saturating_sub(2))
        .flat_map(|i| [strip[i], strip[i + 1 + i % 2], strip[i + 2 - i % 2]])
        .collect()
}

/// Triangle i of a fan is (v_{i+1}, v_{i+2}, v_0), glTF 2.0 section 3.7.2.1.
fn fan_to_list(fan: &[u32]) -> Vec<u32> {
    (0..fan.len().saturating_sub(2))
        .flat_map(|i| [fan[i + 1], fan[i + 2], fan[0]])
        .collect()
}

fn to_rgba8(data: &gltf::image::Data) -> Option<(usize, usize, Vec<u8>)> {
    use gltf::image::Format;
    let (w, h) = (data.width as usize, data.height as usize);
    let px = &data.pixels;
    let n = w.checked_mul(h)?;
    let (channels, bytes) = match data.format {
        Format::R8 => (1, 1),
        Format::R8G8 => (2, 1),
        Format::R8G8B8 => (3, 1),
        Format::R8G8B8A8 => (4, 1),
        Format::R16 => (1, 2),
        Format::R16G16 => (2, 2),
        Format::R16G16B16 => (3, 2),
        Format::R16G16B16A16 => (4, 2),
        _ => return None,
    };
    if px.len() < n * channels * bytes || n == 0 {
        return None;
    }
    let mut out = Vec::with_capacity(n * 4);
    for i in 0..n {
        // 16-bit channels are little-endian; their high byte is the 8-bit value.
        let c = |k: usize| px[(i * channels + k) * bytes + bytes - 1];
        let rgba = match channels {
            1 => [c(0), c(0), c(0), 255],
            2 => [c(0), c(1), 0, 255],
            3 => [c(0), c(1), c(2), 255],
            _ => [c(0), c(1), c(2), c(3)],
        };
        out.extend_from_slice(&rgba);
    }
    Some((w, h, out))
}
