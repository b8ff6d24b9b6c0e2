//! What the gltf crate is not trusted with: the JSON parsed (with a GLB header's length
//! checked first), validated with KHR_draco_mesh_compression's allowance, buffers loaded
//! within the byte limit, and every buffer view, accessor (sparse ones too) and accessor type
//! checked against what the crate's readers assume, so that no read can run past a buffer or
//! reach one of its panics (several found by fuzzing).

use super::err;
use crate::scene::SceneError;
use crate::scene::limits::LoadLimits;
use std::path::Path;

/// The JSON document and the binary chunk of a `.gltf` or `.glb` file. A scene without a
/// `nodes` array is valid glTF (the property is optional) but the gltf crate requires it, so
/// the JSON is read as a value first and the empty array supplied.
pub(super) fn parse(bytes: &[u8]) -> Result<(gltf::json::Root, Option<Vec<u8>>), SceneError> {
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
pub(super) fn validated(root: gltf::json::Root) -> Result<gltf::Document, SceneError> {
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
pub(super) fn load_buffers(
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
pub(super) fn check_views_and_accessors(
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
pub(super) fn check_accessor_types(prim: &gltf::Primitive) -> Result<(), String> {
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
