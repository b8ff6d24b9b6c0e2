//! Writes a scene description as a self-contained glTF 2.0 file (one buffer, embedded as a
//! base64 data URI): how the bundled assets are generated, and how tests make files to break.
//! Materials are written with their factors (textures are not exported).

use crate::camera::Projection;
use crate::scene::{PunctualLightDesc, SceneDescription};
use base64::Engine;
use glam::{Quat, Vec3};
use serde_json::{Value, json};

struct BufferWriter {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl BufferWriter {
    fn push(&mut self, data: &[u8], target: u32, accessor: Value) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len(), "target": target}));
        self.bytes.extend_from_slice(data);
        let mut acc = accessor;
        acc["bufferView"] = json!(self.views.len() - 1);
        self.accessors.push(acc);
        self.accessors.len() - 1
    }

    fn vec3s(&mut self, v: &[Vec3]) -> usize {
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let mut data = Vec::with_capacity(v.len() * 12);
        for p in v {
            min = min.min(*p);
            max = max.max(*p);
            for c in p.to_array() {
                data.extend_from_slice(&c.to_le_bytes());
            }
        }
        self.push(&data, 34962, json!({"componentType": 5126, "count": v.len(), "type": "VEC3", "min": min.to_array(), "max": max.to_array()}))
    }
}

/// The little-endian bytes of a vertex attribute of N floats per vertex, its count and its
/// accessor type.
fn floats<T, const N: usize>(
    values: &[T],
    components: impl Fn(&T) -> [f32; N],
) -> (Vec<u8>, usize, &'static str) {
    let data = values
        .iter()
        .flat_map(components)
        .flat_map(f32::to_le_bytes)
        .collect();
    let kind = match N {
        2 => "VEC2",
        3 => "VEC3",
        _ => "VEC4",
    };
    (data, values.len(), kind)
}

fn light_color(c: Vec3) -> (Vec3, f32) {
    let m = c.max_element();
    if m > 0.0 {
        (c / m, m)
    } else {
        (Vec3::ONE, 0.0)
    }
}

/// The glTF JSON of `desc`, with its buffer embedded as a base64 data URI.
pub fn to_gltf(desc: &SceneDescription) -> Value {
    let (mut root, bytes) = gltf_parts(desc);
    root["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bytes)
    ));
    root
}

/// `desc` as a binary glTF (.glb): the JSON chunk, then the buffer as the BIN chunk, which is
/// how large models are shipped (no base64 to decode on load).
pub fn to_glb(desc: &SceneDescription) -> Vec<u8> {
    let (root, bytes) = gltf_parts(desc);
    let glb = gltf::binary::Glb {
        // `to_vec` writes the real length.
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: 0,
        },
        json: serde_json::to_vec(&root).unwrap_or_default().into(),
        bin: Some(bytes.into()),
    };
    glb.to_vec().expect("writing to memory does not fail")
}

/// The glTF JSON of `desc` whose buffer 0 has no URI (as in a .glb), and that buffer's bytes.
fn gltf_parts(desc: &SceneDescription) -> (Value, Vec<u8>) {
    let mut buf = BufferWriter {
        bytes: Vec::new(),
        views: Vec::new(),
        accessors: Vec::new(),
    };
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for mesh in &desc.meshes {
        let mut attributes = json!({"POSITION": buf.vec3s(&mesh.positions)});
        if let Some(n) = &mesh.normals {
            attributes["NORMAL"] = json!(buf.vec3s(n));
        }
        let sets = [
            (
                "TEXCOORD_0",
                mesh.uvs.as_ref().map(|uv| floats(uv, |t| t.to_array())),
            ),
            (
                "TEXCOORD_1",
                mesh.uvs1.as_ref().map(|uv| floats(uv, |t| t.to_array())),
            ),
            (
                "COLOR_0",
                mesh.colors.as_ref().map(|c| floats(c, |c| c.to_array())),
            ),
        ];
        for (name, values) in sets {
            if let Some((data, count, kind)) = values {
                attributes[name] = json!(buf.push(
                    &data,
                    34962,
                    json!({"componentType": 5126, "count": count, "type": kind})
                ));
            }
        }
        let idx: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = buf.push(
            &idx,
            34963,
            json!({"componentType": 5125, "count": mesh.indices.len(), "type": "SCALAR"}),
        );
        meshes.push(json!({"name": mesh.name, "primitives": [{"attributes": attributes, "indices": indices, "material": mesh.material}]}));
        nodes.push(json!({"name": mesh.name, "mesh": meshes.len() - 1}));
    }
    let mut extensions_used = Vec::new();
    let materials: Vec<Value> = desc
        .materials
        .iter()
        .map(|m| {
            let mut v = json!({
                "name": m.name,
                "pbrMetallicRoughness": {
                    "baseColorFactor": [m.base_color.x, m.base_color.y, m.base_color.z, 1.0],
                    "metallicFactor": m.metallic,
                    "roughnessFactor": m.roughness,
                },
                "doubleSided": m.double_sided,
            });
            let mut ext = serde_json::Map::new();
            if m.is_emissive() {
                let peak = m.emission.max_element();
                let (factor, strength) = if peak > 1.0 {
                    (m.emission / peak, peak)
                } else {
                    (m.emission, 1.0)
                };
                v["emissiveFactor"] = json!(factor.to_array());
                if strength != 1.0 {
                    ext.insert(
                        "KHR_materials_emissive_strength".into(),
                        json!({"emissiveStrength": strength}),
                    );
                }
            }
            if m.transmission > 0.0 {
                ext.insert(
                    "KHR_materials_transmission".into(),
                    json!({"transmissionFactor": m.transmission}),
                );
            }
            if m.ior != 1.5 {
                ext.insert("KHR_materials_ior".into(), json!({"ior": m.ior}));
            }
            if m.specular != 1.0 || m.specular_color != Vec3::ONE {
                ext.insert(
                    "KHR_materials_specular".into(),
                    json!({"specularFactor": m.specular, "specularColorFactor": m.specular_color.to_array()}),
                );
            }
            if m.sheen_color.max_element() > 0.0 {
                ext.insert(
                    "KHR_materials_sheen".into(),
                    json!({"sheenColorFactor": m.sheen_color.to_array(), "sheenRoughnessFactor": m.sheen_roughness}),
                );
            }
            if m.clearcoat > 0.0 {
                ext.insert(
                    "KHR_materials_clearcoat".into(),
                    json!({"clearcoatFactor": m.clearcoat, "clearcoatRoughnessFactor": m.clearcoat_roughness}),
                );
            }
            for k in ext.keys() {
                if !extensions_used.contains(k) {
                    extensions_used.push(k.clone());
                }
            }
            if !ext.is_empty() {
                v["extensions"] = Value::Object(ext);
            }
            v
        })
        .collect();
    let mut lights = Vec::new();
    for l in &desc.lights {
        let (kind, power, translation, direction) = match *l {
            PunctualLightDesc::Point {
                position,
                intensity,
            } => ("point", intensity, position, Vec3::NEG_Z),
            PunctualLightDesc::Spot {
                position,
                direction,
                intensity,
                ..
            } => ("spot", intensity, position, direction),
            PunctualLightDesc::Directional {
                direction,
                irradiance,
            } => ("directional", irradiance, Vec3::ZERO, direction),
        };
        let (color, strength) = light_color(power);
        let mut light = json!({"type": kind, "color": color.to_array(), "intensity": strength});
        if let PunctualLightDesc::Spot {
            inner_cone,
            outer_cone,
            ..
        } = *l
        {
            light["spot"] = json!({"innerConeAngle": inner_cone, "outerConeAngle": outer_cone});
        }
        lights.push(light);
        let rotation = Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize());
        nodes.push(json!({
            "name": format!("light {}", lights.len() - 1),
            "translation": translation.to_array(),
            "rotation": rotation.to_array(),
            "extensions": {"KHR_lights_punctual": {"light": lights.len() - 1}},
        }));
    }
    let mut cameras = Vec::new();
    if let Some(c) = &desc.camera {
        cameras.push(match c.projection {
            Projection::Perspective { yfov } => {
                let mut perspective = json!({"yfov": yfov, "znear": 0.01});
                if let Some(a) = c.aspect {
                    perspective["aspectRatio"] = json!(a);
                }
                json!({"type": "perspective", "perspective": perspective})
            }
            Projection::Orthographic { ymag } => {
                let xmag = ymag * c.aspect.unwrap_or(1.0);
                json!({"type": "orthographic", "orthographic": {"xmag": xmag, "ymag": ymag, "znear": 0.0, "zfar": 1e6}})
            }
        });
        let (_, rotation, translation) = c.camera_to_world.to_scale_rotation_translation();
        nodes.push(json!({"name": "camera", "camera": 0, "translation": translation.to_array(), "rotation": rotation.to_array()}));
    }
    let mut root = json!({
        "asset": {"version": "2.0", "generator": "Caustica (renderer/examples/make_assets.rs)"},
        "scene": 0,
        "scenes": [{"name": desc.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "accessors": buf.accessors,
        "bufferViews": buf.views,
        "buffers": [{"byteLength": buf.bytes.len()}],
    });
    if !cameras.is_empty() {
        root["cameras"] = json!(cameras);
    }
    if !lights.is_empty() {
        extensions_used.push("KHR_lights_punctual".into());
        root["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    if !extensions_used.is_empty() {
        root["extensionsUsed"] = json!(extensions_used);
    }
    (root, buf.bytes)
}

/// The glTF file text, pretty-printed so diffs of regenerated assets stay readable.
pub fn to_gltf_string(desc: &SceneDescription) -> String {
    let mut s = serde_json::to_string_pretty(&to_gltf(desc)).unwrap_or_default();
    s.push('\n');
    s
}
