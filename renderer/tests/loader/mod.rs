//! The glTF loader: valid files in every container (.gltf with embedded or external buffers,
//! .glb), the design's interpretation of materials, lights and cameras, and a set of broken
//! files that must give an error naming the file and the problem, never a panic. One file
//! per part of the loader (`renderer/src/scene/gltf/`); this one holds what they share:
//! temporary files, GLB containers, triangle sets and the error check.

mod containers;
mod material;
mod mesh;
mod nodes;
mod texture;

use caustica_renderer::scene::SceneDescription;
use caustica_renderer::scene::gltf::load;
use glam::Vec3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-loader-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn write_json(dir: &Path, name: &str, v: &Value) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_vec(v).unwrap()).unwrap();
    path
}

/// Splits an exported file's embedded buffer out: (JSON without the data URI, the bytes).
fn split_buffer(mut v: Value) -> (Value, Vec<u8>) {
    use base64::Engine;
    let uri = v["buffers"][0]["uri"].as_str().unwrap().to_string();
    let data = base64::engine::general_purpose::STANDARD
        .decode(uri.split(',').nth(1).unwrap())
        .unwrap();
    v["buffers"][0].as_object_mut().unwrap().remove("uri");
    (v, data)
}

fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

fn expect_error(path: &Path, fragment: &str) {
    match load(path) {
        Ok(_) => panic!(
            "{} loaded, expected an error about '{fragment}'",
            path.display()
        ),
        Err(e) => {
            let msg = e.to_string();
            assert!(
                msg.contains(&path.display().to_string()),
                "error does not name the file: {msg}"
            );
            assert!(
                msg.to_lowercase().contains(&fragment.to_lowercase()),
                "error does not say '{fragment}': {msg}"
            );
        }
    }
}

fn load_glb(dir: &Path, name: &str, j: &Value, bin: &[u8]) -> caustica_renderer::scene::Scene {
    let path = dir.join(name);
    std::fs::write(&path, glb(j, bin)).unwrap();
    load(&path).unwrap()
}

/// Each mesh's triangles as the bits of their vertices' positions, each triangle rotated to
/// start at its smallest vertex (rotation keeps the winding) and the mesh's list sorted.
fn triangle_sets(desc: &SceneDescription) -> Vec<Vec<[[u32; 3]; 3]>> {
    desc.meshes
        .iter()
        .map(|m| {
            let mut tris: Vec<[[u32; 3]; 3]> = m
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let p = [t[0], t[1], t[2]]
                        .map(|i| m.positions[i as usize].to_array().map(f32::to_bits));
                    (0..3)
                        .map(|r| [p[r], p[(r + 1) % 3], p[(r + 2) % 3]])
                        .min()
                        .unwrap()
                })
                .collect();
            tris.sort();
            tris
        })
        .collect()
}

/// Appends `bytes` to the exported file as a new buffer (data URI) with one view; its index.
fn push_buffer_view(v: &mut Value, bytes: &[u8]) -> usize {
    use base64::Engine;
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(bytes)
    );
    let buffers = v["buffers"].as_array_mut().unwrap();
    buffers.push(json!({"uri": uri, "byteLength": bytes.len()}));
    let buffer = buffers.len() - 1;
    let views = v["bufferViews"].as_array_mut().unwrap();
    views.push(json!({"buffer": buffer, "byteLength": bytes.len()}));
    views.len() - 1
}

/// The base colour a ray straight down at (x, z) finds on a diffuse floor.
fn base_colour_at(scene: &caustica_renderer::scene::Scene, x: f32, z: f32) -> Vec3 {
    use caustica_renderer::geometry::Ray;
    use caustica_renderer::material::Bsdf;
    let si = scene
        .intersect(&Ray::new(Vec3::new(x, 1.0, z), Vec3::NEG_Y))
        .unwrap();
    match scene.bsdf(&si) {
        Bsdf::Diffuse(d) => d.r,
        other => panic!("expected the diffuse floor, got {other:?}"),
    }
}
