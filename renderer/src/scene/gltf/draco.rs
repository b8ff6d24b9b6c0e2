//! KHR_draco_mesh_compression: a primitive whose attributes and indices are one Draco
//! bitstream in a buffer view, decoded with the `draco-core` crate (a pure-Rust port of
//! Google's decoder). The extension's `attributes` map each glTF attribute name to the unique
//! id of a Draco attribute; the primitive's accessors then only give counts and types
//! (extension spec, "Conformance"), so everything is read from the decoded mesh.

use glam::{Vec2, Vec3, Vec4};

/// What a compressed primitive holds, in the loader's terms.
pub struct DecodedPrimitive {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub tex_coords: [Option<Vec<Vec2>>; 2],
    pub colors: Option<Vec<Vec4>>,
    pub indices: Vec<u32>,
}

/// Decodes the primitive described by the extension object `extension`, whose bitstream lies
/// in `document`'s buffer views over `buffers`. Errors say what is wrong in a few words.
pub fn decode(
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    extension: &serde_json::Value,
) -> Result<DecodedPrimitive, String> {
    let view_index = extension
        .get("bufferView")
        .and_then(|v| v.as_u64())
        .ok_or("no bufferView")? as usize;
    let view = document
        .views()
        .nth(view_index)
        .ok_or_else(|| format!("bufferView {view_index} does not exist"))?;
    let bytes = buffers
        .get(view.buffer().index())
        .and_then(|b| b.0.get(view.offset()..view.offset() + view.length()))
        .ok_or_else(|| format!("bufferView {view_index} runs past its buffer"))?;
    let mut mesh = draco_core::mesh::Mesh::new();
    draco_core::mesh_decoder::MeshDecoder::new()
        .decode(
            &mut draco_core::decoder_buffer::DecoderBuffer::new(bytes),
            &mut mesh,
        )
        .map_err(|e| format!("the Draco bitstream cannot be decoded ({e})"))?;
    let points = mesh.num_points();
    let attributes = extension.get("attributes").and_then(|a| a.as_object());
    let read = |name: &str, components: usize| -> Result<Option<Vec<f32>>, String> {
        let Some(id) = attributes.and_then(|a| a.get(name)) else {
            return Ok(None);
        };
        let id = id
            .as_u64()
            .ok_or_else(|| format!("attributes.{name} is not an id"))?;
        let attribute = mesh
            .attribute_by_unique_id(id as u32)
            .ok_or_else(|| format!("attributes.{name}: the bitstream has no attribute {id}"))?;
        let mut values = attribute.read_f32s(points, components);
        // Normalised integers (texture coordinates or colours kept as bytes or shorts) mean
        // value / max, as for glTF accessors.
        if attribute.normalized() {
            let max = integer_max(attribute.data_type());
            values.iter_mut().for_each(|v| *v /= max);
        }
        Ok(Some(values))
    };
    let positions = read("POSITION", 3)?
        .ok_or("no POSITION attribute")?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let normals = read("NORMAL", 3)?.map(|v| v.chunks_exact(3).map(Vec3::from_slice).collect());
    let uv = |v: Vec<f32>| v.chunks_exact(2).map(Vec2::from_slice).collect();
    let tex_coords = [
        read("TEXCOORD_0", 2)?.map(uv),
        read("TEXCOORD_1", 2)?.map(uv),
    ];
    // COLOR_0 may be RGB or RGBA: read four and take alpha 1 where the bitstream has three.
    let colors = match mesh_components(&mesh, attributes, "COLOR_0") {
        Some(3) => read("COLOR_0", 3)?.map(|v| {
            v.chunks_exact(3)
                .map(|c| Vec3::from_slice(c).extend(1.0))
                .collect()
        }),
        _ => read("COLOR_0", 4)?.map(|v| v.chunks_exact(4).map(Vec4::from_slice).collect()),
    };
    let indices = mesh
        .faces()
        .iter()
        .flat_map(|face| face.iter().map(|p| p.0))
        .collect::<Vec<u32>>();
    if let Some(&bad) = indices.iter().find(|&&i| i as usize >= points) {
        return Err(format!("index {bad} is past the {points} decoded points"));
    }
    Ok(DecodedPrimitive {
        positions,
        normals,
        tex_coords,
        colors,
        indices,
    })
}

/// The component count of the Draco attribute a glTF attribute `name` maps to.
fn mesh_components(
    mesh: &draco_core::mesh::Mesh,
    attributes: Option<&serde_json::Map<String, serde_json::Value>>,
    name: &str,
) -> Option<u8> {
    let id = attributes?.get(name)?.as_u64()?;
    Some(mesh.attribute_by_unique_id(id as u32)?.num_components())
}

fn integer_max(data_type: draco_core::draco_types::DataType) -> f32 {
    use draco_core::draco_types::DataType;
    match data_type {
        DataType::Int8 => i8::MAX as f32,
        DataType::Uint8 => u8::MAX as f32,
        DataType::Int16 => i16::MAX as f32,
        DataType::Uint16 => u16::MAX as f32,
        DataType::Int32 => i32::MAX as f32,
        DataType::Uint32 => u32::MAX as f32,
        _ => 1.0,
    }
}
